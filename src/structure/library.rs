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
}

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
            if !valid_type(&t) {
                let before = text.get(..start).unwrap_or(text);
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
                return Err(LibraryError::BadType {
                    text: t,
                    line,
                    column,
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

/// `<count><code>...` followed by `2D` or `3D`, codes from the joint catalogue.
fn valid_type(t: &str) -> bool {
    let Some(body) = t.strip_suffix("2D").or_else(|| t.strip_suffix("3D")) else {
        return false;
    };
    let mut rest = body;
    if rest.is_empty() {
        return false;
    }
    while !rest.is_empty() {
        let digits = rest.chars().take_while(|c| c.is_ascii_digit()).count();
        if digits == 0 {
            return false;
        }
        rest = &rest[digits..];
        let letters = rest.chars().take_while(|c| c.is_ascii_uppercase()).count();
        // Longest catalogue code that prefixes the letters.
        let code = (1..=letters)
            .rev()
            .find(|&n| crate::joint::JointType::all().any(|k| k.code() == &rest[..n]));
        match code {
            Some(n) => rest = &rest[n..],
            None => return false,
        }
    }
    true
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
}
