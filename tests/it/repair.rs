//! `mbsa repair`: on the bundled and imported models with redundant constraints or isolated
//! freedoms, the first candidate written with `--apply 1` and read back is checked by
//! `mbsa rigid --finite` (the library's own analyses, run as a user would): no redundant
//! constraint, no isolated freedom, the same true and finite mobility minus the freedoms
//! stiffened. Then the refusals and the budget.

use super::common::mbsa;
use serde_json::Value;

/// `mbsa rigid FILE --finite | --with-inputs --format json`, parsed.
fn rigid(file: &str, with_inputs: bool) -> Value {
    let mut args = vec!["rigid", file, "--method", "geometric", "--format", "json"];
    // The finite test with the inputs released; the isolated freedoms with them driven.
    args.push(if with_inputs {
        "--with-inputs"
    } else {
        "--finite"
    });
    let (code, out, err) = mbsa(&args);
    assert_eq!(code, 0, "{file}: {err}");
    serde_json::from_str(&out).expect("JSON")
}

fn geometric_count(r: &Value, key: &str) -> i64 {
    // With one method the report is the geometric one itself.
    r.get("geometric").unwrap_or(r)[key]
        .as_i64()
        .unwrap_or_else(|| panic!("geometric.{key} in {r}"))
}

fn finite(r: &Value) -> i64 {
    r["finite"]["finite"].as_i64().expect("finite.finite")
}

/// Repair `file` (candidate 1) in `format`, read the result back and check it against the
/// analyses of the original: `redundant` and `isolated` (with the inputs driven) before, all
/// gone after, the mobility lowered by exactly the isolated freedoms stiffened.
fn repaired(file: &str, format: &str, redundant: i64, isolated: i64) -> String {
    let before = rigid(file, false);
    let before_driven = rigid(file, true);
    assert_eq!(geometric_count(&before, "redundant"), redundant, "{file}");
    assert_eq!(
        geometric_count(&before_driven, "isolated"),
        isolated,
        "{file}"
    );
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("repair");
    std::fs::create_dir_all(&dir).unwrap();
    let stem = std::path::Path::new(file.trim_start_matches('@'))
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let out = dir.join(format!("{stem}.{format}"));
    let out_s = out.to_str().unwrap();
    // One candidate: the first is the one written, the others only cost time here.
    let (code, _, err) = mbsa(&[
        "repair",
        file,
        "--apply",
        "1",
        "--format",
        format,
        "-o",
        out_s,
        "--candidates",
        "1",
    ]);
    assert_eq!(code, 0, "{file}: {err}");
    let after = rigid(out_s, false);
    let after_driven = rigid(out_s, true);
    assert_eq!(geometric_count(&after, "redundant"), 0, "{file} repaired");
    assert_eq!(
        geometric_count(&after_driven, "isolated"),
        0,
        "{file} repaired"
    );
    assert_eq!(
        geometric_count(&after, "mobility"),
        geometric_count(&before, "mobility") - isolated,
        "{file}: true mobility"
    );
    assert_eq!(
        finite(&after),
        finite(&before) - isolated,
        "{file}: finite mobility"
    );
    std::fs::read_to_string(&out).unwrap()
}

#[test]
fn a_planar_four_bar_in_3d_gets_one_sphere_cylinder_joint() {
    let text = repaired("@rig-planar-four-bar-3d", "toml", 3, 0);
    assert!(
        text.contains("# mbsa repair: R -> SC axis [0, 0, 1]"),
        "{text}"
    );
    assert_eq!(text.matches("type = \"SC\"").count(), 1, "{text}");
}

#[test]
fn the_gazebo_four_bar_and_the_bricard() {
    repaired("tests/fixtures/import/four_bar.sdf", "yaml", 3, 0);
    let text = repaired("@bricard", "json", 1, 0);
    // JSON has no comments: the change is told in the description.
    assert!(text.contains("mbsa repair: R -> C"), "{text}");
}

#[test]
fn the_cassie_loses_its_two_redundant_rows_and_its_two_rod_spins() {
    let text = repaired("tests/fixtures/import/cassie.xml", "toml", 2, 2);
    assert_eq!(text.matches("# mbsa repair: S -> U").count(), 2, "{text}");
    assert_eq!(text.matches("# mbsa repair: R -> C").count(), 2, "{text}");
}

#[test]
fn a_stewart_platform_with_s_p_s_legs_gets_u_p_s_legs() {
    let text = repaired("tests/fixtures/repair/stewart-sps.toml", "toml", 0, 6);
    assert_eq!(text.matches("# mbsa repair: S -> U").count(), 6, "{text}");
}

