//! The URDF loop dialects on small inline models: the urdfdom `<constraint>` proposal (no
//! public model uses it yet), URDF+ gears, the Extended-URDF joint kinds, Drake's implicit
//! `world` link. The public models are in tests/it/import_dialects.rs.

use crate::import::{Import, ImportOptions, import_str};
use crate::joint::JointType;

fn urdf_with(text: &str, options: &ImportOptions) -> Import {
    import_str("t.urdf", text, None, options).unwrap_or_else(|e| panic!("{e:?}"))
}

fn urdf(text: &str) -> Import {
    urdf_with(text, &ImportOptions::default())
}

/// A parallelogram in the x-y plane: crank `a` (base to a at the origin, about z), coupler
/// `b` (at (0, 1, 0)), rocker `c` (base to c at (1, 0, 0)); `cut` closes b to c at (1, 1, 0).
fn four_bar(cut: &str) -> String {
    format!(
        r#"<robot name="r">
        <link name="base"/><link name="a"/><link name="b"/><link name="c"/>
        <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/></joint>
        <joint name="jb" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 1 0"/><axis xyz="0 0 1"/></joint>
        <joint name="jc" type="revolute"><parent link="base"/><child link="c"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>
        {cut}
        </robot>"#
    )
}

fn proposal(kind: &str, child_origin: &str, axes: &str) -> String {
    four_bar(&format!(
        r#"<constraint name="cut" type="{kind}">
          <parent link="b"/><parent_origin xyz="1 0 0" rpy="0 0 0"/>
          <child link="c"/><child_origin xyz="{child_origin}" rpy="0 0 1.5707963267948966"/>
          {axes}
        </constraint>"#
    ))
}

fn cut(i: &Import) -> &crate::mechanism::Joint {
    i.mechanism
        .joints
        .iter()
        .find(|j| j.id == "cut")
        .unwrap_or_else(|| panic!("no cut joint: {}", i.toml))
}

fn near(a: Option<[f64; 3]>, b: [f64; 3]) -> bool {
    a.is_some_and(|a| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9))
}

#[test]
fn the_urdfdom_proposal_cuts_become_their_joints() {
    let z = r#"<parent_axis xyz="0 0 1"/><child_axis xyz="1 0 0"/>"#;
    let r = urdf(&proposal("revolute", "0 1 0", z));
    let j = cut(&r);
    assert_eq!(j.kind, JointType::R);
    assert!(near(j.geometry.origin, [1.0, 1.0, 0.0]), "{}", r.toml);
    assert!(near(j.geometry.axis, [0.0, 0.0, 1.0]), "{}", r.toml);
    assert!(j.geometry.second.is_none(), "closed: {}", r.toml);
    assert_eq!(r.mechanism.joints.len(), 4);
    let p = urdf(&proposal("prismatic", "0 1 0", z));
    assert_eq!(cut(&p).kind, JointType::P);
    let u = urdf(&proposal("universal", "0 1 0", z));
    let j = cut(&u);
    assert_eq!(j.kind, JointType::U);
    assert!(near(j.geometry.axis, [0.0, 0.0, 1.0]), "{}", u.toml);
    // The child axis x of the child frame, turned a quarter about z: the world y.
    assert!(near(j.geometry.axis2, [0.0, 1.0, 0.0]), "{}", u.toml);
    let s = urdf(&proposal("spherical", "0 1 0", ""));
    assert_eq!(cut(&s).kind, JointType::S);
    // A cut link is a weld: b and c are one body, joined to the base by jc and to a by jb.
    let w = urdf(&proposal("link", "0 1 0", ""));
    assert_eq!(w.mechanism.joints.len(), 3, "{}", w.toml);
    assert!(
        w.notes.iter().any(|n| n.contains("welded")),
        "{:?}",
        w.notes
    );
    assert!(
        w.warnings.iter().any(|x| x.contains("not closed")),
        "the frames turn by a quarter: {:?}",
        w.warnings
    );
}

