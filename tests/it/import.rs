//! `mbsa import` and the analysing commands on simulator model files (MJCF, URDF, SDFormat,
//! OpenSim), through the real binary. The real models in tests/fixtures/import/ come from
//! public repositories (README.md there names them); the numbers checked are what their own
//! engines or documentation state.

use assert_cmd::Command;

const FIX: &str = "tests/fixtures/import";

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

fn snapshot(name: &str, value: &str) {
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!(name, value);
    });
}

fn fixture(name: &str) -> String {
    format!("{FIX}/{name}")
}

/// `mbsa rigid --format json` of a file (extra arguments appended): the geometric part.
fn rigid(file: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["rigid", file, "--format", "json"];
    args.extend_from_slice(extra);
    let (code, out, err) = mbsa(&args);
    assert_eq!(code, 0, "{file}: {err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("rigid emits JSON");
    v["geometric"].clone()
}

/// (count, true mobility, redundant) of the geometric analysis.
fn numbers(file: &str, extra: &[&str]) -> (i64, i64, i64) {
    let g = rigid(file, extra);
    (
        g["count"].as_i64().expect("count"),
        g["mobility"].as_i64().expect("mobility"),
        g["redundant"].as_i64().expect("redundant"),
    )
}

/// Import `file` to a temporary TOML and check that both give the same analyses.
fn round_trip(file: &str, extra: &[&str]) -> String {
    let dir = std::env::temp_dir().join(format!("mbsa-import-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let stem = std::path::Path::new(file)
        .file_stem()
        .and_then(|s| s.to_str())
        .expect("stem");
    let out = dir.join(format!("{stem}-{}.toml", extra.join("_")));
    let out_s = out.to_str().expect("utf-8 path");
    let mut args = vec!["import", file, "-o", out_s];
    args.extend_from_slice(extra);
    let (code, _, err) = mbsa(&args);
    assert_eq!(code, 0, "{err}");
    let toml = std::fs::read_to_string(&out).expect("written");
    let mut from_source = rigid(file, extra);
    let mut from_toml = rigid(out_s, &[]);
    // Loop names mention the same joints; everything must agree.
    from_source["name"] = serde_json::Value::Null;
    from_toml["name"] = serde_json::Value::Null;
    assert_eq!(
        from_source, from_toml,
        "{file}: import output analyses differently"
    );
    for cmd in ["analyze", "mobility"] {
        let (c1, a, e1) = mbsa(&[cmd, file, "--format", "json"]);
        let (c2, b, e2) = mbsa(&[cmd, out_s, "--format", "json"]);
        assert_eq!((c1, c2), (0, 0), "{e1}{e2}");
        if extra.is_empty() {
            assert_eq!(a, b, "{cmd} {file}");
        }
    }
    toml
}

// ------------------------------------------------------------------------------------------
// MJCF

#[test]
fn cassie_at_qpos0_has_count_20_true_mobility_22_and_2_redundant() {
    // MuJoCo's constraint Jacobian at qpos0: 12 rows (4 connects), rank 10.
    assert_eq!(numbers(&fixture("cassie.xml"), &[]), (20, 22, 2));
    let (code, out, err) = mbsa(&["mobility", &fixture("cassie.xml"), "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(v["mobility"]["inputs"], 10, "{out}");
}

#[test]
fn cassie_import_snapshot_and_round_trip() {
    let toml = round_trip(&fixture("cassie.xml"), &[]);
    snapshot("import_cassie", &toml);
}

#[test]
fn cassie_home_keyframe_says_the_loops_do_not_close() {
    let (code, out, err) = mbsa(&["import", &fixture("cassie.xml"), "--keyframe", "home"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        err.matches("is not closed at this configuration").count(),
        4,
        "{err}"
    );
    assert!(out.contains("# Configuration: keyframe `home`"), "{out}");
    round_trip(&fixture("cassie.xml"), &["--keyframe", "home"]);
    let (code, _, err) = mbsa(&["import", &fixture("cassie.xml"), "--keyframe", "walk"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("no keyframe `walk`") && err.contains("`home`"),
        "{err}"
    );
}

#[test]
fn robotiq_2f85_two_planar_five_bars_closed_by_connect() {
    // Each finger: driver, coupler, spring link and follower on parallel x axes, the loop
    // closed by a `connect` (S) whose x equation the planar loop already satisfies. Per
    // finger count 6·4 − 4·5 − 3 = 1, true mobility 2 (a planar five-bar: the adaptive
    // finger), 1 redundant. MuJoCo 4.0.1 at qpos0: 6 connect rows on 8 DOF, rank 4 (the x
    // rows vanish); the drivers' joint equality (not representable) would leave 3.
    let file = fixture("robotiq_2f85.xml");
    assert_eq!(numbers(&file, &[]), (2, 4, 2));
    let (code, _, err) = mbsa(&["import", &file]);
    assert_eq!(code, 0, "{err}");
    // The driver coupling and the tendon actuator are reported, never dropped silently.
    assert!(
        err.contains("<joint> equality coupling: not representable"),
        "{err}"
    );
    assert!(err.contains("acts through tendon"), "{err}");
    assert!(err.contains("0 driven DOF"), "{err}");
    let analyze = |inputs: &str| {
        let (code, out, err) = mbsa(&["analyze", &file, "--inputs", inputs, "--format", "json"]);
        assert_eq!(code, 0, "{inputs}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).expect("json");
        (
            v["status"].as_str().expect("status").to_string(),
            v["uncontrolled"].as_i64().expect("uncontrolled"),
            v["groups"].as_array().expect("groups").len(),
        )
    };
    // The two drivers leave each finger's adaptive DOF free.
    assert_eq!(
        analyze("right_driver_joint,left_driver_joint"),
        ("underdetermined".into(), 2, 2)
    );
    let grounded =
        "right_driver_joint,left_driver_joint,right_spring_link_joint,left_spring_link_joint";
    assert_eq!(analyze(grounded), ("determined".into(), 0, 6));
    // The loop-closing joint is named by its imported id, `:` and all.
    assert_eq!(
        analyze(
            "connect:right_follower-right_coupler,right_driver_joint,left_driver_joint,left_spring_link_joint"
        ),
        ("determined".into(), 0, 5)
    );
    let (code, out, err) = mbsa(&["transform", &file, "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    let s = &v["summary"];
    // Per finger 11 placements of 2 DOF on 4 R and 1 S (driven about world x, then y) pass
    // the count; the S driven twice is not determined (its turn about y is locked, so a
    // freedom stays free), and the search cuts it: 10 per finger examined, all determined.
    assert_eq!(
        (
            &s["f"],
            &s["count_valid"],
            &s["excluded_by_rank"],
            &s["determined"]
        ),
        (&4.into(), &100.into(), &0.into(), &100.into()),
        "{s}"
    );
    assert!(
        s["notes"][0]
            .as_str()
            .is_some_and(|n| n.contains("the search cut 11 branch(es)")),
        "{s}"
    );
    // The source's numbers are known to ±5e-6 (pad pos 0.01352); the composed world
    // coordinates (0.1092 and the like) must not be judged by their own digits (±5e-5, which
    // made the grounded fingers look near-singular).
    let (code, out, err) = mbsa(&["import", &file]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\nprecision = 5e-6\n"), "{out}");
    let (code, out, err) = mbsa(&[
        "rigid",
        &file,
        "--inputs",
        grounded,
        "--with-inputs",
        "--method",
        "geometric",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("true mobility 0"), "{out}");
    assert!(!out.contains("ill-conditioned"), "{out}");
    let toml = round_trip(&file, &[]);
    snapshot("import_robotiq_2f85", &toml);
}

#[test]
fn tilted_four_bar_is_judged_by_its_source_precision() {
    // A planar four-bar written tilted in space with CAD-style 6-decimal quaternions, its
    // loop closed by a `connect`: the composed hinge axes differ by about 1e-6. Judged by the
    // importer's 10-decimal output (±5e-10) the loop looked spatial and rigid; the source's
    // own rounding (the `precision` the import writes) keeps it a planar 1-DOF loop.
    let file = fixture("tilted_fourbar.xml");
    let (code, out, err) = mbsa(&["import", &file]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\nprecision = 5e-6\n"), "{out}");
    assert_eq!(numbers(&file, &["--geometry", "file"]), (0, 1, 1));
    let (code, out, err) = mbsa(&[
        "analyze",
        &file,
        "--inputs",
        "A",
        "--geometry",
        "file",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(v["status"], "determined", "{out}");
    // `--tolerance` still overrides the file's precision.
    assert_eq!(
        numbers(&file, &["--geometry", "file", "--tolerance", "5e-10"]),
        (0, 0, 0)
    );
    round_trip(&file, &[]);
}

#[test]
fn mjcf_includes_resolve_relative_to_the_model() {
    let (code, out, err) = mbsa(&["import", &fixture("include_main.xml")]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("include_forearm.xml:3:5"), "{out}");
    assert!(out.contains("axis = [0, 1, 0]"), "{out}");
    let (code, _, err) = mbsa(&["import", &fixture("include_missing.xml")]);
    assert_eq!(code, 2);
    snapshot("import_error_missing_include", &err.replace('\\', "/"));
}

#[test]
fn analysing_commands_read_models_directly() {
    let (code, out, err) = mbsa(&["analyze", &fixture("include_main.xml")]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("included-pendulum"), "{out}");
    // Forcing the format of a file with another extension, and standard input.
    let dir = std::env::temp_dir().join(format!("mbsa-import-from-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let txt = dir.join("model.txt");
    std::fs::copy(fixture("cassie.xml"), &txt).expect("copy");
    let (code, _, err) = mbsa(&["mobility", txt.to_str().expect("utf-8"), "--from", "mjcf"]);
    assert_eq!(code, 0, "{err}");
    let out = Command::cargo_bin("mbsa")
        .expect("bin")
        .args(["mobility", "-"])
        .write_stdin(std::fs::read(fixture("cassie.xml")).expect("read"))
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn import_errors_are_located_with_exit_code_2() {
    let dir = std::env::temp_dir().join(format!("mbsa-import-err-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let cases = [
        (
            "malformed.xml",
            "<mujoco>\n  <worldbody>\n    <body name=\"a\">\n</mujoco>\n",
        ),
        (
            "bad_quat.xml",
            "<mujoco>\n  <worldbody>\n    <body name=\"a\" quat=\"1 0 zero 0\">\n      <joint/>\n    </body>\n  </worldbody>\n</mujoco>\n",
        ),
        (
            "robot.urdf.xacro",
            "<robot xmlns:xacro=\"http://www.ros.org/wiki/xacro\" name=\"r\">\n  <xacro:macro name=\"m\"/>\n</robot>\n",
        ),
        ("unknown_root.xml", "<scene>\n  <thing/>\n</scene>\n"),
    ];
    for (name, text) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write");
        let (code, out, err) = mbsa(&["import", path.to_str().expect("utf-8")]);
        assert_eq!(code, 2, "{name}: {out}{err}");
        assert!(out.is_empty());
        let shown = err.replace(dir.to_str().expect("utf-8"), "<dir>");
        snapshot(&format!("import_error_{}", name.replace('.', "_")), &shown);
    }
}

// ------------------------------------------------------------------------------------------
// URDF

#[test]
fn ur5_is_a_six_dof_serial_arm() {
    // A tree: every joint needs its input; the fixed joints merge world/base_link and link6/ee_link.
    assert_eq!(numbers(&fixture("ur5.urdf"), &[]), (6, 6, 0));
    let toml = round_trip(&fixture("ur5.urdf"), &[]);
    snapshot("import_ur5", &toml);
}

#[test]
fn gazebo_four_bar_urdf_closed_by_a_gazebo_joint() {
    // The tutorial's four-bar split at E and welded back: 1 DOF, written in 3D.
    assert_eq!(
        numbers(&fixture("four_bar_split_fixed.urdf"), &[]),
        (-2, 1, 3)
    );
    round_trip(&fixture("four_bar_split_fixed.urdf"), &[]);
}

// ------------------------------------------------------------------------------------------
// SDFormat

#[test]
fn gazebo_four_bar_sdf_has_1_dof_count_minus_2_and_3_redundant() {
    assert_eq!(numbers(&fixture("four_bar.sdf"), &[]), (-2, 1, 3));
    let toml = round_trip(&fixture("four_bar.sdf"), &[]);
    snapshot("import_four_bar_sdf", &toml);
}

#[test]
fn merge_pins_turns_two_coaxial_joints_into_one_multiple_joint() {
    let file = fixture("triple_pin.sdf");
    let (code, out, err) = mbsa(&["import", &file, "--merge-pins"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("1 pin joint(s) merged"), "{err}");
    assert!(
        out.contains("bodies = [\"link_BC\", \"link_CD\", \"link_CE\"]"),
        "{out}"
    );
    let (code, out, _) = mbsa(&["import", &file]);
    assert_eq!(code, 0);
    assert_eq!(out.matches("[[joint]]").count(), 7);
    // A planar Watt six-bar written in 3D: 1 DOF either way.
    assert_eq!(numbers(&file, &[]), (-5, 1, 6));
    assert_eq!(numbers(&file, &["--merge-pins"]), (-5, 1, 6));
    round_trip(&file, &["--merge-pins"]);
}

/// Gepetto's Disney-like leg (Onshape) writes each ball joint as three revolute joints through
/// two intermediate links. As written, the rods between two such balls spin with their
/// intermediate links, so no spin is isolated and `transform` places 9 inputs; with
/// `--merge-balls` the five triples are S joints, the rods' 2 spins are isolated and 7 inputs
/// place it (as its motors and the legs' joints need), at the same mobility, 9.
#[test]
fn merge_balls_turns_three_concurrent_pins_into_one_ball() {
    let file = fixture("disney_like.urdf");
    let (code, out, err) = mbsa(&["import", &file, "--merge-balls"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains(
            "15 bodies, 17 joints, 6 driven DOF; 5 ball joint(s) made of revolute triples"
        ),
        "{err}"
    );
    assert!(out.contains("--merge-balls: 5 ball joint(s) written as three revolute joints"));
    assert_eq!(out.matches("type = \"S\"").count(), 5, "{out}");
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("merge_balls");
    std::fs::create_dir_all(&dir).expect("writable");
    let mut seen = Vec::new();
    for opts in [&[][..], &["--merge-balls"][..]] {
        let (code, closed, err) = mbsa(&[&["assemble", file.as_str()][..], opts].concat());
        assert_eq!(code, 0, "{err}");
        let path = dir.join(format!("closed{}.toml", opts.len()));
        std::fs::write(&path, closed).expect("writable");
        let path = path.to_str().expect("UTF-8");
        let (code, out, err) = mbsa(&["rigid", path, "--method", "geometric", "--format", "json"]);
        assert_eq!(code, 0, "{err}");
        let r: serde_json::Value = serde_json::from_str(&out).expect("JSON");
        let (code, out, err) = mbsa(&["transform", path, "--limit", "5", "--format", "json"]);
        assert_eq!(code, 0, "{err}");
        let t: serde_json::Value = serde_json::from_str(&out).expect("JSON");
        seen.push((
            r["bodies"].as_u64(),
            r["mobility"].as_u64(),
            r["isolated"].as_u64(),
            t["summary"]["f"].as_i64(),
        ));
    }
    assert_eq!(
        seen,
        [
            (Some(25), Some(9), Some(0), Some(9)),
            (Some(15), Some(9), Some(2), Some(7))
        ]
    );
}

// ------------------------------------------------------------------------------------------
// OpenSim

#[test]
fn opensim_double_pendulum_is_two_driven_pins() {
    assert_eq!(numbers(&fixture("double_pendulum.osim"), &[]), (2, 2, 0));
    let toml = round_trip(&fixture("double_pendulum.osim"), &[]);
    assert_eq!(toml.matches("driven = 1").count(), 2, "{toml}");
    snapshot("import_double_pendulum_osim", &toml);
}

#[test]
fn opensim_four_bar_closed_by_a_point_constraint_has_1_dof() {
    // Planar four-bar written in 3D with an S closure: count 0, 1 DOF, 1 redundant.
    assert_eq!(
        numbers(&fixture("four_bar_point_constraint.osim"), &[]),
        (0, 1, 1)
    );
    let (code, out, err) = mbsa(&["import", &fixture("four_bar_point_constraint.osim")]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("# <PointConstraint name=\"C\"> (loop closure)"),
        "{out}"
    );
    assert!(
        err.contains("CoordinateCouplerConstraint `couple` couples coordinates: not representable"),
        "{err}"
    );
    round_trip(&fixture("four_bar_point_constraint.osim"), &[]);
}

/// `analyze --format json` of `file` with `inputs`: (status, types of the groups in order).
fn group_types(file: &str, inputs: &str) -> (String, Vec<(String, bool)>) {
    let (code, out, err) = mbsa(&["analyze", file, "--inputs", inputs, "--format", "json"]);
    assert_eq!(code, 0, "{inputs}: {err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    let types = v["groups"]
        .as_array()
        .expect("groups")
        .iter()
        .map(|g| {
            (
                g["type"].as_str().expect("type").to_string(),
                g["in_library"].as_bool().expect("in_library"),
            )
        })
        .collect();
    (v["status"].as_str().expect("status").to_string(), types)
}

#[test]
fn robotiq_coupler_follower_group_is_typed_as_the_planar_dyad_it_is() {
    // The coupler and the follower hang on the driver and the spring link by R joints on
    // parallel x axes and meet at the `connect` (S). The R joints keep both bodies in the
    // plane, so the S's turns about y and z are locked and it acts as a pin: the group is a
    // planar RRR dyad (3R2D, in the built-in library), not a spatial 2R1S3D.
    let file = fixture("robotiq_2f85.xml");
    let grounded =
        "right_driver_joint,left_driver_joint,right_spring_link_joint,left_spring_link_joint";
    let (status, types) = group_types(&file, grounded);
    assert_eq!(status, "determined");
    let dyads: Vec<_> = types.iter().filter(|(t, _)| t != "1R3D").collect();
    assert_eq!(
        dyads,
        [&("3R2D".to_string(), true), &("3R2D".to_string(), true)],
        "{types:?}"
    );
}

#[test]
fn xarm_gripper_fingers_are_parallelograms_closed_by_connect() {
    // UFACTORY xArm gripper (MuJoCo Menagerie): per finger outer knuckle (driver), finger,
    // inner knuckle on parallel x axes, the finger and inner knuckle joined by a `connect`.
    // Its pivots form a parallelogram (knuckles both (0, ±0.035465, 0.042039) long, base and
    // finger pivots both (0, ±0.015, 0.015) apart): per finger count 6·3 − 3·5 − 3 = 0, true
    // mobility 1, 1 redundant (the S's x row); the drivers determine it.
    let file = fixture("xarm7_hand.xml");
    assert_eq!(numbers(&file, &[]), (0, 2, 2));
    let (status, types) = group_types(&file, "left_driver_joint,right_driver_joint");
    assert_eq!(status, "determined");
    let names: Vec<&str> = types.iter().map(|(t, _)| t.as_str()).collect();
    assert_eq!(names, ["1R3D", "1R3D", "3R2D", "3R2D"], "{types:?}");
    // Driving the left outer knuckle 20°: the finger translates (a parallelogram's coupler),
    // so the inner knuckle turns 20° too and the finger turns back 20° on its knuckle.
    let (code, out, err) = mbsa(&[
        "solve",
        &file,
        "--inputs",
        "left_driver_joint,right_driver_joint",
        "--set",
        "left_driver_joint=20",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    let value = |joint: &str| {
        v["joint_values"]
            .as_array()
            .expect("joint_values")
            .iter()
            .find(|j| j["joint"] == joint)
            .and_then(|j| j["values"][0].as_f64())
            .unwrap_or(f64::NAN)
    };
    for (joint, deg) in [
        ("left_inner_knuckle_joint", 20.0),
        ("left_finger_joint", 20.0),
        ("right_driver_joint", 0.0),
        ("right_finger_joint", 0.0),
    ] {
        let got = value(joint);
        assert!((got - deg).abs() < 1e-6, "{joint}: {got} ({out})");
    }
}

#[test]
fn solve_takes_the_inputs_analyze_takes() {
    // The gripper's file drives nothing (its actuator acts through a tendon): `--inputs`
    // chooses the inputs for the groups, the undriven ones held at the file's value.
    let file = fixture("robotiq_2f85.xml");
    let grounded =
        "right_driver_joint,left_driver_joint,right_spring_link_joint,left_spring_link_joint";
    let (code, out, err) = mbsa(&[
        "solve",
        &file,
        "--inputs",
        grounded,
        "--set",
        "right_driver_joint=10",
    ]);
    assert_eq!(code, 0, "{err}");
    // Six groups, every step determined (nullity 0), the spring links held.
    assert!(out.contains("(6 step(s))"), "{out}");
    assert!(!out.contains(" rest "), "{out}");
    let held = out
        .lines()
        .find(|l| l.trim_start().starts_with("right_spring_link_joint "))
        .unwrap_or_default();
    assert!(held.contains(" 0° "), "{held}");
    // An unknown joint in `--inputs` is an input error, as for analyze.
    let (code, _, err) = mbsa(&["solve", &file, "--inputs", "no_such_joint"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no_such_joint"), "{err}");
}

/// The widest line of a report's tables (their rows start with a space or a rule).
fn table_width(out: &str) -> usize {
    out.lines()
        .filter(|l| l.starts_with(' ') || l.starts_with('─'))
        .map(|l| l.trim_end().chars().count())
        .max()
        .unwrap_or(0)
}

#[test]
fn transform_tables_with_long_joint_ids_fit_120_columns() {
    // Imported ids are long (`connect:right_follower-right_coupler`) and every input is
    // written `id (pair)`: the ranked table was about 290 columns wide. Its lists are now
    // broken into lines, every input still written in full.
    let file = fixture("robotiq_2f85.xml");
    let (code, out, err) = mbsa(&["transform", &file]);
    assert_eq!(code, 0, "{err}");
    let widest = table_width(&out);
    assert!(widest <= 120, "{widest} columns:\n{out}");
    for id in [
        "connect:right_follower-right_coupler",
        "(right_follower-right_coupler)",
        "left_spring_link_joint",
        "(world-left_spring_link)",
    ] {
        assert!(out.contains(id), "{id}: {out}");
    }
    let grounded =
        "right_driver_joint,left_driver_joint,right_spring_link_joint,left_spring_link_joint";
    let (code, out, err) = mbsa(&["transform", &file, "--inputs", grounded]);
    assert_eq!(code, 0, "{err}");
    let widest = table_width(&out);
    assert!(widest <= 120, "{widest} columns:\n{out}");
    assert!(out.contains("(world-right_spring_link)"), "{out}");
}

#[test]
fn stewart_upu_platform_has_its_yaw_locked_and_six_pistons_fight() {
    // daniel-s-ingram/stewart: six legs, each base-R(a)-R(b)-P-R(b)-R(a)-platform with a and
    // b horizontal: every leg's constraint is a couple about the vertical, the same for all
    // six. The base is free in the model (6). Fixed base: count 0, true mobility 5 (the
    // platform cannot turn about z), 5 redundant; an independent first-order computation
    // from the SDF poses (numpy) gives the same, and that 5 pistons determine it while 6
    // over-determine it by one equation.
    let file = fixture("stewart_upu.sdf");
    assert_eq!(numbers(&file, &[]), (6, 11, 5));
    let five = "piston1_prismatic_joint,piston2_prismatic_joint,piston3_prismatic_joint,\
                piston4_prismatic_joint,piston5_prismatic_joint,base_link:free:6";
    let (status, _) = group_types(&file, five);
    assert_eq!(status, "determined");
    let six = format!("{five},piston6_prismatic_joint");
    let (code, out, err) = mbsa(&["analyze", &file, "--inputs", &six, "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(v["status"], "overdetermined", "{out}");
}

#[test]
fn stewart_upu_as_published_imports_with_a_warning_on_its_prologue() {
    // Published with `<? xml version="1.0" ?>` (a space after `<?`): not well-formed, but
    // Gazebo's tinyxml2 reads it. mbsa used to stop with "malformed XML" at 1:3.
    let file = fixture("stewart_upu.sdf");
    let text = std::fs::read_to_string(&file).expect("fixture");
    assert!(
        text.starts_with("<? xml version=\"1.0\" ?>\n"),
        "as published"
    );
    let (code, out, err) = mbsa(&["import", &file]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: 2 SDFormat import warning(s):")
            && err.contains("stewart_upu.sdf:1:1: `<? xml version=\"1.0\" ?>` is not a well-formed XML declaration"),
        "{err}"
    );
    // Its controller plugin, the other warning, is located in the file's own lines too.
    assert!(
        err.contains("stewart_upu.sdf:33:2: <plugin> `joint_controller`"),
        "{err}"
    );
    assert!(out.contains("# warning: stewart_upu.sdf:1:1:"), "{out}");
    // Locations after it are the file's own lines.
    let line = text
        .lines()
        .position(|l| l.contains("<joint") && l.contains("\"piston1_prismatic_joint\""))
        .expect("joint")
        + 1;
    assert!(out.contains(&format!("stewart_upu.sdf:{line}:")), "{out}");
}

/// OpenSim writes some elements as `Class::Property` (`<HuntCrossleyForce::ContactParametersSet>`
/// in eight models of opensim-org/opensim-models, the DynamicJumper and the Walker among them):
/// read, where they were refused as "malformed XML: invalid name token".
#[test]
fn opensim_elements_named_class_and_property_are_read() {
    let text = std::fs::read_to_string(fixture("double_pendulum.osim")).expect("fixture");
    let force = "<ForceSet><objects><HuntCrossleyForce name=\"foot\">\
                 <HuntCrossleyForce::ContactParametersSet name=\"contact_parameters\"><objects>\
                 <HuntCrossleyForce::ContactParameters><stiffness>1e8</stiffness>\
                 </HuntCrossleyForce::ContactParameters></objects>\
                 </HuntCrossleyForce::ContactParametersSet></HuntCrossleyForce></objects>\
                 </ForceSet>\n";
    let at = text.rfind("</Model>").expect("a Model element");
    let with = format!("{}{force}{}", &text[..at], &text[at..]);
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("import");
    std::fs::create_dir_all(&dir).expect("writable");
    let file = dir.join("qualified.osim");
    std::fs::write(&file, with).expect("writable");
    let file = file.to_str().expect("UTF-8");
    assert_eq!(numbers(file, &[]), (2, 2, 0));
    // Locations after the renamed tags are unchanged.
    let head = format!("{}{force}", &text[..at]);
    let line = head.matches('\n').count() + 1;
    let broken = dir.join("qualified-broken.osim");
    std::fs::write(&broken, format!("{head}<oops a=>\n{}", &text[at..])).expect("writable");
    let (code, _, err) = mbsa(&["mobility", broken.to_str().expect("UTF-8")]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("qualified-broken.osim:{line}:")),
        "{line}: {err}"
    );
}
