//! Parts of two or more bodies held by balls (S, SP, SPSP) alone whose centres lie on one
//! line: the parts that can spin about that line with every equation independent, so that the
//! rank check sees no dependent equation there. One pass over the joints tells whether any
//! exists; only then does [`super::diagnose::set_aside_spins`] run the geometric analysis that
//! finds the spins (on the placements of `transform` it would run thousands of times).

use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::mobility::Components;
use std::collections::{BTreeMap, BTreeSet};

fn ball(k: JointType) -> bool {
    matches!(k, JointType::S | JointType::SP | JointType::SPSP)
}

/// Whether some part of two or more bodies is held by balls alone on one line (or lacking
/// geometry): joined among themselves by other joints (an S-P-S strut of cylinder and rod),
/// or hanging on the frame (the tetrahedron of S-S bars turns about its frame bar).
pub(super) fn ball_held_part(m: &Mechanism) -> bool {
    // Bodies joined by joints other than balls; the frame's component is held.
    let joined = Components::of_joints(m, (0..m.joints.len()).filter(|&j| !ball(m.joints[j].kind)));
    let frame = joined.root(m.frame);
    let mut struts = Centres::new(m, &joined);
    for j in m.joints.iter().filter(|j| ball(j.kind)) {
        let roots: Vec<usize> = j.bodies.iter().map(|&b| joined.root(b)).collect();
        for &r in &roots {
            if r != frame && roots.iter().any(|&q| q != r) {
                struts.add(r, j.geometry.origin);
            }
        }
    }
    // Bodies joined by the joints that do not touch the frame: what hangs on it.
    let away = Components::of_joints(
        m,
        (0..m.joints.len()).filter(|&j| !m.joints[j].bodies.contains(&m.frame)),
    );
    let mut hung = Centres::new(m, &away);
    for j in m.joints.iter().filter(|j| j.bodies.contains(&m.frame)) {
        for &b in j.bodies.iter().filter(|&&b| b != m.frame) {
            if ball(j.kind) {
                hung.add(away.root(b), j.geometry.origin);
            } else {
                hung.hold(away.root(b));
            }
        }
    }
    struts.any_on_a_line() || hung.any_on_a_line()
}

/// The ball centres holding each set of bodies (a component of `sets`, the frame left out);
/// `None` once a ball lacks geometry. Sets of one body are left out (a single body's spin is
/// an isolated freedom of its own), and so are sets some other joint holds.
struct Centres {
    size: Vec<usize>,
    of: BTreeMap<usize, Option<Vec<[f64; 3]>>>,
    held: BTreeSet<usize>,
}

impl Centres {
    fn new(m: &Mechanism, sets: &Components) -> Centres {
        let mut size = vec![0usize; m.bodies.len()];
        for b in (0..m.bodies.len()).filter(|&b| b != m.frame) {
            size[sets.root(b)] += 1;
        }
        Centres {
            size,
            of: BTreeMap::new(),
            held: BTreeSet::new(),
        }
    }

    /// A ball at `origin` holding set `r`.
    fn add(&mut self, r: usize, origin: Option<[f64; 3]>) {
        if self.size[r] < 2 {
            return;
        }
        let e = self.of.entry(r).or_insert_with(|| Some(Vec::new()));
        match (e.as_mut(), origin) {
            (Some(v), Some(o)) => v.push(o),
            _ => *e = None,
        }
    }

    /// Set `r` held by a joint other than a ball.
    fn hold(&mut self, r: usize) {
        self.held.insert(r);
    }

    /// Whether some set not otherwise held has its balls on one line.
    fn any_on_a_line(&self) -> bool {
        self.of
            .iter()
            .filter(|(r, _)| !self.held.contains(*r))
            .any(|(_, c)| c.as_ref().is_none_or(|c| collinear(c)))
    }
}

/// Whether the points lie on one line (two or fewer distinct ones do), to 1e-9 of their spread.
fn collinear(points: &[[f64; 3]]) -> bool {
    let d =
        |a: &[f64; 3], b: &[f64; 3]| nalgebra::Vector3::new(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    let Some(p) = points.first() else {
        return true;
    };
    let spread = points.iter().map(|q| d(p, q).norm()).fold(0.0f64, f64::max);
    let Some(q) = points
        .iter()
        .find(|q| d(p, q).norm() > 1e-9 * spread.max(f64::MIN_POSITIVE))
    else {
        return true;
    };
    let axis = d(p, q).normalize();
    points
        .iter()
        .all(|r| d(p, r).cross(&axis).norm() <= 1e-9 * spread)
}

#[cfg(test)]
mod tests {
    use super::collinear;

    #[test]
    fn points_on_one_line_and_off_it() {
        assert!(collinear(&[]));
        assert!(collinear(&[[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]));
        assert!(collinear(&[[0.0; 3], [1.0, 1.0, 0.0], [-2.0, -2.0, 0.0]]));
        assert!(!collinear(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]));
    }
}