#[test]
fn an_open_cut_keeps_the_second_frame_and_says_so() {
    let z = r#"<parent_axis xyz="0 0 1"/>"#;
    let r = urdf(&proposal("revolute", "0 1.5 0", z));
    let second = cut(&r).geometry.second.as_ref().expect("second");
    assert!(near(second.origin, [1.0, 1.5, 0.0]), "{}", r.toml);
    assert!(
        r.warnings
            .iter()
            .any(|w| w.contains("is not closed at this configuration (gap 5.000e-1)")),
        "{:?}",
        r.warnings
    );
}

/// The parallelogram closed by a `link` cut that c's frame misses (at (1, 1.2, 0), turned a
/// quarter about z, where b's is at (1, 1, 0)), with the hinges `names` made prismatic.
fn sliding(names: &[&str]) -> Import {
    let mut text = proposal("link", "0 1.2 0", "");
    for n in names {
        text = text.replace(
            &format!(r#"<joint name="{n}" type="revolute">"#),
            &format!(r#"<joint name="{n}" type="prismatic">"#),
        );
    }
    urdf(&text)
}

fn joint<'a>(r: &'a Import, id: &str) -> &'a crate::mechanism::Joint {
    r.mechanism
        .joints
        .iter()
        .find(|j| j.id == id)
        .unwrap_or_else(|| panic!("no joint {id}: {}", r.toml))
}

fn assert_warned(r: &Import, words: &str) {
    assert!(
        r.warnings.iter().any(|w| w.contains(words)),
        "{words}: {:?}",
        r.warnings
    );
}

#[test]
fn an_open_weld_moves_its_link_where_the_cut_puts_it() {
    // c moves where the cut closes, and its hinge to the base carries c's side in `second`.
    let r = sliding(&[]);
    let jc = joint(&r, "jc");
    assert!(near(jc.geometry.origin, [1.0, 0.0, 0.0]), "{}", r.toml);
    let second = jc.geometry.second.as_ref().expect("second");
    assert!(near(second.origin, [-0.2, 1.0, 0.0]), "{}", r.toml);
    assert!(near(second.axis, [0.0, 0.0, 1.0]), "{}", r.toml);
    assert_warned(&r, "`c` is welded where the cut puts it");
}

#[test]
fn an_open_weld_whose_second_link_slides_moves_the_first() {
    // A prismatic joint cannot carry a side turned about its axis: c stays, and b (on a
    // hinge) moves back to where the cut closes.
    let r = sliding(&["jc"]);
    assert!(joint(&r, "jc").geometry.second.is_none(), "{}", r.toml);
    assert!(joint(&r, "jb").geometry.second.is_some(), "{}", r.toml);
    assert_warned(&r, "`b` is welded where the cut puts it");
}

#[test]
fn an_open_weld_whose_links_both_slide_is_welded_as_placed_and_says_which_joint() {
    let r = sliding(&["jb", "jc"]);
    let jc = joint(&r, "jc");
    assert_eq!(jc.kind, JointType::P, "{}", r.toml);
    assert!(jc.geometry.second.is_none(), "{}", r.toml);
    assert_warned(
        &r,
        "welded as they are placed, which is not the assembled mechanism (the joints jc (P) \
         cannot carry a moved side)",
    );
}

#[test]
fn proposal_errors_are_located() {
    let err = |t: &str| import_str("t.urdf", t, None, &ImportOptions::default()).unwrap_err();
    let e = err(&proposal("revolute", "0 1 0", ""));
    assert!(
        e.message().contains("needs <parent_axis xyz=\"...\"/>"),
        "{e}"
    );
    assert!(e.location().is_some());
    let e = err(&proposal("gear", "0 1 0", ""));
    assert!(e.message().contains("unknown type `gear`"), "{e}");
    assert!(e.hint().is_some_and(|h| h.contains("universal")), "{e:?}");
    let e = err(&four_bar(
        r#"<constraint name="cut" type="spherical"><parent link="b"/><child link="zz"/></constraint>"#,
    ));
    assert!(e.message().contains("link `zz` is not defined"), "{e}");
    let (_, line, _) = e.location().expect("located");
    assert_eq!(line, 6);
    let e = err(&four_bar(
        r#"<constraint type="spherical"><parent link="b"/><child link="c"/></constraint>"#,
    ));
    assert!(e.message().contains("without a `name`"), "{e}");
    let e = err(&four_bar(
        r#"<loop name="l" type="revolute"><predecessor link="b"/></loop>"#,
    ));
    assert!(e.message().contains("has no <successor>"), "{e}");
    let e = err(&four_bar(
        r#"<loop name="l" type="revolute"><predecessor link="b"/><successor link="c"/><axis xyz="0 0 0"/></loop>"#,
    ));
    assert!(e.message().contains("axis of zero length"), "{e}");
}

