//! What both writers share: unique names, escaped text, numbers as written.

use std::collections::BTreeSet;

/// Names given so far; a name taken twice gets `#2`, `#3`, ...
#[derive(Clone, Debug, Default)]
pub(crate) struct Names(BTreeSet<String>);

impl Names {
    /// `want`, or `want#n` with the first n that is free.
    pub(crate) fn take(&mut self, want: &str) -> String {
        let mut name = want.to_string();
        let mut n = 2;
        while self.0.contains(&name) {
            name = format!("{want}#{n}");
            n += 1;
        }
        self.0.insert(name.clone());
        name
    }
}

/// Text safe in an attribute value or element content.
pub(crate) fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Text safe inside an XML comment (no `--`, no control characters).
pub(crate) fn comment(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    while out.contains("--") {
        out = out.replace("--", "- -");
    }
    if out.ends_with('-') {
        out.push(' ');
    }
    out
}

/// A number as the shortest decimal that reads back to it (the file's own digits for a
/// number read from a file); `-0` written `0`.
pub(crate) fn num(x: f64) -> String {
    if x == 0.0 { "0".into() } else { format!("{x}") }
}

/// Three numbers separated by spaces.
pub(crate) fn vec3(v: [f64; 3]) -> String {
    format!("{} {} {}", num(v[0]), num(v[1]), num(v[2]))
}

/// Indentation for `depth` (capped, so that a deep chain does not grow the file as its
/// square).
pub(crate) fn indent(depth: usize) -> String {
    "  ".repeat(depth.min(24))
}

/// The centroid of `points` (the origin when there is none).
pub(crate) fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    if points.is_empty() {
        return [0.0; 3];
    }
    let n = points.len() as f64;
    [0, 1, 2].map(|i| points.iter().map(|p| p[i]).sum::<f64>() / n)
}

/// Comment lines from `text`, wrapped at about 96 columns, each `<!-- ... -->` at `pad`.
pub(crate) fn comment_block(pad: &str, text: &str) -> String {
    let mut out = String::new();
    let mut line = String::new();
    for word in comment(text).split_whitespace() {
        if !line.is_empty() && line.len() + word.len() > 88 {
            out.push_str(&format!("{pad}<!-- {line} -->\n"));
            line.clear();
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        out.push_str(&format!("{pad}<!-- {line} -->\n"));
    }
    out
}
