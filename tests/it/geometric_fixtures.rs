//! Geometric rigidity on the thesis examples (mechanisms/rig-*.toml): the numbers of
//! brief/rigidity.md at the file coordinates and at a random realization, plus snapshots.

use mbsa::JointType;
use mbsa::mechanism::{BodyId, Expect, Geometry, JointSpec, Mechanism, Space};
use mbsa::rigidity::geometric::{GeometricOptions, GeometricReport, GeometrySource, analyze};

/// A minimal reader for the fixtures (plain `[[joint]]` tables only), so these tests do not
/// depend on the full reader.
fn load(name: &str) -> Mechanism {
    let path = format!("{}/mechanisms/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("fixture exists");
    let v: toml::Value = toml::from_str(&text).expect("fixture is TOML");
    let id = |x: &toml::Value| match x {
        toml::Value::Integer(i) => BodyId::Int(*i),
        toml::Value::String(s) => BodyId::Name(s.clone()),
        other => panic!("bad body id {other:?}"),
    };
    let vec3 = |x: Option<&toml::Value>| {
        x.map(|a| {
            let a: Vec<f64> = a
                .as_array()
                .expect("array")
                .iter()
                .map(|c| {
                    c.as_float()
                        .or(c.as_integer().map(|i| i as f64))
                        .expect("number")
                })
                .collect();
            [a[0], a[1], a.get(2).copied().unwrap_or(0.0)]
        })
    };
    let space = match v.get("space").and_then(|s| s.as_str()) {
        Some("planar") => Space::Planar,
        Some("spherical") => Space::Spherical,
        _ => Space::Spatial,
    };
    let joints = v["joint"]
        .as_array()
        .expect("joints")
        .iter()
        .map(|j| JointSpec {
            id: j.get("id").and_then(|s| s.as_str()).map(str::to_string),
            kind: JointType::parse(j["type"].as_str().expect("type")).expect("known type"),
            bodies: j["bodies"]
                .as_array()
                .expect("bodies")
                .iter()
                .map(id)
                .collect(),
            driven: j.get("driven").and_then(|d| d.as_integer()).unwrap_or(0) as u32,
            geometry: Geometry {
                origin: vec3(j.get("origin")),
                axis: vec3(j.get("axis")),
                axis2: vec3(j.get("axis2")),
                origin2: vec3(j.get("origin2")),
                normal: vec3(j.get("normal")),
                pitch: j.get("pitch").and_then(|p| p.as_float()),
                ..Geometry::default()
            },
        })
        .collect();
    let mut m = Mechanism::from_parts(
        v["name"].as_str().expect("name"),
        space,
        id(&v["frame"]),
        vec![],
        joints,
    );
    m.expect = v["expect"]
        .clone()
        .try_into::<Expect>()
        .expect("expect table");
    m
}

fn check(r: &GeometricReport, e: &Expect, what: &str) {
    if let Some(x) = e.mobility {
        assert_eq!(r.count, x, "{what}: count");
    }
    if let Some(x) = e.true_mobility {
        assert_eq!(r.mobility as i64, x, "{what}: true mobility");
    }
    if let Some(x) = e.isolated {
        assert_eq!(r.isolated as u64, x, "{what}: isolated");
    }
    if let Some(x) = e.redundant {
        assert_eq!(r.redundant as u64, x, "{what}: redundant");
    }
    if let Some(x) = e.rigid_parts {
        assert_eq!(r.rigid.len() as u64, x, "{what}: rigid parts");
    }
    // Random realizations may legitimately come close to the threshold (a warning, not an
    // error); the file coordinates must not, except the seven-roof's: written to 5-6 decimals
    // and perturbed only slightly from the singular heptagon, its smallest kept singular value
    // is within a factor 100 of what that precision can decide, which mbsa rightly flags.
    if r.geometry == "file" && !what.contains("seven-roof") {
        assert!(
            r.numeric.warning.is_none(),
            "{what}: {:?}",
            r.numeric.warning
        );
    }
}

fn file(name: &str) -> (Mechanism, GeometricReport) {
    let m = load(name);
    let opts = GeometricOptions {
        geometry: GeometrySource::File,
        check_finite: false,
        precision: None,
    };
    let r = analyze(&m, &opts).expect("fixture has its geometry");
    check(&r, &m.expect, name);
    (m, r)
}

fn random(m: &Mechanism, seed: u64) -> GeometricReport {
    let opts = GeometricOptions {
        geometry: GeometrySource::Random { seed },
        check_finite: false,
        precision: None,
    };
    analyze(m, &opts).expect("random geometry always works")
}

fn snap(name: &str, r: &GeometricReport) {
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!(format!("geometric_{name}"), mbsa::report::rigid_geometric::table(r));
    });
}

/// Fixtures whose expected numbers are generic: a random realization gives them too.
#[test]
fn generic_fixtures_file_and_random() {
    for name in [
        "rig-double-banana",
        "rig-seven-roof",
        "rig-tetrahedron",
        "rig-rssr",
        "rig-slider-crank-rusp",
        "rig-double-four-bar",
    ] {
        let (m, r) = file(name);
        snap(name, &r);
        for seed in [1, 2] {
            let rr = random(&m, seed);
            check(&rr, &m.expect, &format!("{name} random {seed}"));
        }
    }
}

