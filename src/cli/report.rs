//! `mbsa report`: gathers the analyses of one FILE (structure, geometric rigidity, a sweep of
//! its first driven input) and hands them to the HTML page writer
//! ([`mbsa::report::html::page`]).

use super::analysis::StructureArgs;
use super::{Failure, FileArg, emit, load_with_inputs};
use mbsa::Mechanism;
use mbsa::position::inputs::{Sweep, Value};
use mbsa::position::sweep::{self, Method, SweepReport};
use mbsa::position::{Configuration, NewtonOptions, PositionModel};
use mbsa::report::html::{Animation, Inputs};
use mbsa::rigidity::geometric;
use mbsa::structure::{self, Library};

/// Angle sweeps: from the file's configuration by 5° up to a full turn each way.
const ANGLE_STEP: f64 = 5.0;
/// Slide sweeps: a quarter of the model size each way, in 40 steps.
const SLIDE_SPAN: f64 = 0.25;
const SLIDE_STEPS: f64 = 40.0;

/// `mbsa report`.
pub fn run(
    file: &FileArg,
    args: &StructureArgs,
    output: Option<&std::path::Path>,
) -> Result<(), Failure> {
    let m = load_with_inputs(file, args.inputs.as_deref())?;
    let lib = args.library()?;
    args.geometry.closure_check(&file.file, &m)?;
    let mut a = structure::analyze_within(&m, &args.options()?, &lib, &super::budget()).map_err(
        |e| match e {
            structure::AnalyzeError::Motion(e) => super::analysis::input_error(file, e),
            structure::AnalyzeError::Budget(e) => super::budget_failure(&e),
        },
    )?;
    structure::check_finite(
        &m,
        &mut a,
        args.geometry.precision()?,
        super::budget().max_work,
    );
    let mut chain = m.clone();
    for j in &mut chain.joints {
        j.driven = 0;
    }
    let opts = geometric::GeometricOptions {
        geometry: args.geometry.source(),
        precision: args.geometry.precision()?,
        check_finite: false,
    };
    let rigid =
        geometric::analyze_within(&chain, &opts, &super::budget()).map_err(|e| e.to_string());
    let animation = animation(&m, &a);
    let html = mbsa::report::html::page(&Inputs {
        mechanism: &m,
        analysis: &a,
        rigid: rigid.as_ref().map_err(Clone::clone),
        animation,
    });
    match output {
        Some(path) => std::fs::write(path, html)
            .map_err(|e| Failure::Input(format!("error: cannot write `{}`: {e}", path.display()))),
        None => emit(&html),
    }
}

/// The joint to sweep: the first driven one, else the first the diagnosis offers for an input,
/// one of a single DOF first (a floating base's free joint is offered too, but sweeping one of
/// its six coordinates moves the whole model rather than the mechanism).
fn swept_joint(m: &Mechanism, a: &structure::Analysis) -> Option<(usize, &'static str)> {
    if let Some(j) = m.joints.iter().position(|j| j.driven > 0) {
        return Some((j, "the first driven input"));
    }
    let candidates = a.diagnosis.as_ref()?.underdetermined.as_ref()?;
    let offered: Vec<usize> = candidates
        .input_candidates
        .iter()
        .filter_map(|id| m.joints.iter().position(|j| &j.id == id))
        .collect();
    offered
        .iter()
        .copied()
        .find(|&j| m.joints[j].kind.grade() == 1)
        .or_else(|| offered.first().copied())
        .map(|j| {
            (
                j,
                "no driven input: the first joint the diagnosis offers for one",
            )
        })
}

/// The sweep of [`swept_joint`] from the file's configuration, both ways when the first
/// stops early, as one sequence of steps.
fn animation(m: &Mechanism, a: &structure::Analysis) -> Animation {
    if !mbsa::motion::has_geometry(m) {
        return Animation::NoGeometry;
    }
    let Some((j, why)) = swept_joint(m, a) else {
        return Animation::NoInput;
    };
    let joint = m.joints[j].id.clone();
    let failed = |reason: String| Animation::Failed {
        joint: joint.clone(),
        reason,
    };
    let mut m = m.clone();
    m.joints[j].driven = m.joints[j].driven.max(1);
    let model = match PositionModel::new(&m) {
        Ok(x) => x,
        Err(e) => return failed(e.to_string()),
    };
    let mut first = m.clone();
    for jt in &mut first.joints {
        jt.geometry.second = None;
    }
    let an = match structure::analyze(&first, &structure::Options::default(), &Library::builtin()) {
        Ok(x) => x,
        Err(e) => return failed(e.to_string()),
    };
    let sched = mbsa::position::schedule(&m, &an, &model);
    let angle = mbsa::position::inputs::angle_flags(&model, j)
        .first()
        .copied()
        .unwrap_or(true);
    let (span, step) = if angle {
        (360.0, ANGLE_STEP)
    } else {
        let s = SLIDE_SPAN * mbsa::position::residual::model_size(&m);
        (s, s / SLIDE_STEPS)
    };
    let opts = NewtonOptions {
        budget: super::budget(),
        ..NewtonOptions::default()
    };
    let run = |to: f64| {
        let v = |x: f64| Value {
            number: x,
            radians: None,
        };
        let sw = Sweep {
            joint: j,
            from: v(0.0),
            to: v(to),
            step: v(step),
        };
        let start = Configuration::reference(m.bodies.len());
        sweep::sweep(&m, &model, &sched, &[], &sw, start, Method::Groups, &opts)
    };
    let fwd = match run(span) {
        Ok(r) => r,
        Err(e) => return failed(e.to_string()),
    };
    let unit = if angle { "°" } else { "" };
    if fwd.stopped.is_none() && angle {
        let note = format!("Swept {why}, 0..{span}{unit} by {step}{unit}");
        return Animation::Swept { sweep: fwd, note };
    }
    let back = match run(-span) {
        Ok(r) => r,
        Err(e) => return failed(e.to_string()),
    };
    let note = format!(
        "Swept {why}, from 0 to {}{unit} and to -{}{unit} by {}{unit}",
        num(span),
        num(span),
        num(step)
    );
    Animation::Swept {
        sweep: joined(back, fwd),
        note,
    }
}

fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The backward sweep reversed (its first step, the file's configuration, once) then the
/// forward one; the reasons either stopped, joined.
fn joined(back: SweepReport, fwd: SweepReport) -> SweepReport {
    let mut steps: Vec<_> = back.steps.into_iter().skip(1).rev().collect();
    steps.extend(fwd.steps);
    let stopped = match (back.stopped, fwd.stopped) {
        (None, None) => None,
        (Some(b), None) => Some(b),
        (None, Some(f)) => Some(f),
        (Some(b), Some(f)) => Some(format!("{f}; backward: {b}")),
    };
    SweepReport {
        name: fwd.name,
        joint: fwd.joint,
        steps,
        stopped,
    }
}
