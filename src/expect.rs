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
}

fn outcome<T: PartialEq + ToString>(key: &'static str, expected: T, actual: T) -> Outcome {
    Outcome {
        key,
        ok: expected == actual,
        expected: expected.to_string(),
        actual: actual.to_string(),
    }
}

/// Compare every expectation present in `m.expect` with the analyses. Analyses whose keys are
/// absent are not run.
pub fn evaluate(m: &Mechanism) -> Vec<Outcome> {
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
    out
}
