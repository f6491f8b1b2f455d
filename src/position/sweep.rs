//! Sweeps: one driven joint stepped through a range, each step solved from the previous one,
//! stopped at a dead point (a group's equations turn singular) or a branch change (a jump far
//! larger than the previous step's).

use super::inputs::{self, InputError, Sweep, Value};
use super::{
    Configuration, NewtonOptions, PoseReport, PositionModel, Schedule, Solution, SolveError,
};
use super::{joint_values, solve::pose_reports, solve_global, solve_groups};
use crate::Mechanism;
use serde::Serialize;
use std::collections::HashMap;

/// One solved step of a sweep.
#[derive(Clone, Debug, Serialize)]
pub struct SweepStep {
    /// The swept joint's value, as written (degrees or file lengths).
    pub value: f64,
    /// Every body's pose.
    pub poses: Vec<PoseReport>,
    /// Every joint's values.
    pub joint_values: Vec<super::JointValues>,
}

/// The steps of a sweep and, when it ended early, why.
#[derive(Clone, Debug, Serialize)]
pub struct SweepReport {
    /// The mechanism's name.
    pub name: String,
    /// The swept joint's id.
    pub joint: String,
    /// The solved steps, in order.
    pub steps: Vec<SweepStep>,
    /// Why the sweep ended before its last value (a dead point, a branch change, a failed
    /// solve), or `None` when it reached it.
    pub stopped: Option<String>,
}

/// How each step is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Group by group, in the schedule's order.
    Groups,
    /// All unknowns at once (the reference).
    Global,
}

/// Steps `sw` through its values with the other inputs held at `sets`, from `start`.
/// An input value out of range is an error; a step that fails to solve ends the sweep with
/// `stopped` set.
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    m: &Mechanism,
    model: &PositionModel,
    sched: &Schedule,
    sets: &[(usize, Vec<Value>)],
    sw: &Sweep,
    start: Configuration,
    method: Method,
    opts: &NewtonOptions,
) -> Result<SweepReport, InputError> {
    let solve = |s: &[(usize, Vec<Value>)], from: &Configuration| {
        let tg = inputs::targets(m, model, s)?;
        Ok::<_, InputError>(match method {
            Method::Global => solve_global(m, model, &tg, from, opts),
            Method::Groups => solve_groups(m, model, sched, &tg, from, opts),
        })
    };
    let joint = m.joints[sw.joint].id.clone();
    let mut tracker = Tracker::default();
    let mut steps: Vec<SweepStep> = Vec::new();
    let mut stopped = None;
    let mut config = start;
    let mut prev_value: Option<f64> = None;
    let at = |x: f64| format!("{joint}={x}");
    for v in sw.values() {
        let mut s: Vec<(usize, Vec<Value>)> = sets.to_vec();
        match s.iter_mut().find(|(j, _)| *j == sw.joint) {
            Some((_, vals)) => vals[0] = v,
            None => s.push((sw.joint, vec![v])),
        }
        let sol = match solve(&s, &config)? {
            Ok(sol) => sol,
            Err(e) => {
                stopped = Some(failed_step(&e, prev_value.map(at), &at(v.number)));
                break;
            }
        };
        stopped = tracker.singular(&sol, &at(v.number));
        if stopped.is_none()
            && let Some(msg) = tracker.branch_change(m, sched, &config, &sol, prev_value.is_some())
        {
            let from = at(prev_value.unwrap_or(v.number));
            stopped = Some(format!(
                "branch change between {from} and {}: {msg}",
                at(v.number)
            ));
            break;
        }
        steps.push(SweepStep {
            value: v.number,
            poses: pose_reports(m, model, &sol.config),
            joint_values: joint_values(m, model, &sol.config),
        });
        config = sol.config;
        prev_value = Some(v.number);
        if stopped.is_some() {
            break;
        }
    }
    Ok(SweepReport {
        name: m.name.clone(),
        joint,
        steps,
        stopped,
    })
}

fn failed_step(e: &SolveError, prev: Option<String>, here: &str) -> String {
    match prev {
        Some(p) => format!(
            "stopped between {p} and {here}: a dead point or the end of the reachable range: {e}"
        ),
        None => format!("stopped at {here}: {e}"),
    }
}

/// What the sweep remembers between steps to see a dead point or a branch change.
#[derive(Default)]
struct Tracker {
    /// Each group's nullity at its first step.
    baseline: HashMap<String, usize>,
    /// The previous step's largest body move.
    last_jump: f64,
}

impl Tracker {
    /// A group whose equations became singular: more nullity than at the sweep's start, or
    /// nearly so.
    fn singular(&mut self, sol: &Solution, at: &str) -> Option<String> {
        for st in &sol.steps {
            self.baseline.entry(st.name.clone()).or_insert(st.nullity);
        }
        let st = sol
            .steps
            .iter()
            .filter(|st| st.conditioning < 1e-6 || st.nullity > self.baseline[&st.name])
            .min_by(|a, b| a.conditioning.total_cmp(&b.conditioning))?;
        Some(format!(
            "dead point at {at}: the equations of group {} (bodies {}) became singular (conditioning {:.1e})",
            st.name,
            crate::words::capped(&st.bodies),
            st.conditioning
        ))
    }

    /// A jump far larger than the previous step's: the group of the body that moved most.
    fn branch_change(
        &mut self,
        m: &Mechanism,
        sched: &Schedule,
        last: &Configuration,
        sol: &Solution,
        has_prev: bool,
    ) -> Option<String> {
        let mut jump = 0.0f64;
        let mut worst_body = m.frame;
        for b in 0..m.bodies.len() {
            let (p, q) = (&last.poses[b], &sol.config.poses[b]);
            let d = (p.rotation - q.rotation).norm() + (p.translation - q.translation).norm();
            if d > jump {
                jump = d;
                worst_body = b;
            }
        }
        if self.last_jump > 1e-9 && jump > 5.0 * self.last_jump + 1e-6 {
            let group = sched
                .steps
                .iter()
                .find(|st| st.bodies.contains(&worst_body))
                .map(|st| st.name.clone())
                .unwrap_or_else(|| "?".into());
            return Some(format!(
                "group {group} (body {}) jumped; the sweep passed a dead point",
                m.body_id(worst_body)
            ));
        }
        if has_prev {
            self.last_jump = jump;
        }
        None
    }
}
