//! Every bundled mechanism through the real binary: `check` passes, `analyze` (table and
//! JSON) and `rigid` are snapshotted, and every DOT view is valid for the real Graphviz.

use assert_cmd::Command;
use std::io::Write;
use std::process::Stdio;

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

fn names() -> Vec<&'static str> {
    mbsa::examples::names().collect()
}

fn snapshot(name: &str, value: &str) {
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!(name, value);
    });
}

#[test]
fn every_bundled_mechanism_meets_its_expectations() {
    let files: Vec<String> = names().iter().map(|n| format!("@{n}")).collect();
    let mut args = vec!["check"];
    args.extend(files.iter().map(String::as_str));
    let (code, out, err) = mbsa(&args);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(
        out.lines().filter(|l| l.starts_with("ok")).count(),
        names().len()
    );
}

#[test]
fn analyze_snapshots() {
    for name in names() {
        let at = format!("@{name}");
        let (code, table, err) = mbsa(&["analyze", &at]);
        assert_eq!(code, 0, "{name}: {err}");
        snapshot(&format!("analyze_{name}"), &table);
        let (code, json, err) = mbsa(&["analyze", &at, "--format", "json"]);
        assert_eq!(code, 0, "{name}: {err}");
        let v: serde_json::Value = serde_json::from_str(&json).expect("analyze emits JSON");
        for key in ["status", "groups", "types", "levels"] {
            assert!(v.get(key).is_some(), "{name}: JSON lacks `{key}`");
        }
        assert!(v["mobility"]["count"].is_i64(), "{name}: mobility.count");
    }
}

#[test]
fn count_only_micro_manipulator_is_the_papers_table_12() {
    let (code, out, err) = mbsa(&["analyze", "@micro-manipulator", "--count-only"]);
    assert_eq!(code, 0, "{err}");
    snapshot("analyze_micro-manipulator_count-only", &out);
    assert!(out.contains("8 structural group(s) on 4 level(s)"), "{out}");
}

#[test]
fn rotor_with_the_second_input_set_matches_table_10() {
    let (code, out, _) = mbsa(&["analyze", "@rotor", "--inputs", "1-2,1-13,13-15"]);
    assert_eq!(code, 0);
    let (_, set2, _) = mbsa(&["analyze", "@rotor-set2"]);
    // Same structure as the bundled set-2 file (only the name line differs).
    let body = |s: &str| s.lines().skip(1).collect::<Vec<_>>().join("\n");
    assert_eq!(body(&out), body(&set2));
    assert!(out.contains("9 structural group(s) on 6 level(s)"), "{out}");
}

#[test]
fn rigid_snapshots() {
    for name in names().into_iter().filter(|n| n.starts_with("rig-")) {
        let (code, out, err) = mbsa(&["rigid", &format!("@{name}")]);
        assert_eq!(code, 0, "{name}: {err}");
        snapshot(&format!("rigid_{name}"), &out);
    }
}

/// Run Graphviz on `dot`: its warnings when it succeeds, the error otherwise. The whole
/// layout and the SVG rendering run, with the network-simplex passes (rank and coordinate
/// optimisation) cut to one iteration: they only make the drawing tidier, and on the large
/// bundled mechanisms they were most of this file's time.
fn graphviz(dot: &str) -> Result<String, String> {
    let mut child = std::process::Command::new("dot")
        .args(["-Tsvg", "-Gnslimit=1", "-Gnslimit1=1"])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot run Graphviz `dot` (install graphviz): {e}"))?;
    child
        .stdin
        .take()
        .expect("stdin is piped")
        .write_all(dot.as_bytes())
        .map_err(|e| e.to_string())?;
    let out = child.wait_with_output().map_err(|e| e.to_string())?;
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    if out.status.success() && !err.contains("Error") {
        Ok(err)
    } else {
        Err(err)
    }
}

fn graphviz_accepts(dot: &str) -> Result<(), String> {
    graphviz(dot).map(|_| ())
}

#[test]
fn every_dot_view_of_every_mechanism_is_valid_graphviz() {
    // The N-four-bar's variants (driven, written in 3D) have the bodies, joints and names of
    // `n-four-bar-40`: Graphviz's layout of a graph that size (seconds per view) is run on the
    // plain one; the variants' views must still be written.
    for name in names() {
        let variant = name.starts_with("n-four-bar-40-");
        for view in ["diagram", "structure", "topology", "rigid"] {
            let (code, dot, err) = mbsa(&["dot", &format!("@{name}"), "--view", view]);
            assert_eq!(code, 0, "{name} {view}: {err}");
            if variant {
                assert!(
                    dot.starts_with("digraph") || dot.starts_with("graph"),
                    "{dot}"
                );
            } else if let Err(e) = graphviz_accepts(&dot) {
                panic!("{name} {view}: Graphviz rejects the DOT: {e}\n{dot}");
            }
        }
    }
}

