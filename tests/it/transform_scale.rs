//! Transform at scale: independent parts placed one by one,
//! `--limit` bounding the work, `truncated` only when placements were left out, JSON lines
//! streamed from the first placement found. The large mechanisms are generated here.

use mbsa::budget::Budget;
use mbsa::format::{Format, load};
use mbsa::structure::Library;
use mbsa::transform::{
    Placement, Progress, TransformError, TransformOptions, enumerate, transform,
};
use mbsa::{BodyId, JointSpec, JointType, Mechanism, Space};
use std::sync::atomic::{AtomicUsize, Ordering};

fn mech(name: &str, space: Space, joints: Vec<(JointType, i64, i64)>) -> Mechanism {
    Mechanism::from_parts(
        name,
        space,
        BodyId::Int(0),
        vec![],
        joints
            .into_iter()
            .enumerate()
            .map(|(i, (k, a, b))| {
                let mut j = JointSpec::new(k, a, b, 0);
                j.id = Some(format!("J{i}"));
                j
            })
            .collect(),
    )
}

/// A spatial leg on the frame: six R joints in series (bodies base+1..=base+6) and a U-P-S
/// strut from body base+2 to body base+4 (bodies base+7, base+8). Mobility 6.
fn leg(base: i64) -> Vec<(JointType, i64, i64)> {
    use JointType::*;
    let b = |i: i64| base + i;
    vec![
        (R, 0, b(1)),
        (R, b(1), b(2)),
        (R, b(2), b(3)),
        (R, b(3), b(4)),
        (R, b(4), b(5)),
        (R, b(5), b(6)),
        (U, b(2), b(7)),
        (P, b(7), b(8)),
        (S, b(8), b(4)),
    ]
}

/// Planar parallel mechanism: platform 1 on `legs` RRR legs from the frame.
fn parallel(legs: i64) -> Mechanism {
    let mut j = Vec::new();
    for k in 0..legs {
        let (a, b) = (2 + 2 * k, 3 + 2 * k);
        j.extend([
            (JointType::R, 0, a),
            (JointType::R, a, b),
            (JointType::R, b, 1),
        ]);
    }
    mech("parallel", Space::Planar, j)
}

fn count_only() -> TransformOptions {
    let mut o = TransformOptions::default();
    o.analysis.count_only = true;
    o
}

/// What a placement is, independent of its rank among equals.
fn essence(p: &Placement) -> (String, Vec<usize>, Vec<Vec<String>>, Vec<String>) {
    let mut part = p.partition.to_vec();
    part.sort();
    let mut types: Vec<String> = p
        .types
        .iter()
        .map(|t| format!("{}x{}{}", t.count, t.kind, t.in_library))
        .collect();
    types.sort();
    let s = &p.scores;
    (
        p.spec(),
        vec![
            s.groups,
            s.largest,
            s.levels,
            s.covered,
            usize::from(s.all_covered),
        ],
        part,
        types,
    )
}

