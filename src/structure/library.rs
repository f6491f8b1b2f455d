//! Libraries of solvable structural-group types (the paper's MBDSBEG library and its planar
//! counterpart), and user libraries read from TOML.

use serde::Serialize;
use std::collections::BTreeSet;

/// A set of SG type strings (`1R3D`, `1P1U1S3D`, ...) whose solution is available.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Library {
    /// Where it came from (`built-in`, `file`; callers may rename it).
    pub name: String,
    /// The type strings, sorted.
    pub types: BTreeSet<String>,
}

/// Errors reading a library file.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LibraryError {
    /// Not valid TOML or not the expected shape.
    #[error("invalid library file: {0}")]
    Syntax(String),
    /// An entry that is not an SG type string.
    #[error(
        "line {line}, column {column}: `{text}` is not an SG type (expected counts and joint codes ending in 2D or 3D, like `1P1U1S3D`)"
    )]
    BadType {
        /// The offending entry.
        text: String,
        /// Its line in the file (1-based).
        line: usize,
        /// Its column in the line (1-based, in characters).
        column: usize,
    },
    /// An SG type string with a count of pairs that no group has (zero, a leading zero, or
    /// past [`MAX_COUNT`]).
    #[error(
        "line {line}, column {column}: `{text}` has the pair count `{count}`: a count is a whole number from 1 to {MAX_COUNT}, written without leading zeros"
    )]
    BadCount {
        /// The offending entry.
        text: String,
        /// The count as written.
        count: String,
        /// Its line in the file (1-based).
        line: usize,
        /// Its column in the line (1-based, in characters).
        column: usize,
    },
}

/// The largest pair count of one kind an SG type string may give (a group's pairs are joints
/// of the mechanism, which the loader numbers in `u32`).
pub const MAX_COUNT: u32 = u32::MAX;

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct LibraryFile {
    types: Vec<toml::Spanned<String>>,
}

