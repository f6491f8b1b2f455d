//! Scale regression of the pebble game (issue 16 item 3), by work units (deterministic, unlike
//! time): a uniform planar Laman framework of 20,000 points (39,997 bars as bodies) and a star
//! of 50,000 bodies on one shared spherical joint must fit in budgets that the previous game
//! (session 4) overran many times over. Measured with the release CLI (`--max-work`): Laman,
//! new < 5·10^6 units, old > 2·10^7 (its whole-rigid `degenerate` check ran the game again,
//! quadratic on the flexible remainder); shared S, new < 2·10^6, old > 2·10^7 (each body's
//! pin was contracted by a reverse search over every bar into the shared node). The budgets
//! below leave the new game twice its need and stay below the old one's.
//!
//! Session 6: the planar Assur linkage of 10^5 bodies (99,998) (`mbsa generate assur --class 2 --groups
//! 24999`, the growth.py family): one flexible piece, no rigid component to contract. Measured
//! with `--max-work` on the release CLI: the new game fits 4·10^7 units, the session-5 game
//! needs more than 1.6·10^8 (each bar fetched its B + 1 pebbles from wherever the few free ones
//! had wandered).

use mbsa::budget::Budget;
use mbsa::generate::{self, Variant};
use mbsa::joint::JointType;
use mbsa::rigidity::pebble::{PebbleOptions, analyze_within};
use mbsa::{BodyId, Geometry, JointSpec, Mechanism, Space};

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// The uniform Laman framework of tests/pebble_perf.rs: Henneberg type I steps on points
/// chosen uniformly; bar k is body k, point p the revolute joining its bars.
fn laman(points: usize, seed: u64) -> Mechanism {
    let mut rng = Rng(seed);
    let mut bars = vec![(0, 1)];
    for i in 2..points {
        let a = rng.below(i);
        let mut b = rng.below(i);
        while b == a {
            b = rng.below(i);
        }
        bars.push((a, i));
        bars.push((b, i));
    }
    let mut at: Vec<Vec<i64>> = vec![Vec::new(); points];
    for (k, &(a, b)) in bars.iter().enumerate() {
        at[a].push(k as i64 + 1);
        at[b].push(k as i64 + 1);
    }
    let joints = at
        .into_iter()
        .enumerate()
        .filter(|(_, bs)| bs.len() >= 2)
        .map(|(p, bs)| JointSpec {
            id: Some(format!("p{p}")),
            kind: JointType::R,
            bodies: bs.into_iter().map(BodyId::Int).collect(),
            driven: 0,
            geometry: Geometry::default(),
        })
        .collect();
    Mechanism::from_parts("laman", Space::Planar, BodyId::Int(1), vec![], joints)
}

fn budget(max_work: u64) -> Budget {
    Budget {
        max_work,
        ..Budget::DEFAULT
    }
}

#[test]
fn laman_20000_points_fits_ten_million_units() {
    let m = laman(20_000, 7);
    let r = analyze_within(&m, &PebbleOptions::default(), &budget(10_000_000))
        .expect("the component game fits the budget");
    assert_eq!((r.dof, r.redundant), (0, 0), "minimally rigid");
    assert_eq!(r.rigid.len(), 1);
    assert_eq!(r.rigid[0].len(), 2 * 20_000 - 3);
    assert!(
        r.degenerate,
        "the first triangle is a proper rigid sub-chain"
    );
}

#[test]
fn shared_spherical_joint_of_50000_bodies_fits_five_million_units() {
    let m = generate::star(50_000, JointType::S, false, true, false).expect("valid");
    let r = analyze_within(&m, &PebbleOptions::default(), &budget(5_000_000))
        .expect("the component game fits the budget");
    assert_eq!(r.redundant, 0);
    assert_eq!(r.dof, 3 * 49_999);
    assert_eq!(r.rigid, [["1"]]);
}

#[test]
fn planar_assur_of_100000_bodies_fits_sixty_million_units() {
    let m = generate::assur(2, 24_999, 364, Variant::A).expect("valid");
    assert_eq!(m.bodies.len(), 99_998);
    let r = analyze_within(&m, &PebbleOptions::default(), &budget(60_000_000))
        .expect("the near-linear game fits the budget");
    assert_eq!((r.dof, r.redundant), (1, 0), "one crank, no redundancy");
    assert_eq!(r.rigid, [["1"]], "no rigid component but the frame");
    assert!(!r.degenerate);
}

#[test]
fn the_budget_still_stops_a_large_game() {
    // The same framework with a budget far below its need: the typed error, not a wrong answer.
    let m = laman(20_000, 7);
    let e = analyze_within(&m, &PebbleOptions::default(), &budget(100_000)).unwrap_err();
    assert!(e.to_string().contains("work units"), "{e}");
}
