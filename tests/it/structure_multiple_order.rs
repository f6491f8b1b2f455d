//! Property test: the structural decomposition does not depend on the order
//! in which a multiple joint lists its bodies. Random planar and spatial mechanisms with
//! multiple joints (3 or 4 bodies) are analysed as generated and with the bodies of every
//! multiple joint permuted; groups (as body-id sets with their levels), the number of levels
//! and the status must be identical.
//!
//! Permutation rule (plan, "Multiple joints"): the driven DOF of a multiple joint drive bodies
//! 2..n relative to the first listed body, k per pair, in listed order. So an undriven multiple
//! joint is permuted fully; a driven one keeps its first listed body and the bodies of its
//! driven pairs (the first ceil(driven / k) after it) in place, and the rest are permuted.
//!
//! Ignored while the groups depend on the order (see
//! @multiple-joint-order and @multiple-joint-order-b).

use mbsa::joint::JointType::{self, *};
use mbsa::mechanism::{BodyId, JointSpec, Mechanism, Space};
use mbsa::rng::SplitMix64;
use mbsa::structure::{Analysis, Library, Options, Status, analyze};
use proptest::prelude::*;

const PLANAR: [JointType; 4] = [R, R, P, RP];
const SPATIAL: [JointType; 9] = [R, P, C, U, S, S, PL, SP, H];
/// Kinds a multiple joint may have (pins, slides, and in space the lower pairs).
const PLANAR_MULTI: [JointType; 3] = [R, R, P];
const SPATIAL_MULTI: [JointType; 5] = [R, P, C, U, S];

fn count_only() -> Options {
    Options {
        count_only: true,
        ..Options::default()
    }
}

fn build(space: Space, joints: &[JointSpec]) -> Mechanism {
    Mechanism::from_parts("random", space, BodyId::Int(1), vec![], joints.to_vec())
}

fn missing(a: &Analysis) -> u64 {
    a.diagnosis
        .as_ref()
        .and_then(|d| d.underdetermined.as_ref())
        .map_or(0, |u| u.missing)
}

fn over(a: &Analysis) -> u64 {
    a.diagnosis
        .as_ref()
        .and_then(|d| d.overdetermined.as_ref())
        .map_or(0, |o| o.excess)
}

fn pick(rng: &mut SplitMix64, kinds: &[JointType]) -> JointType {
    kinds[rng.below(kinds.len() as u64) as usize]
}

/// `k` distinct bodies of 1..=n (k <= n).
fn distinct(rng: &mut SplitMix64, n: usize, k: usize) -> Vec<i64> {
    let mut all: Vec<i64> = (1..=n as i64).collect();
    for i in 0..k {
        let j = i + rng.below((all.len() - i) as u64) as usize;
        all.swap(i, j);
    }
    all.truncate(k);
    all
}

/// A random connected mechanism of `n` bodies (frame 1) with at least one multiple joint: a
/// random spanning tree (some of its joints widened to 3 or 4 bodies), extra joints (half of
/// them multiple) kept when they leave no over-determined part by counting, then inputs placed
/// one by one where they fix a missing DOF (multiple joints may be driven). The result need not
/// be determined: the property holds for every status.
fn random_mechanism(n: usize, planar: bool, seed: u64) -> Option<Mechanism> {
    let mut rng = SplitMix64::new(seed);
    let (space, kinds, multi): (Space, &[JointType], &[JointType]) = if planar {
        (Space::Planar, &PLANAR, &PLANAR_MULTI)
    } else {
        (Space::Spatial, &SPATIAL, &SPATIAL_MULTI)
    };
    let lib = Library::empty();
    let mut joints: Vec<JointSpec> = Vec::new();
    for b in 2..=n as i64 {
        let a = 1 + rng.below(b as u64 - 1) as i64;
        if b > 2 && rng.below(4) == 0 {
            // A multiple joint joining b to two earlier bodies.
            let mut spec = JointSpec::new(pick(&mut rng, multi), a, b, 0);
            let c = 1 + rng.below(b as u64 - 1) as i64;
            if c != a {
                spec.bodies.push(BodyId::Int(c));
            }
            joints.push(spec);
        } else {
            joints.push(JointSpec::new(pick(&mut rng, kinds), a, b, 0));
        }
    }
    let extra = rng.below(2 * n as u64 + 1);
    for _ in 0..extra {
        let spec = if n >= 3 && rng.below(2) == 0 {
            let k = if n >= 4 && rng.below(3) == 0 { 4 } else { 3 };
            let bodies = distinct(&mut rng, n, k);
            let mut s = JointSpec::new(pick(&mut rng, multi), bodies[0], bodies[1], 0);
            s.bodies.extend(bodies[2..].iter().map(|&x| BodyId::Int(x)));
            s
        } else {
            let ab = distinct(&mut rng, n, 2);
            JointSpec::new(pick(&mut rng, kinds), ab[0], ab[1], 0)
        };
        joints.push(spec);
        let a = analyze(&build(space, &joints), &count_only(), &lib).unwrap();
        if over(&a) > 0 {
            joints.pop();
        }
    }
    if !joints.iter().any(|j| j.bodies.len() >= 3) {
        return None;
    }
    // Inputs: try joints in random order, keep an input when it fixes a missing DOF.
    loop {
        let a = analyze(&build(space, &joints), &count_only(), &lib).unwrap();
        let miss = missing(&a);
        if miss == 0 {
            break;
        }
        let start = rng.below(joints.len() as u64) as usize;
        let mut placed = false;
        for i in 0..joints.len() {
            let j = (start + i) % joints.len();
            let cap = joints[j].kind.grade() as u32 * (joints[j].bodies.len() as u32 - 1);
            if joints[j].driven >= cap {
                continue;
            }
            joints[j].driven += 1;
            let b = analyze(&build(space, &joints), &count_only(), &lib).unwrap();
            if over(&b) == 0 && missing(&b) < miss {
                placed = true;
                break;
            }
            joints[j].driven -= 1;
        }
        if !placed {
            break;
        }
    }
    Some(build(space, &joints))
}

