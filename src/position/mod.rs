//! The position level: joint constraints at a configuration, closure check and assembly,
//! solving the positions group by group, and finite mobility.
//!
//! The file's geometry is the reference configuration: every body at the identity pose, each
//! joint's features (points, axes) attached to its bodies. A [`Configuration`] gives a pose
//! per body (the frame stays at the identity). `docs/algorithms.md` ("Position level")
//! describes the equations and algorithms.
//!
//! - [`residual`]: the equations of each joint and their Jacobians w.r.t. body twists.
//! - [`closure`]: [`check_closure`], [`assemble`], [`moved_mechanism`].
//! - [`solve`]: the group-by-group schedule, [`solve_groups`] and the global reference
//!   [`solve_global`].
//! - [`sparse`]: the sparse Gauss–Newton the global reference uses (block Cholesky of the
//!   normal equations in a minimum-degree order).
//! - [`finite`]: the finite-mobility test, [`finite_mobility()`].
//! - [`inputs`]: input values (`JOINT=30`, `JOINT=0.5rad`, sweeps).
//! - [`sweep`]: one input stepped through a range, stopped at a dead point or a branch change.

pub mod closure;
pub mod finite;
pub mod inputs;
pub mod newton;
pub mod pose;
pub mod realize;
pub mod residual;
pub mod solve;
pub mod sparse;
mod sparse_qr;
pub mod sweep;
mod track;

pub use closure::{
    Closure, ClosureStatus, JointResidual, assemble, check_closure, closure_of, file_closure,
    moved_mechanism, tolerance_for,
};
pub use finite::{
    FiniteMobility, FiniteOptions, Verdict, caveat_rounded, finite_mobility,
    finite_mobility_of_file,
};
pub use newton::{NewtonOptions, NewtonOutcome, System, Targets};
pub use pose::{Configuration, Pose, PoseReport};
pub use realize::{Redrawn, with_random_geometry, with_random_geometry_away_from_folds};
pub use residual::{ModelError, PositionModel};
pub use solve::{
    JointValues, OrderedGroup, Schedule, Solution, SolveError, SolveOrder, SolveReport, Step,
    StepReport, joint_values, schedule, solve_global, solve_groups,
};
