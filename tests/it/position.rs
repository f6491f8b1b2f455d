//! The position level: joint Jacobians against finite differences and the motion model,
//! sweeps against closed forms, group-by-group against global Newton, closure and assembly,
//! finite mobility.

use mbsa::JointType;
use mbsa::mechanism::{BodyId, Geometry, JointSpec, Mechanism, Space};
use mbsa::motion::{joint_model, perpendicular_pair};
use mbsa::position::inputs::{Value, targets};
use mbsa::position::*;
use mbsa::rng::SplitMix64;
use mbsa::structure::{self, Library};
use nalgebra::{DMatrix, Vector3};

fn rv(r: &mut SplitMix64) -> [f64; 3] {
    [r.next_signed(), r.next_signed(), r.next_signed()]
}

fn unit(r: &mut SplitMix64) -> [f64; 3] {
    let v = Vector3::from(rv(r)).normalize();
    [v.x, v.y, v.z]
}

fn geometry(kind: JointType, space: Space, r: &mut SplitMix64) -> Geometry {
    let mut g = Geometry {
        origin: Some(rv(r)),
        axis: Some(unit(r)),
        axis2: Some(unit(r)),
        normal: Some(unit(r)),
        pitch: Some(0.3),
        origin2: Some(rv(r)),
        ..Geometry::default()
    };
    if matches!(kind, JointType::PC | JointType::CR) {
        // normal perpendicular to axis
        let a = Vector3::from(g.axis.unwrap());
        let (e1, _) = perpendicular_pair(&a);
        g.normal = Some([e1.x, e1.y, e1.z]);
    }
    match space {
        Space::Planar => {
            let o = g.origin.unwrap();
            g.origin = Some([o[0], o[1], 0.0]);
            let a = g.axis.unwrap();
            g.axis = Some([a[0], a[1], 0.0]);
        }
        Space::Spherical => g.origin = Some([0.0; 3]),
        Space::Spatial => {}
    }
    g
}

fn one_joint(kind: JointType, space: Space, g: Geometry, driven: u32) -> Mechanism {
    Mechanism::from_parts(
        "j",
        space,
        BodyId::Int(1),
        vec![],
        vec![JointSpec {
            id: Some("J".into()),
            kind,
            bodies: vec![BodyId::Int(1), BodyId::Int(2)],
            driven,
            geometry: g,
        }],
    )
}

fn kinds(space: Space) -> Vec<JointType> {
    use JointType::*;
    match space {
        Space::Spatial => vec![R, P, H, C, U, S, PL, FP, F, ER, SP, SPSP, SC, PC, CR],
        Space::Planar => vec![R, P, FP],
        Space::Spherical => vec![R, FP],
    }
}

/// Kinds whose driven values are exact functions with exact derivatives.
fn exact_values(kind: JointType, space: Space) -> bool {
    use JointType::*;
    match space {
        Space::Spherical => kind == R,
        _ => {
            matches!(kind, R | P | H | C | U | PL | CR | PC)
                || (kind == FP && space == Space::Planar)
        }
    }
}

fn random_pose(space: Space, r: &mut SplitMix64, size: f64) -> Pose {
    let b = space.b() as usize;
    let t: Vec<f64> = (0..b).map(|_| r.next_signed() * size).collect();
    Pose::identity().moved_by(space, &t)
}

#[test]
fn jacobians_match_finite_differences() {
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        let b = space.b() as usize;
        for kind in kinds(space) {
            let mut r = SplitMix64::new(kind as u64 * 7 + b as u64);
            let g = geometry(kind, space, &mut r);
            let driven = if exact_values(kind, space) {
                kind.grade() as u32
            } else {
                0
            };
            let m = one_joint(kind, space, g, driven.min(space.b()));
            let model = PositionModel::new(&m).unwrap();
            let pa = random_pose(space, &mut r, 0.3);
            let pb = random_pose(space, &mut r, 0.3);
            let tg: Vec<f64> = (0..model.pairs[0].driven).map(|i| 0.1 * i as f64).collect();
            let e = model.pair_equations(0, &pa, &pb, &tg);
            let h = 1e-6;
            for side in 0..2 {
                for k in 0..b {
                    let mut t = vec![0.0; b];
                    t[k] = h;
                    let mut tm = vec![0.0; b];
                    tm[k] = -h;
                    let (ap, am, bp, bm) = if side == 0 {
                        (pa.moved_by(space, &t), pa.moved_by(space, &tm), pb, pb)
                    } else {
                        (pa, pa, pb.moved_by(space, &t), pb.moved_by(space, &tm))
                    };
                    let ep = model.pair_equations(0, &ap, &bp, &tg);
                    let em = model.pair_equations(0, &am, &bm, &tg);
                    for i in 0..e.residual.len() {
                        let fd = (ep.residual[i] - em.residual[i]) / (2.0 * h);
                        let an = e.jacobian[(i, side * b + k)];
                        assert!(
                            (fd - an).abs() < 1e-6,
                            "{kind:?} {space:?} row {i} col {side}/{k}: fd {fd} analytic {an}"
                        );
                    }
                }
            }
        }
    }
}

/// Allowed twists of the contact kinds at the reference (plan.md).
fn contact_twists(kind: JointType, g: &Geometry) -> Vec<[f64; 6]> {
    let v = |a: [f64; 3]| Vector3::from(a);
    let rot = |u: Vector3<f64>, p: Vector3<f64>| {
        let m = p.cross(&u);
        [u.x, u.y, u.z, m.x, m.y, m.z]
    };
    let tr = |u: Vector3<f64>| [0.0, 0.0, 0.0, u.x, u.y, u.z];
    let o = v(g.origin.unwrap());
    let a = v(g.axis.unwrap()).normalize();
    let n = v(g.normal.unwrap()).normalize();
    let xyz = [Vector3::x(), Vector3::y(), Vector3::z()];
    match kind {
        JointType::SP => {
            let (e1, e2) = perpendicular_pair(&n);
            let mut t = vec![tr(e1), tr(e2)];
            t.extend(xyz.iter().map(|e| rot(*e, o)));
            t
        }
        JointType::SC => {
            let mut t = vec![tr(a)];
            t.extend(xyz.iter().map(|e| rot(*e, o)));
            t
        }
        JointType::PC => {
            let (e1, e2) = perpendicular_pair(&n);
            vec![tr(e1), tr(e2), rot(n, o), rot(a, o)]
        }
        JointType::CR => vec![tr(a), tr(n.cross(&a)), rot(a, o)],
        _ => unreachable!(),
    }
}

