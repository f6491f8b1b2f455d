//! The component pebble game (`analyze`) against the plain game kept as an oracle
//! (`analyze_reference`: a search for every bar, components found after the game) on random
//! mechanisms: planar bar-joint frameworks (multiple revolutes), spatial and planar body-bar
//! mechanisms with mixed joint kinds, multiple joints and driven inputs. The whole report must
//! be equal: rank (dof, redundant), the rigid components, the overconstrained regions and
//! `degenerate`. Each case is small enough for the oracle; 600 cases of each family.

use mbsa::budget::Budget;
use mbsa::joint::JointType;
use mbsa::rigidity::pebble::{PebbleOptions, analyze, analyze_reference, analyze_within};
use mbsa::{BodyId, Geometry, JointSpec, Mechanism, Space};

use crate::common;
use common::Rng;

fn joint(kind: JointType, bodies: &[usize], driven: u32, id: usize) -> JointSpec {
    JointSpec {
        id: Some(format!("j{id}")),
        kind,
        bodies: bodies.iter().map(|&b| BodyId::Int(b as i64 + 1)).collect(),
        driven,
        geometry: Geometry::default(),
    }
}

/// A random planar bar-joint framework: `bars` bars on `points` points (repeats allowed: a
/// doubled bar is redundant), bar k a body, point p a revolute joining its bars.
fn framework(rng: &mut Rng, points: usize, bars: usize) -> Mechanism {
    let mut at: Vec<Vec<usize>> = vec![Vec::new(); points];
    for k in 0..bars {
        let a = rng.below(points);
        let mut b = rng.below(points);
        while b == a {
            b = rng.below(points);
        }
        at[a].push(k);
        at[b].push(k);
    }
    let joints = at
        .iter()
        .enumerate()
        .filter(|(_, bs)| bs.len() >= 2)
        .map(|(p, bs)| joint(JointType::R, bs, 0, p))
        .collect();
    Mechanism::from_parts("framework", Space::Planar, BodyId::Int(1), vec![], joints)
}

/// A random mechanism: `joints` joints of random kinds between random bodies, one in five
/// shared by three or four bodies, some driven.
fn mechanism(rng: &mut Rng, space: Space, bodies: usize, joints: usize) -> Mechanism {
    let kinds: &[JointType] = match space {
        Space::Planar => &[JointType::R, JointType::P, JointType::RP, JointType::L],
        _ => &[
            JointType::R,
            JointType::P,
            JointType::C,
            JointType::U,
            JointType::S,
            JointType::PL,
            JointType::H,
        ],
    };
    let list = (0..joints)
        .map(|id| {
            let kind = kinds[rng.below(kinds.len())];
            let n = if rng.below(5) == 0 {
                3 + rng.below(2)
            } else {
                2
            };
            let mut bs: Vec<usize> = Vec::new();
            while bs.len() < n.min(bodies) {
                let b = rng.below(bodies);
                if !bs.contains(&b) {
                    bs.push(b);
                }
            }
            let driven = if rng.below(4) == 0 { 1 } else { 0 };
            joint(kind, &bs, driven.min(kind.grade() as u32), id)
        })
        .collect();
    Mechanism::from_parts("random", space, BodyId::Int(1), vec![], list)
}

fn check(m: &Mechanism, what: &str) {
    for with_inputs in [false, true] {
        let opts = PebbleOptions { with_inputs };
        let fast = analyze(m, &opts);
        let slow = analyze_reference(m, &opts);
        assert_eq!(
            fast,
            slow,
            "{what} (with_inputs {with_inputs}): component game differs from the plain game on\n{}",
            mbsa::generate::to_toml(m)
        );
    }
}

#[test]
fn frameworks_match_the_plain_game() {
    let mut rng = Rng(1);
    for case in 0..600 {
        let points = 3 + rng.below(12);
        // Mean point degree from 2 to 6: flexible, threshold, over-braced.
        let bars = 2 + rng.below(3 * points);
        check(
            &framework(&mut rng, points, bars),
            &format!("framework {case}"),
        );
    }
}

#[test]
fn mechanisms_match_the_plain_game() {
    let mut rng = Rng(2);
    for case in 0..600 {
        let space = if case % 2 == 0 {
            Space::Spatial
        } else {
            Space::Planar
        };
        let bodies = 2 + rng.below(10);
        let joints = 1 + rng.below(3 * bodies);
        check(
            &mechanism(&mut rng, space, bodies, joints),
            &format!("mechanism {case}"),
        );
    }
}

#[test]
fn larger_frameworks_match_the_plain_game() {
    let mut rng = Rng(3);
    for case in 0..40 {
        let points = 50 + rng.below(150);
        let bars = points + rng.below(2 * points);
        check(&framework(&mut rng, points, bars), &format!("large {case}"));
    }
}

#[test]
fn work_limit_stops_the_game() {
    let mut rng = Rng(4);
    let m = framework(&mut rng, 200, 400);
    let tight = Budget {
        max_work: 1000,
        ..Budget::DEFAULT
    };
    let e = analyze_within(&m, &PebbleOptions::default(), &tight).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("the pebble game needs more than 1000 work units")
    );
    assert!(analyze_within(&m, &PebbleOptions::default(), &Budget::DEFAULT).is_ok());
}

#[test]
fn generated_families_match_the_plain_game() {
    use mbsa::generate::{self, Variant};
    for (points, bars) in [(400, 600), (300, 600), (200, 600), (150, 450)] {
        check(
            &generate::planar_framework(points, bars, 5),
            &format!("planar_framework({points}, {bars})"),
        );
    }
    for class in 1..=3 {
        check(
            &generate::assur(class, 20, 364, Variant::A).expect("valid"),
            "assur",
        );
        check(
            &generate::assur_spatial(class, 20, 364, Variant::B).expect("valid"),
            "assur spatial",
        );
    }
    for seed in 0..4 {
        check(
            &generate::random(150, seed % 2 == 0, seed).expect("valid").0,
            "random",
        );
    }
}

#[test]
fn shuffled_linkages_match_the_plain_game() {
    // The game inserts bars in file order and keeps a structural slack near the newest
    // bodies; the answers must not depend on the order the joints are written in.
    use mbsa::generate::{self, Variant};
    let mut rng = Rng(5);
    for case in 0..24 {
        let class = 1 + case % 3;
        let variant = if case % 2 == 0 {
            Variant::A
        } else {
            Variant::B
        };
        let mut m = if case % 4 < 2 {
            generate::assur(class as u32, 30, case as u64, variant)
        } else {
            generate::assur_spatial(class as u32, 30, case as u64, variant)
        }
        .expect("valid");
        if case >= 6 {
            // Fisher-Yates on the joints (a mechanism keeps them sorted by id; shuffled here
            // only to drive the game through other insertion orders).
            for i in (1..m.joints.len()).rev() {
                m.joints.swap(i, rng.below(i + 1));
            }
        }
        check(&m, &format!("linkage {case}"));
    }
}
