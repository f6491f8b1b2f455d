//! Graphviz DOT views of a mechanism and its kinematic structure.
//!
//! Every id and label goes through [`quote`], so names with spaces, quotes, backslashes or
//! non-ASCII characters stay valid DOT. Output order follows the model's stable order.

use crate::mechanism::Mechanism;
use crate::rigidity::geometric::GeometricReport;
use crate::structure::Analysis;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write;

/// The views `mbsa dot` can draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    /// The paper's structural diagram: one node per structural group, one row per level.
    #[default]
    Diagram,
    /// The structural graph: bodies clustered by group, edges in the direction DOF pass.
    Structure,
    /// The topological graph: bodies and joints.
    Topology,
    /// Rigid parts: bodies clustered by rigid cluster (geometric analysis), redundant joints
    /// highlighted, bodies with isolated freedoms marked.
    Rigid,
}

/// Fill colours that mark parts the analysis could not determine (shared by every view).
const OVER_COLOUR: &str = "#f4a6a6";
const UNDER_COLOUR: &str = "#f9d68a";
const UNCOVERED_COLOUR: &str = "#fff3c4";

/// Draw `view` of `m` with its structural analysis `a` (the `rigid` view needs the geometric
/// report instead: use [`rigid`]).
pub fn render(view: View, m: &Mechanism, a: &Analysis) -> String {
    match view {
        View::Diagram => diagram(a),
        View::Structure => structure(m, a),
        View::Topology | View::Rigid => topology_titled(
            m,
            closure_note(a.geometry.as_ref().and_then(|g| g.closure.as_ref())),
        ),
    }
}

/// The closure line under a view's title: `mbsa analyze`'s closure section
/// ([`super::position::closure_lines`]: the largest residual, the tolerance, the worst
/// joints) when the configuration analysed misses closure; nothing when it is closed or the
/// file's geometry was not used (a closed file's pictures stay as they were).
pub fn closure_note(c: Option<&crate::position::Closure>) -> Option<String> {
    c.filter(|c| c.status != crate::position::ClosureStatus::Closed)
        .map(super::position::closure_lines)
}

