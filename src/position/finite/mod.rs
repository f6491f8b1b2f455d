//! Finite mobility: the local dimension of the solution set at a configuration, against the
//! first-order (instantaneous) mobility.
//!
//! The first-order mobility is the nullity of the constraint Jacobian (frame fixed, driven
//! DOF not counted). The local dimension is found by curve tests on random tangent
//! hyperplanes through the configuration ([`finite_mobility`]): it is at least k + 1 when the
//! constraints with k such slices still have a curve of solutions through the configuration,
//! certified by tracking a landed solution outward and inward along a fixed direction to a
//! residual of 1e-14 ([`Curves::certified`]). The nullity at a few nearby samples is still
//! reported (and used to name the joints of the instantaneous-only freedoms), but it is not
//! the estimate: on a non-reduced component (the N-four-bar's flat pose) it overstates the
//! dimension. `docs/algorithms.md` ("Finite mobility") gives the argument, the measurements
//! and the limits.

mod joints;

use super::closure::{ClosureStatus, assemble, check_closure, undriven};
use super::newton::{NewtonOptions, System, Targets};
use super::pose::Configuration;
use super::residual::{ModelError, PositionModel};
use super::solve::SolveError;
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use crate::rng::SplitMix64;
use joints::{PairMotion, instantaneous_joints, locked_freedoms, locked_note, toggle_joints};
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
    /// Work cap: every Gauss–Newton step, evaluation and SVD is charged to a meter of
    /// [`Budget::max_work`] (deterministic units, about the dense flops).
    pub budget: Budget,
}

