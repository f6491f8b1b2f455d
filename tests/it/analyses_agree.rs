//! Answers that must agree: `mbsa analyze` with `mbsa rigid --with-inputs` on isolated spins,
//! both with the written precision on float noise, and with `mbsa rigid --finite` on a toggle.

use assert_cmd::Command;
use mbsa::joint::JointType;
use mbsa::rigidity::geometric::{self, GeometricOptions};
use mbsa::structure::{Library, Options, Status, analyze};

fn mbsa(args: &[&str], stdin: &str) -> (i32, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .write_stdin(stdin)
        .output()
        .expect("mbsa runs");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let err = String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), format!("{text}{err}"))
}

fn json(args: &[&str], stdin: &str) -> serde_json::Value {
    let (_, out) = mbsa(args, stdin);
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

/// Bodies 1 and 2 hinged by a driven R, each held to the frame by an S joint: the pair turns
/// as one rigid part about the line through the two ball centres, moving nothing else.
const TWO_BALLS: &str = r#"
name = "two bodies hinged between two balls"
space = "spatial"
frame = "0"
[[joint]]
id = "A"
type = "S"
bodies = ["0", "1"]
origin = [0, 0, 0]
[[joint]]
id = "B"
type = "S"
bodies = ["0", "2"]
origin = [1, 0, 0]
[[joint]]
id = "C"
type = "R"
bodies = ["1", "2"]
origin = [0.5, 0.3, 0]
axis = [0, 0, 1]
driven = 1
"#;

#[test]
fn a_part_turning_between_two_balls_is_isolated_in_analyze_as_in_rigid() {
    for geometry in ["file", "random"] {
        let rigid = json(
            &[
                "rigid",
                "-",
                "--with-inputs",
                "--method",
                "geometric",
                "--format",
                "json",
                "--geometry",
                geometry,
            ],
            TWO_BALLS,
        );
        assert_eq!(rigid["structurally_isolated"], 1, "{rigid}");
        assert_eq!(rigid["mobility"], rigid["isolated"], "{rigid}");
        let a = json(
            &["analyze", "-", "--format", "json", "--geometry", geometry],
            TWO_BALLS,
        );
        assert_eq!(a["status"], "determined", "{geometry}: {a}");
        assert_eq!(a["uncontrolled"], 0, "{a}");
        assert_eq!(
            a["spins"][0]["bodies"],
            serde_json::json!(["1", "2"]),
            "{a}"
        );
        assert_eq!(
            a["spins"][0]["joints"],
            serde_json::json!(["A", "B"]),
            "{a}"
        );
        let (code, out) = mbsa(&["analyze", "-", "--geometry", geometry], TWO_BALLS);
        assert_eq!(code, 0, "{out}");
        assert!(out.contains("turn together as one rigid part"), "{out}");
        assert!(!out.contains("one more input"), "{out}");
    }
}

/// The double banana (18 S-S bars): its 2 DOF beyond the bars' own spins are two rigid parts
/// turning (the right bipyramid about A-B, everything about the frame's line A-C), so
/// `rigid` finds no proper mobility; `analyze` set them aside too, at every geometry.
#[test]
fn the_double_banana_spins_are_isolated_in_analyze_as_in_rigid() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/mechanisms/rig-double-banana.toml"
    );
    let text = std::fs::read_to_string(path).expect("bundled file");
    for geometry in ["file", "random"] {
        let r = json(
            &[
                "rigid",
                "-",
                "--with-inputs",
                "--method",
                "geometric",
                "--format",
                "json",
                "--geometry",
                geometry,
            ],
            &text,
        );
        assert_eq!(r["mobility"], r["isolated"], "{geometry}: {r}");
        let a = json(
            &["analyze", "-", "--format", "json", "--geometry", geometry],
            &text,
        );
        assert_eq!(a["status"], "determined", "{geometry}: {a}");
        assert_eq!(
            a["spins"].as_array().map(Vec::len),
            Some(2),
            "{geometry}: {a}"
        );
        assert_eq!(a["uncontrolled"], 0, "{a}");
    }
}

