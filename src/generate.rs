//! Generated mechanisms for benchmarks and tests, reproducible from a seed.
//!
//! - [`assur`]: the planar Assur-group linkages of `docs/benchmarks.md` (the paper's Table 16
//!   family), exactly as specified there (SplitMix64, templates, port rule).
//! - [`assur_spatial`]: the same linkages in space, with universal joints.
//! - [`stewart_stack`]: N Stewart platforms stacked, each on six UPS legs (spatial).
//! - [`random`]: random count-determined mechanisms with mixed joint types, built group by
//!   group so that the expected number of structural groups is known.

use crate::joint::JointType;
use crate::mechanism::{BodyId, Geometry, JointSpec, Mechanism, Space};
use crate::rng::SplitMix64;

/// Which joint carries the single input of an Assur linkage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// The crank (1, 2) is driven.
    A,
    /// The joint between the two last bodies (N − 1, N) is driven instead.
    B,
}

/// Internal pairs and ports of the class-k template (local body indices).
fn template(class: u32) -> (&'static [(usize, usize)], &'static [usize]) {
    match class {
        1 => (&[(0, 1)], &[0, 1]),
        2 => (&[(0, 3), (1, 3), (2, 3)], &[0, 1, 2]),
        _ => (
            &[(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0)],
            &[0, 2, 4],
        ),
    }
}

/// Errors in generator parameters.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GenerateError {
    /// A parameter out of range.
    #[error("{0}")]
    Range(String),
}

/// Memory a generated mechanism and its TOML text take per joint, in bytes (measured at
/// 10^6 bodies: 510 to 560; rounded up). With [`estimated_joints`] it gives the estimate that
/// `mbsa generate` checks against the memory budget before generating, so that parameters it
/// cannot produce are refused with a message instead of aborting on a failed allocation.
pub const BYTES_PER_JOINT: u64 = 640;

/// A generator family and its size parameter, for [`estimated_joints`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// [`assur`] / [`assur_spatial`]: class and groups.
    Assur {
        /// Assur class (1, 2 or 3).
        class: u32,
        /// Number of groups.
        groups: u64,
    },
    /// [`random`]: bodies and planarity.
    Random {
        /// Bodies, the frame included.
        bodies: u64,
        /// Planar.
        planar: bool,
    },
    /// [`stewart_stack`]: stages.
    Stewart {
        /// Stacked platforms.
        stages: u64,
    },
    /// [`serial_chain`] or [`star`]: bodies (the frame included).
    Tree {
        /// Bodies, the frame included.
        bodies: u64,
    },
}

/// How many joints a generator makes (exact for Assur and Stewart, an upper estimate for
/// random mechanisms: 3 joints per body in space, 2.5 in the plane; about 2.6 and 1.9 are
/// typical). Saturating.
pub fn estimated_joints(size: Size) -> u64 {
    match size {
        Size::Assur { class, groups } => {
            let (internal, ports) = template(class.clamp(1, 3));
            groups
                .saturating_mul((internal.len() + ports.len()) as u64)
                .saturating_add(1)
        }
        Size::Random { bodies, planar } => {
            if planar {
                bodies.saturating_mul(5) / 2
            } else {
                bodies.saturating_mul(3)
            }
        }
        Size::Stewart { stages } => stages.saturating_mul(18),
        Size::Tree { bodies } => bodies,
    }
}

/// The planar Assur linkage `assur(class, groups, seed, variant)`: a driven crank plus
/// `groups` Assur groups of class 1 (dyad), 2 (triad) or 3 (three-loop hexagon), attached at
/// random to earlier bodies. N = 2 + 2·class·groups bodies, every pair revolute.
pub fn assur(
    class: u32,
    groups: u64,
    seed: u64,
    variant: Variant,
) -> Result<Mechanism, GenerateError> {
    assur_in(class, groups, seed, variant, Space::Planar)
}

/// The spatial counterpart of [`assur`]: the same bodies, pairs, port targets and driven
/// pair, with every pair a universal joint (4 equations) but the crank (1, 2), a revolute.
/// Each template then has exactly 6 equations per body (dyad 3 · 4 = 2 · 6, triad 6 · 4 =
/// 4 · 6, hexagon 9 · 4 = 6 · 6), so with the crank driven (variant A) every group is one
/// structural group again; variant B merges them as in the plane. Not from the paper: a
/// spatial family of the same shape for the scale benchmarks.
pub fn assur_spatial(
    class: u32,
    groups: u64,
    seed: u64,
    variant: Variant,
) -> Result<Mechanism, GenerateError> {
    assur_in(class, groups, seed, variant, Space::Spatial)
}

