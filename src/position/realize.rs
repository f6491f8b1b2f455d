//! Random joint geometry for mechanisms written without it: a generic realization at which
//! the position level can run (the reference configuration is closed by construction, as
//! every joint's features sit on both its bodies).

use crate::mechanism::Mechanism;
use crate::motion::{SplitMix64, joint_seed, random_geometry};

/// `m` with every joint's geometry replaced by a random generic one (seeded per joint, as
/// [`crate::motion::realize`] does).
pub fn with_random_geometry(m: &Mechanism, seed: u64) -> Mechanism {
    let mut out = m.clone();
    for (i, j) in out.joints.iter_mut().enumerate() {
        let mut rng = SplitMix64::new(joint_seed(seed, i));
        j.geometry = random_geometry(j.kind, m.space, &mut rng);
    }
    out
}
