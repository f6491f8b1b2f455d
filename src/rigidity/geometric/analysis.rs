//! The analysis in steps: the pairs and each body's isolated motions, the parts the Jacobian
//! splits into, each part by the path its size and geometry call for (exact, sparse or dense
//! floating point), then the report from what the parts added up to.

use super::clusters::union_min;
use super::exact_part::ExactPart;
use super::jacobian::{
    Built, Complements, Incidence, Pair, Part, biconnected_parts, build_part, pairs_of,
};
use super::redundancy::{StressStep, Unweighted};
use super::report::{GeometricReport, JointCount, Numeric, RigidCluster};
use super::{sparse_float, threshold};
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::exact::Fp;
use crate::geometry::GeometryUsed;
use crate::mechanism::Mechanism;
use crate::motion::{self, JointModel};
use nalgebra::DMatrix;
use std::collections::{BTreeMap, BTreeSet};

/// Below this a norm or a singular value of the motions is zero (locked DOF, bodies moving
/// alike, structurally isolated motions).
pub(super) const ZERO_TOL: f64 = 1e-7;

/// What every step reads: the mechanism, its joint models at the geometry analysed, its
/// pairs and each body's isolated motions.
pub(super) struct Analysis<'a> {
    pub(super) m: &'a Mechanism,
    pub(super) models: &'a [JointModel],
    pub(super) used: GeometryUsed,
    /// At a random realization, every joint's exact rows.
    pub(super) exact: Option<&'a [DMatrix<Fp>]>,
    pub(super) budget: &'a Budget,
    pub(super) b: usize,
    pub(super) nb: usize,
    pub(super) frame: usize,
    pub(super) pairs: Vec<Pair>,
    pub(super) incident: Incidence,
    /// The dimensionless geometry of the models.
    pub(super) scale: motion::Scale,
    /// File geometry with joints far from the centre: the sparse path at any size.
    pub(super) far: bool,
    pub(super) rows_total: usize,
    /// Relative threshold of the null space of one body's or one cluster's joints.
    pub(super) local_rel: f64,
    /// Each body's fully isolated motions, and the complement its unknowns live in.
    pub(super) iso: Vec<DMatrix<f64>>,
    pub(super) comp: Complements,
}

/// What the parts add up to as they are analysed.
pub(super) struct Tally {
    pub(super) rank: usize,
    pub(super) float_rank: usize,
    pub(super) kept_min: f64,
    pub(super) dropped_max: f64,
    /// Each joint's weight (sum of its squared self-stress shares).
    pub(super) w: BTreeMap<usize, f64>,
    /// The largest ‖yᵀA‖ of the floating-point self-stresses the weights come from.
    pub(super) stress_residual: f64,
    /// Each part's self-stress step: done (its additions to `w`) or deferred.
    pub(super) stress_steps: Vec<StressStep>,
    pub(super) locked_by_joint: BTreeMap<usize, usize>,
    /// The rigid clusters as a union-find forest over the bodies.
    pub(super) uf: Vec<usize>,
    /// The relative tolerance reported.
    pub(super) tol: f64,
}

/// The groups of the reduced Jacobian: movable bodies with a non-empty complement, their
/// sizes and column offsets, and the number of columns.
struct Reduced {
    gbody: Vec<usize>,
    sizes: Vec<usize>,
    offsets: Vec<usize>,
    cols: usize,
}

#[allow(clippy::too_many_arguments)]
pub(super) fn analyze_models(
    m: &Mechanism,
    models: &[JointModel],
    full_twists: &dyn Fn() -> Vec<DMatrix<f64>>,
    used: GeometryUsed,
    exact: Option<&[DMatrix<Fp>]>,
    check_finite: bool,
    budget: &Budget,
    meter: &mut Meter,
    one_part: usize,
    exact_from: usize,
) -> Result<GeometricReport, BudgetExceeded> {
    let geometry = match used.seed {
        Some(seed) => format!("random (seed {seed})"),
        None => "file".to_string(),
    };
    let geometry_note = used.note.clone();
    let a = Analysis::new(m, models, used, exact, budget);
    let reduced = a.reduced();
    let parts = a.parts(one_part);
    let (built, smax) = a.build(&parts, exact_from, meter)?;
    let (base_tol, base_abs) = threshold(m, &a.used, smax, a.rows_total.max(a.b * m.movable()));
    let mut t = Tally {
        rank: 0,
        float_rank: 0,
        kept_min: f64::INFINITY,
        dropped_max: 0.0,
        w: BTreeMap::new(),
        stress_residual: 0.0,
        stress_steps: Vec::new(),
        locked_by_joint: BTreeMap::new(),
        uf: (0..a.nb).collect(),
        tol: base_tol,
    };
    let one_part = parts.len() == 1;
    for (part, bp) in parts.iter().zip(built) {
        let lcols: usize = bp.sizes.iter().sum();
        if let Some(rows) = exact
            && lcols > exact_from
        {
            a.exact_part(part, &bp.groups, rows, meter, &mut t)?;
            continue;
        }
        if exact.is_none() && (a.far || lcols > sparse_float::sparse_from()) {
            a.sparse_part(part, &bp, smax, meter, &mut t)?;
            continue;
        }
        a.dense_part(part, bp, smax, base_abs, one_part, meter, &mut t)?;
    }
    let steps = std::mem::take(&mut t.stress_steps);
    let (unweighted, unweighted_why) = a.weigh(steps, base_abs, meter, &mut t)?;
    Ok(a.report(
        t,
        Closing {
            geometry,
            geometry_note,
            reduced,
            smax,
            unweighted,
            unweighted_why,
            check_finite,
            full_twists,
        },
    ))
}

