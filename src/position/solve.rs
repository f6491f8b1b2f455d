//! Solving the positions for given input values: group by group in the level order of the
//! structural analysis (groups of one level in parallel), or all at once (the reference).

use super::newton::{NewtonOptions, NewtonOutcome, System, Targets};
use super::pose::{Configuration, PoseReport};
use super::residual::{ModelError, PositionModel};
use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use rayon::prelude::*;
use serde::Serialize;
use std::borrow::Cow;
use std::collections::HashMap;

/// One step of the schedule: a structural group (or the bodies no group holds).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// Group name (`SG-I`...) or `rest` for bodies outside every group.
    pub name: String,
    /// Solve level (groups of one level are independent); `rest` comes after all.
    pub level: usize,
    /// Unknown bodies (indices).
    pub bodies: Vec<usize>,
    /// Pairs whose equations the step solves (indices into `PositionModel::pairs`).
    pub pairs: Vec<usize>,
}

/// A pair of a multiple joint that the model does not write but the schedule solves: the
/// joint's features on `a` against those on `b` (see [`schedule`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Link {
    /// Index of the joint in `Mechanism::joints`.
    pub joint: usize,
    /// A model pair of that joint (its equations, with `a` and `b` in place of its bodies).
    pub like: usize,
    /// First body (the joint's earliest known body).
    pub a: usize,
    /// Other body.
    pub b: usize,
}

/// The solve order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Schedule {
    /// Steps in order (levels ascending).
    pub steps: Vec<Step>,
    /// Extra pairs of multiple joints: a step's pair index `model.pairs.len() + i` is
    /// `links[i]`.
    pub links: Vec<Link>,
}

impl Schedule {
    /// `model` with the schedule's links appended as pairs (undriven), and `targets`
    /// extended to match; borrowed as they are when there are no links.
    pub fn extended<'a>(
        &self,
        model: &'a PositionModel,
        targets: &'a Targets,
    ) -> (Cow<'a, PositionModel>, Cow<'a, Targets>) {
        if self.links.is_empty() {
            return (Cow::Borrowed(model), Cow::Borrowed(targets));
        }
        let mut ext = model.clone();
        let mut tg = targets.clone();
        tg.resize(model.pairs.len(), Vec::new());
        for l in &self.links {
            let mut p = model.pairs[l.like].clone();
            p.a = l.a;
            p.b = l.b;
            p.driven = 0;
            p.offset = super::pose::Pose::identity();
            ext.pairs.push(p);
            tg.push(Vec::new());
        }
        (Cow::Owned(ext), Cow::Owned(tg))
    }
}

/// One structural group as a solve order sees it.
pub struct OrderedGroup<'a> {
    /// The group's name (`SG-I`).
    pub name: &'a str,
    /// Its solve level.
    pub level: usize,
    /// Its bodies, by id.
    pub bodies: &'a [String],
}

/// A solve order: the structural groups with their levels, and the bodies of an
/// over-determined part, solved first. The structural analysis
/// ([`crate::structure::Analysis`]) gives one; the position level needs nothing else of it.
pub trait SolveOrder {
    /// The groups, in the analysis' order.
    fn groups(&self) -> Vec<OrderedGroup<'_>>;
    /// The bodies of the over-determined part, if any.
    fn overdetermined(&self) -> Option<&[String]>;
}

