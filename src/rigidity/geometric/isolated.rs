//! Isolated motions: each body's own (fully isolated), the frame's spin and each rigid
//! cluster's (structurally isolated), with the axis of a single one.

use super::analysis::{Analysis, ZERO_TOL};
use super::dense::{orthonormalize, small_null, small_rank};
use super::jacobian::{Complements, complement};
use super::report::{Axis, IsolatedMotion};
use super::sparse_float;
use crate::mechanism::Space;
use crate::motion;
use nalgebra::{DMatrix, DVector};
use std::collections::{BTreeMap, BTreeSet};

/// The axis of the motion `t` of the dimensionless geometry `scale` gives, in file units.
pub(super) fn axis_of(space: Space, scale: &motion::Scale, t: &[f64]) -> Option<Axis> {
    let t = &scale.world_twist(space, t)[..];
    let round = |x: f64| {
        if x.abs() < 1e-12 {
            0.0
        } else {
            (x * 1e9).round() / 1e9
        }
    };
    let canon = |d: [f64; 3]| {
        let first = d.iter().find(|x| x.abs() > 1e-9).copied().unwrap_or(1.0);
        let s = if first < 0.0 { -1.0 } else { 1.0 };
        [round(d[0] * s), round(d[1] * s), round(d[2] * s)]
    };
    match space {
        Space::Spatial => {
            let w = nalgebra::Vector3::new(t[0], t[1], t[2]);
            let v = nalgebra::Vector3::new(t[3], t[4], t[5]);
            let scale = w.norm().max(v.norm());
            if scale == 0.0 {
                return None;
            }
            if w.norm() <= 1e-9 * scale {
                let d = v / v.norm();
                return Some(Axis {
                    kind: "translation".into(),
                    point: None,
                    direction: canon([d.x, d.y, d.z]),
                    pitch: None,
                });
            }
            let w2 = w.norm_squared();
            let p = w.cross(&v) / w2;
            let h = w.dot(&v) / w2;
            let d = w / w.norm();
            let screw = h.abs() > 1e-9;
            Some(Axis {
                kind: if screw { "screw" } else { "rotation" }.into(),
                point: Some([round(p.x), round(p.y), round(p.z)]),
                direction: canon([d.x, d.y, d.z]),
                pitch: screw.then(|| round(h)),
            })
        }
        Space::Planar => {
            let (w, vx, vy) = (t[0], t[1], t[2]);
            let scale = w.abs().max(vx.hypot(vy));
            if scale == 0.0 {
                return None;
            }
            if w.abs() <= 1e-9 * scale {
                let n = vx.hypot(vy);
                return Some(Axis {
                    kind: "translation".into(),
                    point: None,
                    direction: canon([vx / n, vy / n, 0.0]),
                    pitch: None,
                });
            }
            Some(Axis {
                kind: "rotation".into(),
                point: Some([round(-vy / w), round(vx / w), 0.0]),
                direction: [0.0, 0.0, 1.0],
                pitch: None,
            })
        }
        Space::Spherical => {
            let n = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
            if n == 0.0 {
                return None;
            }
            Some(Axis {
                kind: "rotation".into(),
                point: Some([0.0, 0.0, 0.0]),
                direction: canon([t[0] / n, t[1] / n, t[2] / n]),
                pitch: None,
            })
        }
    }
}

