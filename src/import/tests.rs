use super::*;

#[test]
fn sniff_roots() {
    assert_eq!(
        SourceFormat::sniff("<?xml version=\"1.0\"?>\n<!-- c -->\n<mujoco model=\"x\">"),
        Some(SourceFormat::Mjcf)
    );
    assert_eq!(
        SourceFormat::sniff("<sdf version='1.7'>"),
        Some(SourceFormat::Sdf)
    );
    assert_eq!(
        SourceFormat::sniff("<robot name='r'>"),
        Some(SourceFormat::Urdf)
    );
    assert_eq!(
        SourceFormat::sniff("<OpenSimDocument Version=\"40000\">"),
        Some(SourceFormat::Osim)
    );
    assert_eq!(SourceFormat::sniff("name = 'x'"), None);
}

fn mjcf(text: &str) -> Import {
    import_str("t.xml", text, None, &ImportOptions::default()).unwrap_or_else(|e| panic!("{e:?}"))
}

fn mjcf_key(text: &str, key: &str) -> Import {
    let o = ImportOptions {
        keyframe: Some(key.into()),
        ..ImportOptions::default()
    };
    import_str("t.xml", text, None, &o).unwrap_or_else(|e| panic!("{e:?}"))
}

fn geom<'a>(i: &'a Import, id: &str) -> &'a crate::Geometry {
    &i.mechanism
        .joints
        .iter()
        .find(|j| j.id == id)
        .unwrap_or_else(|| panic!("no joint {id}: {}", i.toml))
        .geometry
}

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6)
}

#[track_caller]
fn assert_axis(i: &Import, id: &str, axis: [f64; 3], origin: [f64; 3]) {
    let g = geom(i, id);
    let a = g.axis.expect("axis");
    let o = g.origin.expect("origin");
    assert!(
        close(a, axis),
        "{id}: axis {a:?}, expected {axis:?}\n{}",
        i.toml
    );
    assert!(
        close(o, origin),
        "{id}: origin {o:?}, expected {origin:?}\n{}",
        i.toml
    );
}

/// One body per orientation form, each rotating the local x axis onto world y (at pos 1 0 0).
#[test]
fn mjcf_orientation_forms() {
    let i = mjcf(
        r#"<mujoco><worldbody>
        <body name="q" pos="1 0 0" quat="0.70710678 0 0 0.70710678"><joint name="q" axis="1 0 0"/></body>
        <body name="aa" pos="1 0 0" axisangle="0 0 1 90"><joint name="aa" axis="1 0 0"/></body>
        <body name="eu" pos="1 0 0" euler="0 0 90"><joint name="eu" axis="1 0 0"/></body>
        <body name="xy" pos="1 0 0" xyaxes="0 1 0 -1 0 0"><joint name="xy" axis="1 0 0"/></body>
        <body name="z" pos="1 0 0" zaxis="0 1 0"><joint name="z" axis="0 0 1"/></body>
        </worldbody></mujoco>"#,
    );
    for id in ["q", "aa", "eu", "xy", "z"] {
        assert_axis(&i, id, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]);
    }
}

#[test]
fn mjcf_euler_sequences_and_radians() {
    // Intrinsic xyz (moving axes): Rx(90) Ry(90) maps x to y.
    let i = mjcf(
        r#"<mujoco><compiler angle="radian"/><worldbody>
        <body name="b" euler="1.5707963267948966 1.5707963267948966 0"><joint name="j" axis="1 0 0"/></body>
        </worldbody></mujoco>"#,
    );
    assert_axis(&i, "j", [0.0, 1.0, 0.0], [0.0; 3]);
    // Extrinsic XYZ (fixed axes): Ry(90) Rx(90) maps x to -z.
    let i = mjcf(
        r#"<mujoco><compiler eulerseq="XYZ"/><worldbody>
        <body name="b" euler="90 90 0"><joint name="j" axis="1 0 0"/></body>
        </worldbody></mujoco>"#,
    );
    assert_axis(&i, "j", [0.0, 0.0, -1.0], [0.0; 3]);
}

#[test]
fn mjcf_frames_compose_down_the_tree() {
    let i = mjcf(
        r#"<mujoco><worldbody>
        <body name="a" pos="0 0 1" euler="0 0 90"><joint name="a" pos="1 0 0" axis="1 0 0"/>
          <body name="b" pos="2 0 0"><joint name="b" axis="0 1 0"/>
            <frame pos="0 0 1" euler="90 0 0"><body name="c"><joint name="c" pos="0 1 0" axis="0 1 0"/></body></frame>
          </body>
        </body>
        </worldbody></mujoco>"#,
    );
    assert_axis(&i, "a", [0.0, 1.0, 0.0], [0.0, 1.0, 1.0]);
    assert_axis(&i, "b", [-1.0, 0.0, 0.0], [0.0, 2.0, 1.0]);
    // c's frame: a's rotation (z 90) then x 90; joint pos (0,1,0) -> local (0,0,1) -> world (0,0,1).
    assert_axis(&i, "c", [0.0, 0.0, 1.0], [0.0, 2.0, 3.0]);
}

