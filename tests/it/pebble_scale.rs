//! Scale regression of the pebble game, by work units (deterministic, unlike
//! time): a uniform planar Laman framework of 20,000 points (39,997 bars as bodies) and a star
//! of 50,000 bodies on one shared spherical joint must fit in budgets that an earlier game
//! overran many times over. Measured with the release CLI (`--max-work`): Laman,
//! new < 5·10^6 units, old > 2·10^7 (its whole-rigid `degenerate` check ran the game again,
//! quadratic on the flexible remainder); shared S, new < 2·10^6, old > 2·10^7 (each body's
//! pin was contracted by a reverse search over every bar into the shared node). The budgets
//! below leave the new game twice its need and stay below the old one's.
//!
//! The planar Assur linkage of 10^5 bodies (99,998) (`mbsa generate assur --class 2 --groups
//! 24999`, the growth.py family): one flexible piece, no rigid component to contract. Measured
//! with `--max-work` on the release CLI: the new game fits 4·10^7 units, an earlier game
//! needs more than 1.6·10^8 (each bar fetched its B + 1 pebbles from wherever the few free ones
//! had wandered).
//!
//! A searched bar gathers B + 2 pebbles once (independent, and not tight after it)
//! instead of B + 1 before the bar and B + 1 again after it. The same planar Assur linkage:
//! 2.01·10^7 units (gathering B + 1 twice: 3.12·10^7), so a budget of 2.5·10^7 fails the old game.

use mbsa::budget::Budget;
use mbsa::generate::{self, Variant};
use mbsa::joint::JointType;
use mbsa::rigidity::pebble::{PebbleOptions, analyze_within};

use crate::common;
use common::laman;

fn budget(max_work: u64) -> Budget {
    Budget {
        max_work,
        ..Budget::DEFAULT
    }
}

#[test]
fn laman_20000_points_fits_ten_million_units() {
    let m = laman(20_000, false, 7);
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
fn planar_assur_of_100000_bodies_fits_twenty_five_million_units() {
    let m = generate::assur(2, 24_999, 364, Variant::A).expect("valid");
    let r = analyze_within(&m, &PebbleOptions::default(), &budget(25_000_000))
        .expect("one gather per searched bar fits the budget");
    assert_eq!((r.dof, r.redundant), (1, 0));
    assert_eq!(r.rigid, [["1"]]);
    assert!(!r.degenerate);
}

#[test]
fn the_budget_still_stops_a_large_game() {
    // The same framework with a budget far below its need: the typed error, not a wrong answer.
    let m = laman(20_000, false, 7);
    let e = analyze_within(&m, &PebbleOptions::default(), &budget(100_000)).unwrap_err();
    assert!(e.to_string().contains("work units"), "{e}");
}
