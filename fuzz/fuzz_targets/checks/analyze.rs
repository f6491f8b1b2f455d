//! Structural analysis of whatever parses (size-capped): counting, the rank check, the
//! exhaustive reference search on small inputs, `[expect]` evaluation and every report.

use mbsa::report::dot::{View, render};
use mbsa::structure::{Library, Method, Options, analyze};

/// One input through the checks; a panic is a finding.
pub fn run(data: &[u8]) {
    let Some(m) = super::common::parse(data) else {
        return;
    };
    if !super::common::within(&m, 200, 400) {
        return;
    }
    let lib = Library::builtin();
    let Ok(counted) = analyze(
        &m,
        &Options {
            count_only: true,
            ..Options::default()
        },
        &lib,
    ) else {
        return;
    };
    let _ = mbsa::report::json(&counted);
    let _ = mbsa::report::structure::table(&counted);
    for view in [View::Diagram, View::Structure, View::Topology] {
        let _ = render(view, &m, &counted);
    }
    if super::common::within(&m, 40, 80) {
        // The default geometry (the file's when complete) may be unusable: an error, not a panic.
        if let Ok(ranked) = analyze(&m, &Options::default(), &lib) {
            let _ = mbsa::report::structure::table(&ranked);
        }
        let _ = mbsa::expect::evaluate(&m, &Default::default());
    }
    if super::common::within(&m, 10, 16) {
        let opts = Options {
            count_only: true,
            method: Method::Exhaustive,
            ..Options::default()
        };
        let _ = analyze(&m, &opts, &lib);
    }
}
