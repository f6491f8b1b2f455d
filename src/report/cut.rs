//! `mbsa cut`'s table: the tree, the cut joints and their closures.

use crate::cut::CutReport;
use std::fmt::Write;

/// Loop joints shown in the table before the rest is counted.
const SHOWN: usize = 12;

/// The table of `mbsa cut`.
pub fn table(r: &CutReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: {} loop(s), {} cut joint(s); closures {} rows, rank {}, {} redundant",
        r.name,
        r.loops,
        r.cuts.len(),
        r.rows,
        r.rank,
        r.redundant
    );
    let _ = writeln!(out, "{}", super::geometry_line(&r.geometry_used));
    let _ = writeln!(
        out,
        "\ntree from the frame {} ({} coordinates):",
        r.frame, r.coordinates
    );
    let mut t = super::new_table();
    t.set_header(vec!["joint", "kind", "parent", "child", "dof"]);
    for j in &r.tree {
        t.add_row(vec![
            j.joint.clone(),
            j.kind.to_string(),
            j.parent.clone(),
            j.child.clone(),
            j.dof.to_string(),
        ]);
    }
    let _ = writeln!(out, "{t}");
    if !r.floating.is_empty() {
        let _ = writeln!(
            out,
            "not joined to the frame (free in a simulator), parts rooted at: {}",
            r.floating.join(", ")
        );
    }
    if r.cuts.is_empty() {
        let _ = writeln!(out, "\nno loop: nothing to cut");
    } else {
        let _ = writeln!(out, "\ncuts:");
        let _ = writeln!(out, "{}", cuts_table(r));
    }
    let _ = writeln!(
        out,
        "true mobility: {} coordinates - rank {} = {}",
        r.coordinates, r.rank, r.mobility
    );
    out.push_str(&footer(r));
    out
}

fn cuts_table(r: &CutReport) -> comfy_table::Table {
    let mut t = super::new_table();
    t.set_header(vec![
        "joint",
        "kind",
        "bodies",
        "why",
        "rows",
        "rank",
        "redundant",
        "loop (joints)",
    ]);
    for c in &r.cuts {
        let mut shown: Vec<&str> = c
            .loop_joints
            .iter()
            .take(SHOWN)
            .map(String::as_str)
            .collect();
        let more;
        if c.loop_joints.len() > SHOWN {
            more = format!("... ({} joints)", c.loop_joints.len());
            shown.push(&more);
        }
        t.add_row(vec![
            c.joint.clone(),
            c.kind.to_string(),
            c.bodies.join("-"),
            c.why.to_string(),
            c.rows.to_string(),
            c.rank.to_string(),
            c.redundant.to_string(),
            shown.join(" "),
        ]);
    }
    t
}

/// The words under the tables: the rule's reasons and what redundant rows mean.
fn footer(r: &CutReport) -> String {
    let mut out = String::new();
    let reasons: Vec<String> = [
        ("spherical", "a ball joint of the loop, cut first"),
        (
            "independent",
            "exchanged so that its closure is independent",
        ),
        ("order", "the loop's last joint in the rule's order"),
    ]
    .into_iter()
    .filter(|(why, _)| r.cuts.iter().any(|c| c.why == *why))
    .map(|(why, text)| format!("{why} = {text}"))
    .collect();
    if !reasons.is_empty() {
        let _ = writeln!(out, "why: {} (docs/cut.md)", reasons.join("; "));
    }
    if r.redundant > 0 {
        let _ = writeln!(
            out,
            "{} redundant closure row(s): the mechanism's redundant constraints at this \
             geometry (as `mbsa rigid` counts them); no choice of cuts removes them",
            r.redundant
        );
    }
    if let Some(n) = &r.note {
        let _ = writeln!(out, "note: {n}");
    }
    out
}
