//! Rendering of analysis results as tables, JSON and Graphviz DOT. Works from the serializable
//! library types only; nothing here analyses.

pub mod cut;
pub mod dot;
pub mod html;
pub mod json;
pub mod mobility;
pub mod position;
pub mod repair;
pub mod rigid;
pub mod rigid_geometric;
pub mod rigid_pebble;
pub mod schema;
pub mod structure;
pub mod transform;

pub use json::{FORMAT_VERSION, Versioned, json};

use comfy_table::{LineStyle, Table, TableStyle};

/// Rules above, below and under the header only: compact and readable in a terminal or a file.
const STYLE: TableStyle = TableStyle::new()
    .top_border(LineStyle::none().fill('─').junction('─'))
    .header_separator(LineStyle::none().fill('─').junction('─'))
    .bottom_border(LineStyle::none().fill('─').junction('─'));

/// A table with the project's plain style: UTF-8 rules, no colour, no terminal detection, so
/// the same result renders to the same bytes everywhere.
pub fn new_table() -> Table {
    let mut t = Table::new();
    t.load_style(STYLE)
        .set_content_arrangement(comfy_table::ContentArrangement::Disabled);
    t
}

/// The `geometry:` line of table reports: which geometry the analysis used, how precisely the
/// file's numbers are known, and the closure of the file's configuration when it was checked.
pub fn geometry_line(g: &crate::geometry::GeometryUsed) -> String {
    let mut s = match g.seed {
        Some(seed) => format!("geometry: random (seed {seed}), {}", g.configuration),
        None => format!("geometry: file, {}", g.configuration),
    };
    if let Some(p) = g.precision.filter(|&p| p > 0.0) {
        s.push_str(&format!("; numbers known to ±{p:.0e}"));
    }
    if let Some(n) = &g.note {
        s.push_str(&format!(" ({n})"));
    }
    if let Some(c) = &g.closure {
        s.push('\n');
        s.push_str(&position::closure_lines(c));
    }
    s
}

/// The joint catalogue as a table (`mbsa joints`).
pub fn joints_table() -> String {
    let mut t = new_table();
    t.set_header(vec![
        "code",
        "long names",
        "grade k",
        "removes (3D)",
        "planar",
        "spherical",
        "geometry",
    ]);
    for i in crate::joint::CATALOGUE.iter() {
        let yes = |b: bool| if b { "yes" } else { "-" };
        t.add_row(vec![
            i.code.to_string(),
            i.names.join(", "),
            i.grade.to_string(),
            (6 - i.grade).to_string(),
            yes(i.planar).to_string(),
            yes(i.spherical).to_string(),
            if i.geometry.is_empty() {
                "count only".to_string()
            } else {
                i.geometry.join(", ")
            },
        ]);
    }
    format!(
        "{t}\nCodes and names are matched case-insensitively. A joint of grade k removes B - k DOF\n(B = 6 spatial, 3 planar or spherical); a multiple joint of n bodies counts as n - 1 pairs.\n"
    )
}
