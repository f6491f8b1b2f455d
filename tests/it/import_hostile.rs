//! The importers on bad input: repeated names, names that collide with the importer's own,
//! numbers out of range, files that are not what an `<include>` expects, and sizes that would
//! make the XML reader's or a reader's work grow faster than the input. Each is refused with a
//! location or read correctly, through the real binary or the library.

use assert_cmd::Command;
use mbsa::import::{ImportOptions, import_file, import_str};
use std::path::{Path, PathBuf};

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

/// A fresh directory for one test's files.
fn dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mbsa-import-hostile-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write fixture");
    p.display().to_string()
}

/// `mbsa import` of `text` as a file `name`: (exit code, standard output, standard error).
fn import(test: &str, name: &str, text: &str) -> (i32, String, String) {
    let d = dir(test);
    let p = write(&d, name, text);
    mbsa(&["import", &p])
}

/// An import that must fail with exit 2 and name both `locations` (`line:col`).
fn refused(test: &str, name: &str, text: &str, words: &str, locations: &[&str]) {
    let (code, _, err) = import(test, name, text);
    assert_eq!(code, 2, "{test}: {err}");
    assert!(err.contains(words), "{test}: {err}");
    for l in locations {
        assert!(
            err.contains(&format!("{name}:{l}")),
            "{test}: no {l} in {err}"
        );
    }
    assert!(!err.contains("internal error"), "{test}: {err}");
}

#[test]
fn repeated_mjcf_body_joint_and_keyframe_names_are_refused_with_both_locations() {
    let bodies = "<mujoco>\n<worldbody>\n<body name=\"a\"><joint/></body>\n\
                  <body name=\"a\"><joint/></body>\n</worldbody>\n</mujoco>\n";
    refused(
        "mjcf_body",
        "m.xml",
        bodies,
        "body `a` is defined twice",
        &["3:1", "4:1"],
    );
    let joints = "<mujoco>\n<worldbody>\n<body name=\"a\"><joint name=\"j\"/></body>\n\
                  <body name=\"b\"><joint name=\"j\"/></body>\n</worldbody>\n</mujoco>\n";
    refused(
        "mjcf_joint",
        "m.xml",
        joints,
        "joint `j` is defined twice",
        &["3:16", "4:16"],
    );
    let keys = "<mujoco>\n<worldbody>\n<body name=\"a\"><joint/></body>\n</worldbody>\n\
                <keyframe>\n<key name=\"k\" qpos=\"0\"/>\n<key name=\"k\" qpos=\"1\"/>\n\
                </keyframe>\n</mujoco>\n";
    refused(
        "mjcf_key",
        "m.xml",
        keys,
        "keyframe `k` is defined twice",
        &["6:1", "7:1"],
    );
}

#[test]
fn repeated_urdf_joint_names_are_refused_with_both_locations() {
    let urdf = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n<link name=\"c\"/>\n\
                <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/></joint>\n\
                <joint name=\"j\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/></joint>\n\
                </robot>\n";
    refused(
        "urdf_joint",
        "r.urdf",
        urdf,
        "joint `j` is defined twice",
        &["5:1", "6:1"],
    );
}

/// An OpenSim 3 model: `bodies` holds the `<Body>` elements after the ground.
fn osim3(bodies: &str) -> String {
    format!(
        "<OpenSimDocument Version=\"30000\">\n<Model name=\"m\">\n<BodySet>\n<objects>\n\
         <Body name=\"ground\"><Joint/></Body>\n{bodies}</objects>\n</BodySet>\n</Model>\n\
         </OpenSimDocument>\n"
    )
}

/// An OpenSim 3 body `name` with a joint `<tag name=joint>` to `parent`, `coords` inside.
fn osim3_body(name: &str, tag: &str, joint: &str, parent: &str, coords: &str) -> String {
    format!(
        "<Body name=\"{name}\"><Joint><{tag} name=\"{joint}\"><parent_body>{parent}</parent_body>\
         <CoordinateSet><objects>{coords}</objects></CoordinateSet></{tag}></Joint></Body>\n"
    )
}

fn coord(name: &str, default: &str) -> String {
    format!("<Coordinate name=\"{name}\">{default}</Coordinate>")
}

