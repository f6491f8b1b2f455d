//! Reading mechanism files (TOML, YAML, JSON) into a validated [`crate::Mechanism`], with located diagnostics.
//!
//! The three formats are parsed into one spanned value tree, then converted to the model by
//! hand, so that every error points at the exact key or value (`docs/format.md` is the user
//! reference of format v1). [`load`] takes text; [`load_bytes`] also checks size and UTF-8.

mod error;
mod fast_toml;
mod fast_yaml;
mod model;
mod read;
mod schema;
mod tree;

pub use error::{ErrorKind, LoadError};
/// Decimal digits of an integer, as `Display` writes them (body ids, by the million).
pub(crate) use model::push_int;
pub use schema::schema;

use crate::budget::Budget;
use crate::mechanism::Mechanism;
use error::Label;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// Largest input accepted by default, in bytes ([`crate::budget::Budget::DEFAULT`]).
pub const MAX_INPUT_BYTES: usize = crate::budget::Budget::DEFAULT.max_input_bytes as usize;

/// An input format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Format {
    /// TOML (`.toml`).
    Toml,
    /// YAML 1.2 (`.yaml`, `.yml`).
    Yaml,
    /// JSON (`.json`).
    Json,
}

impl Format {
    /// The format named by a file's extension (case-insensitive), if known.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "toml" => Some(Format::Toml),
            "yaml" | "yml" => Some(Format::Yaml),
            "json" => Some(Format::Json),
            _ => None,
        }
    }

    /// Guess the format of unnamed text (standard input). JSON if the first significant
    /// character is `{` and the text is JSON (or looks like a JSON object: `{"` or `{}`);
    /// TOML if it parses as TOML with at least one key, or if a line looks like a TOML
    /// assignment (`key = ...`) or table header (`[joint]`, `[[joint]]`); YAML otherwise.
    pub fn sniff(text: &str) -> Format {
        let significant = text
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#') && !l.starts_with("//"))
            .unwrap_or("");
        if significant.starts_with('{') {
            // `significant` is a slice of `text`: look past the brace, across lines.
            let at = significant.as_ptr() as usize - text.as_ptr() as usize;
            let rest = text.get(at + 1..).unwrap_or("");
            let looks_json = rest.trim_start().starts_with(['"', '}']);
            if looks_json || serde_json::from_str::<serde::de::IgnoredAny>(text).is_ok() {
                return Format::Json;
            }
            return Format::Yaml;
        }
        if let Ok(t) = toml::de::DeTable::parse(text)
            && !t.get_ref().is_empty()
        {
            return Format::Toml;
        }
        let tomlish = text.lines().map(str::trim).any(|l| {
            let header = l.starts_with('[')
                && l.trim_end_matches(|c: char| c != ']').ends_with(']')
                && !l.contains(',')
                && !l.contains(": ");
            let assignment = l.split_once('=').is_some_and(|(k, _)| {
                let k = k.trim();
                !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '.' | '"'))
            }) && !l.contains(": ");
            header || assignment
        });
        if tomlish { Format::Toml } else { Format::Yaml }
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Format::Toml => "TOML",
            Format::Yaml => "YAML",
            Format::Json => "JSON",
        }
    }
}

/// Read a mechanism from text. `source_name` (a path, `<stdin>`, ...) names the file in
/// diagnostics and gives the default `name` (its file stem). Text over the default input
/// limit ([`MAX_INPUT_BYTES`]) is refused.
pub fn load(source_name: &str, text: &str, format: Format) -> Result<Mechanism, LoadError> {
    if text.len() > MAX_INPUT_BYTES {
        return Err(too_large(text.len() as u64, &Budget::DEFAULT).with_source(source_name, ""));
    }
    load_inner(source_name, text, format).map_err(|e| e.with_source(source_name, text))
}

/// Read a mechanism from raw bytes: like [`load`], after checking the size limit
/// ([`MAX_INPUT_BYTES`]) and that the bytes are UTF-8 (a leading byte-order mark is skipped).
pub fn load_bytes(source_name: &str, bytes: &[u8], format: Format) -> Result<Mechanism, LoadError> {
    load_bytes_within(source_name, bytes, format, &Budget::DEFAULT)
}

/// [`load_bytes`] with the input limit of `budget` instead of the default.
pub fn load_bytes_within(
    source_name: &str,
    bytes: &[u8],
    format: Format,
    budget: &Budget,
) -> Result<Mechanism, LoadError> {
    if bytes.len() as u64 > budget.max_input_bytes {
        return Err(too_large(bytes.len() as u64, budget).with_source(source_name, ""));
    }
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(text) => {
            load_inner(source_name, text, format).map_err(|e| e.with_source(source_name, text))
        }
        Err(e) => {
            let valid = e.valid_up_to();
            // Show the text with the bad bytes replaced (U+FFFD, same offsets before them).
            let shown = String::from_utf8_lossy(bytes);
            Err(LoadError::new(
                ErrorKind::NotUtf8,
                format!(
                    "not UTF-8 text: invalid byte 0x{:02X} at offset {valid}",
                    bytes[valid]
                ),
                vec![Label {
                    span: valid..valid + '\u{FFFD}'.len_utf8(),
                    text: "invalid byte".into(),
                }],
                Some("mechanism files are TOML, YAML or JSON text in UTF-8".into()),
            )
            .with_source(source_name, &shown))
        }
    }
}