/// Random count-determined spatial mechanisms with S joints: wherever `analyze` finds them
/// not determined, the DOF it leaves uncontrolled are the true mobility `rigid --with-inputs`
/// finds less its isolated motions (seeds 38, 347 and 398 held a part spinning between an S
/// and another joint, which `analyze` called uncontrolled).
#[test]
fn random_mechanisms_with_ball_joints_leave_the_same_freedoms_uncontrolled() {
    let lib = Library::builtin();
    let (mut checked, mut spinning) = (0, 0);
    for seed in (0..120).chain([347, 398]) {
        let (m, _) = mbsa::generate::random(3 + seed % 8, false, seed).expect("generated");
        if !m.joints.iter().any(|j| j.kind == JointType::S) {
            continue;
        }
        let a = analyze(&m, &Options::default(), &lib).expect("random geometry");
        let r = geometric::analyze(&m, &GeometricOptions::default()).expect("random geometry");
        let proper = r.mobility - r.isolated;
        if a.status == Status::Determined && r.structurally_isolated == 0 {
            continue;
        }
        checked += 1;
        spinning += usize::from(r.structurally_isolated > 0);
        assert_eq!(
            a.uncontrolled, proper as u64,
            "seed {seed}: analyze {:?} with {} uncontrolled, rigid {} proper ({} structurally isolated)",
            a.status, a.uncontrolled, proper, r.structurally_isolated
        );
    }
    assert!(
        checked >= 10 && spinning >= 3,
        "{checked} checked, {spinning} spinning"
    );
}

/// A parallelogram four-bar written flat, both cranks driven: singular (2 first-order
/// freedoms, 1 finite). `{zero}` is where the clean file writes 0.
const FLAT_PARALLELOGRAM: &str = r#"
name = "Flat parallelogram, both cranks driven"
space = "planar"
frame = 1
[[joint]]
id = "A"
type = "R"
bodies = [1, 2]
driven = 1
origin = [{zero}, {zero}]
[[joint]]
id = "B"
type = "R"
bodies = [2, 3]
origin = [1, {zero}]
[[joint]]
id = "C"
type = "R"
bodies = [3, 4]
origin = [3, {zero}]
[[joint]]
id = "D"
type = "R"
bodies = [4, 1]
driven = 1
origin = [2, {zero}]
"#;

/// What `analyze` and `rigid --finite` conclude about a file: the verdict, the singular note
/// and the finite verdict.
fn verdicts(file: &str) -> (serde_json::Value, serde_json::Value, serde_json::Value) {
    let a = json(&["analyze", "-", "--format", "json"], file);
    let r = json(&["rigid", "-", "--finite", "--format", "json"], file);
    (
        a["status"].clone(),
        a["finite"]["instantaneous_only"].clone(),
        r["finite"]["verdict"].clone(),
    )
}

/// Float noise written where 0 is meant (`1.22464679915e-17`, an exported cos(π/2) scaled)
/// has digits far below double precision at the model's size: the numbers are as exact as
/// the clean file's, and both commands say what they say on it. Before, the noise's own
/// digits made the file "known to ±5e-29": `rigid --finite` left the verdict undecided and
/// `analyze` dropped its singular note.
#[test]
fn float_noise_where_zero_is_meant_leaves_the_verdicts_unchanged() {
    let clean = FLAT_PARALLELOGRAM.replace("{zero}", "0");
    let noisy = FLAT_PARALLELOGRAM.replace("{zero}", "1.22464679915e-17");
    let want = verdicts(&clean);
    assert_eq!(want.0, "determined");
    assert_eq!(want.1, 1, "the clean file has the singular note");
    assert_eq!(want.2, "singular");
    assert_eq!(verdicts(&noisy), want);
    let a = json(&["analyze", "-", "--format", "json"], &noisy);
    assert_eq!(a["geometry"]["precision"], 0.0, "{a}");
    // A bundled mechanism with its zeros so written: the same answers as the clean file.
    let bundled = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/mechanisms/slider-crank-geometry.toml"
    ))
    .expect("bundled file");
    let noisy = bundled
        .replace("[0, ", "[-1.2246467991e-17, ")
        .replace(", 0]", ", 1.2246467991e-17]");
    assert_ne!(noisy, bundled);
    for args in [
        &["analyze", "-", "--format", "json"][..],
        &["rigid", "-", "--finite", "--format", "json"],
    ] {
        let (mut want, mut got) = (json(args, &bundled), json(args, &noisy));
        for v in [&mut want, &mut got] {
            v["geometry"]["closure"] = serde_json::Value::Null;
            v["geometry_used"]["closure"] = serde_json::Value::Null;
        }
        assert_eq!(got, want, "{args:?}");
    }
}