#[test]
fn repeated_opensim_body_and_joint_names_are_refused_with_both_locations() {
    let q = coord("q", "");
    let two_bodies = osim3(&format!(
        "{}{}",
        osim3_body("a", "PinJoint", "p1", "ground", &q),
        osim3_body("a", "PinJoint", "p2", "a", &coord("q2", ""))
    ));
    refused(
        "osim_body",
        "m.osim",
        &two_bodies,
        "body `a` is defined twice",
        &["6:1", "7:1"],
    );
    let two_joints = osim3(&format!(
        "{}{}",
        osim3_body("a", "PinJoint", "p", "ground", &q),
        osim3_body("b", "PinJoint", "p", "a", &coord("q2", ""))
    ));
    refused(
        "osim_joint",
        "m.osim",
        &two_joints,
        "joint `p` is defined twice",
        &["6:23", "7:23"],
    );
}

#[test]
fn repeated_sdformat_model_link_and_joint_names_are_refused_with_both_locations() {
    let link = "<link name=\"l\"/>";
    let models = format!(
        "<sdf version=\"1.7\">\n<world name=\"w\">\n<model name=\"m\">{link}</model>\n\
         <model name=\"m\">{link}</model>\n</world>\n</sdf>\n"
    );
    refused(
        "sdf_model",
        "w.sdf",
        &models,
        "model `m` is defined twice",
        &["3:1", "4:1"],
    );
    let links = "<sdf version=\"1.7\">\n<model name=\"m\">\n<link name=\"l\"/>\n<link name=\"l\"/>\n\
                 </model>\n</sdf>\n";
    refused(
        "sdf_link",
        "m.sdf",
        links,
        "link `l` is defined twice",
        &["3:1", "4:1"],
    );
    let joint = |n: &str, c: &str| {
        format!(
            "<joint name=\"{n}\" type=\"revolute\"><parent>world</parent><child>{c}</child><axis><xyz>0 0 1</xyz></axis></joint>"
        )
    };
    let joints = format!(
        "<sdf version=\"1.7\">\n<model name=\"m\">\n<link name=\"a\"/><link name=\"b\"/>\n{}\n{}\n\
         </model>\n</sdf>\n",
        joint("j", "a"),
        joint("j", "b")
    );
    refused(
        "sdf_joint",
        "m.sdf",
        &joints,
        "joint `j` is defined twice",
        &["4:1", "5:1"],
    );
}