fn assur_in(
    class: u32,
    groups: u64,
    seed: u64,
    variant: Variant,
    space: Space,
) -> Result<Mechanism, GenerateError> {
    if !(1..=3).contains(&class) {
        return Err(GenerateError::Range(format!(
            "Assur class must be 1, 2 or 3, not {class}"
        )));
    }
    if groups == 0 || groups > 10_000_000 {
        return Err(GenerateError::Range(format!(
            "the number of groups must be between 1 and 10^7, not {groups}"
        )));
    }
    let (internal, ports) = template(class);
    let size = 2 * class as u64;
    let n_bodies = 2 + size * groups;
    let mut rng = SplitMix64::new(seed);
    let mut pairs: Vec<(u64, u64)> = vec![(1, 2)];
    for g in 1..=groups {
        let s = 3 + size * (g - 1);
        for &(a, b) in internal {
            pairs.push((s + a as u64, s + b as u64));
        }
        let targets: Vec<u64> = if g == 1 {
            (0..ports.len())
                .map(|i| if i == 0 { 2 } else { 1 })
                .collect()
        } else {
            loop {
                let t: Vec<u64> = ports.iter().map(|_| 1 + rng.below(s - 1)).collect();
                if t.iter().any(|&x| x != t[0]) {
                    break t;
                }
            }
        };
        for (&port, &target) in ports.iter().zip(&targets) {
            pairs.push((target, s + port as u64));
        }
    }
    let driven_pair = match variant {
        Variant::A => (1, 2),
        Variant::B => (n_bodies - 1, n_bodies),
    };
    let joints = pairs
        .iter()
        .map(|&(a, b)| {
            let driven = u32::from((a, b) == driven_pair);
            let kind = if space == Space::Planar || (a, b) == (1, 2) {
                JointType::R
            } else {
                JointType::U
            };
            JointSpec::new(kind, a as i64, b as i64, driven)
        })
        .collect();
    let v = match variant {
        Variant::A => "A",
        Variant::B => "B",
    };
    let roman = ["I", "II", "III"][class as usize - 1];
    let (prefix, what) = match space {
        Space::Planar => ("", ""),
        _ => ("spatial ", "spatial "),
    };
    let mut m = Mechanism::from_parts(
        format!("{prefix}ASSUR {roman}-{groups}{v} (seed {seed})"),
        space,
        BodyId::Int(1),
        vec![],
        joints,
    );
    m.description = Some(format!(
        "Generated: crank plus {groups} {what}Assur group(s) of class {class}, variant {v}, seed {seed} (docs/benchmarks.md)"
    ));
    Ok(m)
}

/// `stages` Stewart platforms stacked: platform s stands on platform s − 1 (the frame for
/// s = 1) through six U-P-S legs with the prismatic joints driven. Each stage is one
/// structural group of 13 bodies (the paper's Stewart case, repeated).
pub fn stewart_stack(stages: u64) -> Result<Mechanism, GenerateError> {
    if stages == 0 || stages > 1_000_000 {
        return Err(GenerateError::Range(format!(
            "the number of stages must be between 1 and 10^6, not {stages}"
        )));
    }
    let mut joints = Vec::new();
    let mut lower = 1i64;
    let mut next = 2i64;
    for _ in 0..stages {
        let platform = next + 12;
        for _ in 0..6 {
            let (a, b) = (next, next + 1);
            joints.push(JointSpec::new(JointType::U, lower, a, 0));
            joints.push(JointSpec::new(JointType::P, a, b, 1));
            joints.push(JointSpec::new(JointType::S, b, platform, 0));
            next += 2;
        }
        lower = platform;
        next = platform + 1;
    }
    let mut m = Mechanism::from_parts(
        format!("Stewart stack x{stages}"),
        Space::Spatial,
        BodyId::Int(1),
        vec![],
        joints,
    );
    m.description = Some(format!(
        "Generated: {stages} Stewart platform(s) stacked on U-P-S legs, prismatic joints driven"
    ));
    Ok(m)
}

fn tree_bodies(bodies: u64) -> Result<i64, GenerateError> {
    if !(2..=10_000_000).contains(&bodies) {
        return Err(GenerateError::Range(format!(
            "the number of bodies must be between 2 and 10^7, not {bodies}"
        )));
    }
    Ok(bodies as i64)
}

