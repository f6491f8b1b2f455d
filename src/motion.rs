//! The joint-motion model: the relative twists each joint allows and the constraint rows it
//! imposes, at given (file) or random (generic) geometry.
//!
//! # Conventions
//! - Spatial (B = 6): a twist is `t = (ω; v_O)`, with `v_O` the velocity of the body point that
//!   is at the world origin. A revolute about unit `u` through `p` allows `(u; p × u)`, a slide
//!   along `u` allows `(0; u)`, a helix of pitch `h` allows `(u; p × u + h u)`.
//! - Planar (B = 3): `t = (ω_z; v_x, v_y)`, `v` again the velocity of the point at the origin;
//!   a revolute at `p` allows `(1; p_y, −p_x)`.
//! - Spherical (B = 3): `t = ω` (every axis passes through the fixed centre, the origin).
//! - A constraint row `r` acts on a twist by the plain dot product `r · t`. Rows are wrenches
//!   written `(m_O; f)` (moment about the origin first) so that the plain dot product with
//!   `(ω; v_O)` is the reciprocal (virtual power) product. `rows · twists = 0` always, and the
//!   rows are an orthonormal basis of the annihilator of `twists`.
//!
//! # Driven DOF
//! The allowed twists are listed in the driven-DOF order of `format.md` (translations before
//! rotations; C slide then turn; PL the two in-plane slides then the turn; U `axis` then
//! `axis2`; S turns about world x, y, z through the centre; F/FP translations then
//! rotations) and the first `driven` of them are removed: a driven DOF is fixed. Kinds whose
//! DOF have no name (the count-only kinds below, SPSP, and the fallback model of a joint no
//! model fits) keep a generic subspace instead: `k − driven` random combinations of their `k`
//! allowed twists, drawn from the geometry's bits (`kept_twists`). Dropping the first twists
//! of their basis, built by pivoting on unit vectors, kept a subspace fixed by the
//! construction: a random realization was degenerate with a fixed probability.
//!
//! # Joints without a standard geometry
//! - ER (slotted spherical) is defined here as a ball at `origin` whose rotation about `axis`
//!   is blocked: it allows the two rotations through `origin` about the axes perpendicular to
//!   `axis` (in the order of [`perpendicular_pair`]), and no translation.
//! - Count-only kinds (CPEP, L, EO, EPI, CTEP, RP, RD, CTRP, CBIP; and SP, SPSP, SC, PC, CR
//!   outside spatial mechanisms, which have a model in space: [`modelled`]) get the generic
//!   realization of a contact joint: `B − k` pure forces (lines). The first line passes
//!   through `origin` along `axis` when they are given; the other points and directions are
//!   pseudo-random, drawn from a generator seeded by the geometry's bits, so the same geometry
//!   always gives the same model. Such a joint has the right number of constraints in general
//!   position: enough for rank and mobility questions, not a model of a particular contact.
//! - FP in a spatial mechanism is treated like PL (normal `normal`, default z).
//!
//! # Multiple joints
//! A joint joining n > 2 bodies is n − 1 binary pairs hub→other (hub = first listed body), each
//! with the same model; pair equation `rows · (t_other − t_hub) = 0`; the frame's twist is 0.

use crate::joint::JointType;
use crate::mechanism::Space;
use nalgebra::DMatrix;

pub use crate::rng::SplitMix64;

mod batch;
pub mod exact;
mod gram;
pub mod kinds;
mod lacking;
mod model;
mod realize;
mod scale;
mod twists;

pub(crate) use batch::{Scratch, pair_rows_many};
pub use lacking::{Lacking, has_geometry, lacking};
pub(crate) use lacking::{lacking_of, lacks};
pub use model::joint_model;
pub(crate) use model::twist_shift;
pub(crate) use realize::{
    check_file_geometry, file_geometries, pair_stack_model, random_joint_geometry,
    random_pair_geometry,
};
pub use realize::{configure, pair_model, random_geometry, realize};
pub(crate) use scale::lever;
pub use scale::{FILE_TOL_FACTOR, Scale, scale_of, written_direction_precision, written_precision};
pub use twists::perpendicular_pair;

/// The motion model of one joint (of one binary pair of it).
#[derive(Clone, Debug, PartialEq)]
pub struct JointModel {
    /// Constraint rows, `(B − k + driven) × B`: an orthonormal basis of the annihilator of
    /// `twists` (see the module conventions).
    pub rows: DMatrix<f64>,
    /// Allowed relative twists once the driven DOF are fixed, `B × (k − driven)`, columns in
    /// driven-DOF order (the driven ones removed).
    pub twists: DMatrix<f64>,
}