/// The summary line of `mbsa import`: `N bodies, M joints`.
fn summary(test: &str, name: &str, text: &str) -> String {
    let (code, _, err) = import(test, name, text);
    assert_eq!(code, 0, "{test}: {err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("imported "))
        .unwrap_or_else(|| panic!("{test}: no summary in {err}"));
    line.split(": ").nth(1).unwrap_or("").to_string()
}

#[test]
fn user_bodies_named_like_the_importers_own_bodies_stay_apart() {
    // Body `a` has two joints: the first ends on a virtual body; the user's `a~1` is another.
    let virtual_name = "<mujoco>\n<worldbody>\n<body name=\"a\"><joint/><joint axis=\"1 0 0\"/>\n\
                        <body name=\"a~1\"><joint/></body>\n</body>\n</worldbody>\n</mujoco>\n";
    let s = summary("virtual", "m.xml", virtual_name);
    assert!(s.starts_with("4 bodies, 3 joints"), "{s}");
    let (_, out, _) = {
        let d = dir("virtual_mobility");
        let p = write(&d, "m.xml", virtual_name);
        mbsa(&["mobility", &p, "--format", "json"])
    };
    let v: serde_json::Value = serde_json::from_str(&out).expect("mobility JSON");
    assert_eq!(v["mobility"]["count"], 3, "{out}");
    // An unnamed body is `body1` inside; a named `body1` is another body.
    let unnamed = "<mujoco>\n<worldbody>\n<body><joint/>\n<body name=\"body1\"><joint/></body>\n\
                   </body>\n</worldbody>\n</mujoco>\n";
    let s = summary("unnamed", "m.xml", unnamed);
    assert!(s.starts_with("3 bodies, 2 joints"), "{s}");
}

/// The imported TOML of `text` (named `name`), through the library.
fn toml_of(name: &str, text: &str) -> String {
    import_str(name, text, None, &ImportOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e:?}"))
        .toml
}

#[test]
fn quaternions_with_huge_components_keep_their_rotation() {
    // (1, 1, 0, 0) scaled: 90 degrees about x turns the joint's z axis to -y.
    let mjcf = "<mujoco><worldbody><body name=\"a\" quat=\"1e200 1e200 0 0\"><joint/></body>\
                </worldbody></mujoco>";
    let t = toml_of("m.xml", mjcf);
    assert!(t.contains("axis = [0, -1, 0]"), "{t}");
    let sdf = "<sdf version=\"1.9\"><model name=\"m\"><link name=\"a\">\
               <pose rotation_format=\"quat_xyzw\">0 0 0 1e200 0 0 1e200</pose></link>\
               <joint name=\"j\" type=\"revolute\"><parent>world</parent><child>a</child>\
               <axis><xyz expressed_in=\"a\">0 0 1</xyz></axis></joint></model></sdf>";
    let t = toml_of("m.sdf", sdf);
    assert!(t.contains("axis = [0, -1, 0]"), "{t}");
    // Axes of 1e308s are directions too, not "zero length".
    let urdf = "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" \
                type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\
                <axis xyz=\"1e308 1e308 1e308\"/></joint></robot>";
    let t = toml_of("r.urdf", urdf);
    assert!(
        t.contains("axis = [0.5773502692, 0.5773502692, 0.5773502692]"),
        "{t}"
    );
}

#[test]
fn opensim_default_values_that_are_not_one_number_are_refused_with_their_location() {
    for bad in ["nan", "inf", "abc", "", "1 2"] {
        let c = coord("q", &format!("<default_value>{bad}</default_value>"));
        let m = osim3(&osim3_body("a", "PinJoint", "p", "ground", &c));
        let (code, _, err) = import("osim_default", "m.osim", &m);
        assert_eq!(code, 2, "{bad}: {err}");
        assert!(err.contains("m.osim:6:"), "{bad}: {err}");
    }
}

#[test]
fn an_unknown_opensim_joint_without_coordinates_is_a_weld() {
    let m = osim3(&format!(
        "{}{}",
        osim3_body("a", "PinJoint", "p", "ground", &coord("q", "")),
        osim3_body("b", "EllipsoidJoint", "e", "a", "")
    ));
    let (code, _, err) = import("osim_weld", "m.osim", &m);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("imported as a weld"), "{err}");
    let d = dir("osim_weld_mobility");
    let p = write(&d, "m.osim", &m);
    let (_, out, _) = mbsa(&["mobility", &p, "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&out).expect("mobility JSON");
    assert_eq!(v["mobility"]["count"], 1, "{out}");
}

#[test]
fn an_sdformat_include_is_warned() {
    let sdf = "<sdf version=\"1.7\">\n<model name=\"m\">\n<link name=\"a\"/>\n\
               <include><uri>model://arm</uri></include>\n<joint name=\"j\" type=\"revolute\">\
               <parent>world</parent><child>a</child><axis><xyz>0 0 1</xyz></axis></joint>\n\
               </model>\n</sdf>\n";
    let (code, _, err) = import("sdf_include", "m.sdf", sdf);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("m.sdf:4:1: <include> of a model by URI"),
        "{err}"
    );
}

/// An MJCF model that includes `file`.
fn including(file: &str) -> String {
    format!(
        "<mujoco>\n<worldbody>\n<body name=\"a\"><joint/>\n<include file=\"{file}\"/>\n</body>\n\
         </worldbody>\n</mujoco>\n"
    )
}

#[test]
fn includes_of_devices_fifos_and_files_over_the_limit_are_refused() {
    let (code, _, err) = import("dev_zero", "m.xml", &including("/dev/zero"));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a regular file"), "{err}");
    let d = dir("fifo");
    let fifo = d.join("pipe.xml");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let p = write(&d, "m.xml", &including("pipe.xml"));
        let (code, _, err) = mbsa(&["import", &p]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("not a regular file"), "{err}");
    }
    // The main file and its includes share the input limit.
    let d = dir("limit");
    let body = format!("<mujoco><!-- {} --></mujoco>", "x".repeat(2000));
    write(&d, "big.xml", &body);
    let p = write(&d, "m.xml", &including("big.xml"));
    let (code, _, err) = mbsa(&["import", &p, "--max-input-bytes", "1500"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--max-input-bytes"), "{err}");
    let (code, _, err) = mbsa(&["import", &p, "--max-input-bytes", "4000"]);
    assert_eq!(code, 0, "{err}");
    // A file's size is checked before it is read: a sparse terabyte is refused at once, its
    // size said (read first, it would take up to the limit and say "more than").
    let sparse = std::fs::File::create(d.join("sparse.xml")).expect("sparse file");
    sparse.set_len(1 << 40).expect("sparse length");
    let p = write(&d, "s.xml", &including("sparse.xml"));
    let (code, _, err) = mbsa(&["import", &p]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("needs 1 TiB") || err.contains("1099511627"),
        "{err}"
    );
    // The library honours its own limit on the main file, before reading it.
    let small = ImportOptions {
        max_input_bytes: Some(100),
        ..ImportOptions::default()
    };
    let e = import_file(&d.join("big.xml"), &small).expect_err("over the limit");
    assert!(e.message().contains("input size limit"), "{e}");
}

#[test]
fn an_include_that_is_not_xml_is_refused_without_quoting_it() {
    let d = dir("not_xml");
    write(
        &d,
        "secret.xml",
        "root:x:0:0:root:/root:/bin/bash\nsecret line\n",
    );
    let p = write(&d, "m.xml", &including("secret.xml"));
    let (code, _, err) = mbsa(&["import", &p]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("is not XML"), "{err}");
    assert!(
        !err.contains("root:x") && !err.contains("secret line"),
        "{err}"
    );
}

#[test]
fn long_names_are_cut_in_errors() {
    let name = "n".repeat(100_000);
    let mjcf = format!(
        "<mujoco>\n<worldbody>\n<body name=\"{name}\"><joint/></body>\n\
         <body name=\"{name}\"><joint/></body>\n</worldbody>\n</mujoco>\n"
    );
    let (code, _, err) = import("long_name", "m.xml", &mjcf);
    assert_eq!(code, 2, "{}", &err[..err.len().min(2000)]);
    assert!(err.len() < 5000, "{} bytes of error", err.len());
    assert!(err.contains(&format!("`{}…`", "n".repeat(60))), "{err}");
}

#[test]
fn long_names_are_cut_in_warnings() {
    let name = "e".repeat(100_000);
    let m = osim3(&format!(
        "{}{}",
        osim3_body("a", "PinJoint", "p", "ground", &coord("q", "")),
        osim3_body("b", "EllipsoidJoint", &name, "a", &coord("q2", ""))
    ));
    let (code, _, err) = import("long_warning", "m.osim", &m);
    assert_eq!(code, 0, "{}", &err[..err.len().min(2000)]);
    assert!(err.len() < 5000, "{} bytes of warnings", err.len());
    assert!(err.contains(&format!("`{}…`", "e".repeat(60))), "{err}");
}

#[test]
fn import_does_not_overwrite_its_input_and_writes_whole_files() {
    let d = dir("output");
    let text = "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" \
                type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>";
    let p = write(&d, "r.urdf", text);
    let (code, _, err) = mbsa(&["import", &p, "-o", &p]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("is the input file"), "{err}");
    assert_eq!(std::fs::read_to_string(&p).expect("source"), text);
    let out = d.join("r.toml").display().to_string();
    let (code, _, err) = mbsa(&["import", &p, "-o", &out]);
    assert_eq!(code, 0, "{err}");
    let written = std::fs::read_to_string(&out).expect("output");
    assert!(written.contains("[[joint]]"), "{written}");
    let names: Vec<String> = std::fs::read_dir(&d)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "a temporary file left: {names:?}");
}

#[test]
fn huge_positions_and_empty_link_names_are_located_input_errors() {
    let mjcf = "<mujoco>\n<worldbody>\n<body name=\"a\" pos=\"1e19 0 0\"><joint/></body>\n\
                </worldbody>\n</mujoco>\n";
    refused("huge_pos", "m.xml", mjcf, "beyond 1e18", &["3:"]);
    // Each in range, summed out of it.
    let chain = "<mujoco>\n<worldbody>\n<body name=\"a\" pos=\"9e17 0 0\">\n\
                 <body name=\"b\" pos=\"9e17 0 0\"><joint/></body>\n</body>\n</worldbody>\n</mujoco>\n";
    refused("summed_pos", "m.xml", chain, "beyond 1e18", &["4:"]);
    let urdf = "<robot name=\"r\">\n<link name=\"\"/>\n<link name=\"b\"/>\n</robot>\n";
    refused("empty_link", "r.urdf", urdf, "empty `name`", &["2:"]);
}

#[test]
fn an_element_with_a_hundred_thousand_attributes_is_refused_in_linear_time() {
    let attrs: String = (0..100_000).map(|i| format!(" a{i}=\"1\"")).collect();
    let text = format!("<mujoco>\n<worldbody{attrs}/>\n</mujoco>\n");
    let t = std::time::Instant::now();
    let e = import_str("m.xml", &text, None, &ImportOptions::default()).expect_err("refused");
    eprintln!("100000 attributes: {:?}", t.elapsed());
    assert!(e.message().contains("more than 128 attributes"), "{e}");
    assert_eq!(e.location().map(|l| (l.1, l.2)), Some((2, 1)), "{e}");
    // 128 attributes, each once, are read (`name` and 127 others).
    let attrs: String = (0..127).map(|i| format!(" a{i}=\"1\"")).collect();
    let text =
        format!("<mujoco><worldbody><body name=\"b\"{attrs}><joint/></body></worldbody></mujoco>");
    toml_of("m.xml", &text);
}

#[test]
fn a_long_urdf_chain_is_read_in_near_linear_time() {
    // Links then joints in reverse order: each joint's parent is reached last.
    let n = 100_000;
    let mut t = String::from("<robot name=\"chain\">\n");
    for i in 0..=n {
        t.push_str(&format!("<link name=\"l{i}\"/>\n"));
    }
    for i in (0..n).rev() {
        t.push_str(&format!(
            "<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{i}\"/><child link=\"l{}\"/>\
             <origin xyz=\"0 0 0.125\"/><axis xyz=\"0 1 0\"/></joint>\n",
            i + 1
        ));
    }
    t.push_str("</robot>\n");
    let start = std::time::Instant::now();
    let i = import_str("chain.urdf", &t, None, &ImportOptions::default()).expect("imports");
    eprintln!("URDF chain of {n} links: {:?}", start.elapsed());
    assert_eq!(i.mechanism.joints.len(), n);
    assert!(
        i.toml.contains("origin = [0, 0, 12500]"),
        "the last joint is 12500 up"
    );
    // Quadratic reading took 40 s here (release); linear, under a second in debug.
    assert!(start.elapsed().as_secs() < 20, "{:?}", start.elapsed());
}

/// The hand-written OpenSim four-bar with its PointConstraint replaced by a WeldConstraint of
/// the coupler's tip to the rocker's, the rocker's frame turned by `turn` about z.
fn four_bar_welded(turn: f64) -> String {
    let text = std::fs::read_to_string("tests/fixtures/import/four_bar_point_constraint.osim")
        .expect("fixture");
    let start = text.find("<PointConstraint").expect("point constraint");
    let end = text.find("</PointConstraint>").expect("its end") + "</PointConstraint>".len();
    let weld = format!(
        "<WeldConstraint name=\"C\">\
         <socket_frame1>coupler_tip</socket_frame1><socket_frame2>rocker_tip</socket_frame2>\
         <frames>\
         <PhysicalOffsetFrame name=\"coupler_tip\"><socket_parent>/bodyset/coupler</socket_parent>\
         <translation>2 0 0</translation><orientation>0 0 0</orientation></PhysicalOffsetFrame>\
         <PhysicalOffsetFrame name=\"rocker_tip\"><socket_parent>/bodyset/rocker</socket_parent>\
         <translation>1 0 0</translation><orientation>0 0 {turn}</orientation></PhysicalOffsetFrame>\
         </frames></WeldConstraint>"
    );
    format!("{}{weld}{}", &text[..start], &text[end..])
}

#[test]
fn an_opensim_weld_constraint_open_at_the_default_coordinates_is_welded_where_it_closes() {
    // The rocker stands at 90°, so its tip frame turned by -90° meets the coupler's: closed.
    let closed = four_bar_welded(-std::f64::consts::FRAC_PI_2);
    let (code, out, err) = import("osim_weld_closed", "m.osim", &closed);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("not closed"), "{err}");
    assert!(out.contains("`rocker` welded to `coupler`"), "{out}");
    // Turned by 0.3 rad more, the weld is open: the rocker is moved where it closes and its
    // hinge to the ground carries the rocker's side in `second` (it was welded as placed,
    // silently).
    let open = four_bar_welded(-std::f64::consts::FRAC_PI_2 + 0.3);
    let (code, out, err) = import("osim_weld_open", "m.osim", &open);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("(gap 0.000e0, angle 3.000e-1 rad): `rocker` is welded where the cut puts it"),
        "{err}"
    );
    assert!(
        out.contains("[joint.second]") || out.contains("second ="),
        "{out}"
    );
    let d = dir("osim_weld_assemble");
    let p = write(&d, "m.toml", &out);
    let (code, _, err) = mbsa(&["assemble", &p]);
    assert_eq!(code, 0, "{err}");
}
