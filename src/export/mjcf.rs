//! The MJCF writer: nested bodies, closures as `<equality>`, actuators, the keyframe.

use super::xml::{centroid, comment_block, esc, indent, vec3};
use super::{Elem, Model, PairOut};
use crate::joint::JointType;
use crate::mechanism::Space;
use std::fmt::Write;

/// Deepest body nesting written: MuJoCo's XML reader (tinyxml2) refuses elements nested more
/// than 500 deep, so a deeper tree continues in top-level bodies ([`relinked`]).
const MAX_NESTING: usize = 400;

/// A node of the body tree: a body of the mechanism, or the light body V of a closure: pair
/// `pair`'s joints from `parent` (in reverse when `reversed`), V welded to `child`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Node {
    Body(usize),
    Closure {
        pair: usize,
        parent: usize,
        child: usize,
        reversed: bool,
    },
}

/// What the body tree leaves for the sections after it.
#[derive(Default)]
struct Sections {
    equality: String,
    actuator: String,
    qpos: Vec<&'static str>,
}

/// The MJCF text of `model`.
pub(super) fn write(model: &mut Model) -> String {
    let relinked = relinked(model);
    let mut out = String::new();
    out.push_str(&header(model, relinked.iter().filter(|&&r| r).count()));
    let _ = writeln!(out, "<mujoco model=\"{}\">", esc(&model.m.name));
    out.push_str("  <compiler angle=\"radian\"/>\n");
    if let Some(p) = model.precision {
        let _ = write!(
            out,
            "  <custom>\n    <!-- how precisely the numbers are known (the file's `precision`) -->\n    \
             <numeric name=\"{}\" data=\"{}\"/>\n  </custom>\n",
            crate::import::PRECISION_NAME,
            super::xml::num(p)
        );
    }
    out.push_str("  <worldbody>\n");
    let mut s = Sections::default();
    body_tree(model, &relinked, &mut out, &mut s);
    out.push_str("  </worldbody>\n");
    for (tag, text) in [("equality", &s.equality), ("actuator", &s.actuator)] {
        if !text.is_empty() {
            let _ = write!(out, "  <{tag}>\n{text}  </{tag}>\n");
        }
    }
    if !s.qpos.is_empty() {
        let _ = write!(
            out,
            "  <keyframe>\n    <key name=\"file\" qpos=\"{}\"/>\n  </keyframe>\n",
            s.qpos.join(" ")
        );
    }
    out.push_str("</mujoco>\n");
    out
}

fn header(model: &Model, relinked: usize) -> String {
    let m = model.m;
    let mut text = format!(
        "{}: written by mbsa export from {} (MJCF). The tree and the cuts are those of `mbsa \
         cut` ({} loop(s), {} closure row(s), {} redundant).",
        m.name, model.source, model.cuts.loops, model.cuts.rows, model.cuts.redundant
    );
    let notes = [
        "Every body frame is the world frame at the file's configuration (a mechanism file \
         gives its joints in one world frame; bodies have no frame of their own): the joint \
         positions and axes are the file's numbers, and the keyframe `file` (every joint at \
         0) is that configuration.",
        "Masses: mechanism files carry none. Every body has a unit mass and a unit inertia at \
         the centroid of its joints, each closure body a mass of 0.001.",
        "Closures: a spherical cut is a <connect>; any other cut of kind K between bodies A \
         and B is a light body, child of A, with the joints of K, welded to B: its freedoms \
         and the weld's 6 rows leave exactly K's constraint.",
    ];
    let mut out = comment_block("", &text);
    for n in notes {
        out.push_str(&comment_block("", n));
    }
    if m.space != Space::Spatial {
        text = format!(
            "A {} mechanism written in space ({}); each closure also frees the motions out of \
             that space, which the tree joints block, so none of its rows is redundant for \
             being written in space.",
            m.space.name(),
            if m.space == Space::Planar {
                "in the plane z = 0"
            } else {
                "about the origin"
            }
        );
        out.push_str(&comment_block("", &text));
    }
    if relinked > 0 {
        text = format!(
            "The tree is deeper than {MAX_NESTING} bodies, and MuJoCo reads XML nested at most \
             500 deep: {relinked} bod(ies) continue the tree at the top level, each with a free \
             joint, its tree joint written as a closure (a light body on its parent, welded to \
             it), which leaves the same motion."
        );
        out.push_str(&comment_block("", &text));
    }
    for w in model.warnings {
        out.push_str(&comment_block("", &format!("warning: {w}")));
    }
    out
}

