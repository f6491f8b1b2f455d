//! Which geometry each joint's model is built at: random generic geometry (seeded per joint),
//! or the file's made dimensionless; the models of a whole mechanism.

use super::model::{StackModel, fallback_model, joint_model, random_unit, stack_model};
use super::scale::scale_of;
use super::{JointModel, MotionError, modelled};
use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism, Space};
use crate::rng::{SplitMix64, indexed_seed};

/// Random generic geometry for a joint of `kind`: every field set (origin, unit axis, unit
/// axis2, unit normal, pitch), coordinates uniform in [−1, 1). Planar: z = 0 and axes in the
/// plane (an R axis is z). Spherical: the origin is the centre (0, 0, 0).
pub fn random_geometry(kind: JointType, space: Space, rng: &mut SplitMix64) -> Geometry {
    random_geometry_to(kind, space, rng, Drawn::All)
}

/// How far into [`random_geometry`]'s draws (origin, axis, axis2, normal, pitch, origin2, in
/// this order) a kind's model reads ([`full_twists`]): the fields after it need not be drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Drawn {
    Origin,
    Axis,
    Axis2,
    Normal,
    All,
}

/// The last field of [`random_geometry`] the model of `kind` in `space` reads. H reads the
/// pitch; SPSP, the contact models and the fallback model hash every field ([`mix_seed`]).
pub(super) fn model_reads(kind: JointType, space: Space) -> Drawn {
    use JointType::*;
    match (space, kind) {
        (Space::Spatial, S) => Drawn::Origin,
        (Space::Spatial, R | P | C | ER | SC) => Drawn::Axis,
        (Space::Spatial, U) => Drawn::Axis2,
        (Space::Spatial, PL | FP | SP | PC | CR) => Drawn::Normal,
        (Space::Planar, R | FP) | (Space::Spherical, FP) => Drawn::Origin,
        (Space::Planar, P) | (Space::Spherical, R) => Drawn::Axis,
        _ => Drawn::All,
    }
}

/// [`random_geometry`] drawn up to field `last` (the later fields `None`): the same stream,
/// so the fields drawn are bit for bit those of the whole geometry.
pub(super) fn random_geometry_to(
    kind: JointType,
    space: Space,
    rng: &mut SplitMix64,
    last: Drawn,
) -> Geometry {
    let mut origin = [rng.next_signed(), rng.next_signed(), rng.next_signed()];
    let draw = |rng: &mut SplitMix64, field: Drawn| -> Option<[f64; 3]> {
        (last >= field).then(|| random_unit(rng).into())
    };
    let mut axis = draw(rng, Drawn::Axis);
    let axis2 = draw(rng, Drawn::Axis2);
    let normal = draw(rng, Drawn::Normal);
    let (pitch, origin2) = if last == Drawn::All {
        let pitch = rng.next_signed();
        let origin2 = [rng.next_signed(), rng.next_signed(), rng.next_signed()];
        (Some(pitch), Some(origin2))
    } else {
        (None, None)
    };
    match space {
        Space::Spatial => {}
        Space::Planar => {
            origin[2] = 0.0;
            axis = axis.map(|axis| {
                if kind == JointType::R {
                    [0.0, 0.0, 1.0]
                } else {
                    let n = (axis[0] * axis[0] + axis[1] * axis[1]).sqrt().max(1e-12);
                    let axis = [axis[0] / n, axis[1] / n, 0.0];
                    if axis == [0.0, 0.0, 0.0] {
                        [1.0, 0.0, 0.0]
                    } else {
                        axis
                    }
                }
            });
        }
        Space::Spherical => origin = [0.0, 0.0, 0.0],
    }
    Geometry {
        origin: Some(origin),
        axis,
        axis2,
        origin2,
        normal,
        pitch,
        second: None,
    }
}

/// One model per joint at random generic geometry (the file geometry is ignored), seeded per
/// (seed, joint index). A joint no model fits (a kind invalid in the space, driven above the
/// grade: the reader rejects both) gets a generic model of its grade.
pub fn realize(m: &Mechanism, seed: u64) -> Vec<JointModel> {
    crate::par::map(m.joints.len(), |i| {
        let j = &m.joints[i];
        let s = indexed_seed(seed, i);
        let mut rng = SplitMix64::new(s);
        let g = random_geometry(j.kind, m.space, &mut rng);
        stack_model(j.kind, &g, m.space, j.driven)
            .unwrap_or_else(|_| fallback_model(j.kind, m.space, j.driven, s))
            .matrices()
    })
}

