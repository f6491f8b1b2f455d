//! Input placement search of whatever parses (small inputs, bounded search): ranking,
//! grouping into families and the comparison with the file's own placement.

use mbsa::structure::Library;
use mbsa::transform::{TransformOptions, transform};

/// One input through the checks; a panic is a finding.
pub fn run(data: &[u8]) {
    let Some(m) = super::common::parse(data) else {
        return;
    };
    if !super::common::within(&m, 10, 14) {
        return;
    }
    let lib = Library::builtin();
    let opts = TransformOptions {
        max_expansions: 4,
        limit: Some(64),
        analysis: mbsa::structure::Options {
            count_only: true,
            ..Default::default()
        },
        ..TransformOptions::default()
    };
    if let Ok(t) = transform(&m, &opts, &lib, None) {
        let _ = mbsa::report::transform::table(&t, 3);
        let _ = mbsa::report::json(&t);
    }
    // The comparison with a one-joint placement (the first joint's id as the spec).
    if let Some(j) = m.joints.first()
        && let Ok(spec) = mbsa::InputSpec::parse(&j.id)
        && let Ok(c) = mbsa::transform::compare(&m, &spec, &opts, &lib)
    {
        let _ = mbsa::report::transform::comparison(&c);
    }
}