impl Library {
    /// The built-in library.
    ///
    /// Spatial types are those the paper's MBDSBEG library holds (Tables 9, 11, 15): a driven
    /// revolute or prismatic body (`1R3D`, `1P3D`), the RUS and PUS legs (`1R1U1S3D`,
    /// `1P1U1S3D`) and a body placed by a free pair driven in all six DOF (`1F3D`).
    ///
    /// Planar types are their classic counterparts: a driven crank or slider (`1R2D`, `1P2D`)
    /// and the Assur dyads, all solved in closed form by intersecting circles and lines:
    /// RRR (`3R2D`); RRP and RPR, which share the type `2R1P2D`; PRP and RPP, which share
    /// `1R2P2D`. The PPP dyad (`3P2D`) is left out on purpose: three sliders cannot fix the
    /// dyad's rotation, so it is not solvable (see the rank check).
    pub fn builtin() -> Library {
        let types = [
            "1R3D", "1P3D", "1P1U1S3D", "1R1U1S3D", "1F3D", "1R2D", "1P2D", "3R2D", "2R1P2D",
            "1R2P2D",
        ];
        Library {
            name: "built-in".into(),
            types: types.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// An empty library (every type uncovered).
    pub fn empty() -> Library {
        Library {
            name: "empty".into(),
            types: BTreeSet::new(),
        }
    }

    /// Parse a library file: `types = ["1R3D", "1P1U1S3D", ...]`.
    pub fn from_toml(text: &str) -> Result<Library, LibraryError> {
        let file: LibraryFile =
            toml::from_str(text).map_err(|e| LibraryError::Syntax(e.to_string()))?;
        let mut types = BTreeSet::new();
        for t in file.types {
            let start = t.span().start;
            let t = t.into_inner().trim().to_string();
            let checked = check_type(&t);
            if checked != Ok(()) {
                let before = text.get(..start).unwrap_or(text);
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
                return Err(match checked {
                    Err(Some(count)) => LibraryError::BadCount {
                        text: t,
                        count,
                        line,
                        column,
                    },
                    _ => LibraryError::BadType {
                        text: t,
                        line,
                        column,
                    },
                });
            }
            types.insert(t);
        }
        Ok(Library {
            name: "file".into(),
            types,
        })
    }

    /// Whether the library solves groups of type `t`.
    pub fn contains(&self, t: &str) -> bool {
        self.types.contains(t)
    }
}

impl Default for Library {
    fn default() -> Library {
        Library::builtin()
    }
}

/// Whether `t` is `<count><code>...` followed by `2D` or `3D`, codes from the joint
/// catalogue: `Err(None)` when not, `Err(Some(count))` for a count that is not from 1 to
/// [`MAX_COUNT`] in its plain decimal form (`0R3D`, `01R3D`, `99999999999R3D`).
fn check_type(t: &str) -> Result<(), Option<String>> {
    let Some(body) = t.strip_suffix("2D").or_else(|| t.strip_suffix("3D")) else {
        return Err(None);
    };
    let mut rest = body;
    if rest.is_empty() {
        return Err(None);
    }
    while !rest.is_empty() {
        let digits = rest.chars().take_while(|c| c.is_ascii_digit()).count();
        if digits == 0 {
            return Err(None);
        }
        let count = &rest[..digits];
        let plain = !count.starts_with('0') && count.parse::<u32>().is_ok();
        if !plain {
            return Err(Some(count.to_string()));
        }
        rest = &rest[digits..];
        let letters = rest.chars().take_while(|c| c.is_ascii_uppercase()).count();
        // Longest catalogue code that prefixes the letters.
        let code = (1..=letters)
            .rev()
            .find(|&n| crate::joint::JointType::all().any(|k| k.code() == &rest[..n]));
        match code {
            Some(n) => rest = &rest[n..],
            None => return Err(None),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_library_files() {
        let l = Library::from_toml("types = [\"1R3D\", \"1P1U1S3D\", \"2R1CPEP2D\"]").unwrap();
        assert!(l.contains("1P1U1S3D"));
        assert_eq!(l.types.len(), 3);
        assert!(matches!(
            Library::from_toml("types = [\"R3D\"]"),
            Err(LibraryError::BadType { .. })
        ));
        assert!(matches!(
            Library::from_toml("types = [\"1R\"]"),
            Err(LibraryError::BadType { .. })
        ));
        assert!(matches!(
            Library::from_toml("typ = 3"),
            Err(LibraryError::Syntax(_))
        ));
        assert!(Library::builtin().contains("1R1U1S3D"));
    }

    #[test]
    fn bad_types_are_located() {
        let e = Library::from_toml("# mine\ntypes = [\n  \"1R3D\",\n  \"XYZ\",\n]\n").unwrap_err();
        assert_eq!(
            e,
            LibraryError::BadType {
                text: "XYZ".into(),
                line: 4,
                column: 3
            }
        );
        assert!(e.to_string().starts_with("line 4, column 3: `XYZ`"));
    }

    /// A pair count is 1 or more, plain decimal, and fits the joint numbering.
    #[test]
    fn counts_are_positive_and_bounded() {
        for (t, count) in [
            ("0R3D", "0"),
            ("01R3D", "01"),
            ("1R0P2D", "0"),
            ("99999999999999999999999R3D", "99999999999999999999999"),
            ("4294967296R3D", "4294967296"),
        ] {
            let e = Library::from_toml(&format!("types = [\"{t}\"]")).unwrap_err();
            assert_eq!(
                e,
                LibraryError::BadCount {
                    text: t.into(),
                    count: count.into(),
                    line: 1,
                    column: 10
                }
            );
            assert!(e.to_string().contains("from 1 to 4294967295"), "{e}");
        }
        assert!(Library::from_toml("types = [\"4294967295R3D\", \"10R2D\"]").is_ok());
    }
}