/// The schedule of `m` from its structural analysis: the over-determined part first (it is
/// known with the frame: step `over`, level 0), the groups by level, then the bodies no group
/// holds (an under-determined part) as one last step `rest`; the first step is named
/// `overdetermined`. A pair is solved by the first
/// step after which both its bodies are known.
///
/// A multiple joint is written in the model as pairs from its first listed body to each
/// other one; the structural analysis sees it symmetrically (a node that belongs to the group
/// placing its first bodies). When a step places some of its bodies before its first listed
/// body is known (the pin `P = [2, 3, 4]` of the published case, bodies 3 and 4 in `SG-II`,
/// 2 in `SG-III`), those pairs cannot tie 3 and 4 together where the analysis does: that step would be
/// under-determined and the later one over-determined (and inconsistent). Such a joint is
/// rooted at its earliest known body instead ([`Schedule::links`]: root against each other
/// body, solved where that body becomes known), and the model's pairs between the first body
/// and the others are left out of the schedule unless driven. The equations are the same
/// joint's, so the solution set is unchanged and independent of the listing order.
pub fn schedule<O: SolveOrder + ?Sized>(m: &Mechanism, a: &O, model: &PositionModel) -> Schedule {
    let groups = a.groups();
    let by_id: HashMap<String, usize> = (0..m.bodies.len())
        .map(|i| (m.body_id(i).to_string(), i))
        .collect();
    let mut order: Vec<usize> = (0..groups.len()).collect();
    order.sort_by_key(|&g| (groups[g].level, g));
    let mut placed = vec![false; m.bodies.len()];
    placed[m.frame] = true;
    let mut steps: Vec<Step> = Vec::new();
    let take = |ids: &[String], placed: &mut Vec<bool>| -> Vec<usize> {
        let bodies: Vec<usize> = ids
            .iter()
            .filter_map(|id| by_id.get(id).copied())
            .filter(|&b| !placed[b])
            .collect();
        for &b in &bodies {
            placed[b] = true;
        }
        bodies
    };
    if let Some(over) = a.overdetermined() {
        let bodies = take(over, &mut placed);
        if !bodies.is_empty() {
            steps.push(Step {
                name: "overdetermined".into(),
                level: 0,
                bodies,
                pairs: Vec::new(),
            });
        }
    }
    for g in order {
        let grp = &groups[g];
        let bodies = take(grp.bodies, &mut placed);
        if !bodies.is_empty() {
            steps.push(Step {
                name: grp.name.to_string(),
                level: grp.level,
                bodies,
                pairs: Vec::new(),
            });
        }
    }
    let rest: Vec<usize> = (0..m.bodies.len()).filter(|&b| !placed[b]).collect();
    if !rest.is_empty() {
        let level = steps.iter().map(|s| s.level).max().unwrap_or(0) + 1;
        steps.push(Step {
            name: "rest".into(),
            level,
            bodies: rest,
            pairs: Vec::new(),
        });
    }
    // Step index at which each body becomes known.
    let mut known_at = vec![0usize; m.bodies.len()];
    for (s, step) in steps.iter().enumerate() {
        for &b in &step.bodies {
            known_at[b] = s;
        }
    }
    // Multiple joints whose first body is known after another of theirs: rooted at the
    // earliest known body (ties: listing order, so the first body wins a tie).
    let mut links = Vec::new();
    let mut skip = vec![false; model.pairs.len()];
    let mut p = 0;
    while p < model.pairs.len() {
        let joint = model.pairs[p].joint;
        let mut e = p;
        while e < model.pairs.len() && model.pairs[e].joint == joint {
            e += 1;
        }
        if e - p >= 2 {
            let first = model.pairs[p].a;
            let others: Vec<usize> = (p..e).map(|q| model.pairs[q].b).collect();
            let root = others
                .iter()
                .copied()
                .filter(|&b| known_at[b] < known_at[first])
                .min_by_key(|&b| known_at[b]);
            if let Some(root) = root {
                for (q, pair) in model.pairs.iter().enumerate().take(e).skip(p) {
                    let b = pair.b;
                    if b == root {
                        continue;
                    }
                    skip[q] = pair.driven == 0;
                    links.push((
                        q,
                        Link {
                            joint,
                            like: q,
                            a: root,
                            b,
                        },
                    ));
                }
            }
        }
        p = e;
    }
    let n = model.pairs.len();
    let ends = model
        .pairs
        .iter()
        .enumerate()
        .filter(|(q, _)| !skip[*q])
        .map(|(q, pair)| (q, pair.a, pair.b))
        .chain(
            links
                .iter()
                .enumerate()
                .map(|(i, (_, l))| (n + i, l.a, l.b)),
        )
        .collect::<Vec<_>>();
    for (q, a, b) in ends {
        let s = known_at[a].max(known_at[b]);
        if let Some(step) = steps.get_mut(s)
            && (step.bodies.contains(&a) || step.bodies.contains(&b))
        {
            step.pairs.push(q);
        }
    }
    for step in &mut steps {
        step.pairs.sort_unstable();
    }
    Schedule {
        steps,
        links: links.into_iter().map(|(_, l)| l).collect(),
    }
}

/// What an unreachable step means: an assembly has no input values, a solve step may.
fn unreachable_why(group: &str) -> &'static str {
    if group == "assembly" {
        "the joints cannot all close from this start"
    } else {
        "an input value out of reach or a configuration that cannot be assembled"
    }
}