/// What the report needs beyond the tally.
struct Closing<'f> {
    geometry: String,
    geometry_note: Option<String>,
    reduced: Reduced,
    smax: f64,
    unweighted: BTreeSet<usize>,
    unweighted_why: Option<Unweighted>,
    check_finite: bool,
    full_twists: &'f dyn Fn() -> Vec<DMatrix<f64>>,
}

impl<'a> Analysis<'a> {
    /// The pairs, their incidence and each body's fully isolated motions.
    fn new(
        m: &'a Mechanism,
        models: &'a [JointModel],
        used: GeometryUsed,
        exact: Option<&'a [DMatrix<Fp>]>,
        budget: &'a Budget,
    ) -> Self {
        let b = m.b() as usize;
        let nb = m.bodies.len();
        let pairs = pairs_of(m);
        // The models are at the dimensionless geometry (`motion::scale_of`: about the centre,
        // in link lengths), so the length unit and the place do not matter. Joints many link
        // lengths from the centre (a long row of windows) still give the dense path's
        // centre-based twists lever arms of size L, which lose rank decisions as L grows; the
        // sparse path takes each body's twists about its own point.
        // (`with_sparse_from(usize::MAX, ..)` keeps the dense path for tests comparing the
        // two.)
        let scale = used.scale.unwrap_or(motion::Scale::IDENTITY);
        let far = used.is_file()
            && motion::lever(m, &scale) > sparse_float::FAR_LEVER
            && sparse_float::sparse_from() < usize::MAX;
        let rows_total: usize = pairs.iter().map(|p| models[p.joint].rows.nrows()).sum();
        let incident = Incidence::new(nb, &pairs);
        let local_rel = 1e-9 * b as f64 * 10.0;
        let mut a = Analysis {
            m,
            models,
            used,
            exact,
            budget,
            b,
            nb,
            frame: m.frame,
            pairs,
            incident,
            scale,
            far,
            rows_total,
            local_rel,
            iso: Vec::new(),
            comp: Complements::new(0, b),
        };
        (a.iso, a.comp) = a.fully_isolated();
        a
    }

    /// The groups of the reduced Jacobian.
    fn reduced(&self) -> Reduced {
        let mut gbody = Vec::new();
        let mut sizes = Vec::new();
        for body in 0..self.nb {
            if body != self.frame && self.comp[body].ncols() > 0 {
                gbody.push(body);
                sizes.push(self.comp[body].ncols());
            }
        }
        let mut offsets = Vec::new();
        let mut acc = 0;
        for &s in &sizes {
            offsets.push(acc);
            acc += s;
        }
        Reduced {
            gbody,
            sizes,
            offsets,
            cols: acc,
        }
    }

    /// The parts analysed. The Jacobian splits over the biconnected blocks of the body graph
    /// (pairs as edges): in coordinates relative to each block's root (its cut body nearest
    /// the frame), a block's rows act on its own bodies only, so ranks, null spaces and
    /// self-stresses add up over the blocks. Mechanisms of at most `one_part` unknowns are one
    /// part (the whole Jacobian, frame fixed).
    fn parts(&self, one_part: usize) -> Vec<Part> {
        if self.b * self.m.movable() <= one_part {
            vec![Part {
                root: self.frame,
                pairs: (0..self.pairs.len()).collect(),
                bodies: (0..self.nb).collect(),
            }]
        } else {
            biconnected_parts(self.nb, &self.pairs, self.frame)
        }
    }

