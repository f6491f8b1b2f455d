//! The bundled mechanism library (`mechanisms/*.toml`), embedded at build time.

include!(concat!(env!("OUT_DIR"), "/examples.rs"));

/// The TOML text of a bundled mechanism by name (`rotor`, `stewart-ik`, ...).
pub fn find(name: &str) -> Option<(&'static str, &'static str)> {
    EXAMPLES
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, file, text)| (*file, *text))
}

/// Names of all bundled mechanisms, sorted.
pub fn names() -> impl Iterator<Item = &'static str> {
    EXAMPLES.iter().map(|(n, _, _)| *n)
}

/// One line about a bundled file: its `name`, then the first line of its header comment when
/// that is a sentence about the mechanism (not a source reference).
pub fn summary(text: &str) -> String {
    let value = |key: &str| {
        text.lines()
            .find_map(|l| l.trim().strip_prefix(key)?.trim_start().strip_prefix('='))
            .map(|v| v.trim().trim_matches('"').to_string())
    };
    let name = value("name").unwrap_or_default();
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with('#') && l.trim_start_matches('#').trim().len() > 1)
        .map(|l| l.trim_start_matches('#').trim())
        .unwrap_or("");
    if first.is_empty() || first.starts_with("Source") || !first.ends_with('.') {
        name
    } else {
        first.to_string()
    }
}
