//! Random joint geometry for mechanisms written without it: a generic realization at which
//! the position level can run (the reference configuration is closed by construction, as
//! every joint's features sit on both its bodies).

use crate::mechanism::Mechanism;
use crate::motion::random_geometry;
use crate::rng::{SplitMix64, indexed_seed};

/// `m` with every joint's geometry replaced by a random generic one (seeded per joint, as
/// [`crate::motion::realize`] does).
pub fn with_random_geometry(m: &Mechanism, seed: u64) -> Mechanism {
    let mut out = m.clone();
    for (i, j) in out.joints.iter_mut().enumerate() {
        let mut rng = SplitMix64::new(indexed_seed(seed, i));
        j.geometry = random_geometry(j.kind, m.space, &mut rng).into();
    }
    out
}

/// What [`with_random_geometry_away_from_folds`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct Redrawn {
    /// Steps whose joints were drawn again at least once.
    pub steps: usize,
    /// Draws in all (first draws excluded).
    pub draws: usize,
    /// Steps still below the margin after every try.
    pub below: usize,
    /// Smallest step conditioning at the end.
    pub worst: f64,
}

/// `m` with a random generic geometry as [`with_random_geometry`] gives it, except that the
/// joints solved by a step of `sched` (the pairs of the step) are drawn again (up to `tries`
/// times, other seeds) while that step's Jacobian at the reference configuration has a
/// conditioning (smallest over largest singular value, as [`super::StepReport`]'s) below
/// `margin` (the best draw is kept when none reaches it): a dyad near a fold (its links nearly
/// aligned) is replaced by one with room, so a
/// small input step or perturbation keeps every group solvable. Each joint belongs to one step,
/// so redrawing a step changes no other step's equations. Linear in the size (a dense SVD per
/// step draw). Driven DOF count as equations (the input fixes them).
pub fn with_random_geometry_away_from_folds(
    m: &Mechanism,
    seed: u64,
    sched: &super::Schedule,
    margin: f64,
    tries: usize,
) -> Result<(Mechanism, Redrawn), super::ModelError> {
    let mut out = with_random_geometry(m, seed);
    let all = super::PositionModel::new(&out)?;
    let scale = all.scale;
    // A joint is redrawn by the first step that solves one of its pairs only (a multiple
    // joint's pairs may fall in several steps).
    let mut owner: Vec<Option<usize>> = vec![None; m.joints.len()];
    let reference = super::Configuration::reference(m.bodies.len());
    let mut done = Redrawn {
        steps: 0,
        draws: 0,
        below: 0,
        worst: 1.0,
    };
    for (si, step) in sched.steps.iter().enumerate() {
        let mut joints: Vec<usize> = step
            .pairs
            .iter()
            .filter(|&&p| p < all.pairs.len())
            .map(|&p| all.pairs[p].joint)
            .collect();
        joints.sort_unstable();
        joints.dedup();
        if joints.is_empty() {
            continue;
        }
        for &ji in &joints {
            owner[ji].get_or_insert(si);
        }
        let conditioning = |mech: &Mechanism| -> Result<f64, super::ModelError> {
            let model =
                super::PositionModel::of_joints_scaled(mech, joints.iter().copied(), scale)?;
            let targets: super::Targets = model.pairs.iter().map(|p| vec![0.0; p.driven]).collect();
            let sys = super::System {
                pairs: (0..model.pairs.len()).collect(),
                bodies: step.bodies.clone(),
            };
            let (_, j, _) = sys.evaluate(&model, &targets, &reference);
            let s = j.singular_values();
            let top = s.iter().copied().fold(0.0, f64::max).max(1.0);
            Ok(s.iter()
                .copied()
                .filter(|&x| x > 1e-9 * top)
                .fold(top, f64::min)
                / top)
        };
        let mine: Vec<usize> = joints
            .iter()
            .copied()
            .filter(|&ji| owner[ji] == Some(si))
            .collect();
        let mut c = conditioning(&out)?;
        // The best draw so far (kept when no draw reaches the margin).
        let mut best: (f64, Vec<_>) = (
            c,
            mine.iter()
                .map(|&ji| out.joints[ji].geometry.clone())
                .collect(),
        );
        let mut attempt = 0;
        while c < margin && attempt < tries {
            attempt += 1;
            done.draws += 1;
            let again = seed ^ (attempt as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            for &ji in &mine {
                let mut rng = SplitMix64::new(indexed_seed(again, ji));
                out.joints[ji].geometry =
                    random_geometry(out.joints[ji].kind, m.space, &mut rng).into();
            }
            c = conditioning(&out)?;
            if c > best.0 {
                let kept = mine
                    .iter()
                    .map(|&ji| out.joints[ji].geometry.clone())
                    .collect();
                best = (c, kept);
            }
        }
        if c < best.0 {
            for (&ji, g) in mine.iter().zip(best.1) {
                out.joints[ji].geometry = g;
            }
            c = best.0;
        }
        if attempt > 0 {
            done.steps += 1;
        }
        if c < margin {
            done.below += 1;
        }
        done.worst = done.worst.min(c);
    }
    Ok((out, done))
}
