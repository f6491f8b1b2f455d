//! JSON output: every report object starts with `format_version`, so scripts can tell which
//! layout they read (docs/json.md; `mbsa schema --output REPORT` prints each layout's schema).

use serde::Serialize;

/// The layout version of the JSON reports. Raised when a key is renamed, removed or changes
/// meaning; adding a key does not raise it.
pub const FORMAT_VERSION: u32 = 1;

/// A report with `format_version` as its first key, then the report's own keys. The report
/// must serialize as an object (a struct or a map).
#[derive(Serialize)]
pub struct Versioned<'a, T: ?Sized + Serialize> {
    format_version: u32,
    #[serde(flatten)]
    report: &'a T,
}

impl<'a, T: ?Sized + Serialize> Versioned<'a, T> {
    /// Wrap `report`.
    pub fn new(report: &'a T) -> Self {
        Versioned {
            format_version: FORMAT_VERSION,
            report,
        }
    }
}

/// A report as pretty JSON with a trailing newline, `format_version` first (`--format json`).
pub fn json<T: ?Sized + Serialize>(report: &T) -> String {
    plain(&Versioned::new(report))
}

/// A report as one JSON line with a trailing newline, `format_version` first (`--format jsonl`).
pub fn jsonl<T: ?Sized + Serialize>(report: &T) -> String {
    let mut s = serde_json::to_string(&Versioned::new(report)).unwrap_or_else(|e| {
        // Serializing our own types cannot fail (no maps with non-string keys, no I/O).
        format!("{{\"error\": {:?}}}", e.to_string())
    });
    s.push('\n');
    s
}

/// Any value as pretty JSON with a trailing newline, without a version (schemas, documents
/// that are not reports).
pub fn plain<T: ?Sized + Serialize>(value: &T) -> String {
    let mut s = serde_json::to_string_pretty(value).unwrap_or_else(|e| {
        // Serializing our own types cannot fail (no maps with non-string keys, no I/O).
        format!("{{\"error\": {:?}}}", e.to_string())
    });
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Report {
        name: &'static str,
        #[serde(skip_serializing_if = "Option::is_none")]
        note: Option<&'static str>,
        count: u128,
    }

    #[test]
    fn version_comes_first_and_the_rest_is_unchanged() {
        let r = Report {
            name: "x",
            note: None,
            count: u128::from(u64::MAX) + 1,
        };
        let bare = plain(&r);
        let versioned = json(&r);
        assert_eq!(
            versioned,
            bare.replacen("{\n", "{\n  \"format_version\": 1,\n", 1)
        );
        assert_eq!(
            jsonl(&r),
            "{\"format_version\":1,\"name\":\"x\",\"count\":18446744073709551616}\n"
        );
    }
}