#[test]
fn gears_are_warned_as_not_representable() {
    let i = urdf(&four_bar(
        r#"<constraint name="g" type="rolling"><predecessor link="a"/><successor link="c"/><ratio value="2"/></constraint>
        <coupling name="g2"><predecessor link="a"/><successor link="c"/><ratio value="2"/></coupling>"#,
    ));
    assert_eq!(i.mechanism.joints.len(), 3);
    assert_eq!(
        i.warnings
            .iter()
            .filter(|w| w.contains("not representable"))
            .count(),
        2,
        "{:?}",
        i.warnings
    );
}

#[test]
fn a_world_link_the_file_does_not_define_is_the_world() {
    let i = urdf(
        r#"<robot name="r"><link name="floor"/><link name="a"/>
        <joint name="w" type="fixed"><parent link="world"/><child link="floor"/><axis xyz="0 0 0"/></joint>
        <joint name="j" type="revolute"><parent link="floor"/><child link="a"/><axis xyz="0 1 0"/></joint>
        </robot>"#,
    );
    assert_eq!(i.mechanism.body_id(i.mechanism.frame).to_string(), "world");
    assert!(
        i.notes
            .iter()
            .any(|n| n.contains("Drake's and Gazebo's convention")),
        "{:?}",
        i.notes
    );
    assert_eq!(i.mechanism.joints.len(), 1);
}

