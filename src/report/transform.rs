//! Structural transformations as tables: the ranked families of determined placements, and
//! one given placement beside the file's own; JSON lines for streaming.

use crate::structure::Status;
use crate::transform::{
    Comparison, Criterion, Evaluation, Input, Placement, Ranked, Summary, Transform, count_words,
};
use std::fmt::Write;

/// How many member placements a family row lists before `+n more`.
const MEMBERS_SHOWN: usize = 3;

/// Widest table (in columns) printed as it is; a wider one (long joint ids: every input is
/// written `id (pair)`) has its lists broken into lines so that it fits a terminal.
const TABLE_WIDTH: usize = 120;

/// Widest line of a wrapped inputs or types cell.
const INPUTS_WIDTH: usize = 40;

/// How much of a family table is broken into lines: the lists of types (and a family's size
/// under its rank) first, then the inputs too (and one type a line).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Wrap {
    None,
    Types,
    All,
}

/// Widest line of a table, in characters.
fn table_width(rendered: &str) -> usize {
    rendered
        .lines()
        .map(|l| l.trim_end().chars().count())
        .max()
        .unwrap_or(0)
}

/// `labels` joined by `, ` in lines of at most `width` characters (an entry is never split
/// except one too wide alone, broken before its ` (pair)`); continuation lines are indented
/// by `indent` spaces (two for inputs, so that the lines of several placements in one cell
/// stay apart).
fn wrap_labels(labels: &[String], width: usize, indent: usize) -> String {
    let mut out = String::new();
    let mut line = 0;
    for (k, l) in labels.iter().enumerate() {
        let sep = if k + 1 < labels.len() { "," } else { "" };
        let n = l.chars().count() + sep.len();
        if k > 0 {
            if line + 1 + n > width {
                out.push('\n');
                out.push_str(&" ".repeat(indent));
                line = indent;
            } else {
                out.push(' ');
                line += 1;
            }
        }
        match l.split_once(" (") {
            Some((id, pair)) if line + n > width && line + id.chars().count() < width => {
                let _ = write!(out, "{id}\n{}({pair}{sep}", " ".repeat(indent + 2));
                line = indent + 3 + pair.chars().count() + sep.len();
            }
            _ => {
                let _ = write!(out, "{l}{sep}");
                line += n;
            }
        }
    }
    out
}

/// `1-13` when the id is the body pair, `A (1-2)` otherwise; `:n` for n driven DOF.
fn input_label(i: &Input) -> String {
    let base = if i.joint == i.pair {
        i.joint.clone()
    } else {
        format!("{} ({})", i.joint, i.pair)
    };
    if i.driven == 1 {
        base
    } else {
        format!("{base}:{}", i.driven)
    }
}

fn inputs_label(inputs: &[Input]) -> String {
    if inputs.is_empty() {
        return "(none)".into();
    }
    inputs
        .iter()
        .map(input_label)
        .collect::<Vec<_>>()
        .join(", ")
}