/// Special geometries (planar loops written in 3D, Bennett): the file geometry gives the
/// thesis numbers, a random realization gives the generic count.
#[test]
fn special_fixtures_file_and_random() {
    for name in [
        "rig-slider-crank-rrrp",
        "rig-planar-four-bar-3d",
        "rig-stacked-four-bars",
        "rig-bennett",
    ] {
        let (m, r) = file(name);
        snap(name, &r);
        let rr = random(&m, 1);
        assert_eq!(
            rr.redundant as i64,
            (-r.count).max(0),
            "{name}: generic redundancy"
        );
        assert_eq!(
            rr.mobility as i64,
            r.count.max(0),
            "{name}: generic mobility = count"
        );
    }
}

#[test]
fn double_banana_details() {
    let (_, r) = file("rig-double-banana");
    // 17 moving bars spin; the frame never moves, so the frame bar AC's spin is the rest
    // turning about the line AC (structurally isolated), beside the implied hinge A-B.
    assert_eq!(r.fully_isolated, 17);
    assert_eq!(r.structurally_isolated, 2);
    assert_eq!(r.proper_mobility, 0);
    let hinge = r
        .isolated_motions
        .iter()
        .find(|i| i.kind == "structurally" && i.bodies.len() < 17)
        .expect("the implied hinge");
    let axis = hinge.axis.as_ref().expect("one motion has an axis");
    assert_eq!(axis.kind, "rotation");
    // The line A(0,0,2)-B(0,0,-2): direction z through the z axis.
    assert!((axis.direction[2].abs() - 1.0).abs() < 1e-6);
    let p = axis.point.expect("rotation has a point");
    assert!(p[0].abs() < 1e-6 && p[1].abs() < 1e-6);
    let mut sizes: Vec<usize> = r.rigid.iter().map(|c| c.bodies.len()).collect();
    sizes.sort();
    assert_eq!(sizes, [9, 9]);
    assert!(!r.redundant_joints.is_empty());
}

#[test]
fn loop_spatiality() {
    let (_, r) = file("rig-bennett");
    assert_eq!(r.loops.len(), 1);
    assert_eq!(r.loops[0].spatiality, 3);
    assert_eq!(r.loops[0].overconstraint, 3);
    let (_, r) = file("rig-rssr");
    assert_eq!(r.loops[0].spatiality, 6);
    let (_, r) = file("rig-slider-crank-rusp");
    assert_eq!(r.locked, 3);
}

/// `cargo test --release --test it -- --ignored --nocapture geometric_fixtures::timing`
#[test]
#[ignore]
fn timing_double_banana() {
    let m = load("rig-double-banana");
    let opts = GeometricOptions {
        geometry: GeometrySource::File,
        check_finite: false,
        precision: None,
    };
    let t = std::time::Instant::now();
    let n = 100;
    for _ in 0..n {
        let _ = analyze(&m, &opts).expect("geometry given");
    }
    eprintln!("double banana: {:?} per analysis", t.elapsed() / n);
}

/// The project's reader accepts every fixture and gives the same analysis as the minimal one.
#[test]
fn fixtures_load_with_the_reader() {
    let dir = format!("{}/mechanisms", env!("CARGO_MANIFEST_DIR"));
    for name in [
        "rig-double-banana",
        "rig-seven-roof",
        "rig-tetrahedron",
        "rig-rssr",
        "rig-slider-crank-rusp",
        "rig-double-four-bar",
        "rig-slider-crank-rrrp",
        "rig-planar-four-bar-3d",
        "rig-stacked-four-bars",
        "rig-bennett",
    ] {
        let path = format!("{dir}/{name}.toml");
        let text = std::fs::read_to_string(&path).expect("fixture exists");
        let m = mbsa::format::load(&path, &text, mbsa::format::Format::Toml)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let opts = GeometricOptions {
            geometry: GeometrySource::File,
            check_finite: false,
            precision: None,
        };
        let r = analyze(&m, &opts).expect("fixture has its geometry");
        check(&r, &m.expect, name);
        let mine = analyze(&load(name), &opts).expect("fixture has its geometry");
        assert_eq!(r, mine, "{name}: reader and minimal loader agree");
    }
}

/// One body between two S joints to the frame: the body spins about the line through the
/// joints' centres, and seen with the frame fixed that is the frame's own spin too. It is one
/// motion: 1 fully isolated, none structurally, proper mobility 0, at the file's geometry and
/// at every random realization (a closed form: 12 - 6 - 6 = 0 counted, 1 spin).
#[test]
fn a_spin_shared_with_the_frame_is_counted_once() {
    let text = r#"
name = "one body on two balls"
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
bodies = ["0", "1"]
origin = [1, 0, 0]
"#;
    let m = mbsa::format::load("two-balls.toml", text, mbsa::format::Format::Toml).unwrap();
    let mut reports = vec![("file".to_string(), {
        let opts = GeometricOptions {
            geometry: GeometrySource::File,
            check_finite: false,
            precision: None,
        };
        analyze(&m, &opts).unwrap()
    })];
    for seed in 0..20 {
        reports.push((format!("seed {seed}"), random(&m, seed)));
    }
    for (what, r) in &reports {
        assert_eq!(
            (
                r.mobility,
                r.fully_isolated,
                r.structurally_isolated,
                r.proper_mobility
            ),
            (1, 1, 0, 0),
            "{what}"
        );
    }
}
