//! The joint changes a repair may make, from the catalogue, at the joint's own geometry.
//!
//! A *relaxation* replaces a joint by a kind whose allowed twists contain the old ones (its
//! constraint rows a subspace of the old rows): R → C, U, S, SC, CR, SP; C → SC, CR, PC;
//! U → S, SC, SP; S → SC, SP; SC → SP; H → C; ER → S. The new kind keeps the joint's point and
//! axis; a direction it adds (U's second axis, SC's slide, SP's and CR's normals) is read from
//! the loads the self-stresses put on the joint, so that the rows removed are the ones the
//! stresses carry. A *stiffening* (S → U) blocks a ball's turn about one line: the spin of a
//! rod between two balls.

use crate::joint::JointType::{self, *};
use crate::mechanism::{Geometry, Space};
use crate::motion::{JointModel, Scale, joint_model};
use nalgebra::{DMatrix, Matrix3xX, Vector3};

/// One candidate kind for a joint: the kind, its geometry (file units) and its rows.
#[derive(Clone, Debug)]
pub(super) struct Proposal {
    /// The new kind.
    pub kind: JointType,
    /// Its geometry, file units.
    pub geometry: Geometry,
    /// Its constraint rows at the scaled geometry.
    pub model: JointModel,
}

/// The order in which kinds are preferred at equal rows removed: the ones simulators and CAD
/// offer most directly first (a hinge with a slide, two hinges, a ball, ...).
pub(super) fn preference(kind: JointType) -> usize {
    [C, U, S, SC, CR, PC, SP]
        .iter()
        .position(|k| *k == kind)
        .unwrap_or(usize::MAX)
}

/// The relaxations of a joint of `kind` at `g` (file units), their directions read from
/// `loads` (`6 × r` wrenches `(m_O; f)` at the scaled geometry). One arm per kind: the table
/// of relaxations reads best whole, so the function is longer than most.
pub(super) fn relaxations(
    kind: JointType,
    g: &Geometry,
    loads: &DMatrix<f64>,
    scale: &Scale,
) -> Vec<Proposal> {
    let (Some(p), u) = (g.origin, g.axis.map(unit)) else {
        return Vec::new();
    };
    let ps = Vector3::from(scale.point(p));
    let f = forces(loads);
    let m = moments_about(loads, &ps);
    let snaps: Vec<Vector3<f64>> = [g.axis, g.axis2, g.normal]
        .into_iter()
        .flatten()
        .map(unit)
        .chain((0..3).map(|i| Vector3::ith(i, 1.0)))
        .collect();
    let dir = |v: Option<Vector3<f64>>| v.map(|v| snap(v, &snaps));
    let top_force = dir(principal(&f, None, true));
    let least_force = dir(principal(&f, None, false));
    let mut out: Vec<(JointType, Geometry)> = Vec::new();
    let at = |origin: [f64; 3],
              axis: Option<Vector3<f64>>,
              axis2: Option<Vector3<f64>>,
              normal: Option<Vector3<f64>>| Geometry {
        origin: Some(origin),
        axis: axis.map(arr),
        axis2: axis2.map(arr),
        normal: normal.map(arr),
        ..Geometry::default()
    };
    match (kind, u) {
        (R, Some(u)) => {
            out.push((C, at(p, Some(u), None, None)));
            if let Some(b) = dir(principal(&m, Some(u), true)) {
                out.push((U, at(p, Some(u), Some(b), None)));
            }
            out.push((S, at(p, None, None, None)));
            for a in [Some(u), top_force].into_iter().flatten() {
                out.push((SC, at(p, Some(a), None, None)));
            }
            if let Some(s) = dir(principal(&f, Some(u), true)) {
                out.push((CR, at(p, Some(u), None, Some(u.cross(&s)))));
            }
            if let Some(n) = least_force {
                out.push((SP, at(p, None, None, Some(n))));
            }
        }
        (C, Some(u)) => {
            out.push((SC, at(p, Some(u), None, None)));
            if let Some(s) = dir(principal(&f, Some(u), true)) {
                out.push((CR, at(p, Some(u), None, Some(u.cross(&s)))));
                out.push((PC, at(p, Some(u), None, Some(u.cross(&s)))));
            }
        }
        (U, _) => {
            out.push((S, at(p, None, None, None)));
            if let Some(a) = top_force {
                out.push((SC, at(p, Some(a), None, None)));
            }
            if let Some(n) = least_force {
                out.push((SP, at(p, None, None, Some(n))));
            }
        }
        (S, _) => {
            if let Some(a) = top_force {
                out.push((SC, at(p, Some(a), None, None)));
            }
            if let Some(n) = least_force {
                out.push((SP, at(p, None, None, Some(n))));
            }
        }
        (SC, Some(a)) => {
            if let Some(s) = dir(principal(&f, Some(a), true)) {
                out.push((SP, at(p, None, None, Some(a.cross(&s)))));
            }
        }
        (H, Some(u)) => out.push((C, at(p, Some(u), None, None))),
        (ER, _) => out.push((S, at(p, None, None, None))),
        _ => {}
    }
    out.into_iter()
        .filter(|(_, g)| valid_directions(g))
        .filter_map(|(k, g)| {
            let model = joint_model(k, &scale.geometry(&g), Space::Spatial, 0).ok()?;
            Some(Proposal {
                kind: k,
                geometry: g,
                model,
            })
        })
        .collect()
}

