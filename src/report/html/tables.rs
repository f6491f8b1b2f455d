//! The summary and the group table.

use super::{Inputs, esc};
use crate::structure::{Analysis, Status};
use std::fmt::Write;

/// The status in the words `mbsa analyze` uses.
pub(super) fn status_words(s: Status) -> &'static str {
    match s {
        Status::Determined => "determined",
        Status::Overdetermined => "over-determined",
        Status::Underdetermined => "under-determined",
        Status::Mixed => "not determined (over- and under-determined parts)",
    }
}

/// The summary: counts, status and the diagnosis's words.
pub(super) fn summary(out: &mut String, r: &Inputs) {
    let a = r.analysis;
    let class = match a.status {
        Status::Determined => "ok",
        Status::Overdetermined => "over",
        Status::Underdetermined => "under",
        Status::Mixed => "mixed",
    };
    out.push_str("<h2>Summary</h2>\n<table class=\"summary\">\n");
    let mut row = |k: &str, v: String| {
        let _ = writeln!(out, "<tr><th>{}</th><td>{}</td></tr>", esc(k), v);
    };
    row("space", esc(a.space));
    row(
        "bodies, joints",
        format!("{}, {}", r.mechanism.bodies.len(), r.mechanism.joints.len()),
    );
    row("mobility (count)", a.mobility.count.to_string());
    row("driven inputs", a.mobility.inputs.to_string());
    row(
        "true mobility",
        match &r.rigid {
            Ok(g) => format!(
                "{} (rank of the constraint Jacobian, inputs not counted)",
                g.mobility
            ),
            Err(_) => "not computed".into(),
        },
    );
    row(
        "status",
        format!(
            "<span id=\"status\" class=\"{class}\">{}</span>{}",
            status_words(a.status),
            if a.count_only { " (count only)" } else { "" }
        ),
    );
    row(
        "groups, levels",
        format!("{}, {}", a.groups.len(), a.levels),
    );
    if let Some(g) = &a.geometry {
        row("geometry", esc(&super::super::geometry_line(g)));
    }
    out.push_str("</table>\n");
    let notes: &[String] = match &a.diagnosis {
        Some(d) => &d.notes,
        None => &a.notes,
    };
    let mut items: Vec<String> = Vec::new();
    if let Some(d) = &a.diagnosis
        && !d.unsolved.is_empty()
    {
        items.push(format!(
            "bodies left unsolved: {}",
            crate::structure::capped(&d.unsolved)
        ));
    }
    if !a.isolated.is_empty() {
        let list: Vec<String> = a
            .isolated
            .iter()
            .map(|i| format!("{} ({})", i.body, i.dimension))
            .collect();
        items.push(format!(
            "isolated freedoms (each turns one body alone, moving no other; left out): {}",
            crate::structure::capped(&list)
        ));
    }
    items.extend(notes.iter().cloned());
    if !items.is_empty() {
        out.push_str("<ul class=\"diagnosis\">\n");
        for n in items {
            let _ = writeln!(out, "<li>{}</li>", esc(&n));
        }
        out.push_str("</ul>\n");
    }
}

/// The group table (the columns of `mbsa analyze`) and the type table.
pub(super) fn groups(out: &mut String, a: &Analysis) {
    if a.groups.is_empty() {
        out.push_str("<p class=\"none\">No structural group: no part of the mechanism is determined by its inputs.</p>\n");
        return;
    }
    out.push_str("<table class=\"groups\">\n<tr><th>SG</th><th>bodies</th><th>Nm</th><th>inputs</th><th>level</th><th>type</th><th>from</th><th>internal</th><th>to</th></tr>\n");
    let dash = |s: &str| {
        if s.is_empty() {
            "-".to_string()
        } else {
            esc(s)
        }
    };
    for (i, g) in a.groups.iter().enumerate() {
        let _ = writeln!(
            out,
            "<tr id=\"row-g{i}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&g.name),
            esc(&g.bodies.join(", ")),
            g.nm,
            g.inputs,
            g.level,
            esc(&g.kind),
            dash(&g.from),
            dash(&g.internal),
            dash(&g.to)
        );
    }
    out.push_str("</table>\n");
    let _ = writeln!(
        out,
        "<table class=\"types\">\n<tr><th>SG type</th><th>SGs</th><th>in library ({})</th></tr>",
        esc(&a.library)
    );
    for t in &a.types {
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&t.kind),
            t.count,
            if t.in_library { "yes" } else { "no" }
        );
    }
    out.push_str("</table>\n");
}
