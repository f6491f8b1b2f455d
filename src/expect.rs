//! Evaluate a mechanism's `[expect]` table: run the analyses it names and compare.

use crate::mechanism::Mechanism;
use serde::Serialize;

/// One expectation compared with the analysis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Outcome {
    /// The `[expect]` key.
    pub key: &'static str,
    /// The value written in the file.
    pub expected: String,
    /// The value the analysis gives.
    pub actual: String,
    /// Whether they agree.
    pub ok: bool,
    /// What the value does not say (the `determined` verdict at a singular configuration:
    /// [`crate::structure::check_finite`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

fn outcome<T: PartialEq + ToString>(key: &'static str, expected: T, actual: T) -> Outcome {
    Outcome {
        key,
        ok: expected == actual,
        expected: expected.to_string(),
        actual: actual.to_string(),
        note: None,
    }
}

/// Compare every expectation present in `m.expect` with the analyses, at the geometry
/// `geometry` asks for. Analyses whose keys are absent are not run. Every key means what the
/// command that prints it means (`true_mobility`: `mbsa rigid`, inputs not counted;
/// `uncontrolled`: `mbsa analyze`, the DOF the inputs leave free).
pub fn evaluate(
    m: &Mechanism,
    geometry: &crate::rigidity::geometric::GeometricOptions,
) -> Vec<Outcome> {
    let e = &m.expect;
    let mut out = Vec::new();
    if e.mobility.is_some() || e.inputs.is_some() {
        let r = crate::mobility::mobility(m);
        if let Some(x) = e.mobility {
            out.push(outcome("mobility", x, r.mobility.count));
        }
        if let Some(x) = e.inputs {
            out.push(outcome("inputs", x, r.mobility.inputs));
        }
    }
    if e.groups.is_some()
        || e.levels.is_some()
        || e.determined.is_some()
        || e.uncontrolled.is_some()
    {
        let opts = crate::structure::Options {
            geometry: geometry.geometry,
            precision: geometry.precision,
            ..Default::default()
        };
        match crate::structure::analyze(m, &opts, &crate::structure::Library::builtin()) {
            Ok(mut a) => {
                if e.determined.is_some() {
                    crate::structure::check_finite(
                        m,
                        &mut a,
                        geometry.precision,
                        crate::budget::Budget::DEFAULT.max_work,
                    );
                }
                if let Some(x) = e.groups {
                    out.push(outcome("groups", x, a.groups.len() as u64));
                }
                if let Some(x) = e.levels {
                    out.push(outcome("levels", x, a.levels as u64));
                }
                if let Some(x) = e.determined {
                    let determined = a.status == crate::structure::Status::Determined;
                    let mut o = outcome("determined", x, determined);
                    o.note = a.finite.map(|f| f.note);
                    out.push(o);
                }
                if let Some(x) = e.uncontrolled {
                    out.push(outcome("uncontrolled", x, a.uncontrolled));
                }
            }
            Err(err) => out.push(geometry_failed(err)),
        }
    }
    if let Some(x) = e.generic_dof {
        let r = crate::rigidity::pebble::analyze(m, &Default::default());
        out.push(outcome("generic_dof", x, r.dof));
    }
    if e.true_mobility.is_some()
        || e.isolated.is_some()
        || e.redundant.is_some()
        || e.rigid_parts.is_some()
    {
        // As `mbsa rigid` prints them: the chain alone, inputs not counted.
        let mut chain = m.clone();
        for j in &mut chain.joints {
            j.driven = 0;
        }
        match crate::rigidity::geometric::analyze(&chain, geometry) {
            Ok(r) => {
                if let Some(x) = e.true_mobility {
                    out.push(outcome("true_mobility", x, r.mobility as i64));
                }
                if let Some(x) = e.isolated {
                    out.push(outcome("isolated", x, r.isolated as u64));
                }
                if let Some(x) = e.redundant {
                    out.push(outcome("redundant", x, r.redundant as u64));
                }
                if let Some(x) = e.rigid_parts {
                    out.push(outcome("rigid_parts", x, r.rigid.len() as u64));
                }
            }
            Err(err) => out.push(geometry_failed(err)),
        }
    }
    out
}

fn geometry_failed(err: crate::motion::MotionError) -> Outcome {
    Outcome {
        key: "geometry",
        expected: "a geometric analysis".into(),
        actual: err.to_string(),
        ok: false,
        note: None,
    }
}
