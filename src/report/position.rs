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
            st.bodies.join(", "),
            st.iterations.to_string(),
            st.nullity.to_string(),
            format!("{:.2e}", st.conditioning),
        ]);
    }
    let _ = writeln!(s, "\n{t}");
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

/// A sweep: one row per step, the swept value and every joint's values.
pub fn sweep_table(joint: &str, rows: &[(f64, Vec<JointValues>)]) -> String {
    let mut t = super::new_table();
    let mut header = vec![format!("{joint} (input)")];
    if let Some((_, first)) = rows.first() {
        header.extend(
            first
                .iter()
                .filter(|v| !v.values.is_empty())
                .map(|v| v.joint.clone()),
        );
    }
    t.set_header(header);
    for (x, vals) in rows {
        let mut row = vec![num(*x)];
        row.extend(
            vals.iter()
                .filter(|v| !v.values.is_empty())
                .map(values_text),
        );
        t.add_row(row);
    }
    format!("{t}\n")
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
    let _ = writeln!(
        s,
        "Finite mobility: {} (first order {}, count {}; nullity at {} nearby points: {:?})",
        f.finite,
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
    use super::axis_text;

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
