//! Scale measurements of the position solve (docs/benchmarks.md, "Position level"):
//! `cargo run --release --example position_scale -- FAMILY BODIES METHOD [MAX_MEMORY_MB]`.
//!
//! Families (every one with a seeded random joint geometry, `with_random_geometry(m, 3)`):
//! - `planar`: the planar Assur linkage `assur(1, (BODIES − 2)/2, 1, A)`;
//! - `spatial`: its spatial twin `assur_spatial(1, (BODIES − 2)/2, 1, A)`;
//! - `ladder`: the planar parallelogram ladder of the benches (crank +10°, file geometry);
//! - `strip`: the strip of RRR dyads of scripts/cliffs.py, each pinned to the two bodies of the
//!   one before (crank +1°, file geometry: a long chain of loops whose Jacobian's conditioning
//!   grows with its length).
//!
//! The Assur workload: every moving body started at a random twist of size 1e-5 (model units)
//! from the file's configuration, the crank at 0: both solvers must bring every body back
//! (the reference is the solution; random dyads near a fold make a turned crank unreachable
//! at 10^3 bodies and more, docs/benchmarks.md). METHOD: `groups`, `global` or `both` (then
//! the largest pose difference is printed). Prints one line: the times of the schedule and of
//! the solves, the factor's size for the global solve, and the largest residual. Run it under
//! `/usr/bin/time -v` for the peak memory. `MARGIN=c` (Assur families): the random geometry
//! is drawn again group by group until every group's Jacobian at the reference has a
//! conditioning of at least `c` (`with_random_geometry_away_from_folds`), so that no dyad
//! sits near a fold.

use mbsa::budget::Budget;
use mbsa::generate::{self, Variant};
use mbsa::mechanism::Mechanism;
use mbsa::position::inputs::{Value, targets};
use mbsa::position::sparse::Sparse;
use mbsa::position::{
    Configuration, NewtonOptions, PositionModel, System, schedule, solve_global, solve_groups,
    with_random_geometry, with_random_geometry_away_from_folds,
};
use mbsa::rng::SplitMix64;
use mbsa::structure::{self, Library};
use std::time::Instant;

fn ladder(bodies: u64) -> Mechanism {
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
        joints.push(r(
            [2.0 * i as f64, 0.0, 0.0],
            1,
            rocker(i),
            u32::from(i == 0),
        ));
    }
    for i in 0..w {
        let x = 2.0 * i as f64;
        joints.push(r([x, 1.0, 0.0], rocker(i), coupler(i), 0));
        joints.push(r([x + 2.0, 1.0, 0.0], coupler(i), rocker(i + 1), 0));
    }
    Mechanism::from_parts("ladder", Space::Planar, BodyId::Int(1), vec![], joints)
}