#[test]
fn reference_jacobian_spans_the_motion_rows() {
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        let b = space.b() as usize;
        for kind in kinds(space) {
            let mut r = SplitMix64::new(kind as u64 + 3);
            let g = geometry(kind, space, &mut r);
            let m = one_joint(kind, space, g.clone(), 0);
            let model = PositionModel::new(&m).unwrap();
            let id = Pose::identity();
            let e = model.pair_equations(0, &id, &id, &[]);
            assert!(
                e.residual.iter().all(|x| x.abs() < 1e-12),
                "{kind:?} closed at reference"
            );
            let k = kind.grade() as usize;
            assert_eq!(
                e.residual.len(),
                b - k.min(b),
                "{kind:?} {space:?} equation count"
            );
            // J acts on t_B − t_A: J_A = −J_B at the reference.
            let jb = e.jacobian.columns(b, b).into_owned();
            let ja = e.jacobian.columns(0, b).into_owned();
            assert!((&ja + &jb).norm() < 1e-12, "{kind:?}");
            if jb.nrows() == 0 {
                continue;
            }
            assert_eq!(jb.rank(1e-9), b - k, "{kind:?} {space:?} rank");
            if matches!(
                kind,
                JointType::SP | JointType::SC | JointType::PC | JointType::CR
            ) {
                for t in contact_twists(kind, &g) {
                    let t = nalgebra::DVector::from_row_slice(&t);
                    assert!((&jb * t).norm() < 1e-12, "{kind:?} allows its twists");
                }
                continue;
            }
            let jm = joint_model(kind, &g, space, 0).unwrap();
            let stacked = DMatrix::from_fn(jb.nrows() + jm.rows.nrows(), b, |i, j| {
                if i < jb.nrows() {
                    jb[(i, j)]
                } else {
                    jm.rows[(i - jb.nrows(), j)]
                }
            });
            assert_eq!(
                stacked.rank(1e-9),
                jb.nrows(),
                "{kind:?} {space:?} row space"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Mechanisms with geometry.

fn j(
    id: &str,
    kind: JointType,
    a: i64,
    b: i64,
    origin: [f64; 3],
    axis: Option<[f64; 3]>,
) -> JointSpec {
    JointSpec {
        id: Some(id.into()),
        kind,
        bodies: vec![BodyId::Int(a), BodyId::Int(b)],
        driven: 0,
        geometry: Geometry {
            origin: Some(origin),
            axis,
            ..Geometry::default()
        },
    }
}

const A: f64 = 1.0; // crank
const BL: f64 = 3.0; // coupler
const CL: f64 = 2.5; // rocker
const D: f64 = 3.0; // ground

/// Closed-form four-bar: the coupler-rocker joint for crank angle θ (branch `up`).
fn four_bar_c(theta: f64) -> [f64; 2] {
    let (bx, by) = (A * theta.cos(), A * theta.sin());
    let (dx, dy) = (D - bx, -by);
    let dist = (dx * dx + dy * dy).sqrt();
    let l = (BL * BL - CL * CL + dist * dist) / (2.0 * dist);
    let hgt = (BL * BL - l * l).max(0.0).sqrt();
    let (ux, uy) = (dx / dist, dy / dist);
    [bx + l * ux - hgt * uy, by + l * uy + hgt * ux]
}

fn four_bar(space: Space, theta0: f64) -> Mechanism {
    let b = [A * theta0.cos(), A * theta0.sin(), 0.0];
    let c = four_bar_c(theta0);
    let z = match space {
        Space::Planar => None,
        _ => Some([0.0, 0.0, 1.0]),
    };
    let mut m = Mechanism::from_parts(
        "four-bar",
        space,
        BodyId::Int(1),
        vec![],
        vec![
            j("A", JointType::R, 1, 2, [0.0; 3], z),
            j("B", JointType::R, 2, 3, b, z),
            j("C", JointType::R, 3, 4, [c[0], c[1], 0.0], z),
            j("D", JointType::R, 4, 1, [D, 0.0, 0.0], z),
        ],
    );
    m.joints[0].driven = 1;
    m
}

fn analysis(m: &Mechanism) -> structure::Analysis {
    structure::analyze(m, &structure::Options::default(), &Library::builtin()).unwrap()
}

fn solve_both(
    m: &Mechanism,
    sets: &[(usize, Vec<Value>)],
    start: &Configuration,
) -> (Solution, Solution) {
    let model = PositionModel::new(m).unwrap();
    let tg = targets(m, &model, sets).unwrap();
    let sched = schedule(m, &analysis(m), &model);
    let o = NewtonOptions::default();
    let g = solve_groups(m, &model, &sched, &tg, start, &o).unwrap();
    let w = solve_global(m, &model, &tg, start, &o).unwrap();
    (g, w)
}

fn deg(x: f64) -> Value {
    Value {
        number: x,
        radians: None,
    }
}

fn angle_of(p: &Pose) -> f64 {
    p.rotation[(1, 0)].atan2(p.rotation[(0, 0)])
}

#[test]
fn four_bar_full_turn_matches_closed_form() {
    let theta0 = 60f64.to_radians();
    for space in [Space::Planar, Space::Spatial] {
        let m = four_bar(space, theta0);
        let c0 = four_bar_c(theta0);
        let psi0 = (c0[1]).atan2(c0[0] - D);
        let mut cfg = Configuration::reference(m.bodies.len());
        for step in 0..=36 {
            let v = 10.0 * step as f64;
            let (g, w) = solve_both(&m, &[(0, vec![deg(v)])], &cfg);
            let theta = theta0 + v.to_radians();
            let c = four_bar_c(theta);
            let psi = c[1].atan2(c[0] - D);
            // body 4 (index 3) turns about (D, 0) by psi - psi0
            let got = angle_of(&g.config.poses[3]);
            let want = psi - psi0;
            let diff = (got - want + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            assert!(
                diff.abs() < 1e-8,
                "{space:?} at {v}: rocker {got} want {want}"
            );
            for b in 0..m.bodies.len() {
                let (pg, pw) = (&g.config.poses[b], &w.config.poses[b]);
                assert!((pg.rotation - pw.rotation).norm() < 1e-8);
                assert!((pg.translation - pw.translation).norm() < 1e-8);
            }
            cfg = g.config.clone();
        }
    }
}

#[test]
fn slider_crank_full_turn_matches_closed_form() {
    let (a, b) = (1.0f64, 3.0f64);
    let t0 = 30f64.to_radians();
    let bpt = [a * t0.cos(), a * t0.sin(), 0.0];
    let x0 = a * t0.cos() + (b * b - (a * t0.sin()).powi(2)).sqrt();
    let mut m = Mechanism::from_parts(
        "slider-crank",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        vec![
            j("A", JointType::R, 1, 2, [0.0; 3], None),
            j("B", JointType::R, 2, 3, bpt, None),
            j("C", JointType::R, 3, 4, [x0, 0.0, 0.0], None),
            j(
                "D",
                JointType::P,
                4,
                1,
                [x0, 0.0, 0.0],
                Some([1.0, 0.0, 0.0]),
            ),
        ],
    );
    m.joints[0].driven = 1;
    let mut cfg = Configuration::reference(m.bodies.len());
    for step in 0..=24 {
        let v = 15.0 * step as f64;
        let (g, w) = solve_both(&m, &[(0, vec![deg(v)])], &cfg);
        let t = t0 + v.to_radians();
        let x = a * t.cos() + (b * b - (a * t.sin()).powi(2)).sqrt();
        // the slider (index 3) translates along x by x − x0
        let p = g.config.poses[3].translation * mbsa::position::residual::model_size(&m);
        assert!(
            (p.x - (x - x0)).abs() < 1e-8 && p.y.abs() < 1e-8,
            "at {v}: {p:?}"
        );
        assert!((g.config.poses[2].translation - w.config.poses[2].translation).norm() < 1e-8);
        cfg = g.config.clone();
    }
}

#[test]
fn closure_is_checked_and_assembled() {
    let m = four_bar(Space::Planar, 1.0);
    let reference = Configuration::reference(m.bodies.len());
    let c = check_closure(&m, &reference, None).unwrap();
    assert_eq!(c.status, ClosureStatus::Closed);
    let mut off = reference.clone();
    // Pose translations are in model units (file lengths / model size).
    let size = mbsa::position::residual::model_size(&m);
    off.poses[2] = off.poses[2].moved_by(Space::Planar, &[0.0, 1e-5 / size, 0.0]);
    let c = check_closure(&m, &off, None).unwrap();
    assert_eq!(c.status, ClosureStatus::Open);
    let ids: Vec<&str> = c.joints.iter().map(|j| j.joint.as_str()).collect();
    assert_eq!(ids, ["B", "C"]);
    assert!((c.max_residual - 1e-5).abs() < 1e-12);
    off.poses[2] = off.poses[2].moved_by(Space::Planar, &[0.0, 0.1, 0.0]);
    let c = check_closure(&m, &off, None).unwrap();
    assert_eq!(c.status, ClosureStatus::Broken);
    assert!(c.message().unwrap().contains("B ("));
    let (fixed, _) = assemble(&m, &off, &NewtonOptions::default()).unwrap();
    assert_eq!(
        check_closure(&m, &fixed, None).unwrap().status,
        ClosureStatus::Closed
    );
    let moved = moved_mechanism(&m, &fixed);
    assert_eq!(
        mbsa::position::file_closure(&moved, None).unwrap().status,
        ClosureStatus::Closed
    );
}

#[test]
fn unreachable_input_is_an_error_naming_the_group() {
    // The rocker of a crank-rocker cannot turn half a turn.
    let mut m = four_bar(Space::Planar, 60f64.to_radians());
    m.joints[0].driven = 0;
    m.joints[3].driven = 1;
    let model = PositionModel::new(&m).unwrap();
    let sched = schedule(&m, &analysis(&m), &model);
    let start = Configuration::reference(m.bodies.len());
    let tg = targets(&m, &model, &[(3, vec![deg(150.0)])]).unwrap();
    let e = solve_groups(&m, &model, &sched, &tg, &start, &NewtonOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cannot be closed") && e.contains("group SG-"),
        "{e}"
    );
    let g = solve_global(&m, &model, &tg, &start, &NewtonOptions::default());
    assert!(g.is_err());
}

/// A strip of `dyads` planar RRR dyads at right angles, each pinned to the two bodies of the
/// one before; the crank `A0` driven.
fn dyad_strip(dyads: usize) -> Mechanism {
    let mut t = String::from("space = \"planar\"\nframe = 1\n");
    let mut joint = |id: &str, a: usize, b: usize, x: f64, y: f64, driven: u32| {
        t += &format!(
            "[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, {y}]\ndriven = {driven}\n"
        );
    };
    joint("A0", 1, 2, 0.0, 0.5, 1);
    for k in 1..=dyads {
        let (a, b) = (2 * k + 1, 2 * k + 2);
        let x = k as f64;
        joint(
            &format!("T{k}"),
            if k == 1 { 2 } else { a - 2 },
            a,
            x,
            1.0,
            0,
        );
        joint(&format!("C{k}"), a, b, x + 0.5, 0.5, 0);
        joint(
            &format!("B{k}"),
            if k == 1 { 1 } else { b - 2 },
            b,
            x,
            0.0,
            0,
        );
    }
    mbsa::format::load("strip", &t, mbsa::format::Format::Toml).unwrap()
}

#[test]
fn a_failed_global_solve_names_a_few_bodies_and_joints() {
    // Half a turn of the crank takes the first dyad out of reach: the global solve leaves a
    // residual on most of the strip's 91 joints, and its error names 12 of each, then a count.
    let m = dyad_strip(30);
    let model = PositionModel::new(&m).unwrap();
    let start = Configuration::reference(m.bodies.len());
    let tg = targets(&m, &model, &[(0, vec![deg(180.0)])]).unwrap();
    let e = solve_global(&m, &model, &tg, &start, &NewtonOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("group global (bodies {2, 3,"), "{e}");
    assert!(e.matches(" more").count() == 2, "{e}");
    assert!(e.len() < 400, "{} characters: {e}", e.len());
    let sched = schedule(&m, &analysis(&m), &model);
    let e = solve_groups(&m, &model, &sched, &tg, &start, &NewtonOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("group SG-II (bodies {3, 4}) cannot be closed"),
        "{e}"
    );
}

#[test]
fn a_long_dyad_strip_solves_globally_as_group_by_group() {
    // 3,002 bodies: the Jacobian's conditioning grows as the square of the strip's length, and
    // the normal equations' steps (conditioning squared) stopped at a residual of 4e-6 here.
    let m = dyad_strip(1_500);
    let start = Configuration::reference(m.bodies.len());
    let (g, w) = solve_both(&m, &[(0, vec![deg(1.0)])], &start);
    let far = m.bodies.len() - 1;
    for b in [2, far / 2, far] {
        let (pg, pw) = (&g.config.poses[b], &w.config.poses[b]);
        assert!(
            (pg.rotation - pw.rotation).norm() < 1e-7
                && (pg.translation - pw.translation).norm() < 1e-6,
            "body {} differs",
            m.body_id(b)
        );
    }
    // The crank's turn carried through to the strip's far end.
    assert!(w.config.poses[far].translation.norm() > 1e-3);
}

#[test]
fn a_move_too_large_for_one_global_solve_is_made_in_pieces() {
    // With 4 iterations allowed, Newton cannot take the strip's crank 20° in one solve; the
    // continuation moves it 5° at a time, each piece solved from the last (at 10^5 bodies the
    // default limits do not take 20° in one solve either). The pieces end where the
    // group-by-group solve does.
    let m = dyad_strip(500);
    let model = PositionModel::new(&m).unwrap();
    let start = Configuration::reference(m.bodies.len());
    let tg = targets(&m, &model, &[(0, vec![deg(20.0)])]).unwrap();
    let o = NewtonOptions {
        max_iterations: 4,
        ..NewtonOptions::default()
    };
    let g = solve_global(&m, &model, &tg, &start, &o).expect("solved in pieces");
    assert!(g.steps[0].iterations > o.max_iterations, "{:?}", g.steps[0]);
    let (_, w) = solve_both(&m, &[(0, vec![deg(20.0)])], &start);
    let far = m.bodies.len() - 1;
    let (pg, pw) = (&g.config.poses[far], &w.config.poses[far]);
    assert!((pg.translation - pw.translation).norm() < 1e-6);
}

#[test]
fn a_long_dyad_strip_out_of_reach_stops_early_and_says_not_converged() {
    // Half a turn of the crank takes the first dyad out of reach. The global solve stops once
    // its steps make no progress (it ran its 60 iterations, each up to 30 halvings, before),
    // and it says "did not converge": a stall says nothing of whether a solution exists.
    let m = dyad_strip(1_500);
    let model = PositionModel::new(&m).unwrap();
    let start = Configuration::reference(m.bodies.len());
    let tg = targets(&m, &model, &[(0, vec![deg(180.0)])]).unwrap();
    let o = NewtonOptions::default();
    match solve_global(&m, &model, &tg, &start, &o) {
        Err(SolveError::NotConverged { iterations, .. }) => {
            assert!(iterations < o.max_iterations, "{iterations} iterations")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bennett_moves_with_finite_mobility_one() {
    let (_, text) = mbsa::examples::find("rig-bennett").unwrap();
    let mut m = mbsa::format::load("bennett", text, mbsa::format::Format::Toml).unwrap();
    let cfg = Configuration::reference(m.bodies.len());
    let f = finite_mobility(&m, &cfg, &FiniteOptions::default()).unwrap();
    assert_eq!((f.count, f.first_order, f.finite), (-2, 1, 1));
    assert_eq!(f.verdict, Verdict::OverconstrainedMoving);
    m.joints[0].driven = 1;
    let mut c = cfg.clone();
    for step in 0..=12 {
        let v = 5.0 * step as f64;
        let (g, w) = solve_both(&m, &[(0, vec![deg(v)])], &c);
        for b in 0..m.bodies.len() {
            assert!((g.config.poses[b].rotation - w.config.poses[b].rotation).norm() < 1e-8);
        }
        let f = finite_mobility(&m, &g.config, &FiniteOptions::default()).unwrap();
        assert_eq!((f.first_order, f.finite), (1, 1), "at {v}");
        c = g.config;
    }
}

/// IFToMM A02: N windows of parallelograms, all bars on one line.
fn n_four_bar(n: i64) -> Mechanism {
    let ground = 1;
    let rocker = |i: i64| 10 + i;
    let coupler = |i: i64| 100 + i;
    let mut joints = Vec::new();
    for i in 0..=n {
        let x = 2.0 * i as f64;
        joints.push(j(
            &format!("G{i}"),
            JointType::R,
            ground,
            rocker(i),
            [x, 0.0, 0.0],
            None,
        ));
    }
    for i in 0..n {
        let x = 2.0 * i as f64 + 1.0;
        joints.push(j(
            &format!("T{i}"),
            JointType::R,
            rocker(i),
            coupler(i),
            [x, 0.0, 0.0],
            None,
        ));
        joints.push(j(
            &format!("U{i}"),
            JointType::R,
            coupler(i),
            rocker(i + 1),
            [x + 2.0, 0.0, 0.0],
            None,
        ));
    }
    Mechanism::from_parts(
        "n-four-bar",
        Space::Planar,
        BodyId::Int(ground),
        vec![],
        joints,
    )
}

#[test]
fn n_four_bar_singular_pose() {
    for n in [2, 3] {
        let m = n_four_bar(n);
        let f = finite_mobility(
            &m,
            &Configuration::reference(m.bodies.len()),
            &FiniteOptions::default(),
        )
        .unwrap();
        assert_eq!(f.first_order as i64, n + 1, "{f:?}");
        assert_eq!(f.finite, 1, "{f:?}");
        assert_eq!(f.verdict, Verdict::Singular);
        assert!(!f.singular_joints.is_empty());
    }
}

#[test]
fn four_bar_toggle_names_the_locked_joint() {
    // crank and coupler collinear: the rocker is at its extreme.
    let cos_t = ((A + BL).powi(2) + D * D - CL * CL) / (2.0 * (A + BL) * D);
    let t = cos_t.acos();
    let b = [A * t.cos(), A * t.sin(), 0.0];
    let c = [(A + BL) * t.cos(), (A + BL) * t.sin(), 0.0];
    let m = Mechanism::from_parts(
        "toggle",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        vec![
            j("A", JointType::R, 1, 2, [0.0; 3], None),
            j("B", JointType::R, 2, 3, b, None),
            j("C", JointType::R, 3, 4, c, None),
            j("D", JointType::R, 4, 1, [D, 0.0, 0.0], None),
        ],
    );
    let f = finite_mobility(
        &m,
        &Configuration::reference(m.bodies.len()),
        &FiniteOptions::default(),
    )
    .unwrap();
    assert_eq!((f.first_order, f.finite), (1, 1));
    assert_eq!(f.locked_at_toggle, ["D"]);
    assert!(f.notes.iter().any(|n| n.contains("toggle")));
}

/// A five-bar loop (two DOF) at a generic pose, in the plane and written in space with every
/// axis along z: finite 2, so the curve test must pass level 1 (a curve inside one slice
/// through the configuration) and fail level 2.
#[test]
fn five_bar_moves_with_finite_mobility_two() {
    let pins = [
        [0.0, 0.0, 0.0],
        [0.3, 1.1, 0.0],
        [1.6, 1.7, 0.0],
        [2.9, 0.9, 0.0],
        [2.2, -0.2, 0.0],
    ];
    for (space, axis, count, verdict) in [
        (Space::Planar, None, 2, Verdict::Regular),
        (
            Space::Spatial,
            Some([0.0, 0.0, 1.0]),
            -1,
            Verdict::OverconstrainedMoving,
        ),
    ] {
        let joints = (0..5)
            .map(|i| {
                let a = 1 + i as i64;
                let b = if i == 4 { 1 } else { a + 1 };
                j(&format!("J{i}"), JointType::R, a, b, pins[i], axis)
            })
            .collect();
        let m = Mechanism::from_parts("five-bar", space, BodyId::Int(1), vec![], joints);
        for seed in 0..3 {
            let f = finite_mobility(
                &m,
                &Configuration::reference(m.bodies.len()),
                &FiniteOptions {
                    seed,
                    ..FiniteOptions::default()
                },
            )
            .unwrap();
            assert_eq!((f.count, f.first_order, f.finite), (count, 2, 2), "{f:?}");
            assert_eq!(f.verdict, verdict, "{f:?}");
        }
    }
}

/// Two bars of length 1 pinned to the ground 2 apart and to each other: a flat triangle. The
/// middle pin has a first-order flex (up and down) but the point is isolated, with a double
/// root (a non-reduced point of dimension 0): landed points are near misses, which the curve
/// test must not certify. In the plane and written in space.
#[test]
fn flat_triangle_is_rigid_with_a_first_order_flex() {
    for (space, axis, count) in [
        (Space::Planar, None, 0),
        (Space::Spatial, Some([0.0, 0.0, 1.0]), -3),
    ] {
        let m = Mechanism::from_parts(
            "flat-triangle",
            space,
            BodyId::Int(1),
            vec![],
            vec![
                j("A", JointType::R, 1, 2, [0.0, 0.0, 0.0], axis),
                j("B", JointType::R, 2, 3, [1.0, 0.0, 0.0], axis),
                j("C", JointType::R, 3, 1, [2.0, 0.0, 0.0], axis),
            ],
        );
        for seed in 0..3 {
            let f = finite_mobility(
                &m,
                &Configuration::reference(m.bodies.len()),
                &FiniteOptions {
                    seed,
                    ..FiniteOptions::default()
                },
            )
            .unwrap();
            assert_eq!((f.count, f.first_order, f.finite), (count, 1, 0), "{f:?}");
            assert_eq!(f.verdict, Verdict::Singular, "{f:?}");
        }
    }
}

/// An open chain (full row rank: a regular point) moves with every first-order freedom: the
/// implicit function theorem decides it after the first level, where a level per freedom
/// took minutes at 200 joints (measured: over 120 s, now 1.7 s in release).
#[test]
fn open_chain_is_regular_with_every_freedom_finite() {
    for (space, axis, n) in [
        (Space::Planar, None, 40usize),
        (Space::Spatial, Some([0.0, 0.3, 1.0]), 12),
    ] {
        let joints = (1..=n as i64)
            .map(|k| {
                j(
                    &format!("R{k}"),
                    JointType::R,
                    k,
                    k + 1,
                    [k as f64 - 1.0, 0.1 * (k % 7) as f64, 0.0],
                    axis,
                )
            })
            .collect();
        let m = Mechanism::from_parts("chain", space, BodyId::Int(1), vec![], joints);
        let f = finite_mobility(
            &m,
            &Configuration::reference(m.bodies.len()),
            &FiniteOptions::default(),
        )
        .unwrap();
        assert_eq!(
            (f.count, f.first_order, f.finite),
            (n as i64, n, n),
            "{f:?}"
        );
        assert_eq!(f.verdict, Verdict::Regular, "{f:?}");
    }
}

fn bundled(name: &str) -> Mechanism {
    let (file, text) = mbsa::examples::find(name).unwrap();
    mbsa::format::load(file, text, mbsa::format::Format::Toml).unwrap()
}

/// Every driven DOF set to a small value: angles 0.05 degree, slides 0.005 % of the model
/// size (random geometry leaves some groups little room: a random Stewart platform is
/// conditioned about 1e-4 at its reference and meets a fold 0.05 % of its size away).
fn small_inputs(m: &Mechanism, model: &PositionModel) -> Vec<(usize, Vec<Value>)> {
    let scale = model.scale;
    (0..m.joints.len())
        .filter(|&j| m.joints[j].driven > 0)
        .map(|j| {
            let flags = mbsa::position::inputs::angle_flags(model, j);
            let vals = (0..m.joints[j].driven as usize)
                .map(|i| {
                    if flags[i] {
                        deg(0.05)
                    } else {
                        Value {
                            number: 0.00005 * scale,
                            radians: None,
                        }
                    }
                })
                .collect();
            (j, vals)
        })
        .collect()
}

fn groups_equal_global(m: &Mechanism) -> usize {
    let model = PositionModel::new(m).unwrap();
    let sets = small_inputs(m, &model);
    let start = Configuration::reference(m.bodies.len());
    let (g, w) = solve_both(m, &sets, &start);
    for b in 0..m.bodies.len() {
        let (pg, pw) = (&g.config.poses[b], &w.config.poses[b]);
        assert!(
            (pg.rotation - pw.rotation).norm() < 1e-8
                && (pg.translation - pw.translation).norm() < 1e-8,
            "{}: body {} differs",
            m.name,
            m.body_id(b)
        );
    }
    // The inputs moved the mechanism.
    assert!(
        g.config.poses.iter().any(
            |p| (p.rotation - nalgebra::Matrix3::identity()).norm() > 1e-6
                || p.translation.norm() > 1e-6
        )
    );
    g.steps.len()
}

#[test]
fn rotor_and_stewart_groups_equal_global_at_random_geometry() {
    // The bundled files have no geometry (the rotor only some): a seeded generic one.
    // (Not the micro-manipulator: at a random realization its inputs fix bodies 5 and 10
    // independently, and body 21's two spherical joints then ask for a distance between
    // them that generic input values do not give: no solution, as the structural analysis's
    // redundant-equation note says.)
    for name in ["rotor", "rotor-set2", "stewart", "four-bar-rscp"] {
        let m = with_random_geometry(&bundled(name), 1);
        let steps = groups_equal_global(&m);
        assert!(steps >= 1, "{name}");
    }
    let m = with_random_geometry(&bundled("rotor"), 1);
    assert!(
        groups_equal_global(&m) > 3,
        "the rotor is solved in several groups"
    );
}

#[test]
fn generated_mechanisms_groups_equal_global() {
    use mbsa::generate::{self, Variant};
    for m in [
        generate::assur(1, 6, 3, Variant::A).unwrap(),
        generate::assur(2, 3, 4, Variant::A).unwrap(),
        generate::assur_spatial(1, 4, 5, Variant::A).unwrap(),
        generate::stewart_stack(2).unwrap(),
    ] {
        let m = with_random_geometry(&m, 7);
        groups_equal_global(&m);
    }
}

/// Bricard's trihedral 6R loop on six corners of a unit cube (IFToMM A04 shape): count 0,
/// moves with one DOF.
fn bricard() -> Mechanism {
    let c = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
        [0.0, 0.0, 1.0],
    ];
    let axes = [
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
    ];
    let joints = (0..6)
        .map(|i| {
            let a = 1 + i as i64;
            let b = if i == 5 { 1 } else { a + 1 };
            j(&format!("J{i}"), JointType::R, a, b, c[i], Some(axes[i]))
        })
        .collect();
    Mechanism::from_parts("bricard", Space::Spatial, BodyId::Int(1), vec![], joints)
}

#[test]
fn bricard_moves_with_finite_mobility_one() {
    let mut m = bricard();
    let cfg = Configuration::reference(m.bodies.len());
    let f = finite_mobility(&m, &cfg, &FiniteOptions::default()).unwrap();
    assert_eq!((f.count, f.first_order, f.finite), (0, 1, 1), "{f:?}");
    assert_eq!(f.verdict, Verdict::OverconstrainedMoving);
    m.joints[0].driven = 1;
    // J0 turns between about -30 and +30 degrees (J1 reaches -90 there: a dead point for J0).
    let mut c = cfg;
    for step in 1..=5 {
        let v = -5.0 * step as f64;
        let (g, w) = solve_both(&m, &[(0, vec![deg(v)])], &c);
        for b in 0..m.bodies.len() {
            assert!((g.config.poses[b].rotation - w.config.poses[b].rotation).norm() < 1e-8);
        }
        let f = finite_mobility(&m, &g.config, &FiniteOptions::default()).unwrap();
        assert_eq!((f.first_order, f.finite), (1, 1), "at {v}");
        c = g.config;
    }
}

/// The bundled N-four-bar (N = 40, bars of length 1, verticals V_k pivoted at (k, 0) with
/// their tops at (k + 0.6, 0.8)) moved to its singular pose: every vertical turned down onto
/// the x axis (−53.13°), every horizontal translated by (0.4, −0.8), so all bars lie on one
/// line. Body ids: V0 = 2, H_k = 2k + 1, V_k = 2k + 2.
fn n_four_bar_40_singular(name: &str) -> (Mechanism, Configuration) {
    let m = bundled(name);
    let scale = mbsa::position::residual::model_size(&m);
    let theta = -(0.8f64).atan2(0.6);
    let mut cfg = Configuration::reference(m.bodies.len());
    for (i, pose) in cfg.poses.iter_mut().enumerate() {
        let id: i64 = m.body_id(i).to_string().parse().unwrap();
        if id == 1 {
            continue;
        }
        if id % 2 == 0 {
            let k = (id - 2) / 2;
            let c = Vector3::new(k as f64, 0.0, 0.0) / scale;
            let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), theta).into_inner();
            *pose = Pose {
                rotation: r,
                translation: c - r * c,
            };
        } else {
            pose.translation = Vector3::new(0.4, -0.8, 0.0) / scale;
        }
    }
    let closure = check_closure(&m, &cfg, None).unwrap();
    assert!(closure.max_residual < 1e-12, "{name}: {closure:?}");
    (m, cfg)
}

/// The configuration of the N = 40 file with vertical V_k turned by `a[k]` from the flat
/// pose (every H_k placed on the two tops it joins).
fn n_four_bar_40_at(m: &Mechanism, a: &[f64; 41]) -> Configuration {
    let scale = mbsa::position::residual::model_size(m);
    let theta = -(0.8f64).atan2(0.6);
    let rot = |x: f64| nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), x).into_inner();
    // Top of V_k: its pivot (k, 0) plus the unit bar at angle a_k from the x axis.
    let top = |k: usize| Vector3::new(k as f64 + a[k].cos(), a[k].sin(), 0.0);
    let mut cfg = Configuration::reference(m.bodies.len());
    for (i, pose) in cfg.poses.iter_mut().enumerate() {
        let id: i64 = m.body_id(i).to_string().parse().unwrap();
        if id == 1 {
            continue;
        }
        if id % 2 == 0 {
            let k = ((id - 2) / 2) as usize;
            let c = Vector3::new(k as f64, 0.0, 0.0);
            let r = rot(theta + a[k]);
            *pose = Pose {
                rotation: r,
                translation: (c - r * c) / scale,
            };
        } else {
            // H_k: its pin with V_(k-1) is at (k - 1 + 0.6, 0.8) in the file, H horizontal.
            let k = ((id - 1) / 2) as usize;
            let (p, q) = (top(k - 1), top(k));
            let r = rot((q.y - p.y).atan2(q.x - p.x));
            let pin = Vector3::new(k as f64 - 0.4, 0.8, 0.0);
            *pose = Pose {
                rotation: r,
                translation: (p - r * pin) / scale,
            };
        }
    }
    cfg
}

/// The flat pose's solution set is 41 lines (docs/algorithms.md, "Finite mobility"):
/// L_j = {a_0..a_j = 0, a_(j+1)..a_40 = t}, j = -1..39, not 2^40 branches. Each line is a
/// set of solutions (closed to rounding at t = 0.3 rad), a point off them is not, and the
/// Jacobian's nullity along L_j is j + 1 (the motion, and one for each of the j flat windows
/// below it, whose equations keep a double root; 1 on L_-1): why the nullity at nearby
/// samples overstates the dimension (planar file).
#[test]
fn n_four_bar_40_flat_pose_is_41_lines() {
    let m = bundled("n-four-bar-40");
    let free = mbsa::position::closure::undriven(&m);
    let model = PositionModel::new(&free).unwrap();
    let sys = System {
        pairs: (0..model.pairs.len()).collect(),
        bodies: (0..m.bodies.len()).filter(|&x| x != m.frame).collect(),
    };
    let targets: Targets = vec![Vec::new(); model.pairs.len()];
    for j in [-1i64, 0, 1, 7, 20, 39] {
        let mut a = [0.3; 41];
        for x in a.iter_mut().take((j + 1) as usize) {
            *x = 0.0;
        }
        let cfg = n_four_bar_40_at(&m, &a);
        let c = check_closure(&m, &cfg, None).unwrap();
        assert!(c.max_residual < 1e-12, "L_{j}: {c:?}");
        let (_, jac, _) = sys.evaluate(&model, &targets, &cfg);
        let s = nalgebra::SVD::new(jac.clone(), false, false).singular_values;
        let top = s.max();
        let rank = s.iter().filter(|&&x| x > 1e-8 * top).count();
        assert_eq!(
            jac.ncols() - rank,
            (j + 1).max(1) as usize,
            "nullity on L_{j}"
        );
    }
    // Off the lines: only V_0 turned (window 1: a_0 != 0 and a_0 != a_1).
    let mut a = [0.0; 41];
    a[0] = 0.3;
    let c = check_closure(&m, &n_four_bar_40_at(&m, &a), None).unwrap();
    assert!(c.max_residual > 1e-3, "{c:?}");
}

fn n_four_bar_40_case(name: &str, singular: Verdict, regular: Verdict) {
    let (m, cfg) = n_four_bar_40_singular(name);
    let t = std::time::Instant::now();
    let f = finite_mobility(&m, &cfg, &FiniteOptions::default()).unwrap();
    let secs = t.elapsed().as_secs_f64();
    assert_eq!(f.first_order, 41, "{name}: {f:?}");
    assert_eq!(f.finite, 1, "{name}: {f:?}");
    assert_eq!(f.verdict, singular, "{name}");
    assert_eq!(f.instantaneous_only, 40, "{name}");
    assert!(!f.singular_joints.is_empty(), "{name}");
    assert!(
        f.notes
            .iter()
            .any(|n| n.starts_with("singular configuration: first-order mobility 41")),
        "{name}: {:?}",
        f.notes
    );
    // At the bundled (parallelogram) pose: regular, 1 and 1.
    let r = finite_mobility(
        &m,
        &Configuration::reference(m.bodies.len()),
        &FiniteOptions::default(),
    )
    .unwrap();
    assert_eq!((r.first_order, r.finite), (1, 1), "{name}");
    assert_eq!(r.verdict, regular, "{name}");
    eprintln!("{name}: singular pose analysed in {secs:.2} s");
}

#[test]
fn n_four_bar_40_singular_pose_planar() {
    n_four_bar_40_case("n-four-bar-40", Verdict::Singular, Verdict::Regular);
}

/// The 3D twin (every R axis along z) has the planar twin's solution set exactly: every body
/// is reached from the frame by a tree of R joints with parallel axes (A0, VB0, B1, VB1, ...),
/// so every configuration the joints allow is planar, and the closing joints P_k add nothing
/// out of the plane. In the plane, window k is a rhombus (ground, V_(k-1), H_k, V_k all of
/// length 1) whose closure equation in the verticals' angles (a = V_(k-1), b = V_k, from the
/// flat pose) is exactly -4 sin(a/2) cos(b/2) sin((b - a)/2) = 0: near the flat pose a = 0
/// or a = b. With a_0..a_40 the verticals' angles, window k says a_(k-1) = 0 or a_(k-1) = a_k:
/// the first window from the top taking a_(k-1) = 0 forces every lower angle to 0, every
/// window above it a_i = a_40, so the set is 41 lines (not 2^40 branches: the 2^40 choices
/// give 41 distinct sets), L_j = {a_0..a_j = 0, a_(j+1)..a_40 = t}, j = -1..39, each of
/// dimension 1, their directions spanning the 41 first-order motions. So: first order 41 (no out-of-plane first-order motion either), finite 1, as
/// in the plane; the verdict adds "overconstrained by design" because the spatial count is
/// -119 (3 redundant constraints per planar loop written in space), and at the parallelogram
/// pose it is overconstrained-moving with 1 and 1.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "slow in debug (150-230 s on the shared machine): run with --release"
)]
fn n_four_bar_40_singular_pose_in_space() {
    n_four_bar_40_case(
        "n-four-bar-40-3d",
        Verdict::SingularOverconstrained,
        Verdict::OverconstrainedMoving,
    );
}

