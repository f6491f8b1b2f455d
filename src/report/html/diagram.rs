//! The structural diagram as SVG: the frame on top, one row per solve level, the over- and
//! under-determined parts in a last row, edges from each group to the groups that depend on
//! it. Positions are computed here: in a row, nodes are ordered by the mean position of the
//! nodes they depend on (ties by canonical order), so the layout is deterministic.

use super::{Named, esc, px};
use crate::structure::Analysis;
use std::fmt::Write;

const W: f64 = 170.0;
const H: f64 = 54.0;
const GAP_X: f64 = 24.0;
const GAP_Y: f64 = 46.0;
const MARGIN: f64 = 16.0;

/// One node of the layout.
struct Node {
    id: String,
    class: String,
    lines: [String; 3],
    title: String,
    row: usize,
    x: f64,
}

/// Cut a label to `n` characters, with an ellipsis.
fn cut(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        let t: String = s.chars().take(n - 1).collect();
        format!("{t}…")
    }
}

/// The nodes: frame, groups, the diagnosis's parts.
fn nodes(a: &Analysis, named: &Named) -> Vec<Node> {
    let mut v = vec![Node {
        id: "frame".into(),
        class: "frame".into(),
        lines: ["0".into(), "frame".into(), String::new()],
        title: "the frame".into(),
        row: 0,
        x: 0.0,
    }];
    for (i, g) in a.groups.iter().enumerate() {
        let mut class = vec!["group"];
        if g.bodies.iter().any(|b| named.over_bodies.contains(b)) {
            class.push("over");
        }
        if g.bodies.iter().any(|b| named.under_bodies.contains(b)) {
            class.push("under");
        }
        if !g.in_library {
            class.push("uncovered");
        }
        v.push(Node {
            id: format!("g{i}"),
            class: class.join(" "),
            lines: [
                g.name.clone(),
                cut(&format!("{{{}}}", g.bodies.join(",")), 22),
                format!("({}, {}) {}", g.nm, g.inputs, cut(&g.kind, 16)),
            ],
            title: format!("{} {{{}}} type {}", g.name, g.bodies.join(","), g.kind),
            row: g.level,
            x: 0.0,
        });
    }
    let last = a.groups.iter().map(|g| g.level).max().unwrap_or(0) + 1;
    for (name, class, bodies, joints) in [
        (
            "over-determined",
            "part over",
            &named.over_bodies,
            &named.over_joints,
        ),
        (
            "under-determined",
            "part under",
            &named.under_bodies,
            &named.under_joints,
        ),
    ] {
        if bodies.is_empty() {
            continue;
        }
        let b: Vec<&str> = bodies.iter().map(String::as_str).collect();
        let j: Vec<&str> = joints.iter().map(String::as_str).collect();
        v.push(Node {
            id: name.into(),
            class: class.into(),
            lines: [
                name.into(),
                cut(&format!("{{{}}}", b.join(",")), 22),
                cut(&format!("joints {}", j.join(",")), 22),
            ],
            title: format!(
                "{name} part: bodies {}; joints named: {}",
                b.join(", "),
                j.join(", ")
            ),
            row: last,
            x: 0.0,
        });
    }
    v
}

/// Place the nodes row by row; returns the width of the widest row.
fn place(v: &mut [Node], parents: &[Vec<usize>]) -> f64 {
    let rows = v.iter().map(|n| n.row).max().unwrap_or(0) + 1;
    let mut widest: f64 = 0.0;
    let mut placed: Vec<Vec<usize>> = vec![Vec::new(); rows];
    for (r, row) in placed.iter_mut().enumerate() {
        let mut members: Vec<(f64, usize)> = (0..v.len())
            .filter(|&i| v[i].row == r)
            .map(|i| {
                let p = &parents[i];
                let key = if p.is_empty() {
                    f64::INFINITY
                } else {
                    p.iter().map(|&k| v[k].x).sum::<f64>() / p.len() as f64
                };
                (key, i)
            })
            .collect();
        members.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (k, &(_, i)) in members.iter().enumerate() {
            v[i].x = k as f64 * (W + GAP_X);
        }
        widest = widest.max(members.len() as f64 * (W + GAP_X) - GAP_X);
        *row = members.into_iter().map(|(_, i)| i).collect();
    }
    // Centre each row under the widest.
    for row in &placed {
        let w = row.len() as f64 * (W + GAP_X) - GAP_X;
        for &i in row {
            v[i].x += (widest - w) / 2.0 + MARGIN;
        }
    }
    widest
}