fn too_large(len: u64, budget: &Budget) -> LoadError {
    let e = budget
        .check_input(len, || "the file".to_string())
        .err()
        .unwrap_or(crate::budget::BudgetExceeded {
            limit: crate::budget::Limit::InputBytes,
            what: "the file".into(),
            needed: len,
            at_least: false,
            allowed: budget.max_input_bytes,
        });
    LoadError::new(
        ErrorKind::TooLarge,
        e.to_string(),
        Vec::new(),
        Some(e.help()),
    )
}

fn load_inner(source_name: &str, text: &str, format: Format) -> Result<Mechanism, LoadError> {
    if text.trim().is_empty() {
        return Err(model::empty_document());
    }
    let name = default_name(source_name);
    match format {
        Format::Toml => {
            // The common shapes in one pass (`fast_toml`); anything it does not read, and any
            // error, read again by the toml crate below, which finds and locates every error.
            if let Some((root, joints)) = fast_toml::parse(text) {
                let lazy = if joints.count == 0 {
                    read::Lazy::None
                } else {
                    read::Lazy::TomlLines { text, joints }
                };
                if let Ok(m) = model::build(root, &name, lazy) {
                    return Ok(m);
                }
            }
            // Large files: the joints read a piece at a time (see `read::parse_toml_lazy`);
            // anything that way cannot join is read again whole.
            let fallback = AtomicBool::new(false);
            if let Some((root, lazy)) = read::parse_toml_lazy(text, &fallback) {
                let built = model::build(root, &name, lazy);
                if !fallback.load(Ordering::Relaxed) {
                    return built;
                }
            }
            model::build(read::parse_toml(text)?, &name, read::Lazy::None)
        }
        Format::Yaml => {
            // The joint list last, its items in the common shapes (`fast_yaml`): the head read
            // by saphyr, the items by hand. Anything else, and any error, read again below.
            if let Some((root, lazy)) = read::parse_yaml_fast(text)
                && let Ok(m) = model::build(root, &name, lazy)
            {
                return Ok(m);
            }
            // The joint list last (the common case): one read, the joints one at a time.
            if let Some((root, lazy)) = read::parse_yaml_resume(text)
                && let Ok(m) = model::build(root, &name, lazy)
            {
                return Ok(m);
            }
            match read::parse_yaml_lazy(text) {
                // Otherwise the joints read one at a time from a second read of the text. Any
                // error: found again by the whole read, in the order it finds them.
                Ok(Some(root))
                    if matches!(&root.value, tree::Value::Map(es)
                        if es.iter().any(|e| matches!(e.value.value, tree::Value::Deferred))) =>
                {
                    match model::build(root, &name, read::Lazy::Yaml { text }) {
                        Ok(m) => Ok(m),
                        Err(_) => yaml_whole(text, &name),
                    }
                }
                _ => yaml_whole(text, &name),
            }
        }
        Format::Json => {
            // The joint list last (the common case): one pass, the joints one at a time.
            // Anything else, and any error, read again below (errors found and located there).
            if let Some((root, lazy)) = read::parse_json_resume(text)
                && let Ok(m) = model::build(root, &name, lazy)
            {
                return Ok(m);
            }
            // One pass: the tree parser refuses whatever serde_json refuses; after an error,
            // serde_json's check reports its own first (as when it ran before the tree).
            read::parse_json_tree(text)
                .and_then(|(root, lazy)| model::build(root, &name, lazy))
                .map_err(|e| read::json_check(text).err().unwrap_or(e))
        }
    }
}

/// YAML read whole (one tree), as before the lazy read.
fn yaml_whole(text: &str, name: &str) -> Result<Mechanism, LoadError> {
    match read::parse_yaml(text)? {
        Some(root) => model::build(root, name, read::Lazy::None),
        None => Err(model::empty_document()),
    }
}

/// The file stem of a source name (`mechanisms/four-bar.toml` -> `four-bar`).
fn default_name(source_name: &str) -> String {
    Path::new(source_name)
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty())
        .unwrap_or(source_name)
        .to_string()
}

#[cfg(test)]
mod tests;

/// Mutated copies of `base` for the reader's tests: `count` texts, each with 1 to
/// `max_edits` random one-byte edits (replace, insert or remove, from `alphabet`), drawn by
/// a xorshift stream from `seed`; texts that are not UTF-8 are skipped.
#[cfg(test)]
pub(crate) fn mutated_texts(
    base: &str,
    alphabet: &[u8],
    seed: u64,
    count: usize,
    max_edits: u64,
) -> Vec<String> {
    let mut state = seed;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut out = Vec::new();
    for _ in 0..count {
        let mut bytes = base.as_bytes().to_vec();
        for _ in 0..1 + next() % max_edits {
            let at = (next() % bytes.len() as u64) as usize;
            let c = alphabet[(next() % alphabet.len() as u64) as usize];
            match next() % 3 {
                0 => bytes[at] = c,
                1 => bytes.insert(at, c),
                _ => {
                    bytes.remove(at);
                }
            }
        }
        if let Ok(text) = String::from_utf8(bytes) {
            out.push(text);
        }
    }
    out
}
