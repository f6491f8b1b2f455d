//! Unit tests of the geometric rigidity analysis: the block-by-block, exact and whole-Jacobian
//! paths agree; the weights carry their check.

use super::jacobian::{Complements, Incidence, Pair, complement};
use super::*;
use crate::budget::Budget;
use crate::generate::{self, Variant};
use std::collections::BTreeSet;

/// [`Complements`] reads as the former vector of complements: the identity
/// ([`complement`] of no isolated motion, the same matrix) for every body not set, the
/// matrix set for the others, planar and spatial.
#[test]
fn complements_read_as_a_matrix_per_body() {
    for b in [3, 6] {
        let mut c = Complements::new(5, b);
        let own = DMatrix::from_fn(b, 2, |i, j| (i * 7 + j) as f64 - 0.5);
        c.set(3, own.clone());
        c.set(1, DMatrix::zeros(b, 0));
        assert_eq!(c.len(), 5);
        for body in [0, 2, 4] {
            assert_eq!(c[body], complement(&DMatrix::zeros(b, 0), b));
            assert_eq!(c[body], DMatrix::identity(b, b));
        }
        assert_eq!(c[3], own);
        assert_eq!(c[1].shape(), (b, 0));
    }
}

/// The flat incidence lists each body's pairs as the former `Vec` per body did: in
/// increasing order, a pair on one body twice (hub = other) listed twice, bodies without
/// pairs empty.
#[test]
fn incidence_lists_the_pairs_of_each_body_in_order() {
    let mut seed = 0x1234_5678_u64;
    let mut next = |n: usize| {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        ((seed >> 33) as usize) % n
    };
    for nb in [1usize, 2, 5, 17, 60] {
        let np = next(3 * nb + 1);
        let pairs: Vec<Pair> = (0..np)
            .map(|j| Pair {
                joint: j,
                hub: next(nb),
                other: next(nb),
            })
            .collect();
        let mut former: Vec<Vec<usize>> = vec![Vec::new(); nb];
        for (pi, p) in pairs.iter().enumerate() {
            former[p.hub].push(pi);
            former[p.other].push(pi);
        }
        let flat = Incidence::new(nb, &pairs);
        for (body, list) in former.iter().enumerate() {
            assert_eq!(&flat[body], list.as_slice(), "body {body} of {nb}");
        }
    }
}

/// The block-by-block path agrees with the whole-Jacobian one on every number and list.
fn same_both_ways(m: &Mechanism, opts: &GeometricOptions) {
    let whole = analyze_split(m, opts, &Budget::UNLIMITED, usize::MAX, usize::MAX);
    let split = analyze_split(m, opts, &Budget::UNLIMITED, 0, usize::MAX);
    let (whole, split) = match (whole, split) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(a), Err(b)) => {
            assert_eq!(a, b);
            return;
        }
        (a, b) => panic!("{}: {a:?} vs {b:?}", m.name),
    };
    let n = &m.name;
    assert_eq!(whole.rank, split.rank, "{n}");
    assert_eq!(whole.mobility, split.mobility, "{n}");
    assert_eq!(whole.redundant, split.redundant, "{n}");
    assert_eq!(whole.locked_joints, split.locked_joints, "{n}");
    assert_eq!(whole.isolated_motions, split.isolated_motions, "{n}");
    assert_eq!(whole.rigid, split.rigid, "{n}");
    let joints = |r: &GeometricReport| {
        let mut v: Vec<String> = r.redundant_joints.iter().map(|j| j.joint.clone()).collect();
        v.sort();
        v
    };
    assert_eq!(joints(&whole), joints(&split), "{n}");
    for (a, b) in whole.redundant_joints.iter().zip(&split.redundant_joints) {
        if a.joint == b.joint {
            assert!((a.weight - b.weight).abs() < 1e-4, "{n}: {a:?} {b:?}");
        }
    }
}

