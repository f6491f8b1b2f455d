//! Text reports of the position level ([`crate::position`]): solved poses, sweeps, the
//! closure section and finite mobility.

use crate::position::{Closure, ClosureStatus, FiniteMobility, JointValues, SolveReport};
use std::fmt::Write;

fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

/// A rotation's axis as printed: an angle that prints as 0 has no meaningful axis (a rotation
/// of 10^-8 degrees has one made of rounding noise), so it gets the axis an exact zero gets.
fn axis_text(angle_deg: f64, axis: [f64; 3]) -> String {
    let axis = if num(angle_deg) == "0" {
        [0.0, 0.0, 1.0]
    } else {
        axis
    };
    format!("({}, {}, {})", num(axis[0]), num(axis[1]), num(axis[2]))
}

fn values_text(v: &JointValues) -> String {
    v.values
        .iter()
        .zip(&v.units)
        .map(|(x, u)| {
            if *u == "deg" {
                format!("{}°", num(*x))
            } else {
                num(*x)
            }
        })
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The solved poses, joint values and solve steps.
pub fn solve_table(r: &SolveReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: solved {} ({} step(s)), largest joint residual {:.1e}",
        r.name,
        if r.method == "groups" {
            "group by group"
        } else {
            "globally"
        },
        r.steps.len(),
        r.max_residual
    );
    let mut t = super::new_table();
    t.set_header([
        "step",
        "level",
        "bodies",
        "iterations",
        "nullity",
        "conditioning",
    ]);
    for st in &r.steps {
        t.add_row([
            st.name.clone(),
            st.level.to_string(),
            crate::words::capped(&st.bodies),
            st.iterations.to_string(),
            st.nullity.to_string(),
            format!("{:.2e}", st.conditioning),
        ]);
    }
    let _ = writeln!(s, "\n{t}");
    s.push_str(&freedom_notes(r));
    let mut t = super::new_table();
    t.set_header(["body", "x", "y", "z", "angle (deg)", "axis"]);
    for p in &r.poses {
        t.add_row([
            p.body.clone(),
            num(p.translation[0]),
            num(p.translation[1]),
            num(p.translation[2]),
            num(p.angle_deg),
            axis_text(p.angle_deg, p.axis),
        ]);
    }
    let _ = writeln!(
        s,
        "\nBody poses (position of the body point at the file's origin; rotation from the file's configuration)\n{t}"
    );
    let mut t = super::new_table();
    t.set_header(["joint", "values (from the file's configuration)"]);
    for v in &r.joint_values {
        if !v.values.is_empty() {
            t.add_row([v.joint.clone(), values_text(v)]);
        }
    }
    let _ = writeln!(s, "\n{t}");
    if let Some(f) = &r.finite {
        let _ = write!(s, "\n{}", finite_section(f));
    }
    s
}

/// A note per step whose equations leave freedoms at the solution (nullity above 0): along
/// them its bodies kept their start pose, which no input chose.
fn freedom_notes(r: &SolveReport) -> String {
    let mut s = String::new();
    for st in r.steps.iter().filter(|st| st.nullity > 0) {
        // Exactly the isolated spins of the step's bodies (a Delta's three rods): named.
        let spins: Vec<&str> = r
            .isolated
            .iter()
            .filter(|(b, _)| st.bodies.contains(b))
            .map(|(b, _)| b.as_str())
            .collect();
        let dof: u64 = r
            .isolated
            .iter()
            .filter(|(b, _)| st.bodies.contains(b))
            .map(|&(_, d)| u64::from(d))
            .sum();
        if dof == st.nullity as u64 {
            let _ = writeln!(
                s,
                "note: step {} leaves {} freedom(s) that neither its equations nor the inputs fix: \
                 the isolated freedoms of {} (each turns one body alone, moving no other), which \
                 take the pose of least change, not one an input chose; harmless.",
                st.name,
                st.nullity,
                crate::words::capped(&spins)
            );
            continue;
        }
        let _ = writeln!(
            s,
            "note: step {} leaves {} freedom(s) that neither its equations nor the inputs fix \
             (bodies {}):\n      along them its bodies stay near their start pose, which no \
             input chose. An isolated spin is harmless;\n      otherwise drive a joint there \
             (`--set JOINT=VALUE`), or the configuration is singular.",
            st.name,
            st.nullity,
            crate::words::capped(&st.bodies)
        );
    }
    if !s.is_empty() {
        s.push('\n');
    }
    s
}

