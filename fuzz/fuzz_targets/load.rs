//! The reader: any bytes, in each format, give a mechanism or a located error, never a panic.
//! A loaded mechanism must also survive the cheap reports, and the bytes the `--inputs` parser.

#![no_main]

use libfuzzer_sys::fuzz_target;
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

fuzz_target!(|data: &[u8]| {
    for format in [Format::Toml, Format::Yaml, Format::Json] {
        match load_bytes("<fuzz>", data, format) {
            Ok(m) => {
                let r = mbsa::mobility::mobility(&m);
                let _ = mbsa::report::json(&r);
                let _ = mbsa::report::mobility::table(&r);
                let _ = mbsa::report::json(&m);
            }
            Err(e) => {
                let _ = e.line_col();
                let _ = mbsa::diagnostic::render(&e, false);
            }
        }
    }
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = Format::sniff(text);
        // The text as an `--inputs` spec.
        if let Ok(spec) = mbsa::InputSpec::parse(text) {
            let mut m = rotor().clone();
            if m.apply_inputs(&spec).is_ok() {
                let _ = mbsa::mobility::mobility(&m);
            }
        }
    }
});
