//! The Chebyshev-Gruebler-Kutzbach mobility count and the connectivity facts around it.

use crate::mechanism::Mechanism;
use serde::Serialize;

/// How the driven inputs compare with the mobility count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// As many inputs as the count: the mechanism can be determined.
    Equal,
    /// Fewer inputs than the count: some motion is not driven.
    Fewer,
    /// More inputs than the count: inputs fight each other or the chain.
    More,
}

/// The count itself: `count = B·Nm − Σ pairs_j·(B − k_j)`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Mobility {
    /// The Chebyshev-Gruebler-Kutzbach count.
    pub count: i64,
    /// Total driven DOF.
    pub inputs: u64,
    /// Inputs against the count.
    pub verdict: Verdict,
}

/// The mobility report of a mechanism.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct MobilityReport {
    /// Mechanism name.
    pub name: String,
    /// Motion space name.
    pub space: &'static str,
    /// DOF of a free body (6 or 3).
    pub b: u32,
    /// Number of bodies, frame included.
    pub bodies: usize,
    /// Movable bodies (Nm).
    pub movable: usize,
    /// Number of joints as written (a multiple joint is one joint).
    pub joints: usize,
    /// Number of binary pairs (a multiple joint of n bodies counts n − 1).
    pub pairs: u64,
    /// Constraints removed by the pairs: Σ pairs_j·(B − k_j).
    pub constraints: u64,
    /// Independent loops: pairs − bodies + connected components.
    pub loops: u64,
    /// The count and the inputs.
    pub mobility: Mobility,
    /// Bodies not linked to the frame through joints (ids as strings).
    pub disconnected: Vec<String>,
}

/// Compute the mobility report.
pub fn mobility(m: &Mechanism) -> MobilityReport {
    let b = m.b() as i64;
    // One pass over the joints (a million joints are hundreds of megabytes): the sums and
    // the components together.
    let (mut pairs, mut constraints, mut inputs) = (0u64, 0u64, 0u64);
    let mut components = Components::new(m.bodies.len());
    for j in &m.joints {
        pairs += j.pairs() as u64;
        constraints += j.pairs() as u64 * (b as u64).saturating_sub(j.grade() as u64);
        inputs += j.driven as u64;
        components.join(&j.bodies);
    }
    components.flatten();
    let count = b * m.movable() as i64 - constraints as i64;
    let verdict = match (inputs as i128).cmp(&(count as i128)) {
        std::cmp::Ordering::Equal => Verdict::Equal,
        std::cmp::Ordering::Less => Verdict::Fewer,
        std::cmp::Ordering::Greater => Verdict::More,
    };

    let frame_root = components.root(m.frame);
    let disconnected = (0..m.bodies.len())
        .filter(|&i| components.root(i) != frame_root)
        .map(|i| m.body_id(i).to_string())
        .collect();
    let loops = (pairs + components.count as u64).saturating_sub(m.bodies.len() as u64);

    MobilityReport {
        name: m.name.clone(),
        space: m.space.name(),
        b: m.b(),
        bodies: m.bodies.len(),
        movable: m.movable(),
        joints: m.joints.len(),
        pairs,
        constraints,
        loops,
        mobility: Mobility {
            count,
            inputs,
            verdict,
        },
        disconnected,
    }
}

/// The bodies through which other bodies reach the frame (the cut vertices of the body graph
/// on the frame's side; a joint of three bodies or more is a vertex of its own, so its bodies
/// are not cut vertices merely for sharing it). An isolated freedom of such a body is no
/// freedom to leave out: an input on a joint beyond it drives a body relative to it, and so
/// drags it.
pub fn separating_bodies(m: &Mechanism) -> Vec<bool> {
    let nb = m.bodies.len();
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(m.joints.len());
    let mut n = nb;
    for j in &m.joints {
        match j.bodies[..] {
            [a, c] => edges.push((a as u32, c as u32)),
            [_] | [] => {}
            _ => {
                edges.extend(j.bodies.iter().map(|&x| (n as u32, x as u32)));
                n += 1;
            }
        }
    }
    let mut sep = crate::graph::cut::separating(n, &edges, m.frame);
    sep.truncate(nb);
    sep
}

