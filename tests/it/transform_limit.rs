//! `transform --limit` at scale: the work of a limited run is one
//! analysis of the mechanism, a search whose cost grows with the placements found (not with
//! the candidates times the bodies), and one analysis per placement that reuses what earlier
//! ones factorized. Work units are deterministic: each budget below is one the linear search
//! fits in and the previous one (a full breadth-first search per candidate that takes no
//! unit) overran by two orders of magnitude.

use mbsa::budget::Budget;
use mbsa::generate::{self, Variant};
use mbsa::structure::{self, AnalysisCache, Library, Status};
use mbsa::transform::{TransformError, TransformOptions, transform};
use mbsa::{InputSpec, Mechanism};

fn count_only() -> TransformOptions {
    let mut o = TransformOptions::default();
    o.analysis.count_only = true;
    o
}

/// Planar Assur II linkage of 10^4 bodies, `--count-only --limit 20`: the search walks
/// 15,001 candidate joints for one input. It used to run one breadth-first search over the
/// linkage per candidate that takes no input (about 0.4 s and 10^9 work units per placement);
/// now a body from which no free unit is reachable is skipped until the placement changes.
/// 20 analyses cost 2.5·10^7 units on their own meter; the search fits in 5·10^7 as well.
#[test]
fn limit_20_on_a_planar_assur_linkage_of_10000_bodies_fits_a_small_work_budget() {
    let m = generate::assur(2, 2_500, 364, Variant::A).unwrap();
    assert_eq!(m.bodies.len(), 10_002);
    let o = TransformOptions {
        limit: Some(20),
        budget: Budget {
            max_work: 50_000_000,
            ..Budget::DEFAULT
        },
        ..count_only()
    };
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.count_valid, 20);
    assert_eq!(t.placements.len(), t.summary.determined as usize);
    assert!(t.summary.truncated);
}

/// A random spatial mechanism: thousands of inputs to place (f = 442 at 10^3). The greedy
/// first placement tried every candidate with a full search once it could take no more;
/// bodies whose unknowns are all used are now marked once for the whole pass.
#[test]
fn a_random_mechanism_places_its_first_inputs_in_linear_work() {
    let (m, _) = generate::random(3_000, false, 1).unwrap();
    let o = TransformOptions {
        limit: Some(5),
        budget: Budget {
            max_work: 40_000_000,
            ..Budget::DEFAULT
        },
        ..count_only()
    };
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.count_valid, 5);
    assert!(t.summary.truncated);
}

/// The phase before the search (the analysis that finds isolated freedoms and constraints
/// set aside, and the routing of the joints' equations) is charged to `--max-work`: a budget
/// smaller than one analysis stops there with the typed error, before any placement.
#[test]
fn the_analysis_before_the_search_is_charged() {
    let (m, _) = generate::random(2_000, false, 1).unwrap();
    let o = TransformOptions {
        limit: Some(1),
        budget: Budget {
            max_work: 10_000,
            ..Budget::DEFAULT
        },
        ..TransformOptions::default()
    };
    match transform(&m, &o, &Library::builtin(), None) {
        Err(TransformError::Budget(e)) => {
            assert!(e.to_string().contains("transform search"), "{e}");
            assert!(e.help().contains("--max-work"));
        }
        other => panic!("{:?}", other.map(|t| t.summary)),
    }
}

/// The placements of `m` found with `--limit`, as `--inputs` specs.
fn specs(m: &Mechanism, limit: usize) -> Vec<String> {
    let o = TransformOptions {
        limit: Some(limit),
        ..TransformOptions::default()
    };
    let t = transform(m, &o, &Library::builtin(), None).unwrap();
    assert!(!t.placements.is_empty());
    t.placements.iter().map(|p| p.spec()).collect()
}

