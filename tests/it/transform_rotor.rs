//! Structural transformations of the helicopter rotor control (paper Figs. 12-14).

use mbsa::format::{Format, load};
use mbsa::structure::{self, Library, Status};
use mbsa::transform::{Criterion, TransformOptions, transform};
use mbsa::{InputSpec, Mechanism};
use rayon::prelude::*;

fn example(name: &str) -> Mechanism {
    let (file, text) = mbsa::examples::find(name).expect("bundled example");
    load(file, text, Format::Toml).expect("bundled example loads")
}

fn spec_set(p: &mbsa::transform::Placement) -> Vec<String> {
    let mut v: Vec<String> = p
        .inputs
        .iter()
        .map(|i| format!("{}:{}", i.pair, i.driven))
        .collect();
    v.sort();
    v
}

#[test]
fn paper_second_input_set_is_found_and_ranks_first() {
    let m = example("rotor");
    let lib = Library::builtin();
    let t = transform(&m, &TransformOptions::default(), &lib, None).unwrap();
    assert_eq!(t.summary.f, 3);
    let set2 = t
        .placements
        .iter()
        .find(|p| spec_set(p) == ["1-13:1", "1-2:1", "13-15:1"])
        .expect("the paper's second input set is a determined placement");
    assert_eq!(set2.scores.groups, 9);
    assert!(set2.scores.all_covered);
    assert_eq!(set2.scores.levels, 6);
    // No placement beats it on groups, then library.
    let crit = [Criterion::Groups, Criterion::Library];
    for p in &t.placements {
        assert_ne!(
            mbsa::transform::compare_scores(&p.scores, &set2.scores, &crit),
            std::cmp::Ordering::Less,
            "{} beats the paper's set 2",
            p.spec()
        );
    }
    // The file's own inputs (set 1) are among the determined placements.
    assert!(t.original_rank.is_some());
    let top = t.placements.first().unwrap();
    assert_eq!(top.scores.groups, 9);
    assert!(top.scores.all_covered);
}

/// Every w vector with Σw = f and w_j ≤ k_j, in lexicographic order.
fn all_vectors(grades: &[u32], f: u32) -> Vec<Vec<u32>> {
    fn rec(g: &[u32], left: u32, cur: &mut Vec<u32>, out: &mut Vec<Vec<u32>>) {
        if cur.len() == g.len() {
            if left == 0 {
                out.push(cur.clone());
            }
            return;
        }
        let rest: u32 = g[cur.len() + 1..].iter().sum();
        for w in 0..=g[cur.len()].min(left) {
            if left - w > rest {
                continue;
            }
            cur.push(w);
            rec(g, left - w, cur, out);
            cur.pop();
        }
    }
    let mut out = Vec::new();
    rec(grades, f, &mut Vec::new(), &mut out);
    out
}

#[test]
fn determined_count_equals_brute_force() {
    let m = example("rotor");
    let lib = Library::builtin();
    let t = transform(&m, &TransformOptions::default(), &lib, None).unwrap();
    let grades: Vec<u32> = m.joints.iter().map(|j| j.grade()).collect();
    let opts = structure::Options::default();
    let count_opts = structure::Options {
        count_only: true,
        ..opts
    };
    // Each vector analysed twice (count only, and in full), in parallel.
    let results: Vec<(bool, Option<Vec<String>>)> = all_vectors(&grades, 3)
        .par_iter()
        .map(|w| {
            let mut mm = m.clone();
            for (j, &x) in mm.joints.iter_mut().zip(w) {
                j.driven = x;
            }
            let count =
                structure::analyze(&mm, &count_opts, &lib).unwrap().status == Status::Determined;
            let full = (structure::analyze(&mm, &opts, &lib).unwrap().status == Status::Determined)
                .then(|| {
                    let mut v: Vec<String> = mm
                        .joints
                        .iter()
                        .filter(|j| j.driven > 0)
                        .map(|j| format!("{}:{}", j.id, j.driven))
                        .collect();
                    v.sort();
                    v
                });
            (count, full)
        })
        .collect();
    let count_valid = results.iter().filter(|r| r.0).count();
    let mut brute: Vec<Vec<String>> = results.into_iter().filter_map(|r| r.1).collect();
    brute.sort();
    let mut found: Vec<Vec<String>> = t.placements.iter().map(spec_set).collect();
    found.sort();
    assert_eq!(t.summary.determined, brute.len() as u128);
    assert_eq!(found, brute);
    assert_eq!(t.summary.count_valid, count_valid as u128);
    assert_eq!(
        t.summary.excluded_by_rank,
        t.summary.count_valid - t.summary.determined
    );
}

#[test]
fn inputs_comparison_shows_what_changed() {
    let m = example("rotor");
    let lib = Library::builtin();
    let spec = InputSpec::parse("1-2,1-13,13-15").unwrap();
    let c = mbsa::transform::compare(&m, &spec, &TransformOptions::default(), &lib).unwrap();
    assert_eq!(c.file.scores.groups, 7);
    assert_eq!(c.given.scores.groups, 9);
    assert_eq!(c.changes.groups, 2);
    assert_eq!(c.changes.levels, 1);
    assert_eq!(c.changes.covered, 9 - 5);
    assert_eq!(c.changes.verdict, "better");
    let text = mbsa::report::transform::comparison(&c);
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!("transform_rotor_compare", text);
    });
}

#[test]
fn top_table_snapshot() {
    let m = example("rotor");
    let t = transform(&m, &TransformOptions::default(), &Library::builtin(), None).unwrap();
    let text = mbsa::report::transform::table(&t, 10);
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!("transform_rotor_top", text);
    });
}