/// A four-bar at a toggle: crank (A-B) and coupler (B-C) aligned along x, the rocker (C-D)
/// upright and driven at D. The rocker stands at its extreme: D cannot move, the crank can.
const TOGGLE: &str = r#"
name = "Four-bar at a toggle pose, rocker driven"
space = "planar"
frame = 1
[[joint]]
id = "A"
type = "R"
bodies = [1, 2]
origin = [0, 0]
{a}
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
origin = [3, 2]
{d}
"#;

#[test]
fn analyze_names_a_driven_joint_locked_at_a_toggle_as_rigid_finite_does() {
    let rocker = TOGGLE.replace("{a}", "").replace("{d}", "driven = 1");
    let r = json(&["rigid", "-", "--finite", "--format", "json"], &rocker);
    assert_eq!(
        r["finite"]["locked_at_toggle"],
        serde_json::json!(["D"]),
        "{r}"
    );
    let a = json(&["analyze", "-", "--format", "json"], &rocker);
    assert_eq!(a["status"], "mixed", "{a}");
    let d = &a["diagnosis"];
    assert_eq!(
        d["overdetermined"]["joints"],
        serde_json::json!(["D"]),
        "{a}"
    );
    assert_eq!(
        d["underdetermined"]["input_candidates"],
        serde_json::json!([]),
        "{a}"
    );
    let (_, out) = mbsa(&["analyze", "-"], &rocker);
    assert!(
        out.contains("- toggle: the input on D cannot move at this configuration"),
        "{out}"
    );
    assert!(!out.contains("one more input"), "{out}");
    // The crank driven instead moves at this pose: determined, no toggle.
    let crank = TOGGLE.replace("{a}", "driven = 1").replace("{d}", "");
    let (code, out) = mbsa(&["analyze", "-"], &crank);
    assert_eq!(code, 0, "{out}");
    assert!(
        out.lines().next().unwrap_or("").ends_with("; determined"),
        "{out}"
    );
    assert!(!out.contains("- toggle:"), "{out}");
}

/// A body on a free joint to the frame carrying a driven pendulum: `driven` is written on the
/// free joint when `FREE_DRIVEN` replaces its marker.
const FLOATING_PENDULUM: &str = r#"
name = "pendulum on a free trunk"
space = "spatial"
frame = "ground"
[[joint]]
id = "base"
type = "F"
bodies = ["ground", "trunk"]
# FREE_DRIVEN
[[joint]]
id = "hip"
type = "R"
bodies = ["trunk", "leg"]
driven = 1
"#;

/// The DOF no input fixes say which of them are a floating base, on a line of their own, as
/// `transform` (which drives such a base in full by default) has it; a base driven in full is
/// not named. On the Cassie, 6 of the 12 DOF are its pelvis's free joint, and the legs, which
/// meet only at the pelvis, are told one to a line with their own candidates (one line of
/// 849 characters named 23 bodies and 17 joints of both legs).
#[test]
fn a_floating_base_is_named_on_a_line_of_its_own() {
    let (_, out) = mbsa(&["analyze", "-", "--count-only"], FLOATING_PENDULUM);
    assert!(
        out.contains(
            "- floating base: 6 of these 6 DOF are the free joint(s) base (ground to trunk); \
             give the base's pose"
        ),
        "{out}"
    );
    // Two legs, each hip driven: the 6 DOF are the base's, no part beyond it is told (a
    // humanoid got "the rest in 3 parts", each with an empty list of joints).
    let two_legs = format!(
        "{FLOATING_PENDULUM}[[joint]]\nid = \"hip2\"\ntype = \"R\"\nbodies = [\"trunk\", \"leg2\"]\ndriven = 1\n"
    );
    let (_, out) = mbsa(&["analyze", "-", "--count-only"], &two_legs);
    assert!(out.contains("6 DOF not fixed"), "{out}");
    assert!(!out.contains("meet only at the base"), "{out}");
    // A base tethered to the ground by a ball too is no floating base: the ball fixes 3 of
    // its DOF (a MuJoCo `connect` to the world).
    let tethered = format!(
        "{FLOATING_PENDULUM}[[joint]]\nid = \"tether\"\ntype = \"S\"\nbodies = [\"ground\", \"trunk\"]\n"
    );
    let (_, out) = mbsa(&["analyze", "-", "--count-only"], &tethered);
    assert!(out.contains("3 DOF not fixed"), "{out}");
    assert!(!out.contains("floating base"), "{out}");
    let driven = FLOATING_PENDULUM.replace("# FREE_DRIVEN", "driven = 6");
    let (_, out) = mbsa(&["analyze", "-", "--count-only"], &driven);
    assert!(out.contains("determined"), "{out}");
    assert!(!out.contains("floating base"), "{out}");
    let (_, out) = mbsa(&["analyze", "tests/fixtures/import/cassie.xml"], "");
    assert!(
        out.contains(
            "- floating base: 6 of these 12 DOF are the free joint(s) cassie-pelvis:free \
             (world to cassie-pelvis)"
        ),
        "{out}"
    );
    assert!(
        out.contains(
            "- 12 DOF not fixed by any input: 6 of the floating base (below), the rest in 2 \
             parts that meet only at the base:\n  - bodies {left-achilles-rod, left-foot,"
        ),
        "{out}"
    );
    assert!(
        out.contains("\n  - bodies {right-achilles-rod, right-foot,"),
        "{out}"
    );
    let longest = out
        .lines()
        .filter(|l| l.contains("DOF not fixed") || l.starts_with("  "))
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest < 500, "a line of {longest} characters:\n{out}");
}