/// The rigid view: one dashed cluster per rigid part found by the geometric analysis (the
/// frame's part grey), joints that carry redundant constraints in red with their weight in
/// the left null space, bodies with isolated freedoms double-circled.
pub fn rigid(m: &Mechanism, r: &GeometricReport) -> String {
    let mut out = String::new();
    let note = closure_note(r.geometry_used.closure.as_ref());
    header(&mut out, &format!("{}: rigid parts", m.name), "TB", note);
    let _ = writeln!(out, "  edge [dir=none];");
    let ids: Vec<String> = m.bodies.iter().map(|b| b.id.to_string()).collect();
    let mut cluster_of: BTreeMap<&str, usize> = BTreeMap::new();
    for (ci, c) in r.rigid.iter().enumerate() {
        for b in &c.bodies {
            cluster_of.insert(b.as_str(), ci);
        }
    }
    let isolated: BTreeSet<&str> = r
        .isolated_motions
        .iter()
        .filter(|i| i.kind == "fully")
        .flat_map(|i| i.bodies.iter().map(String::as_str))
        .collect();
    let node = |i: usize| -> String {
        let id = ids[i].as_str();
        let shape = if i == m.frame {
            "box"
        } else if isolated.contains(id) {
            "doublecircle"
        } else {
            "circle"
        };
        let fill = if i == m.frame { "#dddddd" } else { "white" };
        format!(
            "{} [label={}, shape={shape}, style=filled, fillcolor={}];",
            body_node(i),
            quote(id),
            quote(fill)
        )
    };
    // The bodies of each part in body order, in one pass (not one pass per part).
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); r.rigid.len()];
    for (i, id) in ids.iter().enumerate() {
        if let Some(&ci) = cluster_of.get(id.as_str()) {
            members[ci].push(i);
        }
    }
    for (ci, c) in r.rigid.iter().enumerate() {
        let _ = writeln!(out, "  subgraph cluster_rigid_{ci} {{");
        let label = if c.frame {
            format!("rigid part {} (with the frame)", ci + 1)
        } else {
            format!("rigid part {}", ci + 1)
        };
        let style = if c.frame {
            "style=\"dashed,filled\"; fillcolor=\"#f2f2f2\";"
        } else {
            "style=dashed;"
        };
        let _ = writeln!(out, "    label={}; {style}", quote(&label));
        for &i in &members[ci] {
            let _ = writeln!(out, "    {}", node(i));
        }
        out.push_str("  }\n");
    }
    for (i, id) in ids.iter().enumerate() {
        if !cluster_of.contains_key(id.as_str()) {
            let _ = writeln!(out, "  {}", node(i));
        }
    }
    let redundant: BTreeMap<&str, f64> = r
        .redundant_joints
        .iter()
        .map(|w| (w.joint.as_str(), w.weight))
        .collect();
    let unweighted: BTreeSet<&str> = r
        .redundant_joints_unweighted
        .iter()
        .map(|j| j.as_str())
        .collect();
    for (ji, j) in m.joints.iter().enumerate() {
        let mut label = format!("{} {}", j.id, j.kind.code());
        let mut attrs = String::new();
        if let Some(w) = redundant.get(j.id.as_str()) {
            label.push_str(&format!("\nredundant {w:.2}"));
            attrs.push_str(", color=\"#c0392b\", fontcolor=\"#c0392b\", penwidth=2.5");
        } else if unweighted.contains(j.id.as_str()) {
            // In the redundant constraints, its weight not computed (the budget's note).
            label.push_str("\nredundant");
            attrs.push_str(", color=\"#c0392b\", fontcolor=\"#c0392b\", penwidth=2.5");
        }
        draw_joint(&mut out, ji, &j.bodies, &label, &attrs);
    }
    let _ = writeln!(
        out,
        "  legend [shape=plaintext, label=<<table border=\"0\" cellborder=\"0\" cellspacing=\"0\" cellpadding=\"2\"><tr><td align=\"left\">{}: mobility {} (count {}), {} isolated, {} redundant</td></tr><tr><td align=\"left\"><font color=\"#c0392b\">red</font>: joints in the redundant constraints; double circle: body with an isolated freedom</td></tr></table>>];",
        html(&r.geometry),
        r.mobility,
        r.count,
        r.isolated,
        r.redundant
    );
    out.push_str("}\n");
    out
}

/// Node name of group `i`.
fn sg_node(i: usize) -> String {
    format!("g{i}")
}

/// Bodies of the over- and under-determined parts, if any.
fn troubled(a: &Analysis) -> (BTreeSet<&str>, BTreeSet<&str>) {
    let mut over = BTreeSet::new();
    let mut under = BTreeSet::new();
    if let Some(d) = &a.diagnosis {
        if let Some(o) = &d.overdetermined {
            over.extend(o.bodies.iter().map(String::as_str));
        }
        if let Some(u) = &d.underdetermined {
            under.extend(u.bodies.iter().map(String::as_str));
        }
    }
    (over, under)
}

fn legend(out: &mut String, a: &Analysis, over: bool, under: bool) {
    let mut rows = Vec::new();
    if over {
        rows.push(format!("<tr><td bgcolor=\"{OVER_COLOUR}\">  </td><td align=\"left\">over-determined part</td></tr>"));
    }
    if under {
        rows.push(format!("<tr><td bgcolor=\"{UNDER_COLOUR}\">  </td><td align=\"left\">under-determined part</td></tr>"));
    }
    if a.groups.iter().any(|g| !g.in_library) {
        rows.push(format!("<tr><td bgcolor=\"{UNCOVERED_COLOUR}\">  </td><td align=\"left\">type not in library ({})</td></tr>", html(&a.library)));
    }
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "  legend [shape=plaintext, label=<<table border=\"0\" cellborder=\"1\" cellspacing=\"0\" cellpadding=\"3\">{}</table>>];",
        rows.join("")
    );
}

