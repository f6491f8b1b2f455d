//! `mbsa rigid` as one call: counting, geometry and the finite mobility at the file's
//! configuration, as asked ([`analyze`]). The command line and the Python package both call
//! it, so the two give the same reports.

use super::{geometric, pebble};
use crate::budget::{Budget, BudgetExceeded};
use crate::geometry::GeometrySource;
use crate::mechanism::Mechanism;
use crate::motion::MotionError;
use crate::position::{self, FiniteMobility, SolveError};

/// Which analyses [`analyze`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Methods {
    /// Counting (pebble game) and geometry (constraint Jacobian rank).
    #[default]
    Both,
    /// Counting only: generic rigidity from the topology.
    Counting,
    /// Geometry only: true mobility, redundant constraints, isolated DOF.
    Geometric,
}

/// Options of [`analyze`] (`mbsa rigid`'s flags).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct RigidOptions {
    /// Which analyses.
    pub methods: Methods,
    /// Count driven inputs as constraints (default: the chain alone, every input released).
    pub with_inputs: bool,
    /// Also the finite mobility at the file's configuration.
    pub finite: bool,
    /// Geometry of the geometric analysis.
    pub geometry: GeometrySource,
    /// How precisely the file's numbers are known (default: from the digits written).
    pub precision: Option<f64>,
    /// Limits of every step.
    pub budget: Budget,
}

/// The reports [`analyze`] made: those asked for.
#[derive(Clone, Debug, Default)]
pub struct RigidReports {
    /// Counting (pebble game).
    pub counting: Option<pebble::PebbleReport>,
    /// Geometry (constraint Jacobian).
    pub geometric: Option<geometric::GeometricReport>,
    /// Finite mobility at the file's configuration.
    pub finite: Option<FiniteMobility>,
}

/// Why [`analyze`] gave no reports.
#[derive(Debug, thiserror::Error)]
pub enum RigidError {
    /// The joint geometry cannot be modelled.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// A step would exceed the budget.
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
    /// The finite mobility was asked without the file's geometry to move from.
    #[error(
        "--finite needs the file's geometry (a configuration to move from); some joints lack it \
         or `--geometry random` was asked"
    )]
    FiniteNeedsFileGeometry,
    /// The finite-mobility test failed (the file's configuration could not be assembled).
    #[error(transparent)]
    Finite(SolveError),
}

/// Rigid subsystems of `m` (its inputs already applied): counting and geometry, and the
/// finite mobility when asked. Without `with_inputs` every driven input is released first.
pub fn analyze(m: &Mechanism, opts: &RigidOptions) -> Result<RigidReports, RigidError> {
    let released;
    let m = if opts.with_inputs {
        m
    } else {
        let mut c = m.clone();
        for j in &mut c.joints {
            j.driven = 0;
        }
        released = c;
        &released
    };
    let mut out = RigidReports::default();
    if matches!(opts.methods, Methods::Both | Methods::Counting) {
        let p = pebble::PebbleOptions {
            with_inputs: opts.with_inputs,
        };
        out.counting = Some(pebble::analyze_within(m, &p, &opts.budget)?);
    }
    if matches!(opts.methods, Methods::Both | Methods::Geometric) {
        let g = geometric::GeometricOptions {
            geometry: opts.geometry,
            precision: opts.precision,
            check_finite: false,
        };
        out.geometric = Some(geometric::analyze_within(m, &g, &opts.budget).map_err(
            |e| match e {
                geometric::GeometricError::Motion(e) => RigidError::Motion(e),
                geometric::GeometricError::Budget(e) => RigidError::Budget(e),
            },
        )?);
    }
    if opts.finite {
        out.finite = Some(finite(m, opts, out.geometric.as_ref())?);
    }
    Ok(out)
}

/// The finite mobility at the file's configuration, with the caveat of rounded numbers.
fn finite(
    m: &Mechanism,
    opts: &RigidOptions,
    geometric: Option<&geometric::GeometricReport>,
) -> Result<FiniteMobility, RigidError> {
    let file_geometry =
        geometric.is_none_or(|g| g.geometry_used.is_file()) && crate::motion::has_geometry(m);
    if !file_geometry {
        return Err(RigidError::FiniteNeedsFileGeometry);
    }
    // An open file is assembled first (the report's first note says so).
    let scale = position::residual::model_size(m);
    let tolerance = opts.precision.map(|p| position::tolerance_for(scale, p));
    let mut f = position::finite_mobility_of_file(
        m,
        tolerance,
        &position::FiniteOptions {
            budget: opts.budget,
            ..Default::default()
        },
    )
    .map_err(|e| match e {
        SolveError::Budget(b) => RigidError::Budget(b),
        e => RigidError::Finite(e),
    })?;
    // Rounded numbers: the test takes them as exact, the geometric analysis as known to their
    // precision; where the two disagree the finite answer is not decided (and says why).
    let precision = opts
        .precision
        .unwrap_or_else(|| crate::motion::written_precision(m));
    let at_precision = geometric.filter(|_| !opts.with_inputs).map(|g| g.mobility);
    position::caveat_rounded(&mut f, precision, at_precision);
    if opts.with_inputs {
        // The test follows the mechanism's own motions: its inputs, fixed in the counting and
        // the geometry above, move here.
        f.notes.insert(
            0,
            "the finite mobility is the mechanism's own, its inputs free: `--with-inputs` \
             applies to the counting and the geometry, not to this test"
                .into(),
        );
    }
    Ok(f)
}