/// Widest a sweep table gets before its joints are split over several tables.
const TABLE_WIDTH: usize = 120;

/// A sweep: one row per step, the swept value and every joint's values. A mechanism with many
/// joints (Modelica's EngineV6: 19 joints, 420 columns) gets several tables of at most
/// [`TABLE_WIDTH`] columns, each starting with the swept value, the joints in file order.
pub fn sweep_table(joint: &str, rows: &[(f64, Vec<JointValues>)]) -> String {
    let input = format!("{joint} (input)");
    let steps: Vec<String> = rows.iter().map(|(x, _)| num(*x)).collect();
    // One column per joint with values: header, then a cell per step.
    let mut columns: Vec<Vec<String>> = Vec::new();
    if let Some((_, first)) = rows.first() {
        for (k, v) in first.iter().enumerate() {
            if v.values.is_empty() {
                continue;
            }
            let mut col = vec![v.joint.clone()];
            col.extend(
                rows.iter()
                    .map(|(_, vals)| vals.get(k).map(values_text).unwrap_or_default()),
            );
            columns.push(col);
        }
    }
    // A column's share of the width: its widest line and 3 characters of padding and rule.
    let width = |cells: &mut dyn Iterator<Item = &String>| {
        cells
            .flat_map(|c| c.lines())
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0)
            + 3
    };
    let first = width(&mut std::iter::once(&input).chain(&steps));
    // A multiple joint's values (the double banana's 15 pairs) wrap at their separators.
    let room = TABLE_WIDTH.saturating_sub(first + 3).max(20);
    for col in &mut columns {
        for cell in col.iter_mut().skip(1) {
            if cell.chars().count() > room {
                *cell = wrap_values(cell, room);
            }
        }
    }
    let mut chunks: Vec<Vec<&Vec<String>>> = Vec::new();
    let mut chunk: Vec<&Vec<String>> = Vec::new();
    let mut used = first;
    for col in &columns {
        let w = width(&mut col.iter());
        if !chunk.is_empty() && used + w > TABLE_WIDTH {
            chunks.push(std::mem::take(&mut chunk));
            used = first;
        }
        used += w;
        chunk.push(col);
    }
    chunks.push(chunk);
    let mut out = String::new();
    for (i, chunk) in chunks.iter().enumerate() {
        let mut t = super::new_table();
        let mut header = vec![input.clone()];
        header.extend(chunk.iter().map(|c| c[0].clone()));
        t.set_header(header);
        for (r, step) in steps.iter().enumerate() {
            let mut row = vec![step.clone()];
            row.extend(chunk.iter().map(|c| c[r + 1].clone()));
            t.add_row(row);
        }
        if i > 0 {
            out.push('\n');
        }
        let _ = writeln!(out, "{t}");
    }
    out
}

/// `a / b / c ...` broken into lines of at most `room` characters at the separators (a single
/// value longer than `room` keeps its line).
fn wrap_values(text: &str, room: usize) -> String {
    let mut out = String::new();
    let mut line = 0;
    for (i, v) in text.split(" / ").enumerate() {
        let n = v.chars().count();
        if i > 0 {
            if line + 3 + n > room {
                out.push_str(" /\n");
                line = 0;
            } else {
                out.push_str(" / ");
                line += 3;
            }
        }
        out.push_str(v);
        line += n;
    }
    out
}

/// The closure section (for other reports): one line when closed, else a line with the
/// verdict and the worst joints, one per line.
pub fn closure_section(c: &Closure) -> String {
    let mut s = closure_lines(c);
    s.push('\n');
    s
}

/// [`closure_section`] without the final newline: `closure: every joint closed` when closed;
/// else the largest residual, the tolerance, what the first-order results use, and the worst
/// joints ([`crate::position::closure::LISTED`] at most).
pub fn closure_lines(c: &Closure) -> String {
    let mut s = String::new();
    match c.status {
        ClosureStatus::Closed => s.push_str("closure: every joint closed"),
        _ => {
            let word = if c.status == ClosureStatus::Open {
                "warning"
            } else {
                "error"
            };
            let _ = write!(
                s,
                "closure ({word}): the configuration misses closure by up to {:.3e} at {} joint(s) (tolerance {:.1e}); first-order results use the first body's geometry of each joint; `mbsa assemble` closes it",
                c.max_residual,
                c.joints.len(),
                c.tolerance
            );
            for j in c.worst(crate::position::closure::LISTED) {
                let _ = write!(s, "\n  joint {}: {:.3e}", j.joint, j.residual);
            }
            let more = c
                .joints
                .len()
                .saturating_sub(crate::position::closure::LISTED);
            if more > 0 {
                let _ = write!(s, "\n  ... and {more} more joint(s)");
            }
        }
    }
    s
}

