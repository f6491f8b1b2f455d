//! `mbsa analyze` and `mbsa check` at a singular configuration of the file: the first-order
//! verdict gets a note (and the JSON key `finite`) when the finite-mobility test finds fewer
//! finite than first-order freedoms, and only then (`structure::check_finite`).

use assert_cmd::Command;

fn mbsa(args: &[&str], stdin: &str) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .write_stdin(stdin)
        .output()
        .expect("mbsa runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A parallelogram four-bar (cranks 1, coupler and frame 2) written flat, every pin on the x
/// axis, both cranks driven, with an `[expect]` table: the parallelogram and the
/// anti-parallelogram branches cross here (2 first-order freedoms, 1 finite).
const FLAT_PARALLELOGRAM: &str = r#"
name = "Flat parallelogram, both cranks driven"
space = "planar"
frame = 1

[[joint]]
id = "A"
type = "R"
bodies = [1, 2]
driven = 1
origin = [0, 0]

[[joint]]
id = "B"
type = "R"
bodies = [2, 3]
origin = [1, 0]

[[joint]]
id = "C"
type = "R"
bodies = [3, 4]
origin = [3, 0]

[[joint]]
id = "D"
type = "R"
bodies = [4, 1]
driven = 1
origin = [2, 0]

[expect]
determined = true
"#;

const NOTE: &str = "singular configuration: at the file's configuration the joints allow 2 DOF \
                    to first order (inputs not counted) but only 1 for finite motion";

#[test]
fn a_flat_parallelogram_is_determined_to_first_order_only() {
    let (code, out, err) = mbsa(&["analyze", "-"], FLAT_PARALLELOGRAM);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.lines().next().unwrap_or("").ends_with("; determined"),
        "{out}"
    );
    assert!(out.contains(NOTE), "{out}");
    assert!(
        out.contains("\"determined\" holds to first order only"),
        "{out}"
    );

    let (code, json, err) = mbsa(&["analyze", "-", "--format", "json"], FLAT_PARALLELOGRAM);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    assert_eq!(v["status"], "determined");
    let f = &v["finite"];
    assert_eq!(f["first_order"], 2, "{json}");
    assert_eq!(f["finite"], 1, "{json}");
    assert_eq!(f["instantaneous_only"], 1, "{json}");
    let note = f["note"].as_str().expect("a note");
    assert!(
        v["notes"]
            .as_array()
            .expect("notes")
            .iter()
            .any(|n| n == note)
    );

    // `check`: the expectation holds (the verdict is the first-order one) and the note follows.
    let (code, out, err) = mbsa(&["check", "-"], FLAT_PARALLELOGRAM);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.starts_with("ok      -: determined true\n"), "{out}");
    assert!(
        out.contains("        note: determined: singular configuration"),
        "{out}"
    );

    // Numbers declared rounded (the finite test takes them as exact): nothing is said.
    let (code, out, err) = mbsa(&["analyze", "-", "--tolerance", "1e-6"], FLAT_PARALLELOGRAM);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("singular configuration"), "{out}");
}

/// Redundant by design, moving: a planar four-bar written in space, the Bennett linkage (exact
/// and rounded to 8 decimals) keep their first-order verdict without a note.
#[test]
fn redundancy_by_design_gets_no_note() {
    for name in [
        "@four-bar-3d-driven",
        "@rig-planar-four-bar-3d",
        "@rig-bennett",
        "@bennett-rounded-8",
    ] {
        let (code, out, err) = mbsa(&["analyze", name], "");
        assert_eq!(code, 0, "{name}: {err}");
        assert!(out.contains("set aside"), "{name}: {out}");
        assert!(!out.contains("singular configuration"), "{name}: {out}");
        let (code, json, err) = mbsa(&["analyze", name, "--format", "json"], "");
        assert_eq!(code, 0, "{name}: {err}");
        let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
        assert!(v.get("finite").is_none(), "{name}: {json}");
    }
}

/// `rigid --finite --tolerance 0` on the Bennett linkage rounded to 8 digits (its numbers
/// taken as exact): no nearby configuration is reached (so taken, it is rigid), so the
/// singular note names no joints rather than printing an empty list.
#[test]
fn a_singular_note_with_no_joints_to_name_prints_no_empty_list() {
    let (code, out, err) = mbsa(
        &[
            "rigid",
            "--finite",
            "@bennett-rounded-8",
            "--tolerance",
            "0",
        ],
        "",
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("singular configuration: first-order mobility 1"),
        "{out}"
    );
    assert!(!out.contains("(joints )"), "{out}");
}

