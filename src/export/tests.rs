use super::*;
use crate::format::{Format, load};

fn bundled(name: &str) -> Mechanism {
    let (file, text) = crate::examples::find(name).expect("bundled");
    load(file, text, Format::Toml).expect("valid")
}

fn options(target: Target, geometry: GeometrySource) -> ExportOptions {
    ExportOptions {
        target,
        geometry,
        precision: None,
        source: "test".into(),
    }
}

fn export(name: &str, target: Target) -> Result<Export, ExportError> {
    export_within(
        &bundled(name),
        &options(target, GeometrySource::File),
        &Budget::UNLIMITED,
    )
}

#[test]
fn a_revolute_cut_is_a_light_body_welded_to_the_other_side() {
    let e = export("rig-planar-four-bar-3d", Target::Mjcf).expect("exported");
    assert!(
        e.text.contains("<weld name=\"D\" body1=\"cut:D\"/>"),
        "{}",
        e.text
    );
    assert!(e.text.contains("<key name=\"file\" qpos=\"0 0 0 0\"/>"));
    assert_eq!(e.warnings.len(), 1, "{:?}", e.warnings);
    assert!(e.warnings[0].contains("3 redundant constraint row(s)"));
}

#[test]
fn spherical_cuts_are_connects() {
    let m = bundled("stewart");
    let opts = options(Target::Mjcf, GeometrySource::Random { seed: 1 });
    let e = export_within(&m, &opts, &Budget::UNLIMITED).expect("exported");
    assert_eq!(e.text.matches("<connect ").count(), 6);
    assert_eq!(e.text.matches("<position ").count(), 6);
}

#[test]
fn a_mechanism_without_geometry_is_refused_with_its_joints_named() {
    let e = export("four-bar", Target::Mjcf).expect_err("no geometry");
    let text = e.to_string();
    assert!(text.starts_with("4 joint(s) lack the geometry"), "{text}");
    assert!(text.contains("A (R: origin)"), "{text}");
}

#[test]
fn count_only_kinds_and_mjcf_screws_are_refused_by_name() {
    let mut m = bundled("rig-planar-four-bar-3d");
    m.joints[1].kind = JointType::H;
    m.joints[1].geometry.pitch = Some(0.1);
    let opts = options(Target::Mjcf, GeometrySource::File);
    let e = export_within(&m, &opts, &Budget::UNLIMITED).expect_err("no MJCF screw");
    assert_eq!(e.to_string(), "MJCF has no joint for joint(s) `B` (H)");
    let opts = options(Target::Sdf, GeometrySource::File);
    let e = export_within(&m, &opts, &Budget::UNLIMITED).expect("an SDFormat screw");
    assert!(e.text.contains("type=\"screw\""));
}