impl Analysis<'_> {
    /// Each body's fully isolated motions (the null space of its pairs' rows acting on it
    /// alone, its neighbours fixed) and the complement its unknowns live in.
    pub(super) fn fully_isolated(&self) -> (Vec<DMatrix<f64>>, Complements) {
        let (m, models, pairs, incident) = (self.m, self.models, &self.pairs, &self.incident);
        let (b, nb) = (self.b, self.nb);
        let mut iso: Vec<DMatrix<f64>> = vec![DMatrix::zeros(b, 0); nb];
        let mut comp = Complements::new(nb, b);
        // Isolated means undrivable: a motion across a cut of two or more joints that
        // constrain (a body on one joint moves by that joint's own DOF, which an input
        // drives). A body on an F joint (which constrains nothing) moves by that joint's DOF,
        // every motion of the body: none is isolated. Nor is one others reach the frame
        // through: the inputs beyond it drag it. The frame never moves.
        let cut: Vec<usize> = (0..nb)
            .map(|body| {
                if incident[body]
                    .iter()
                    .any(|&pi| models[pairs[pi].joint].rows.nrows() == 0)
                {
                    return 0;
                }
                let mut js: Vec<usize> = incident[body]
                    .iter()
                    .map(|&pi| pairs[pi].joint)
                    .filter(|&j| models[j].rows.nrows() > 0)
                    .collect();
                js.sort_unstable();
                js.dedup();
                js.len()
            })
            .collect();
        // Found only when a body has an isolated motion, which few have.
        let mut separating: Option<Vec<bool>> = None;
        for body in 0..nb {
            if cut[body] < 2 {
                iso[body] = DMatrix::zeros(b, 0);
                continue;
            }
            let rows: usize = incident[body]
                .iter()
                .map(|&pi| models[pairs[pi].joint].rows.nrows())
                .sum();
            let mut a = DMatrix::zeros(rows, b);
            let mut r0 = 0;
            for &pi in &incident[body] {
                let r = &models[pairs[pi].joint].rows;
                a.view_mut((r0, 0), (r.nrows(), b)).copy_from(r);
                r0 += r.nrows();
            }
            iso[body] = if rows == 0 {
                DMatrix::identity(b, b)
            } else {
                sparse_float::isolated(
                    m,
                    &self.scale,
                    &a,
                    self.local_rel,
                    incident[body].iter().map(|&pi| pairs[pi].joint),
                )
            };
            if iso[body].ncols() > 0
                && separating.get_or_insert_with(|| crate::mobility::separating_bodies(m))[body]
            {
                iso[body] = DMatrix::zeros(b, 0);
            }
            if iso[body].ncols() > 0 {
                comp.set(body, complement(&iso[body], b));
            }
        }
        (iso, comp)
    }

    /// The frame never moves. When it is itself held by two joints or more with a spin of its
    /// own (a frame bar between two S joints), that spin appears, frame fixed, as every other
    /// body turning about the same axis: a structurally isolated motion of the rest, set
    /// aside like the others. Its dimension, over the reduced Jacobian's groups `gbody`.
    pub(super) fn frame_spin(
        &self,
        gbody: &[usize],
        offsets: &[usize],
        sizes: &[usize],
        cols: usize,
    ) -> usize {
        // A frame motion that the other bodies' own isolated motions already make (one body
        // between the same two S joints as the frame spins about the same line) projects to
        // rounding noise: measured against the motion itself, not against the noise's own
        // norm, or the same spin is counted twice.
        let frame_motions: Vec<DVector<f64>> = self.iso[self.frame]
            .column_iter()
            .filter_map(|s| {
                let mut z = DVector::zeros(cols);
                for (g, &body) in gbody.iter().enumerate() {
                    z.rows_mut(offsets[g], sizes[g])
                        .copy_from(&(self.comp[body].transpose() * s));
                }
                (z.norm() > ZERO_TOL * s.norm()).then_some(z)
            })
            .collect();
        orthonormalize(frame_motions).len()
    }

    /// The joints (ids, in joint order) of some pairs.
    fn joint_ids(&self, ps: &mut dyn Iterator<Item = usize>) -> Vec<String> {
        let set: BTreeSet<usize> = ps.map(|pi| self.pairs[pi].joint).collect();
        set.into_iter()
            .map(|j| self.m.joints[j].id.clone())
            .collect()
    }

    /// Isolated motions: fully (per body) and structurally (the frame's spin, then per
    /// cluster of `clusters`), with the number structurally isolated.
    pub(super) fn isolated_motions(
        &self,
        clusters: &BTreeMap<usize, Vec<usize>>,
        frame_spin: usize,
    ) -> (Vec<IsolatedMotion>, usize) {
        let (m, nb, frame, iso) = (self.m, self.nb, self.frame, &self.iso);
        let id = |i: usize| m.body_id(i).to_string();
        let mut isolated_motions = Vec::new();
        for (body, own) in iso.iter().enumerate() {
            let k = own.ncols();
            if body == frame || k == 0 {
                continue;
            }
            isolated_motions.push(IsolatedMotion {
                kind: "fully".into(),
                bodies: vec![id(body)],
                joints: self.joint_ids(&mut self.incident[body].iter().copied()),
                dof: k,
                axis: if k == 1 {
                    axis_of(m.space, &self.scale, own.column(0).as_slice())
                } else {
                    None
                },
            });
        }
        let mut structurally = 0;
        if frame_spin > 0 {
            structurally += frame_spin;
            let comps = crate::mobility::Components::of(m);
            let frame_root = comps.root(frame);
            isolated_motions.push(IsolatedMotion {
                kind: "structurally".into(),
                bodies: (0..nb)
                    .filter(|&x| x != frame && comps.root(x) == frame_root)
                    .map(id)
                    .collect(),
                joints: self.joint_ids(&mut self.incident[frame].iter().copied()),
                dof: frame_spin,
                axis: if frame_spin == 1 {
                    axis_of(m.space, &self.scale, iso[frame].column(0).as_slice())
                } else {
                    None
                },
            });
        }
        for (c, boundary) in clusters.values().zip(self.boundaries(clusters)) {
            if let Some(motion) = self.cluster_motion(c, &boundary) {
                structurally += motion.dof;
                isolated_motions.push(motion);
            }
        }
        (isolated_motions, structurally)
    }

    /// The boundary pairs of every cluster, in one pass over the pairs (ascending).
    fn boundaries(&self, clusters: &BTreeMap<usize, Vec<usize>>) -> Vec<Vec<usize>> {
        let mut cluster_of = vec![usize::MAX; self.nb];
        for (ci, c) in clusters.values().enumerate() {
            for &x in c {
                cluster_of[x] = ci;
            }
        }
        let mut boundaries: Vec<Vec<usize>> = vec![Vec::new(); clusters.len()];
        for (pi, p) in self.pairs.iter().enumerate() {
            let (a, c) = (cluster_of[p.hub], cluster_of[p.other]);
            if a != c {
                boundaries[a].push(pi);
                boundaries[c].push(pi);
            }
        }
        boundaries
    }

    /// The structurally isolated motions of cluster `c` (its bodies) with its `boundary`
    /// pairs: the rigid motions its boundary joints allow (the rest fixed), modulo its
    /// bodies' own isolated motions; none for a single body, the frame's cluster or none.
    fn cluster_motion(&self, c: &[usize], boundary: &[usize]) -> Option<IsolatedMotion> {
        let (m, models, pairs, b) = (self.m, self.models, &self.pairs, self.b);
        if c.len() < 2 || c.contains(&self.frame) {
            return None;
        }
        // Isolated only across a cut of two or more constraining joints (one joint's own DOF
        // is driven by an input on it, an F joint's every motion).
        if boundary
            .iter()
            .any(|&pi| models[pairs[pi].joint].rows.nrows() == 0)
        {
            return None;
        }
        let mut cut_joints: Vec<usize> = boundary
            .iter()
            .map(|&pi| pairs[pi].joint)
            .filter(|&j| models[j].rows.nrows() > 0)
            .collect();
        cut_joints.sort_unstable();
        cut_joints.dedup();
        if cut_joints.len() < 2 {
            return None;
        }
        let rows: usize = boundary
            .iter()
            .map(|&pi| models[pairs[pi].joint].rows.nrows())
            .sum();
        let mut a = DMatrix::zeros(rows, b);
        let mut r0 = 0;
        for &pi in boundary {
            let r = &models[pairs[pi].joint].rows;
            a.view_mut((r0, 0), (r.nrows(), b)).copy_from(r);
            r0 += r.nrows();
        }
        let t = if rows == 0 {
            DMatrix::identity(b, b)
        } else {
            small_null(&a, self.local_rel)
        };
        if t.ncols() == 0 {
            return None;
        }
        // Modulo the bodies' own isolated motions.
        let mut stacked = DMatrix::zeros(b * c.len(), t.ncols());
        for (i, &body) in c.iter().enumerate() {
            let pc = &self.comp[body] * self.comp[body].transpose() * &t;
            stacked.view_mut((i * b, 0), (b, t.ncols())).copy_from(&pc);
        }
        let k = small_rank(&stacked, ZERO_TOL);
        if k == 0 {
            return None;
        }
        Some(IsolatedMotion {
            kind: "structurally".into(),
            bodies: c.iter().map(|&x| m.body_id(x).to_string()).collect(),
            joints: self.joint_ids(&mut boundary.iter().copied()),
            dof: k,
            axis: if k == 1 && t.ncols() == 1 {
                axis_of(m.space, &self.scale, t.column(0).as_slice())
            } else {
                None
            },
        })
    }
}
