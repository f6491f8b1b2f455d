//! The loop dialects of URDF, each on a public model (tests/fixtures/import/README.md names
//! them): Gazebo's `<gazebo><joint>`, Drake's `drake:ball_constraint`, the `<constraint>` and
//! `<loop>` elements of URDF+, and the Extended-URDF YAML closure file of Pinocchio users. The
//! numbers checked come from the model's own tools or its known mobility; every malformed
//! closure is refused at its file:line:col.

use crate::common::mbsa;
use std::path::{Path, PathBuf};

const FIX: &str = "tests/fixtures/import";

fn fixture(name: &str) -> String {
    format!("{FIX}/{name}")
}

/// A fresh scratch folder for this test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mbsa-dialects-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch folder");
    d
}

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// (count, true mobility, redundant) of `mbsa rigid --format json`.
fn rigid(file: &str, extra: &[&str]) -> (i64, i64, i64) {
    let mut args = vec!["rigid", file, "--format", "json"];
    args.extend_from_slice(extra);
    let (code, out, err) = mbsa(&args);
    assert_eq!(code, 0, "{file}: {err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("rigid emits JSON");
    let g = &v["geometric"];
    let n = |k: &str| g[k].as_i64().unwrap_or_else(|| panic!("{k} in {out}"));
    (n("count"), n("mobility"), n("redundant"))
}

/// `mbsa analyze --format json` of a file.
fn analyze(file: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["analyze", file, "--format", "json"];
    args.extend_from_slice(extra);
    let (code, out, err) = mbsa(&args);
    assert_eq!(code, 0, "{file}: {err}");
    serde_json::from_str(&out).expect("analyze emits JSON")
}

/// Import `file` (extra arguments appended) to `out`; the standard error.
fn import_to(file: &str, out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["import", file, "-o", path(out)];
    args.extend_from_slice(extra);
    let (code, _, err) = mbsa(&args);
    assert_eq!(code, 0, "{file}: {err}");
    err
}

/// The error of a refused import: exit code 2 and the rendered diagnostic.
fn refused(args: &[&str]) -> String {
    let (code, out, err) = mbsa(args);
    assert_eq!(code, 2, "expected a refusal: {out}{err}");
    err
}

// ------------------------------------------------------------------------------------------
// Gazebo: an SDFormat joint inside <gazebo>

#[test]
fn gazebo_revolute_loop_joint_closes_a_four_bar_of_one_dof() {
    // Four boxes joined by parallel hinges, the fourth hinge a <gazebo> joint whose axis is in
    // the model frame (use_parent_model_frame): a four-bar, 1 DOF, written in 3D (3 redundant).
    let file = fixture("closed_loop_gazebo.urdf");
    assert_eq!(rigid(&file, &[]), (-2, 1, 3));
    let (code, toml, err) = mbsa(&["import", &file]);
    assert_eq!(code, 0, "{err}");
    assert!(
        toml.contains(
            "# <gazebo><joint name=\"1_to_4\" type=\"revolute\"> at closed_loop_gazebo.urdf:"
        ),
        "{toml}"
    );
    let closing = toml
        .split("id = \"1_to_4\"")
        .nth(1)
        .expect("the loop joint");
    assert!(closing.contains("axis = [1, 0, 0]"), "{closing}");
}

#[test]
fn gazebo_loop_joint_naming_a_missing_link_is_refused_where_it_is_named() {
    let d = scratch("gazebo_missing");
    let text = std::fs::read_to_string(fixture("closed_loop_gazebo.urdf")).expect("fixture");
    let bad = text.replace("<child>element_1</child>", "<child>element_9</child>");
    let f = d.join("bad.urdf");
    std::fs::write(&f, &bad).expect("write");
    let line = bad
        .lines()
        .position(|l| l.contains("element_9"))
        .expect("edited")
        + 1;
    let err = refused(&["import", path(&f)]);
    assert!(
        err.contains("names link `element_9`, which is not defined"),
        "{err}"
    );
    assert!(err.contains(&format!("bad.urdf:{line}:")), "{err}");
}

// ------------------------------------------------------------------------------------------
// Drake: drake:ball_constraint

#[test]
fn drake_strandbeest_at_drakes_assembled_pose_has_the_mobility_drake_finds() {
    // Drake's Strandbeest: 12 Jansen legs on one crank, 36 ball constraints, the crossbar a
    // free body. At zero joint positions the loops are open (Drake assembles them by inverse
    // kinematics); strandbeest_ik_poses.json is that solution, computed with Drake's own
    // parse of the file (pydrake 1.51.1), where its constraint Jacobian has 108 rows of rank
    // 72 over 79 velocities: 7 DOF (6 of the free crossbar, 1 of the crank), 36 redundant.
    let d = scratch("strandbeest");
    let (open, closed) = (d.join("open.toml"), d.join("closed.toml"));
    let err = import_to(&fixture("strandbeest_ball_constraints.urdf"), &open, &[]);
    assert_eq!(
        err.matches("drake:ball_constraint between").count(),
        36,
        "{err}"
    );
    assert!(
        err.contains("link `crossbar` is a second root: given a free (F) joint to `world`"),
        "{err}"
    );
    let toml = std::fs::read_to_string(&open).expect("imported");
    assert!(
        toml.contains("the link `world`, which the file does not define"),
        "{toml}"
    );
    let poses = fixture("strandbeest_ik_poses.json");
    let (code, out, err) = mbsa(&["assemble", path(&open), "--poses", &poses]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(&closed, out).expect("write");
    assert_eq!(rigid(path(&closed), &[]), (-29, 7, 36));
}

#[test]
fn a_ball_constraint_naming_a_missing_link_is_refused_where_it_is_named() {
    let d = scratch("ball_missing");
    let text =
        std::fs::read_to_string(fixture("strandbeest_ball_constraints.urdf")).expect("fixture");
    let bad = text.replacen(
        "<drake:ball_constraint_body_B name=\"pair01_leg1_bar_g\"/>",
        "<drake:ball_constraint_body_B name=\"no_such_bar\"/>",
        1,
    );
    assert_ne!(bad, text, "the fixture names pair01_leg1_bar_g");
    let f = d.join("bad.urdf");
    std::fs::write(&f, &bad).expect("write");
    let line = bad
        .lines()
        .position(|l| l.contains("no_such_bar"))
        .expect("edited")
        + 1;
    let err = refused(&["import", path(&f)]);
    assert!(err.contains("link `no_such_bar` is not defined"), "{err}");
    assert!(err.contains(&format!("bad.urdf:{line}:")), "{err}");
}

// ------------------------------------------------------------------------------------------
// URDF+: <constraint> and <loop>

#[test]
fn urdf_plus_planar_leg_linkage_has_two_dof() {
    // A hip and a parallelogram knee linkage closed by <constraint type="position">: 2 DOF
    // (hip and knee). URDF+ writes it at zero joint positions, every link on one line: a
    // singular pose with one more first-order freedom, which the finite test sets aside.
    let v = analyze(&fixture("urdfplus_planar_leg_linkage.urdf"), &[]);
    assert_eq!(v["finite"]["finite"], 2, "{v}");
    assert_eq!(v["finite"]["first_order"], 3, "{v}");
    let (code, toml, err) = mbsa(&["import", &fixture("urdfplus_planar_leg_linkage.urdf")]);
    assert_eq!(code, 0, "{err}");
    let cut = toml
        .split("id = \"linkage\"")
        .nth(1)
        .expect("the cut joint");
    assert!(cut.starts_with("\ntype = \"S\""), "{cut}");
}

#[test]
fn urdf_plus_loop_element_four_bar_has_one_dof() {
    // URDF+ 2.1: the four-bar's coupler joined to its rocker by <loop type="revolute">; a
    // parallelogram written flat (all joints on one line): 1 DOF, 2 to first order there.
    let v = analyze(&fixture("urdfplus_four_bar_loop.urdf"), &[]);
    assert_eq!(v["finite"]["finite"], 1, "{v}");
    assert_eq!(v["finite"]["first_order"], 2, "{v}");
    let (code, toml, _) = mbsa(&["import", &fixture("urdfplus_four_bar_loop.urdf")]);
    assert_eq!(code, 0);
    let cut = toml.split("id = \"loop1\"").nth(1).expect("the cut joint");
    assert!(cut.starts_with("\ntype = \"R\""), "{cut}");
    assert!(cut.contains("axis = [0, 0, 1]"), "{cut}");
}

#[test]
fn a_constraint_naming_a_missing_link_or_an_unknown_type_is_refused_where_it_is_written() {
    let d = scratch("constraint_errors");
    let text =
        std::fs::read_to_string(fixture("urdfplus_planar_leg_linkage.urdf")).expect("fixture");
    for (from, to, says) in [
        (
            "<successor link=\"shank_support\">",
            "<successor link=\"shank\">",
            "link `shank` is not defined",
        ),
        (
            "name=\"linkage\" type=\"position\"",
            "name=\"linkage\" type=\"weld\"",
            "has the unknown type `weld`",
        ),
    ] {
        let bad = text.replace(from, to);
        assert_ne!(bad, text, "{from}");
        let f = d.join("bad.urdf");
        std::fs::write(&f, &bad).expect("write");
        let line = bad.lines().position(|l| l.contains(to)).expect("edited") + 1;
        let err = refused(&["import", path(&f)]);
        assert!(err.contains(says), "{err}");
        assert!(err.contains(&format!("bad.urdf:{line}:")), "{err}");
    }
}

// ------------------------------------------------------------------------------------------
// Extended URDF: the YAML closure file beside the URDF

#[test]
fn extended_urdf_five_bar_reads_its_yaml_beside_it_and_has_two_dof() {
    // Gepetto's five-bar (one joint axis skewed: "iso3d"): its loop closed by a 3D contact
    // (a ball joint), two motors. Pinocchio, loading robot.urdf with the 3D contact of
    // robot.yaml: 5 velocities, 3 constraint rows of rank 3, so 2 DOF and 0 redundant. The
    // file's zero pose leaves the loop open by 4.3 mm: `mbsa assemble` closes it.
    let d = scratch("five_bar");
    let (open, closed) = (d.join("open.toml"), d.join("closed.toml"));
    let err = import_to(&fixture("five_bar_iso3d.urdf"), &open, &[]);
    assert!(err.contains("five_bar_iso3d.yaml:"), "{err}");
    assert!(
        err.contains("is not closed at this configuration (gap 4.295e-3)"),
        "{err}"
    );
    let toml = std::fs::read_to_string(&open).expect("imported");
    assert!(
        toml.contains("read from `tests/fixtures/import/five_bar_iso3d.yaml` (Extended URDF)"),
        "{toml}"
    );
    assert_eq!(toml.matches("driven = 1").count(), 2, "{toml}");
    let (code, out, err) = mbsa(&["assemble", path(&open)]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(&closed, out).expect("write");
    assert_eq!(rigid(path(&closed), &[]), (2, 2, 0));
    let v = analyze(path(&closed), &[]);
    assert_eq!(v["status"], "determined", "{v}");
    assert_eq!(v["mobility"]["inputs"], 2, "{v}");
    // Without its closure file the five-bar is two open chains: 5 DOF.
    let tree = d.join("tree.toml");
    import_to(&fixture("five_bar_iso3d.urdf"), &tree, &["--no-closures"]);
    assert_eq!(rigid(path(&tree), &[]), (5, 5, 0));
}

#[test]
fn extended_urdf_delta_welds_its_open_6d_cuts_where_they_close() {
    // Gepetto's planar delta: three 6D cuts (welds) that zero joint positions leave open by
    // 1 to 3 cm and up to pi rad. Pinocchio (PyPI `pin` 4.1.0), loading robot.urdf with the
    // three 6D contacts of robot.yaml and closing them by Gauss-Newton: 14 velocities, 18
    // rows of rank 9, so 5 DOF and 9 redundant. Welded as placed, the model had 5 proper
    // DOF and 3 not fixed by its 2 motors; welded where each cut puts it, the three sphere
    // links turn alone on their coaxial hinges and the 2 motors determine the rest.
    let d = scratch("delta");
    let (open, closed) = (d.join("open.toml"), d.join("closed.toml"));
    let err = import_to(&fixture("robot_delta.urdf"), &open, &[]);
    assert_eq!(
        err.matches("is welded where the cut puts it").count(),
        3,
        "{err}"
    );
    let (code, _, err) = mbsa(&["analyze", path(&open)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("is not assembled"), "{err}");
    let (code, out, err) = mbsa(&["assemble", path(&open)]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(&closed, out).expect("write");
    assert_eq!(rigid(path(&closed), &[]), (-4, 5, 9));
    let v = analyze(path(&closed), &[]);
    assert_eq!(v["status"], "determined", "{v}");
    assert_eq!(v["mobility"]["inputs"], 2, "{v}");
    let isolated: Vec<&str> = v["isolated"]
        .as_array()
        .expect("isolated")
        .iter()
        .filter_map(|i| i["body"].as_str())
        .collect();
    assert_eq!(isolated, ["sphere_2", "sphere_5", "sphere_6"], "{v}");
}

#[test]
fn digit_like_leg_transform_cuts_the_placements_that_drive_a_rod_spin() {
    // Gepetto's Digit-like leg: 6 motors, three rods each between two spherical joints
    // written as three revolutes, closed by 6D cuts. Assembled, the count is 9, of which the
    // three rod spins turn alone: 6 inputs. The search's first count-valid placements put
    // their inputs on the rods' revolutes (every one of the first 500 drove one motion twice
    // or a spin, none was determined, and the whole search ran past 120 s); now it cuts
    // those branches, and each placement it reaches is determined.
    let d = scratch("digit_like");
    let (open, closed) = (d.join("open.toml"), d.join("closed.toml"));
    import_to(&fixture("digit_like.urdf"), &open, &[]);
    let (code, out, err) = mbsa(&["assemble", path(&open)]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(&closed, out).expect("write");
    let v = analyze(path(&closed), &[]);
    assert_eq!(v["status"], "determined", "{v}");
    let t = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["transform", path(&closed), "--format", "json"];
        args.extend_from_slice(extra);
        let (code, out, err) = mbsa(&args);
        assert_eq!(code, 0, "{err}");
        serde_json::from_str(&out).expect("json")
    };
    let five = t(&["--limit", "5"]);
    assert_eq!(five["summary"]["determined"], 5, "{}", five["summary"]);
    assert_eq!(
        five["summary"]["excluded_by_rank"], 0,
        "{}",
        five["summary"]
    );
    // The whole search: every placement reached is determined, the file's own among them.
    let all = t(&[]);
    let s = &all["summary"];
    assert_eq!(s["excluded_by_rank"], 0, "{s}");
    assert_eq!(s["determined"], s["count_valid"], "{s}");
    assert!(s["determined"].as_u64().is_some_and(|n| n >= 100), "{s}");
    assert!(
        all["original_rank"].as_u64().is_some(),
        "{}",
        all["original_rank"]
    );
}

#[test]
fn the_closure_file_can_be_named_and_counts_against_the_input_limit() {
    let d = scratch("named");
    let yaml = d.join("loops.yaml");
    std::fs::copy(fixture("five_bar_iso3d.yaml"), &yaml).expect("copy");
    let urdf = d.join("five_bar.urdf");
    std::fs::copy(fixture("five_bar_iso3d.urdf"), &urdf).expect("copy");
    // Not beside it under its name: no closure unless named.
    let (code, out, _) = mbsa(&["mobility", path(&urdf), "--format", "json"]);
    assert_eq!(code, 0);
    assert!(out.contains("\"count\": 5"), "{out}");
    let (code, out, err) = mbsa(&[
        "mobility",
        path(&urdf),
        "--closures",
        path(&yaml),
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\"count\": 2"), "{out}");
    let urdf_len = std::fs::metadata(&urdf).expect("size").len();
    let limit = (urdf_len + 100).to_string();
    let err = refused(&[
        "import",
        path(&urdf),
        "--closures",
        path(&yaml),
        "--max-input-bytes",
        &limit,
    ]);
    assert!(err.contains("needs 1861 bytes"), "{err}");
    let err = refused(&[
        "import",
        path(&urdf),
        "--closures",
        path(&d.join("none.yaml")),
    ]);
    assert!(err.contains("cannot read the closure file"), "{err}");
}

#[test]
fn a_closure_file_naming_a_missing_frame_or_malformed_is_refused_where_it_is_written() {
    let d = scratch("yaml_errors");
    std::fs::copy(fixture("five_bar_iso3d.urdf"), d.join("robot.urdf")).expect("copy");
    let text = std::fs::read_to_string(fixture("five_bar_iso3d.yaml")).expect("fixture");
    let header = text.lines().take_while(|l| l.starts_with('#')).count();
    for (from, to, says, label) in [
        (
            "'closedloop3D_1A']]",
            "'closedloop3D_9A']]",
            "frame `closedloop3D_9A` is neither a joint nor a link",
            "no such frame",
        ),
        (
            "['3d']",
            "['5d']",
            "loop type `5d` is neither 3d nor 6d",
            "unknown type",
        ),
        (
            "'mot1']",
            "'mot9']",
            "`name_mot` names joint `mot9`",
            "no such joint",
        ),
        (
            "[['closedloop3D_1B'",
            "[['closedloop3D_1B' 'x'",
            "malformed YAML",
            "here",
        ),
        (
            "type: ['3d']",
            "type: ['3d', '3d']",
            "`type` has 2 item(s) but `closed_loop` has 1",
            "length differs",
        ),
    ] {
        let bad = text.replace(from, to);
        assert_ne!(bad, text, "{from}");
        std::fs::write(d.join("robot.yaml"), &bad).expect("write");
        let line = bad.lines().position(|l| l.contains(to)).expect("edited") + 1;
        assert!(line > header);
        let err = refused(&["import", path(&d.join("robot.urdf"))]);
        assert!(err.contains(says), "{err}");
        assert!(err.contains(label), "{err}");
        assert!(err.contains(&format!("robot.yaml:{line}:")), "{err}");
    }
}