/// Write the diagram.
pub(super) fn svg(out: &mut String, a: &Analysis) {
    let named = Named::of(a);
    let mut v = nodes(a, &named);
    // Parents by node index: the frame is 0, group i is i + 1.
    let mut parents: Vec<Vec<usize>> = vec![Vec::new(); v.len()];
    for (i, g) in a.groups.iter().enumerate() {
        parents[i + 1] = if g.depends_on.is_empty() {
            vec![0]
        } else {
            g.depends_on.iter().map(|&d| d + 1).collect()
        };
    }
    let widest = place(&mut v, &parents);
    let rows = v.iter().map(|n| n.row).max().unwrap_or(0) + 1;
    let width = widest + 2.0 * MARGIN;
    let height = rows as f64 * (H + GAP_Y) - GAP_Y + 2.0 * MARGIN;
    let y = |row: usize| MARGIN + row as f64 * (H + GAP_Y);
    let _ = writeln!(
        out,
        "<svg id=\"diagram\" class=\"view\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {} {}\" width=\"{}\" data-groups=\"{}\">",
        px(width),
        px(height),
        px(width.min(1100.0)),
        a.groups.len()
    );
    out.push_str("<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"10\" refY=\"5\" markerWidth=\"7\" markerHeight=\"7\" orient=\"auto-start-reverse\"><path d=\"M0,0L10,5L0,10z\" fill=\"#555\"/></marker></defs>\n");
    for (i, p) in parents.iter().enumerate() {
        for &k in p {
            let (x1, y1) = (v[k].x + W / 2.0, y(v[k].row) + H);
            let (x2, y2) = (v[i].x + W / 2.0, y(v[i].row));
            let _ = writeln!(
                out,
                "<line class=\"edge\" data-from=\"{}\" data-to=\"{}\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" marker-end=\"url(#arrow)\"/>",
                v[k].id,
                v[i].id,
                px(x1),
                px(y1),
                px(x2),
                px(y2)
            );
        }
    }
    for n in &v {
        let top = y(n.row);
        let _ = writeln!(
            out,
            "<g id=\"{}\" class=\"{}\"><title>{}</title><rect x=\"{}\" y=\"{}\" width=\"{W}\" height=\"{H}\" rx=\"10\"/>",
            esc(&n.id),
            n.class,
            esc(&n.title),
            px(n.x),
            px(top)
        );
        for (k, line) in n.lines.iter().enumerate() {
            if line.is_empty() {
                continue;
            }
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\"{}>{}</text>",
                px(n.x + W / 2.0),
                px(top + 16.0 + 15.0 * k as f64),
                if k == 0 { " class=\"name\"" } else { "" },
                esc(line)
            );
        }
        out.push_str("</g>\n");
    }
    out.push_str("</svg>\n");
    legend(out, a, &named);
}

fn legend(out: &mut String, a: &Analysis, named: &Named) {
    let mut items = Vec::new();
    if !named.over_bodies.is_empty() {
        items.push("<span class=\"key over\"></span> over-determined part");
    }
    if !named.under_bodies.is_empty() {
        items.push("<span class=\"key under\"></span> under-determined part");
    }
    if a.groups.iter().any(|g| !g.in_library) {
        items.push("<span class=\"key uncovered\"></span> type not in the library");
    }
    if !items.is_empty() {
        let _ = writeln!(out, "<p class=\"legend\">{}</p>", items.join(" &nbsp; "));
    }
}