/// Escape text for a Graphviz HTML-like label.
fn html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The structural diagram (paper Fig. 8g, 13b): the frame as node 0, one node per group with
/// its name, bodies, (Nm, nc) = (bodies, driven inputs) and type, arrows from the groups it
/// depends on, and one `rank=same` row per level.
pub fn diagram(a: &Analysis) -> String {
    let mut out = String::new();
    let _ = write_diagram(a, &mut out);
    out
}

/// [`diagram`], written to `out` as it is made: at 10^6 bodies the text is tens of MB, and
/// held whole (grown by doubling) it set the peak of `mbsa dot` after the analysis.
pub fn write_diagram(a: &Analysis, out: &mut dyn std::fmt::Write) -> std::fmt::Result {
    let mut head = String::new();
    let note = closure_note(a.geometry.as_ref().and_then(|g| g.closure.as_ref()));
    header(
        &mut head,
        &format!("{}: structural diagram", a.name),
        "TB",
        note,
    );
    out.write_str(&head)?;
    writeln!(
        out,
        "  frame [label=\"0\\nframe\", shape=doublecircle, style=filled, fillcolor=\"#dddddd\"];"
    )?;
    let mut by_level: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (i, g) in a.groups.iter().enumerate() {
        by_level.entry(g.level).or_default().push(i);
        let label = format!(
            "{} {{{}}}\n({}, {})\n{}",
            g.name,
            g.bodies.join(","),
            g.nm,
            g.inputs,
            g.kind
        );
        let fill = if g.in_library {
            "white"
        } else {
            UNCOVERED_COLOUR
        };
        writeln!(
            out,
            "  {} [label={}, shape=ellipse, style=filled, fillcolor={}];",
            sg_node(i),
            quote(&label),
            quote(fill)
        )?;
    }
    let (over, under) = troubled(a);
    for (name, bodies, colour) in [
        ("over-determined", &over, OVER_COLOUR),
        ("under-determined", &under, UNDER_COLOUR),
    ] {
        if !bodies.is_empty() {
            let list: Vec<&str> = bodies.iter().copied().collect();
            let label = format!("{name}\n{{{}}}", list.join(","));
            writeln!(
                out,
                "  {} [label={}, shape=box, style=\"filled,dashed\", fillcolor={}];",
                quote(name),
                quote(&label),
                quote(colour)
            )?;
        }
    }
    for (i, g) in a.groups.iter().enumerate() {
        if g.depends_on.is_empty() {
            writeln!(out, "  frame -> {};", sg_node(i))?;
        }
        for &d in &g.depends_on {
            writeln!(out, "  {} -> {};", sg_node(d), sg_node(i))?;
        }
    }
    writeln!(out, "  {{ rank=same; frame; }}")?;
    for (level, groups) in &by_level {
        let nodes: Vec<String> = groups.iter().map(|&i| sg_node(i)).collect();
        writeln!(
            out,
            "  {{ rank=same; {}; }}  // level {level}",
            nodes.join("; ")
        )?;
    }
    let mut tail = String::new();
    legend(&mut tail, a, !over.is_empty(), !under.is_empty());
    out.write_str(&tail)?;
    out.write_str("}\n")
}