/// Why a joint model cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// A geometry field this joint kind needs is missing.
    #[error("a {kind} joint needs `{field}` for geometric analysis")]
    MissingField {
        /// Joint kind code.
        kind: &'static str,
        /// The missing field.
        field: &'static str,
    },
    /// A direction is zero (or not finite).
    #[error("`{field}` of a {kind} joint is zero or not finite")]
    ZeroVector {
        /// Joint kind code.
        kind: &'static str,
        /// The field.
        field: &'static str,
    },
    /// The geometry makes the joint's twists dependent (e.g. a U with parallel axes).
    #[error("a {kind} joint has degenerate geometry: {reason}")]
    Degenerate {
        /// Joint kind code.
        kind: &'static str,
        /// Why.
        reason: &'static str,
    },
    /// The kind cannot be modelled in this motion space.
    #[error("a {kind} joint cannot be modelled in a {space} mechanism")]
    InvalidInSpace {
        /// Joint kind code.
        kind: &'static str,
        /// The space name.
        space: &'static str,
    },
    /// More driven DOF than the joint's grade.
    #[error("a {kind} joint has {driven} driven DOF but grade {grade}")]
    DrivenAboveGrade {
        /// Joint kind code.
        kind: &'static str,
        /// Driven DOF.
        driven: u32,
        /// Grade.
        grade: u32,
    },
    /// The file's configuration misses closure grossly (more than
    /// [`crate::position::closure::GROSS`] × the model size): it is not assembled.
    #[error(
        "the configuration written is not assembled: joint `{joint}` is open by {residual:.3e}, more than {limit:.1e} (1e-2 x model size; a gap in file lengths, a turn of e rad counted as e x model size){others}; `mbsa assemble FILE > closed.toml` projects it onto the constraints (least change)"
    )]
    NotClosed {
        /// The worst joint.
        joint: String,
        /// Its residual (file lengths).
        residual: f64,
        /// The gross limit.
        limit: f64,
        /// The other joints over the limit, in words (empty when none).
        others: String,
    },
    /// The closure of a joint with `second` geometry cannot be evaluated.
    #[error("closure check: {0}")]
    Closure(ModelError),
    /// An error located at a joint of a mechanism.
    #[error("joint `{joint}`: {source}")]
    InJoint {
        /// Joint id.
        joint: String,
        /// The error.
        #[source]
        source: Box<MotionError>,
    },
}

/// Why a mechanism has no position model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A geometry field the joint needs is missing.
    #[error("joint `{joint}`: a {kind} joint needs `{field}` for the position level")]
    MissingField {
        /// Joint id.
        joint: String,
        /// Kind code.
        kind: &'static str,
        /// Field.
        field: &'static str,
    },
    /// A direction is zero or not finite, or a number is not finite.
    #[error("joint `{joint}`: `{field}` is zero or not finite")]
    BadVector {
        /// Joint id.
        joint: String,
        /// Field.
        field: &'static str,
    },
    /// The kind has no position model (generic contact kinds, or not in this space).
    #[error("joint `{joint}`: a {kind} joint has no position model in a {space} mechanism")]
    NoModel {
        /// Joint id.
        joint: String,
        /// Kind code.
        kind: &'static str,
        /// Space.
        space: &'static str,
    },
    /// The mechanism is too large for a dense analysis.
    #[error("{bodies} bodies: the dense position analysis handles at most {limit}")]
    TooLarge {
        /// Bodies.
        bodies: usize,
        /// Limit.
        limit: usize,
    },
    /// Driving this kind is not supported.
    #[error("joint `{joint}`: driving a {kind} joint is not supported by the position level")]
    NotDrivable {
        /// Joint id.
        joint: String,
        /// Kind code.
        kind: &'static str,
    },
}

/// Whether a kind has no geometric model of its own (count only) and gets the generic contact
/// realization.
pub fn is_contact(kind: JointType) -> bool {
    use JointType::*;
    matches!(kind, CPEP | L | EO | EPI | CTEP | RP | RD | CTRP | CBIP)
}

/// Whether a kind has a geometric model in this motion space: contact kinds with geometry
/// (SP, SPSP, SC, PC, CR) have one in space only; the count-only kinds ([`is_contact`]) never.
fn modelled(kind: JointType, space: Space) -> bool {
    use JointType::*;
    match kind {
        SP | SPSP | SC | PC | CR => space == Space::Spatial,
        k => !is_contact(k),
    }
}

#[cfg(test)]
mod tests;