#[test]
fn blocks_agree_with_the_whole_jacobian_on_the_examples() {
    let mut compared = 0;
    for name in crate::examples::names() {
        let Some((file, text)) = crate::examples::find(name) else {
            continue;
        };
        let Ok(m) = crate::format::load(file, text, crate::format::Format::sniff(text)) else {
            continue;
        };
        if m.bodies.len() > 60 {
            continue;
        }
        compared += 1;
        for geometry in [
            GeometrySource::Auto { seed: 1 },
            GeometrySource::Random { seed: 3 },
        ] {
            let opts = GeometricOptions {
                geometry,
                ..Default::default()
            };
            same_both_ways(&m, &opts);
        }
    }
    assert!(compared >= 20, "{compared} examples compared");
}

#[test]
fn blocks_agree_with_the_whole_jacobian_on_generated_families() {
    let mut ms = vec![generate::stewart_stack(2).expect("small")];
    for seed in 0..4 {
        ms.push(generate::assur(1, 6, seed, Variant::A).expect("small"));
        ms.push(generate::assur_spatial(2, 3, seed, Variant::B).expect("small"));
        ms.push(generate::random(30, seed % 2 == 0, seed).expect("small").0);
    }
    for m in &ms {
        same_both_ways(m, &GeometricOptions::default());
    }
}

/// The exact path (every part, however small) agrees with the floating-point one on
/// every answer: rank, mobility, redundancy and the redundant joints, locked DOF,
/// isolated motions, rigid clusters.
fn exact_path_agrees(m: &Mechanism, opts: &GeometricOptions) -> usize {
    let mut compared = 0;
    for one_part in [usize::MAX, 0] {
        let float = analyze_split(m, opts, &Budget::UNLIMITED, one_part, usize::MAX);
        let exact = analyze_split(m, opts, &Budget::UNLIMITED, one_part, 0);
        let (float, exact) = match (float, exact) {
            (Ok(a), Ok(b)) => (a, b),
            (Err(a), Err(b)) => {
                assert_eq!(a, b);
                continue;
            }
            (a, b) => panic!("{}: {a:?} vs {b:?}", m.name),
        };
        let n = &m.name;
        assert_eq!(float.rank, exact.rank, "{n}");
        assert_eq!(float.mobility, exact.mobility, "{n}");
        assert_eq!(float.redundant, exact.redundant, "{n}");
        // The floating-point motions are only compared when they are reliable: the
        // elimination kept exactly the rank decided exactly, without a warning.
        let reliable = float.numeric.warning.is_none()
            && float
                .numeric
                .exact
                .as_deref()
                .is_some_and(|e| !e.contains("approximate"));
        if !reliable {
            continue;
        }
        let only = |a: &Vec<JointCount>, b: &Vec<JointCount>| {
            a.iter()
                .filter(|x| !b.contains(x))
                .cloned()
                .collect::<Vec<_>>()
        };
        assert_eq!(
            float.locked_joints,
            exact.locked_joints,
            "{n} ({one_part}): float only {:?}, exact only {:?}",
            only(&float.locked_joints, &exact.locked_joints),
            only(&exact.locked_joints, &float.locked_joints)
        );
        assert_eq!(float.isolated_motions, exact.isolated_motions, "{n}");
        let onlyr = |a: &Vec<RigidCluster>, b: &Vec<RigidCluster>| {
            a.iter()
                .filter(|x| !b.contains(x))
                .cloned()
                .collect::<Vec<_>>()
        };
        assert_eq!(
            float.rigid,
            exact.rigid,
            "{n} ({one_part}): float only {:?}, exact only {:?}",
            onlyr(&float.rigid, &exact.rigid),
            onlyr(&exact.rigid, &float.rigid)
        );
        let joints = |r: &GeometricReport| {
            let mut v: Vec<String> = r.redundant_joints.iter().map(|j| j.joint.clone()).collect();
            v.sort();
            v
        };
        assert_eq!(joints(&float), joints(&exact), "{n}");
        for (a, b) in float.redundant_joints.iter().zip(&exact.redundant_joints) {
            if a.joint == b.joint {
                assert!((a.weight - b.weight).abs() < 1e-4, "{n}: {a:?} {b:?}");
            }
        }
        compared += 1;
    }
    compared
}