/// `2×1P1U1S3D, 1×1R3D`: each type with its count, uncovered types marked `*`.
fn types_label(types: &[crate::structure::TypeCount]) -> String {
    types
        .iter()
        .map(|t| {
            format!(
                "{}×{}{}",
                t.count,
                t.kind,
                if t.in_library { "" } else { "*" }
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn coverage(covered: usize, groups: usize) -> String {
    format!("{covered}/{groups}")
}

/// The counts and notes above the table.
pub fn summary(s: &Summary) -> String {
    let mut out = String::new();
    // Where the count is not the mobility, say both: "count -2, true mobility 1: 1 input".
    let mut why = format!("count {}", s.count);
    if s.set_aside > 0 {
        let _ = write!(why, ", true mobility {}", s.count + s.set_aside as i64);
    }
    if s.isolated > 0 {
        let _ = write!(why, ", minus {} isolated", s.isolated);
    }
    // A negative f is a count of surplus constraints, not of inputs: no input can be placed.
    let to_place = if s.f < 0 {
        format!("no input to place ({} DOF over-constrained by count)", -s.f)
    } else {
        format!("{} input(s) to place", s.f)
    };
    let _ = writeln!(
        out,
        "{}: {}: {}; {} count-valid placement(s) examined, {} excluded by the rank check, {} \
         determined{}",
        s.name,
        why,
        to_place,
        count_words(s.count_valid),
        count_words(s.excluded_by_rank),
        count_words(s.determined),
        if s.parts > 1 {
            format!(" (products over {} independent parts)", s.parts)
        } else {
            String::new()
        }
    );
    if let Some(g) = &s.geometry {
        let _ = writeln!(out, "{}", super::geometry_line(g));
    }
    for n in &s.notes {
        let _ = writeln!(out, "note: {n}");
    }
    out
}

/// The top `top` families of placements (placements with the same partition into groups
/// share a row; the row shows its best member's scores).
pub fn table(t: &Transform, top: usize) -> String {
    let families: Vec<&[usize]> = t.families.iter().map(|f| &f.placements[..]).collect();
    ranked_table(
        &t.summary,
        &t.criteria,
        t.original_rank,
        &t.placements,
        &families,
        top,
    )
}

/// [`table`] of a [`Ranked`] (the table shows no partition: none is made).
pub fn table_of_ranked(t: &Ranked, top: usize) -> String {
    let families: Vec<&[usize]> = t.families.iter().map(|f| &f[..]).collect();
    ranked_table(
        &t.summary,
        &t.criteria,
        t.original_rank,
        &t.placements,
        &families,
        top,
    )
}

/// The table of ranked `placements` grouped into `families` (each its members' ranks).
fn ranked_table(
    summary_: &Summary,
    criteria: &[Criterion],
    original_rank: Option<usize>,
    placements: &[Placement],
    families: &[&[usize]],
    top: usize,
) -> String {
    let mut out = summary(summary_);
    let crit: Vec<&str> = criteria.iter().map(|c| c.name()).collect();
    let _ = writeln!(
        out,
        "{} placement(s) in {} famil{} with distinct groups; ranked by {}{}",
        placements.len(),
        families.len(),
        if families.len() == 1 { "y" } else { "ies" },
        crit.join(", "),
        match original_rank {
            Some(r) => format!("; the file's own inputs rank {r}"),
            None => String::new(),
        }
    );
    if families.is_empty() {
        return out;
    }
    let expansions = placements.iter().any(|p| p.expansion.is_some());
    let mut tbl = String::new();
    for wrap in [Wrap::None, Wrap::Types, Wrap::All] {
        tbl = family_table(placements, families, top, expansions, wrap, INPUTS_WIDTH);
        let width = table_width(&tbl);
        if wrap == Wrap::All && width < TABLE_WIDTH {
            // The inputs take the room the other columns leave.
            let wider = INPUTS_WIDTH + TABLE_WIDTH - width;
            tbl = family_table(placements, families, top, expansions, wrap, wider);
        }
        if width <= TABLE_WIDTH {
            break;
        }
    }
    let _ = writeln!(out, "{tbl}");
    if families.len() > top {
        let _ = writeln!(
            out,
            "{} more famil{} not shown (raise --top, or use --format json)",
            families.len() - top,
            if families.len() - top == 1 {
                "y"
            } else {
                "ies"
            }
        );
    }
    out
}

/// The rows of the top `top` families, their lists broken into lines as `wrap` says.
fn family_table(
    placements: &[Placement],
    families: &[&[usize]],
    top: usize,
    expansions: bool,
    wrap: Wrap,
    inputs_width: usize,
) -> String {
    let mut tbl = super::new_table();
    let mut header = vec!["rank", "inputs"];
    if expansions {
        header.push("expansion");
    }
    header.extend([
        "groups",
        "largest",
        "levels",
        "library",
        if wrap == Wrap::All {
            "types\n(* not in library)"
        } else {
            "types (* not in library)"
        },
    ]);
    tbl.set_header(header);
    for fam in families.iter().take(top) {
        let members: Vec<&Placement> = fam.iter().filter_map(|&r| placements.get(r - 1)).collect();
        let Some(best) = members.first() else {
            continue;
        };
        let mut lines: Vec<String> = members
            .iter()
            .take(MEMBERS_SHOWN)
            .map(|p| {
                if wrap == Wrap::All && !p.inputs.is_empty() {
                    let labels: Vec<String> = p.inputs.iter().map(input_label).collect();
                    wrap_labels(&labels, inputs_width, 2)
                } else {
                    inputs_label(&p.inputs)
                }
            })
            .collect();
        if members.len() > MEMBERS_SHOWN {
            let sep = if wrap == Wrap::All { "\n  " } else { " " };
            lines.push(format!(
                "(+{} more with{sep}the same groups)",
                members.len() - MEMBERS_SHOWN
            ));
        }
        let ranks = if members.len() == 1 {
            best.rank.unwrap_or(0).to_string()
        } else {
            let sep = if wrap > Wrap::None { "\n" } else { " " };
            format!(
                "{}{sep}({} placements)",
                best.rank.unwrap_or(0),
                members.len()
            )
        };
        let mut row = vec![ranks, lines.join("\n")];
        if expansions {
            let e = best.expansion_brief().unwrap_or_default().to_string();
            // One multiple joint's pairs a line.
            row.push(if wrap == Wrap::All {
                e.replace("; ", ";\n")
            } else {
                e
            });
        }
        row.extend([
            best.scores.groups.to_string(),
            best.scores.largest.to_string(),
            best.scores.levels.to_string(),
            coverage(best.scores.covered, best.scores.groups),
            match wrap {
                Wrap::None => types_label(&best.types),
                Wrap::Types => {
                    let labels: Vec<String> = types_label(&best.types)
                        .split(", ")
                        .map(String::from)
                        .collect();
                    wrap_labels(&labels, INPUTS_WIDTH, 0)
                }
                Wrap::All => types_label(&best.types).replace(", ", "\n"),
            },
        ]);
        tbl.add_row(row);
    }
    tbl.to_string()
}

fn status_label(s: Status) -> &'static str {
    match s {
        Status::Determined => "determined",
        Status::Overdetermined => "over-determined",
        Status::Underdetermined => "under-determined",
        Status::Mixed => "not determined",
    }
}

fn groups_label(e: &Evaluation) -> String {
    let mut by_level: Vec<String> = Vec::new();
    let mut level = 0;
    for g in &e.groups {
        if g.level != level {
            level = g.level;
            by_level.push(format!("L{level}:"));
        }
        if let Some(last) = by_level.last_mut() {
            let _ = write!(
                last,
                " {{{}}} {}{}",
                g.bodies.join(","),
                g.kind,
                if g.in_library { "" } else { "*" }
            );
        }
    }
    by_level.join("\n")
}

/// One given placement beside the file's own.
pub fn comparison(c: &Comparison) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{}: the file's inputs against the given ones", c.name);
    let rendered = comparison_table(c, false);
    let t = if table_width(&rendered) > TABLE_WIDTH {
        comparison_table(c, true)
    } else {
        rendered
    };
    let _ = writeln!(out, "{t}");
    let crit: Vec<&str> = c.criteria.iter().map(|x| x.name()).collect();
    let ch = &c.changes;
    if ch.same_partition {
        let _ = writeln!(out, "same partition into groups");
    } else {
        let list = |gs: &[crate::transform::GroupBrief]| {
            gs.iter()
                .map(|g| format!("{{{}}}", g.bodies.join(",")))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let _ = writeln!(
            out,
            "{} group(s) in common; only with the file's inputs: {}; only with the given: {}",
            ch.common,
            if ch.only_file.is_empty() {
                "-".into()
            } else {
                list(&ch.only_file)
            },
            if ch.only_given.is_empty() {
                "-".into()
            } else {
                list(&ch.only_given)
            },
        );
    }
    let _ = writeln!(
        out,
        "verdict ({}): the given placement is {}",
        crit.join(", "),
        ch.verdict
    );
    out
}

/// The table of [`comparison`]; `wrap`: the inputs and the groups broken into lines.
fn comparison_table(c: &Comparison, wrap: bool) -> String {
    let inputs_cell = |inputs: &[Input]| {
        if wrap && !inputs.is_empty() {
            let labels: Vec<String> = inputs.iter().map(input_label).collect();
            wrap_labels(&labels, INPUTS_WIDTH, 2)
        } else {
            inputs_label(inputs)
        }
    };
    let groups_cell = |e: &Evaluation| {
        let text = groups_label(e);
        if wrap {
            // One group a line, under its level.
            text.replace(" {", "\n  {")
        } else {
            text
        }
    };
    let mut t = super::new_table();
    t.set_header(vec!["", "file", "given", "change"]);
    let signed = |d: i64| {
        if d == 0 {
            "=".to_string()
        } else {
            format!("{d:+}")
        }
    };
    let (f, g, ch) = (&c.file, &c.given, &c.changes);
    t.add_row(vec![
        "inputs".to_string(),
        inputs_cell(&f.inputs),
        inputs_cell(&g.inputs),
        String::new(),
    ]);
    t.add_row(vec![
        "status".to_string(),
        status_label(f.status).to_string(),
        status_label(g.status).to_string(),
        String::new(),
    ]);
    let numbers = [
        ("groups", f.scores.groups, g.scores.groups, ch.groups),
        (
            "largest group",
            f.scores.largest,
            g.scores.largest,
            ch.largest,
        ),
        ("levels", f.scores.levels, g.scores.levels, ch.levels),
    ];
    for (label, file, given, change) in numbers {
        t.add_row(vec![
            label.to_string(),
            file.to_string(),
            given.to_string(),
            signed(change),
        ]);
    }
    t.add_row(vec![
        "library coverage".to_string(),
        coverage(f.scores.covered, f.scores.groups),
        coverage(g.scores.covered, g.scores.groups),
        signed(ch.covered),
    ]);
    t.add_row(vec![
        "types (* not in library)".to_string(),
        types_label(&f.types).replace(", ", "\n"),
        types_label(&g.types).replace(", ", "\n"),
        String::new(),
    ]);
    t.add_row(vec![
        "groups by level".to_string(),
        groups_cell(f),
        groups_cell(g),
        String::new(),
    ]);
    t.to_string()
}

/// One record as a single JSON line with a trailing newline, `format_version` first, for
/// `--format jsonl`.
pub fn jsonl<T: serde::Serialize>(value: &T) -> String {
    super::json::jsonl(value)
}

pub mod shard;