/// The structural graph (paper Fig. 13b, 14a): bodies inside one cluster per group, edges
/// directed from the side solved first to the side that receives the DOF (undirected inside
/// a group), driven joints bold, levels from top to bottom.
pub fn structure(m: &Mechanism, a: &Analysis) -> String {
    let mut out = String::new();
    let note = closure_note(a.geometry.as_ref().and_then(|g| g.closure.as_ref()));
    header(
        &mut out,
        &format!("{}: structural graph", m.name),
        "TB",
        note,
    );
    let (over, under) = troubled(a);
    // Body id -> group index; the frame and unsolved bodies have none.
    let mut group_of: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, g) in a.groups.iter().enumerate() {
        for b in &g.bodies {
            group_of.insert(b.as_str(), i);
        }
    }
    let ids: Vec<String> = m.bodies.iter().map(|b| b.id.to_string()).collect();
    let body_attrs = |i: usize| -> String {
        let id = ids[i].as_str();
        let fill = if i == m.frame {
            "#dddddd"
        } else if over.contains(id) {
            OVER_COLOUR
        } else if under.contains(id) {
            UNDER_COLOUR
        } else {
            "white"
        };
        let shape = if i == m.frame { "box" } else { "circle" };
        format!(
            "label={}, shape={shape}, style=filled, fillcolor={}",
            quote(id),
            quote(fill)
        )
    };
    let _ = writeln!(out, "  {} [{}];", body_node(m.frame), body_attrs(m.frame));
    // The bodies of each group in body order, in one pass (not one pass per group).
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); a.groups.len()];
    for (i, id) in ids.iter().enumerate() {
        if let Some(&gi) = group_of.get(id.as_str()) {
            members[gi].push(i);
        }
    }
    for (gi, g) in a.groups.iter().enumerate() {
        let _ = writeln!(out, "  subgraph cluster_{gi} {{");
        let _ = writeln!(
            out,
            "    label={}; style=dashed;",
            quote(&format!("{} (level {}) {}", g.name, g.level, g.kind))
        );
        for &i in &members[gi] {
            let _ = writeln!(out, "    {} [{}];", body_node(i), body_attrs(i));
        }
        out.push_str("  }\n");
    }
    for (i, id) in ids.iter().enumerate() {
        if i != m.frame && !group_of.contains_key(id.as_str()) {
            let _ = writeln!(out, "  {} [{}];", body_node(i), body_attrs(i));
        }
    }
    // Solve order of a body: 0 for the frame, group level otherwise, unsolved last.
    let order = |i: usize| -> (usize, usize) {
        if i == m.frame {
            return (0, 0);
        }
        match group_of.get(ids[i].as_str()) {
            Some(&g) => (a.groups[g].level, g + 1),
            None => (usize::MAX, usize::MAX),
        }
    };
    for j in &m.joints {
        let hub = j.bodies[0];
        let label = quote(&format!("{} {}", short_id(&j.id), j.kind.code()));
        for &other in &j.bodies[1..] {
            let (x, y) = if order(hub) <= order(other) {
                (hub, other)
            } else {
                (other, hub)
            };
            let same = order(x).1 == order(y).1;
            let mut attrs = vec![format!("label={label}")];
            if same {
                attrs.push("dir=none".into());
            }
            if j.driven > 0 {
                attrs.push(format!(
                    "style=bold, penwidth=2.5, xlabel={}",
                    quote(&format!("driven {}", j.driven))
                ));
            }
            let _ = writeln!(
                out,
                "  {} -> {} [{}];",
                body_node(x),
                body_node(y),
                attrs.join(", ")
            );
        }
    }
    legend(&mut out, a, !over.is_empty(), !under.is_empty());
    out.push_str("}\n");
    out
}

/// A joint id for an edge label: ids of more than 60 characters (the default id of a joint
/// shared by thousands of bodies lists them all) keep their first and last 28, so that a view
/// drawing one edge per pair stays linear in size.
fn short_id(id: &str) -> String {
    let n = id.chars().count();
    if n <= 60 {
        return id.to_string();
    }
    let head: String = id.chars().take(28).collect();
    let tail: String = id.chars().skip(n - 28).collect();
    format!("{head}...{tail}")
}