/// Placing the parts one by one gives exactly the placements, scores, groups and ranking of
/// placing the whole (rank check on): two planar four-bars and a five-bar on one frame.
#[test]
fn parts_combine_to_exactly_the_whole() {
    use JointType::R;
    let mut j = vec![(R, 0, 1), (R, 1, 2), (R, 2, 3), (R, 3, 0)];
    j.extend([(R, 0, 4), (R, 4, 5), (R, 5, 6), (R, 6, 0)]);
    j.extend([(R, 0, 7), (R, 7, 8), (R, 8, 9), (R, 9, 10), (R, 10, 0)]);
    let m = mech("three loops", Space::Planar, j);
    let lib = Library::builtin();
    let split = transform(&m, &TransformOptions::default(), &lib, None).unwrap();
    let whole = transform(
        &m,
        &TransformOptions {
            split: false,
            ..TransformOptions::default()
        },
        &lib,
        None,
    )
    .unwrap();
    assert_eq!(split.summary.parts, 3);
    assert_eq!(whole.summary.parts, 1);
    // 4 × 4 × C(5, 2) placements, every one determined.
    assert_eq!(split.summary.determined, 160);
    assert_eq!(split.summary.determined, whole.summary.determined);
    assert_eq!(split.summary.count_valid, whole.summary.count_valid);
    assert_eq!(split.summary.f, whole.summary.f);
    assert_eq!(split.placements.len(), whole.placements.len());
    let set = |t: &mbsa::transform::Transform| {
        let mut v: Vec<_> = t.placements.iter().map(essence).collect();
        v.sort();
        v
    };
    assert_eq!(set(&split), set(&whole));
    // The same ranking: score sequences in rank order agree, and so do the families.
    let scores = |t: &mbsa::transform::Transform| {
        t.placements
            .iter()
            .map(|p| p.scores.clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(scores(&split), scores(&whole));
    assert_eq!(split.families.len(), whole.families.len());
    // Groups in canonical order (level, size, smallest body) as the whole's analysis lists
    // them: the best placement's partition is identical, not only as a set.
    let best = &split.placements[0];
    let same = whole
        .placements
        .iter()
        .find(|p| p.spec() == best.spec())
        .unwrap();
    assert_eq!(best.partition, same.partition);
    assert_eq!(best.types, same.types);
}

/// A biped of two independent legs (12 inputs) printed nothing in 120 s. Its
/// placements are the pairs of the legs' placements.
#[test]
fn biped_legs_are_placed_independently() {
    let one = mech("leg", Space::Spatial, leg(0));
    let mut both = leg(0);
    both.extend(leg(10));
    let biped = mech("biped", Space::Spatial, both);
    let lib = Library::builtin();
    let l = transform(&one, &count_only(), &lib, None).unwrap();
    let b = transform(&biped, &count_only(), &lib, None).unwrap();
    assert_eq!(l.summary.f, 6);
    assert_eq!(b.summary.f, 12);
    assert_eq!(b.summary.parts, 2);
    assert!(l.summary.determined > 1);
    assert_eq!(b.summary.determined, l.summary.determined.pow(2));
    assert!(!b.summary.truncated);
    // The best biped placement is the best leg placement on both legs.
    let (lb, bb) = (&l.placements[0].scores, &b.placements[0].scores);
    assert_eq!(bb.groups, 2 * lb.groups);
    assert_eq!(bb.largest, lb.largest);
    assert_eq!(bb.levels, lb.levels);
    assert_eq!(
        b.placements[0].inputs.len(),
        2 * l.placements[0].inputs.len()
    );
}

/// `--limit 1 --count-only` on a star of 4,000 R joints ran past 100 s. On the
/// frame (4,000 parts) and on a hub body (one part, every joint forced): one placement,
/// found at once, and the search knows there is no other.
#[test]
fn stars_of_4000_joints_answer_at_once() {
    let on_frame = mech(
        "star on the frame",
        Space::Spatial,
        (1..=4000).map(|b| (JointType::R, 0, b)).collect(),
    );
    let mut hub = vec![(JointType::R, 0, 1)];
    hub.extend((2..=4000).map(|b| (JointType::R, 1, b)));
    let on_hub = mech("star on a hub", Space::Spatial, hub);
    let lib = Library::builtin();
    for (m, parts) in [(on_frame, 4000), (on_hub, 1)] {
        let o = TransformOptions {
            limit: Some(1),
            ..count_only()
        };
        let t = transform(&m, &o, &lib, None).unwrap();
        assert_eq!(t.summary.parts, parts, "{}", m.name);
        assert_eq!(t.summary.f, 4000);
        assert_eq!(t.summary.determined, 1);
        assert!(!t.summary.truncated, "{}", m.name);
        assert_eq!(t.placements[0].inputs.len(), 4000);
    }
}

/// The 40-leg planar parallel mechanism (3.9 KB) ran 101 s and aborted at 3.5 GB.
/// `--limit` now bounds the work: the first placements come at once and `truncated` says
/// more exist.
#[test]
fn limit_bounds_the_work_on_a_40_leg_parallel_mechanism() {
    let m = parallel(40);
    let lib = Library::builtin();
    let o = TransformOptions {
        limit: Some(200),
        ..TransformOptions::default()
    };
    let t = transform(&m, &o, &lib, None).unwrap();
    assert_eq!(t.summary.f, 3);
    assert_eq!(t.summary.count_valid, 200);
    assert!(t.summary.truncated);
    assert!(t.placements.len() <= 200);
    assert!(!t.placements.is_empty());
}

/// All C(120, 3) = 280,840 triples of the 40-leg mechanism's joints are placements (three
/// inputs anywhere fix the platform and every leg, by count); every one analysed, the memory
/// bounded by the listing cap. Seconds in release; minutes in debug.
#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds; run with --release")]
fn every_placement_of_the_40_leg_mechanism_is_counted() {
    let m = parallel(40);
    let t = transform(&m, &count_only(), &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.count_valid, 120 * 119 * 118 / 6);
    assert_eq!(t.summary.determined, t.summary.count_valid);
    assert!(!t.summary.truncated);
    assert!(t.placements.len() < 280_840);
    assert!(t.summary.notes.iter().any(|n| n.contains("are listed")));
}

/// `--limit N` with exactly N placements said `truncated` and "more placements
/// exist". Now only when one more exists.
#[test]
fn limit_equal_to_the_count_is_not_truncated() {
    let m = parallel(2);
    let lib = Library::builtin();
    let all = transform(&m, &count_only(), &lib, None).unwrap();
    let n = all.summary.count_valid as usize;
    assert!(n > 2);
    for (limit, cut) in [(n, false), (n + 1, false), (n - 1, true)] {
        let o = TransformOptions {
            limit: Some(limit),
            ..count_only()
        };
        let t = transform(&m, &o, &lib, None).unwrap();
        assert_eq!(t.summary.truncated, cut, "limit {limit} of {n}");
        assert_eq!(
            t.summary
                .notes
                .iter()
                .any(|x| x.contains("more placements exist")),
            cut
        );
        assert_eq!(t.summary.count_valid as usize, limit.min(n));
    }
}

/// `transform --limit 300 --format jsonl` on a 2,000-body random mechanism streamed
/// nothing for 120 s. The first placement is now analysed and streamed on its own, before the
/// search goes on: progress is reported after each analysed batch, and the first report
/// counts that one placement (the batches then grow), not the 300 the search can find.
#[test]
fn jsonl_streams_from_the_first_placement() {
    let (m, _) = mbsa::generate::random(2000, false, 0).unwrap();
    let lib = Library::builtin();
    let o = TransformOptions {
        limit: Some(300),
        ..count_only()
    };
    let first_batch = AtomicUsize::new(0);
    let report = |p: Progress| {
        let _ = first_batch.compare_exchange(0, p.examined, Ordering::Relaxed, Ordering::Relaxed);
    };
    let mut n = 0usize;
    let s = enumerate(&m, &o, &lib, Some(&report), &mut |_| {
        n += 1;
        // One is enough to show it streams; the rest is the same loop.
        assert!(n <= 300);
    })
    .unwrap();
    assert!(n > 0, "a placement streams");
    assert_eq!(first_batch.into_inner(), 1, "placements in the first batch");
    assert!(s.truncated);
    assert_eq!(s.count_valid, 300);
}

/// The work budget bounds the search: past it, a typed error naming the limit.
#[test]
fn the_search_stops_at_the_work_budget() {
    let m = parallel(40);
    let o = TransformOptions {
        budget: Budget {
            max_work: 10_000,
            ..Budget::DEFAULT
        },
        ..count_only()
    };
    match transform(&m, &o, &Library::builtin(), None) {
        Err(TransformError::Budget(e)) => {
            assert!(e.to_string().contains("work limit"), "{e}");
            assert!(e.help().contains("--max-work"));
        }
        other => panic!("{:?}", other.map(|t| t.summary)),
    }
}

/// Counts of many parts multiply; too large to hold, they are said in words.
#[test]
fn a_product_too_large_to_hold_is_said_in_words() {
    // 70 planar four-bars on one frame: 4^70 placements, more than 2^128.
    let mut j = Vec::new();
    for k in 0..70 {
        let b = 1 + 3 * k;
        j.extend([
            (JointType::R, 0, b),
            (JointType::R, b, b + 1),
            (JointType::R, b + 1, b + 2),
            (JointType::R, b + 2, 0),
        ]);
    }
    let m = mech("70 four-bars", Space::Planar, j);
    let o = TransformOptions {
        top: 3,
        ..count_only()
    };
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.parts, 70);
    assert_eq!(t.summary.determined, u128::MAX);
    let text = mbsa::report::transform::table(&t, 3);
    assert!(text.contains("more than 10^38"), "{text}");
    assert!(!text.contains(&u128::MAX.to_string()));
    let json = mbsa::report::json(&t);
    assert!(
        json.contains("\"determined\": \"more than 10^38\""),
        "{json:.400}"
    );
    // 30 four-bars: 4^30 exactly.
    let small = mech(
        "30 four-bars",
        Space::Planar,
        m.joints
            .iter()
            .take(120)
            .map(|jt| {
                let id = |i: usize| match &m.bodies[i].id {
                    BodyId::Int(n) => *n,
                    _ => 0,
                };
                (jt.kind, id(jt.bodies[0]), id(jt.bodies[1]))
            })
            .collect(),
    );
    let t = transform(&small, &o, &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.determined, 4u128.pow(30));
}

/// A bundled example keeps its answer through the new search (the rotor: 1,031 placements,
/// equal to brute force in transform_rotor.rs) and its file's placement is found.
#[test]
fn bundled_examples_keep_their_counts() {
    let (file, text) = mbsa::examples::find("rotor").unwrap();
    let m = load(file, text, Format::Toml).unwrap();
    let t = transform(&m, &count_only(), &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.parts, 1);
    assert!(!t.summary.truncated);
    assert_eq!(t.placements.len() as u128, t.summary.determined);
    assert!(t.original_rank.is_some());
}

/// A serial chain of 20,000 R joints: every unit is needed by every placement (the matroid's
/// coloops), fixed by one search before the enumeration: one placement, no backtracking.
#[test]
fn a_serial_chain_of_20000_joints_is_decided_in_linear_time() {
    let m = mech(
        "chain",
        Space::Spatial,
        (0..20_000).map(|b| (JointType::R, b, b + 1)).collect(),
    );
    let o = TransformOptions {
        limit: Some(1),
        ..count_only()
    };
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.determined, 1);
    assert!(!t.summary.truncated);
}
