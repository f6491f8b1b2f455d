//! A verdict of the rank check must not depend on the random realization (`--seed`): a generic
//! rank is the largest over realizations, so a deficit is real only if it persists at another
//! draw. Before this rule, 13 of the 480 small random mechanisms below got a verdict
//! that changed with `--seed` (a redundant equation or an isolated DOF at some draws).

use mbsa::geometry::GeometrySource;
use mbsa::structure::{Analysis, Library, Options, Status, analyze};

/// What a verdict is made of: the status, the isolated DOF and redundant equations in total,
/// and which bodies are isolated.
fn verdict(a: &Analysis) -> (Status, u32, u32, Vec<String>) {
    let mut bodies: Vec<String> = a.isolated.iter().map(|i| i.body.clone()).collect();
    bodies.sort();
    (
        a.status,
        a.isolated.iter().map(|i| i.dimension).sum(),
        a.redundant.iter().map(|r| r.count).sum(),
        bodies,
    )
}

fn at_seed(m: &mbsa::mechanism::Mechanism, seed: u64) -> Analysis {
    let opts = Options {
        geometry: GeometrySource::Random { seed },
        ..Options::default()
    };
    analyze(m, &opts, &Library::empty()).expect("a generated mechanism is analysed")
}

/// A planar random mechanism of 4 bodies (generator seed 20): its group {2, 3} (two P joints
/// and an EO joint with one driven DOF) was reported with a redundant equation and a freedom
/// no input controls at `--seed` 1, 2, 4 and 5, and determined at 0, 3, 6 and 7 (the input's
/// direction in the synthetic contact model is a pure translation at some draws).
#[test]
fn planar_four_bodies_is_determined_at_every_seed() {
    let (m, _) = mbsa::generate::random(4, true, 20).expect("valid parameters");
    for seed in 0..8 {
        let a = at_seed(&m, seed);
        assert_eq!(
            verdict(&a),
            (Status::Determined, 0, 0, Vec::new()),
            "--seed {seed}"
        );
    }
}

/// Small random mechanisms (planar and spatial, 4 to 16 bodies, 40 generator seeds each),
/// each analysed at 8 seeds: one verdict.
#[test]
fn verdicts_of_small_random_mechanisms_do_not_depend_on_the_seed() {
    let mut differ = Vec::new();
    for planar in [false, true] {
        for bodies in [4, 6, 8, 10, 12, 16] {
            for g in 0..40 {
                let (m, _) = mbsa::generate::random(bodies, planar, g).expect("valid parameters");
                let first = verdict(&at_seed(&m, 0));
                for seed in 1..8 {
                    let v = verdict(&at_seed(&m, seed));
                    if v != first {
                        differ.push(format!(
                            "planar {planar}, {bodies} bodies, generator seed {g}: \
                             --seed 0 {first:?}, --seed {seed} {v:?}"
                        ));
                        break;
                    }
                }
            }
        }
    }
    assert!(differ.is_empty(), "{}", differ.join("\n"));
}