#[test]
fn mjcf_defaults_childclass_and_joint_kinds() {
    let i = mjcf(
        r#"<mujoco><default>
          <joint axis="0 1 0"/>
          <default class="slider"><joint type="slide" axis="1 0 0"/>
            <default class="sub"><joint axis="0 0 1"/></default></default>
        </default><worldbody>
        <body name="a"><joint name="a"/>
          <body name="s" childclass="slider"><joint name="s"/>
            <body name="t"><joint name="t" class="sub"/><joint name="h" type="hinge" class="main"/></body>
          </body>
          <body name="ball"><joint name="ball" type="ball" pos="0 0 2"/></body>
          <body name="free"><freejoint name="free"/></body>
          <body name="welded"/>
        </body>
        </worldbody></mujoco>"#,
    );
    let m = &i.mechanism;
    let kind = |id: &str| m.joints.iter().find(|j| j.id == id).map(|j| j.kind);
    assert_eq!(kind("a"), Some(JointType::R));
    assert_axis(&i, "a", [0.0, 1.0, 0.0], [0.0; 3]);
    assert_eq!(kind("s"), Some(JointType::P));
    assert_axis(&i, "s", [1.0, 0.0, 0.0], [0.0; 3]);
    assert_eq!(kind("t"), Some(JointType::P));
    assert_axis(&i, "t", [0.0, 0.0, 1.0], [0.0; 3]);
    assert_eq!(kind("h"), Some(JointType::R));
    assert_axis(&i, "h", [0.0, 1.0, 0.0], [0.0; 3]);
    assert_eq!(kind("ball"), Some(JointType::S));
    assert!(close(
        geom(&i, "ball").origin.expect("origin"),
        [0.0, 0.0, 2.0]
    ));
    assert_eq!(kind("free"), Some(JointType::F));
    // Two joints in body t: a chain through a virtual body.
    let t = m.joints.iter().find(|j| j.id == "t").expect("t");
    assert_eq!(m.body_id(t.bodies[1]).to_string(), "t~1");
    // The body without joints is welded to its parent.
    assert!(m.bodies.iter().all(|b| b.id.to_string() != "welded"));
    assert!(i.notes.iter().any(|n| n.contains("`welded` welded to `a`")));
}

