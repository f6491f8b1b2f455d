//! The serial-chain and star generators (issue 16's scale families): their counts follow from
//! the construction, so the generated files are checked through the real binary.

use assert_cmd::Command;

fn mbsa() -> Command {
    Command::cargo_bin("mbsa").expect("the binary is built")
}

/// `mbsa generate ARGS | mbsa mobility - --format json`, parsed.
fn mobility(args: &[&str]) -> serde_json::Value {
    let file = mbsa().arg("generate").args(args).output().expect("runs");
    assert!(
        file.status.success(),
        "{}",
        String::from_utf8_lossy(&file.stderr)
    );
    let out = mbsa()
        .args(["mobility", "-", "--format", "json"])
        .write_stdin(file.stdout)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

#[test]
fn chain_counts_one_grade_per_joint() {
    let v = mobility(&["chain", "--bodies", "100", "--joint", "U"]);
    assert_eq!(v["bodies"], 100);
    assert_eq!(v["pairs"], 99);
    assert_eq!(v["loops"], 0);
    assert_eq!(v["mobility"]["count"], 2 * 99);
    let v = mobility(&["chain", "--bodies", "100", "--planar", "--driven"]);
    assert_eq!(v["mobility"]["count"], 99);
    assert_eq!(v["mobility"]["inputs"], 99);
}

#[test]
fn star_own_and_shared_joints_count_alike() {
    let own = mobility(&["star", "--bodies", "40", "--joint", "S"]);
    let shared = mobility(&["star", "--bodies", "40", "--joint", "S", "--shared"]);
    assert_eq!(own["joints"], 39);
    assert_eq!(shared["joints"], 1);
    for v in [&own, &shared] {
        assert_eq!(v["pairs"], 39);
        assert_eq!(v["mobility"]["count"], 3 * 39);
    }
    let driven = mobility(&[
        "star", "--bodies", "40", "--joint", "S", "--shared", "--driven",
    ]);
    assert_eq!(driven["mobility"]["inputs"], 3 * 39);
}

#[test]
fn generators_refuse_what_they_cannot_make() {
    for args in [
        &["chain", "--bodies", "1"][..],
        &["star", "--bodies", "5", "--joint", "S", "--planar"],
        &["chain", "--bodies", "5", "--joint", "nonsense"],
    ] {
        let out = mbsa().arg("generate").args(args).output().expect("runs");
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    }
}
