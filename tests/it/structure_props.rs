//! Property tests of the structural decomposition on random count-determined mechanisms:
//! the flow method agrees with the paper's exhaustive search, and the rank check agrees with
//! the rank of the global constraint Jacobian.

use mbsa::joint::JointType::{self, *};
use mbsa::mechanism::{BodyId, JointSpec, Mechanism, Space};
use mbsa::rng::SplitMix64;
use mbsa::structure::{Analysis, Library, Method, Options, Status, analyze};
use nalgebra::DMatrix;
use proptest::prelude::*;

const PLANAR: [JointType; 4] = [R, R, P, RP];
const SPATIAL: [JointType; 9] = [R, P, C, U, S, S, PL, SP, H];

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

/// A random connected mechanism of `n` bodies (frame 1) that is determined by counting:
/// a random spanning tree plus extra joints that keep it free of over-determined parts, then
/// inputs placed one by one where they fix a missing DOF. `multi` allows 3-body joints.
fn random_mechanism(n: usize, planar: bool, seed: u64, multi: bool) -> Option<Mechanism> {
    let mut rng = SplitMix64::new(seed);
    let (space, kinds): (Space, &[JointType]) = if planar {
        (Space::Planar, &PLANAR)
    } else {
        (Space::Spatial, &SPATIAL)
    };
    let lib = Library::empty();
    let kind = |rng: &mut SplitMix64| kinds[rng.below(kinds.len() as u64) as usize];
    let mut joints: Vec<JointSpec> = Vec::new();
    for b in 2..=n as i64 {
        let a = 1 + rng.below(b as u64 - 1) as i64;
        joints.push(JointSpec::new(kind(&mut rng), a, b, 0));
    }
    let extra = rng.below(2 * n as u64 + 1);
    for _ in 0..extra {
        let a = 1 + rng.below(n as u64) as i64;
        let b = 1 + rng.below(n as u64) as i64;
        if a == b {
            continue;
        }
        let mut spec = JointSpec::new(kind(&mut rng), a, b, 0);
        if multi && rng.below(6) == 0 {
            let c = 1 + rng.below(n as u64) as i64;
            if c != a && c != b {
                spec.bodies.push(BodyId::Int(c));
            }
        }
        joints.push(spec);
        let a = analyze(&build(space, &joints), &count_only(), &lib).unwrap();
        if over(&a) > 0 {
            joints.pop();
        }
    }
    // Inputs: try joints in random order, keep an input when it fixes a missing DOF.
    loop {
        let a = analyze(&build(space, &joints), &count_only(), &lib).unwrap();
        let miss = missing(&a);
        if miss == 0 {
            return (a.status == Status::Determined).then(|| build(space, &joints));
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
            return None;
        }
    }
}

/// Groups as a sorted list of body sets with levels.
fn groups(a: &Analysis) -> Vec<(usize, Vec<String>)> {
    let mut g: Vec<(usize, Vec<String>)> = a
        .groups
        .iter()
        .map(|g| (g.level, g.bodies.clone()))
        .collect();
    g.sort();
    g
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn flow_equals_exhaustive(n in 2usize..=15, planar: bool, seed: u64) {
        let Some(m) = random_mechanism(n, planar, seed, true) else {
            return Ok(());
        };
        let lib = Library::empty();
        let flow = analyze(&m, &count_only(), &lib).unwrap();
        let ex = analyze(&m, &Options { method: Method::Exhaustive, ..count_only() }, &lib).unwrap();
        prop_assert_eq!(flow.status, Status::Determined);
        prop_assert_eq!(groups(&flow), groups(&ex));
        // The canonical order and the rendered strings agree too.
        prop_assert_eq!(&flow.groups, &ex.groups);
    }
}

/// The global constraint Jacobian at the rank check's realization: one block row per pair
/// (`rows · (t_other − t_hub)`), B columns per movable body.
fn global_rank(m: &Mechanism, seed: u64) -> (usize, usize, usize) {
    let b = m.b() as usize;
    let models = mbsa::motion::realize(m, seed);
    let mut col = vec![usize::MAX; m.bodies.len()];
    let mut n = 0;
    for (i, c) in col.iter_mut().enumerate() {
        if i != m.frame {
            *c = n;
            n += b;
        }
    }
    let nrows: usize = m
        .joints
        .iter()
        .zip(&models)
        .map(|(j, jm)| jm.rows.nrows() * j.pairs() as usize)
        .sum();
    let mut jac = DMatrix::<f64>::zeros(nrows, n);
    let mut r0 = 0;
    for (j, jm) in m.joints.iter().zip(&models) {
        let hub = j.bodies[0];
        for &o in &j.bodies[1..] {
            let k = jm.rows.nrows();
            for (x, sign) in [(hub, -1.0), (o, 1.0)] {
                if x != m.frame {
                    let blk = &jm.rows * sign;
                    let mut v = jac.view_mut((r0, col[x]), (k, b));
                    v += blk;
                }
            }
            r0 += k;
        }
    }
    let svd = jac.clone().svd(false, false);
    let max = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let tol = max * nrows.max(n) as f64 * 1e-12;
    let rank = svd.singular_values.iter().filter(|&&s| s > tol).count();
    (rank, nrows, n)
}