/// A DOT string literal: `"..."` with `"` and `\` escaped and newlines as `\n`.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => {}
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Graph header shared by all views; `note` (the closure line) goes under the title.
pub(crate) fn header(out: &mut String, name: &str, rankdir: &str, note: Option<String>) {
    let _ = writeln!(out, "digraph {} {{", quote(name));
    let label = match note {
        Some(n) => format!("{name}\n{n}"),
        None => name.to_string(),
    };
    let _ = writeln!(
        out,
        "  graph [rankdir={rankdir}, newrank=true, fontname=\"Helvetica\", label={}, labelloc=t];",
        quote(&label)
    );
    let _ = writeln!(out, "  node [fontname=\"Helvetica\", fontsize=11];");
    let _ = writeln!(out, "  edge [fontname=\"Helvetica\", fontsize=9];");
}

/// One joint of the topology-like views: an edge for a binary joint, a small hub node with an
/// edge to each body for a multiple joint. `attrs` is empty or starts with `, `.
fn draw_joint(out: &mut String, ji: usize, bodies: &[usize], label: &str, attrs: &str) {
    if let [a, b] = bodies {
        let _ = writeln!(
            out,
            "  {} -> {} [label={}{attrs}];",
            body_node(*a),
            body_node(*b),
            quote(label)
        );
        return;
    }
    let hub = format!("j{ji}");
    let _ = writeln!(
        out,
        "  {hub} [xlabel={}, label=\"\", shape=point, width=0.12, fontsize=8{attrs}];",
        quote(label)
    );
    for &b in bodies {
        let _ = writeln!(
            out,
            "  {hub} -> {} [{}];",
            body_node(b),
            attrs.trim_start_matches(", ")
        );
    }
}

/// Node name of body `i` (stable, independent of the id's spelling).
pub(crate) fn body_node(i: usize) -> String {
    format!("b{i}")
}

/// The topological graph: bodies as nodes (the frame as a grey box), one edge per binary
/// pair labelled with the joint id and type, driven joints bold with their driven DOF, and a
/// small hub node for each multiple joint.
pub fn topology(m: &Mechanism) -> String {
    topology_titled(m, None)
}

/// [`topology`] with a closure line under the title ([`closure_note`]).
fn topology_titled(m: &Mechanism, note: Option<String>) -> String {
    let mut out = String::new();
    header(&mut out, &format!("{}: topology", m.name), "TB", note);
    let _ = writeln!(out, "  edge [dir=none];");
    for (i, b) in m.bodies.iter().enumerate() {
        let label = match &b.label {
            Some(l) => format!("{}\n{}", b.id, l),
            None => b.id.to_string(),
        };
        if i == m.frame {
            let _ = writeln!(
                out,
                "  {} [label={}, shape=box, style=filled, fillcolor=\"#dddddd\"];",
                body_node(i),
                quote(&format!("{label}\n(frame)"))
            );
        } else {
            let _ = writeln!(
                out,
                "  {} [label={}, shape=ellipse];",
                body_node(i),
                quote(&label)
            );
        }
    }
    for (ji, j) in m.joints.iter().enumerate() {
        let mut label = format!("{} {}", j.id, j.kind.code());
        if j.driven > 0 {
            label.push_str(&format!("\ndriven {}", j.driven));
        }
        let style = if j.driven > 0 {
            ", style=bold, penwidth=2.5"
        } else {
            ""
        };
        draw_joint(&mut out, ji, &j.bodies, &label, style);
    }
    out.push_str("}\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotes_everything_dangerous() {
        assert_eq!(quote("a b"), "\"a b\"");
        assert_eq!(quote("say \"hi\""), "\"say \\\"hi\\\"\"");
        assert_eq!(quote("back\\slash"), "\"back\\\\slash\"");
        assert_eq!(quote("two\nlines"), "\"two\\nlines\"");
        assert_eq!(quote("rotor ü"), "\"rotor ü\"");
    }
}