fn tree_space(kind: JointType, planar: bool) -> Result<Space, GenerateError> {
    let space = if planar {
        Space::Planar
    } else {
        Space::Spatial
    };
    if planar && !kind.valid_in(space) {
        return Err(GenerateError::Range(format!(
            "a {} joint is not a planar joint",
            kind.code()
        )));
    }
    Ok(space)
}

/// An open serial chain of `bodies` bodies (the frame, body 1, included): joint k joins bodies
/// k and k + 1, every joint of kind `kind`, all of its DOF driven when `driven` (a determined
/// arm: one group per body) or none (mobility = the sum of the grades). No geometry: the
/// geometric analyses use a random realization. For the scale benchmarks (docs/benchmarks.md).
pub fn serial_chain(
    bodies: u64,
    kind: JointType,
    planar: bool,
    driven: bool,
) -> Result<Mechanism, GenerateError> {
    let n = tree_bodies(bodies)?;
    let space = tree_space(kind, planar)?;
    let d = if driven { u32::from(kind.grade()) } else { 0 };
    let joints = (1..n).map(|k| JointSpec::new(kind, k, k + 1, d)).collect();
    let mut m = Mechanism::from_parts(
        format!("serial chain x{}", n - 1),
        space,
        BodyId::Int(1),
        vec![],
        joints,
    );
    m.description = Some(format!(
        "Generated: an open serial chain of {} {} joints{}",
        n - 1,
        kind.code(),
        if driven { ", every DOF driven" } else { "" }
    ));
    Ok(m)
}

/// A star of `bodies` bodies (the frame, body 1, included): every other body joined to the
/// frame by its own `kind` joint, or with `shared` by one multiple joint naming all of them.
/// Every DOF driven when `driven`. No geometry. For the scale benchmarks (docs/benchmarks.md).
pub fn star(
    bodies: u64,
    kind: JointType,
    planar: bool,
    shared: bool,
    driven: bool,
) -> Result<Mechanism, GenerateError> {
    let n = tree_bodies(bodies)?;
    let space = tree_space(kind, planar)?;
    let d = if driven { u32::from(kind.grade()) } else { 0 };
    let joints = if shared {
        vec![JointSpec {
            id: Some("hub".to_string()),
            kind,
            bodies: (1..=n).map(BodyId::Int).collect(),
            // A multiple joint of k bodies is k - 1 pairs; `driven` counts the pair DOF.
            driven: d.saturating_mul((n - 1) as u32),
            geometry: Geometry::default(),
        }]
    } else {
        (2..=n).map(|k| JointSpec::new(kind, 1, k, d)).collect()
    };
    let mut m = Mechanism::from_parts(
        format!("star x{}", n - 1),
        space,
        BodyId::Int(1),
        vec![],
        joints,
    );
    m.description = Some(format!(
        "Generated: {} bodies on the frame by {} {} joint{}{}",
        n - 1,
        if shared { "one shared" } else { "their own" },
        kind.code(),
        if shared { "" } else { "s" },
        if driven { ", every DOF driven" } else { "" }
    ));
    Ok(m)
}