/// DOF no input fixes in parts that no joint joins are told part by part: the Robotiq
/// gripper's two fingers (2 DOF each at the file's configuration) each with their own
/// candidates, where one line named all eight bodies and every joint of both; past six parts
/// the rest are counted.
#[test]
fn dof_no_input_fixes_are_told_by_independent_part() {
    let (_, out) = mbsa(&["analyze", "tests/fixtures/import/robotiq_2f85.xml"], "");
    assert!(
        out.contains(
            "- 4 DOF not fixed by any input, in 2 independent parts: 2 DOF of bodies \
             {left_coupler, left_driver, left_follower, left_spring_link} (one more input on \
             one of the joints connect:left_follower-left_coupler, left_coupler_joint, \
             left_driver_joint, left_follower_joint, left_spring_link_joint would fix one); 2 \
             DOF of bodies {right_coupler,"
        ),
        "{out}"
    );
    let (_, out, _) = crate::common::mbsa(&[
        "analyze",
        "tests/fixtures/import/robotiq_2f85.xml",
        "--format",
        "json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    let pieces = &v["diagnosis"]["underdetermined"]["pieces"];
    assert_eq!(pieces.as_array().map(Vec::len), Some(2), "{out}");
    assert_eq!(pieces[1]["missing"], 2, "{out}");
    // Eight legs of one DOF hanging from the frame: six told, two counted.
    let mut legs = String::from("space = \"planar\"\nframe = 0\n");
    for k in 0..8 {
        legs.push_str(&format!(
            "[[joint]]\ntype = \"R\"\nbodies = [0, {}]\n[[joint]]\ntype = \"R\"\nbodies = [{}, {}]\n",
            2 * k + 1,
            2 * k + 1,
            2 * k + 2
        ));
    }
    let (_, out) = mbsa(&["analyze", "-", "--count-only"], &legs);
    assert!(
        out.contains(
            "- 16 DOF not fixed by any input, in 8 independent parts: 2 DOF of bodies {1, 2}"
        ),
        "{out}"
    );
    assert!(out.contains("; 2 more parts of 4 DOF"), "{out}");
}

/// A chassis on a free joint with two wheels hinged on one axle (MuJoCo's `car.xml`): the
/// chassis pitching about the axle moves no other body, but the free joint's input drives it.
const CAR: &str = r#"<mujoco model="car">
  <worldbody>
    <body name="car" pos="0 0 .03">
      <freejoint/>
      <geom type="box" size=".06 .04 .01"/>
      <body name="left wheel" pos="-.07 .06 0" zaxis="0 1 0">
        <joint name="left"/>
        <geom type="cylinder" size=".03 .01"/>
      </body>
      <body name="right wheel" pos="-.07 -.06 0" zaxis="0 1 0">
        <joint name="right"/>
        <geom type="cylinder" size=".03 .01"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"#;

/// A femur on a hinge at the hip and a planar knee whose normal is the hinge's axis (OpenSim's
/// leg39, its knee's coupled translations left out): the femur's turn about the hip moves no
/// other body, an isolated freedom, but the tibia reaches the frame only through the femur.
const HIP_AND_PLANAR_KNEE: &str = r#"
name = "hip hinge and planar knee"
space = "spatial"
frame = "pelvis"
[[joint]]
id = "hip"
type = "R"
bodies = ["pelvis", "femur"]
origin = [0, 0, 0]
axis = [0, 0, 1]
[[joint]]
id = "knee"
type = "PL"
bodies = ["femur", "tibia"]
origin = [0, -0.4, 0]
normal = [0, 0, 1]
"#;

/// A chain of three ball joints (a MuJoCo rope): the inner links spin about the line through
/// their two balls, moving no other body.
const BALL_CHAIN: &str = r#"<mujoco model="rope">
  <worldbody>
    <body name="b1" pos="0 0 1"><joint name="j1" type="ball"/><geom size="0.05"/>
      <body name="b2" pos="0 0 -0.2"><joint name="j2" type="ball"/><geom size="0.05"/>
        <body name="b3" pos="0 0 -0.2"><joint name="j3" type="ball"/><geom size="0.05"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"#;

/// A body on a free joint has no isolated freedom: the free joint's input drives every motion
/// of it (MuJoCo's car: the chassis pitching about its wheels' axle moves no other body).
/// Before, `transform` placed one input too few (0 determined, exit 0) and `analyze` said an
/// input on the wheels "may only turn it, fixing none", while driving every joint determined
/// the car. Nor has a body others reach the frame through (a ball chain's inner links, a
/// femur between a hip hinge and a planar knee): the inputs beyond it drag it, and leaving
/// its spin out placed too few inputs (0 determined, exit 0). A rod between two balls keeps
/// its spin.
#[test]
fn a_body_on_a_free_joint_has_no_isolated_freedom() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("analyses_agree");
    std::fs::create_dir_all(&dir).expect("writable");
    let car = dir.join("car.xml");
    std::fs::write(&car, CAR).expect("writable");
    let car = car.to_str().expect("UTF-8");
    let rigid = json(
        &["rigid", car, "--method", "geometric", "--format", "json"],
        "",
    );
    assert_eq!(rigid["mobility"], 8, "{rigid}");
    assert_eq!(rigid["isolated"], 0, "{rigid}");
    let a = json(&["analyze", car, "--format", "json"], "");
    assert_eq!(a["isolated"], serde_json::json!([]), "{a}");
    assert_eq!(a["uncontrolled"], 8, "{a}");
    let a = json(
        &[
            "analyze",
            car,
            "--format",
            "json",
            "--inputs",
            "car:free:6,left,right",
        ],
        "",
    );
    assert_eq!(a["status"], "determined", "{a}");
    let t = json(&["transform", car, "--format", "json"], "");
    assert_eq!(t["summary"]["f"], 8, "{t}");
    assert_eq!(t["summary"]["determined"], 1, "{t}");
    // The ball chain: 9 inputs (7 before, none of which determined it), as every command
    // counts them.
    let chain = dir.join("ball_chain.xml");
    std::fs::write(&chain, BALL_CHAIN).expect("writable");
    let chain = chain.to_str().expect("UTF-8");
    let t = json(&["transform", chain, "--format", "json"], "");
    assert_eq!(t["summary"]["f"], 9, "{t}");
    assert_eq!(t["summary"]["isolated"], 0, "{t}");
    assert_eq!(t["summary"]["determined"], 1, "{t}");
    let a = json(&["analyze", chain, "--format", "json"], "");
    assert_eq!(a["isolated"], serde_json::json!([]), "{a}");
    assert_eq!(a["uncontrolled"], 9, "{a}");
    let rigid = json(
        &["rigid", chain, "--method", "geometric", "--format", "json"],
        "",
    );
    assert_eq!(
        (&rigid["mobility"], &rigid["isolated"]),
        (&9.into(), &0.into()),
        "{rigid}"
    );
    let t = json(&["transform", "-", "--format", "json"], HIP_AND_PLANAR_KNEE);
    assert_eq!(t["summary"]["f"], 4, "{t}");
    assert_eq!(t["summary"]["determined"], 1, "{t}");
    let a = json(
        &[
            "analyze",
            chain,
            "--format",
            "json",
            "--inputs",
            "j1:3,j2:3,j3:3",
        ],
        "",
    );
    assert_eq!(a["status"], "determined", "{a}");
    // Bar frameworks keep their bars' spins: no body reaches the frame through a bar.
    let rigid = json(
        &[
            "rigid",
            "@rig-double-banana",
            "--method",
            "geometric",
            "--format",
            "json",
        ],
        "",
    );
    assert!(rigid["isolated"].as_u64() > Some(0), "{rigid}");
    let a = json(
        &["analyze", "-", "--format", "json", "--inputs", "hip,knee:3"],
        HIP_AND_PLANAR_KNEE,
    );
    assert_eq!(a["status"], "determined", "{a}");
    // The rod of an RSSR keeps its spin about the line through its ball centres.
    let rigid = json(
        &[
            "rigid",
            "@rig-rssr",
            "--method",
            "geometric",
            "--format",
            "json",
        ],
        "",
    );
    assert_eq!(rigid["isolated"], 1, "{rigid}");
}

/// `rigid --with-inputs` on a driven five-bar: its two passive pins are locked because the
/// inputs fix them, not "as at a dead centre" (the words of the mechanism's own locked
/// freedoms, which plain `rigid` gives: none here).
#[test]
fn locked_freedoms_with_the_inputs_held_say_the_inputs_may_fix_them() {
    let mut five_bar = String::from("space = \"spatial\"\nframe = \"built\"\n");
    for (id, a, c, y, z, driven) in [
        ("mot1", "built", "rod", 0.15, 0.0, 1),
        ("free1", "rod", "rod_2", 0.15, -0.4, 0),
        ("a", "rod_2", "tip", 0.0, -0.8, 0),
        ("free2", "rod_3", "tip", -0.15, -0.4, 0),
        ("mot2", "built", "rod_3", -0.15, 0.0, 1),
    ] {
        five_bar.push_str(&format!(
            "[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [\"{a}\", \"{c}\"]\n\
             origin = [0, {y}, {z}]\naxis = [1, 0, 0]\ndriven = {driven}\n"
        ));
    }
    let (_, out) = mbsa(
        &["rigid", "-", "--method", "geometric", "--with-inputs"],
        &five_bar,
    );
    assert!(
        out.contains("with the inputs held: fixed by the inputs, or by the geometry"),
        "{out}"
    );
    assert!(!out.contains("; `--finite` tells which"), "{out}");
    let (_, out) = mbsa(&["rigid", "-", "--method", "geometric"], &five_bar);
    assert!(!out.contains("locked DOF"), "{out}");
}

/// The N-four-bar written in 3D (every pin's axis z), every number declared known to
/// `precision` (as scripts/cliffs.py writes it).
fn n_four_bar_3d(windows: usize, precision: f64) -> String {
    let header = format!("space = \"spatial\"\nframe = 1\nprecision = {precision}");
    crate::common::n_four_bar_with(windows, &header, |x, y| {
        format!("origin = [{x}, {y}, 0]\naxis = [0, 0, 1]")
    })
}

/// Axes known to ±0.05 (about 3°) over a row 12 links long cannot decide the ranks:
/// `rigid --method geometric` warns "ill-conditioned", and `analyze`, whose answer then differs
/// (not determined, 27 isolated freedoms, where the exact file is determined with true mobility
/// 1), says it too (it said nothing). Exact numbers: determined, no such note.
#[test]
fn analyze_flags_rank_decisions_near_the_precision_threshold_as_rigid_does() {
    let coarse = n_four_bar_3d(24, 0.05);
    let (_, rigid) = mbsa(&["rigid", "-", "--method", "geometric"], &coarse);
    assert!(rigid.contains("Warning: ill-conditioned"), "{rigid}");
    let (code, out) = mbsa(&["analyze", "-"], &coarse);
    assert_eq!(code, 0, "{out}");
    assert!(
        out.contains("- ill-conditioned: with the numbers known to ±5e-2, a rank decision at the file's configuration lies within a factor 10 of its threshold"),
        "{out}"
    );
    let j = json(&["analyze", "-", "--format", "json"], &coarse);
    let notes = j["diagnosis"]["notes"].as_array().expect("diagnosis notes");
    assert!(
        notes
            .iter()
            .any(|n| n.as_str().is_some_and(|n| n.starts_with("ill-conditioned"))),
        "{notes:?}"
    );
    let (_, exact) = mbsa(&["analyze", "-", "--tolerance", "0"], &coarse);
    assert!(
        exact.contains("true mobility 1, inputs 1; determined"),
        "{exact}"
    );
    assert!(!exact.contains("ill-conditioned"), "{exact}");
}

/// A Stewart platform whose six legs are S-P-S struts of two bodies, cylinder and rod, the
/// sliders driven: the inputs fix the platform and each strut spins about the line through its
/// balls. `rigid --with-inputs` says 6 structurally isolated freedoms and nothing else;
/// `analyze` said "6 DOF not fixed by any input", the platform among the bodies that can move,
/// and advised an input on a ball joint (every equation is independent, so the spins never
/// showed as dependent equations). It now sets the six spins aside and finds the platform
/// determined, as MuJoCo-free robots with such legs are (Gepetto's WL16-like leg, its balls
/// merged).
#[test]
fn struts_of_two_bodies_spin_in_analyze_as_in_rigid() {
    let base = [0.0f64, 40.0, 120.0, 160.0, 240.0, 280.0];
    let top = [-20.0f64, 60.0, 100.0, 180.0, 220.0, 300.0];
    let mut s = String::from("name = \"SPS Stewart\"\nspace = \"spatial\"\nframe = \"base\"\n");
    for i in 0..6 {
        let (a, c) = (base[i].to_radians(), top[i].to_radians());
        let b = [a.cos(), a.sin(), 0.0];
        let p = [0.5 * c.cos(), 0.5 * c.sin(), 1.0];
        let d: Vec<f64> = (0..3).map(|k| p[k] - b[k]).collect();
        let n = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        let f = |v: &[f64]| format!("[{:.6}, {:.6}, {:.6}]", v[0], v[1], v[2]);
        let mid: Vec<f64> = (0..3).map(|k| 0.5 * (b[k] + p[k])).collect();
        let axis: Vec<f64> = d.iter().map(|x| x / n).collect();
        s.push_str(&format!(
            "[[joint]]\nid = \"S{i}\"\ntype = \"S\"\nbodies = [\"base\", \"cyl{i}\"]\norigin = {}\n\
             [[joint]]\nid = \"P{i}\"\ntype = \"P\"\nbodies = [\"cyl{i}\", \"rod{i}\"]\norigin = {}\naxis = {}\ndriven = 1\n\
             [[joint]]\nid = \"T{i}\"\ntype = \"S\"\nbodies = [\"rod{i}\", \"platform\"]\norigin = {}\n",
            f(&b),
            f(&mid),
            f(&axis),
            f(&p)
        ));
    }
    let (_, rigid) = mbsa(
        &["rigid", "-", "--with-inputs", "--method", "geometric"],
        &s,
    );
    assert!(
        rigid.contains("= 6 structurally isolated + 0 proper"),
        "{rigid}"
    );
    let (code, out) = mbsa(&["analyze", "-"], &s);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("mobility 12, inputs 6; determined"), "{out}");
    for i in 0..6 {
        assert!(
            out.contains(&format!(
                "bodies {{cyl{i}, rod{i}}} turn together as one rigid part, moving no other body, \
                 by 1 freedom(s) the joints S{i}, T{i} allow"
            )),
            "{out}"
        );
    }
    assert!(!out.contains("not fixed by any input"), "{out}");
}

/// The tetrahedron of S-S bars: five bars turn together about the frame bar's two balls, the
/// bars each spin. `rigid` finds 5 fully and 1 structurally isolated freedoms and nothing to
/// drive; `analyze` said "under-determined, 1 DOF not fixed by any input" (the balls' rows
/// are independent, so the part's spin never showed as dependent equations).
#[test]
fn a_part_hung_on_the_frame_by_two_balls_spins_in_analyze_as_in_rigid() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("mechanisms/rig-tetrahedron.toml"),
    )
    .expect("bundled");
    let (_, rigid) = mbsa(&["rigid", "-", "--method", "geometric"], &text);
    assert!(
        rigid.contains("= 5 fully isolated + 1 structurally isolated + 0 proper"),
        "{rigid}"
    );
    let (code, out) = mbsa(&["analyze", "-"], &text);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("mobility 6, inputs 0; determined"), "{out}");
    assert!(
        out.contains("bodies {P1P3, P1P4, P2P3, P2P4, P3P4} turn together as one rigid part"),
        "{out}"
    );
    assert!(!out.contains("not fixed by any input"), "{out}");
}
