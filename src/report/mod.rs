//! Rendering of analysis results as tables, JSON and Graphviz DOT. Works from the serializable
//! library types only; nothing here analyses.

pub mod mobility;

use comfy_table::{Table, presets};

/// A table with the project's plain style: UTF-8 rules, no colour, no terminal detection, so
/// the same result renders to the same bytes everywhere.
pub fn new_table() -> Table {
    let mut t = Table::new();
    t.load_style(presets::UTF8_HORIZONTAL_ONLY)
        .set_content_arrangement(comfy_table::ContentArrangement::Disabled);
    t
}

/// Pretty JSON with a trailing newline, for `--format json`.
pub fn json<T: serde::Serialize>(value: &T) -> String {
    let mut s = serde_json::to_string_pretty(value).unwrap_or_else(|e| {
        // Serializing our own types cannot fail (no maps with non-string keys, no I/O).
        format!("{{\"error\": {:?}}}", e.to_string())
    });
    s.push('\n');
    s
}
