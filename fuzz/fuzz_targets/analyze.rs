//! Structural analysis of whatever parses (size-capped): counting, the rank check, the
//! exhaustive reference search on small inputs, `[expect]` evaluation and every report.

#![no_main]

use libfuzzer_sys::fuzz_target;
use mbsa::report::dot::{View, render};
use mbsa::structure::{Library, Method, Options, analyze};

mod common;

fuzz_target!(|data: &[u8]| {
    let Some(m) = common::parse(data) else { return };
    if !common::within(&m, 200, 400) {
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
    if common::within(&m, 40, 80) {
        // The default geometry (the file's when complete) may be unusable: an error, not a panic.
        if let Ok(ranked) = analyze(&m, &Options::default(), &lib) {
            let _ = mbsa::report::structure::table(&ranked);
        }
        let _ = mbsa::expect::evaluate(&m, &Default::default());
    }
    if common::within(&m, 10, 16) {
        let opts = Options {
            count_only: true,
            method: Method::Exhaustive,
            ..Options::default()
        };
        let _ = analyze(&m, &opts, &lib);
    }
});
