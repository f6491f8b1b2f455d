//! The reader: any bytes give a mechanism or a located error, never a panic. A loaded
//! mechanism must also survive the cheap reports, and the bytes the `--inputs` parser.
//!
//! One parse per input, so that a long campaign reaches its executions: the format is
//! sniffed as the CLI does for standard input, unless the first byte is 0, 1 or 2, which
//! forces TOML, YAML or JSON on the rest (a TOML file read as YAML, ...).

use mbsa::Mechanism;
use mbsa::format::{Format, load, load_bytes};
use std::sync::OnceLock;

/// The bundled rotor, parsed once: the target for fuzzed `--inputs` specs.
fn rotor() -> &'static Mechanism {
    static ROTOR: OnceLock<Mechanism> = OnceLock::new();
    ROTOR.get_or_init(|| {
        let (_, toml) = mbsa::examples::find("rotor").expect("rotor is bundled");
        load("rotor.toml", toml, Format::Toml).expect("bundled examples load")
    })
}

/// One input through the checks; a panic is a finding.
pub fn run(data: &[u8]) {
    let (format, bytes) = match data.first() {
        Some(0) => (Format::Toml, &data[1..]),
        Some(1) => (Format::Yaml, &data[1..]),
        Some(2) => (Format::Json, &data[1..]),
        _ => {
            let valid = match std::str::from_utf8(data) {
                Ok(s) => s,
                Err(e) => std::str::from_utf8(&data[..e.valid_up_to()]).unwrap_or_default(),
            };
            (Format::sniff(valid), data)
        }
    };
    match load_bytes("<fuzz>", bytes, format) {
        Ok(m) => {
            let r = mbsa::mobility::mobility(&m);
            let _ = mbsa::report::json(&r);
            let _ = mbsa::report::mobility::table(&r, mbsa::motion::has_geometry(&m));
            let _ = mbsa::report::json(&m);
        }
        Err(e) => {
            let _ = e.line_col();
            let _ = mbsa::diagnostic::render(&e, false);
        }
    }
    if let Ok(text) = std::str::from_utf8(bytes) {
        // The text as an `--inputs` spec.
        if let Ok(spec) = mbsa::InputSpec::parse(text) {
            let mut m = rotor().clone();
            if m.apply_inputs(&spec).is_ok() {
                let _ = mbsa::mobility::mobility(&m);
            }
        }
    }
}