/// The bodies written at the top level although the tree gives them a parent: every
/// [`MAX_NESTING`]-th level of a deep tree. Each gets a free joint, and its tree joint is
/// written as a closure (a light body on the parent, welded to it): exact, as a cut is.
fn relinked(model: &Model) -> Vec<bool> {
    let plan = model.plan;
    let mut level = vec![0usize; model.m.bodies.len()];
    let mut out = vec![false; model.m.bodies.len()];
    for &b in &plan.order {
        level[b] = match plan.links[b] {
            Some(l) if level[l.parent] + 1 > MAX_NESTING => {
                out[b] = true;
                1
            }
            Some(l) => level[l.parent] + 1,
            None => usize::from(b != model.m.frame),
        };
    }
    out
}

/// The children of every body (its tree children, then the closure bodies hung on it), and
/// the bodies written at the top level.
fn children(model: &Model, relinked: &[bool]) -> (Vec<Vec<Node>>, Vec<Node>) {
    let plan = model.plan;
    let mut kids: Vec<Vec<Node>> = vec![Vec::new(); model.m.bodies.len()];
    let mut later: Vec<Node> = Vec::new();
    for &b in &plan.order {
        let Some(l) = plan.links[b] else { continue };
        if relinked[b] {
            kids[l.parent].push(Node::Closure {
                pair: l.pair,
                parent: l.parent,
                child: b,
                reversed: plan.pairs[l.pair].hub != l.parent,
            });
            later.push(Node::Body(b));
        } else {
            kids[l.parent].push(Node::Body(b));
        }
    }
    for &c in &plan.cuts {
        if !connects(model, c) {
            let p = plan.pairs[c];
            kids[p.hub].push(Node::Closure {
                pair: c,
                parent: p.hub,
                child: p.other,
                reversed: false,
            });
        }
    }
    let mut top: Vec<Node> = kids[model.m.frame].clone();
    top.extend(plan.roots.iter().skip(1).map(|&r| Node::Body(r)));
    top.extend(later);
    (kids, top)
}

/// Whether cut `c` is written as a `<connect>` (a spherical joint, not driven).
fn connects(model: &Model, c: usize) -> bool {
    let p = &model.pairs[c];
    p.kind == JointType::S && p.driven == 0 && model.m.space == Space::Spatial
}

/// The bodies, depth first, without recursion (a chain may be deep).
fn body_tree(model: &mut Model, relinked: &[bool], out: &mut String, s: &mut Sections) {
    let (kids, top) = children(model, relinked);
    // (node, depth, opening?)
    let mut stack: Vec<(Node, usize, bool)> = top.iter().rev().map(|&n| (n, 2, true)).collect();
    while let Some((node, depth, open)) = stack.pop() {
        let pad = indent(depth);
        if !open {
            let _ = writeln!(out, "{pad}</body>");
            continue;
        }
        open_node(model, node, relinked, &pad, out, s);
        stack.push((node, depth, false));
        if let Node::Body(b) = node {
            for &k in kids[b].iter().rev() {
                stack.push((k, depth + 1, true));
            }
        }
    }
    for &c in &model.plan.cuts {
        if connects(model, c) {
            connect(model, c, s);
        }
    }
}