/// Finite against first-order mobility.
pub fn finite_section(f: &FiniteMobility) -> String {
    let mut s = String::new();
    // Rounded numbers the test took as exact: the numbers are theirs, not the mechanism's.
    let (value, taken) = if f.verdict == crate::position::Verdict::Undecided {
        (
            "not decided at the written precision".to_string(),
            format!("taken as exact: {}; ", f.finite),
        )
    } else {
        (f.finite.to_string(), String::new())
    };
    let _ = writeln!(
        s,
        "Finite mobility: {value} ({taken}first order {}, count {}; nullity at {} nearby points: {:?})",
        f.first_order,
        f.count,
        f.samples.len(),
        f.samples
    );
    for n in &f.notes {
        let _ = writeln!(s, "- {n}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::{JointValues, axis_text, sweep_table};

    /// A sweep of many joints is split into tables of at most 120 columns, each led by the
    /// swept value, every joint in one of them once, in order; a narrow sweep stays one table.
    #[test]
    fn a_wide_sweep_is_split_into_tables_that_fit() {
        let joint = |id: &str, x: f64| JointValues {
            joint: id.to_string(),
            values: vec![x, -x],
            units: vec!["length", "deg"],
        };
        let ids: Vec<String> = (1..=19).map(|i| format!("cylinder{i}.cylinder")).collect();
        let rows: Vec<(f64, Vec<JointValues>)> = (0..4)
            .map(|s| {
                let x = 0.123456 * s as f64;
                (s as f64 * 60.0, ids.iter().map(|id| joint(id, x)).collect())
            })
            .collect();
        let text = sweep_table("bearing", &rows);
        let tables: Vec<&str> = text.split("\n\n").collect();
        assert!(tables.len() > 3, "{text}");
        let mut seen = Vec::new();
        for t in &tables {
            let widest = t.lines().map(|l| l.chars().count()).max().unwrap_or(0);
            assert!(widest <= 120, "{widest} columns:\n{t}");
            let header = t.lines().nth(1).expect("header line");
            assert!(header.trim_start().starts_with("bearing (input)"), "{t}");
            seen.extend(
                header
                    .split_whitespace()
                    .filter(|w| w.starts_with("cylinder")),
            );
        }
        assert_eq!(seen, ids.iter().map(String::as_str).collect::<Vec<_>>());
        // A multiple joint's 15 values wrap inside their cell.
        let multiple = vec![(
            20.0,
            vec![JointValues {
                joint: "A".into(),
                values: (0..15).map(|k| 13.812908 * f64::from(k)).collect(),
                units: vec!["deg"; 15],
            }],
        )];
        let text = sweep_table("A", &multiple);
        assert!(text.lines().all(|l| l.chars().count() <= 120), "{text}");
        assert!(text.contains("193.380712°"), "{text}");
        // Four joints fit in one table.
        let narrow: Vec<(f64, Vec<JointValues>)> =
            rows.iter().map(|(x, v)| (*x, v[..4].to_vec())).collect();
        assert_eq!(
            sweep_table("bearing", &narrow)
                .matches("bearing (input)")
                .count(),
            1
        );
    }

    /// A rotation too small to print (the xArm gripper's finger after a solve: 10^-8 degrees)
    /// printed an axis of rounding noise, `(0.975093, 0.175655, -0.135423)`; it gets the zero
    /// rotation's axis now. A rotation that prints keeps its own.
    #[test]
    fn an_angle_printed_as_zero_has_the_zero_rotations_axis() {
        let noise = [0.975093, 0.175655, -0.135423];
        assert_eq!(axis_text(1e-8, noise), "(0, 0, 1)");
        assert_eq!(axis_text(-4e-7, noise), "(0, 0, 1)");
        assert_eq!(axis_text(0.0, [0.0, 0.0, 1.0]), "(0, 0, 1)");
        assert_eq!(axis_text(20.0, [1.0, 0.0, 0.0]), "(1, 0, 0)");
        assert_eq!(axis_text(1e-6, noise), "(0.975093, 0.175655, -0.135423)");
    }
}