#[test]
fn mjcf_keyframes_and_ref() {
    let text = r#"<mujoco><worldbody>
        <body name="a"><joint name="a" axis="0 0 1" ref="90"/>
          <body name="b" pos="1 0 0"><joint name="b" axis="0 1 0"/>
            <body name="c" pos="0 0 1"><joint name="c" type="slide" axis="1 0 0"/>
              <body name="d" pos="1 0 0"><joint name="d" axis="1 0 0"/></body></body></body>
        </body></worldbody>
        <keyframe><key name="zero" qpos="1.5707963267948966 0 0 0"/><key name="turned" qpos="3.141592653589793 0 0.5 0"/></keyframe>
        </mujoco>"#;
    let i0 = mjcf(text);
    assert_axis(&i0, "b", [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]);
    let z = mjcf_key(text, "zero");
    assert_axis(&z, "b", [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]);
    // qpos - ref = 90 degrees about z; the slide moves d by 0.5 along c's x (now world y).
    let t = mjcf_key(text, "turned");
    assert_axis(&t, "b", [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    assert_axis(&t, "c", [0.0, 1.0, 0.0], [0.0, 1.0, 1.0]);
    assert_axis(&t, "d", [0.0, 1.0, 0.0], [0.0, 2.5, 1.0]);
    // By index too; unknown names list the keys.
    let by_index = mjcf_key(text, "1");
    assert_eq!(
        by_index.toml.lines().skip(2).collect::<Vec<_>>(),
        t.toml.lines().skip(2).collect::<Vec<_>>()
    );
    let o = ImportOptions {
        keyframe: Some("nope".into()),
        ..ImportOptions::default()
    };
    let e = import_str("t.xml", text, None, &o).unwrap_err();
    assert!(e.hint().unwrap_or("").contains("`zero`, `turned`"), "{e:?}");
}

#[test]
fn mjcf_equality_and_actuators() {
    let text = r#"<mujoco><worldbody>
        <body name="crank" pos="0 0 0"><joint name="crank"/>
          <body name="rod" pos="1 0 0"><joint name="rod"/><site name="s1" pos="2 0 0"/></body></body>
        <body name="rocker" pos="3 0 0"><joint name="rocker"/><site name="s2" pos="0 0 0"/></body>
        <body name="lid" pos="0 0 5"><joint name="lid" type="slide"/></body>
        <body name="cap" pos="0 0 6"><freejoint/></body>
        </worldbody>
        <equality>
          <connect name="loop" body1="rod" body2="rocker" anchor="2 0 0"/>
          <connect site1="s1" site2="s2"/>
          <weld body1="cap" body2="lid"/>
          <joint joint1="crank" joint2="rocker"/>
        </equality>
        <actuator><motor joint="crank"/><position name="p" joint="lid"/><motor tendon="t"/></actuator>
        </mujoco>"#;
    let i = mjcf(text);
    let m = &i.mechanism;
    let lp = m.joints.iter().find(|j| j.id == "loop").expect("loop");
    assert_eq!(lp.kind, JointType::S);
    assert!(close(lp.geometry.origin.expect("origin"), [3.0, 0.0, 0.0]));
    assert!(m.joints.iter().any(|j| j.id == "connect:rod-rocker"));
    // The free joint of `cap` went with the weld: cap and lid are one body.
    let free = m
        .joints
        .iter()
        .find(|j| j.id == "cap:free")
        .expect("cap:free");
    assert_eq!(m.body_id(free.bodies[1]).to_string(), "cap");
    let lid = m.joints.iter().find(|j| j.id == "lid").expect("lid");
    assert_eq!(m.body_id(lid.bodies[1]).to_string(), "cap");
    assert!(
        i.warnings
            .iter()
            .any(|w| w.contains("<joint> equality coupling: not representable"))
    );
    assert!(i.warnings.iter().any(|w| w.contains("acts through tendon")));
    assert_eq!(m.inputs(), 2);
    // The four-bar crank-rod-rocker is planar: count 1 - 3 (redundant) with the second connect.
    assert!(i.toml.contains("# driven by <position name=\"p\">"));
}

#[test]
fn mjcf_errors_are_located() {
    let e = import_str(
        "t.xml",
        "<mujoco><worldbody>\n<body name=\"a\" quat=\"1 0 0\"/></worldbody></mujoco>",
        None,
        &ImportOptions::default(),
    )
    .unwrap_err();
    assert_eq!(e.location().map(|l| (l.1, l.2)), Some((2, 22)), "{e:?}");
    assert!(e.message().contains("expected 4 numbers"));
    let e = import_str(
        "t.xml",
        "<mujoco>\n  <worldbody>\n</mujoco>",
        None,
        &ImportOptions::default(),
    )
    .unwrap_err();
    assert!(e.message().starts_with("malformed XML"), "{e:?}");
    assert_eq!(e.location().map(|l| l.1), Some(3));
    let e = import_str(
        "t.xml",
        "<mujoco><worldbody><body name=\"a\"><joint name=\"j\" type=\"hing\"/></body></worldbody></mujoco>",
        None,
        &ImportOptions::default(),
    )
    .unwrap_err();
    assert!(e.message().contains("unknown joint type `hing`"));
    let e = import_str(
        "t.xml",
        "<mujoco><worldbody><body name=\"a\"><joint/></body></worldbody><actuator><motor joint=\"x\"/></actuator></mujoco>",
        None,
        &ImportOptions::default(),
    )
    .unwrap_err();
    assert!(e.message().contains("names joint `x`"), "{e:?}");
    let e = import_str(
        "t.xml",
        "<robot name='r'/>",
        None,
        &ImportOptions {
            format: Some(SourceFormat::Mjcf),
            ..ImportOptions::default()
        },
    )
    .unwrap_err();
    assert!(e.message().contains("expected a <mujoco> root"), "{e:?}");
}

#[test]
fn numbers_are_written_short() {
    assert_eq!(num(0.1 + 0.2), "0.3");
    assert_eq!(num(6.123e-17), "0");
    assert_eq!(num(-1e-12), "0");
    assert_eq!(num(-0.5), "-0.5");
    assert_eq!(num(2.0), "2");
}

fn urdf(text: &str) -> Import {
    import_str("t.urdf", text, None, &ImportOptions::default()).unwrap_or_else(|e| panic!("{e:?}"))
}

#[test]
fn urdf_joint_kinds_transmissions_mimic_and_ball_constraints() {
    let i = urdf(
        r#"<robot name="r" xmlns:drake="http://drake.mit.edu">
        <link name="base"/><link name="a"/><link name="b"/><link name="c"/><link name="d"/><link name="e"/><link name="f"/>
        <joint name="ja" type="revolute"><parent link="base"/><child link="a"/>
          <origin xyz="0 0 1" rpy="0 0 1.5707963267948966"/><axis xyz="1 0 0"/></joint>
        <joint name="jb" type="prismatic"><parent link="a"/><child link="b"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>
        <joint name="jc" type="fixed"><parent link="b"/><child link="c"/><origin xyz="0 0 5"/></joint>
        <joint name="jd" type="planar"><parent link="c"/><child link="d"/><axis xyz="0 0 1"/></joint>
        <joint name="je" type="floating"><parent link="base"/><child link="e"/></joint>
        <joint name="jf" type="continuous"><parent link="e"/><child link="f"/><mimic joint="ja" multiplier="2"/></joint>
        <transmission name="t1"><type>transmission_interface/SimpleTransmission</type>
          <joint name="ja"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>
          <actuator name="m1"/></transmission>
        <transmission name="t2"><joint name="jc"/></transmission>
        <drake:ball_constraint>
          <drake:ball_constraint_body_A name="d"/><drake:ball_constraint_p_AP value="0 0 0"/>
          <drake:ball_constraint_body_B name="f"/><drake:ball_constraint_p_BQ value="0 1 0"/>
        </drake:ball_constraint>
        </robot>"#,
    );
    let m = &i.mechanism;
    let kind = |id: &str| m.joints.iter().find(|j| j.id == id).map(|j| j.kind);
    assert_eq!(kind("ja"), Some(JointType::R));
    assert_axis(&i, "ja", [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    assert_eq!(kind("jb"), Some(JointType::P));
    assert_axis(&i, "jb", [0.0, 0.0, 1.0], [0.0, 1.0, 1.0]);
    assert_eq!(kind("jc"), None);
    assert_eq!(kind("jd"), Some(JointType::PL));
    let jd = m.joints.iter().find(|j| j.id == "jd").expect("jd");
    assert_eq!(
        m.body_id(jd.bodies[0]).to_string(),
        "b",
        "c is welded into b"
    );
    assert!(close(jd.geometry.normal.expect("normal"), [0.0, 0.0, 1.0]));
    assert!(close(jd.geometry.origin.expect("origin"), [0.0, 1.0, 6.0]));
    assert_eq!(kind("je"), Some(JointType::F));
    assert_eq!(kind("ball:d-f"), Some(JointType::S));
    assert_eq!(m.inputs(), 1);
    assert!(
        i.warnings.iter().any(|w| w.contains("mimics `ja`")),
        "{:?}",
        i.warnings
    );
    assert!(
        i.warnings
            .iter()
            .any(|w| w.contains("names joint `jc`, which is fixed"))
    );
    assert!(
        i.warnings
            .iter()
            .any(|w| w.contains("ball_constraint between `d` and `f` is not closed"))
    );
}

#[test]
fn urdf_errors() {
    let err = |t: &str| import_str("t.urdf", t, None, &ImportOptions::default()).unwrap_err();
    let e = err(r#"<robot name="r"><link name="a"/><link name="b"/>
        <joint name="j" type="hinge"><parent link="a"/><child link="b"/></joint></robot>"#);
    assert!(e.message().contains("unknown type `hinge`"), "{e:?}");
    let e = err(r#"<robot name="r"><link name="a"/><link name="b"/>
        <joint name="j" type="revolute"><parent link="a"/><child link="c"/></joint></robot>"#);
    assert!(
        e.message().contains("link `c`, which is not defined"),
        "{e:?}"
    );
    assert_eq!(e.location().map(|l| l.1), Some(2));
    let e = err(
        r#"<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
        <joint name="j" type="revolute"><parent link="a"/><child link="b"/></joint>
        <joint name="k" type="revolute"><parent link="c"/><child link="b"/></joint></robot>"#,
    );
    assert!(e.message().contains("child of joints `j` and `k`"), "{e:?}");
}

fn sdf(text: &str) -> Import {
    import_str("t.sdf", text, None, &ImportOptions::default()).unwrap_or_else(|e| panic!("{e:?}"))
}

/// The same model under the pre-1.7 rules: link poses in the model frame, the joint pose in
/// the child link's frame, the axis in the model frame (1.4) or the joint frame (1.5, 1.6,
/// unless use_parent_model_frame).
fn old_sdf(version: &str, upm: bool) -> String {
    format!(
        r#"<sdf version="{version}"><model name="m">
        <pose>0 0 1 0 0 1.5707963267948966</pose>
        <link name="L"><pose>1 0 0 0 0 1.5707963267948966</pose></link>
        <joint name="J" type="revolute"><pose>0 0 0.5 0 0 0</pose><parent>world</parent><child>L</child>
          <axis><xyz>1 0 0</xyz>{}</axis></joint>
        </model></sdf>"#,
        if upm {
            "<use_parent_model_frame>true</use_parent_model_frame>"
        } else {
            ""
        }
    )
}

#[test]
fn sdf_pre_1_7_frame_rules() {
    assert_axis(
        &sdf(&old_sdf("1.4", false)),
        "J",
        [0.0, 1.0, 0.0],
        [0.0, 1.0, 1.5],
    );
    assert_axis(
        &sdf(&old_sdf("1.5", false)),
        "J",
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 1.5],
    );
    assert_axis(
        &sdf(&old_sdf("1.6", true)),
        "J",
        [0.0, 1.0, 0.0],
        [0.0, 1.0, 1.5],
    );
}

#[test]
fn sdf_1_7_relative_to_frames_and_expressed_in() {
    let i = sdf(r#"<sdf version="1.7"><model name="m">
        <frame name="F" attached_to="__model__"><pose>0 0 2 0 0 0</pose></frame>
        <link name="L"><pose relative_to="F">1 0 0 0 0 1.5707963267948966</pose></link>
        <link name="L2"/>
        <joint name="J1" type="revolute"><pose>1 0 0 0 0 0</pose><parent>world</parent><child>L</child>
          <axis><xyz>1 0 0</xyz></axis></joint>
        <joint name="J2" type="prismatic"><pose relative_to="__model__">0 0 0 0 0 0</pose><parent>L</parent><child>L2</child>
          <axis><xyz expressed_in="__model__">1 0 0</xyz></axis></joint>
        <joint name="J3" type="universal"><pose relative_to="F"/><parent>L</parent><child>L2</child>
          <axis><xyz expressed_in="L">1 0 0</xyz></axis><axis2><xyz>0 0 1</xyz></axis2></joint>
        </model></sdf>"#);
    assert_axis(&i, "J1", [0.0, 1.0, 0.0], [1.0, 1.0, 2.0]);
    assert_axis(&i, "J2", [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    assert_axis(&i, "J3", [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]);
    assert!(close(geom(&i, "J3").axis2.expect("axis2"), [0.0, 0.0, 1.0]));
}

/// SDFormat has no actuators: the import says no joint is driven, and each `<plugin>` of a
/// model (the controller that drives a Gazebo Delta robot's arms) gets a located warning, as
/// MJCF's unsupported elements do, where it used to be dropped without a word.
#[test]
fn sdf_plugins_are_warned_and_no_actuators_noted() {
    let i = sdf(r#"<sdf version="1.7"><model name="m">
        <plugin name="joint_controller" filename="libjoint_controller.so"/>
        <link name="L"/>
        <joint name="J" type="revolute"><parent>world</parent><child>L</child>
          <axis><xyz>0 0 1</xyz></axis></joint>
        </model></sdf>"#);
    assert!(
        i.notes
            .iter()
            .any(|n| n.starts_with("SDFormat declares no actuators")),
        "{:?}",
        i.notes
    );
    assert_eq!(i.warnings.len(), 1, "{:?}", i.warnings);
    let w = &i.warnings[0];
    assert!(
        w.starts_with("t.sdf:2:9: <plugin> `joint_controller`"),
        "{w}"
    );
    assert!(
        w.contains("libjoint_controller.so") && w.contains("--inputs"),
        "{w}"
    );
}

#[test]
fn sdf_1_9_degrees_and_quaternions_free_and_static_models() {
    let i = sdf(r#"<sdf version="1.9"><world name="w">
        <model name="a"><link name="L"><pose degrees="true">0 0 0 0 0 90</pose></link>
          <link name="K"><pose rotation_format="quat_xyzw">1 0 0 0 0 0.70710678 0.70710678</pose></link>
          <joint name="J" type="revolute"><parent>L</parent><child>K</child><axis><xyz>1 0 0</xyz></axis></joint>
        </model>
        <model name="b"><static>true</static><link name="L"/><link name="K"/>
          <joint name="J" type="ball"><parent>L</parent><child>K</child></joint></model>
        </world></sdf>"#);
    assert_axis(&i, "a::J", [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]);
    let m = &i.mechanism;
    let free = m
        .joints
        .iter()
        .find(|j| j.id == "a::L:free")
        .expect("model a floats");
    assert_eq!(free.kind, JointType::F);
    // Model b is static: its links are welded to the world, so its joint joins welded bodies,
    // named as the file names them (not the weld's result twice: `world`, `world`).
    assert!(
        i.warnings.iter().any(|w| w
            .contains("`b::J` joins bodies welded together (`b::L`, `b::K`, welded into `world`)")),
        "{:?}",
        i.warnings
    );
}

#[test]
fn sdf_errors() {
    let err = |t: &str| import_str("t.sdf", t, None, &ImportOptions::default()).unwrap_err();
    let e = err(r#"<sdf version="2.0"><model name="m"/></sdf>"#);
    assert!(e.message().contains("unknown SDFormat version"), "{e:?}");
    let e = err(
        "<sdf version=\"1.7\"><model name=\"m\"><link name=\"L\"/>\n<joint name=\"J\" type=\"revolute\"><parent>world</parent><child>X</child></joint></model></sdf>",
    );
    assert!(e.message().contains("names `X`"), "{e:?}");
    assert_eq!(e.location().map(|l| l.1), Some(2));
    let e = err(
        r#"<sdf version="1.7"><model name="m"><link name="L"><pose relative_to="L">0 0 0 0 0 0</pose></link>
        <joint name="J" type="revolute"><parent>world</parent><child>L</child><axis><xyz>0 0 1</xyz></axis></joint></model></sdf>"#,
    );
    assert!(e.message().contains("cycle"), "{e:?}");
}

#[test]
fn osim_coupled_custom_joint_is_reported_and_mapped_to_its_independent_coordinate() {
    let i = import_str(
        "t.osim",
        r#"<OpenSimDocument Version="30000"><Model name="knee"><BodySet><objects>
        <Body name="ground"><Joint/></Body>
        <Body name="femur"><Joint><CustomJoint name="hip"><parent_body>ground</parent_body>
          <location_in_parent>0 1 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
          <location>0 0 0</location><orientation>0 0 0</orientation>
          <SpatialTransform>
            <TransformAxis name="rotation1"><coordinates>hip_flex</coordinates><axis>0 0 1</axis><function><LinearFunction><coefficients>1 0</coefficients></LinearFunction></function></TransformAxis>
            <TransformAxis name="rotation2"><coordinates>hip_add</coordinates><axis>1 0 0</axis><function><LinearFunction><coefficients>1 0</coefficients></LinearFunction></function></TransformAxis>
            <TransformAxis name="rotation3"><coordinates>hip_rot</coordinates><axis>0 1 0</axis><function><LinearFunction><coefficients>1 0</coefficients></LinearFunction></function></TransformAxis>
          </SpatialTransform>
          <CoordinateSet><objects><Coordinate name="hip_flex"/><Coordinate name="hip_add"/><Coordinate name="hip_rot"/></objects></CoordinateSet>
        </CustomJoint></Joint></Body>
        <Body name="tibia"><Joint><CustomJoint name="knee"><parent_body>femur</parent_body>
          <location_in_parent>0 -0.4 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
          <location>0 0 0</location><orientation>0 0 0</orientation>
          <SpatialTransform>
            <TransformAxis name="rotation1"><coordinates>knee_angle</coordinates><axis>0 0 1</axis><function><LinearFunction><coefficients>1 0</coefficients></LinearFunction></function></TransformAxis>
            <TransformAxis name="translation1"><coordinates>knee_angle</coordinates><axis>1 0 0</axis>
              <function><SimmSpline><x>-2 0</x><y>-0.01 0.005</y></SimmSpline></function></TransformAxis>
          </SpatialTransform>
          <CoordinateSet><objects><Coordinate name="knee_angle"><default_value>0</default_value></Coordinate></objects></CoordinateSet>
        </CustomJoint></Joint></Body>
        </objects></BodySet>
        <ForceSet><objects><CoordinateActuator name="k"><coordinate>knee_angle</coordinate></CoordinateActuator>
          <TorqueActuator name="h"><body_A>ground</body_A><body_B>femur</body_B></TorqueActuator></objects></ForceSet>
        </Model></OpenSimDocument>"#,
        None,
        &ImportOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    let m = &i.mechanism;
    let kind = |id: &str| m.joints.iter().find(|j| j.id == id).map(|j| j.kind);
    assert_eq!(kind("hip"), Some(JointType::S));
    assert_eq!(kind("knee"), Some(JointType::R));
    assert_axis(&i, "knee", [0.0, 0.0, 1.0], [0.005, 0.6, 0.0]);
    assert!(
        i.warnings
            .iter()
            .any(|w| w.contains("coupled coordinates (knee_angle)")),
        "{:?}",
        i.warnings
    );
    assert_eq!(m.inputs(), 2);
}

/// The imported file's `precision`: the coarsest rounding of the source numbers read for the
/// geometry (angles in degrees converted to radians; a site only when a closure uses it),
/// at least the ±5e-11 of the importer's own 10 decimals; never the digits of the sums it
/// writes (0.1 + 0.0092 = 0.1092 is exact here).
#[test]
fn precision_comes_from_the_source_numbers() {
    let p = |i: &Import| i.mechanism.precision.expect("the import writes precision");
    let exact = mjcf(
        "<mujoco><worldbody><body pos=\"0.1 0 0\"><joint type=\"hinge\"/>\
         <body pos=\"0.0092 0 0\"><joint type=\"hinge\"/></body></body></worldbody></mujoco>",
    );
    assert!(
        exact.toml.contains("origin = [0.1092, 0, 0]"),
        "{}",
        exact.toml
    );
    assert_eq!(p(&exact), 0.0, "{}", exact.toml);
    // 6 decimals of a quaternion; the composed axes are rounded to 10 decimals.
    let cad = mjcf(
        "<mujoco><worldbody><body quat=\"0.965926 0 0 -0.258819\"><joint type=\"hinge\" \
         axis=\"1 0 0\"/></body></worldbody></mujoco>",
    );
    assert_eq!(p(&cad), 5e-7, "{}", cad.toml);
    let rotated = mjcf(
        "<mujoco><worldbody><body euler=\"0 0 30\"><joint type=\"hinge\" axis=\"1 0 0\"/>\
         </body></worldbody></mujoco>",
    );
    assert_eq!(p(&rotated), 5e-11, "{}", rotated.toml);
    // 30.25 degrees: ±0.005° = ±8.73e-5 rad.
    let degrees = mjcf(
        "<mujoco><worldbody><body euler=\"0 0 30.25\"><joint type=\"hinge\"/>\
         </body></worldbody></mujoco>",
    );
    assert_eq!(p(&degrees), 8.73e-5, "{}", degrees.toml);
    // A sensor site with 4-digit numbers counts only when a connect uses it.
    let site = |connect: &str| {
        mjcf(&format!(
            "<mujoco><worldbody><body name=\"a\"><joint type=\"hinge\"/>\
             <site name=\"s\" pos=\"0.1234 0 0\"/></body>\
             <body name=\"b\"><joint type=\"hinge\"/><site name=\"t\" pos=\"0.1234 0 0\"/>\
             </body></worldbody>{connect}</mujoco>"
        ))
    };
    assert_eq!(p(&site("")), 0.0);
    let used = site("<equality><connect site1=\"s\" site2=\"t\"/></equality>");
    assert_eq!(p(&used), 5e-5, "{}", used.toml);
    // URDF and SDFormat (degrees too).
    let urdf = import_str(
        "t.urdf",
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" \
         type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\
         <origin xyz=\"0.05 0 0.1225\" rpy=\"0 0 0\"/><axis xyz=\"0 0 1\"/></joint></robot>",
        None,
        &ImportOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(p(&urdf), 5e-5, "{}", urdf.toml);
    assert_eq!(precision_text(0.5 * 10f64.powi(-6)), "5e-7");
    assert_eq!(precision_text(0.005f64.to_radians()), "8.73e-5");
    assert_eq!(precision_text(0.0), "0");
}

#[test]
fn a_spaced_declaration_at_the_start_is_read_as_the_reference_loaders_read_it() {
    // The published Stewart platform SDF begins `<? xml version="1.0" ?>`: not well-formed,
    // but tinyxml2 (Gazebo, MuJoCo) takes any `<?` … `?>` first in the document as the
    // declaration. Every importer accepts it with a located warning; the rest of the
    // file's locations are unchanged.
    let decl = "<? xml version=\"1.0\" ?>\n";
    let cases: [(&str, String); 4] = [
        (
            "t.sdf",
            r#"<sdf version="1.6"><model name="m"><link name="L"/>
<joint name="J" type="revolute"><parent>world</parent><child>L</child><axis><xyz>0 0 1</xyz></axis></joint></model></sdf>"#
                .to_string(),
        ),
        (
            "t.urdf",
            r#"<robot name="r"><link name="a"/><link name="b"/>
<joint name="J" type="revolute"><parent link="a"/><child link="b"/></joint></robot>"#
                .to_string(),
        ),
        (
            "t.xml",
            "<mujoco><worldbody><body name=\"a\">\n<joint name=\"J\"/></body></worldbody></mujoco>"
                .to_string(),
        ),
        (
            "t.osim",
            r#"<OpenSimDocument Version="30000"><Model name="p"><BodySet><objects>
<Body name="ground"/><Body name="a"><Joint><PinJoint name="J"><parent_body>ground</parent_body>
<location_in_parent>0 0 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
<location>0 0 0</location><orientation>0 0 0</orientation></PinJoint></Joint></Body>
</objects></BodySet></Model></OpenSimDocument>"#
                .to_string(),
        ),
    ];
    for (name, body) in &cases {
        let clean = import_str(name, body, None, &ImportOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert!(
            clean.warnings.iter().all(|w| !w.contains("declaration")),
            "{name}: {:?}",
            clean.warnings
        );
        let spaced = format!("{decl}{body}");
        let i = import_str(name, &spaced, None, &ImportOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert_eq!(i.warnings.len(), clean.warnings.len() + 1, "{name}");
        let w = &i.warnings[0];
        assert!(
            w.starts_with(&format!("{name}:1:1: `<? xml version=\"1.0\" ?>`"))
                && w.contains("not a well-formed XML declaration")
                && w.contains("TinyXML"),
            "{name}: {w}"
        );
        assert_eq!(i.mechanism.joints.len(), clean.mechanism.joints.len());
        // The comments naming source lines are one line later, nothing else moves.
        assert!(i.toml.contains(&format!("{name}:3:")), "{name}: {}", i.toml);
        // An error after the tolerated line is located as before (one line down).
        let broken = format!("{decl}{}", body.replacen("name=\"J\"", "name=\"J\" <", 1));
        let e = import_str(name, &broken, None, &ImportOptions::default()).unwrap_err();
        assert!(e.message().starts_with("malformed XML"), "{name}: {e:?}");
        assert_eq!(e.location().map(|l| l.1), Some(3), "{name}: {e:?}");
    }
    // Two of them, and one after a well-formed declaration, are tolerated too (tinyxml2 reads
    // several declarations before the first other node).
    let body = &cases[0].1;
    let i = import_str(
        "t.sdf",
        &format!("<?xml version=\"1.0\"?>\n<?\txml version=\"1.0\"?>{decl}{body}"),
        None,
        &ImportOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(i.warnings.len(), 2, "{:?}", i.warnings);
    assert!(
        i.warnings[0].starts_with("t.sdf:2:1: `<?\txml"),
        "{:?}",
        i.warnings
    );
    assert!(i.warnings[1].starts_with("t.sdf:2:"), "{:?}", i.warnings);
    // Everything else stays an error: after a comment or inside the document (tinyxml2
    // rejects a declaration after another node), unterminated, or `<?` + a non-name.
    for bad in [
        format!("<!-- c -->\n{decl}{body}"),
        body.replacen("<model", &format!("{decl}<model"), 1),
        format!("<? xml version=\"1.0\"\n{body}"),
        format!("<?1xml?>{body}"),
    ] {
        let e = import_str("t.sdf", &bad, None, &ImportOptions::default()).unwrap_err();
        assert!(e.message().starts_with("malformed XML"), "{bad}: {e:?}");
    }
}

/// A CustomJoint that no single mbsa joint makes (the pelvis of OpenSim's leg39: one rotation
/// and three translations, 4 DOF; it was imported as F, 6) is the chain OpenSim composes: a
/// slider along each translation, then a hinge about each rotation axis through the joint's
/// origin, through massless virtual bodies whose names avoid the model's own; an actuator
/// drives its coordinate's joint of the chain.
#[test]
fn osim_custom_joint_no_single_joint_makes_is_a_chain_of_its_axes() {
    let lin =
        "<function><LinearFunction><coefficients>1 0</coefficients></LinearFunction></function>";
    let zero = "<function><Constant><value>0</value></Constant></function>";
    let text = format!(
        r#"<OpenSimDocument Version="30000"><Model name="leg"><BodySet><objects>
        <Body name="ground"><Joint/></Body>
        <Body name="pelvis~1"><Joint><PinJoint name="pin"><parent_body>pelvis</parent_body>
          <location_in_parent>0 0 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
          <location>0 0 0</location><orientation>0 0 0</orientation>
          <CoordinateSet><objects><Coordinate name="q"/></objects></CoordinateSet>
        </PinJoint></Joint></Body>
        <Body name="pelvis"><Joint><CustomJoint name="ground_pelvis"><parent_body>ground</parent_body>
          <location_in_parent>0 0 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
          <location>0 0 0</location><orientation>0 0 0</orientation>
          <SpatialTransform>
            <TransformAxis name="rotation1"><coordinates>tilt</coordinates><axis>0 0 1</axis>{lin}</TransformAxis>
            <TransformAxis name="rotation2"><coordinates>rock</coordinates><axis>1 0 0</axis>{lin}</TransformAxis>
            <TransformAxis name="rotation3"><coordinates></coordinates><axis>0 1 0</axis>{zero}</TransformAxis>
            <TransformAxis name="translation1"><coordinates>tx</coordinates><axis>1 0 0</axis>{lin}</TransformAxis>
            <TransformAxis name="translation2"><coordinates>ty</coordinates><axis>0 1 0</axis>{lin}</TransformAxis>
            <TransformAxis name="translation3"><coordinates>tz</coordinates><axis>0 0 1</axis>{lin}</TransformAxis>
          </SpatialTransform>
          <CoordinateSet><objects>
            <Coordinate name="tilt"><default_value>0.5</default_value></Coordinate>
            <Coordinate name="rock"><default_value>0</default_value></Coordinate>
            <Coordinate name="tx"><default_value>1</default_value></Coordinate>
            <Coordinate name="ty"><default_value>2</default_value></Coordinate>
            <Coordinate name="tz"><default_value>3</default_value></Coordinate>
          </objects></CoordinateSet>
        </CustomJoint></Joint></Body>
        </objects></BodySet>
        <ForceSet><objects><CoordinateActuator name="a"><coordinate>ty</coordinate></CoordinateActuator></objects></ForceSet>
        </Model></OpenSimDocument>"#
    );
    let i = import_str("t.osim", &text, None, &ImportOptions::default())
        .unwrap_or_else(|e| panic!("{e:?}"));
    assert!(i.warnings.is_empty(), "{:?}", i.warnings);
    let m = &i.mechanism;
    let joint = |id: &str| {
        m.joints
            .iter()
            .find(|j| j.id == id)
            .unwrap_or_else(|| panic!("no joint {id}\n{}", i.toml))
    };
    let names = |id: &str| -> Vec<String> {
        joint(id)
            .bodies
            .iter()
            .map(|&b| m.bodies[b].id.to_string())
            .collect()
    };
    for (id, kind) in [
        ("ground_pelvis:tx", JointType::P),
        ("ground_pelvis:ty", JointType::P),
        ("ground_pelvis:tz", JointType::P),
        ("ground_pelvis:tilt", JointType::R),
        ("ground_pelvis:rock", JointType::R),
    ] {
        assert_eq!(joint(id).kind, kind, "{id}\n{}", i.toml);
    }
    assert_axis(&i, "ground_pelvis:tx", [1.0, 0.0, 0.0], [1.0, 2.0, 3.0]);
    assert_axis(&i, "ground_pelvis:tz", [0.0, 0.0, 1.0], [1.0, 2.0, 3.0]);
    assert_axis(&i, "ground_pelvis:tilt", [0.0, 0.0, 1.0], [1.0, 2.0, 3.0]);
    // The second rotation's axis is turned by the first (0.5 rad about z).
    let (c, s) = (0.5f64.cos(), 0.5f64.sin());
    assert_axis(&i, "ground_pelvis:rock", [c, s, 0.0], [1.0, 2.0, 3.0]);
    // Sliders from the ground, hinges to the pelvis; the user's `pelvis~1` keeps its name.
    assert_eq!(names("ground_pelvis:tx"), ["ground", "pelvis~1#2"]);
    assert_eq!(names("ground_pelvis:rock"), ["pelvis~4", "pelvis"]);
    assert_eq!(names("pin"), ["pelvis", "pelvis~1"]);
    assert_eq!(joint("ground_pelvis:ty").driven, 1);
    assert_eq!(m.inputs(), 1);
    // 5 coordinates of the chain and the pin: 6 DOF, as OpenSim counts them (F would give 7).
    assert_eq!(crate::mobility::mobility(m).mobility.count, 6);
}

/// The knee translations of OpenSim's gait2392 (`SimmSpline`s of 12 and 7 knots) at the default
/// knee angle 0, between knots: the cubic spline OpenSim evaluates them with (values from an
/// independent implementation of the Forsythe-Malcolm-Moler spline), not the line between the
/// knots (0.4 mm off in x; every joint below the knee carried it).
#[test]
fn osim_simm_spline_is_the_cubic_opensim_evaluates() {
    let spline = |x: &str, y: &str| {
        format!("<function><SimmSpline><x>{x}</x><y>{y}</y></SimmSpline></function>")
    };
    let tx = spline(
        "-2.0944 -1.74533 -1.39626 -1.0472 -0.698132 -0.349066 -0.174533 0.197344 0.337395 0.490178 1.52146 2.0944",
        "-0.0032 0.00179 0.00411 0.0041 0.00212 -0.001 -0.0031 -0.005227 -0.005435 -0.005574 -0.005435 -0.00525",
    );
    let ty = spline(
        "-2.0944 -1.22173 -0.523599 -0.349066 -0.174533 0.159149 2.0944",
        "-0.4226 -0.4082 -0.399 -0.3976 -0.3966 -0.395264 -0.396",
    );
    let lin =
        "<function><LinearFunction><coefficients>1 0</coefficients></LinearFunction></function>";
    let text = format!(
        r#"<OpenSimDocument Version="30000"><Model name="knee"><BodySet><objects>
        <Body name="ground"><Joint/></Body>
        <Body name="tibia"><Joint><CustomJoint name="knee"><parent_body>ground</parent_body>
          <location_in_parent>0 0 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
          <location>0 0 0</location><orientation>0 0 0</orientation>
          <SpatialTransform>
            <TransformAxis name="rotation1"><coordinates>knee_angle</coordinates><axis>0 0 1</axis>{lin}</TransformAxis>
            <TransformAxis name="translation1"><coordinates>knee_angle</coordinates><axis>1 0 0</axis>{tx}</TransformAxis>
            <TransformAxis name="translation2"><coordinates>knee_angle</coordinates><axis>0 1 0</axis>{ty}</TransformAxis>
          </SpatialTransform>
          <CoordinateSet><objects><Coordinate name="knee_angle"><default_value>0</default_value></Coordinate></objects></CoordinateSet>
        </CustomJoint></Joint></Body>
        </objects></BodySet></Model></OpenSimDocument>"#
    );
    let i = import_str("t.osim", &text, None, &ImportOptions::default())
        .unwrap_or_else(|e| panic!("{e:?}"));
    let o = geom(&i, "knee").origin.expect("origin");
    assert!((o[0] - -0.004499856517536013).abs() < 1e-10, "{o:?}");
    assert!((o[1] - -0.39582069644835033).abs() < 1e-10, "{o:?}");
}