/// A closure file in a scratch folder.
fn closure_file(name: &str, text: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mbsa-urdf-closures-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("scratch");
    let p = d.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

#[test]
fn extended_urdf_joint_kinds_actuators_and_loops() {
    // The parallelogram cut at c: a frame on b and the link c meet at (1, 1, 0).
    let text = four_bar(
        r#"<link name="tip"/><joint name="tip_frame" type="fixed"><parent link="b"/><child link="tip"/><origin xyz="1 0 0"/></joint>
        <link name="d"/><joint name="jd" type="revolute"><parent link="c"/><child link="d"/><origin xyz="0 1 0"/><axis xyz="0 0 1"/></joint>"#,
    );
    let yaml = "closed_loop: [[tip_frame, d]]\ntype: [3D]\nname_mot: [ja]\njoint_name: [jb, jc, jd]\njoint_type: [SPHERICAL, UJOINT_ZX, FIXED]\nextra: 1\n";
    let o = ImportOptions {
        closures: Some(closure_file("kinds.yaml", yaml)),
        ..ImportOptions::default()
    };
    let i = urdf_with(&text, &o);
    let kind = |id: &str| {
        i.mechanism
            .joints
            .iter()
            .find(|j| j.id == id)
            .map(|j| j.kind)
    };
    assert_eq!(kind("jb"), Some(JointType::S));
    assert_eq!(kind("jc"), Some(JointType::U));
    assert_eq!(kind("jd"), None, "FIXED: c and d welded");
    assert_eq!(kind("tip_frame-d"), Some(JointType::S), "{}", i.toml);
    let jc = i
        .mechanism
        .joints
        .iter()
        .find(|j| j.id == "jc")
        .expect("jc");
    assert!(
        near(jc.geometry.axis, [0.0, 0.0, 1.0]) && near(jc.geometry.axis2, [1.0, 0.0, 0.0]),
        "{}",
        i.toml
    );
    assert_eq!(i.mechanism.inputs(), 1);
    assert!(
        i.warnings
            .iter()
            .any(|w| w.contains("key `extra` of the closure file not read")),
        "{:?}",
        i.warnings
    );
    assert!(
        i.warnings.iter().any(|w| w.contains("kinds.yaml:6:1")),
        "{:?}",
        i.warnings
    );
}

#[test]
fn an_empty_closure_path_reads_none_and_a_file_without_closed_loop_is_refused() {
    let text = four_bar("");
    let none = ImportOptions {
        closures: Some(std::path::PathBuf::new()),
        ..ImportOptions::default()
    };
    assert_eq!(urdf_with(&text, &none).mechanism.joints.len(), 3);
    let o = ImportOptions {
        closures: Some(closure_file("empty.yaml", "name_mot: [ja]\n")),
        ..ImportOptions::default()
    };
    let e = import_str("t.urdf", &text, None, &o).unwrap_err();
    assert!(e.message().contains("no `closed_loop` key"), "{e}");
    let o = ImportOptions {
        closures: Some(closure_file("alias.yaml", "a: &x [ja]\nclosed_loop: *x\n")),
        ..ImportOptions::default()
    };
    let e = import_str("t.urdf", &text, None, &o).unwrap_err();
    assert!(e.message().contains("aliases are not read"), "{e}");
    assert_eq!(e.location().map(|l| l.1), Some(2));
}

fn distance(dist: &str, body_b: &str) -> String {
    format!(
        r#"<robot name="r" xmlns:drake="http://drake.mit.edu">
        <link name="base"/><link name="a"/><link name="c"/>
        <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/></joint>
        <joint name="jc" type="revolute"><parent link="base"/><child link="c"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>
        <drake:distance_constraint>
          <drake:distance_constraint_body_A name="a"/><drake:distance_constraint_p_AP value="0 1 0"/>
          <drake:distance_constraint_body_B name="{body_b}"/><drake:distance_constraint_p_BQ value="0 1 0"/>
          <drake:distance_constraint_distance value="{dist}"/>
          <drake:distance_constraint_stiffness value="1e6"/><drake:distance_constraint_damping value="1"/>
        </drake:distance_constraint>
        </robot>"#
    )
}

#[test]
fn a_drake_distance_constraint_is_a_sphere_sphere_joint() {
    let i = urdf(&distance("1", "c"));
    let j = i
        .mechanism
        .joints
        .iter()
        .find(|j| j.id == "distance:a-c")
        .expect("the joint");
    assert_eq!(j.kind, JointType::SPSP);
    assert!(
        near(j.geometry.origin, [0.0, 1.0, 0.0]) && near(j.geometry.origin2, [1.0, 1.0, 0.0]),
        "{}",
        i.toml
    );
    assert!(i.warnings.is_empty(), "{:?}", i.warnings);
    let far = urdf(&distance("1.5", "c"));
    assert!(
        far.warnings
            .iter()
            .any(|w| w.contains("keeps 1.5, but its points are 1.000000e0 apart")),
        "{:?}",
        far.warnings
    );
    let err = |t: &str| import_str("t.urdf", t, None, &ImportOptions::default()).unwrap_err();
    let e = err(&distance("1", "zz"));
    assert!(e.message().contains("link `zz` is not defined"), "{e}");
    assert_eq!(e.location().map(|l| l.1), Some(7));
    let e = err(&distance("0", "c"));
    assert!(
        e.message()
            .contains("the distance must be a positive number"),
        "{e}"
    );
}

fn gazebo_axis(model_frame: &str) -> Import {
    urdf(&format!(
        r#"<robot name="r"><link name="base"/><link name="a"/><link name="b"/>
        <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><origin rpy="0 0 1.5707963267948966"/><axis xyz="0 0 1"/></joint>
        <joint name="jb" type="revolute"><parent link="a"/><child link="b"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>
        <gazebo><joint name="close" type="revolute"><parent>base</parent><child>b</child>
          <axis><xyz>1 0 0</xyz>{model_frame}</axis></joint></gazebo>
        </robot>"#
    ))
}

#[test]
fn a_gazebo_joint_axis_is_in_the_joint_frame_or_the_model_frame() {
    // b is turned a quarter about z: its x is the world's y.
    let joint = gazebo_axis("");
    let g = &joint
        .mechanism
        .joints
        .iter()
        .find(|j| j.id == "close")
        .expect("close")
        .geometry;
    assert!(near(g.axis, [0.0, 1.0, 0.0]), "{}", joint.toml);
    let model = gazebo_axis("<use_parent_model_frame>1</use_parent_model_frame>");
    let g = &model
        .mechanism
        .joints
        .iter()
        .find(|j| j.id == "close")
        .expect("close")
        .geometry;
    assert!(near(g.axis, [1.0, 0.0, 0.0]), "{}", model.toml);
}