/// A random count-determined mechanism of `bodies` bodies (frame included) with mixed joint
/// types, built group by group: each new group of 1 or 2 bodies gets joints to earlier bodies
/// (and one internal joint) whose equations add up to exactly B per body, with driven inputs
/// filling the rest, and no body of a 2-body group determined on its own. The returned count
/// is the number of structural groups this construction makes by counting.
pub fn random(bodies: u64, planar: bool, seed: u64) -> Result<(Mechanism, usize), GenerateError> {
    if !(2..=10_000_000).contains(&bodies) {
        return Err(GenerateError::Range(format!(
            "the number of bodies must be between 2 and 10^7, not {bodies}"
        )));
    }
    let (space, b) = if planar {
        (Space::Planar, 3u32)
    } else {
        (Space::Spatial, 6u32)
    };
    // Pools of joint kinds by the number of equations c = B − k they bring.
    let by_c = |c: u32| -> &'static [JointType] {
        use JointType::*;
        match (planar, c) {
            (true, 1) => &[L, EO, RP],
            (true, 2) => &[R, R, R, P],
            (false, 1) => &[SP, SPSP],
            (false, 2) => &[SC, PC],
            (false, 3) => &[S, S, PL],
            (false, 4) => &[U, C, C],
            (false, 5) => &[R, R, P, H],
            _ => &[],
        }
    };
    let mut rng = SplitMix64::new(seed);
    let mut joints: Vec<JointSpec> = Vec::new();
    let mut n = 1u64; // bodies so far (the frame is body 1)
    let mut groups = 0usize;
    let pick = |rng: &mut SplitMix64, pool: &'static [JointType]| {
        pool[rng.below(pool.len() as u64) as usize]
    };
    let earlier = |rng: &mut SplitMix64, n: u64| -> i64 {
        // Favour recent bodies so that chains get deep, but reach back to the frame too.
        if rng.below(4) == 0 {
            1 + rng.below(n) as i64
        } else {
            (n - rng.below(n.min(8))) as i64
        }
    };
    // Add joints from `body` to earlier bodies bringing exactly `need` equations.
    let attach =
        |rng: &mut SplitMix64, joints: &mut Vec<JointSpec>, body: i64, mut need: u32, n: u64| {
            while need > 0 {
                let c = 1 + rng.below(u64::from(need.min(b))) as u32;
                let (kind, driven) = if c == b {
                    // A whole body's worth: a driven grade-1 joint (B − 1 + 1 equations).
                    (pick(rng, by_c(b - 1)), 1)
                } else if c >= 2 && rng.below(3) == 0 {
                    // Sometimes a looser joint with a driven DOF.
                    let k = pick(rng, by_c(c - 1));
                    (k, 1)
                } else {
                    (pick(rng, by_c(c)), 0)
                };
                let target = earlier(rng, n);
                joints.push(JointSpec::new(kind, target, body, driven));
                need -= c;
            }
        };
    while n < bodies {
        let size = if bodies - n >= 2 && rng.below(2) == 0 {
            2
        } else {
            1
        };
        let first = n as i64 + 1;
        if size == 1 {
            attach(&mut rng, &mut joints, first, b, n);
        } else {
            let second = first + 1;
            // Internal joint with c_int equations; externals split so neither body reaches B alone.
            let c_int = 2 + rng.below(u64::from(b - 2)) as u32; // 2..=B−1 keeps lo <= B − 1
            joints.push(JointSpec::new(
                pick(&mut rng, by_c(c_int)),
                first,
                second,
                0,
            ));
            let rest = 2 * b - c_int; // in [B + 1, 2B − 2]
            let lo = rest - (b - 1); // each side at most B − 1
            let e1 = lo + rng.below(u64::from(b - 1 - lo + 1)) as u32;
            let e2 = rest - e1;
            attach(&mut rng, &mut joints, first, e1, n);
            attach(&mut rng, &mut joints, second, e2, n);
        }
        n += size;
        groups += 1;
    }
    let mut m = Mechanism::from_parts(
        format!(
            "random {} mechanism, {bodies} bodies (seed {seed})",
            if planar { "planar" } else { "spatial" }
        ),
        space,
        BodyId::Int(1),
        vec![],
        joints,
    );
    m.description = Some(format!(
        "Generated: random count-determined mechanism with mixed joint types, {groups} structural groups by construction"
    ));
    Ok((m, groups))
}