#[test]
fn the_n_four_bar_in_3d_gets_one_change_per_window() {
    let text = repaired("@n-four-bar-40-3d", "toml", 120, 0);
    assert_eq!(text.matches("type = \"SC\"").count(), 40);
}

#[test]
fn the_list_is_deterministic_and_its_json_names_every_change() {
    let (code, a, _) = mbsa(&[
        "repair",
        "tests/fixtures/import/cassie.xml",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0);
    let (_, b, _) = mbsa(&[
        "repair",
        "tests/fixtures/import/cassie.xml",
        "--format",
        "json",
    ]);
    assert_eq!(a, b);
    let r: Value = serde_json::from_str(&a).unwrap();
    assert_eq!(r["format_version"], 1);
    assert_eq!(r["before"]["redundant"], 2);
    let c = &r["candidates"][0];
    assert_eq!(c["complete"], true);
    assert_eq!(c["joints_changed"], 4);
    assert_eq!(c["after"]["redundant"], 0);
}

#[test]
fn nothing_to_repair_is_said_so() {
    let (code, out, _) = mbsa(&["repair", "@n-four-bar-40"]);
    assert_eq!(code, 0);
    assert!(out.contains("nothing to repair"), "{out}");
    assert!(!out.contains("candidate 1"), "{out}");
}

#[test]
fn a_model_without_geometry_is_refused_naming_its_joints() {
    let (code, _, err) = mbsa(&["repair", "@hexapod-rss"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("lack it: 1-2 (R: origin, axis)"), "{err}");
    assert!(err.contains("help:"), "{err}");
}

#[test]
fn a_candidate_that_does_not_exist_is_refused() {
    let (code, _, err) = mbsa(&["repair", "@bricard", "--apply", "9"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--apply 9"), "{err}");
    let (code, _, err) = mbsa(&["repair", "@bricard", "--format", "yaml"]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn the_search_stops_at_the_work_budget() {
    let (code, _, err) = mbsa(&["--max-work", "100000", "repair", "@n-four-bar-40-3d"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("work"), "{err}");
}

/// Every bundled mechanism written by the file writer the repair uses, in each format, reads
/// back as the same mechanism (the writer's own test: it lives here because the writer is
/// below the reader's layer).
#[test]
fn every_bundled_mechanism_written_in_each_format_reads_back() {
    use mbsa::format::Format;
    use mbsa::write::{TextFormat, write};
    for name in mbsa::examples::names() {
        let (file, text) = mbsa::examples::find(name).expect("bundled");
        let m = mbsa::format::load(file, text, Format::Toml).expect("bundled reads");
        for (tf, f) in [
            (TextFormat::Toml, Format::Toml),
            (TextFormat::Yaml, Format::Yaml),
            (TextFormat::Json, Format::Json),
        ] {
            let text = write(&m, tf, &[Some("a note\non two lines".into())]);
            let back = mbsa::format::load(name, &text, f)
                .unwrap_or_else(|e| panic!("{name} as {f:?}: {e:?}\n{text}"));
            assert_eq!(back.joints.len(), m.joints.len(), "{name} {f:?}");
            for (a, b) in back.joints.iter().zip(&m.joints) {
                assert_eq!(a.id, b.id);
                assert_eq!(a.kind, b.kind);
                assert_eq!(a.driven, b.driven);
                assert_eq!(*a.geometry, *b.geometry, "{name} {f:?} {}", a.id);
            }
        }
    }
}

#[test]
fn where_no_catalogue_joint_frees_the_rows_it_says_so_and_lists_nothing() {
    let (code, out, err) = mbsa(&["repair", "tests/fixtures/repair/parallel-sliders.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("before: 5 redundant constraints"), "{out}");
    assert!(!out.contains("candidate 1"), "{out}");
    assert!(
        out.contains("no catalogue joint at the same geometry frees the last 5 redundant"),
        "{out}"
    );
}

/// At a singular configuration (the Gazebo Stewart platform as written: finite mobility 9,
/// first order 11) a relaxation that keeps the first-order motions frees the singular ones:
/// the check rejects it, and the report says why instead of offering it.
#[test]
fn at_a_singular_configuration_no_candidate_passes_the_check() {
    let (code, out, err) = mbsa(&["repair", "tests/fixtures/import/stewart_upu.sdf"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("the file's configuration is singular (finite mobility 9"),
        "{out}"
    );
    assert!(out.contains("was rejected when checked"), "{out}");
    assert!(!out.contains("candidate 1"), "{out}");
}
