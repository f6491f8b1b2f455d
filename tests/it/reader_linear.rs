//! Readers in linear time on inputs shaped to defeat them: many unknown top-level keys in
//! TOML, and large bar-joint frameworks. The time is printed and bounded far above the
//! linear reader's (a quadratic reader takes minutes here).

use mbsa::format::{ErrorKind, Format, load};
use std::fmt::Write as _;
use std::time::Instant;

/// 10^5 unknown top-level keys `kNNN = 1`: the fast TOML reader's duplicate check was a scan
/// of the keys so far (23 s in a release build); the first unknown key is the error.
#[test]
fn many_unknown_top_level_toml_keys_read_in_linear_time() {
    let mut keys = String::from("name = \"keys\"\nframe = 1\n");
    for k in 0..100_000 {
        let _ = writeln!(keys, "k{k} = 1");
    }
    let joint = "\n[[joint]]\nid = \"A\"\ntype = \"R\"\nbodies = [1, 2]\n";
    let text = format!("{keys}{joint}");
    let start = Instant::now();
    let e = load("keys.toml", &text, Format::Toml).expect_err("unknown keys");
    let took = start.elapsed();
    eprintln!("10^5 unknown top-level keys read in {took:?}");
    // Linear: a tenth of a second; the quadratic scan took 23 s in a release build.
    assert!(took.as_secs() < 10, "{took:?}");
    assert_eq!(e.kind(), ErrorKind::UnknownKey, "{e}");
    assert!(e.to_string().contains("`k0`"), "{e}");
    // The same keys, the fifth repeated last: the duplicate is still found.
    let text = format!("{keys}k5 = 2\n{joint}");
    let start = Instant::now();
    let e = load("keys.toml", &text, Format::Toml).expect_err("a duplicate key");
    eprintln!("10^5 keys and a duplicate read in {:?}", start.elapsed());
    assert_eq!(e.kind(), ErrorKind::Syntax, "{e}");
    assert!(e.to_string().contains("duplicate key"), "{e}");
}

/// A planar Laman framework of `points` points (Henneberg steps onto the 8 previous
/// points, from a fixed stream): 2·points − 3 bars.
fn laman(points: usize) -> String {
    let mut s = String::from("name = \"laman\"\nspace = \"planar\"\nframe = \"0-1\"\n");
    let mut x: u64 = 7;
    let mut next = |n: usize| {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 33) % n as u64) as usize
    };
    for p in 0..points {
        let _ = write!(
            s,
            "\n[[point]]\nid = {p}\nat = [{}, {}]\n",
            next(1000),
            next(1000)
        );
    }
    let _ = write!(s, "\n[[bar]]\npoints = [0, 1]\n");
    for i in 2..points {
        let lo = i.saturating_sub(8);
        let a = lo + next(i - lo);
        let mut b = lo + next(i - lo);
        while b == a {
            b = lo + next(i - lo);
        }
        let _ = write!(
            s,
            "\n[[bar]]\npoints = [{a}, {i}]\n\n[[bar]]\npoints = [{b}, {i}]\n"
        );
    }
    s
}

/// A 10^5-point framework: each point's joint gathered the bars meeting there by a scan of
/// every bar (58.5 s in `mbsa mobility`); now one pass over the bars.
#[test]
fn a_hundred_thousand_point_framework_reads_in_linear_time() {
    let points = 100_000;
    let text = laman(points);
    let start = Instant::now();
    let m = load("laman.toml", &text, Format::Toml).expect("the framework reads");
    let r = mbsa::mobility::mobility(&m);
    let took = start.elapsed();
    eprintln!("10^5-point framework read and counted in {took:?}");
    // Linear: about a second; the scan per point took 58.5 s in a release build.
    assert!(took.as_secs() < 20, "{took:?}");
    assert_eq!(m.bodies.len(), 2 * points - 3);
    // A minimally rigid framework: mobility 0 by the count (3 per bar, 2 per R pair).
    assert_eq!(r.bodies, 2 * points - 3);
    assert_eq!(r.mobility.count, 0, "{r:?}");
}