/// The rank check's cache and the flow's warm start change nothing: every placement's
/// analysis with one cache shared by all (and a warm start that is no flow at all, or one
/// that overfills every pair) equals the plain analysis.
fn cached_equals_plain(m: &Mechanism, limit: usize) {
    let lib = Library::builtin();
    let opts = structure::Options::default();
    let cache = AnalysisCache::default();
    let n = m.joints.len();
    let mut base = m.clone();
    for j in &mut base.joints {
        j.driven = 0;
    }
    let hints: [Vec<[u8; 2]>; 3] = [vec![[0, 0]; n], vec![[6, 6]; n], vec![[1, 0]; n]];
    for (i, spec) in specs(m, limit).iter().enumerate() {
        let mut pm = base.clone();
        pm.apply_inputs(&InputSpec::parse(spec).unwrap()).unwrap();
        let plain = structure::analyze(&pm, &opts, &lib).unwrap();
        assert_eq!(plain.status, Status::Determined, "{spec}");
        let hint = &hints[i % hints.len()];
        let cached = structure::analyze_cached(&pm, &opts, &lib, Some(&cache), Some(hint)).unwrap();
        assert_eq!(plain, cached, "{spec}");
        // Twice: the second analysis takes every factorization from the cache.
        let again = structure::analyze_cached(&pm, &opts, &lib, Some(&cache), None).unwrap();
        assert_eq!(plain, again, "{spec}");
        // `transform`'s analysis: certified (its inputs' exact rank is full: it is determined)
        // or not, it answers the same.
        for certified in [true, false] {
            let (a, _) =
                structure::analyze_placement(&pm, &opts, &lib, Some(&cache), Some(hint), certified)
                    .unwrap();
            assert_eq!(Some(&plain), a.as_ref(), "{spec} certified {certified}");
        }
    }
}

#[test]
fn cached_analyses_equal_plain_ones_on_a_planar_assur_linkage() {
    cached_equals_plain(&generate::assur(2, 60, 7, Variant::A).unwrap(), 12);
}

#[test]
fn cached_analyses_equal_plain_ones_on_a_spatial_assur_linkage() {
    cached_equals_plain(&generate::assur_spatial(2, 30, 7, Variant::A).unwrap(), 8);
}

#[test]
fn cached_analyses_equal_plain_ones_on_a_random_spatial_mechanism() {
    cached_equals_plain(&generate::random(40, false, 2).unwrap().0, 30);
}