/// Connected components of the body graph (union-find, path halving).
pub struct Components {
    parent: Vec<usize>,
    /// Number of components.
    pub count: usize,
}

impl Components {
    /// Components of the bodies linked by joints.
    pub fn of(m: &Mechanism) -> Components {
        Components::of_joints(m, 0..m.joints.len())
    }

    /// Components of the bodies linked by the joints `joints` (indices) only.
    pub fn of_joints(m: &Mechanism, joints: impl Iterator<Item = usize>) -> Components {
        let mut c = Components::new(m.bodies.len());
        for j in joints {
            c.join(&m.joints[j].bodies);
        }
        c.flatten();
        c
    }

    /// `n` bodies, each alone.
    fn new(n: usize) -> Components {
        Components {
            parent: (0..n).collect(),
            count: n,
        }
    }

    /// Join the bodies of one joint.
    fn join(&mut self, bodies: &[usize]) {
        for w in bodies.windows(2) {
            self.union(w[0], w[1]);
        }
    }

    /// Every body straight to its root (a root is the smallest index of its component, so the
    /// parents of smaller indices are final already): `root` is then one step.
    fn flatten(&mut self) {
        for i in 0..self.parent.len() {
            self.parent[i] = self.parent[self.parent[i]];
        }
    }

    /// Representative of `i`'s component.
    pub fn root(&self, mut i: usize) -> usize {
        while self.parent[i] != i {
            i = self.parent[i];
        }
        i
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            // Smaller root wins so that the result does not depend on joint order.
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.parent[hi] = lo;
            self.count -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::JointType::*;
    use crate::mechanism::{BodyId, JointSpec, Space};

    fn mech(space: Space, joints: Vec<JointSpec>) -> Mechanism {
        Mechanism::from_parts("t", space, BodyId::Int(1), vec![], joints)
    }

    #[test]
    fn spatial_four_bar_rscp() {
        let m = mech(
            Space::Spatial,
            vec![
                JointSpec::new(R, 1, 2, 1),
                JointSpec::new(S, 2, 3, 0),
                JointSpec::new(C, 3, 4, 0),
                JointSpec::new(P, 1, 4, 0),
            ],
        );
        let r = mobility(&m);
        assert_eq!(r.mobility.count, 1);
        assert_eq!(r.mobility.verdict, Verdict::Equal);
        assert_eq!(r.loops, 1);
        assert!(r.disconnected.is_empty());
    }

    #[test]
    fn multiple_joint_counts_n_minus_one_pairs() {
        // Planar: ternary pin joining 2, 3 and 4 plus pins to ground.
        let mut j = JointSpec::new(R, 2, 3, 0);
        j.bodies.push(BodyId::Int(4));
        let m = mech(
            Space::Planar,
            vec![
                JointSpec::new(R, 1, 2, 1),
                j,
                JointSpec::new(R, 3, 1, 0),
                JointSpec::new(R, 4, 1, 0),
            ],
        );
        let r = mobility(&m);
        assert_eq!(r.pairs, 5);
        assert_eq!(r.mobility.count, 3 * 3 - 5 * 2);
        assert_eq!(r.loops, 2);
    }

    #[test]
    fn reports_disconnected_bodies() {
        let m = mech(
            Space::Planar,
            vec![JointSpec::new(R, 1, 2, 0), JointSpec::new(R, 3, 4, 0)],
        );
        let r = mobility(&m);
        assert_eq!(r.disconnected, ["3", "4"]);
        assert_eq!(r.mobility.verdict, Verdict::Fewer);
        assert_eq!(r.loops, 0);
    }
}