    /// Each part's row blocks, and σ_max over all of them.
    fn build(
        &self,
        parts: &[Part],
        exact_from: usize,
        meter: &mut Meter,
    ) -> Result<(Vec<Built>, f64), BudgetExceeded> {
        let b = self.b;
        let mut built: Vec<Built> = Vec::with_capacity(parts.len());
        for part in parts {
            meter
                .charge(part.pairs.len() as u64 * (b * b * 4) as u64 + part.bodies.len() as u64)?;
            let mut bp = build_part(part, &self.pairs, self.models, &self.comp, self.frame);
            if self.exact.is_some() && bp.sizes.iter().sum::<usize>() > exact_from {
                // The exact path takes its rows from `exact`: the floating-point blocks were
                // needed for σ_max only (hundreds of megabytes at 10^6 bodies).
                bp.blocks = Vec::new();
            }
            built.push(bp);
        }
        let smax = built.iter().map(|x| x.smax).fold(0.0, f64::max);
        Ok((built, smax))
    }
}

impl Analysis<'_> {
    /// A large part at a random realization, analysed exactly ([`ExactPart`]); its
    /// floating-point self-stresses deferred to the end.
    fn exact_part(
        &self,
        part: &Part,
        groups: &[usize],
        rows: &[DMatrix<Fp>],
        meter: &mut Meter,
        t: &mut Tally,
    ) -> Result<(), BudgetExceeded> {
        let ctx = ExactPart {
            part,
            pairs: &self.pairs,
            models: self.models,
            rows,
            iso: &self.iso,
            incident: &self.incident,
            frame: self.frame,
            b: self.b,
        };
        let (r, luf, support) = ctx.run(self.budget, meter, &mut t.locked_by_joint)?;
        let prow: usize = part
            .pairs
            .iter()
            .map(|&pi| self.models[self.pairs[pi].joint].rows.nrows())
            .sum();
        if let Some(support) = support.filter(|_| prow > r) {
            t.stress_steps.push(StressStep::Exact(
                self.deferred(part, &support, groups, prow, r),
            ));
        }
        t.rank += r;
        t.float_rank += r;
        for (x, &l) in luf.iter().enumerate() {
            if l != x {
                union_min(&mut t.uf, part.bodies[l], part.bodies[x]);
            }
        }
        Ok(())
    }

    /// A large part at the file's geometry: the sparse floating-point path.
    fn sparse_part(
        &self,
        part: &Part,
        bp: &Built,
        smax: f64,
        meter: &mut Meter,
        t: &mut Tally,
    ) -> Result<(), BudgetExceeded> {
        let out = sparse_float::SparsePart {
            m: self.m,
            part,
            pairs: &self.pairs,
            models: self.models,
            comp: &self.comp,
            iso: &self.iso,
            b: self.b,
            used: &self.used,
            ntol: self.rows_total.max(self.b * self.m.movable()),
            smax,
            groups: &bp.groups,
            sizes: &bp.sizes,
        }
        .run(
            self.budget,
            meter,
            &mut t.w,
            &mut t.locked_by_joint,
            &mut t.uf,
        )?;
        t.rank += out.rank;
        t.float_rank += out.rank;
        t.kept_min = t.kept_min.min(out.kept_min);
        t.dropped_max = t.dropped_max.max(out.dropped_max);
        t.stress_residual = t.stress_residual.max(out.stress_residual);
        Ok(())
    }

    /// The report from what the parts added up to. Over 80 lines: the report's literal takes
    /// one line a field.
    fn report(self, t: Tally, c: Closing) -> GeometricReport {
        let (m, nb, frame, b) = (self.m, self.nb, self.frame, self.b);
        let id = |i: usize| m.body_id(i).to_string();
        let (rank, smax) = (t.rank, c.smax);
        let exact_note = self.exact.map(|_| {
            if t.float_rank == rank {
                "rank decided exactly over GF(2^61 - 1) at a random realization".to_string()
            } else {
                format!(
                    "rank decided exactly over GF(2^61 - 1): {rank}; the floating-point \
                     motions below come from a rank-{} elimination and may be approximate",
                    t.float_rank
                )
            }
        });
        let fully: usize = (0..nb)
            .filter(|&x| x != frame)
            .map(|x| self.iso[x].ncols())
            .sum();
        let mobility = fully + c.reduced.cols.saturating_sub(rank);
        let redundant = self.rows_total.saturating_sub(rank);
        let frame_spin = self.frame_spin(
            &c.reduced.gbody,
            &c.reduced.offsets,
            &c.reduced.sizes,
            c.reduced.cols,
        );
        let redundant_joints = self.ranked_joints(t.w);
        let locked: usize = t.locked_by_joint.values().sum();
        let locked_joints = self.locked_joints(t.locked_by_joint);
        let mut uf = t.uf;
        let clusters = super::clusters::clusters(&mut uf);
        let rigid = self.rigid(&clusters);
        let count = self.count();
        let (isolated_motions, structurally) = self.isolated_motions(&clusters, frame_spin);
        let isolated = fully + structurally;
        let (loops, loops_note) = super::loops::loops(m, c.full_twists);
        let numeric = numeric(smax, t.kept_min, t.dropped_max, t.tol, exact_note);
        let redundant_joints_unweighted: Vec<String> = c
            .unweighted
            .iter()
            .map(|&j| m.joints[j].id.clone())
            .collect();
        let weights_note = self.weights_note(
            smax,
            t.stress_residual,
            c.unweighted_why,
            redundant_joints_unweighted.len(),
            !redundant_joints.is_empty(),
        );
        GeometricReport {
            name: m.name.clone(),
            space: m.space,
            b: m.b(),
            frame: id(frame),
            geometry: c.geometry,
            geometry_note: c.geometry_note,
            geometry_used: self.used,
            bodies: nb,
            rows: self.rows_total,
            columns: b * m.movable(),
            rank,
            count,
            mobility,
            redundant,
            redundant_joints,
            redundant_joints_unweighted,
            locked,
            locked_joints,
            driven: m.joints.iter().map(|j| u64::from(j.driven)).sum(),
            isolated,
            fully_isolated: fully,
            structurally_isolated: structurally,
            isolated_motions,
            proper_mobility: mobility as i64 - isolated as i64,
            rigid,
            loops,
            loops_note,
            weights_note,
            finite_note: c.check_finite.then(|| {
                "finite-mobility check not implemented: results are instantaneous".to_string()
            }),
            numeric,
        }
    }
}

