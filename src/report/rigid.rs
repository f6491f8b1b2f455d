//! `mbsa rigid`'s output: the reports [`crate::rigidity::both::analyze`] made, as a table or
//! JSON (one report alone, or several under `counting`, `geometric`, `finite`).

use crate::position::FiniteMobility;
use crate::rigidity::both::RigidReports;
use crate::rigidity::{geometric, pebble};
use serde::Serialize;

/// Several rigidity reports in one JSON object.
#[derive(Serialize)]
struct Both<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    counting: Option<&'a pebble::PebbleReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    geometric: Option<&'a geometric::GeometricReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    finite: Option<&'a FiniteMobility>,
}

/// The JSON of `mbsa rigid --format json`: the counting or the geometric report alone when
/// only one was made, else all under their names (docs/json.md).
pub fn json(r: &RigidReports) -> String {
    match (&r.counting, &r.geometric, &r.finite) {
        (Some(c), None, None) => super::json(c),
        (None, Some(g), None) => super::json(g),
        (None, None, None) => String::new(),
        (c, g, f) => super::json(&Both {
            counting: c.as_ref(),
            geometric: g.as_ref(),
            finite: f.as_ref(),
        }),
    }
}

/// The tables of `mbsa rigid`: one section per report made.
pub fn table(r: &RigidReports) -> String {
    let mut parts = Vec::new();
    if let Some(c) = &r.counting {
        parts.push(format!(
            "Counting (pebble game, topology only)\n\n{}",
            super::rigid_pebble::table(c)
        ));
    }
    if let Some(g) = &r.geometric {
        parts.push(format!(
            "Geometry (constraint Jacobian)\n\n{}",
            super::rigid_geometric::table(g)
        ));
    }
    if let Some(f) = &r.finite {
        parts.push(format!(
            "Finite mobility (position level)\n\n{}",
            super::position::finite_section(f)
        ));
    }
    parts.join("\n")
}