/// Build every joint model at the file's geometry (in parallel), keeping only the first error
/// in joint order.
pub(crate) fn check_file_geometry(m: &Mechanism) -> Result<(), MotionError> {
    let errors: Vec<Option<MotionError>> = crate::par::map(m.joints.len(), |i| {
        let j = &m.joints[i];
        if !modelled(j.kind, m.space) && j.geometry.is_empty() {
            return None;
        }
        joint_model(j.kind, &j.geometry, m.space, j.driven)
            .err()
            .map(|e| MotionError::InJoint {
                joint: j.id.clone(),
                source: Box::new(e),
            })
    });
    match errors.into_iter().flatten().next() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Joint `i`'s geometry in the random realization `seed` ([`geometries`]' choice, one joint at
/// a time: 10^6 joints need not hold them all).
pub(crate) fn random_joint_geometry(m: &Mechanism, seed: u64, i: usize) -> Geometry {
    random_geometry(
        m.joints[i].kind,
        m.space,
        &mut SplitMix64::new(indexed_seed(seed, i)),
    )
}

/// Joint `i`'s geometry in the random realization `seed` as its pair model reads it: the
/// fields of [`random_joint_geometry`] its model reads, the later ones not drawn.
pub(crate) fn random_pair_geometry(m: &Mechanism, seed: u64, i: usize) -> Geometry {
    let kind = m.joints[i].kind;
    let mut rng = SplitMix64::new(indexed_seed(seed, i));
    random_geometry_to(kind, m.space, &mut rng, model_reads(kind, m.space))
}

/// Every joint's geometry when the file's is used ([`geometries`]), made dimensionless
/// ([`scale_of`], the same as [`GeometryUsed::scale`]): the rank decisions made on it do not
/// depend on the length unit or on where the model sits.
pub(crate) fn file_geometries(m: &Mechanism) -> Vec<Geometry> {
    let scale = scale_of(m);
    m.joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            if !modelled(j.kind, m.space) && j.geometry.is_empty() {
                random_geometry(j.kind, m.space, &mut SplitMix64::new(indexed_seed(0, i)))
            } else {
                scale.geometry(&j.geometry)
            }
        })
        .collect()
}

/// The model of one binary pair of joint `index` of `m` at geometry `g` with `driven` of its
/// DOF fixed; a joint no model fits (the reader rejects such files) gets a generic model of
/// its grade, so analyses of mechanisms built in code never fail here.
pub fn pair_model(m: &Mechanism, index: usize, g: &Geometry, driven: u32) -> JointModel {
    pair_stack_model(m, index, g, driven).matrices()
}

/// [`pair_model`] on the stack.
pub(crate) fn pair_stack_model(
    m: &Mechanism,
    index: usize,
    g: &Geometry,
    driven: u32,
) -> StackModel {
    let j = &m.joints[index];
    stack_model(j.kind, g, m.space, driven)
        .unwrap_or_else(|_| fallback_model(j.kind, m.space, driven, indexed_seed(0, index)))
}

/// One model per joint at the file geometry made dimensionless ([`scale_of`]: every point
/// taken about the model's centre and every length divided by its characteristic length, so
/// the twists and rows are those of the same model in any length unit and at any place).
/// Kinds without a geometric model get the generic contact model seeded by the joint index.
/// Errors name the joint.
pub fn configure(m: &Mechanism) -> Result<Vec<JointModel>, MotionError> {
    let scale = scale_of(m);
    m.joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let g = if !modelled(j.kind, m.space) && j.geometry.is_empty() {
                random_geometry(j.kind, m.space, &mut SplitMix64::new(indexed_seed(0, i)))
            } else {
                scale.geometry(&j.geometry)
            };
            joint_model(j.kind, &g, m.space, j.driven).map_err(|e| MotionError::InJoint {
                joint: j.id.clone(),
                source: Box::new(e),
            })
        })
        .collect()
}