#[test]
fn cached_analyses_equal_plain_ones_on_a_shared_s_joint() {
    // Expanded multiple joints are binary, the file's own multiple joint is not: the warm
    // start skips its pairs.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mbsa"))
        .args([
            "generate", "star", "--bodies", "12", "--joint", "S", "--shared",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let m = mbsa::format::load("hub.toml", &text, mbsa::format::Format::Toml).unwrap();
    let lib = Library::builtin();
    let opts = structure::Options::default();
    let cache = AnalysisCache::default();
    let plain = structure::analyze(&m, &opts, &lib).unwrap();
    let hint = vec![[6u8, 6]; m.joints.len()];
    let cached = structure::analyze_cached(&m, &opts, &lib, Some(&cache), Some(&hint)).unwrap();
    assert_eq!(plain, cached);
}

/// `--limit 100` with the rank check on a planar Assur II linkage of 4,002 bodies: each
/// placement found moves the input down the linkage, and the group above it grows (hundreds
/// of bodies, ill-conditioned loops the sparse screen declines). Their rank was a dense SVD
/// per placement (`n^3` work units: 10^8 to 10^9 each for groups of 300 to 1,000 unknowns);
/// now the exact rank over GF(p) of the inputs on the linkage's one motion certifies each
/// placement before its analysis, which then factorizes nothing new. The work units of the
/// rank decisions are charged to the budget (deterministic): the whole run fits in 10^8.
#[test]
fn limit_100_with_the_rank_check_on_an_assur_linkage_fits_a_small_work_budget() {
    let m = generate::assur(2, 1_000, 364, Variant::A).unwrap();
    assert_eq!(m.bodies.len(), 4_002);
    let o = TransformOptions {
        limit: Some(100),
        budget: Budget {
            max_work: 100_000_000,
            ..Budget::DEFAULT
        },
        ..TransformOptions::default()
    };
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.count_valid, 100);
    assert_eq!(t.placements.len(), 100);
    assert!(t.summary.truncated);
    // The largest group of the placements listed: the growth the old check paid for.
    let largest = t.placements.iter().map(|p| p.scores.largest).max().unwrap();
    assert!(largest >= 300, "largest group {largest}");
}

/// The random families: every count-valid placement the search finds has a group whose
/// rank is deficient (the count and rank matroids differ). The check now stops at the first
/// deficient group the count calls well-determined (before factorizing the giant one exactly,
/// about a second per placement at 10^4 bodies), or at once when the count itself is not
/// determined: the verdicts are the full check's (every placement excluded, as before), and the
/// search stops at the first ones.
#[test]
fn rejected_placements_of_a_random_mechanism_keep_their_verdict() {
    let (m, _) = generate::random(2_000, true, 1).unwrap();
    let o = TransformOptions {
        limit: Some(30),
        ..TransformOptions::default()
    };
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    // Its constraint equations are dependent: every placement is rejected, and the search
    // stops at the first ones rejected, saying why, instead of rejecting 30.
    assert_eq!(t.summary.determined, 0);
    assert!(t.summary.count_valid > 0 && t.summary.count_valid < 30);
    assert_eq!(t.summary.excluded_by_rank, t.summary.count_valid);
    assert!(!t.summary.truncated);
    assert!(
        t.summary
            .notes
            .iter()
            .any(|n| n.starts_with("the constraint equations are dependent")),
        "{:?}",
        t.summary.notes
    );
}

/// `transform` of `m` as the command line runs it, and by the former path (every count-valid
/// placement analysed in full).
fn default_and_full(
    m: &Mechanism,
    limit: Option<usize>,
) -> (mbsa::transform::Transform, mbsa::transform::Transform) {
    let lib = Library::builtin();
    let o = TransformOptions {
        limit,
        ..TransformOptions::default()
    };
    let run = transform(m, &o, &lib, None).unwrap();
    let full = TransformOptions {
        full_analyses: true,
        ..o
    };
    (run, transform(m, &full, &lib, None).unwrap())
}

/// A placement the exact rank certifies is analysed from the search's own flow (its strongly
/// connected components, levels and types), not by a full analysis: the same placements,
/// groups, types, scores, ranks and families as the full analyses give.
fn lean_equals_full(m: &Mechanism, limit: Option<usize>) {
    let (lean, full) = default_and_full(m, limit);
    assert!(!full.placements.is_empty());
    assert_eq!(lean, full);
}

#[test]
fn lean_analyses_equal_full_ones_on_assur_linkages() {
    lean_equals_full(&generate::assur(2, 60, 7, Variant::A).unwrap(), None);
    lean_equals_full(
        &generate::assur(2, 300, 364, Variant::A).unwrap(),
        Some(100),
    );
    lean_equals_full(&generate::assur(3, 20, 5, Variant::B).unwrap(), Some(200));
    lean_equals_full(
        &generate::assur_spatial(2, 30, 7, Variant::A).unwrap(),
        None,
    );
    lean_equals_full(
        &generate::assur_spatial(2, 200, 364, Variant::B).unwrap(),
        Some(100),
    );
}

/// `--limit 100` in work units (deterministic), on two families where each placement used to
/// cost a full analysis of the mechanism (50 units a body or joint, 5·10^5 here, so 100
/// placements at least 5·10^7): a planar Assur II linkage of 4,002 bodies, each placement
/// certified by the exact rank and now analysed from the search's flow (8 units a body or
/// joint), and a random planar mechanism of 3,000 bodies whose constraint equations are
/// dependent, each placement now rejected by one exact rank of the constraints before the
/// search. Both fit 2·10^7 units; the former path (`full_analyses`) overruns it.
#[test]
fn limit_100_fits_a_budget_the_full_analyses_overrun() {
    let assur = generate::assur(2, 1_000, 364, Variant::A).unwrap();
    let (random, _) = generate::random(3_000, true, 1).unwrap();
    let lib = Library::builtin();
    for (m, determined) in [(&assur, 100), (&random, 0)] {
        let o = TransformOptions {
            limit: Some(100),
            budget: Budget {
                max_work: 20_000_000,
                ..Budget::DEFAULT
            },
            ..TransformOptions::default()
        };
        let t = transform(m, &o, &lib, None).unwrap();
        assert_eq!(t.summary.determined, determined, "{}", m.name);
        // The random mechanism's dependent equations stop its search at the first rejected
        // placements.
        let examined = if determined > 0 {
            100
        } else {
            t.summary.count_valid
        };
        assert!(examined > 0 && examined <= 100, "{}", m.name);
        assert_eq!(t.summary.count_valid, examined, "{}", m.name);
        assert_eq!(t.summary.truncated, determined > 0, "{}", m.name);
        let full = TransformOptions {
            full_analyses: true,
            ..o
        };
        match transform(m, &full, &lib, None) {
            Err(TransformError::Budget(e)) => assert!(e.help().contains("--max-work"), "{e}"),
            other => panic!("{}: {:?}", m.name, other.map(|t| t.summary)),
        }
    }
}

/// The cache keeps isolated freedoms' confirmations too: on the hexapod (six rod spins, each
/// confirmed at other draws), analyses of placements determined or not, with one cache shared
/// by all and each twice, equal the plain analyses.
#[test]
fn cached_analyses_equal_plain_ones_with_isolated_rod_spins() {
    let (file, text) = mbsa::examples::find("hexapod-rss").expect("bundled example");
    let m = mbsa::format::load(file, text, mbsa::format::Format::Toml).unwrap();
    let lib = Library::builtin();
    let opts = structure::Options::default();
    let cache = AnalysisCache::default();
    let mut base = m.clone();
    for j in &mut base.joints {
        j.driven = 0;
    }
    let specs = [
        "1-2,1-4,1-6,1-8,1-10,1-12",
        "1-2,1-4,1-6,1-8,1-10,2-3:1",
        "1-2,1-4,1-6,1-8,3-14:2",
        "1-2,1-4,1-6,1-8,1-10,1-12",
        "2-3:1,4-5:1,6-7:1,1-8,1-10,1-12",
    ];
    let mut determined = 0;
    for spec in specs {
        let mut pm = base.clone();
        pm.apply_inputs(&InputSpec::parse(spec).unwrap()).unwrap();
        let plain = structure::analyze(&pm, &opts, &lib).unwrap();
        assert!(!plain.isolated.is_empty(), "{spec}");
        determined += usize::from(plain.status == Status::Determined);
        for _ in 0..2 {
            let cached = structure::analyze_cached(&pm, &opts, &lib, Some(&cache), None).unwrap();
            assert_eq!(plain, cached, "{spec}");
        }
    }
    // The crank placement (twice) is determined, and not every other one is.
    assert!((2..specs.len()).contains(&determined), "{determined}");
}

/// Where the count does not see every motion at the file's geometry (rod spins between ball
/// joints, equations set aside), the search cuts the branches whose inputs drive one motion
/// twice or a spin. The placements it then lists are the ones the former path (every
/// count-valid placement analysed in full) lists, in the same ranks; only the count-valid
/// placements it examines, and excludes, are fewer.
#[test]
fn the_search_cut_at_rod_spins_lists_the_placements_the_full_analyses_list() {
    let lib = Library::builtin();
    let bundled = |name: &str| {
        let (_, text) = mbsa::examples::find(name).expect("bundled");
        mbsa::format::load(name, text, mbsa::format::Format::Toml).expect("reads")
    };
    let delta = {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/import/delta_robot.sdf");
        mbsa::import::import_file(&path, &mbsa::import::ImportOptions::default())
            .expect("imports")
            .mechanism
    };
    let cases = [
        bundled("rig-rssr"),
        bundled("rig-tetrahedron"),
        bundled("rig-planar-four-bar-3d"),
        delta,
    ];
    for m in &cases {
        let name = &m.name;
        let (cut, full) = default_and_full(m, None);
        // The same placements in the same ranks, groups and scores (their numbers in the
        // enumeration differ: the search skips the branches it cuts).
        let key = |t: &mbsa::transform::Transform| -> Vec<String> {
            t.placements
                .iter()
                .map(|p| format!("{:?} {:?} {:?} {:?}", p.rank, p.inputs, p.scores, p.types))
                .collect()
        };
        assert_eq!(key(&cut), key(&full), "{name}");
        assert_eq!(cut.original_rank, full.original_rank, "{name}");
        assert_eq!(cut.summary.determined, full.summary.determined, "{name}");
        assert!(
            cut.summary.excluded_by_rank <= full.summary.excluded_by_rank,
            "{name}"
        );
        assert!(
            cut.summary.count_valid <= full.summary.count_valid,
            "{name}"
        );
    }
    // The Delta robot (base free, six rod spins): 635 count-valid placements, 21 determined;
    // the search now examines 26.
    let t = transform(&cases[3], &TransformOptions::default(), &lib, None).unwrap();
    assert_eq!((t.summary.count_valid, t.summary.determined), (26, 21));
}
