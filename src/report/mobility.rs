//! The mobility report as a table for people.

use crate::mobility::{MobilityReport, Verdict};
use std::fmt::Write;

/// Render the mobility report. `file_geometry` says the file gives every joint its geometry:
/// the count then may not be the mechanism's mobility, and the verdict points to the commands
/// that decide it at the file's configuration.
pub fn table(r: &MobilityReport, file_geometry: bool) -> String {
    let mut t = super::new_table();
    t.set_header(vec!["quantity", "value", "meaning"]);
    let rows: Vec<[String; 3]> = vec![
        [
            "space".into(),
            format!("{} (B = {})", r.space, r.b),
            "DOF of a free body".into(),
        ],
        [
            "bodies".into(),
            format!("{} ({} movable)", r.bodies, r.movable),
            "the frame included".into(),
        ],
        [
            "joints".into(),
            format!("{} ({} pairs)", r.joints, r.pairs),
            "a multiple joint of n bodies is n - 1 pairs".into(),
        ],
        [
            "constraints".into(),
            r.constraints.to_string(),
            "sum over pairs of (B - grade)".into(),
        ],
        [
            "loops".into(),
            r.loops.to_string(),
            "independent loops: pairs - bodies + components".into(),
        ],
        [
            "mobility".into(),
            r.mobility.count.to_string(),
            format!(
                "B·Nm - constraints = {}·{} - {}",
                r.b, r.movable, r.constraints
            ),
        ],
        [
            "inputs".into(),
            r.mobility.inputs.to_string(),
            "driven DOF".into(),
        ],
    ];
    for row in rows {
        t.add_row(row.to_vec());
    }
    let mut out = String::new();
    // Every line here is the count (topology only): worded so, since the joint geometry can
    // make the true mobility larger (`rigid`, `analyze`).
    let _ = writeln!(
        out,
        "{}: mobility {} by the count",
        r.name, r.mobility.count
    );
    let _ = writeln!(out, "{t}");
    let verdict = match r.mobility.verdict {
        Verdict::Equal => format!(
            "inputs = count ({}): enough to determine the mechanism if the geometry is generic (`mbsa analyze` checks where they are, at the geometry)",
            r.mobility.count
        ),
        Verdict::Fewer => format!(
            "fewer inputs ({}) than the count ({}): {} DOF not driven",
            r.mobility.inputs,
            r.mobility.count,
            r.mobility.count - r.mobility.inputs as i64
        ),
        Verdict::More => format!(
            "more inputs ({}) than the count ({}): they over-determine the mechanism if the geometry is generic",
            r.mobility.inputs, r.mobility.count
        ),
    };
    let _ = writeln!(out, "count verdict: {verdict}");
    // The count ignores geometry; with the file's geometry at hand, say where the true
    // mobility comes from rather than let the count's verdict stand for the mechanism.
    if file_geometry {
        let _ = writeln!(
            out,
            "note: the count ignores the joint geometry written in the file; special geometry \
             (parallel or concurrent axes, a planar or spherical loop written in space) can make \
             the true mobility larger: `mbsa rigid` gives it at the file's configuration and \
             `mbsa analyze` checks the inputs there"
        );
    }
    if !r.disconnected.is_empty() {
        let _ = writeln!(
            out,
            "warning: {} bod{} not linked to the frame: {}",
            r.disconnected.len(),
            if r.disconnected.len() == 1 {
                "y"
            } else {
                "ies"
            },
            r.disconnected.join(", ")
        );
    }
    out
}
