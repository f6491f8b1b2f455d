//! Shared by the fuzz targets: turn fuzzer bytes into a mechanism the way the CLI does.

use mbsa::Mechanism;
use mbsa::format::{Format, load_bytes};

/// Parse `data` as the CLI parses standard input: format sniffed from the valid UTF-8 prefix.
/// Every error is also rendered, because the CLI renders every error it prints.
pub fn parse(data: &[u8]) -> Option<Mechanism> {
    let valid = match std::str::from_utf8(data) {
        Ok(s) => s,
        Err(e) => std::str::from_utf8(&data[..e.valid_up_to()]).unwrap_or_default(),
    };
    match load_bytes("<fuzz>", data, Format::sniff(valid)) {
        Ok(m) => Some(m),
        Err(e) => {
            let _ = mbsa::diagnostic::render(&e, false);
            None
        }
    }
}

/// Whether `m` is small enough for an analysis whose cost grows fast with size: the fuzzer
/// looks for crashes, not for slow inputs that are slow by design.
pub fn within(m: &Mechanism, bodies: usize, joints: usize) -> bool {
    m.bodies.len() <= bodies
        && m.joints.len() <= joints
        && m.joints.iter().map(|j| j.bodies.len()).sum::<usize>() <= 2 * joints
}
