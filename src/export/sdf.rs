//! The SDFormat writer: links, and every joint directly (loops included).

use super::xml::{centroid, comment_block, esc, num, vec3};
use super::{Elem, Model, PairOut};
use crate::joint::JointType;
use std::fmt::Write;

/// The SDFormat 1.7 text of `model`.
pub(super) fn write(model: &mut Model) -> String {
    let m = model.m;
    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    out.push_str(&header(model));
    match model.precision {
        None => {
            let _ = writeln!(
                out,
                "<sdf version=\"1.7\">\n  <model name=\"{}\">",
                esc(&m.name)
            );
        }
        Some(p) => {
            let _ = write!(
                out,
                "<sdf version=\"1.7\" xmlns:mbsa=\"{}\">\n  <model name=\"{}\">\n    \
                 <!-- how precisely the numbers are known (the file's `precision`) -->\n    \
                 <mbsa:precision>{}</mbsa:precision>\n",
                crate::import::MBSA_NAMESPACE,
                esc(&m.name),
                num(p)
            );
        }
    }
    for b in (0..m.bodies.len()).filter(|&b| b != m.frame) {
        let com = centroid(&points_of(model, b));
        let name = model.body_names[b].clone();
        link(&mut out, &name, com, 1.0);
    }
    for p in 0..model.pairs.len() {
        pair(model, p, &mut out);
    }
    out.push_str("  </model>\n</sdf>\n");
    out
}

fn header(model: &Model) -> String {
    let m = model.m;
    let mut out = comment_block(
        "",
        &format!(
            "{}: written by mbsa export from {} (SDFormat 1.7). Every joint is written \
             directly, the loops' too ({} loop(s); `mbsa cut` lists them).",
            m.name, model.source, model.cuts.loops
        ),
    );
    out.push_str(&comment_block(
        "",
        "Every link frame is the world frame at the file's configuration (a mechanism file \
         gives its joints in one world frame): the joint positions and axes are the file's \
         numbers. Masses: mechanism files carry none; every link has a unit mass and a unit \
         inertia at the centroid of its joints, the light links of a joint written as a chain \
         0.001.",
    ));
    if m.space != crate::mechanism::Space::Spatial {
        out.push_str(&comment_block(
            "",
            &format!(
                "A {} mechanism written in space; each cut joint of `mbsa cut` also frees the \
                 motions out of that space (a chain through light links), so that none of its \
                 rows is redundant for being written in space.",
                m.space.name()
            ),
        ));
    }
    let driven: Vec<String> = model
        .pairs
        .iter()
        .filter(|p| p.driven > 0)
        .map(|p| format!("`{}` ({} DOF: {})", p.label, p.driven, p.names.join(", ")))
        .collect();
    if !driven.is_empty() {
        out.push_str(&comment_block(
            "",
            &format!(
                "Driven inputs (SDFormat has no actuator element; a controller plugin drives \
                 them): {}.",
                driven.join("; ")
            ),
        ));
    }
    for w in model.warnings {
        out.push_str(&comment_block("", &format!("warning: {w}")));
    }
    out
}

fn link(out: &mut String, name: &str, com: [f64; 3], mass: f64) {
    let i = if mass == 1.0 { "1" } else { "1e-6" };
    let _ = write!(
        out,
        "    <link name=\"{}\">\n      <inertial>\n        <pose>{} 0 0 0</pose>\n        \
         <mass>{}</mass>\n        <inertia><ixx>{i}</ixx><ixy>0</ixy><ixz>0</ixz><iyy>{i}</iyy>\
         <iyz>0</iyz><izz>{i}</izz></inertia>\n      </inertial>\n    </link>\n",
        esc(name),
        vec3(com),
        num(mass)
    );
}

/// The joint points of body `b` (for its centre of mass).
fn points_of(model: &Model, b: usize) -> Vec<[f64; 3]> {
    model
        .plan
        .pairs
        .iter()
        .enumerate()
        .filter(|(_, p)| p.hub == b || p.other == b)
        .filter_map(|(i, _)| model.pairs[i].elems.first().map(Elem::pos))
        .collect()
}

/// A pair: one SDFormat joint, or a chain of them through light links.
fn pair(model: &mut Model, p: usize, out: &mut String) {
    let pr = model.plan.pairs[p];
    let name_of = |b: usize| {
        if b == model.m.frame {
            "world".to_string()
        } else {
            model.body_names[b].clone()
        }
    };
    let (parent, child) = (name_of(pr.hub), name_of(pr.other));
    let po = model.pairs[p].clone();
    let _ = writeln!(
        out,
        "    <!-- {} ({}{}) -->",
        super::xml::comment(&po.label),
        po.kind.code(),
        if po.cut { ", cut" } else { "" }
    );
    if po.kind == JointType::U && po.elems.len() == 2 {
        universal(out, &po, &parent, &child);
        return;
    }
    let n = po.elems.len();
    let mut from = parent;
    for (k, (e, name)) in po.elems.iter().zip(&po.names).enumerate() {
        let to = if k + 1 == n {
            child.clone()
        } else {
            let l = model.bodies.take(&format!("{}~{}", po.label, k + 1));
            link(out, &l, e.pos(), 0.001);
            l
        };
        joint(out, name, e, &from, &to);
        from = to;
    }
}

fn joint(out: &mut String, name: &str, e: &Elem, parent: &str, child: &str) {
    let (kind, axis, extra) = match *e {
        Elem::Hinge { axis, .. } => ("revolute", Some(axis), String::new()),
        Elem::Slide { axis, .. } => ("prismatic", Some(axis), String::new()),
        Elem::Ball { .. } => ("ball", None, String::new()),
        Elem::Screw { axis, pitch, .. } => {
            // The importer's reading of 1.7: `thread_pitch` in radians per length.
            let t = if pitch == 0.0 { 0.0 } else { 1.0 / pitch };
            (
                "screw",
                Some(axis),
                format!("      <thread_pitch>{}</thread_pitch>\n", num(t)),
            )
        }
    };
    let _ = write!(
        out,
        "    <joint name=\"{}\" type=\"{kind}\">\n      <parent>{}</parent>\n      \
         <child>{}</child>\n      <pose>{} 0 0 0</pose>\n{extra}",
        esc(name),
        esc(parent),
        esc(child),
        vec3(e.pos())
    );
    if let Some(a) = axis {
        let _ = writeln!(out, "      <axis><xyz>{}</xyz></axis>", vec3(a));
    }
    out.push_str("    </joint>\n");
}

/// A U joint as one `universal` joint.
fn universal(out: &mut String, p: &PairOut, parent: &str, child: &str) {
    let (Elem::Hinge { pos, axis }, Elem::Hinge { axis: axis2, .. }) = (p.elems[0], p.elems[1])
    else {
        return;
    };
    let _ = write!(
        out,
        "    <joint name=\"{}\" type=\"universal\">\n      <parent>{}</parent>\n      \
         <child>{}</child>\n      <pose>{} 0 0 0</pose>\n      <axis><xyz>{}</xyz></axis>\n      \
         <axis2><xyz>{}</xyz></axis2>\n    </joint>\n",
        esc(&p.label),
        esc(parent),
        esc(child),
        vec3(pos),
        vec3(axis),
        vec3(axis2)
    );
}
