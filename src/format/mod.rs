//! Reading mechanism files (TOML, YAML, JSON) into a validated [`crate::Mechanism`], with located diagnostics.