/// A ball at `g` stiffened into a universal joint whose two axes are perpendicular to
/// `spin`: it blocks the turn about `spin` through the ball's centre and nothing else.
pub(super) fn stiffening(g: &Geometry, spin: Vector3<f64>, scale: &Scale) -> Option<Proposal> {
    let p = g.origin?;
    let axes: Vec<Vector3<f64>> = (0..3).map(|i| Vector3::ith(i, 1.0)).collect();
    let d = snap(unit(arr(spin)), &axes);
    let (e1, e2) = match axes.iter().position(|e| e.dot(&d).abs() == 1.0) {
        Some(k) => (axes[(k + 1) % 3], axes[(k + 2) % 3]),
        None => crate::motion::perpendicular_pair(&d),
    };
    let geometry = Geometry {
        origin: Some(p),
        axis: Some(arr(e1)),
        axis2: Some(arr(e2)),
        ..Geometry::default()
    };
    let model = joint_model(U, &scale.geometry(&geometry), Space::Spatial, 0).ok()?;
    Some(Proposal {
        kind: U,
        geometry,
        model,
    })
}

/// The part of `old`'s rows (`c × B`) that `new`'s rows do not keep, orthonormal (`d × B`);
/// `None` when `new`'s rows are not inside `old`'s (not a relaxation at this geometry).
pub(super) fn removed_rows(old: &DMatrix<f64>, new: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let inside = new - new * old.transpose() * old;
    if inside.norm() > 1e-8 * (1.0 + new.norm()) {
        return None;
    }
    let rest = old - old * new.transpose() * new;
    let d = old.nrows().checked_sub(new.nrows())?;
    if d == 0 {
        return None;
    }
    let svd = rest.svd(false, true);
    let vt = svd.v_t?;
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&x, &y| svd.singular_values[y].total_cmp(&svd.singular_values[x]));
    if svd.singular_values[order[d - 1]] < 0.5 {
        return None;
    }
    let rows: Vec<_> = order[..d].iter().map(|&i| vt.row(i).into_owned()).collect();
    Some(DMatrix::from_rows(&rows))
}

fn unit(v: [f64; 3]) -> Vector3<f64> {
    Vector3::from(v).normalize()
}

fn arr(v: Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Every direction of `g` finite and of unit length.
fn valid_directions(g: &Geometry) -> bool {
    [g.axis, g.axis2, g.normal]
        .into_iter()
        .flatten()
        .all(|v| v.iter().all(|x| x.is_finite()) && (Vector3::from(v).norm() - 1.0).abs() < 1e-6)
}

/// The force parts of the loads.
fn forces(loads: &DMatrix<f64>) -> Matrix3xX<f64> {
    Matrix3xX::from_fn(loads.ncols(), |i, k| loads[(3 + i, k)])
}

/// The moments of the loads about `p`: `m_p = m_O − p × f`.
fn moments_about(loads: &DMatrix<f64>, p: &Vector3<f64>) -> Matrix3xX<f64> {
    let mut out = Matrix3xX::zeros(loads.ncols());
    for k in 0..loads.ncols() {
        let mo = Vector3::new(loads[(0, k)], loads[(1, k)], loads[(2, k)]);
        let f = Vector3::new(loads[(3, k)], loads[(4, k)], loads[(5, k)]);
        out.set_column(k, &(mo - p.cross(&f)));
    }
    out
}

/// The most (or least) loaded direction of the 3-vectors `v`, perpendicular to `perp` when
/// given; `None` when the loads there are all zero.
fn principal(v: &Matrix3xX<f64>, perp: Option<Vector3<f64>>, most: bool) -> Option<Vector3<f64>> {
    let mut v = v.clone();
    if let Some(u) = perp {
        for mut c in v.column_iter_mut() {
            let along = c.dot(&u);
            c -= u * along;
        }
    }
    let gram = &v * v.transpose();
    let eig = gram.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let top = eig.eigenvalues[order[0]];
    if top <= 1e-18 {
        return None;
    }
    let pick = if most {
        order[0]
    } else {
        // The least loaded direction among those perpendicular to `perp`.
        *order
            .iter()
            .rev()
            .find(|&&i| perp.is_none_or(|u| eig.eigenvectors.column(i).dot(&u).abs() < 0.5))?
    };
    Some(eig.eigenvectors.column(pick).into_owned())
}

/// `v` replaced by the nearest of `options` (or its opposite, signed to agree with `v`) when
/// within 1e-7 rad of it; else `v` with components below 1e-12 set to zero. Written files
/// then say `[0, 0, 1]`, not `[1e-17, -3e-17, 1]`.
fn snap(v: Vector3<f64>, options: &[Vector3<f64>]) -> Vector3<f64> {
    for o in options {
        let c = v.dot(o);
        if v.cross(o).norm() < 1e-7 {
            return if c >= 0.0 { *o } else { -o };
        }
    }
    let w = v.map(|x| if x.abs() < 1e-12 { 0.0 } else { x });
    w.normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ball_is_a_relaxation_of_a_hinge_and_removes_two_moments() {
        let g = Geometry {
            origin: Some([1.0, 2.0, 0.0]),
            axis: Some([0.0, 0.0, 1.0]),
            ..Geometry::default()
        };
        let r = joint_model(R, &g, Space::Spatial, 0).unwrap();
        let s = joint_model(S, &g, Space::Spatial, 0).unwrap();
        let q = removed_rows(&r.rows, &s.rows).unwrap();
        assert_eq!(q.nrows(), 2);
        // A hinge is not a relaxation of a ball.
        assert!(removed_rows(&s.rows, &r.rows).is_none());
    }

    #[test]
    fn directions_snap_to_the_axes() {
        let axes: Vec<_> = (0..3).map(|i| Vector3::ith(i, 1.0)).collect();
        let v = Vector3::new(1e-10, -2e-10, -1.0).normalize();
        assert_eq!(snap(v, &axes), Vector3::new(0.0, 0.0, -1.0));
        let w = Vector3::new(1.0, 1.0, 0.0).normalize();
        assert!((snap(w, &axes) - w).norm() < 1e-15);
    }
}