/// Why a solve failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// No position model.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The work or memory budget ran out (`--max-work`, `--max-memory`, `--budget`).
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
    /// A step's equations have no solution near the start (a value out of reach, a
    /// configuration that cannot be assembled).
    #[error(
        "group {group} (bodies {bodies}) cannot be closed: residual {residual:.3e} stays on joint(s) {joints}; {}",
        unreachable_why(group)
    )]
    Unreachable {
        /// Step name.
        group: String,
        /// Body ids.
        bodies: String,
        /// Joints left open.
        joints: String,
        /// Largest residual (file units).
        residual: f64,
    },
    /// Newton ran out of iterations.
    #[error(
        "group {group} (bodies {bodies}) did not converge in {iterations} iterations: residual {residual:.3e} on joint(s) {joints}"
    )]
    NotConverged {
        /// Step name.
        group: String,
        /// Body ids.
        bodies: String,
        /// Joints left open.
        joints: String,
        /// Largest residual (file units).
        residual: f64,
        /// Iterations done.
        iterations: usize,
    },
}

/// How one step went.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepReport {
    /// Step name.
    pub name: String,
    /// Level.
    pub level: usize,
    /// Body ids.
    pub bodies: Vec<String>,
    /// Newton iterations.
    pub iterations: usize,
    /// Largest residual after the step (file units).
    pub residual: f64,
    /// Nullity of the step's Jacobian over its unknowns (relative threshold 1e-9): freedoms
    /// the step's equations leave (an isolated spin; more at a singular configuration).
    pub nullity: usize,
    /// Smallest nonzero over largest singular value of the step's Jacobian (near 0: close to
    /// a singular configuration).
    pub conditioning: f64,
}

/// A solved configuration.
#[derive(Clone, Debug)]
pub struct Solution {
    /// The poses.
    pub config: Configuration,
    /// Per step.
    pub steps: Vec<StepReport>,
    /// Largest residual over every pair (file units).
    pub max_residual: f64,
}

/// The joints of `pairs` whose residual exceeds `tol`, in pair order, each once; at most
/// [`capped`](crate::words::capped)'s count named.
pub(super) fn joints_of(
    m: &Mechanism,
    model: &PositionModel,
    pairs: &[usize],
    res: &[f64],
    tol: f64,
) -> String {
    let mut seen = std::collections::HashSet::new();
    let ids: Vec<&str> = pairs
        .iter()
        .enumerate()
        .filter(|&(i, _)| res.get(i).is_some_and(|&r| r > tol))
        .map(|(_, &p)| m.joints[model.pairs[p].joint].id.as_str())
        .filter(|id| seen.insert(*id))
        .collect();
    if ids.is_empty() {
        "(none)".into()
    } else {
        crate::words::capped(&ids)
    }
}

fn body_list(m: &Mechanism, bodies: &[usize]) -> String {
    let ids: Vec<String> = bodies.iter().map(|&b| m.body_id(b).to_string()).collect();
    format!("{{{}}}", crate::words::capped(&ids))
}

fn outcome_error(
    m: &Mechanism,
    model: &PositionModel,
    name: &str,
    sys: &System,
    out: &NewtonOutcome,
    opts: &NewtonOptions,
) -> SolveError {
    let joints = joints_of(m, model, &sys.pairs, &out.pair_residuals, opts.tolerance);
    let bodies = body_list(m, &sys.bodies);
    let residual = out.residual * model.scale;
    if out.iterations >= opts.max_iterations || out.stalled {
        SolveError::NotConverged {
            group: name.into(),
            bodies,
            joints,
            residual,
            iterations: out.iterations,
        }
    } else {
        SolveError::Unreachable {
            group: name.into(),
            bodies,
            joints,
            residual,
        }
    }
}

fn report(m: &Mechanism, model: &PositionModel, step: &Step, out: &NewtonOutcome) -> StepReport {
    StepReport {
        name: step.name.clone(),
        level: step.level,
        bodies: step
            .bodies
            .iter()
            .map(|&b| m.body_id(b).to_string())
            .collect(),
        iterations: out.iterations,
        residual: out.residual * model.scale,
        nullity: out.nullity(1e-9),
        conditioning: out.conditioning(),
    }
}

