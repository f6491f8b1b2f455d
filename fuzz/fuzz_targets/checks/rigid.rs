//! Rigidity of whatever parses (size-capped): the pebble game with and without inputs, and
//! the geometric analysis from the file's geometry and from a random realization.

use mbsa::rigidity::geometric::{self, GeometricOptions, GeometrySource};
use mbsa::rigidity::pebble::{self, PebbleOptions};

/// One input through the checks; a panic is a finding.
pub fn run(data: &[u8]) {
    let Some(m) = super::common::parse(data) else {
        return;
    };
    if !super::common::within(&m, 300, 600) {
        return;
    }
    for with_inputs in [false, true] {
        let r = pebble::analyze(&m, &PebbleOptions { with_inputs });
        let _ = mbsa::report::rigid_pebble::table(&r);
        let _ = mbsa::report::json(&r);
    }
    if super::common::within(&m, 24, 48) {
        for geometry in [
            GeometrySource::Auto { seed: 0 },
            GeometrySource::File,
            GeometrySource::Random { seed: 7 },
        ] {
            if let Ok(r) = geometric::analyze(
                &m,
                &GeometricOptions {
                    geometry,
                    check_finite: false,
                    precision: None,
                },
            ) {
                let _ = mbsa::report::rigid_geometric::table(&r);
                let _ = mbsa::report::json(&r);
            }
        }
    }
}
