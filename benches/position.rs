//! Benchmarks of the position level (divan): `cargo bench --bench position`.
//!
//! - `groups` / `global`: solving, group by group (the structural analysis's schedule, made
//!   outside the timed closure) and all at once (the sparse global Gauss–Newton, the
//!   reference), a planar ladder of parallelograms (N-four-bar at a regular pose, 2 + 2w
//!   bodies, its crank turned 10 degrees: w dyads on w levels) and the planar and spatial
//!   Assur families at a seeded random geometry: crank turned 1e-4 degree (100 bodies: random
//!   dyads meet folds, and larger random linkages have a group out of reach even then), and
//!   `*_return`: every body started 1e-5 (model units) off the file's configuration, crank at
//!   0, solved back (any size). Larger sizes: `examples/position_scale.rs`.
//! - `sweep_step`: one step of a sweep of the bundled slider-crank with geometry and of a
//!   10^3-body Assur linkage.
//!
//! See docs/benchmarks.md for the results.

use divan::{Bencher, black_box};
use mbsa::generate::{self, Variant};
use mbsa::mechanism::Mechanism;
use mbsa::position::inputs::{Value, targets};
use mbsa::position::{
    Configuration, NewtonOptions, PositionModel, Schedule, Targets, schedule, solve_global,
    solve_groups, with_random_geometry,
};
use mbsa::structure::{self, Library};

fn main() {
    divan::main();
}

struct Case {
    m: Mechanism,
    model: PositionModel,
    sched: Schedule,
    targets: Targets,
    start: Configuration,
}

fn case(m: Mechanism, degrees: f64) -> Case {
    let model = PositionModel::new(&m).expect("random geometry has a model");
    let a = structure::analyze(&m, &structure::Options::default(), &Library::builtin())
        .expect("the structure of a mechanism with geometry");
    let sched = schedule(&m, &a, &model);
    let driven = (0..m.joints.len())
        .find(|&j| m.joints[j].driven > 0)
        .expect("the crank is driven");
    let value = Value {
        number: degrees,
        radians: None,
    };
    let targets = targets(&m, &model, &[(driven, vec![value])]).expect("valid value");
    let start = Configuration::reference(m.bodies.len());
    Case {
        m,
        model,
        sched,
        targets,
        start,
    }
}

fn planar(bodies: u64) -> Case {
    let g = (bodies - 2) / 2;
    let m = generate::assur(1, g, 1, Variant::A).expect("valid parameters");
    case(with_random_geometry(&m, 3), 1e-4)
}

fn spatial(bodies: u64) -> Case {
    let g = (bodies - 2) / 2;
    let m = generate::assur_spatial(1, g, 1, Variant::A).expect("valid parameters");
    case(with_random_geometry(&m, 3), 1e-4)
}

/// Every moving body started at a seeded random twist of size 1e-5 from the file's
/// configuration, the crank at 0: the solve brings them back.
fn perturbed(mut c: Case) -> Case {
    let mut rng = mbsa::rng::SplitMix64::new(11);
    let b = c.model.b();
    c.targets = targets(&c.m, &c.model, &[]).expect("no values");
    for (i, p) in c.start.poses.iter_mut().enumerate() {
        if i != c.m.frame {
            let tw: Vec<f64> = (0..b).map(|_| 1e-5 * rng.next_signed()).collect();
            *p = p.moved_by(c.m.space, &tw);
        }
    }
    c
}