/// Largest residual of every pair at `config` (model units).
pub fn max_residual(model: &PositionModel, targets: &Targets, config: &Configuration) -> f64 {
    let all = System {
        pairs: (0..model.pairs.len()).collect(),
        bodies: Vec::new(),
    };
    let (r, _, _) = all.evaluate(model, targets, config);
    r.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// Steps with more unknown columns than this are solved by the sparse solver
/// ([`super::sparse`]); smaller ones by the dense SVD of [`System::solve_local`].
pub const SPARSE_COLUMNS: usize = 600;

/// Solve one system, dense or sparse by its size, charging `meter`.
fn solve_system(
    sys: &System,
    model: &PositionModel,
    targets: &Targets,
    config: &Configuration,
    opts: &NewtonOptions,
    meter: &mut Meter,
) -> Result<(NewtonOutcome, Vec<super::pose::Pose>), BudgetExceeded> {
    if sys.bodies.len() * model.b() > SPARSE_COLUMNS {
        let sp = super::sparse::Sparse::new(sys, model, targets, opts, meter)?;
        sp.solve(config, opts, meter)
    } else {
        sys.solve_metered(model, targets, config, opts, meter)
    }
}

/// Solve group by group from `start`. Steps of one level run in parallel. Every step charges
/// its Newton iterations (evaluations, factorizations) to one work meter of `opts.budget`
/// (a level's steps each get the allowance left when the level starts; the level's total is
/// charged after it): a huge solve stops with the budget error instead of running away.
pub fn solve_groups(
    m: &Mechanism,
    model: &PositionModel,
    sched: &Schedule,
    targets: &Targets,
    start: &Configuration,
    opts: &NewtonOptions,
) -> Result<Solution, SolveError> {
    let (model, targets) = sched.extended(model, targets);
    let (model, targets) = (model.as_ref(), targets.as_ref());
    let mut config = start.clone();
    let mut reports = Vec::new();
    let mut meter = opts.budget.meter("the group-by-group position solve");
    let mut s = 0;
    while s < sched.steps.len() {
        let level = sched.steps[s].level;
        let mut e = s;
        while e < sched.steps.len() && sched.steps[e].level == level {
            e += 1;
        }
        let left = crate::budget::Budget {
            max_work: opts.budget.max_work.saturating_sub(meter.used()),
            ..opts.budget
        };
        let run = |step: &Step| {
            let sys = System {
                pairs: step.pairs.clone(),
                bodies: step.bodies.clone(),
            };
            let mut mine = left.meter("the group-by-group position solve");
            let r = solve_system(&sys, model, targets, &config, opts, &mut mine);
            (sys, r, mine.used())
        };
        let results: Vec<_> = if e - s > 1 && model.bodies > 64 {
            sched.steps[s..e].par_iter().map(run).collect()
        } else {
            sched.steps[s..e].iter().map(run).collect()
        };
        for (step, (sys, r, used)) in sched.steps[s..e].iter().zip(results) {
            let (out, poses) = r?;
            meter.charge(used)?;
            if !out.converged {
                return Err(outcome_error(m, model, &step.name, &sys, &out, opts));
            }
            for (&b, p) in step.bodies.iter().zip(poses) {
                config.poses[b] = p;
            }
            reports.push(report(m, model, step, &out));
        }
        s = e;
    }
    finish(m, model, targets, config, reports, opts)
}

fn finish(
    m: &Mechanism,
    model: &PositionModel,
    targets: &Targets,
    config: Configuration,
    steps: Vec<StepReport>,
    opts: &NewtonOptions,
) -> Result<Solution, SolveError> {
    let all = System {
        pairs: (0..model.pairs.len()).collect(),
        bodies: Vec::new(),
    };
    let (r, _, per_pair) = all.evaluate(model, targets, &config);
    let worst = r.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if worst > 10.0 * opts.tolerance {
        return Err(SolveError::Unreachable {
            group: "(all)".into(),
            bodies: body_list(
                m,
                &(0..m.bodies.len())
                    .filter(|&b| b != m.frame)
                    .collect::<Vec<_>>(),
            ),
            joints: joints_of(m, model, &all.pairs, &per_pair, 10.0 * opts.tolerance),
            residual: worst * model.scale,
        });
    }
    Ok(Solution {
        config,
        steps,
        max_residual: worst * model.scale,
    })
}

/// Solve every equation at once (the reference): the sparse Gauss–Newton of
/// [`super::sparse`] on every body but the frame, charging a work meter of `opts.budget` and
/// checking the factor's memory against it before allocating.
pub fn solve_global(
    m: &Mechanism,
    model: &PositionModel,
    targets: &Targets,
    start: &Configuration,
    opts: &NewtonOptions,
) -> Result<Solution, SolveError> {
    let step = Step {
        name: "global".into(),
        level: 1,
        bodies: (0..m.bodies.len()).filter(|&b| b != m.frame).collect(),
        pairs: (0..model.pairs.len()).collect(),
    };
    let sys = System {
        pairs: step.pairs.clone(),
        bodies: step.bodies.clone(),
    };
    let mut meter = opts.budget.meter("the global position solve");
    let mut sp = super::sparse::Sparse::new(&sys, model, targets, opts, &mut meter)?;
    let (out, poses) = sp.solve_continued(start, opts, &mut meter)?;
    if !out.converged {
        return Err(outcome_error(m, model, "global", &sys, &out, opts));
    }
    let mut config = start.clone();
    for (&b, p) in sys.bodies.iter().zip(poses) {
        config.poses[b] = p;
    }
    let rep = report(m, model, &step, &out);
    finish(m, model, targets, config, vec![rep], opts)
}

/// The pose of every body, for reports.
pub fn pose_reports(
    m: &Mechanism,
    model: &PositionModel,
    config: &Configuration,
) -> Vec<PoseReport> {
    (0..m.bodies.len())
        .map(|b| {
            PoseReport::new(
                m.body_id(b).to_string(),
                &config.poses[b],
                m.space,
                model.scale,
            )
        })
        .collect()
}

/// The values of one joint (driven-DOF order; all pairs of a multiple joint in turn).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointValues {
    /// Joint id.
    pub joint: String,
    /// Values: degrees for angles, file lengths for slides.
    pub values: Vec<f64>,
    /// `deg` or `length` per value.
    pub units: Vec<&'static str>,
}