/// Every bundled mechanism whose file has complete joint geometry, its driven joints (or, if
/// none, its first joint) set to small values: group by group and global give the same
/// poses. Returns the names solved.
#[test]
fn bundled_with_geometry_groups_equal_global() {
    let mut solved = Vec::new();
    let mut failed: Vec<String> = Vec::new();
    for name in mbsa::examples::names() {
        let mut m = bundled(name);
        if PositionModel::new(&m).is_err() {
            continue;
        }
        if m.joints.iter().all(|j| j.driven == 0) {
            // Drive what the structural analysis would need: skip undriven files.
            continue;
        }
        // Files already at a singular pose are for the finite-mobility tests.
        if name.starts_with("n-four-bar") {
            continue;
        }
        m.name = name.to_string();
        let model = PositionModel::new(&m).unwrap();
        let sets = small_inputs(&m, &model);
        let tg = targets(&m, &model, &sets).unwrap();
        let sched = schedule(&m, &analysis(&m), &model);
        let start = Configuration::reference(m.bodies.len());
        let o = NewtonOptions::default();
        let g = solve_groups(&m, &model, &sched, &tg, &start, &o);
        let w = solve_global(&m, &model, &tg, &start, &o);
        match (g, w) {
            (Ok(g), Ok(w)) => {
                for b in 0..m.bodies.len() {
                    let (pg, pw) = (&g.config.poses[b], &w.config.poses[b]);
                    assert!(
                        (pg.rotation - pw.rotation).norm() < 1e-8
                            && (pg.translation - pw.translation).norm() < 1e-8,
                        "{name}: body {} differs",
                        m.body_id(b)
                    );
                }
                solved.push(name);
            }
            (g, w) => failed.push(format!(
                "{name}: groups {:?} / global {:?}",
                g.err().map(|e| e.to_string()),
                w.err().map(|e| e.to_string())
            )),
        }
    }
    eprintln!("solved both ways: {solved:?}");
    // Every one, `multiple-joint-order` included (its pin P = [2, 3, 4] is placed by SG-II
    // with bodies 3 and 4 before body 2 is known: the schedule roots it at body 3).
    assert!(failed.is_empty(), "{failed:?}");
    for want in [
        "slider-crank-geometry",
        "four-bar-3d-driven",
        "bricard-driven",
        "multiple-joint-order",
        "multiple-joint-order-b",
    ] {
        assert!(solved.contains(&want), "{want} not solved: {solved:?}");
    }
}