/// A random planar bar-joint framework: `bars` random bars on `points` points (no repeated
/// pair, no loop), each bar a body, each point a multiple revolute joint, bar 1 the frame.
/// For the pebble-game benchmarks (mean point degree 2·bars/points; 4 is the rigidity
/// threshold).
pub fn planar_framework(points: u64, bars: usize, seed: u64) -> Mechanism {
    let mut rng = SplitMix64::new(seed);
    let mut seen = std::collections::BTreeSet::new();
    let mut at: Vec<Vec<i64>> = vec![Vec::new(); points as usize];
    while seen.len() < bars {
        let (a, b) = (rng.below(points), rng.below(points));
        if a == b || !seen.insert((a.min(b), a.max(b))) {
            continue;
        }
        let id = seen.len() as i64;
        at[a as usize].push(id);
        at[b as usize].push(id);
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
    Mechanism::from_parts(
        "random framework",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        joints,
    )
}

/// A random spatial framework built by Henneberg steps: each new point is joined by bars to three
/// earlier points (three of the six nearest). Generically rigid: true mobility = bars − 1 spins +
/// 1 frame-bar spin, no redundancy. Bars are bodies, points are multiple S joints with their
/// centres as geometry. For the geometric-rigidity benchmarks.
pub fn henneberg_framework(points: usize, seed: u64) -> Mechanism {
    let mut rng = SplitMix64::new(seed);
    let mut p: Vec<[f64; 3]> = Vec::new();
    let mut bars: Vec<(usize, usize)> = vec![(0, 1), (0, 2), (1, 2)];
    for i in 0..points {
        let s = (i as f64).cbrt();
        p.push([
            s * rng.next_signed(),
            s * rng.next_signed(),
            s * rng.next_signed(),
        ]);
        if i >= 3 {
            let mut near: Vec<(f64, usize)> = (0..i)
                .map(|j| {
                    let d: f64 = (0..3).map(|k| (p[i][k] - p[j][k]).powi(2)).sum();
                    (d, j)
                })
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            // Three of the six nearest, at random: local, and not too flat.
            let mut pick: Vec<usize> = near.iter().take(6).map(|x| x.1).collect();
            for _ in 0..3 {
                let k = rng.below(pick.len() as u64) as usize;
                bars.push((pick.swap_remove(k), i));
            }
        }
    }
    let name = |k: usize| BodyId::Name(format!("b{k:05}"));
    let joints = (0..points)
        .map(|i| JointSpec {
            id: Some(format!("p{i}")),
            kind: JointType::S,
            bodies: bars
                .iter()
                .enumerate()
                .filter(|(_, (a, b))| *a == i || *b == i)
                .map(|(k, _)| name(k))
                .collect(),
            driven: 0,
            geometry: Geometry {
                origin: Some(p[i]),
                ..Geometry::default()
            },
        })
        .collect();
    Mechanism::from_parts("framework", Space::Spatial, name(0), vec![], joints)
}

/// Write a mechanism as a format-v1 TOML file (joints only; bodies declared when labelled).
pub fn to_toml(m: &Mechanism) -> String {
    crate::write::write(m, crate::write::TextFormat::Toml, &[])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mobility::mobility;

    #[test]
    fn assur_body_counts_follow_the_spec() {
        for (class, groups, bodies) in [(1, 2, 6), (1, 8, 18), (2, 4, 18), (3, 4, 26)] {
            let m = assur(class, groups, 364, Variant::A).unwrap();
            assert_eq!(m.bodies.len() as u64, bodies);
            let r = mobility(&m);
            assert_eq!(r.mobility.count, 1, "class {class} groups {groups}");
            assert_eq!(r.mobility.inputs, 1);
            assert!(r.disconnected.is_empty());
        }
    }

    #[test]
    fn assur_variant_b_moves_the_input_to_the_last_pair() {
        let m = assur(2, 4, 364, Variant::B).unwrap();
        let driven: Vec<&str> = m
            .joints
            .iter()
            .filter(|j| j.driven > 0)
            .map(|j| j.id.as_str())
            .collect();
        assert_eq!(driven, ["17-18"]);
    }

    #[test]
    fn assur_first_group_ports_hit_crank_then_frame() {
        let m = assur(2, 1, 0, Variant::A).unwrap();
        // The spec's pair order is (1,2), internal (3,6) (4,6) (5,6), ports (2,3) (1,4) (1,5);
        // the model keeps joints in natural id order.
        let ids: Vec<&str> = m.joints.iter().map(|j| j.id.as_str()).collect();
        assert_eq!(ids, ["1-2", "1-4", "1-5", "2-3", "3-6", "4-6", "5-6"]);
    }

    #[test]
    fn random_mechanisms_are_count_determined() {
        for seed in 0..200 {
            for planar in [false, true] {
                let (m, groups) = random(2 + seed % 17, planar, seed).unwrap();
                let r = mobility(&m);
                assert_eq!(r.mobility.count, r.mobility.inputs as i64, "seed {seed}");
                assert!(r.disconnected.is_empty());
                assert!(groups >= 1);
                for j in &m.joints {
                    assert!(j.driven <= j.grade());
                }
            }
        }
    }

    #[test]
    fn stewart_stack_counts() {
        let m = stewart_stack(3).unwrap();
        assert_eq!(m.bodies.len(), 1 + 3 * 13);
        let r = mobility(&m);
        assert_eq!(r.mobility.count, 18);
        assert_eq!(r.mobility.inputs, 18);
    }

    #[test]
    fn toml_writer_escapes_and_omits_default_ids() {
        let m = assur(1, 1, 1, Variant::A).unwrap();
        let text = to_toml(&m);
        assert!(text.contains("space = \"planar\""));
        assert!(text.contains("[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\n"));
        assert!(!text.contains("id = "));
    }
}
