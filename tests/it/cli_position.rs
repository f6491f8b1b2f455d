//! `mbsa solve` and `mbsa assemble` through the real binary: outputs, sweeps that stop at a
//! dead point, exit codes and messages for bad input, closing a configuration.

use assert_cmd::Command;

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

#[test]
fn slider_crank_sweep_is_the_closed_form() {
    let (code, out, err) = mbsa(&["solve", "@slider-crank-geometry", "--sweep", "O=0..360:30"]);
    assert_eq!(code, 0, "{err}");
    snapshot("solve_slider-crank-geometry_sweep", &out);
    // At O = 90 (crank at 180 degrees) the piston is at 0.2062 - 0.05 = 0.1562 from the
    // origin: it moved by 0.2 - 0.15616 = 0.043845 toward the crank (S measures the frame
    // relative to the piston, so positive).
    assert!(
        out.lines()
            .any(|l| l.trim_start().starts_with("90 ") && l.contains("0.043845")),
        "{out}"
    );
}

#[test]
fn solve_json_and_table() {
    let (code, out, err) = mbsa(&["solve", "@slider-crank-geometry", "--set", "O=30"]);
    assert_eq!(code, 0, "{err}");
    snapshot("solve_slider-crank-geometry_30", &out);
    let (code, out, _) = mbsa(&[
        "solve",
        "@slider-crank-geometry",
        "--set",
        "O=0.5236rad",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["method"], "groups");
    assert_eq!(v["steps"].as_array().unwrap().len(), 2);
    let slider = v["poses"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["body"] == "slider")
        .unwrap();
    assert!((slider["translation"][0].as_f64().unwrap() + 0.023444).abs() < 1e-5);
}

#[test]
fn a_step_with_freedoms_no_input_fixes_is_named() {
    // The pendulum's joint is not driven: its bar stays at the file's pose, which no input
    // chose, and the report says so (a solve of an under-driven robot read "solved" alone).
    for extra in [&[][..], &["--global"][..]] {
        let mut args = vec!["solve", "@pendulum"];
        args.extend_from_slice(extra);
        let (code, out, err) = mbsa(&args);
        assert_eq!(code, 0, "{err}");
        assert!(
            out.contains(
                "leaves 1 freedom(s) that neither its equations nor the inputs fix (bodies 2)"
            ),
            "{out}"
        );
    }
    // Driven, it has none.
    let (code, out, err) = mbsa(&["solve", "@pendulum-driven", "--set", "O=30"]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("freedom(s)"), "{out}");
}

/// Where a step's freedoms are exactly the isolated spins `analyze` finds (the double
/// banana's bars), the note names those bodies and says they are harmless, instead of every
/// body of the step with "an isolated spin is harmless; otherwise drive a joint there"; where
/// there are more, the general note stays.
#[test]
fn freedoms_that_are_isolated_spins_are_named_as_such() {
    let (code, out, err) = mbsa(&["solve", "@rig-double-banana"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains(
            "note: step SG-III leaves 3 freedom(s) that neither its equations nor the inputs \
             fix: the isolated freedoms of AG, BG, FG (each turns one body alone, moving no \
             other), which take the pose of least change, not one an input chose; harmless."
        ),
        "{out}"
    );
    // SG-I's 9 freedoms are more than its bars' 8 spins (the bananas' hinge): the general
    // note stays.
    assert!(
        out.contains(
            "note: step SG-I leaves 9 freedom(s) that neither its equations nor the inputs fix \
             (bodies AD,"
        ),
        "{out}"
    );
}

#[test]
fn global_and_groups_agree_on_the_bennett() {
    let (c1, g, _) = mbsa(&["solve", "@rig-bennett", "--set", "A=25", "--format", "json"]);
    let (c2, w, _) = mbsa(&[
        "solve",
        "@rig-bennett",
        "--set",
        "A=25",
        "--format",
        "json",
        "--global",
    ]);
    assert_eq!((c1, c2), (0, 0));
    let pg: serde_json::Value = serde_json::from_str(&g).unwrap();
    let pw: serde_json::Value = serde_json::from_str(&w).unwrap();
    assert_eq!(pg["poses"], pw["poses"]);
}

#[test]
fn sweep_stops_at_the_dead_point_naming_the_group() {
    // The planar four-bar in 3D is a triple rocker: the crank cannot pass about 50 degrees.
    let (code, out, err) = mbsa(&["solve", "@rig-planar-four-bar-3d", "--sweep", "A=0..90:15"]);
    assert_eq!(code, 1, "{out}");
    assert!(err.contains("stopped between A=45 and A=60"), "{err}");
    assert!(err.contains("group SG-II (bodies {3, 4})"), "{err}");
    assert!(out.contains(" 45 "), "{out}");
}

#[test]
fn bad_inputs_exit_2_with_the_reason() {
    for (args, needle) in [
        (vec!["--set", "Q=3"], "matches no joint"),
        (vec!["--set", "O=3x"], "not a number"),
        (vec!["--set", "S=2rad"], "is a slide"),
        (vec!["--set", "O=1,2"], "1 DOF but 2 value(s)"),
        (vec!["--sweep", "O=0..10:0"], "STEP is zero"),
        (vec!["--sweep", "O=0..10"], "FROM..TO:STEP"),
    ] {
        let mut a = vec!["solve", "@slider-crank-geometry"];
        a.extend(args);
        let (code, _, err) = mbsa(&a);
        assert_eq!(code, 2, "{a:?}: {err}");
        assert!(err.contains(needle), "{a:?}: {err}");
    }
    let (code, _, err) = mbsa(&["solve", "@four-bar"]);
    assert_eq!(code, 2);
    assert!(err.contains("needs `origin`"), "{err}");
    // Out of reach: the rocker of the triple rocker cannot turn 120 degrees.
    let (code, _, err) = mbsa(&["solve", "@rig-planar-four-bar-3d", "--set", "A=120"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("cannot be closed") && err.contains("joint(s)"),
        "{err}"
    );
}

#[test]
fn an_assembly_that_cannot_close_names_poses_as_the_way_on() {
    // A four-bar whose ground link (10) is longer than the other three together: no
    // projection closes it. From the file's own configuration the help names `--poses`,
    // the way on when a start nearer a closed configuration exists (Gepetto's kangaroo leg
    // from zero joint positions).
    let dir = std::env::temp_dir().join(format!("mbsa-unreachable-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("four-bar.toml");
    let joint = |id: &str, a: u32, b: u32, x: f64| {
        format!("[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, 0]\n")
    };
    let text = format!(
        "name = \"four-bar\"\nspace = \"planar\"\nframe = 1\n{}{}{}{}second = {{ origin = [10, 0] }}\n",
        joint("A", 1, 2, 0.0),
        joint("B", 2, 3, 1.0),
        joint("C", 3, 4, 2.0),
        joint("D", 4, 1, 3.0)
    );
    std::fs::write(&path, text).unwrap();
    let (code, _, err) = mbsa(&["assemble", path.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("cannot be closed") && err.contains("--poses FILE"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_configuration_missing_closure_is_reported_and_assembled() {
    let dir = std::env::temp_dir().join(format!("mbsa-position-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Poses of the slider-crank at O=30, then the rod displaced by 1e-4 (a keyframe that
    // misses closure) or by 0.05 (not assembled).
    let (_, out, _) = mbsa(&[
        "solve",
        "@slider-crank-geometry",
        "--set",
        "O=30",
        "--format",
        "json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for (shift, code_without) in [(1e-4, 0), (0.05, 2)] {
        let mut w = v.clone();
        for p in w["poses"].as_array_mut().unwrap() {
            if p["body"] == "rod" {
                let y = p["translation"][1].as_f64().unwrap();
                p["translation"][1] = serde_json::json!(y + shift);
            }
        }
        let path = dir.join(format!("poses-{shift}.json"));
        std::fs::write(&path, serde_json::to_string(&w).unwrap()).unwrap();
        let p = path.to_str().unwrap();
        let (code, _, err) = mbsa(&[
            "solve",
            "@slider-crank-geometry",
            "--poses",
            p,
            "--set",
            "O=30",
        ]);
        assert_eq!(code, code_without, "{err}");
        assert!(err.contains("joint(s) A") && err.contains("B"), "{err}");
        let (code, toml, err) = mbsa(&["assemble", "@slider-crank-geometry", "--poses", p]);
        assert_eq!(code, 0, "{err}");
        assert!(
            toml.starts_with("# assembled by mbsa: largest joint residual"),
            "{toml}"
        );
        let closed = dir.join(format!("closed-{shift}.toml"));
        std::fs::write(&closed, &toml).unwrap();
        let c = closed.to_str().unwrap();
        let (code, out, err) = mbsa(&["solve", c, "--set", "O=0", "--format", "json"]);
        assert_eq!(code, 0, "{err}");
        assert!(err.is_empty(), "closed: no warning: {err}");
        let r: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!(r["max_residual"].as_f64().unwrap() < 1e-9);
        let (code, _, err) = mbsa(&["check", c]);
        assert_eq!(code, 0, "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn toml_output_is_the_mechanism_at_the_solved_configuration() {
    let (code, toml, _) = mbsa(&[
        "solve",
        "@slider-crank-geometry",
        "--set",
        "O=90",
        "--format",
        "toml",
    ]);
    assert_eq!(code, 0);
    // The crank pin turned from (0, 0.05) to (-0.05, 0); the piston pin to 0.15616.
    assert!(toml.contains("origin = [-0.05, 0.0]"), "{toml}");
    assert!(toml.contains("origin = [0.156155281281, 0.0]"), "{toml}");
}

#[test]
fn finite_mobility_of_the_bennett() {
    let (code, out, _) = mbsa(&[
        "solve",
        "@rig-bennett",
        "--set",
        "A=10",
        "--finite",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["finite"]["finite"], 1);
    assert_eq!(v["finite"]["first_order"], 1);
    assert_eq!(v["finite"]["count"], -2);
    assert_eq!(v["finite"]["verdict"], "overconstrained_moving");
}

#[test]
fn hostile_values_are_refused() {
    for (args, needle) in [
        (vec!["--set", "O=1e308"], "out of range"),
        (vec!["--set", "S=1e300"], "out of range"),
        (vec!["--set", "S=nan"], "not a finite number"),
        (vec!["--sweep", "O=0..1e9:1e-9"], "at most 100000"),
        (vec!["--tolerance=-1"], "positive length"),
        (vec!["--set", "S=1e5"], "cannot be closed"),
    ] {
        let mut a = vec!["solve", "@slider-crank-geometry"];
        a.extend(args);
        let (code, out, err) = mbsa(&a);
        assert_eq!(code, 2, "{a:?}: {err}");
        assert!(out.is_empty() && err.contains(needle), "{a:?}: {err}");
    }
}

#[test]
fn rigid_reports_finite_beside_first_order_mobility() {
    // The Bricard: count 0, first-order mobility 1, and it really moves (finite 1).
    let (code, out, err) = mbsa(&["rigid", "@bricard", "--finite", "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(v["geometric"]["mobility"], 1);
    assert_eq!(v["finite"]["first_order"], 1);
    assert_eq!(v["finite"]["finite"], 1);
    // Without the file's geometry there is no configuration to move from: exit 2.
    let (code, _, err) = mbsa(&["rigid", "@rotor", "--finite"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--finite needs the file's geometry"), "{err}");
}

/// Modelica's Fourbar1 (R-S-U-P written as 6 R + 1 P, bundled as `@msl-fourbar1`): the body
/// between the ball and the universal joint keeps the distance between their centres, so the
/// slider's travel has a closed form in the crank angle.
#[test]
fn modelica_fourbar1_sweep_is_the_closed_form() {
    let (code, out, err) = mbsa(&[
        "solve",
        "@msl-fourbar1",
        "--sweep",
        "j1=-60..60:30",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("sweep JSON");
    let steps = v["steps"].as_array().expect("steps");
    assert_eq!(steps.len(), 5, "{out}");
    for step in steps {
        let t = step["value"].as_f64().expect("crank angle").to_radians();
        // The ball's centre (0, 0.5, 0.1) turned about x; the universal joint's at
        // (1 - s, 0.2, 0); 1.1 is their squared distance in the file.
        let (ay, az) = (0.5 * t.cos() - 0.1 * t.sin(), 0.5 * t.sin() + 0.1 * t.cos());
        let s = 1.0 - (1.1 - (ay - 0.2).powi(2) - az * az).sqrt();
        let b2 = step["poses"]
            .as_array()
            .expect("poses")
            .iter()
            .find(|p| p["body"] == "b2")
            .expect("b2");
        let x = b2["translation"][0].as_f64().expect("x");
        assert!(
            (x + s).abs() < 1e-9,
            "crank {t}: slider at {x}, closed form {}",
            -s
        );
        // b2 only slides: no rotation, and the zero rotation's axis.
        assert_eq!(b2["angle_deg"].as_f64(), Some(0.0));
        assert_eq!(b2["axis"], serde_json::json!([0.0, 0.0, 1.0]), "{b2}");
    }
}

/// Modelica's EngineV6 (`@msl-engine-v6`): six slider-cranks on one crankshaft. Each piston's
/// travel has the slider-crank's closed form in its own crank offset and cylinder inclination.
#[test]
fn modelica_engine_v6_sweep_is_the_closed_form() {
    let (code, out, err) = mbsa(&[
        "solve",
        "@msl-engine-v6",
        "--sweep",
        "bearing=0..360:45",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("sweep JSON");
    let steps = v["steps"].as_array().expect("steps");
    assert_eq!(steps.len(), 9, "{out}");
    let offset = [-30.0f64, 90.0, 210.0, 210.0, 90.0, -30.0];
    let inclination = [-30.0f64, 30.0, -30.0, 30.0, -30.0, 30.0];
    // Distance of the piston pin from the crank axis along the cylinder: crank 0.1, rod 0.2.
    let reach = |angle: f64| {
        let c = angle.to_radians().cos();
        0.1 * c + (0.01 * c * c + 0.03).sqrt()
    };
    for step in steps {
        let turn = step["value"].as_f64().expect("bearing angle");
        for i in 0..6 {
            let id = format!("cylinder{}.cylinder", i + 1);
            let slide = step["joint_values"]
                .as_array()
                .expect("joint values")
                .iter()
                .find(|j| j["joint"] == id.as_str())
                .and_then(|j| j["values"][0].as_f64())
                .expect("the cylinder's slide");
            // The P joint's axis points from the piston toward the crank: its value grows as
            // the piston comes down.
            let expected =
                reach(offset[i] - inclination[i]) - reach(offset[i] + turn - inclination[i]);
            assert!(
                (slide - expected).abs() < 1e-9,
                "{id} at {turn} deg: {slide}, closed form {expected}"
            );
        }
    }
}

/// The engine's file configuration has cylinders 1 and 4 at dead centre: their pistons are
/// stationary in the first-order motion but move at once (a toggle), which `solve --finite`
/// names. Written with plain revolutes for the crank pins (not Modelica's planar-loop
/// revolute), each planar loop has 3 redundant constraints.
#[test]
fn modelica_engine_v6_dead_centres_and_plain_revolutes() {
    let (code, out, err) = mbsa(&["solve", "@msl-engine-v6", "--finite", "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("finite JSON");
    assert_eq!(v["finite"]["finite"], 1, "{out}");
    assert_eq!(
        v["finite"]["locked_at_toggle"],
        serde_json::json!(["cylinder1.cylinder", "cylinder4.cylinder"]),
        "{out}"
    );
    let text = mbsa::examples::find("msl-engine-v6")
        .expect("bundled")
        .1
        .replace("type = \"SC\"", "type = \"R\"");
    let dir = std::env::temp_dir().join(format!("mbsa-engine-v6-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("engine-r.toml");
    std::fs::write(&path, text).expect("write");
    let path = path.to_str().expect("utf-8 path");
    let (code, out, err) = mbsa(&["rigid", path, "--method", "geometric", "--format", "json"]);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("rigid JSON");
    assert_eq!(
        (&v["count"], &v["mobility"], &v["redundant"]),
        (
            &serde_json::json!(-17),
            &serde_json::json!(1),
            &serde_json::json!(18)
        ),
        "{out}"
    );
}

#[test]
fn a_step_names_at_most_twelve_bodies() {
    // A driven planar chain of 20 bodies: the global step holds them all, and its row names
    // 12 (a strip of 10^5 bodies wrote them all on one line).
    let mut text = String::from("space = \"planar\"\nframe = 0\n");
    for k in 1..=20 {
        text.push_str(&format!(
            "[[joint]]\ntype = \"R\"\nbodies = [{}, {k}]\ndriven = 1\norigin = [{}, 0]\n",
            k - 1,
            k - 1
        ));
    }
    let d = std::env::temp_dir().join(format!("mbsa-step-bodies-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    let p = d.join("chain.toml");
    std::fs::write(&p, text).expect("write");
    let (code, out, err) = mbsa(&["solve", "--global", p.to_str().expect("utf-8")]);
    let _ = std::fs::remove_dir_all(&d);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains(" 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12 and 8 more "),
        "{out}"
    );
}

#[test]
fn a_floating_base_nothing_drives_is_held_where_the_file_puts_it() {
    // A pendulum on a body that floats on a free joint to the ground: with the pendulum's
    // joint set and the base driven by nothing, the base stays at the file's pose (left free,
    // each solve moved it as its steps chose), in both solves, and a warning says so.
    let text = "space = \"spatial\"\nframe = \"ground\"\n\
                [[joint]]\nid = \"base\"\ntype = \"F\"\nbodies = [\"ground\", \"trunk\"]\n\
                [[joint]]\nid = \"hinge\"\ntype = \"R\"\nbodies = [\"trunk\", \"arm\"]\n\
                origin = [0, 0, 1]\naxis = [0, 1, 0]\n";
    let d = std::env::temp_dir().join(format!("mbsa-floating-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    let p = d.join("floating.toml");
    std::fs::write(&p, text).expect("write");
    let path = p.to_str().expect("utf-8");
    for extra in [&[][..], &["--global"][..]] {
        let mut args = vec!["solve", path, "--set", "hinge=30", "--format", "json"];
        args.extend_from_slice(extra);
        let (code, out, err) = mbsa(&args);
        assert_eq!(code, 0, "{err}");
        assert!(
            err.contains("the floating base `base` (a free joint to the frame, not driven) is held at the file's pose"),
            "{err}"
        );
        let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
        let poses = v["poses"].as_array().expect("poses");
        let pose = |b: &str| poses.iter().find(|p| p["body"] == b).expect("body").clone();
        let trunk = pose("trunk");
        let moved = trunk["angle_deg"].as_f64().expect("angle").abs()
            + trunk["translation"]
                .as_array()
                .expect("translation")
                .iter()
                .map(|x| x.as_f64().expect("number").abs())
                .sum::<f64>();
        assert!(moved < 1e-9, "{out}");
        let arm = pose("arm")["angle_deg"].as_f64().expect("angle");
        assert!((arm - 30.0).abs() < 1e-9, "{out}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `solve --assemble` on Gepetto's Disney-like leg (three 6D loop cuts open at zero joint
/// positions): the motors no `--set` gives hold the values the assembly left them at. They
/// were sent back to the file's own values, those of the open configuration, which the closed
/// loops do not reach: "did not converge", exit 1, while `assemble` then `solve` solved it.
#[test]
fn solve_assemble_holds_the_inputs_where_the_assembly_left_them() {
    let file = "tests/fixtures/import/disney_like.urdf";
    let (code, out, err) = mbsa(&["solve", file, "--assemble", "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    assert!(v["max_residual"].as_f64() < Some(1e-9), "{v}");
    let (code, out, err) = mbsa(&[
        "solve",
        file,
        "--assemble",
        "--set",
        "motor_hip_x=-30",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    let hip = v["joint_values"]
        .as_array()
        .expect("joint values")
        .iter()
        .find(|j| j["joint"] == "motor_hip_x")
        .expect("the hip motor");
    assert!(
        (hip["values"][0].as_f64().expect("a value") + 30.0).abs() < 1e-6,
        "{hip}"
    );
}

/// A joint of several DOF given fewer values drives its first DOF, in the order docs/format.md
/// gives; a note says which (a value meant as the turn of a planar joint moved its first slide,
/// silently). No note when every DOF gets a value, or the file drives as many as given.
#[test]
fn fewer_values_than_a_joints_dof_are_named_in_a_note() {
    let file = "name = \"puck\"\nspace = \"spatial\"\nframe = 1\n\n[[joint]]\nid = \"slide\"\ntype = \"PL\"\nbodies = [1, 2]\norigin = [0, 0, 0]\nnormal = [0, 0, 1]\n\n[[joint]]\nid = \"pin\"\ntype = \"R\"\nbodies = [2, 3]\norigin = [1, 0, 0]\naxis = [0, 0, 1]\ndriven = 1\n";
    let run = |set: &str, driven: bool| {
        let text = if driven {
            file.replace("normal = [0, 0, 1]\n", "normal = [0, 0, 1]\ndriven = 1\n")
        } else {
            file.to_string()
        };
        let out = Command::cargo_bin("mbsa")
            .expect("the mbsa binary is built")
            .args(["solve", "-", "--set", set])
            .write_stdin(text)
            .output()
            .expect("mbsa runs");
        assert_eq!(out.status.code(), Some(0), "{out:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = run("slide=30", false);
    assert!(
        err.contains(
            "warning: `slide=30`: joint `slide` (PL) has 3 DOF; the value drives its first (PL's \
             DOF in order: the two slides in the plane, then the turn about the normal; \
             docs/format.md)"
        ),
        "{err}"
    );
    let err = run("slide=0.1,0.2", false);
    assert!(err.contains("the 2 values drive its first 2"), "{err}");
    assert!(!run("slide=0.1,0.2,30", false).contains("DOF;"));
    assert!(!run("slide=0.1", true).contains("DOF;"));
}

/// A body on a free joint that a ball also ties to the ground (MuJoCo's `connect` to the
/// world, `jdotv_connect_3d.xml`) is no floating base: `solve` held it at the file's pose with
/// a warning, over-constraining it against the ball (its one step called "overdetermined").
#[test]
fn a_free_body_tied_to_the_ground_is_not_held_as_a_floating_base() {
    let text = "space = \"spatial\"\nframe = \"ground\"\n\
                [[joint]]\nid = \"free\"\ntype = \"F\"\nbodies = [\"ground\", \"lower\"]\n\
                [[joint]]\nid = \"tie\"\ntype = \"S\"\nbodies = [\"ground\", \"lower\"]\n\
                origin = [0, 0, 1]\n";
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(["solve", "-"])
        .write_stdin(text)
        .output()
        .expect("mbsa runs");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("floating base"), "{stderr}");
    assert!(!stdout.contains("overdetermined"), "{stdout}");
}

/// `--set` on a joint the file does not drive adds an input to the file's: on the driven
/// slider-crank it over-determines the group and the solve fails. The error now names the
/// added joint, the file's inputs and `--inputs` (it said only "an input value out of reach").
/// `--inputs A --set A=10` moves the crank pin in place of the crank: solved.
#[test]
fn an_input_set_on_top_of_the_files_names_them_and_inputs() {
    let (code, _, err) = mbsa(&["solve", "@slider-crank-geometry", "--set", "A=10"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(
            "help: `--set` drives A on top of the file's inputs (O): where those were all the \
             mechanism needs, that is an input too many"
        ),
        "{err}"
    );
    let (code, _, err) = mbsa(&[
        "solve",
        "@slider-crank-geometry",
        "--inputs",
        "A",
        "--set",
        "A=10",
    ]);
    assert_eq!(code, 0, "{err}");
}