/// A pin shared by three bodies, listed [2, 3, 4] and [3, 4, 2]: SG-II places bodies
/// 3 and 4, which meet at the pin, before body 2 (the first listed in one file) is known. The
/// schedule must tie 3 and 4 together in SG-II (square 6 x 6 steps, no inconsistent
/// leftover in SG-III), and both listings give the same poses, group by group and globally,
/// over a range of crank angles.
#[test]
fn multiple_joint_listing_order_solves_the_same() {
    let mut poses: Vec<Vec<Configuration>> = Vec::new();
    for name in ["multiple-joint-order", "multiple-joint-order-b"] {
        let m = bundled(name);
        let model = PositionModel::new(&m).unwrap();
        let sched = schedule(&m, &analysis(&m), &model);
        let names: Vec<&str> = sched.steps.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["SG-I", "SG-II", "SG-III"], "{name}");
        // Every step square: its equations count its unknowns (3 per planar body).
        let none: Targets = vec![Vec::new(); model.pairs.len()];
        let (ext, _) = sched.extended(&model, &none);
        for st in &sched.steps {
            let rows: usize = st
                .pairs
                .iter()
                .map(|&p| ext.constraint_count(p) + ext.pairs[p].driven)
                .sum();
            assert_eq!(rows, 3 * st.bodies.len(), "{name} {}", st.name);
        }
        let mut mine = Vec::new();
        let mut start = Configuration::reference(m.bodies.len());
        for deg in [0.05, 5.0, 20.0, -15.0] {
            let sets = vec![(0usize, vec![self::deg(deg)])];
            let tg = targets(&m, &model, &sets).unwrap();
            let o = NewtonOptions::default();
            let g = solve_groups(&m, &model, &sched, &tg, &start, &o)
                .unwrap_or_else(|e| panic!("{name} at {deg}: {e}"));
            let w = solve_global(&m, &model, &tg, &start, &o).unwrap();
            for b in 0..m.bodies.len() {
                let (pg, pw) = (&g.config.poses[b], &w.config.poses[b]);
                assert!(
                    (pg.rotation - pw.rotation).norm() < 1e-8
                        && (pg.translation - pw.translation).norm() < 1e-8,
                    "{name} at {deg}: body {}",
                    m.body_id(b)
                );
            }
            start = g.config.clone();
            mine.push(g.config);
        }
        // Index configurations by body id for the comparison across files.
        let mut by_id = Vec::new();
        for c in mine {
            let mut v: Vec<(String, Pose)> = (0..m.bodies.len())
                .map(|b| (m.body_id(b).to_string(), c.poses[b]))
                .collect();
            v.sort_by(|a, b| a.0.cmp(&b.0));
            by_id.push(Configuration {
                poses: v.into_iter().map(|(_, p)| p).collect(),
            });
        }
        poses.push(by_id);
    }
    for (a, b) in poses[0].iter().zip(&poses[1]) {
        for (pa, pb) in a.poses.iter().zip(&b.poses) {
            assert!((pa.rotation - pb.rotation).norm() < 1e-8);
            assert!((pa.translation - pb.translation).norm() < 1e-8);
        }
    }
}

