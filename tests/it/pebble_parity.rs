//! Parity of the pebble game with PyRigi on small 2D bar-joint frameworks.
//!
//! The fixtures (tests/fixtures/pebble/*.toml) and their expected answers (expected.json) are
//! written by benches/pebble_fixtures.py, which runs PyRigi 1.3; this test needs no Python.
//! Every bar is a body and every point a revolute joining the bars that meet there; PyRigi's
//! components (sets of points) are mapped to the bars with both ends in them. Components of a
//! single bar are left out on both sides. The fixtures are read here with a minimal local
//! reader so that the test does not depend on the file-format module.

use mbsa::joint::JointType;
use mbsa::rigidity::pebble::{PebbleOptions, analyze};
use mbsa::{BodyId, Geometry, JointSpec, Mechanism, Space};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Deserialize)]
struct Fixture {
    name: String,
    frame: i64,
    joint: Vec<FixtureJoint>,
}

#[derive(Deserialize)]
struct FixtureJoint {
    id: String,
    bodies: Vec<i64>,
}

#[derive(Deserialize)]
struct Expected {
    rigid: Vec<Vec<i64>>,
    redundant: u64,
    dof_free: i64,
}

fn load(path: &Path) -> Mechanism {
    let text = std::fs::read_to_string(path).expect("fixture readable");
    let f: Fixture = toml::from_str(&text).expect("fixture is valid TOML");
    let joints = f
        .joint
        .into_iter()
        .map(|j| JointSpec {
            id: Some(j.id),
            kind: JointType::R,
            bodies: j.bodies.into_iter().map(BodyId::Int).collect(),
            driven: 0,
            geometry: Geometry::default(),
        })
        .collect();
    Mechanism::from_parts(f.name, Space::Planar, BodyId::Int(f.frame), vec![], joints)
}

#[test]
fn pebble_game_matches_pyrigi() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/pebble");
    let expected: BTreeMap<String, Expected> = serde_json::from_str(
        &std::fs::read_to_string(dir.join("expected.json")).expect("expected.json readable"),
    )
    .expect("expected.json parses");
    assert!(expected.len() >= 10, "the fixture set is complete");
    let mut failures = Vec::new();
    for (name, want) in &expected {
        let m = load(&dir.join(format!("{name}.toml")));
        let r = analyze(&m, &PebbleOptions::default());
        let mut got: Vec<Vec<i64>> = r
            .rigid
            .iter()
            .filter(|c| c.len() >= 2)
            .map(|c| {
                c.iter()
                    .map(|b| b.parse().expect("integer bar ids"))
                    .collect()
            })
            .collect();
        got.sort();
        if got != want.rigid || r.redundant != want.redundant || r.dof_free != want.dof_free {
            failures.push(format!(
                "{name}: mbsa rigid {got:?} redundant {} dof_free {}; PyRigi rigid {:?} redundant {} dof_free {}",
                r.redundant, r.dof_free, want.rigid, want.redundant, want.dof_free
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