#[test]
fn dot_escapes_awkward_names() {
    let file = "name = \"a \\\"quoted\\\" name with \\\\ and ü\"\nspace = \"planar\"\nframe = \"the ground\"\n\
        [[joint]]\nid = \"crank \\\"A\\\"\"\ntype = \"R\"\nbodies = [\"the ground\", \"crank ü\"]\ndriven = 1\n";
    let path = std::env::temp_dir().join(format!("mbsa-dot-escape-{}.toml", std::process::id()));
    std::fs::write(&path, file).expect("temp file");
    let p = path.to_string_lossy().into_owned();
    for view in ["diagram", "structure", "topology"] {
        let (code, dot, err) = mbsa(&["dot", &p, "--view", view]);
        assert_eq!(code, 0, "{view}: {err}");
        graphviz_accepts(&dot).unwrap_or_else(|e| panic!("{view}: {e}\n{dot}"));
    }
    let _ = std::fs::remove_file(path);
}

#[test]
fn dot_is_deterministic_and_marks_undetermined_parts() {
    let (_, a, _) = mbsa(&["dot", "@micro-manipulator"]);
    let (_, b, _) = mbsa(&["dot", "@micro-manipulator"]);
    assert_eq!(a, b);
    assert!(a.contains("under-determined"), "{a}");
    assert!(a.contains("legend"), "{a}");
    snapshot("dot_rotor_diagram", &mbsa(&["dot", "@rotor"]).1);
}

#[test]
fn generated_mechanisms_round_trip_through_the_reader() {
    for args in [
        vec![
            "generate",
            "assur",
            "--class",
            "3",
            "--groups",
            "4",
            "--variant",
            "B",
        ],
        vec!["generate", "random", "--bodies", "40", "--seed", "3"],
        vec![
            "generate", "random", "--bodies", "40", "--planar", "--seed", "3",
        ],
        vec!["generate", "stewart", "--stages", "2"],
    ] {
        let (code, toml, err) = mbsa(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
        let m = mbsa::format::load("gen.toml", &toml, mbsa::format::Format::Toml)
            .unwrap_or_else(|e| panic!("{args:?}: {e}"));
        assert_eq!(
            mbsa::generate::to_toml(&m),
            toml,
            "{args:?}: writer and reader agree"
        );
    }
}

#[test]
fn a_hundred_groups_render_without_graphviz_warnings() {
    let (code, toml, err) = mbsa(&["generate", "assur", "--class", "1", "--groups", "100"]);
    assert_eq!(code, 0, "{err}");
    let path = std::env::temp_dir().join(format!("mbsa-dot-100-{}.toml", std::process::id()));
    std::fs::write(&path, toml).expect("temp file");
    let p = path.to_string_lossy().into_owned();
    let (_, summary, _) = mbsa(&["analyze", &p]);
    assert!(summary.contains("101 structural group(s)"), "{summary}");
    for view in ["diagram", "structure", "topology"] {
        let (code, dot, err) = mbsa(&["dot", &p, "--view", view]);
        assert_eq!(code, 0, "{view}: {err}");
        let warnings = graphviz(&dot).unwrap_or_else(|e| panic!("{view}: {e}"));
        assert!(warnings.trim().is_empty(), "{view}: {warnings}");
    }
    let _ = std::fs::remove_file(path);
}

/// `mobility` is the count; on a file with geometry it must not let the count's verdict stand
/// for the mechanism: the planar four-bar written in 3D has count -2 with one input, yet moves
/// with 1 DOF at its geometry (as `rigid` says), so the verdict is "by the count" and a note
/// points to the commands that decide at the file's configuration.
#[test]
fn mobility_on_a_file_with_geometry_points_to_the_true_mobility() {
    let (code, out, err) = mbsa(&["mobility", "@four-bar-3d-driven"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("count verdict: more inputs (1) than the count (-2): they over-determine the mechanism if the geometry is generic"),
        "{out}"
    );
    assert!(
        out.contains("note: the count ignores the joint geometry"),
        "{out}"
    );
    let (_, rigid, _) = mbsa(&["rigid", "@four-bar-3d-driven"]);
    assert!(rigid.contains("true mobility 1"), "{rigid}");
    // Without geometry the count is all there is: no note.
    let (code, out, err) = mbsa(&["mobility", "@four-bar"]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("note:"), "{out}");
}

/// `mobility` is the count only, and says so: on the Bricard linkage (count 0, true mobility 1)
/// it must not present the count's verdict as the mechanism's.
#[test]
fn mobility_words_its_verdict_as_the_counts() {
    let (code, out, _) = mbsa(&["mobility", "@bricard"]);
    assert_eq!(code, 0);
    assert!(
        out.starts_with("Bricard linkage: mobility 0 by the count\n"),
        "{out}"
    );
    assert!(out.contains("\ncount verdict: inputs = count (0): enough to determine the mechanism if the geometry is generic"), "{out}");
    assert!(!out.contains("can be kinematically determined"), "{out}");
    let (_, rigid, _) = mbsa(&["rigid", "@bricard", "--method", "geometric"]);
    assert!(rigid.contains("true mobility 1"), "{rigid}");
}
