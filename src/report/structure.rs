//! The structural analysis as tables for people, in the layout of the paper's Table 8 (groups)
//! and Table 9 (types against the library), followed by the findings.

use crate::structure::{Analysis, Status};
use std::fmt::Write;

fn dash(s: &str) -> String {
    if s.is_empty() {
        "-".into()
    } else {
        s.to_string()
    }
}

/// Render the analysis.
pub fn table(a: &Analysis) -> String {
    let mut out = String::new();
    let status = match a.status {
        Status::Determined => "determined",
        Status::Overdetermined => "over-determined",
        Status::Underdetermined => "under-determined",
        Status::Mixed => "not determined (over- and under-determined parts)",
    };
    let _ = writeln!(
        out,
        "{}: {} structural group(s) on {} level(s); mobility {}, inputs {}; {}{}",
        a.name,
        a.groups.len(),
        a.levels,
        a.mobility.count,
        a.mobility.inputs,
        status,
        if a.count_only { " (count only)" } else { "" }
    );
    if let Some(g) = &a.geometry {
        let _ = writeln!(out, "{}", g.line());
    }
    if !a.groups.is_empty() {
        let mut t = super::new_table();
        t.set_header(vec![
            "SG", "bodies", "Nm", "inputs", "level", "type", "from", "internal", "to",
        ]);
        for g in &a.groups {
            t.add_row(vec![
                g.name.clone(),
                wrap(&g.bodies.join(","), ','),
                g.nm.to_string(),
                g.inputs.to_string(),
                g.level.to_string(),
                g.kind.clone(),
                wrap(&dash(&g.from), '.'),
                wrap(&dash(&g.internal), '.'),
                wrap(&dash(&g.to), '.'),
            ]);
        }
        let _ = writeln!(out, "{t}");
        let mut t = super::new_table();
        t.set_header(vec![
            "SG type".to_string(),
            "SGs".to_string(),
            format!("in library ({})", a.library),
        ]);
        for ty in &a.types {
            t.add_row(vec![
                ty.kind.clone(),
                ty.count.to_string(),
                if ty.in_library { "yes" } else { "no" }.to_string(),
            ]);
        }
        let _ = writeln!(out, "{t}");
    }
    if !a.unchecked.is_empty() {
        let sizes: Vec<String> = a
            .unchecked
            .iter()
            .map(|u| format!("{} bodies ({} unknowns)", u.bodies, u.unknowns))
            .collect();
        let _ = writeln!(
            out,
            "note: the rank check left {} block(s) to the count, too large to factorize densely: {}",
            a.unchecked.len(),
            sizes.join(", ")
        );
    }
    if !a.isolated.is_empty() {
        let list: Vec<String> = a
            .isolated
            .iter()
            .map(|i| format!("{} ({})", i.body, i.dimension))
            .collect();
        let _ = writeln!(
            out,
            "isolated freedoms (no input can drive them, left out): {}",
            list.join(", ")
        );
    }
    if let Some(d) = &a.diagnosis {
        if !d.unsolved.is_empty() {
            let _ = writeln!(out, "bodies left unsolved: {}", d.unsolved.join(", "));
        }
        for n in &d.notes {
            let _ = writeln!(out, "- {n}");
        }
    } else {
        for n in &a.notes {
            let _ = writeln!(out, "- {n}");
        }
    }
    out
}

/// Widest line of a list cell. Tables pad every row to the widest cell, so one giant group
/// (thousands of pairs) would otherwise make every row of the table as wide as its list.
const CELL_WIDTH: usize = 48;

/// Break a list (`9&10S.9&13R.` or `3,5,7`) into lines of at most [`CELL_WIDTH`] characters,
/// after a separator, so that no entry is split.
fn wrap(text: &str, sep: char) -> String {
    let mut out = String::with_capacity(text.len() + text.len() / CELL_WIDTH + 1);
    let mut line = 0;
    for entry in text.split_inclusive(sep) {
        let n = entry.chars().count();
        if line > 0 && line + n > CELL_WIDTH {
            out.push('\n');
            line = 0;
        }
        out.push_str(entry);
        line += n;
    }
    out
}
