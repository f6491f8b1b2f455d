//! The report of the geometric rigidity analysis: the counts, the joints and bodies they
//! concern, the loops and the numerical facts of the rank decisions.

use crate::geometry::GeometryUsed;
use crate::mechanism::Space;
use serde::Serialize;

/// A joint with a weight (participation in the redundant constraints).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointWeight {
    /// Joint id.
    pub joint: String,
    /// Participation, the largest normalised to 1.
    pub weight: f64,
}

/// A joint with a number of DOF.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct JointCount {
    /// Joint id.
    pub joint: String,
    /// DOF.
    pub dof: usize,
}

/// The axis of a one-dimensional motion.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Axis {
    /// `rotation`, `translation` or `screw`.
    pub kind: String,
    /// A point of the axis (the one nearest the origin); none for a translation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    /// Unit direction.
    pub direction: [f64; 3],
    /// Pitch (screw only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch: Option<f64>,
}

/// Isolated motions of one body or one rigid cluster.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IsolatedMotion {
    /// `fully` (one body) or `structurally` (a rigid cluster).
    pub kind: String,
    /// The bodies moving (ids).
    pub bodies: Vec<String>,
    /// The joints allowing it (the body's joints, or the cluster's boundary joints).
    pub joints: Vec<String>,
    /// Number of independent isolated motions.
    pub dof: usize,
    /// Their axis when there is exactly one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<Axis>,
}

/// A rigid cluster.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RigidCluster {
    /// Body ids in body order.
    pub bodies: Vec<String>,
    /// Whether it contains the frame.
    pub frame: bool,
}

/// One loop of the minimum cycle basis.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct LoopInfo {
    /// Joints around the loop.
    pub joints: Vec<String>,
    /// Bodies around the loop.
    pub bodies: Vec<String>,
    /// Rank of the loop's joint twists (6 general spatial, 3 planar or spherical).
    pub spatiality: usize,
    /// Redundant constraints of the loop alone (B − spatiality).
    pub overconstraint: usize,
}

/// Numerical facts about the rank decisions.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Numeric {
    /// Relative tolerance used (times σ_max).
    pub tolerance: f64,
    /// Estimate of the largest singular value.
    pub sigma_max: f64,
    /// Smallest pivot kept, relative to σ_max.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smallest_kept: Option<f64>,
    /// Largest pivot dropped, relative to σ_max.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub largest_dropped: Option<f64>,
    /// Warning when a decision lies within a factor 100 of the threshold.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
    /// At a random realization: the rank was decided exactly (over GF(2^61 − 1)).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exact: Option<String>,
}

/// The result of [`analyze`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GeometricReport {
    /// Mechanism name.
    pub name: String,
    /// Motion space.
    pub space: Space,
    /// B.
    pub b: u32,
    /// The frame's id.
    pub frame: String,
    /// Geometry used: `file` or `random (seed N)`.
    pub geometry: String,
    /// Why this geometry (for `Auto`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub geometry_note: Option<String>,
    /// The geometry and configuration analysed, in full.
    pub geometry_used: GeometryUsed,
    /// Number of bodies (frame included).
    pub bodies: usize,
    /// Constraint rows.
    pub rows: usize,
    /// Unknowns (B per movable body).
    pub columns: usize,
    /// Rank of the constraint Jacobian.
    pub rank: usize,
    /// Chebyshev-Gruebler-Kutzbach count with the driven DOF fixed.
    pub count: i64,
    /// True instantaneous mobility (nullity, frame fixed, driven DOF fixed).
    pub mobility: usize,
    /// Redundant constraints N = rows − rank.
    pub redundant: usize,
    /// Joints taking part in the redundant constraints, by weight.
    pub redundant_joints: Vec<JointWeight>,
    /// Joints taking part in the redundant constraints whose weights were not computed (in
    /// file order): those carrying a self-stress of a rigid block analysed exactly whose
    /// floating-point self-stresses did not fit in what the rest of the analysis left of the
    /// budget, found from the exact ones over GF(2^61 − 1). Empty (absent from JSON)
    /// whenever every weight was computed; else `weights_note` says why and how to get them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub redundant_joints_unweighted: Vec<String>,
    /// Locked joint DOF (zero in every motion), total.
    pub locked: usize,
    /// Driven DOF held in the analysis (`rigid --with-inputs`): a freedom the inputs fix is
    /// locked too, so the table says which way to tell the two apart.
    #[serde(skip)]
    pub driven: u64,
    /// Locked DOF per joint (joints with none omitted).
    pub locked_joints: Vec<JointCount>,
    /// Isolated DOF, fully + structurally.
    pub isolated: usize,
    /// Fully isolated DOF.
    pub fully_isolated: usize,
    /// Structurally isolated DOF.
    pub structurally_isolated: usize,
    /// The isolated motions.
    pub isolated_motions: Vec<IsolatedMotion>,
    /// mobility − isolated.
    pub proper_mobility: i64,
    /// Rigid clusters with two or more bodies or the frame (singletons omitted).
    pub rigid: Vec<RigidCluster>,
    /// Minimum cycle basis.
    pub loops: Vec<LoopInfo>,
    /// Why loops are missing, if they are.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub loops_note: Option<String>,
    /// When the floating-point self-stresses the joints' weights come from are not null
    /// vectors to within rounding (‖yᵀA‖ above [`STRESS_RESIDUAL`] · σ_max, or the file's
    /// precision at its own geometry): the weights are approximate, and by how much. When
    /// some were not computed (`redundant_joints_unweighted`): why, and the flag that gets
    /// them (both sentences when both apply).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weights_note: Option<String>,
    /// Finite-mobility check status.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finite_note: Option<String>,
    /// Rank-decision facts.
    pub numeric: Numeric,
}
