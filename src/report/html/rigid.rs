//! The rigid parts of the geometric analysis (`mbsa rigid`): one box per rigid part with its
//! bodies, the bodies that belong to none alone, bodies with an isolated freedom outlined,
//! and a table of the counts and the joints carrying redundant constraints.

use super::{esc, px};
use crate::mechanism::Mechanism;
use crate::rigidity::geometric::GeometricReport;
use std::collections::BTreeSet;
use std::fmt::Write;

const CHIP_W: f64 = 120.0;
const CHIP_H: f64 = 22.0;
const PAD: f64 = 8.0;
const PER_ROW: usize = 3;
const MAX_W: f64 = 1060.0;

/// A box: its title, class and bodies.
struct Part {
    title: String,
    class: &'static str,
    bodies: Vec<String>,
}

fn parts(m: &Mechanism, r: &GeometricReport) -> Vec<Part> {
    let mut listed: BTreeSet<&str> = BTreeSet::new();
    let mut v = Vec::new();
    for (i, c) in r.rigid.iter().enumerate() {
        listed.extend(c.bodies.iter().map(String::as_str));
        v.push(Part {
            title: if c.frame {
                format!("rigid part {} (with the frame)", i + 1)
            } else {
                format!("rigid part {}", i + 1)
            },
            class: if c.frame { "part framed" } else { "part" },
            bodies: c.bodies.clone(),
        });
    }
    for b in &m.bodies {
        let id = b.id.to_string();
        if !listed.contains(id.as_str()) {
            v.push(Part {
                title: "alone".into(),
                class: "part alone",
                bodies: vec![id],
            });
        }
    }
    v
}

/// Write the view: the SVG, its legend and the table.
pub(super) fn view(out: &mut String, m: &Mechanism, r: &GeometricReport) {
    let isolated: BTreeSet<&str> = r
        .isolated_motions
        .iter()
        .flat_map(|i| i.bodies.iter().map(String::as_str))
        .collect();
    let frame = m.body_id(m.frame).to_string();
    let ps = parts(m, r);
    // Flow layout: boxes left to right, wrapped at MAX_W.
    let (mut x, mut y, mut row_h, mut width) = (PAD, PAD, 0.0f64, 0.0f64);
    let mut boxes = Vec::new();
    for p in &ps {
        let cols = p.bodies.len().clamp(1, PER_ROW);
        let rows = p.bodies.len().div_ceil(PER_ROW).max(1);
        let w = cols as f64 * (CHIP_W + PAD) + PAD;
        let h = rows as f64 * (CHIP_H + PAD) + PAD + 18.0;
        if x + w > MAX_W && x > PAD {
            x = PAD;
            y += row_h + PAD;
            row_h = 0.0;
        }
        boxes.push((x, y, w, h));
        x += w + PAD;
        row_h = row_h.max(h);
        width = width.max(x);
    }
    let height = y + row_h + PAD;
    let _ = writeln!(
        out,
        "<svg id=\"rigid\" class=\"view\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {} {}\" width=\"{}\" data-parts=\"{}\">",
        px(width),
        px(height),
        px(width),
        r.rigid.len()
    );
    for (p, &(bx, by, w, h)) in ps.iter().zip(&boxes) {
        let _ = writeln!(
            out,
            "<g class=\"{}\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" rx=\"8\"/><text class=\"ptitle\" x=\"{}\" y=\"{}\">{}</text>",
            p.class,
            px(bx),
            px(by),
            px(w),
            px(h),
            px(bx + PAD),
            px(by + 14.0),
            esc(&p.title)
        );
        for (k, b) in p.bodies.iter().enumerate() {
            let cx = bx + PAD + (k % PER_ROW) as f64 * (CHIP_W + PAD);
            let cy = by + 18.0 + PAD + (k / PER_ROW) as f64 * (CHIP_H + PAD);
            let mut class = vec!["body"];
            if *b == frame {
                class.push("frame");
            }
            if isolated.contains(b.as_str()) {
                class.push("isolated");
            }
            let short: String = if b.chars().count() > 16 {
                b.chars().take(15).chain(['…']).collect()
            } else {
                b.clone()
            };
            let _ = writeln!(
                out,
                "<g class=\"{}\" data-body=\"{}\"><title>{}</title><rect x=\"{}\" y=\"{}\" width=\"{CHIP_W}\" height=\"{CHIP_H}\" rx=\"11\"/><text x=\"{}\" y=\"{}\">{}</text></g>",
                class.join(" "),
                esc(b),
                esc(b),
                px(cx),
                px(cy),
                px(cx + CHIP_W / 2.0),
                px(cy + 15.0),
                esc(&short)
            );
        }
        out.push_str("</g>\n");
    }
    out.push_str("</svg>\n<p class=\"legend\"><span class=\"key framed\"></span> rigid with the frame &nbsp; <span class=\"key isolated\"></span> body with an isolated freedom</p>\n");
    table(out, r);
}

fn table(out: &mut String, r: &GeometricReport) {
    let weights: Vec<String> = r
        .redundant_joints
        .iter()
        .map(|w| format!("{} ({:.2})", w.joint, w.weight))
        .chain(r.redundant_joints_unweighted.iter().cloned())
        .collect();
    let isolated: Vec<String> = r
        .isolated_motions
        .iter()
        .map(|i| format!("{} {} ({})", i.kind, i.bodies.join(", "), i.dof))
        .collect();
    let dash = |v: &[String]| {
        if v.is_empty() {
            "-".to_string()
        } else {
            esc(&v.join(", "))
        }
    };
    let _ = writeln!(
        out,
        "<table class=\"summary\">\n<tr><th>geometry</th><td>{}</td></tr>\n<tr><th>count, true mobility</th><td>{}, {}</td></tr>\n<tr><th>isolated, proper</th><td>{}, {}</td></tr>\n<tr><th>isolated motions</th><td>{}</td></tr>\n<tr><th>redundant constraints</th><td>{}</td></tr>\n<tr><th>joints involved (weight)</th><td>{}</td></tr>\n</table>",
        esc(&r.geometry),
        r.count,
        r.mobility,
        r.isolated,
        r.proper_mobility,
        dash(&isolated),
        r.redundant,
        dash(&weights)
    );
}
