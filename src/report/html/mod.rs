//! `mbsa report`: one self-contained HTML page (no network, no external script or style) of a
//! mechanism's analyses: the summary, the group table, the structural diagram and the rigid
//! parts as inline SVG laid out here, and the mechanism drawn from its joint geometry,
//! animated through a sweep of one input. The same inputs give the same bytes.
//!
//! - [`page`]: the page and its tables (`tables`).
//! - `diagram`: the layered layout of the structural diagram.
//! - `rigid`: the rigid parts.
//! - `drawing`: the mechanism projected onto a plane, one frame per sweep step.
//! - `script`: the small inline script (slider, play button, error report).

mod diagram;
mod drawing;
mod rigid;
mod script;
mod tables;

use crate::mechanism::Mechanism;
use crate::position::sweep::SweepReport;
use crate::rigidity::geometric::GeometricReport;
use crate::structure::Analysis;
use std::fmt::Write;

/// What the mechanism view animates.
#[derive(Clone, Debug)]
pub enum Animation {
    /// A joint lacks the geometry the drawing needs.
    NoGeometry,
    /// No driven input and no joint the diagnosis offers for one.
    NoInput,
    /// The sweep could not start (the reason, in words).
    Failed {
        /// The joint that was to be swept.
        joint: String,
        /// Why.
        reason: String,
    },
    /// The sweep's steps, in the order they are played.
    Swept {
        /// The sweep (its steps possibly joined from two directions).
        sweep: SweepReport,
        /// How the swept joint was chosen and the range, in words.
        note: String,
    },
}

/// Everything the page shows, gathered by the caller.
pub struct Inputs<'a> {
    /// The mechanism.
    pub mechanism: &'a Mechanism,
    /// Its structural analysis.
    pub analysis: &'a Analysis,
    /// The geometric rigidity analysis (inputs not counted), or why it is missing.
    pub rigid: Result<&'a GeometricReport, String>,
    /// The mechanism view.
    pub animation: Animation,
}

/// The HTML page.
pub fn page(r: &Inputs) -> String {
    let a = r.analysis;
    let mut out = String::with_capacity(1 << 16);
    let title = format!("{}: structural analysis", a.name);
    let _ = write!(
        out,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{}</style>\n<script>{}</script>\n</head>\n<body>\n<h1>{}</h1>\n",
        esc(&title),
        script::CSS,
        script::ON_ERROR,
        esc(&title)
    );
    tables::summary(&mut out, r);
    out.push_str("<h2>Structural groups</h2>\n");
    tables::groups(&mut out, a);
    out.push_str("<h2>Structural diagram</h2>\n");
    diagram::svg(&mut out, a);
    out.push_str("<h2>Rigid parts</h2>\n");
    match &r.rigid {
        Ok(g) => rigid::view(&mut out, r.mechanism, g),
        Err(e) => {
            let _ = writeln!(out, "<p class=\"none\">No rigid-parts view: {}</p>", esc(e));
        }
    }
    out.push_str("<h2>Mechanism</h2>\n");
    drawing::view(&mut out, r.mechanism, a, &r.animation);
    let _ = write!(out, "<script>{}</script>\n</body>\n</html>\n", script::MAIN);
    out
}

/// Escape text for HTML content and attribute values.
pub(crate) fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// A coordinate for SVG: one decimal, no `-0.0`.
pub(crate) fn px(x: f64) -> String {
    let s = format!("{x:.1}");
    if s == "-0.0" { "0.0".into() } else { s }
}

/// Bodies of the over- and under-determined parts and the joints the diagnosis names.
pub(crate) struct Named {
    pub over_bodies: std::collections::BTreeSet<String>,
    pub under_bodies: std::collections::BTreeSet<String>,
    pub over_joints: std::collections::BTreeSet<String>,
    pub under_joints: std::collections::BTreeSet<String>,
    pub redundant_joints: std::collections::BTreeSet<String>,
}

impl Named {
    pub(crate) fn of(a: &Analysis) -> Named {
        let mut n = Named {
            over_bodies: Default::default(),
            under_bodies: Default::default(),
            over_joints: Default::default(),
            under_joints: Default::default(),
            redundant_joints: Default::default(),
        };
        if let Some(d) = &a.diagnosis {
            if let Some(o) = &d.overdetermined {
                n.over_bodies.extend(o.bodies.iter().cloned());
                n.over_joints.extend(o.joints.iter().cloned());
            }
            if let Some(u) = &d.underdetermined {
                n.under_bodies.extend(u.bodies.iter().cloned());
                n.under_joints.extend(u.input_candidates.iter().cloned());
            }
        }
        for r in &a.redundant {
            n.redundant_joints.extend(r.joints.iter().cloned());
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_quotes() {
        assert_eq!(esc("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
        assert_eq!(px(-0.01), "0.0");
        assert_eq!(px(12.345), "12.3");
    }
}
