//! Finite mobility: the local dimension of the solution set at a configuration, against the
//! first-order (instantaneous) mobility.
//!
//! The first-order mobility is the nullity of the constraint Jacobian (frame fixed, driven
//! DOF not counted). To estimate the local dimension, the configuration is moved a small step
//! along a few random first-order motions, projected back onto the constraints by
//! Gauss–Newton, and the nullity is taken again there; the smallest nullity over the samples
//! is the estimate (the nullity at a generic nearby point of a solution set of dimension d is
//! d; at a singular point it is larger). Limits: a branch of dimension d through a
//! bifurcation is found only if a sample falls near it; the samples see a neighbourhood of
//! about `step` × model size.

use super::closure::{ClosureStatus, assemble, check_closure, undriven};
use super::newton::{NewtonOptions, System, Targets};
use super::pose::Configuration;
use super::residual::{ModelError, PositionModel};
use super::solve::SolveError;
use crate::mechanism::Mechanism;
use crate::rng::SplitMix64;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Options of [`finite_mobility`].
#[derive(Clone, Copy, Debug)]
pub struct FiniteOptions {
    /// Number of nearby samples.
    pub samples: usize,
    /// Step along a first-order motion (model units, i.e. fraction of the model size).
    pub step: f64,
    /// Seed of the random directions.
    pub seed: u64,
    /// Relative singular-value threshold of the rank decisions.
    pub rank_tolerance: f64,
}

impl Default for FiniteOptions {
    fn default() -> Self {
        FiniteOptions {
            samples: 4,
            step: 1e-3,
            seed: 0,
            rank_tolerance: 1e-8,
        }
    }
}

/// What the comparison says.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// First-order and finite mobility agree, and the count agrees with them.
    Regular,
    /// More first-order freedoms than finite ones: a singular configuration (toggle, dead
    /// point, bifurcation).
    Singular,
    /// Moves (finite mobility above the count) with first order agreeing: overconstrained by
    /// design but really moving (Bennett, Bricard, planar loops in space).
    OverconstrainedMoving,
    /// Both: overconstrained by design and at a singular configuration.
    SingularOverconstrained,
}

/// The finite-mobility report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FiniteMobility {
    /// Chebyshev–Grübler–Kutzbach count `B·Nm − Σ pairs·(B − k)`.
    pub count: i64,
    /// Nullity of the constraint Jacobian at the configuration.
    pub first_order: usize,
    /// Estimated local dimension of the solution set.
    pub finite: usize,
    /// Nullity at each nearby sample.
    pub samples: Vec<usize>,
    /// Verdict.
    pub verdict: Verdict,
    /// First-order freedoms that do not extend to a finite motion.
    pub instantaneous_only: usize,
    /// Joints that move in those instantaneous-only freedoms.
    pub singular_joints: Vec<String>,
    /// Joints stationary in every first-order motion here but moving at nearby
    /// configurations: locked only at this configuration (a toggle).
    pub locked_at_toggle: Vec<String>,
    /// Plain-language findings.
    pub notes: Vec<String>,
    /// The configuration analysed is not the file's: the file's missed closure and was
    /// assembled first ([`finite_mobility_of_file`]; the first note says by how much).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub assembled: bool,
}