/// A body's opening tag, inertial and joints.
fn open_node(
    model: &mut Model,
    node: Node,
    relinked: &[bool],
    pad: &str,
    out: &mut String,
    s: &mut Sections,
) {
    let inner = format!("{pad}  ");
    match node {
        Node::Body(b) => {
            let name = model.body_names[b].clone();
            let _ = writeln!(out, "{pad}<body name=\"{}\">", esc(&name));
            let com = centroid(&points_of(model, b));
            let _ = writeln!(
                out,
                "{inner}<inertial pos=\"{}\" mass=\"1\" diaginertia=\"1 1 1\"/>",
                vec3(com)
            );
            match model.plan.links[b].filter(|_| !relinked[b]) {
                None => {
                    let _ = writeln!(out, "{inner}<freejoint name=\"{}\"/>", esc(&name));
                    s.qpos.extend(["0", "0", "0", "1", "0", "0", "0"]);
                }
                Some(l) => {
                    let reversed = model.plan.pairs[l.pair].hub != l.parent;
                    joints(&model.pairs[l.pair], reversed, &inner, out, s);
                }
            }
        }
        Node::Closure {
            pair: c,
            child: other,
            reversed,
            ..
        } => {
            let label = model.pairs[c].label.clone();
            let v = model.bodies.take(&format!("cut:{label}"));
            let p = &model.pairs[c];
            let _ = writeln!(out, "{pad}<body name=\"{}\">", esc(&v));
            let com = p.elems.first().map(Elem::pos).unwrap_or([0.0; 3]);
            let _ = writeln!(
                out,
                "{inner}<inertial pos=\"{}\" mass=\"0.001\" diaginertia=\"1e-6 1e-6 1e-6\"/>",
                vec3(com)
            );
            joints(p, reversed, &inner, out, s);
            let body2 = if other == model.m.frame {
                String::new()
            } else {
                format!(" body2=\"{}\"", esc(&model.body_names[other]))
            };
            let _ = writeln!(
                s.equality,
                "    <weld name=\"{}\" body1=\"{}\"{body2}/>",
                esc(&label),
                esc(&v)
            );
        }
    }
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

/// A pair's joints (in reverse when the tree runs from its other body to its first), and
/// their actuators and keyframe values.
fn joints(p: &PairOut, reversed: bool, pad: &str, out: &mut String, s: &mut Sections) {
    let _ = writeln!(
        out,
        "{pad}<!-- {} ({}{}) -->",
        super::xml::comment(&p.label),
        p.kind.code(),
        if p.cut { ", cut" } else { "" }
    );
    let order: Vec<usize> = if reversed {
        (0..p.elems.len()).rev().collect()
    } else {
        (0..p.elems.len()).collect()
    };
    for i in order {
        let name = esc(&p.names[i]);
        match p.elems[i] {
            Elem::Hinge { pos, axis } | Elem::Screw { pos, axis, .. } => {
                let (pos, axis) = (vec3(pos), vec3(axis));
                let _ = writeln!(
                    out,
                    "{pad}<joint name=\"{name}\" type=\"hinge\" pos=\"{pos}\" axis=\"{axis}\"/>"
                );
                s.qpos.push("0");
            }
            Elem::Slide { pos, axis } => {
                let (pos, axis) = (vec3(pos), vec3(axis));
                let _ = writeln!(
                    out,
                    "{pad}<joint name=\"{name}\" type=\"slide\" pos=\"{pos}\" axis=\"{axis}\"/>"
                );
                s.qpos.push("0");
            }
            Elem::Ball { pos } => {
                let _ = writeln!(
                    out,
                    "{pad}<joint name=\"{name}\" type=\"ball\" pos=\"{}\"/>",
                    vec3(pos)
                );
                s.qpos.extend(["1", "0", "0", "0"]);
            }
        }
    }
    actuators(p, s);
}

/// The actuators of a pair's driven DOF: the first `driven` freedoms of its joints.
fn actuators(p: &PairOut, s: &mut Sections) {
    let mut left = p.driven;
    for (e, name) in p.elems.iter().zip(&p.names) {
        if left == 0 {
            break;
        }
        let name = esc(name);
        if let Elem::Ball { .. } = e {
            let axes = [("x", "1 0 0"), ("y", "0 1 0"), ("z", "0 0 1")];
            for (word, gear) in axes.into_iter().take(left as usize) {
                let _ = writeln!(
                    s.actuator,
                    "    <motor name=\"{name}:{word}\" joint=\"{name}\" gear=\"{gear}\"/>"
                );
                left -= 1;
            }
        } else {
            let _ = writeln!(
                s.actuator,
                "    <position name=\"{name}\" joint=\"{name}\" kp=\"1\"/>"
            );
            left -= 1;
        }
    }
}

/// A spherical cut as a `<connect>` (the frame, if it is one of the bodies, as the world).
fn connect(model: &Model, c: usize, s: &mut Sections) {
    let pair = model.plan.pairs[c];
    let frame = model.m.frame;
    let (b1, b2) = if pair.hub == frame {
        (pair.other, pair.hub)
    } else {
        (pair.hub, pair.other)
    };
    let body2 = if b2 == frame {
        String::new()
    } else {
        format!(" body2=\"{}\"", esc(&model.body_names[b2]))
    };
    let anchor = model.geoms[pair.joint].origin.unwrap_or([0.0; 3]);
    let _ = writeln!(
        s.equality,
        "    <connect name=\"{}\" body1=\"{}\"{body2} anchor=\"{}\"/>",
        esc(&model.pairs[c].label),
        esc(&model.body_names[b1]),
        vec3(anchor)
    );
}