/// Group by group against global on generated linkages with a seeded random geometry, every
/// body started 1e-5 off the file's configuration and the crank at 0: both bring every body
/// back (the reference is the solution) and agree.
fn generated_return(m: &Mechanism) {
    generated_return_with(m, None);
}

/// [`generated_return`] with the geometry drawn away from folds (every group's conditioning
/// at the reference at least `margin`) when given.
fn generated_return_with(m: &Mechanism, margin: Option<f64>) {
    let first = with_random_geometry(m, 3);
    let model = PositionModel::new(&first).unwrap();
    let a = analysis(&first);
    let (m, model, sched) = match margin {
        Some(c) => {
            let sched = schedule(&first, &a, &model);
            let (m2, r) =
                mbsa::position::with_random_geometry_away_from_folds(m, 3, &sched, c, 50).unwrap();
            eprintln!("{}: away from folds: {r:?}", m.name);
            let model2 = PositionModel::new(&m2).unwrap();
            let sched2 = schedule(&m2, &a, &model2);
            (m2, model2, sched2)
        }
        None => {
            let sched = schedule(&first, &a, &model);
            (first, model, sched)
        }
    };
    let tg = targets(&m, &model, &[]).unwrap();
    let mut start = Configuration::reference(m.bodies.len());
    let mut rng = SplitMix64::new(11);
    let b = model.b();
    for (i, p) in start.poses.iter_mut().enumerate() {
        if i != m.frame {
            let tw: Vec<f64> = (0..b).map(|_| 1e-5 * rng.next_signed()).collect();
            *p = p.moved_by(m.space, &tw);
        }
    }
    // Random dyads can sit near a fold (conditioning 1e-8): a residual of 1e-11 leaves
    // pose errors of 1e-3 there, so both solve to 1e-13.
    let o = NewtonOptions {
        tolerance: 1e-13,
        ..NewtonOptions::default()
    };
    let g = solve_groups(&m, &model, &sched, &tg, &start, &o).unwrap();
    let w = solve_global(&m, &model, &tg, &start, &o).unwrap();
    for i in 0..m.bodies.len() {
        let (pg, pw) = (&g.config.poses[i], &w.config.poses[i]);
        let off = (pg.rotation - nalgebra::Matrix3::identity())
            .norm()
            .max(pg.translation.norm());
        assert!(
            off < 1e-8,
            "{}: body {} not back: {off}",
            m.name,
            m.body_id(i)
        );
        assert!(
            (pg.rotation - pw.rotation).norm() < 1e-8
                && (pg.translation - pw.translation).norm() < 1e-8,
            "{}: body {} differs",
            m.name,
            m.body_id(i)
        );
    }
}