/// The property below for one case: the rank check's verdict and counts against the rank of
/// the global Jacobian (the largest over eight draws).
fn rank_check_case(n: usize, planar: bool, seed: u64) -> Result<(), TestCaseError> {
    let Some(m) = random_mechanism(n, planar, seed, false) else {
        return Ok(());
    };
    let opts = Options {
        geometry: mbsa::geometry::GeometrySource::Random {
            seed: seed ^ 0x5eed,
        },
        ..Options::default()
    };
    let a = analyze(&m, &opts, &Library::empty()).unwrap();
    // The generic rank: the largest over realizations (a draw is degenerate with probability
    // zero, but the reference takes the best of several anyway).
    let (rank, nrows, nunk) = (0..8u64)
        .map(|k| global_rank(&m, seed ^ 0x5eed ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15)))
        .max_by_key(|r| r.0)
        .expect("eight draws");
    let iso: usize = a.isolated.iter().map(|i| i.dimension as usize).sum();
    let red: usize = a.redundant.iter().map(|r| r.count as usize).sum();
    let determined = rank == nrows && rank + iso == nunk && iso == 0;
    prop_assert_eq!(
        a.status == Status::Determined && a.redundant.is_empty(),
        determined,
        "rank {} rows {} unknowns {} isolated {} redundant {}",
        rank,
        nrows,
        nunk,
        iso,
        red
    );
    // Redundant equations: those the rank check found plus the count's surplus.
    prop_assert_eq!(nrows - rank, red + over(&a) as usize);
    // Uncontrolled freedoms: isolated ones (a body's own, a rigid part's spin) plus the
    // count's missing DOF.
    let spins: usize = a.spins.iter().map(|s| s.dimension as usize).sum();
    prop_assert_eq!(nunk - rank, iso + spins + missing(&a) as usize);
    Ok(())
}

proptest! {
    // A random stream (a fixed stream once hid it: a driven DOF of a contact
    // kind dropped a direction fixed by the model's construction, degenerate at a fixed
    // fraction of draws, and the rank check could keep a deficit every confirming draw
    // repeated). With the generic input model 220,000 cases at 110 fixed seeds passed, where
    // the old model failed at 4 of 30 seeds. `PROPTEST_RNG_SEED` fixes a stream to explore.
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn rank_check_matches_global_jacobian(n in 2usize..=12, planar: bool, seed: u64) {
        rank_check_case(n, planar, seed)?;
    }
}

/// Cases the property met with the former fixed input model (proptest seeds 2, 3, 11
/// and 17, 2,000 cases each): planar mechanisms of P, RP and R joints with driven RP joints,
/// where the rank check kept a deficit that the generic rank does not have.
#[test]
fn rank_check_cases_the_fixed_input_model_failed() {
    for (n, seed) in [
        (12, 14036240559547251828u64),
        (6, 6880465464844845752),
        (11, 17707228102595443322),
        (10, 1652893656849841939),
    ] {
        if let Err(e) = rank_check_case(n, true, seed) {
            panic!("n = {n}, seed = {seed}: {e}");
        }
    }
}

/// A case the generic input model fixed: a planar 9-body
/// mechanism (P, RP and R joints, one RP joint driven) whose generic answer is one redundant
/// equation; at the analysis seed below the rank check kept a second one in the loop 2-3,
/// 3-8, 8-9, 9-2 (at 2 of 12 nearby seeds), which every confirming draw repeated. Found by
/// `rank_check_matches_global_jacobian` with a random stream.
#[test]
fn rank_check_keeps_a_deficit_other_draws_do_not_have() {
    let seed: u64 = 6682289030365868298;
    let m = random_mechanism(9, true, seed, false).expect("a mechanism");
    let opts = Options {
        geometry: mbsa::geometry::GeometrySource::Random {
            seed: seed ^ 0x5eed,
        },
        ..Options::default()
    };
    let a = analyze(&m, &opts, &Library::empty()).unwrap();
    let (rank, nrows, _) = (0..16u64)
        .map(|k| global_rank(&m, seed ^ 0x5eed ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15)))
        .max_by_key(|r| r.0)
        .expect("sixteen draws");
    let red: usize = a.redundant.iter().map(|r| r.count as usize).sum();
    assert_eq!(nrows - rank, red + over(&a) as usize);
}