/// The joints' weights carry their own check. On random spatial 400 seed 6
/// with its driven DOF kept, the transposed elimination reaches the exact rank only at a
/// raised threshold, and the self-stresses it gives leave ‖yᵀA‖ about 6·10^-5 σ_max
/// (above the analysis's own threshold, 1e-9 · rows · σ_max): the report says the weights
/// are approximate, with that residual (the old code printed them as if exact). Where the
/// first elimination finds the exact rank (10^3 seed 2) and at a file's geometry within
/// the precision of its rounded numbers (the Bennett linkage to 4 decimals, residual about
/// 10^-6), no note.
#[test]
fn weights_carry_their_residual_check() {
    let (m, _) = generate::random(400, false, 6).expect("generates");
    let r = analyze(&m, &GeometricOptions::default()).expect("answers");
    assert!(r.redundant > 0 && !r.redundant_joints.is_empty());
    let note = r.weights_note.expect("a note on approximate weights");
    let shown: f64 = note
        .split("up to ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .expect("the residual in the note");
    assert!(shown > 1e-6 && shown < 1e-3, "{note}");

    let (m, _) = generate::random(1000, false, 2).expect("generates");
    let r = analyze(&m, &GeometricOptions::default()).expect("answers");
    assert!(r.redundant > 0 && !r.redundant_joints.is_empty());
    assert_eq!(r.weights_note, None);

    let (file, text) = crate::examples::find("bennett-rounded-4").expect("bundled");
    let m = crate::format::load(file, text, crate::format::Format::sniff(text)).expect("loads");
    let r = analyze(&m, &GeometricOptions::default()).expect("answers");
    assert!(
        r.redundant > 0,
        "the rounded Bennett linkage is overconstrained"
    );
    assert_eq!(r.weights_note, None);
}

/// No cliffs: an exactly analysed block's floating-point self-stresses (for
/// the joints' weights) run last, on what the rest of the analysis left of the budget.
/// Where they do not fit (work or memory), the analysis still answers: the same report
/// (exact count, motions, clusters) but the joints carrying the exact self-stresses listed
/// without weights (every joint the weights name among them) and a note saying why and
/// which flag gets them. The old code stopped with the limit's error on both budgets. With
/// room, no list (absent from JSON) and the weights as before.
#[test]
fn unweighted_joints_when_the_float_self_stresses_do_not_fit() {
    let (m, _) = generate::random(400, false, 6).expect("generates");
    let opts = GeometricOptions::default();
    let full = analyze(&m, &opts).expect("answers");
    assert!(full.redundant > 0 && !full.redundant_joints.is_empty());
    assert!(full.redundant_joints_unweighted.is_empty());
    let json = serde_json::to_string(&full).expect("serializes");
    assert!(
        !json.contains("redundant_joints_unweighted"),
        "absent when unused"
    );
    let tight = [
        (
            Budget {
                max_work: 100_000_000,
                ..Budget::DEFAULT
            },
            "--max-work",
        ),
        (
            Budget {
                max_memory_bytes: 4_000_000,
                ..Budget::DEFAULT
            },
            "--max-memory",
        ),
    ];
    for (budget, flag) in tight {
        let cut = analyze_within(&m, &opts, &budget).expect("answers without weights");
        assert!(cut.redundant_joints.is_empty());
        let listed: BTreeSet<&str> = cut
            .redundant_joints_unweighted
            .iter()
            .map(|j| j.as_str())
            .collect();
        assert_eq!(listed.len(), cut.redundant_joints_unweighted.len());
        for j in &full.redundant_joints {
            assert!(listed.contains(j.joint.as_str()), "{} not listed", j.joint);
        }
        let note = cut.weights_note.clone().expect("a note");
        assert!(note.contains("were not computed"), "{note}");
        assert!(note.contains(flag), "{note}");
        assert!(note.contains(&format!("{} joints", listed.len())), "{note}");
        let json = serde_json::to_string(&cut).expect("serializes");
        assert!(json.contains("redundant_joints_unweighted"));
        // Everything else is the full report's.
        let mut a = cut.clone();
        a.redundant_joints_unweighted.clear();
        a.redundant_joints = full.redundant_joints.clone();
        a.weights_note = None;
        let mut f = full.clone();
        f.weights_note = None;
        assert_eq!(a, f);
    }
    // Just enough work for the analysis with its weights: the same report.
    let room = Budget {
        max_work: 300_000_000,
        ..Budget::DEFAULT
    };
    assert_eq!(analyze_within(&m, &opts, &room).expect("answers"), full);
}

#[test]
fn exact_path_agrees_on_the_examples() {
    let mut compared = 0;
    for name in crate::examples::names() {
        let Some((file, text)) = crate::examples::find(name) else {
            continue;
        };
        let Ok(m) = crate::format::load(file, text, crate::format::Format::sniff(text)) else {
            continue;
        };
        if m.bodies.len() > 60 {
            continue;
        }
        for seed in [1, 3] {
            let opts = GeometricOptions {
                geometry: GeometrySource::Random { seed },
                ..Default::default()
            };
            compared += exact_path_agrees(&m, &opts);
        }
    }
    assert!(compared >= 40, "{compared} comparisons");
}

#[test]
fn exact_path_agrees_on_random_mechanisms() {
    let mut ms = vec![generate::stewart_stack(2).expect("small")];
    for seed in 0..12 {
        ms.push(generate::assur(1 + seed % 2, 6, seed as u64, Variant::A).expect("small"));
        ms.push(generate::assur_spatial(2, 3, seed as u64, Variant::B).expect("small"));
        ms.push(
            generate::random(40, seed % 2 == 0, seed as u64)
                .expect("small")
                .0,
        );
        ms.push(
            generate::random(120, seed % 2 == 1, seed as u64 + 100)
                .expect("small")
                .0,
        );
    }
    let mut compared = 0;
    for m in &ms {
        compared += exact_path_agrees(m, &GeometricOptions::default());
    }
    // Most cases have reliable floating-point motions (those that do not are a reason
    // for the exact path: the float elimination misses one pivot there).
    assert!(compared >= 80, "{compared} of {} comparisons", 2 * ms.len());
}

/// A body spinning between two coaxial pins (Gepetto's five-bar, its ball end as written)
/// moves like each neighbour, modulo its spin, while the neighbours turn relative to each
/// other: they are two rigid parts, not one through it. Both floating-point paths, at the
/// file's geometry.
#[test]
fn a_spinning_body_does_not_join_its_neighbours_into_one_rigid_part() {
    let text = r#"
name = "five-bar, ball end between coaxial pins"
space = "spatial"
frame = "built"
[[joint]]
id = "mot1"
type = "R"
bodies = ["built", "rod"]
origin = [0, 0.15, 0]
axis = [1, 0, 0]
[[joint]]
id = "free1"
type = "R"
bodies = ["rod", "rod_2"]
origin = [0, 0.15, -0.4]
axis = [1, 0, 0]
[[joint]]
id = "a"
type = "R"
bodies = ["rod_2", "sphere"]
origin = [0, 0, -0.8]
axis = [1, 0, 0]
[[joint]]
id = "b"
type = "R"
bodies = ["end_rod", "sphere"]
origin = [0, 0, -0.8]
axis = [1, 0, 0]
[[joint]]
id = "free2"
type = "R"
bodies = ["rod_3", "end_rod"]
origin = [0, -0.15, -0.4]
axis = [1, 0, 0]
[[joint]]
id = "mot2"
type = "R"
bodies = ["built", "rod_3"]
origin = [0, -0.15, 0]
axis = [1, 0, 0]
"#;
    let m = crate::format::load("five-bar", text, crate::format::Format::Toml).expect("valid");
    let opts = GeometricOptions::default();
    let check = |r: &GeometricReport| {
        assert_eq!((r.mobility, r.isolated), (3, 1), "{r:?}");
        for c in &r.rigid {
            let has = |b: &str| c.bodies.iter().any(|x| x == b);
            assert!(!(has("rod_2") && has("end_rod")), "{:?}", r.rigid);
        }
    };
    check(&analyze(&m, &opts).expect("answers"));
    check(&with_sparse_from(0, || analyze(&m, &opts)).expect("answers"));
}
