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
