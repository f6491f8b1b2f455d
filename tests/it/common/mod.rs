//! Helpers shared by the test modules: the binary run with arguments (`mbsa`), and the
//! generators of the pebble-game tests (`pebble_*`) and `geometric_exact`: the local
//! SplitMix64 stream and the planar bar-joint frameworks written as mechanisms.
#![allow(dead_code)]

use mbsa::joint::JointType;
use mbsa::{BodyId, Geometry, JointSpec, Mechanism, Space};

/// SplitMix64, local so that the fixtures do not move when the library's generator does.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A bar-joint framework as a planar mechanism: bar k (1-based) is body k, point p the
/// revolute `p<p>` joining the bars that meet there; bar 1 is the frame.
pub fn bar_framework(name: &str, points: usize, bars: &[(usize, usize)]) -> Mechanism {
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
    Mechanism::from_parts(name, Space::Planar, BodyId::Int(1), vec![], joints)
}

/// A planar Laman framework of `points` points by Henneberg type I steps: each new point is
/// joined to two distinct earlier points, chosen uniformly (`local` = false) or among the 8
/// previous points (`local` = true). 2·points − 3 bars, minimally rigid.
pub fn laman(points: usize, local: bool, seed: u64) -> Mechanism {
    let mut rng = Rng(seed);
    let mut bars = vec![(0, 1)];
    for i in 2..points {
        let lo = if local { i.saturating_sub(8) } else { 0 };
        let a = lo + rng.below(i - lo);
        let mut b = lo + rng.below(i - lo);
        while b == a {
            b = lo + rng.below(i - lo);
        }
        bars.push((a, i));
        bars.push((b, i));
    }
    bar_framework("laman", points, &bars)
}

/// Runs this crate's `mbsa` binary with `args`: exit code (-1 if killed), stdout, stderr.
pub fn mbsa(args: &[&str]) -> (i32, String, String) {
    let out = assert_cmd::Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .output()
        .expect("mbsa runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The IFToMM N-four-bar of `windows` windows (as the bundled `n-four-bar-40`), its first
/// crank driven: verticals pinned to the ground (body 1) at `(k, 0)`, their tops at
/// `(k + 0.6, 0.8)` joined by horizontals. `header`: the lines after the name (`space`,
/// `frame`, `precision`); `pin(x, y)`: the geometry lines of a pin at `(x, y)`.
pub fn n_four_bar_with(windows: usize, header: &str, pin: impl Fn(f64, f64) -> String) -> String {
    let mut out = format!("name = \"N-four-bar (N = {windows})\"\n{header}\n");
    let mut joint = |id: String, a: usize, b: usize, (x, y): (f64, f64), driven: bool| {
        out.push_str(&format!(
            "\n[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\n{}\n{}",
            pin(x, y),
            if driven { "driven = 1\n" } else { "" }
        ));
    };
    joint("A0".into(), 1, 2, (0.0, 0.0), true);
    for k in 1..=windows {
        let kf = k as f64;
        joint(
            format!("VB{}", k - 1),
            2 * k,
            2 * k + 1,
            (kf - 0.4, 0.8),
            false,
        );
        joint(
            format!("B{k}"),
            2 * k + 1,
            2 * k + 2,
            (kf + 0.6, 0.8),
            false,
        );
        joint(format!("P{k}"), 1, 2 * k + 2, (kf, 0.0), false);
    }
    out
}