/// Parallelogram ladder: rockers of length 1 pivoted at (2i, 0) on the frame, standing up,
/// couplers joining the tips; rocker 0 driven.
fn ladder(bodies: u64) -> Case {
    use mbsa::JointType;
    use mbsa::mechanism::{BodyId, Geometry, JointSpec, Space};
    let w = (bodies - 2) / 2;
    let r = |at: [f64; 3], a: i64, b: i64, driven: u32| JointSpec {
        id: None,
        kind: JointType::R,
        bodies: vec![BodyId::Int(a), BodyId::Int(b)],
        driven,
        geometry: Geometry {
            origin: Some(at),
            ..Geometry::default()
        },
    };
    let rocker = |i: u64| 2 + 2 * i as i64;
    let coupler = |i: u64| 3 + 2 * i as i64;
    let mut joints = Vec::new();
    for i in 0..=w {
        let x = 2.0 * i as f64;
        joints.push(r([x, 0.0, 0.0], 1, rocker(i), u32::from(i == 0)));
    }
    for i in 0..w {
        let x = 2.0 * i as f64;
        joints.push(r([x, 1.0, 0.0], rocker(i), coupler(i), 0));
        joints.push(r([x + 2.0, 1.0, 0.0], coupler(i), rocker(i + 1), 0));
    }
    let m = Mechanism::from_parts("ladder", Space::Planar, BodyId::Int(1), vec![], joints);
    case(m, 10.0)
}

#[divan::bench_group(sample_count = 5)]
mod groups {
    use super::*;

    fn run(bencher: Bencher, c: Case) {
        let opts = NewtonOptions::default();
        bencher.bench_local(|| {
            solve_groups(
                &c.m,
                &c.model,
                &c.sched,
                &c.targets,
                black_box(&c.start),
                &opts,
            )
            .expect("solves")
        });
    }

    #[divan::bench(args = [100, 1000, 10000])]
    fn planar_ladder(bencher: Bencher, n: u64) {
        run(bencher, ladder(n));
    }

    #[divan::bench(args = [100])]
    fn planar_assur(bencher: Bencher, n: u64) {
        run(bencher, planar(n));
    }

    #[divan::bench(args = [100])]
    fn spatial_assur(bencher: Bencher, n: u64) {
        run(bencher, spatial(n));
    }

    #[divan::bench(args = [100, 1000])]
    fn planar_assur_return(bencher: Bencher, n: u64) {
        run(bencher, perturbed(planar(n)));
    }

    #[divan::bench(args = [100, 1000])]
    fn spatial_assur_return(bencher: Bencher, n: u64) {
        run(bencher, perturbed(spatial(n)));
    }
}

#[divan::bench_group(sample_count = 3)]
mod global {
    use super::*;

    fn run(bencher: Bencher, c: Case) {
        let opts = NewtonOptions::default();
        bencher.bench_local(|| {
            solve_global(&c.m, &c.model, &c.targets, black_box(&c.start), &opts).expect("solves")
        });
    }

    #[divan::bench(args = [100, 1000, 10000])]
    fn planar_ladder(bencher: Bencher, n: u64) {
        run(bencher, ladder(n));
    }

    #[divan::bench(args = [100])]
    fn planar_assur(bencher: Bencher, n: u64) {
        run(bencher, planar(n));
    }

    #[divan::bench(args = [100])]
    fn spatial_assur(bencher: Bencher, n: u64) {
        run(bencher, spatial(n));
    }

    #[divan::bench(args = [100, 1000])]
    fn planar_assur_return(bencher: Bencher, n: u64) {
        run(bencher, perturbed(planar(n)));
    }

    #[divan::bench(args = [100, 1000])]
    fn spatial_assur_return(bencher: Bencher, n: u64) {
        run(bencher, perturbed(spatial(n)));
    }
}

#[divan::bench_group(sample_count = 20)]
mod sweep_step {
    use super::*;

    #[divan::bench]
    fn slider_crank(bencher: Bencher) {
        let (file, text) = mbsa::examples::find("slider-crank-geometry").expect("bundled");
        let m = mbsa::format::load(file, text, mbsa::format::Format::Toml).expect("loads");
        let c = case(m, 10.0);
        let opts = NewtonOptions::default();
        bencher.bench_local(|| {
            solve_groups(
                &c.m,
                &c.model,
                &c.sched,
                &c.targets,
                black_box(&c.start),
                &opts,
            )
            .expect("solves")
        });
    }

    #[divan::bench]
    fn planar_ladder_1000(bencher: Bencher) {
        let c = ladder(1000);
        let opts = NewtonOptions::default();
        bencher.bench_local(|| {
            solve_groups(
                &c.m,
                &c.model,
                &c.sched,
                &c.targets,
                black_box(&c.start),
                &opts,
            )
            .expect("solves")
        });
    }
}