/// Every joint's values at `config` (measured from the file's configuration).
pub fn joint_values(
    m: &Mechanism,
    model: &PositionModel,
    config: &Configuration,
) -> Vec<JointValues> {
    let mut out: Vec<JointValues> = m
        .joints
        .iter()
        .map(|j| JointValues {
            joint: j.id.clone(),
            values: Vec::new(),
            units: Vec::new(),
        })
        .collect();
    for (p, pair) in model.pairs.iter().enumerate() {
        let vals = model.pair_values(p, &config.poses[pair.a], &config.poses[pair.b]);
        let o = &mut out[pair.joint];
        for (v, angle) in vals {
            let x = if angle {
                // (−180, 180]: a half turn reads 180 whatever the rounding.
                let d = v.to_degrees();
                if d <= -180.0 + 1e-9 { d + 360.0 } else { d }
            } else {
                v * model.scale
            };
            o.values.push(super::pose::tidy(x));
            o.units.push(if angle { "deg" } else { "length" });
        }
    }
    out
}

/// A solve as reported (`mbsa solve --format json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SolveReport {
    /// Mechanism name.
    pub name: String,
    /// How it was solved: `groups` or `global`.
    pub method: &'static str,
    /// The steps in solve order.
    pub steps: Vec<StepReport>,
    /// Largest residual over every joint (file units).
    pub max_residual: f64,
    /// Body poses.
    pub poses: Vec<PoseReport>,
    /// Joint values.
    pub joint_values: Vec<JointValues>,
    /// Finite against first-order mobility at the solved configuration, when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finite: Option<super::finite::FiniteMobility>,
    /// The isolated freedoms the structural analysis found (body, dimension), for the words
    /// on the freedoms a step leaves (not in the JSON: `analyze` lists them).
    #[serde(skip)]
    pub isolated: Vec<(String, u32)>,
}

impl SolveReport {
    /// The report of `sol`.
    pub fn new(
        m: &Mechanism,
        model: &PositionModel,
        sol: &Solution,
        method: &'static str,
    ) -> SolveReport {
        SolveReport {
            name: m.name.clone(),
            method,
            steps: sol.steps.clone(),
            max_residual: super::pose::tidy(sol.max_residual),
            poses: pose_reports(m, model, &sol.config),
            joint_values: joint_values(m, model, &sol.config),
            finite: None,
            isolated: Vec::new(),
        }
    }
}
