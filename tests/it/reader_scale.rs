//! Reader at scale: one joint shared by a million bodies reads in linear
//! time, in the three formats.
//!
//! The repeated-body check scanned the bodies read so far for each body: n²/2 comparisons,
//! 1.5 s for 10^5 bodies in a release build, about 150 s for 10^6 (5·10^11 comparisons). The
//! linear reader takes about a second a format here; the time is printed, not asserted (a
//! loaded machine is no test of speed), and a quadratic reader would show as minutes.

use mbsa::format::{Format, load};
use mbsa::joint::JointType;
use std::fmt::Write as _;
use std::time::Instant;

const BODIES: i64 = 1_000_000;

fn body_list() -> String {
    let mut s = String::with_capacity(8 * BODIES as usize);
    for b in 1..=BODIES {
        if b > 1 {
            s.push_str(", ");
        }
        let _ = write!(s, "{b}");
    }
    s
}

#[test]
fn one_joint_shared_by_a_million_bodies_reads_in_linear_time() {
    let m = mbsa::generate::star(BODIES as u64, JointType::S, false, true, false)
        .expect("a star of 10^6 bodies");
    let toml = mbsa::generate::to_toml(&m);
    drop(m);
    let list = body_list();
    let json = format!(
        "{{\"frame\": 1, \"joints\": [{{\"id\": \"hub\", \"type\": \"S\", \"bodies\": [{list}]}}]}}"
    );
    let yaml = format!("frame: 1\njoints:\n  - id: hub\n    type: S\n    bodies: [{list}]\n");
    for (text, format) in [
        (toml, Format::Toml),
        (json, Format::Json),
        (yaml, Format::Yaml),
    ] {
        let start = Instant::now();
        let m = load("star", &text, format).expect("the star reads");
        let r = mbsa::mobility::mobility(&m);
        let took = start.elapsed();
        assert_eq!(r.bodies, BODIES as usize);
        assert_eq!(r.joints, 1);
        assert_eq!(r.pairs, BODIES as u64 - 1);
        assert!(r.disconnected.is_empty());
        assert_eq!(m.joints[0].id, "hub");
        eprintln!(
            "{}: read + count of one joint of 10^6 bodies in {took:?}",
            format.name()
        );
    }
}

/// A body named twice in a long list is still found, where the list is long enough for the
/// per-body marks (more than 16 bodies), and located at both places.
#[test]
fn a_repeated_body_in_a_long_joint_is_found() {
    let mut list: Vec<String> = (1..=40).map(|b| b.to_string()).collect();
    list[30] = "7".into();
    let text = format!(
        "frame = 1\n[[joint]]\ntype = \"S\"\nbodies = [{}]\n",
        list.join(", ")
    );
    let e = load("t.toml", &text, Format::Toml).expect_err("body 7 twice");
    assert_eq!(e.kind(), mbsa::format::ErrorKind::RepeatedBody);
    let shown = e.to_string();
    assert!(shown.contains("body `7` appears twice"), "{shown}");
    // Two joints naming the same bodies are not a repetition (the marks are per joint).
    let again = format!(
        "frame = 1\n[[joint]]\ntype = \"S\"\nbodies = [{0}]\n[[joint]]\ntype = \"S\"\nbodies = [{0}]\n",
        (1..=40)
            .map(|b| b.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let m = load("t.toml", &again, Format::Toml).expect("two shared joints");
    assert_eq!(m.joints.len(), 2);
}