/// The finite-mobility test of a file, at the configuration it describes. A closed file is
/// tested at its own configuration. A file that misses closure (joints with `second`
/// geometry) does not describe a configuration of the mechanism: it is first assembled as
/// `mbsa assemble` does it (Gauss–Newton from the file's configuration, least change, every
/// body's own geometry kept), the test runs at the assembled configuration, and the first
/// note says so (the gap, the joints, how far the bodies moved). `tolerance` is the closure
/// tolerance in file units (default from the written precision); a configuration that cannot
/// be assembled is the assembly's error.
pub fn finite_mobility_of_file(
    m: &Mechanism,
    tolerance: Option<f64>,
    opts: &FiniteOptions,
) -> Result<FiniteMobility, SolveError> {
    let reference = Configuration::reference(m.bodies.len());
    let closure = check_closure(m, &reference, tolerance)?;
    if closure.status == ClosureStatus::Closed {
        return Ok(finite_mobility(m, &reference, opts)?);
    }
    let (config, _) = assemble(m, &reference, &NewtonOptions::default())?;
    let scale = super::residual::model_size(m);
    let moved = config
        .poses
        .iter()
        .map(|p| {
            let angle = nalgebra::Rotation3::from_matrix_unchecked(p.rotation).angle();
            (p.translation.norm() * scale).max(angle * scale)
        })
        .fold(0.0f64, f64::max);
    let mut f = finite_mobility(m, &config, opts)?;
    f.assembled = true;
    f.notes.insert(
        0,
        format!(
            "the file's configuration misses closure by up to {:.3e} at joint(s) {}: analysed at the assembled configuration (the least change that closes it, as `mbsa assemble` writes it; bodies moved by up to {:.3e}, a rotation of ε rad counted as ε × the model size)",
            closure.max_residual,
            closure
                .worst(super::closure::LISTED)
                .iter()
                .map(|j| j.joint.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            moved
        ),
    );
    Ok(f)
}

/// Largest mechanism (bodies) the dense test handles.
pub const MAX_BODIES: usize = 400;

/// Null-space basis (columns) of `j` and its rank threshold decisions.
fn null_basis(j: &DMatrix<f64>, rel: f64) -> DMatrix<f64> {
    let n = j.ncols();
    if n == 0 {
        return DMatrix::zeros(0, 0);
    }
    // Pad to at least n rows so the SVD gives a full V.
    let rows = j.nrows().max(n);
    let mut a = DMatrix::zeros(rows, n);
    a.view_mut((0, 0), (j.nrows(), n)).copy_from(j);
    if !a.iter().all(|x| x.is_finite()) {
        return DMatrix::zeros(n, 0);
    }
    let Some(svd) = nalgebra::SVD::try_new(a, false, true, f64::EPSILON, 10_000) else {
        return DMatrix::zeros(n, 0);
    };
    let (Some(vt), s) = (svd.v_t, svd.singular_values) else {
        return DMatrix::zeros(n, 0);
    };
    let top = s.iter().copied().fold(0.0, f64::max).max(1.0);
    let cols: Vec<usize> = (0..s.len()).filter(|&i| s[i] <= rel * top).collect();
    DMatrix::from_fn(n, cols.len(), |r, c| vt[(cols[c], r)])
}

/// The slice coordinates `d(x)` of [`solve_sliced`] (each unknown body's rotation vector and
/// translation change from `config`, its `B` embedded components) and their derivative with
/// respect to the body twists (rotation vector ≈ ω, translation change dp = v + ω × p).
fn slice_coords(
    sys: &System,
    model: &PositionModel,
    config: &Configuration,
    x: &Configuration,
) -> (DVector<f64>, DMatrix<f64>) {
    let b = model.b();
    let cols = super::pose::embed_columns(model.space);
    let n = sys.bodies.len() * b;

    let mut d = DVector::zeros(n);
    let mut jd = DMatrix::zeros(n, n);
    for (i, &body) in sys.bodies.iter().enumerate() {
        let p0 = &config.poses[body];
        let p = &x.poses[body];
        let rel = nalgebra::Rotation3::from_matrix_unchecked(p.rotation * p0.rotation.transpose());
        let rv = rel.scaled_axis();
        let dt = p.translation - p0.translation;
        let full = [rv.x, rv.y, rv.z, dt.x, dt.y, dt.z];
        // d(translation)/d(ω) = −[p]×, d/dv = I; d(rv)/dω ≈ I.
        let t = p.translation;
        let dfull = |row: usize, col: usize| -> f64 {
            match (row, col) {
                (r, c) if r < 3 && c < 3 => f64::from(u8::from(r == c)),
                (r, c) if r >= 3 && c >= 3 => f64::from(u8::from(r == c)),
                (r, c) if r >= 3 => {
                    // −[t]× (r−3, c)
                    let sk = [[0.0, t.z, -t.y], [-t.z, 0.0, t.x], [t.y, -t.x, 0.0]];
                    sk[r - 3][c]
                }
                _ => 0.0,
            }
        };
        for (a, &ra) in cols.iter().enumerate() {
            d[i * b + a] = full[ra];
            for (c, &cc) in cols.iter().enumerate() {
                jd[(i * b + a, i * b + c)] = dfull(ra, cc);
            }
        }
    }
    (d, jd)
}

/// Solve the constraints together with `slices.len()` linear slices through `config`:
/// `c_i · d(x) = o_i`, where `d(x)` stacks each unknown body's rotation vector and
/// translation change from `config` (planar: its `B` embedded components). Dense Gauss–Newton
/// with minimum-norm steps from `from`; the solution, or `None` when the residual stays above
/// `tol`.
fn solve_sliced(
    sys: &System,
    model: &PositionModel,
    targets: &Targets,
    config: &Configuration,
    from: &Configuration,
    slices: &[(DVector<f64>, f64)],
    tol: f64,
) -> Option<Configuration> {
    let b = model.b();
    let n = sys.bodies.len() * b;
    let mut x = from.clone();
    let coords = |x: &Configuration| slice_coords(sys, model, config, x);
    let eval = |x: &Configuration| -> (DVector<f64>, DMatrix<f64>) {
        let (r, j, _) = sys.evaluate(model, targets, x);
        let (d, jd) = coords(x);
        let rows = r.len() + slices.len();
        let mut rr = DVector::zeros(rows);
        let mut jj = DMatrix::zeros(rows, n);
        rr.rows_mut(0, r.len()).copy_from(&r);
        jj.view_mut((0, 0), (j.nrows(), n)).copy_from(&j);
        for (k, (c, o)) in slices.iter().enumerate() {
            rr[r.len() + k] = c.dot(&d) - o;
            let row = c.transpose() * &jd;
            jj.row_mut(r.len() + k).copy_from(&row);
        }
        (rr, jj)
    };
    let inf = |r: &DVector<f64>| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (mut r, mut j) = eval(&x);
    let mut slow = 0;
    for _ in 0..40 {
        if !r.iter().chain(j.iter()).all(|v| v.is_finite()) {
            return None;
        }
        if inf(&r) <= TIGHT {
            break;
        }
        let svd = nalgebra::SVD::try_new(j.clone(), true, true, f64::EPSILON, 10_000)?;
        let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
        let step = svd.solve(&(-&r), 1e-10 * top.max(1e-300)).ok()?;
        let norm0 = r.norm();
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let mut y = x.clone();
            for (i, &body) in sys.bodies.iter().enumerate() {
                let tw: Vec<f64> = (0..b).map(|k| t * step[i * b + k]).collect();
                y.poses[body] = x.poses[body].moved_by(model.space, &tw);
            }
            let (r2, j2) = eval(&y);
            if r2.norm() < norm0 {
                // A set of lower dimension than the slices' count: Newton creeps.
                slow = if r2.norm() > 0.9 * norm0 { slow + 1 } else { 0 };
                (x, r, j) = (y, r2, j2);
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted || slow >= 5 {
            break;
        }
    }
    (inf(&r) <= tol).then_some(x)
}

/// Residual a slice solution is found to (model units).
const LOOSE: f64 = 1e-9;
/// Residual a slice solution must be reached to at its moved offsets to be confirmed.
const TIGHT: f64 = 1e-12;
/// Independent trials of the slicing test at most (two, a third when they disagree).
const TRIALS: usize = 3;

/// Finite against first-order mobility of `m` at `config` (driven DOF ignored).
pub fn finite_mobility(
    m: &Mechanism,
    config: &Configuration,
    opts: &FiniteOptions,
) -> Result<FiniteMobility, ModelError> {
    if m.bodies.len() > MAX_BODIES {
        return Err(ModelError::TooLarge {
            bodies: m.bodies.len(),
            limit: MAX_BODIES,
        });
    }
    let free = undriven(m);
    let model = PositionModel::new(&free)?;
    let b = model.b();
    let sys = System {
        pairs: (0..model.pairs.len()).collect(),
        bodies: (0..m.bodies.len()).filter(|&x| x != m.frame).collect(),
    };
    let targets: Targets = vec![Vec::new(); model.pairs.len()];
    let count = b as i64 * sys.bodies.len() as i64
        - model
            .pairs
            .iter()
            .map(|p| (b - m.joints[p.joint].grade().min(b as u32) as usize) as i64)
            .sum::<i64>();
    let (_, j0, _) = sys.evaluate(&model, &targets, config);
    let n0 = null_basis(&j0, opts.rank_tolerance);
    let first_order = n0.ncols();
    let mut rng = SplitMix64::new(opts.seed ^ 0xF1_u64);
    let mut samples = Vec::new();
    let mut best: Option<(usize, DMatrix<f64>)> = None;
    let newton = NewtonOptions {
        tolerance: 1e-13,
        max_iterations: 40,
        ..NewtonOptions::default()
    };
    // Whether a sample found a curve of solutions through `config` (local dimension >= 1).
    let mut curve = false;
    if first_order > 0 {
        for _ in 0..opts.samples {
            let c = DVector::from_fn(first_order, |_, _| rng.next_signed());
            let dir = &n0 * c;
            let norm = dir.norm().max(1e-300);
            let mut moved = config.clone();
            for (i, &body) in sys.bodies.iter().enumerate() {
                let t: Vec<f64> = (0..b).map(|k| dir[i * b + k] / norm * opts.step).collect();
                moved.poses[body] = config.poses[body].moved_by(model.space, &t);
            }
            let out = sys.solve(&model, &targets, &mut moved, &newton);
            if out.residual > 1e-9 {
                continue;
            }
            let (_, j1, _) = sys.evaluate(&model, &targets, &moved);
            let n1 = null_basis(&j1, opts.rank_tolerance);
            samples.push(n1.ncols());
            // A curve of solutions through `config`: the projection from half the step along
            // the same direction lands about half as far (an isolated point with a
            // first-order flex pulls both back to itself; equations homogeneous to leading
            // order at a singular point scale their solutions with the start).
            let (d, _) = slice_coords(&sys, &model, config, &moved);
            if !curve && d.norm() > 0.1 * opts.step {
                let mut half = config.clone();
                for (i, &body) in sys.bodies.iter().enumerate() {
                    let t: Vec<f64> = (0..b)
                        .map(|k| dir[i * b + k] / norm * 0.5 * opts.step)
                        .collect();
                    half.poses[body] = config.poses[body].moved_by(model.space, &t);
                }
                let out2 = sys.solve(&model, &targets, &mut half, &newton);
                if out2.residual <= 1e-9 {
                    let (d2, _) = slice_coords(&sys, &model, config, &half);
                    curve = (0.3..=0.7).contains(&(d2.norm() / d.norm()));
                }
            }
            if best.as_ref().is_none_or(|(k, _)| n1.ncols() < *k) {
                best = Some((n1.ncols(), n1));
            }
        }
    }
    // The local dimension by slicing: the largest k such that the constraints with k random
    // linear slices at offsets of about `step` still have a solution near `config` (a set of
    // dimension d meets a generic slice of codimension k ≤ d, and misses one of codimension
    // d + 1). Unlike the nullity at a nearby sample, this is not fooled by components along
    // which the Jacobian stays rank-deficient (the N-four-bar's branches with flat windows).
    // Two random tries per k; each solution found is confirmed with its slices moved; k runs
    // up to the smallest sample nullity (an upper bound). At least 1 when a sample saw a
    // curve.
    let cap = best.as_ref().map(|(k, _)| *k).unwrap_or(first_order);
    // One trial of the slicing test with its own random stream: the dimension it finds.
    let trial = |rng: &mut SplitMix64, best: &mut Option<(usize, DMatrix<f64>)>| -> usize {
        let mut finite = 0;
        'dims: for k in 1..=cap {
            for _ in 0..2 {
                let slices: Vec<(DVector<f64>, f64)> = (0..k)
                    .map(|_| {
                        // A random direction of the first-order motions: a tangent slice.
                        let w = DVector::from_fn(first_order, |_, _| rng.next_signed());
                        let c = &n0 * w;
                        let c = &c / c.norm().max(1e-300);
                        // Offsets ten samples' steps: a set of lower dimension then misses the
                        // slices by a residual of order (10·step)² (10⁻⁴), far above what Newton
                        // reaches on a real solution.
                        (c, 10.0 * opts.step * rng.next_signed())
                    })
                    .collect();
                let found = solve_sliced(&sys, &model, &targets, config, config, &slices, LOOSE);
                // Confirm: a set of dimension k meets slices moved a little near the point found;
                // a near miss of lower dimension does not. Near a point where the equations have
                // double roots (the N-four-bar's flat pose: every window) a residual of 1e-9
                // allows errors of about 3e-5, so near misses of a union of curves pass within
                // 1e-9 of some codimension-k slices by chance (planar seed 1 gave 2). Hence two
                // moved offsets, each solved to 1e-12 (errors about 1e-6 at a double root): a
                // real solution is reached to rounding (Newton converges, linearly at worst), a
                // near miss stalls at about its distance squared.
                let confirmed = found.filter(|x| {
                    (0..2).all(|_| {
                        let moved: Vec<(DVector<f64>, f64)> = slices
                            .iter()
                            .map(|(c, o)| {
                                let by = 0.25 * o.abs().max(opts.step) * rng.next_signed();
                                (c.clone(), o + by)
                            })
                            .collect();
                        solve_sliced(&sys, &model, &targets, config, x, &moved, TIGHT).is_some()
                    })
                });
                if let Some(x) = confirmed {
                    let (_, j1, _) = sys.evaluate(&model, &targets, &x);
                    let n1 = null_basis(&j1, opts.rank_tolerance);
                    if best.as_ref().is_none_or(|(q, _)| n1.ncols() < *q) {
                        *best = Some((n1.ncols(), n1));
                    }
                    finite = k;
                    continue 'dims;
                }
            }
            break;
        }
        finite
    };
    // Independent trials (the first continues the samples' stream, the others have their
    // own): a single trial can be wrong at a non-reduced singular point (over seeds 0..=5 the
    // N-four-bar's 3D twin gave 0 once), so two trials, a third when they disagree, and the
    // majority (the median of three) is the answer; a disagreement is reported in the notes.
    let mut trials = Vec::new();
    if first_order > 0 {
        trials.push(trial(&mut rng, &mut best));
        for t in 1..TRIALS {
            if t == TRIALS - 1 && trials.iter().all(|&d| d == trials[0]) {
                break;
            }
            let mut own = SplitMix64::new(opts.seed ^ 0xF1_u64 ^ ((t as u64) << 40));
            trials.push(trial(&mut own, &mut best));
        }
    }
    let mut sorted = trials.clone();
    sorted.sort_unstable();
    let mut finite = sorted
        .get(sorted.len().saturating_sub(1) / 2)
        .copied()
        .unwrap_or(0);
    if curve {
        // At a very singular point (the N-four-bar's flat pose: 2^40 branches along which
        // the equations are not reduced) Newton on a random slice can creep and fail where
        // the samples saw the curve.
        finite = finite.max(1);
    }
    if first_order == 0 {
        finite = 0;
    }
    let near = best.map(|(_, n)| n).unwrap_or_else(|| n0.clone());
    // Relative motion of pair p over the columns of a basis.
    let motion = |basis: &DMatrix<f64>, p: usize| -> f64 {
        let pair = &model.pairs[p];
        let col = |body: usize| sys.bodies.iter().position(|&x| x == body);
        let mut worst: f64 = 0.0;
        for c in 0..basis.ncols() {
            let mut s = 0.0;
            for k in 0..b {
                let tb = col(pair.b).map(|i| basis[(i * b + k, c)]).unwrap_or(0.0);
                let ta = col(pair.a).map(|i| basis[(i * b + k, c)]).unwrap_or(0.0);
                s += (tb - ta) * (tb - ta);
            }
            worst = worst.max(s.sqrt());
        }
        worst
    };
    let mut singular_joints = Vec::new();
    let mut locked_at_toggle = Vec::new();
    let instantaneous_only = first_order.saturating_sub(finite);
    if instantaneous_only > 0 {
        // The part of the first-order motions far from the nearby tangent space.
        let proj = &n0 - &near * (near.transpose() * &n0);
        let svd = nalgebra::SVD::try_new(proj, true, false, f64::EPSILON, 10_000);
        if let Some((Some(u), values)) = svd.map(|d| (d.u, d.singular_values)) {
            let svd_values = values;
            let keep: Vec<usize> = (0..svd_values.len())
                .filter(|&i| svd_values[i] > 0.1)
                .collect();
            let extra = DMatrix::from_fn(u.nrows(), keep.len(), |r, c| u[(r, keep[c])]);
            for p in 0..model.pairs.len() {
                let id = &m.joints[model.pairs[p].joint].id;
                if motion(&extra, p) > 1e-6 && !singular_joints.contains(id) {
                    singular_joints.push(id.clone());
                }
            }
        }
    }
    if first_order > 0 {
        for p in 0..model.pairs.len() {
            let id = &m.joints[model.pairs[p].joint].id;
            if motion(&n0, p) < 1e-7 && motion(&near, p) > 1e-4 && !locked_at_toggle.contains(id) {
                locked_at_toggle.push(id.clone());
            }
        }
    }
    let singular = instantaneous_only > 0;
    let over = (finite as i64) > count;
    let verdict = match (singular, over) {
        (false, false) => Verdict::Regular,
        (true, false) => Verdict::Singular,
        (false, true) => Verdict::OverconstrainedMoving,
        (true, true) => Verdict::SingularOverconstrained,
    };
    let mut notes = Vec::new();
    if trials.iter().any(|&d| d != trials[0]) {
        notes.push(format!(
            "uncertain: independent slicing trials found local dimension {} (the majority, {}, is taken; the configuration is very singular, e.g. equations with double roots)",
            trials
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            sorted.get(sorted.len().saturating_sub(1) / 2).copied().unwrap_or(0)
        ));
    }
    if singular {
        notes.push(format!(
            "singular configuration: first-order mobility {first_order} but the mechanism moves with {finite} DOF; {instantaneous_only} freedom(s) are instantaneous only (joints {})",
            singular_joints.join(", ")
        ));
    }
    if over {
        notes.push(format!(
            "overconstrained by design but really moving: the count gives {count}, the mechanism moves with {finite} DOF ({} redundant constraint(s) hold along the motion)",
            finite as i64 - count
        ));
    }
    if !locked_at_toggle.is_empty() {
        notes.push(format!(
            "toggle: joint(s) {} are stationary in every first-order motion here but move at nearby configurations: locked only at this configuration",
            locked_at_toggle.join(", ")
        ));
    }
    Ok(FiniteMobility {
        count,
        first_order,
        finite,
        samples,
        verdict,
        instantaneous_only,
        singular_joints,
        locked_at_toggle,
        notes,
        assembled: false,
    })
}