fn strip(bodies: u64) -> Mechanism {
    let mut t = String::from("space = \"planar\"\nframe = 1\n");
    let mut joint = |id: String, a: u64, b: u64, x: f64, y: f64, driven: u32| {
        t += &format!(
            "[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, {y}]\ndriven = {driven}\n"
        );
    };
    joint("A0".into(), 1, 2, 0.0, 0.5, 1);
    for k in 1..=(bodies - 2) / 2 {
        let (a, b) = (2 * k + 1, 2 * k + 2);
        let x = k as f64;
        joint(
            format!("T{k}"),
            if k == 1 { 2 } else { a - 2 },
            a,
            x,
            1.0,
            0,
        );
        joint(format!("C{k}"), a, b, x + 0.5, 0.5, 0);
        joint(
            format!("B{k}"),
            if k == 1 { 1 } else { b - 2 },
            b,
            x,
            0.0,
            0,
        );
    }
    mbsa::format::load("strip", &t, mbsa::format::Format::Toml).expect("a strip")
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let family = args.first().map(String::as_str).unwrap_or("planar");
    let bodies: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let method = args.get(2).map(String::as_str).unwrap_or("both");
    let max_mb: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(2500);
    let g = (bodies - 2) / 2;
    let margin: Option<f64> = std::env::var("MARGIN").ok().and_then(|s| s.parse().ok());
    let (m, degrees, perturb) = match family {
        "planar" => (
            with_random_geometry(&generate::assur(1, g, 1, Variant::A).expect("valid"), 3),
            0.0,
            1e-5,
        ),
        "spatial" => (
            with_random_geometry(
                &generate::assur_spatial(1, g, 1, Variant::A).expect("valid"),
                3,
            ),
            0.0,
            1e-5,
        ),
        "strip" => (strip(bodies), 1.0, 0.0),
        _ => (ladder(bodies), 10.0, 0.0),
    };
    let t = Instant::now();
    let model = PositionModel::new(&m).expect("a model");
    let a = structure::analyze(&m, &structure::Options::default(), &Library::builtin())
        .expect("structure");
    let sched = schedule(&m, &a, &model);
    let t_sched = t.elapsed().as_secs_f64();
    // MARGIN=c (Assur families): every group's joints drawn again until its Jacobian at the
    // reference has a conditioning of at least c (no dyad near a fold); the groups are the
    // topology's, so the analysis is kept.
    let mut redraw_note = String::new();
    let (m, model, sched) = match margin {
        Some(c) if family != "ladder" => {
            let t = Instant::now();
            let (m2, r) =
                with_random_geometry_away_from_folds(&m, 3, &sched, c, 50).expect("a model");
            let model2 = PositionModel::new(&m2).expect("a model");
            let sched2 = schedule(&m2, &a, &model2);
            redraw_note = format!(
                " redraw={:.3}s margin={c:e} redrawn_steps={} draws={} below={} worst={:.1e}",
                t.elapsed().as_secs_f64(),
                r.steps,
                r.draws,
                r.below,
                r.worst
            );
            (m2, model2, sched2)
        }
        _ => (m, model, sched),
    };
    let driven = (0..m.joints.len())
        .find(|&j| m.joints[j].driven > 0)
        .expect("driven");
    let value = Value {
        number: degrees,
        radians: None,
    };
    let tg = targets(&m, &model, &[(driven, vec![value])]).expect("value");
    let mut start = Configuration::reference(m.bodies.len());
    let mut rng = SplitMix64::new(11);
    let b = model.b();
    for (i, p) in start.poses.iter_mut().enumerate() {
        if i != m.frame {
            let tw: Vec<f64> = (0..b).map(|_| perturb * rng.next_signed()).collect();
            *p = p.moved_by(m.space, &tw);
        }
    }
    let tolerance: f64 = std::env::var("TOL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e-11);
    let opts = NewtonOptions {
        tolerance,
        budget: Budget {
            max_memory_bytes: max_mb * 1024 * 1024,
            ..Budget::DEFAULT
        },
        ..NewtonOptions::default()
    };
    let start_ref = Configuration::reference(m.bodies.len());
    let mut line = format!(
        "{family} bodies={} pairs={} steps={} schedule={t_sched:.3}s{redraw_note}",
        m.bodies.len(),
        model.pairs.len(),
        sched.steps.len()
    );
    let mut groups = None;
    if method != "global" {
        let t = Instant::now();
        let s = solve_groups(&m, &model, &sched, &tg, &start, &opts);
        let dt = t.elapsed().as_secs_f64();
        match s {
            Ok(s) => {
                line += &format!(" groups={dt:.4}s residual={:.1e}", s.max_residual);
                groups = Some(s);
            }
            Err(e) => line += &format!(" groups=FAILED({e})"),
        }
    }
    if method != "groups" {
        let sys = System {
            pairs: (0..model.pairs.len()).collect(),
            bodies: (0..m.bodies.len()).filter(|&x| x != m.frame).collect(),
        };
        let t = Instant::now();
        let mut meter = opts.budget.meter("ordering");
        match Sparse::new(&sys, &model, &tg, &opts, &mut meter) {
            Ok(sp) => {
                let s = sp.symbolic();
                line += &format!(
                    " order={:.3}s factor_blocks={} factor_mb={:.1}",
                    t.elapsed().as_secs_f64(),
                    s.off_blocks(),
                    s.factor_bytes() as f64 / 1048576.0
                );
            }
            Err(e) => line += &format!(" order=FAILED({e})"),
        }
        let t = Instant::now();
        let s = solve_global(&m, &model, &tg, &start, &opts);
        let dt = t.elapsed().as_secs_f64();
        match s {
            Ok(s) => {
                line += &format!(
                    " global={dt:.4}s iterations={} residual={:.1e}",
                    s.steps[0].iterations, s.max_residual
                );
                if let Some(gs) = &groups {
                    let d = gs
                        .config
                        .poses
                        .iter()
                        .zip(&s.config.poses)
                        .map(|(p, q)| {
                            (p.rotation - q.rotation)
                                .norm()
                                .max((p.translation - q.translation).norm())
                        })
                        .fold(0.0f64, f64::max);
                    line += &format!(" max_pose_difference={d:.1e}");
                    if perturb > 0.0 {
                        let off = |c: &Configuration| {
                            c.poses
                                .iter()
                                .zip(&start_ref.poses)
                                .map(|(p, q)| {
                                    (p.rotation - q.rotation)
                                        .norm()
                                        .max((p.translation - q.translation).norm())
                                })
                                .fold(0.0f64, f64::max)
                        };
                        line += &format!(
                            " off_reference: groups={:.1e} global={:.1e}",
                            off(&gs.config),
                            off(&s.config)
                        );
                    }
                }
            }
            Err(e) => line += &format!(" global=FAILED({e})"),
        }
    }
    println!("{line}");
}
