//! The generic rigidity (pebble game) report as plain text for people.

use crate::rigidity::pebble::PebbleReport;
use std::fmt::Write;

/// Render the pebble-game report: the counts, the rigid components, the overconstrained
/// regions and the limits of counting. No colour; the same report gives the same bytes.
pub fn table(r: &PebbleReport) -> String {
    let mut t = super::new_table();
    t.set_header(vec!["quantity", "value", "meaning"]);
    let inputs = if r.with_inputs {
        "B - k per pair (n·(B - k) to a shared node for n ≥ 3 bodies), one per driven DOF"
    } else {
        "B - k per pair (n·(B - k) to a shared node for n ≥ 3 bodies); inputs not counted"
    };
    let rows: Vec<[String; 3]> = vec![
        [
            "space".into(),
            format!("{} (B = {})", r.space, r.b),
            "DOF of a free body".into(),
        ],
        [
            "bodies".into(),
            r.bodies.to_string(),
            "the frame included".into(),
        ],
        ["bars".into(), r.bars.to_string(), inputs.into()],
        [
            "count".into(),
            r.count.to_string(),
            "B·Nm - Σ pairs·(B - k)".into(),
        ],
        [
            "redundant".into(),
            r.redundant.to_string(),
            "bars implied by the others (generic)".into(),
        ],
        [
            "dof".into(),
            r.dof.to_string(),
            "generic DOF, frame fixed".into(),
        ],
        [
            "dof free".into(),
            r.dof_free.to_string(),
            format!("free chain, its {} rigid motions included", r.b),
        ],
        [
            "degenerate".into(),
            if r.degenerate { "yes" } else { "no" }.into(),
            "a proper sub-chain of ≥ 2 bodies is rigid on its own".into(),
        ],
    ];
    for row in rows {
        t.add_row(row.to_vec());
    }
    let mut out = String::new();
    let _ = writeln!(out, "{}: generic DOF {} (pebble game)", r.name, r.dof);
    let _ = writeln!(out, "{t}");
    let _ = writeln!(
        out,
        "rigid components (singletons other than the frame's not listed):"
    );
    for c in &r.rigid {
        let _ = writeln!(out, "  {{{}}}", c.join(", "));
    }
    if !r.immobile.is_empty() {
        let _ = writeln!(
            out,
            "immobile (rigid with the frame): {}",
            r.immobile.join(", ")
        );
    }
    if r.overconstrained.is_empty() {
        let _ = writeln!(out, "overconstrained regions: none");
    } else {
        let _ = writeln!(out, "overconstrained regions:");
        for (i, g) in r.overconstrained.iter().enumerate() {
            let _ = writeln!(
                out,
                "  {}. {} redundant; bodies {{{}}}; joints {}",
                i + 1,
                g.redundant,
                g.bodies.join(", "),
                g.joints.join(", ")
            );
        }
    }
    let _ = writeln!(out, "limits: {}", r.limits);
    out
}