impl Analysis<'_> {
    /// Chebyshev-Gruebler-Kutzbach count with the driven DOF fixed.
    fn count(&self) -> i64 {
        (self.b * self.m.movable()) as i64
            - self
                .pairs
                .iter()
                .map(|p| self.models[p.joint].rows.nrows() as i64)
                .sum::<i64>()
    }

    /// The joints with locked DOF, in joint order.
    fn locked_joints(&self, locked_by_joint: BTreeMap<usize, usize>) -> Vec<JointCount> {
        locked_by_joint
            .into_iter()
            .filter(|(_, v)| *v > 0)
            .map(|(j, v)| JointCount {
                joint: self.m.joints[j].id.clone(),
                dof: v,
            })
            .collect()
    }

    /// The rigid clusters reported: two or more bodies, or the frame's.
    fn rigid(&self, clusters: &BTreeMap<usize, Vec<usize>>) -> Vec<RigidCluster> {
        let frame = self.frame;
        clusters
            .values()
            .filter(|c| c.len() > 1 || c.contains(&frame))
            .map(|c| RigidCluster {
                bodies: c.iter().map(|&x| self.m.body_id(x).to_string()).collect(),
                frame: c.contains(&frame),
            })
            .collect()
    }
}

/// The numerical facts of the rank decisions, relative to σ_max and to 3 significant digits,
/// with a warning when one lies within a factor 100 of the threshold (unless the rank was
/// decided exactly).
fn numeric(
    smax: f64,
    kept_min: f64,
    dropped_max: f64,
    tol: f64,
    exact_note: Option<String>,
) -> Numeric {
    let rel = |x: f64| if smax > 0.0 { x / smax } else { x };
    let smallest_kept = kept_min.is_finite().then(|| rel(kept_min));
    let largest_dropped = (dropped_max > 0.0).then(|| rel(dropped_max));
    let mut warning = None;
    if exact_note.is_none()
        && (smallest_kept.is_some_and(|k| k < tol * 1e2)
            || largest_dropped.is_some_and(|x| x > tol / 1e2))
    {
        warning = Some(format!(
            "ill-conditioned: a rank decision lies within a factor 100 of the threshold {:.1e} \
             (smallest kept {:.1e}, largest dropped {:.1e}); the configuration may be near a \
             singularity",
            tol,
            smallest_kept.unwrap_or(f64::NAN),
            largest_dropped.unwrap_or(0.0)
        ));
    }
    let sig = |x: f64| {
        if x == 0.0 {
            0.0
        } else {
            let e = x.abs().log10().floor();
            let f = 10f64.powf(e - 2.0);
            (x / f).round() * f
        }
    };
    Numeric {
        tolerance: tol,
        sigma_max: sig(smax),
        smallest_kept: smallest_kept.map(sig),
        largest_dropped: largest_dropped.map(sig),
        warning,
        exact: exact_note,
    }
}
