//! The repair report (`mbsa repair`) as a table for people and as JSON; the comments the
//! repaired file carries on each changed joint.

use crate::repair::{Candidate, Change, RepairReport, State};
use std::fmt::Write;

/// The report as JSON (`format_version` first).
pub fn json(r: &RepairReport) -> String {
    super::json(r)
}

/// One line on the analyses of a model.
fn state_line(s: &State) -> String {
    let finite = s.finite.map_or("finite mobility unknown".into(), |f| {
        format!("finite mobility {f}")
    });
    format!(
        "{} redundant constraint{}, true mobility {}, {} isolated freedom{}, {finite}",
        s.redundant,
        if s.redundant == 1 { "" } else { "s" },
        s.mobility,
        s.isolated,
        if s.isolated == 1 { "" } else { "s" }
    )
}

/// A change's new kind with the geometry it adds, e.g. `SC axis [0, 0, 1]`.
pub fn after_text(c: &Change) -> String {
    let mut s = c.to.clone();
    let g = &c.geometry;
    for (key, v) in [("axis", g.axis), ("axis2", g.axis2), ("normal", g.normal)] {
        if let Some(v) = v {
            let _ = write!(s, " {key} [{}]", numbers(&v));
        }
    }
    s
}

fn numbers(v: &[f64; 3]) -> String {
    v.iter()
        .map(|x| format!("{x}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The comment written above a changed joint in the repaired file.
pub fn comment(c: &Change) -> String {
    format!("mbsa repair: {} -> {}: {}", c.from, after_text(c), c.why)
}

/// The report as a table: the analyses before, then each candidate's changes and analyses.
pub fn table(r: &RepairReport, file: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{}: repair at the file's configuration", r.name);
    let _ = writeln!(out, "before: {}", state_line(&r.before));
    for (i, c) in r.candidates.iter().enumerate() {
        out.push('\n');
        candidate(&mut out, i + 1, c);
    }
    if !r.notes.is_empty() {
        out.push('\n');
        for n in &r.notes {
            let _ = writeln!(out, "note: {n}");
        }
    }
    if !r.candidates.is_empty() {
        let _ = writeln!(
            out,
            "\nwrite a repaired file: mbsa repair {file} --apply 1 --format toml -o repaired.toml"
        );
    }
    out
}

fn candidate(out: &mut String, n: usize, c: &Candidate) {
    let _ = writeln!(
        out,
        "candidate {n}: {} joint{} changed, {} joint freedom{} {}{}",
        c.joints_changed,
        if c.joints_changed == 1 { "" } else { "s" },
        c.freedoms_added.abs(),
        if c.freedoms_added.abs() == 1 { "" } else { "s" },
        if c.freedoms_added < 0 {
            "removed"
        } else {
            "added"
        },
        if c.complete { "" } else { " (partial)" }
    );
    let mut t = super::new_table();
    t.set_header(vec!["joint", "bodies", "before", "after", "rows"]);
    for ch in &c.changes {
        t.add_row(vec![
            ch.joint.clone(),
            ch.bodies.join("-"),
            ch.from.clone(),
            short_after(ch),
            format!("{:+}", -ch.rows_removed),
        ]);
    }
    let _ = writeln!(out, "{t}");
    // One line per distinct reason, naming its joints.
    let mut reasons: Vec<(&str, Vec<&str>)> = Vec::new();
    for ch in &c.changes {
        match reasons.iter_mut().find(|(w, _)| *w == ch.why) {
            Some((_, joints)) => joints.push(&ch.joint),
            None => reasons.push((&ch.why, vec![&ch.joint])),
        }
    }
    for (why, joints) in reasons {
        let _ = writeln!(out, "why {}: {why}", names(&joints));
    }
    let _ = writeln!(out, "after (checked): {}", state_line(&c.after));
}

/// At most six names, then how many more.
fn names(joints: &[&str]) -> String {
    if joints.len() <= 6 {
        return joints.join(", ");
    }
    format!("{} and {} more", joints[..5].join(", "), joints.len() - 5)
}

/// [`after_text`] with directions to four decimals (the written file keeps every digit).
fn short_after(c: &Change) -> String {
    let mut s = c.to.clone();
    let g = &c.geometry;
    for (key, v) in [("axis", g.axis), ("axis2", g.axis2), ("normal", g.normal)] {
        if let Some(v) = v {
            let parts: Vec<String> = v
                .iter()
                .map(|x| {
                    let t = format!("{x:.4}");
                    let t = t.trim_end_matches('0').trim_end_matches('.').to_string();
                    if t == "-0" { "0".into() } else { t }
                })
                .collect();
            let _ = write!(s, " {key} [{}]", parts.join(", "));
        }
    }
    s
}