/// The same joints with the bodies of every multiple joint permuted (driven ones keep their
/// first body and the bodies of their driven pairs in place).
fn permuted(space: Space, joints: &[JointSpec], seed: u64) -> Mechanism {
    let mut rng = SplitMix64::new(seed);
    let mut out = joints.to_vec();
    for j in &mut out {
        if j.bodies.len() < 3 {
            continue;
        }
        let k = j.kind.grade() as u32;
        let fixed = if j.driven == 0 {
            0
        } else {
            1 + j.driven.div_ceil(k) as usize
        };
        let len = j.bodies.len();
        let tail = &mut j.bodies[fixed.min(len)..];
        for i in (1..tail.len()).rev() {
            let r = rng.below(i as u64 + 1) as usize;
            tail.swap(i, r);
        }
    }
    build(space, &out)
}

/// Groups as sorted (level, sorted body ids), the number of levels and the status.
fn shape(a: &Analysis) -> (Vec<(usize, Vec<String>)>, usize, Status) {
    let mut g: Vec<(usize, Vec<String>)> = a
        .groups
        .iter()
        .map(|g| {
            let mut b = g.bodies.clone();
            b.sort();
            (g.level, b)
        })
        .collect();
    g.sort();
    (g, a.levels, a.status)
}

/// The specs of `m` with explicit ids, so that permuting a multiple joint's bodies does not
/// rename it (a default id is made of its first two bodies) and thus reorder the joints.
fn joints_of(m: &Mechanism) -> Vec<JointSpec> {
    m.joints
        .iter()
        .map(|j| JointSpec {
            id: Some(j.id.clone()),
            kind: j.kind,
            bodies: j.bodies.iter().map(|&b| m.bodies[b].id.clone()).collect(),
            driven: j.driven,
            geometry: j.geometry.to_geometry(),
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn multiple_joint_order_does_not_change_the_structure(
        n in 3usize..=12, planar: bool, seed: u64, perm in any::<[u64; 3]>()
    ) {
        let Some(m) = random_mechanism(n, planar, seed) else {
            return Ok(());
        };
        let space = m.space;
        let specs = joints_of(&m);
        let m = build(space, &specs);
        let lib = Library::empty();
        for opts in [count_only(), Options::default()] {
            let base = shape(&analyze(&m, &opts, &lib).unwrap());
            for &p in &perm {
                let q = permuted(space, &specs, p);
                let other = shape(&analyze(&q, &opts, &lib).unwrap());
                prop_assert_eq!(&base, &other, "count_only {}; permutation seed {}", opts.count_only, p);
            }
        }
    }
}

/// The issue's own example, both listings, through the library (the permutation property in
/// its smallest form): {5}, {3,4}, {2,6} on 3 levels, determined.
#[test]
fn issue_example_in_every_order() {
    let lib = Library::empty();
    let mut shapes = Vec::new();
    for order in [
        [2, 3, 4],
        [2, 4, 3],
        [3, 2, 4],
        [3, 4, 2],
        [4, 2, 3],
        [4, 3, 2],
    ] {
        let mut pin = JointSpec::new(R, order[0], order[1], 0);
        pin.id = Some("P".to_string());
        pin.bodies.push(BodyId::Int(order[2]));
        let joints = vec![
            JointSpec::new(R, 1, 5, 1),
            JointSpec::new(R, 5, 4, 0),
            JointSpec::new(R, 1, 3, 0),
            pin,
            JointSpec::new(R, 2, 6, 0),
            JointSpec::new(R, 1, 6, 0),
        ];
        let m = build(Space::Planar, &joints);
        for opts in [count_only(), Options::default()] {
            shapes.push((
                order,
                opts.count_only,
                shape(&analyze(&m, &opts, &lib).unwrap()),
            ));
        }
    }
    let want = (
        vec![
            (1, vec!["5".to_string()]),
            (2, vec!["3".to_string(), "4".to_string()]),
            (3, vec!["2".to_string(), "6".to_string()]),
        ],
        3,
        Status::Determined,
    );
    for (order, co, s) in &shapes {
        assert_eq!(s, &want, "order {order:?}, count_only {co}");
    }
}
