//! Bundled mechanisms that state their numbers in an `[expect]` table (derived in each file's
//! header comment): each one passes `mbsa check` through the real binary, i.e. the analyses of
//! the mechanism as written give those numbers.

use assert_cmd::Command;

/// The checked files, by bundled name.
const CHECKED: [&str; 18] = [
    "four-bar-3d-driven",
    "slider-crank-3d-driven",
    "bricard",
    "bricard-driven",
    "bennett-rounded-4",
    "bennett-rounded-6",
    "bennett-rounded-8",
    "n-four-bar-40",
    "n-four-bar-40-3d",
    "n-four-bar-40-driven",
    "n-four-bar-40-3d-driven",
    "pendulum",
    "pendulum-driven",
    "rrp-chain",
    "floating-base",
    "planar-path-free-end",
    "multiple-joint-order",
    "multiple-joint-order-b",
];

fn mbsa(args: &[&str]) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .output()
        .expect("mbsa runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Every file is bundled (so `@name` works) and states its numbers in `[expect]`.
#[test]
fn checked_files_are_bundled_with_expectations() {
    let names: Vec<&str> = mbsa::examples::names().collect();
    for name in CHECKED {
        assert!(names.contains(&name), "@{name} is not bundled");
        let (code, out, err) = mbsa(&["check", &format!("@{name}")]);
        // Exit 0 (met) or 1 (mismatch) but never a read error: the file parses and has a table.
        assert!(code == 0 || code == 1, "@{name}: exit {code}\n{out}{err}");
        assert!(
            out.contains("mobility"),
            "@{name} has no [expect] table:\n{out}"
        );
    }
}

#[test]
fn checked_files_meet_their_expectations() {
    let mut failed = Vec::new();
    for name in CHECKED {
        let (code, out, err) = mbsa(&["check", &format!("@{name}")]);
        if code != 0 || !out.starts_with("ok") {
            failed.push(format!("@{name} (exit {code}):\n{out}{err}"));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// The two listings of the multiple-joint example give the same groups.
#[test]
fn multiple_joint_listing_order_does_not_change_the_groups() {
    let groups = |name: &str| {
        let (code, json, err) = mbsa(&["analyze", &format!("@{name}"), "--format", "json"]);
        assert_eq!(code, 0, "{name}: {err}");
        let v: serde_json::Value = serde_json::from_str(&json).expect("analyze emits JSON");
        let mut g: Vec<(u64, Vec<String>)> = v["groups"]
            .as_array()
            .expect("groups is an array")
            .iter()
            .map(|g| {
                let bodies = g["bodies"]
                    .as_array()
                    .expect("bodies is an array")
                    .iter()
                    .map(|b| b.as_str().map_or_else(|| b.to_string(), str::to_owned))
                    .collect();
                (g["level"].as_u64().expect("level"), bodies)
            })
            .collect();
        g.sort();
        (g, v["status"].clone(), v["levels"].clone())
    };
    let a = groups("multiple-joint-order");
    let b = groups("multiple-joint-order-b");
    assert_eq!(a, b);
    let want: Vec<(u64, Vec<String>)> = vec![
        (1, vec!["5".into()]),
        (2, vec!["3".into(), "4".into()]),
        (3, vec!["2".into(), "6".into()]),
    ];
    assert_eq!(a.0, want);
}
