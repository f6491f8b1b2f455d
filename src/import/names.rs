//! Names in the source files: one of a kind defined twice is refused with both locations (the
//! reference loaders refuse it too), and names quoted in messages are shortened.

use super::error::ImportError;
use super::xml::{Node, Src};
use std::collections::HashMap;

/// Longest name quoted whole in a message, in characters.
const MAX_QUOTED: usize = 60;

/// The names of one kind of element (bodies, joints, ...) seen so far, each with the location
/// of its first definition.
pub(crate) struct Unique {
    /// What the names name, in messages (`body`, `joint`, `keyframe`).
    what: &'static str,
    first: HashMap<String, String>,
}

impl Unique {
    /// No names seen yet.
    pub fn new(what: &'static str) -> Unique {
        Unique {
            what,
            first: HashMap::new(),
        }
    }

    /// Note `name`, the `attr` attribute of `n` in `src`: an error naming both locations if
    /// it was seen before.
    pub fn add(&mut self, src: &Src, n: Node, attr: &str, name: &str) -> Result<(), ImportError> {
        let here = src.loc(n);
        if let Some(first) = self.first.get(name) {
            return Err(src
                .err_attr(
                    n,
                    attr,
                    "defined again",
                    format!(
                        "{} `{name}` is defined twice: at {first} and at {here}",
                        self.what
                    ),
                )
                .with_help(format!(
                    "{} names must be unique (the model's own loader refuses a repeated one too): \
                     rename one",
                    self.what
                )));
        }
        self.first.insert(name.to_string(), here);
        Ok(())
    }

    /// Whether `name` was seen.
    pub fn contains(&self, name: &str) -> bool {
        self.first.contains_key(name)
    }
}

/// `text` with every `` `quoted` `` part longer than [`MAX_QUOTED`] characters cut there and
/// marked `…`: a 10 MB name is not printed whole.
pub(crate) fn cap_quoted(text: String) -> String {
    let long = text
        .split('`')
        .skip(1)
        .step_by(2)
        .any(|q| q.len() > MAX_QUOTED && q.chars().count() > MAX_QUOTED);
    if !long {
        return text;
    }
    let parts: Vec<&str> = text.split('`').collect();
    let mut out = String::with_capacity(text.len().min(4096));
    for (i, part) in parts.iter().enumerate() {
        if i > 0 {
            out.push('`');
        }
        // Odd parts are inside quotes, unless the last quote is not closed.
        let quoted = i % 2 == 1 && i + 1 < parts.len();
        if quoted && part.chars().count() > MAX_QUOTED {
            out.extend(part.chars().take(MAX_QUOTED));
            out.push('…');
        } else {
            out.push_str(part);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::cap_quoted;

    #[test]
    fn long_quoted_names_are_cut() {
        let name = "x".repeat(1000);
        let s = cap_quoted(format!("body `{name}` is `short` and `{name}`"));
        assert_eq!(
            s,
            format!(
                "body `{}…` is `short` and `{}…`",
                "x".repeat(60),
                "x".repeat(60)
            )
        );
        assert_eq!(cap_quoted("a `b` c".into()), "a `b` c");
        assert_eq!(cap_quoted(format!("open `{name}")), format!("open `{name}"));
    }
}
