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

/// The first line of a bundled file's header comment, without the `#`.
pub fn summary(text: &str) -> &str {
    text.lines()
        .map(str::trim)
        .find(|l| l.starts_with('#') && l.trim_start_matches('#').trim().len() > 1)
        .map(|l| l.trim_start_matches('#').trim())
        .unwrap_or("")
}