/// Rounded numbers: the finite test takes them as exact, the geometric analysis as known to
/// their precision. Where the two disagree (the Bennett to 4 digits: first order 0 as written,
/// true mobility 1 at ±5e-5; to 8 digits: first order 1, finite 0 as written) `rigid --finite`
/// says "not decided" with what it found taken as exact, where it used to say finite 0 (and
/// "singular configuration" at 8 digits) beside "true mobility 1" in the same report. Exact
/// numbers, and `--tolerance 0`, keep the test's verdict.
#[test]
fn rounded_numbers_leave_a_disagreeing_finite_answer_undecided() {
    for (name, precision, at_precision) in [
        ("@bennett-rounded-4", 5e-5, true),
        ("@bennett-rounded-8", 5e-8, false),
    ] {
        let (code, out, err) = mbsa(&["rigid", "--finite", name], "");
        assert_eq!(code, 0, "{name}: {err}");
        assert!(out.contains("true mobility 1"), "{name}: {out}");
        assert!(
            out.contains(
                "Finite mobility: not decided at the written precision (taken as exact: 0;"
            ),
            "{name}: {out}"
        );
        assert!(
            out.contains("- not decided: the geometry's numbers are rounded"),
            "{name}: {out}"
        );
        assert!(!out.contains("- singular configuration:"), "{name}: {out}");
        assert_eq!(
            out.contains("the first-order count at their precision is 1"),
            at_precision,
            "{name}: {out}"
        );
        let (code, json, err) = mbsa(&["rigid", "--finite", name, "--format", "json"], "");
        assert_eq!(code, 0, "{name}: {err}");
        let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
        assert_eq!(v["finite"]["verdict"], "undecided", "{name}: {json}");
        let rounded = v["finite"]["rounded"].as_f64().expect("the precision");
        assert!(
            (rounded - precision).abs() < 1e-3 * precision,
            "{name}: {rounded}"
        );
    }
    // Taken as exact, the test's own verdict.
    let (_, json, _) = mbsa(
        &[
            "rigid",
            "--finite",
            "@bennett-rounded-8",
            "--tolerance",
            "0",
            "--format",
            "json",
        ],
        "",
    );
    let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    assert_eq!(v["finite"]["verdict"], "singular", "{json}");
    assert!(v["finite"].get("rounded").is_none(), "{json}");
    // Exact numbers that agree: unchanged.
    let (_, json, _) = mbsa(
        &["rigid", "--finite", "@rig-bennett", "--format", "json"],
        "",
    );
    let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    assert_eq!(v["finite"]["verdict"], "overconstrained_moving", "{json}");
    assert!(v["finite"].get("rounded").is_none(), "{json}");
}

/// The geometric report's locked DOF point to `--finite` for those that move nearby: the
/// finite test accounts for each of them, at a dead centre (they move) and in a rigid
/// sub-assembly (they stay).
#[test]
fn rigid_finite_accounts_for_every_locked_freedom() {
    let (code, out, _) = mbsa(&["rigid", "mechanisms/msl-engine-v6.toml", "--finite"], "");
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("20 locked DOF"), "{out}");
    assert!(
        out.contains(
            "locked DOF: 20 joint freedom(s) have no first-order motion here; 2 move at the \
             nearby configurations (cylinder1.cylinder 1, cylinder4.cylinder 1), 18 stay locked \
             there (cylinder1.b1 3, cylinder2.b1 3"
        ),
        "{out}"
    );
    let (code, out, _) = mbsa(&["rigid", "mechanisms/rig-rssr.toml", "--finite"], "");
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("2 locked DOF"), "{out}");
    assert!(out.contains("2 stay locked there (B 1, C 1)"), "{out}");
}

/// `rigid --with-inputs --finite`: the counting and the geometry fix the inputs, the finite
/// test follows the mechanism's own motion; the report says so instead of printing two
/// mobilities without a word (`count 0; true mobility 0`, then `Finite mobility: 1`).
#[test]
fn rigid_finite_with_inputs_says_the_finite_mobility_is_the_mechanisms_own() {
    let (code, out, _) = mbsa(
        &[
            "rigid",
            "@slider-crank-geometry",
            "--with-inputs",
            "--finite",
        ],
        "",
    );
    assert_eq!(code, 0, "{out}");
    assert!(
        out.contains(
            "the finite mobility is the mechanism's own, its inputs free: `--with-inputs` \
             applies to the counting and the geometry, not to this test"
        ),
        "{out}"
    );
    let (_, out, _) = mbsa(&["rigid", "@slider-crank-geometry", "--finite"], "");
    assert!(!out.contains("its inputs free"), "{out}");
}