#[test]
fn generated_return_groups_equal_global() {
    use mbsa::generate::{self, Variant};
    generated_return(&generate::assur(1, 49, 1, Variant::A).unwrap());
    generated_return(&generate::assur(2, 12, 2, Variant::A).unwrap());
    generated_return(&generate::assur_spatial(1, 49, 1, Variant::A).unwrap());
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug: run with --release")]
fn generated_1000_bodies_groups_equal_global() {
    use mbsa::generate::{self, Variant};
    // At 10^3 bodies some random dyads sit so near a fold (conditioning 1e-8) that the
    // global Newton stalls at 4.6e-13 above the 1e-13 asked (measured), and a margin of 1e-2
    // per group still lets pose errors grow level by level past 1e-8: the geometry is drawn
    // away from folds with a margin of 0.1 (planar; spatial groups rarely reach 0.1: 0.03,
    // where 1e-2 still left a global pose 1e-8 off) (docs/benchmarks.md, "Geometry away from
    // folds").
    generated_return_with(&generate::assur(1, 499, 1, Variant::A).unwrap(), Some(0.1));
    generated_return_with(
        &generate::assur_spatial(1, 499, 1, Variant::A).unwrap(),
        Some(0.03),
    );
}

#[test]
fn budget_stops_a_global_solve() {
    use mbsa::generate::{self, Variant};
    let m = with_random_geometry(&generate::assur(1, 49, 1, Variant::A).unwrap(), 3);
    let model = PositionModel::new(&m).unwrap();
    let tg = targets(&m, &model, &[]).unwrap();
    let mut start = Configuration::reference(m.bodies.len());
    start.poses[5] = start.poses[5].moved_by(m.space, &[1e-4, 0.0, 0.0]);
    let tiny = mbsa::budget::Budget {
        max_work: 10_000,
        ..mbsa::budget::Budget::DEFAULT
    };
    let o = NewtonOptions {
        budget: tiny,
        ..NewtonOptions::default()
    };
    for e in [
        solve_global(&m, &model, &tg, &start, &o).unwrap_err(),
        solve_groups(
            &m,
            &model,
            &schedule(&m, &analysis(&m), &model),
            &tg,
            &start,
            &o,
        )
        .unwrap_err(),
    ] {
        assert!(matches!(e, SolveError::Budget(_)), "{e}");
        assert!(e.to_string().contains("work limit"), "{e}");
    }
    let small_memory = NewtonOptions {
        budget: mbsa::budget::Budget {
            max_memory_bytes: 1000,
            ..mbsa::budget::Budget::DEFAULT
        },
        ..NewtonOptions::default()
    };
    let e = solve_global(&m, &model, &tg, &start, &small_memory).unwrap_err();
    assert!(e.to_string().contains("memory limit"), "{e}");
}

#[test]
fn cli_solve_over_budget_exits_2_naming_the_limit() {
    for global in [false, true] {
        let mut cmd = assert_cmd::Command::cargo_bin("mbsa").unwrap();
        cmd.args([
            "solve",
            "mechanisms/slider-crank-geometry.toml",
            "--set",
            "O=10",
            "--max-work",
            "100",
        ]);
        if global {
            cmd.arg("--global");
        }
        let out = cmd.output().unwrap();
        assert_eq!(out.status.code(), Some(2), "global {global}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("position solve")
                && err.contains("work limit")
                && err.contains("--max-work"),
            "{err}"
        );
    }
}

/// Random geometry drawn again away from folds: every group's conditioning at the reference
/// reaches the margin (some groups had to be drawn again), and a turned crank then solves
/// group by group like the global solve.
#[test]
fn random_geometry_away_from_folds_has_room_in_every_group() {
    use mbsa::generate::{self, Variant};
    let m = generate::assur(1, 199, 1, Variant::A).unwrap();
    let first = with_random_geometry(&m, 3);
    let model = PositionModel::new(&first).unwrap();
    let a = analysis(&first);
    let sched = schedule(&first, &a, &model);
    let (m2, r) =
        mbsa::position::with_random_geometry_away_from_folds(&m, 3, &sched, 0.05, 50).unwrap();
    assert!(r.steps > 0 && r.draws >= r.steps, "{r:?}");
    assert_eq!(r.below, 0, "{r:?}");
    assert!(r.worst >= 0.05, "{r:?}");
    let model2 = PositionModel::new(&m2).unwrap();
    let sched2 = schedule(&m2, &a, &model2);
    let tg = targets(&m2, &model2, &[(0, vec![deg(0.5)])]).unwrap();
    let start = Configuration::reference(m2.bodies.len());
    let o = NewtonOptions {
        tolerance: 1e-13,
        ..NewtonOptions::default()
    };
    let g = solve_groups(&m2, &model2, &sched2, &tg, &start, &o).unwrap();
    let w = solve_global(&m2, &model2, &tg, &start, &o).unwrap();
    for b in 0..m2.bodies.len() {
        let (pg, pw) = (&g.config.poses[b], &w.config.poses[b]);
        assert!(
            (pg.rotation - pw.rotation).norm() < 1e-8
                && (pg.translation - pw.translation).norm() < 1e-8,
            "body {}",
            m2.body_id(b)
        );
    }
    for st in &g.steps {
        assert!(st.conditioning > 1e-3, "{st:?}");
    }
}

/// The flat pose is non-reduced (every window has a double root there). The former offset
/// slices gave 2 at seed 1 for the planar file and 0 at seeds 2 and 5 for the 3D twin; the
/// curve test on slices through the configuration must give 1 at every seed given: 0..=5
/// for the planar file, the 3D twin at 0 and its former failures 2 and 5 (release, CPU:
/// about 0.4 s a seed planar, 4.4 s a seed 3D).
fn n_four_bar_40_over_seeds(name: &str, seeds: &[u64]) {
    let (m, cfg) = n_four_bar_40_singular(name);
    let mut got = Vec::new();
    for &seed in seeds {
        let f = finite_mobility(
            &m,
            &cfg,
            &FiniteOptions {
                seed,
                ..FiniteOptions::default()
            },
        )
        .unwrap();
        assert_eq!(f.first_order, 41, "{name} seed {seed}: {f:?}");
        got.push(f.finite);
    }
    assert_eq!(
        got,
        vec![1; seeds.len()],
        "{name}: finite mobility per seed {seeds:?}"
    );
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug: run with --release")]
fn n_four_bar_40_singular_pose_planar_over_seeds() {
    n_four_bar_40_over_seeds("n-four-bar-40", &[0, 1, 2, 3, 4, 5]);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug: run with --release")]
fn n_four_bar_40_singular_pose_in_space_over_seeds() {
    n_four_bar_40_over_seeds("n-four-bar-40-3d", &[0, 2, 5]);
}

/// Measurement, not a check: the finite mobility of the N = 40 singular pose at the seeds in
/// `MBSA_SEEDS` (default 0..=5), the files in `MBSA_FILES` (default both), one line per run;
/// `MBSA_SAMPLES=0` records no nearby samples' nullities (the curve test still runs).
#[test]
#[ignore = "measurement: run with --release --ignored --nocapture"]
fn n_four_bar_40_seed_survey() {
    let seeds: Vec<u64> = std::env::var("MBSA_SEEDS")
        .unwrap_or_else(|_| "0,1,2,3,4,5".into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    let files =
        std::env::var("MBSA_FILES").unwrap_or_else(|_| "n-four-bar-40,n-four-bar-40-3d".into());
    let samples = std::env::var("MBSA_SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(FiniteOptions::default().samples);
    for name in files.split(',') {
        let (m, cfg) = n_four_bar_40_singular(name);
        for &seed in &seeds {
            let t = std::time::Instant::now();
            let f = finite_mobility(
                &m,
                &cfg,
                &FiniteOptions {
                    seed,
                    samples,
                    ..FiniteOptions::default()
                },
            )
            .unwrap();
            eprintln!(
                "{name} seed {seed}: first order {} finite {} samples {:?} notes {:?} ({:.1} s)",
                f.first_order,
                f.finite,
                f.samples,
                f.notes
                    .iter()
                    .map(|n| n.split(':').next().unwrap_or(""))
                    .collect::<Vec<_>>(),
                t.elapsed().as_secs_f64()
            );
        }
    }
}

/// An open planar chain of `n` R joints with its last joint written twice (two coincident
/// pins between the same bodies: 2 dependent rows, so no full row rank): the curve test runs
/// one slicing level per freedom.
fn doubled_chain(n: i64) -> Mechanism {
    let mut joints: Vec<JointSpec> = (1..=n)
        .map(|k| {
            j(
                &format!("R{k}"),
                JointType::R,
                k,
                k + 1,
                [k as f64 - 1.0, 0.1 * (k % 7) as f64, 0.0],
                None,
            )
        })
        .collect();
    let mut twin = joints[n as usize - 1].clone();
    twin.id = Some("R-twin".into());
    joints.push(twin);
    Mechanism::from_parts(
        "doubled chain",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        joints,
    )
}

/// The finite-mobility test charges its solves to the work budget
/// (deterministic units): a row-deficient chain with many freedoms stops with the budget
/// error under a small cap, and the same chain gives the same answer unbudgeted.
#[test]
fn finite_mobility_charges_its_work_to_the_budget() {
    let m = doubled_chain(12);
    let config = Configuration::reference(m.bodies.len());
    let f = finite_mobility(
        &m,
        &config,
        &FiniteOptions {
            budget: mbsa::budget::Budget::UNLIMITED,
            ..FiniteOptions::default()
        },
    )
    .unwrap();
    assert_eq!((f.first_order, f.finite), (12, 12), "{f:?}");
    let small = FiniteOptions {
        budget: mbsa::budget::Budget {
            max_work: 1_000_000,
            ..mbsa::budget::Budget::DEFAULT
        },
        ..FiniteOptions::default()
    };
    let e = finite_mobility(&m, &config, &small).unwrap_err();
    assert!(matches!(e, SolveError::Budget(_)), "{e}");
    assert!(
        e.to_string().contains("finite-mobility test") && e.to_string().contains("work limit"),
        "{e}"
    );
}

#[test]
fn cli_rigid_finite_over_budget_exits_2_naming_the_limit() {
    let dir = std::env::temp_dir().join(format!("mbsa-finite-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("doubled-chain.toml");
    let m = doubled_chain(12);
    let mut text = String::from("name = \"doubled chain\"\nspace = \"planar\"\nframe = 1\n");
    for jt in &m.joints {
        let o = jt.geometry.origin.unwrap();
        text += &format!(
            "\n[[joint]]\nid = \"{}\"\ntype = \"R\"\nbodies = [{}, {}]\norigin = [{}, {}]\n",
            jt.id,
            m.body_id(jt.bodies[0]),
            m.body_id(jt.bodies[1]),
            o[0],
            o[1]
        );
    }
    std::fs::write(&path, text).unwrap();
    let run = |work: &str| {
        assert_cmd::Command::cargo_bin("mbsa")
            .unwrap()
            .args([
                "rigid",
                path.to_str().unwrap(),
                "--finite",
                "--max-work",
                work,
            ])
            .output()
            .unwrap()
    };
    let out = run("1000000");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("finite-mobility test") && err.contains("--max-work"),
        "{err}"
    );
    let out = run("100000000000");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
