//! Text report of the geometric rigidity analysis ([`crate::rigidity::geometric`]): a short
//! explanation of why the count and the true mobility differ, then the details.

use crate::rigidity::geometric::{Axis, GeometricReport};
use std::fmt::Write;

fn num(x: f64) -> String {
    let s = format!("{:.4}", x);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

fn vec3(v: &[f64; 3]) -> String {
    format!("({}, {}, {})", num(v[0]), num(v[1]), num(v[2]))
}

fn axis_text(a: &Axis) -> String {
    match (a.kind.as_str(), &a.point) {
        ("translation", _) => format!("translation along {}", vec3(&a.direction)),
        ("screw", Some(p)) => format!(
            "screw about {} through {}, pitch {}",
            vec3(&a.direction),
            vec3(p),
            num(a.pitch.unwrap_or(0.0))
        ),
        (_, Some(p)) => format!("rotation about {} through {}", vec3(&a.direction), vec3(p)),
        _ => a.kind.clone(),
    }
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The report as an explanation, e.g. for the double banana: "count 18; true mobility 19 =
/// 18 fully isolated + 1 structurally isolated + 0 proper; 1 redundant constraint ...".
pub fn table(r: &GeometricReport) -> String {
    let mut s = String::new();
    header(&mut s, r);
    let _ = writeln!(s);
    mobility_and_redundancy(&mut s, r);
    isolated_motions(&mut s, r);
    rigid_parts(&mut s, r);
    loops(&mut s, r);
    if let Some(n) = &r.finite_note {
        let _ = writeln!(s, "Note: {n}.");
    }
    if let Some(w) = &r.numeric.warning {
        let _ = writeln!(s, "Warning: {w}.");
    }
    s
}

/// The mechanism, the geometry analysed and the frame.
fn header(s: &mut String, r: &GeometricReport) {
    let _ = writeln!(
        s,
        "Geometric rigidity: {} ({}, B = {})",
        r.name,
        r.space.name(),
        r.b
    );
    let geometry = if r.geometry == "file" {
        "the configuration given in the file".to_string()
    } else {
        format!(
            "a {} of the joint types",
            r.geometry.replace("random", "random realization")
        )
    };
    let _ = writeln!(
        s,
        "Results are instantaneous (first order) and hold for {geometry}; frame: {}.",
        r.frame
    );
    if let Some(n) = &r.geometry_note {
        let _ = writeln!(s, "Geometry: {n}.");
    }
    if let Some(c) = &r.geometry_used.closure {
        let _ = writeln!(s, "{}", super::position::closure_lines(c));
    }
}

/// The count against the true mobility, the redundant constraints and the locked DOF.
fn mobility_and_redundancy(s: &mut String, r: &GeometricReport) {
    let _ = writeln!(s, "count {}; true mobility {}", r.count, r.mobility);
    let mut parts = Vec::new();
    if r.fully_isolated > 0 {
        parts.push(format!("{} fully isolated", r.fully_isolated));
    }
    if r.structurally_isolated > 0 {
        parts.push(format!("{} structurally isolated", r.structurally_isolated));
    }
    parts.push(format!("{} proper", r.proper_mobility));
    let _ = writeln!(s, "  = {}", parts.join(" + "));
    let _ = writeln!(
        s,
        "{} (rows {}, rank {}, unknowns {})",
        plural(r.redundant, "redundant constraint", "redundant constraints"),
        r.rows,
        r.rank,
        r.columns
    );
    if !r.redundant_joints.is_empty() {
        let list: Vec<String> = r
            .redundant_joints
            .iter()
            .map(|w| format!("{} ({})", w.joint, num(w.weight)))
            .collect();
        let _ = writeln!(s, "  joints involved, by weight: {}", list.join(", "));
    }
    if !r.redundant_joints_unweighted.is_empty() {
        let _ = writeln!(
            s,
            "  joints involved, weights not computed: {}",
            r.redundant_joints_unweighted.join(", ")
        );
    }
    if let Some(n) = &r.weights_note {
        let _ = writeln!(s, "  Note: {n}.");
    }
    if r.mobility as i64 != r.count && r.redundant > 0 {
        let _ = writeln!(
            s,
            "Why the count differs: it assumes all constraints independent; at this geometry {} \
             dependent.",
            if r.redundant == 1 {
                "1 is".to_string()
            } else {
                format!("{} are", r.redundant)
            }
        );
    }
    if r.locked > 0 {
        let list: Vec<String> = r
            .locked_joints
            .iter()
            .map(|j| format!("{} {}", j.joint, j.dof))
            .collect();
        // At the file's configuration "locked" is first order: a piston at a crank's dead
        // centre has no velocity there but moves at once (Modelica's EngineV6).
        let what = if r.driven > 0 {
            // With the inputs held, what they fix is locked too (a driven five-bar's pins).
            "joint freedoms with no first-order motion with the inputs held: fixed by the inputs, or by the geometry as at a dead centre; `rigid` without `--with-inputs` gives the geometry's own"
        } else if r.geometry == "file" {
            "joint freedoms with no first-order motion here; `--finite` tells which of these joints move nearby, as at a dead centre"
        } else {
            "joint freedoms that never move"
        };
        let _ = writeln!(
            s,
            "{} ({what}): {}",
            plural(r.locked, "locked DOF", "locked DOF"),
            list.join(", ")
        );
    }
}

/// The isolated motions, each with its axis when it has one.
fn isolated_motions(s: &mut String, r: &GeometricReport) {
    if !r.isolated_motions.is_empty() {
        let _ = writeln!(s);
        let _ = writeln!(s, "Isolated motions ({}):", r.isolated);
        for m in &r.isolated_motions {
            let what = if m.kind == "fully" {
                format!("body {}", m.bodies.join(", "))
            } else {
                format!("rigid part [{}]", m.bodies.join(", "))
            };
            let how = m
                .axis
                .as_ref()
                .map(axis_text)
                .unwrap_or_else(|| plural(m.dof, "motion", "independent motions"));
            let _ = writeln!(
                s,
                "  {} {what}: {how} (joints {})",
                m.kind,
                m.joints.join(", ")
            );
        }
    }
}

/// The rigid parts beyond single bodies.
fn rigid_parts(s: &mut String, r: &GeometricReport) {
    let _ = writeln!(s);
    if r.rigid.is_empty() {
        let _ = writeln!(s, "Rigid parts: none beyond single bodies.");
    } else {
        let _ = writeln!(
            s,
            "Rigid parts (isolated motions set aside; single bodies omitted):"
        );
        for c in &r.rigid {
            let tag = if c.frame { " (with the frame)" } else { "" };
            let _ = writeln!(s, "  [{}]{tag}", c.bodies.join(", "));
        }
    }
}

/// The loops of the minimum cycle basis, or why they are not listed.
fn loops(s: &mut String, r: &GeometricReport) {
    let _ = writeln!(s);
    if let Some(n) = &r.loops_note {
        let _ = writeln!(s, "Loops: {n}.");
    } else if !r.loops.is_empty() {
        let _ = writeln!(
            s,
            "Loops (minimum cycle basis: spatiality, overconstraint):"
        );
        for l in &r.loops {
            let _ = writeln!(
                s,
                "  {}: spatiality {}, overconstraint {}",
                l.joints.join("-"),
                l.spatiality,
                l.overconstraint
            );
        }
    }
}