impl Default for FiniteOptions {
    fn default() -> Self {
        FiniteOptions {
            samples: 4,
            step: 1e-3,
            seed: 0,
            rank_tolerance: 1e-8,
            budget: Budget::DEFAULT,
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
    /// The geometry's numbers are rounded and the test, which takes them as exact, disagrees
    /// with the first-order count at their precision (or finds fewer finite than first-order
    /// freedoms): whether the difference is a singular configuration or the rounding's
    /// cannot be told from these numbers ([`caveat_rounded`]).
    Undecided,
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
    /// Set with [`Verdict::Undecided`]: how precisely the geometry's numbers are known (file
    /// units), which this test took as exact ([`caveat_rounded`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rounded: Option<f64>,
}

/// The test takes the geometry's numbers as exact, while the first-order analyses take
/// rounded numbers as known to their `precision` (file units; 0 when exact): rounding alone
/// can lock a linkage that moves by design (`@bennett-rounded-8`: first order 1, finite 0 as
/// written; `@bennett-rounded-4`: first order 0 as written, true mobility 1 at its precision).
/// So on rounded numbers the test's answer stands only where it agrees with the first-order
/// count at their precision (`first_order_at_precision`, the geometric analysis's true
/// mobility, when known) and finds every first-order freedom finite. Otherwise the verdict
/// becomes [`Verdict::Undecided`], the singular-configuration note gives way to one that says
/// what was found taken as exact and what cannot be told, and [`FiniteMobility::rounded`]
/// holds the precision. `mbsa analyze` does not run the test on rounded numbers for the same
/// reason ([`crate::structure::check_finite`]); `--tolerance 0` takes them as exact in both.
pub fn caveat_rounded(
    f: &mut FiniteMobility,
    precision: f64,
    first_order_at_precision: Option<usize>,
) {
    let agrees = first_order_at_precision.is_none_or(|k| k == f.first_order);
    let rounded = precision > 0.0;
    if !rounded || (agrees && f.finite >= f.first_order) {
        return;
    }
    f.notes.retain(|n| !n.starts_with("singular configuration"));
    let at_precision = match first_order_at_precision {
        Some(k) if k != f.first_order => {
            format!(", where the first-order count at their precision is {k}")
        }
        _ => String::new(),
    };
    f.notes.push(format!(
        "not decided: the geometry's numbers are rounded (known to ±{precision:e}) and this test \
         takes them as exact; so taken they allow {} DOF to first order and {} for finite \
         motion{at_precision}. Rounding alone can lock a linkage that moves by design (a Bennett \
         linkage written to 8 digits), so whether the difference is a singular configuration's \
         or the rounding's cannot be told from these numbers: write them with more digits (or \
         take them as exact with `mbsa rigid --finite --tolerance 0`)",
        f.first_order, f.finite
    ));
    f.verdict = Verdict::Undecided;
    f.rounded = Some(precision);
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
        return finite_mobility(m, &reference, opts);
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

/// Work units of one [`null_basis`] SVD per `max(rows, n) · n²`: nalgebra's SVD with `V`
/// takes about 23 ns per such step at 1,200 unknowns (40 s), where a unit is about 1 ns;
/// charged as 1, a 2,400-unknown loop ran for minutes inside its first SVD before the meter
/// could stop it.
const SVD_UNITS: u64 = 24;

/// The units of [`null_basis`] on a `rows × n` matrix.
fn svd_units(rows: usize, n: usize) -> u64 {
    let n = n as u64;
    (rows as u64)
        .max(n)
        .saturating_mul(n)
        .saturating_mul(n)
        .saturating_mul(SVD_UNITS)
}

/// The units of one Gauss–Newton step of [`solve_sliced`] on `rows × n`.
fn step_units(rows: usize, n: usize) -> u64 {
    let (rows, n) = (rows as u64, n as u64);
    rows.saturating_mul(n)
        .saturating_mul(n)
        .saturating_add(n.saturating_mul(n).saturating_mul(n))
}

/// [`null_basis`] charged to `meter` ([`svd_units`]).
fn null_basis_within(
    j: &DMatrix<f64>,
    rel: f64,
    meter: &mut Meter,
) -> Result<DMatrix<f64>, BudgetExceeded> {
    meter.charge(svd_units(j.nrows(), j.ncols()))?;
    Ok(null_basis(j, rel))
}

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
        let rv = super::pose::log_rotation(&(p.rotation * p0.rotation.transpose()));
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

/// The configuration at slice coordinates `d` from `config` (the inverse of
/// [`slice_coords`]: each unknown body rotated by its rotation vector, translated by its
/// translation change).
fn from_coords(
    sys: &System,
    model: &PositionModel,
    config: &Configuration,
    d: &DVector<f64>,
) -> Configuration {
    let b = model.b();
    let cols = super::pose::embed_columns(model.space);
    let mut x = config.clone();
    for (i, &body) in sys.bodies.iter().enumerate() {
        let mut full = [0.0; 6];
        for (a, &ra) in cols.iter().enumerate() {
            full[ra] = d[i * b + a];
        }
        let p0 = &config.poses[body];
        let r = nalgebra::Rotation3::new(nalgebra::Vector3::new(full[0], full[1], full[2]));
        x.poses[body] = super::pose::Pose {
            rotation: r.into_inner() * p0.rotation,
            translation: p0.translation + nalgebra::Vector3::new(full[3], full[4], full[5]),
        };
    }
    x
}

/// A damped Gauss–Newton step `−(JᵀJ + μI)⁻¹ Jᵀ r` (Cholesky; `μ` from `1e-16` of the
/// largest diagonal, raised tenfold while the factorization fails): the minimum-norm step to
/// within the damping, about 20 times cheaper than the SVD at 500 unknowns, but it stalls
/// near `1e-13` at non-reduced points, where [`solve_sliced`] finishes with
/// [`regularized_step`].
fn damped_step(j: &DMatrix<f64>, r: &DVector<f64>) -> Option<DVector<f64>> {
    let jtj = j.transpose() * j;
    let g = j.transpose() * r;
    let top = (0..jtj.nrows())
        .map(|i| jtj[(i, i)])
        .fold(0.0, f64::max)
        .max(1e-300);
    let mut mu = 1e-16 * top;
    for _ in 0..6 {
        let mut a = jtj.clone();
        for i in 0..a.nrows() {
            a[(i, i)] += mu;
        }
        if let Some(c) = nalgebra::Cholesky::new(a) {
            return Some(-c.solve(&g));
        }
        mu *= 10.0;
    }
    None
}

/// A Tikhonov-regularized Gauss–Newton step: the least-squares solution of
/// `[J; λI] δ = [−r; 0]` by Householder QR, `λ = 1e-10 ×` the largest column norm of `J`. No
/// squared condition number (unlike [`damped_step`]), so it converges to rounding at
/// non-reduced points like the minimum-norm SVD step (directions with singular values far
/// above λ solved exactly, far below it left still), at about a fifth of the SVD's cost.
fn regularized_step(j: &DMatrix<f64>, r: &DVector<f64>) -> Option<DVector<f64>> {
    let (m, n) = j.shape();
    let top = (0..n)
        .map(|c| j.column(c).norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    let mut a = DMatrix::zeros(m + n, n);
    a.view_mut((0, 0), (m, n)).copy_from(j);
    for i in 0..n {
        a[(m + i, i)] = 1e-10 * top;
    }
    let mut rhs = DVector::zeros(m + n);
    rhs.rows_mut(0, m).copy_from(r);
    let qr = nalgebra::QR::new(a);
    let qtr = qr.q().transpose() * rhs;
    let x = qr
        .r()
        .solve_upper_triangular(&qtr.rows(0, n).into_owned())?;
    Some(-x)
}

/// Residual below which [`solve_sliced`] takes regularized QR steps (the damped steps stall
/// near it).
const POLISH: f64 = 1e-12;
/// Regularized QR steps at most per solve.
const POLISH_STEPS: usize = 4;

/// Solve the constraints together with `slices.len()` linear slices through `config`:
/// `c_i · d(x) = o_i`, where `d(x)` stacks each unknown body's rotation vector and
/// translation change from `config` (planar: its `B` embedded components). Dense Gauss–Newton
/// from `from`: damped normal-equation steps while the residual is above [`POLISH`], then
/// regularized QR steps ([`regularized_step`]); the solution, or `None` when the residual
/// stays above `tol`. Every evaluation (`rows · n` units) and step (`rows · n² + n³`) is
/// charged to `meter`.
#[allow(clippy::too_many_arguments)]
fn solve_sliced(
    sys: &System,
    model: &PositionModel,
    targets: &Targets,
    config: &Configuration,
    from: &Configuration,
    slices: &[(DVector<f64>, f64)],
    tol: f64,
    meter: &mut Meter,
) -> Result<Option<Configuration>, BudgetExceeded> {
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
    let eval_units = (j.nrows() as u64).saturating_mul(n as u64).max(1);
    let step_units = step_units(j.nrows(), n);
    meter.charge(eval_units)?;
    let mut slow = 0;
    let mut polish_steps = 0;
    for _ in 0..40 {
        if !r.iter().chain(j.iter()).all(|v| v.is_finite()) {
            return Ok(None);
        }
        meter.charge(step_units)?;
        if inf(&r) <= tol {
            break;
        }
        let damped = if inf(&r) > POLISH {
            damped_step(&j, &r)
        } else {
            None
        };
        let step = match damped {
            Some(s) => s,
            None => {
                if polish_steps == POLISH_STEPS {
                    break;
                }
                polish_steps += 1;
                match regularized_step(&j, &r) {
                    Some(s) => s,
                    None => return Ok(None),
                }
            }
        };
        let norm0 = r.norm();
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let mut y = x.clone();
            for (i, &body) in sys.bodies.iter().enumerate() {
                let tw: Vec<f64> = (0..b).map(|k| t * step[i * b + k]).collect();
                y.poses[body] = x.poses[body].moved_by(model.space, &tw);
            }
            meter.charge(eval_units)?;
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
    Ok((inf(&r) <= tol).then_some(x))
}

/// Residual a landed point is projected to (model units).
const LAND: f64 = 1e-12;
/// Residual every point of a curve certificate is solved to (model units).
const TRACK: f64 = 1e-14;
/// Starts per level of the curve test (at least; level 0 takes `samples` if more).
const TRIES: usize = 4;
/// Halvings of a curve certificate toward the configuration.
const HALVINGS: i32 = 4;

/// The mechanism's data for the curve tests.
struct Curves<'a> {
    sys: &'a System,
    model: &'a PositionModel,
    targets: &'a Targets,
    config: &'a Configuration,
    step: f64,
}

impl Curves<'_> {
    /// The configuration moved from `config` along the twist column vector `v` (length
    /// `step`).
    fn start(&self, v: &DVector<f64>) -> Configuration {
        let b = self.model.b();
        let mut moved = self.config.clone();
        for (i, &body) in self.sys.bodies.iter().enumerate() {
            let t: Vec<f64> = (0..b).map(|k| v[i * b + k] * self.step).collect();
            moved.poses[body] = self.config.poses[body].moved_by(self.model.space, &t);
        }
        moved
    }

    /// Whether a curve of solutions of the constraints and `slices` (through `config`)
    /// passes through `config` and through the landed solution `y`, at distance
    /// `rho = |d(y)|`. With `u = d(y)/rho`, the extra slice `u·d(x) = s` is solved to
    /// [`TRACK`] at `s = 2ρ, 4ρ, ...` up to `2·step` (outward), then at `s = ρ/2, ...,
    /// ρ/16` (inward), each from the previous point scaled to `s`; every point must stay in
    /// a narrow cone about the previous one (`|d| ≤ 1.2 s`, direction within 18°).
    /// Inward: the curve reaches `config` (a component passing near it stops). Outward: it
    /// is a curve of exact solutions, not a near miss. At a non-reduced point (double roots)
    /// a residual of 1e-14 is met by whole thin neighbourhoods of the branches, and a slice
    /// nearly tangent to a branch (at angle θ) keeps near-solutions along it to a distance of
    /// about `sqrt(1e-14)/θ`; there the residual grows as the square of the distance, so the
    /// outward points (to 2·step) miss [`TRACK`] while a real curve is solved to rounding.
    fn certified(
        &self,
        slices: &[(DVector<f64>, f64)],
        d: &DVector<f64>,
        meter: &mut Meter,
    ) -> Result<bool, BudgetExceeded> {
        let rho = d.norm();
        let u = d / rho;
        let mut plan = Vec::new();
        let mut s = rho;
        while s < 2.0 * self.step && plan.len() < 8 {
            s *= 2.0;
            plan.push(s);
        }
        let outward = plan.len();
        plan.extend((1..=HALVINGS).map(|h| rho * 0.5f64.powi(h)));
        let mut prev = d.clone();
        let mut prev_s = rho;
        for (i, &s) in plan.iter().enumerate() {
            if i == outward {
                prev = d.clone();
                prev_s = rho;
            }
            let from = from_coords(self.sys, self.model, self.config, &(&prev * (s / prev_s)));
            let mut with = slices.to_vec();
            with.push((u.clone(), s));
            let Some(z) = solve_sliced(
                self.sys,
                self.model,
                self.targets,
                self.config,
                &from,
                &with,
                TRACK,
                meter,
            )?
            else {
                return Ok(false);
            };
            let (dz, _) = slice_coords(self.sys, self.model, self.config, &z);
            let cos = dz.dot(&prev) / (dz.norm() * prev.norm()).max(1e-300);
            let in_cone = dz.norm() <= 1.2 * s && cos >= 0.95; // false for NaN too
            if !in_cone {
                return Ok(false);
            }
            prev = dz;
            prev_s = s;
        }
        Ok(true)
    }
}

/// Finite against first-order mobility of `m` at `config` (driven DOF ignored).
///
/// The local dimension is found by curve tests on slices through the configuration: it is
/// at least `k + 1` when the constraints together with `k` random tangent hyperplanes
/// through `config` still have a curve of solutions through `config` (a component of
/// dimension e through `config` meets `k < e` generic hyperplanes through it in a set of
/// dimension `e − k ≥ 1` there; one of dimension `e ≤ k` only in `config`). A curve is
/// certified from a landed point (a random first-order motion of length `step` in the
/// slices, projected back by Gauss–Newton) by [`Curves::certified`]; `k` runs up from 0
/// and stops at the first level where no start is certified.
///
/// The work (every solve, evaluation and SVD) is charged to a meter of `opts.budget`: past
/// it, [`SolveError::Budget`] (a mechanism with many freedoms and no full row rank runs one
/// slicing level per freedom).
pub fn finite_mobility(
    m: &Mechanism,
    config: &Configuration,
    opts: &FiniteOptions,
) -> Result<FiniteMobility, SolveError> {
    if m.bodies.len() > MAX_BODIES {
        return Err(ModelError::TooLarge {
            bodies: m.bodies.len(),
            limit: MAX_BODIES,
        }
        .into());
    }
    let mut meter = opts.budget.meter("the finite-mobility test");
    let meter = &mut meter;
    let free = undriven(m);
    let model = PositionModel::new(&free)?;
    let b = model.b();
    let sys = System {
        pairs: (0..model.pairs.len()).collect(),
        bodies: (0..m.bodies.len()).filter(|&x| x != m.frame).collect(),
    };
    let targets: Targets = vec![Vec::new(); model.pairs.len()];
    // Each pair's constraints: at least as many rows of the Jacobian.
    let rows: usize = model
        .pairs
        .iter()
        .map(|p| b - m.joints[p.joint].grade().min(b as u32) as usize)
        .sum();
    let count = b as i64 * sys.bodies.len() as i64 - rows as i64;
    // The least the test does, from the sizes alone: the first SVD and one Gauss–Newton step
    // per start of the first level. Over the budget, refused before any of it.
    let n = sys.bodies.len() * b;
    let least = svd_units(rows, n)
        .saturating_add(step_units(rows, n).saturating_mul(TRIES.max(opts.samples) as u64));
    opts.budget.check_work(least, || {
        format!("the finite-mobility test on {n} unknowns and {rows} constraint rows")
    })?;
    let (_, j0, _) = sys.evaluate(&model, &targets, config);
    let n0 = null_basis_within(&j0, opts.rank_tolerance, meter)?;
    let first_order = n0.ncols();
    let curves = Curves {
        sys: &sys,
        model: &model,
        targets: &targets,
        config,
        step: opts.step,
    };
    // Full row rank at the configuration: the constraints are a submersion there, so the
    // solution set is locally a manifold of dimension `first_order` (implicit function
    // theorem). Only the first level runs then, for the nearby samples; without this an open
    // chain of a few hundred joints ran one level per freedom (minutes).
    let regular = j0.ncols() - first_order == j0.nrows();
    let sure = if regular {
        1
    } else {
        (count.max(0) as usize).min(first_order)
    };
    // The levels sure to be certified (the solution set has dimension at least the count),
    // each at least a landing and the halvings of its certificate, two steps a solve:
    // refused now rather than after minutes of them.
    let per_level = step_units(rows + sure, n).saturating_mul(2 * (1 + HALVINGS as u64));
    opts.budget.check_work(
        meter
            .used()
            .saturating_add(per_level.saturating_mul(sure as u64)),
        || {
            format!(
                "the finite-mobility test on {n} unknowns and {rows} constraint rows, at least \
                 {sure} level(s) of curve tests,"
            )
        },
    )?;
    let levels = slice_levels(&curves, &n0, regular, sure, opts, meter)?;
    let finite = levels.finite;
    let near = levels.best.map(|(_, n)| n).unwrap_or_else(|| n0.clone());
    let motion = PairMotion {
        model: &model,
        sys: &sys,
    };
    let instantaneous_only = first_order.saturating_sub(finite);
    let singular_joints = if instantaneous_only > 0 {
        instantaneous_joints(m, &motion, &n0, &near)
    } else {
        Vec::new()
    };
    let locked_at_toggle = if first_order > 0 {
        toggle_joints(m, &motion, &n0, &near, opts.step)
    } else {
        Vec::new()
    };
    let mut r = finite_report(FiniteMobility {
        count,
        first_order,
        finite,
        samples: levels.samples,
        verdict: Verdict::Regular,
        instantaneous_only,
        singular_joints,
        locked_at_toggle,
        notes: Vec::new(),
        assembled: false,
        rounded: None,
    });
    // Every freedom locked here accounted for: the geometric report's "locked DOF" line
    // points here for those that move nearby.
    if first_order > 0 {
        let locked = locked_freedoms(m, &motion, &n0, &near, opts.step);
        r.notes.extend(locked_note(&locked));
    }
    Ok(r)
}

/// What the slicing levels of [`finite_mobility`] found: the local dimension, the nullities
/// of the nearby samples, and the nearby tangent space of least dimension met.
struct Levels {
    finite: usize,
    samples: Vec<usize>,
    best: Option<(usize, DMatrix<f64>)>,
}

/// The slicing levels of [`finite_mobility`] from the first-order motions `n0`: `k` runs up
/// from 0 while some start is certified on a curve within `k` random tangent hyperplanes.
///
/// `sure` levels are certain to be certified (the count): after each from the second on, the
/// work of those left is projected from the work of the levels since the first, and past the budget the test stops then, not at the
/// end of the budget.
fn slice_levels(
    curves: &Curves<'_>,
    n0: &DMatrix<f64>,
    regular: bool,
    sure: usize,
    opts: &FiniteOptions,
    meter: &mut Meter,
) -> Result<Levels, SolveError> {
    let mut after_first = meter.used();
    let first_order = n0.ncols();
    let (_, jd0) = slice_coords(curves.sys, curves.model, curves.config, curves.config);
    let mut rng = SplitMix64::new(opts.seed ^ 0xF1_u64);
    let mut levels = Levels {
        finite: 0,
        samples: Vec::new(),
        best: None,
    };
    let mut slices: Vec<(DVector<f64>, f64)> = Vec::new();
    while levels.finite < first_order {
        // The first-order motions that keep the slices: n0 times the null space of the
        // slices' rows on n0.
        let rows = DMatrix::from_fn(slices.len(), first_order, |i, c| {
            (slices[i].0.transpose() * &jd0 * n0.column(c))[(0, 0)]
        });
        let within = if slices.is_empty() {
            DMatrix::identity(first_order, first_order)
        } else {
            null_basis_within(&rows, 1e-8, meter)?
        };
        let kernel = n0 * within;
        if kernel.ncols() == 0 {
            break;
        }
        let found = try_starts(curves, &kernel, &slices, opts, &mut rng, &mut levels, meter)?;
        if regular {
            levels.finite = first_order;
            break;
        }
        if !found {
            break;
        }
        levels.finite += 1;
        // The first level also samples the nullity nearby: the projection starts after it.
        if levels.finite == 1 {
            after_first = meter.used();
        }
        if levels.finite >= 2 && levels.finite < sure {
            // Later levels cost at least what the earlier ones did (each adds a slice).
            let per_level = (meter.used() - after_first) / (levels.finite - 1) as u64;
            let left = (sure - levels.finite) as u64;
            let projected = meter.used().saturating_add(per_level.saturating_mul(left));
            opts.budget.check_work(projected, || {
                format!(
                    "the finite-mobility test (projected from its first {} of at least {sure} \
                     levels of curve tests)",
                    levels.finite
                )
            })?;
        }
        // One more random tangent hyperplane through the configuration.
        let w = DVector::from_fn(first_order, |_, _| rng.next_signed());
        let c = n0 * w;
        slices.push((&c / c.norm().max(1e-300), 0.0));
    }
    Ok(levels)
}

/// One level of [`slice_levels`]: random starts along the motions `kernel` that keep the
/// `slices`, landed and tested for a curve; the first level also samples the nullity at
/// the landed points. Whether a curve was certified.
fn try_starts(
    curves: &Curves<'_>,
    kernel: &DMatrix<f64>,
    slices: &[(DVector<f64>, f64)],
    opts: &FiniteOptions,
    rng: &mut SplitMix64,
    levels: &mut Levels,
    meter: &mut Meter,
) -> Result<bool, SolveError> {
    let (sys, model, targets, config) = (curves.sys, curves.model, curves.targets, curves.config);
    let tries = if slices.is_empty() {
        TRIES.max(opts.samples)
    } else {
        TRIES
    };
    let mut found = false;
    for t in 0..tries {
        let v = kernel * DVector::from_fn(kernel.ncols(), |_, _| rng.next_signed());
        let v = &v / v.norm().max(1e-300);
        let start = curves.start(&v);
        let Some(y) = solve_sliced(sys, model, targets, config, &start, slices, LAND, meter)?
        else {
            continue;
        };
        if slices.is_empty() && t < opts.samples {
            // A nearby sample: its nullity (at a generic point of a reduced component, the
            // component's dimension).
            let (_, j1, _) = sys.evaluate(model, targets, &y);
            let n1 = null_basis_within(&j1, opts.rank_tolerance, meter)?;
            levels.samples.push(n1.ncols());
            keep_least(&mut levels.best, n1);
        }
        if found {
            continue;
        }
        let (d, _) = slice_coords(sys, model, config, &y);
        // Pulled back to the configuration (an isolated point, or the double roots of a
        // non-reduced one, attract Newton): no evidence either way.
        let away = d.norm() >= 0.05 * opts.step; // false for NaN too
        if !away {
            continue;
        }
        if curves.certified(slices, &d, meter)? {
            found = true;
            if !slices.is_empty() {
                let (_, j1, _) = sys.evaluate(model, targets, &y);
                let n1 = null_basis_within(&j1, opts.rank_tolerance, meter)?;
                keep_least(&mut levels.best, n1);
            }
            if !slices.is_empty() || t + 1 >= opts.samples {
                break;
            }
        }
    }
    Ok(found)
}

/// Keep the nearby tangent basis `n1` if it has fewer columns than the best so far.
fn keep_least(best: &mut Option<(usize, DMatrix<f64>)>, n1: DMatrix<f64>) {
    if best.as_ref().is_none_or(|(k, _)| n1.ncols() < *k) {
        *best = Some((n1.ncols(), n1));
    }
}

/// The verdict and notes of a finite-mobility report from its counts and joints.
fn finite_report(mut r: FiniteMobility) -> FiniteMobility {
    let (count, first_order, finite) = (r.count, r.first_order, r.finite);
    let instantaneous_only = r.instantaneous_only;
    let singular = instantaneous_only > 0;
    // Really moving: a configuration that does not move (finite 0) is not "moving" whatever
    // the count (a rigid structure with redundant bars, a flat triangle written in space).
    let over = finite > 0 && (finite as i64) > count;
    r.verdict = match (singular, over) {
        (false, false) => Verdict::Regular,
        (true, false) => Verdict::Singular,
        (false, true) => Verdict::OverconstrainedMoving,
        (true, true) => Verdict::SingularOverconstrained,
    };
    if singular {
        r.notes.push(format!(
            "singular configuration: first-order mobility {first_order} but the mechanism moves with {finite} DOF; {instantaneous_only} freedom(s) are instantaneous only{}",
            // No joint is named when no nearby configuration was reached to compare with.
            if r.singular_joints.is_empty() {
                String::new()
            } else {
                format!(" (joints {})", r.singular_joints.join(", "))
            }
        ));
    }
    if over {
        r.notes.push(format!(
            "overconstrained by design but really moving: the count gives {count}, the mechanism moves with {finite} DOF ({} redundant constraint(s) hold along the motion)",
            finite as i64 - count
        ));
    }
    if !r.locked_at_toggle.is_empty() {
        r.notes.push(format!(
            "toggle: joint(s) {} are stationary in every first-order motion here but move at nearby configurations: locked only at this configuration",
            r.locked_at_toggle.join(", ")
        ));
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(first_order: usize, finite: usize, singular: bool) -> FiniteMobility {
        FiniteMobility {
            count: -2,
            first_order,
            finite,
            samples: Vec::new(),
            verdict: if singular {
                Verdict::Singular
            } else {
                Verdict::Regular
            },
            instantaneous_only: first_order.saturating_sub(finite),
            singular_joints: Vec::new(),
            locked_at_toggle: Vec::new(),
            notes: if singular {
                vec!["singular configuration: ...".into()]
            } else {
                Vec::new()
            },
            assembled: false,
            rounded: None,
        }
    }

    /// The caveat applies only to rounded numbers, and there only where the test disagrees
    /// with the first-order count at their precision or finds fewer finite freedoms.
    #[test]
    fn only_a_disagreement_on_rounded_numbers_is_undecided() {
        // Exact numbers: the test's verdict stands, singular or not.
        let mut f = report(1, 0, true);
        caveat_rounded(&mut f, 0.0, Some(1));
        assert_eq!(f, report(1, 0, true));
        // Rounded, agreeing, every freedom finite: unchanged.
        let mut f = report(1, 1, false);
        caveat_rounded(&mut f, 5e-5, Some(1));
        assert_eq!(f, report(1, 1, false));
        // Rounded, fewer finite freedoms: undecided, the singular note replaced.
        let mut f = report(1, 0, true);
        caveat_rounded(&mut f, 5e-8, Some(1));
        assert_eq!((f.verdict, f.rounded), (Verdict::Undecided, Some(5e-8)));
        assert_eq!(f.notes.len(), 1);
        assert!(f.notes[0].starts_with("not decided: "), "{:?}", f.notes);
        assert!(
            !f.notes[0].contains("at their precision is"),
            "{:?}",
            f.notes
        );
        // Rounded, first order below the count at precision: undecided, and it says so.
        let mut f = report(0, 0, false);
        caveat_rounded(&mut f, 5e-5, Some(1));
        assert_eq!(f.verdict, Verdict::Undecided);
        assert!(f.notes[0].contains("the first-order count at their precision is 1"));
        // Unknown count at precision (`solve --finite`): only fewer finite freedoms count.
        let mut f = report(0, 0, false);
        caveat_rounded(&mut f, 5e-5, None);
        assert_eq!(f, report(0, 0, false));
    }
}
