//! Which geometry an analysis works at: the configuration written in the file (checked for
//! closure first) or a random generic realization of the joint types, and the words every
//! report uses to say which.
//!
//! This sits above the joint model ([`crate::motion`]) and the position level
//! ([`crate::position`]): choosing the file's configuration means checking that it closes.

use crate::mechanism::{Geometry, Mechanism};
use crate::motion::{
    FILE_TOL_FACTOR, JointModel, MotionError, Scale, check_file_geometry, configure,
    file_geometries, lacking, lacking_of, lacks, lever, random_joint_geometry, realize, scale_of,
    written_direction_precision, written_precision,
};
use crate::position::{self, Closure, ClosureStatus, closure};

/// Where the joint geometry of an analysis comes from (what the user asked for).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometrySource {
    /// The file's `origin`/`axis`/... fields (an error names a joint lacking one).
    File,
    /// A random generic realization of the joint types, seeded.
    Random {
        /// The seed.
        seed: u64,
    },
    /// The file's geometry when every joint has it, else a random realization with this seed.
    Auto {
        /// The seed of the random realization, if one is used.
        seed: u64,
    },
}

impl Default for GeometrySource {
    fn default() -> GeometrySource {
        GeometrySource::Auto { seed: 0 }
    }
}

/// The geometry an analysis used, as every report states it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GeometryUsed {
    /// `file` or `random`.
    pub mode: &'static str,
    /// The seed of a random realization.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// The configuration analysed, in words.
    pub configuration: String,
    /// Why this geometry, and which joints lack theirs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// File geometry: how precisely its numbers are known (±, from `--tolerance`, the file's
    /// `precision` key or the digits written, in that order); 0 when every number is exact.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub precision: Option<f64>,
    /// File geometry: the precision of the direction numbers (axes, normals) alone, which the
    /// lever arm multiplies ([`file_threshold`]); `--tolerance` sets both.
    #[serde(skip)]
    pub direction_precision: Option<f64>,
    /// File geometry: the centre and characteristic length that make it dimensionless before
    /// the rank decisions ([`scale_of`]); `None` at a random realization (already
    /// dimensionless).
    #[serde(skip)]
    pub scale: Option<Scale>,
    /// File geometry: whether the configuration written satisfies every joint (only joints
    /// with `second` geometry can miss it); the first-order analyses use the first body's
    /// geometry of an open joint.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub closure: Option<Closure>,
}

impl GeometryUsed {
    /// Whether the file's geometry was used.
    pub fn is_file(&self) -> bool {
        self.mode == "file"
    }
}

/// The joint models of a mechanism at the chosen geometry, and what was chosen.
#[derive(Clone, Debug)]
pub struct Realization {
    /// One model per joint (driven DOF removed), in joint order.
    pub models: Vec<JointModel>,
    /// The geometry used.
    pub used: GeometryUsed,
}

/// The joint models at `source` (with `precision` overriding the written digits in file
/// mode). `Auto` takes the file geometry when every joint has the fields its kind needs
/// ([`lacking`] is empty), else a random realization with a note naming the joints.
pub fn realization(
    m: &Mechanism,
    source: GeometrySource,
    precision: Option<f64>,
) -> Result<Realization, MotionError> {
    let used = choose(m, source, precision)?;
    let models = match used.seed {
        Some(seed) => realize(m, seed),
        None => configure(m)?,
    };
    Ok(Realization { models, used })
}

/// Which geometry `source` gives for `m` (see [`realization`]), without building the joint
/// models; the file geometry is checked (an error names the joint) when it is chosen.
pub fn choose(
    m: &Mechanism,
    source: GeometrySource,
    precision: Option<f64>,
) -> Result<GeometryUsed, MotionError> {
    let random = |seed: u64, note: Option<String>| GeometryUsed {
        mode: "random",
        seed: Some(seed),
        configuration: "a random generic realization of the joint types".into(),
        note,
        precision: None,
        direction_precision: None,
        scale: None,
        closure: None,
    };
    let file = |note: Option<String>| -> Result<GeometryUsed, MotionError> {
        // Every joint model must build at the file's geometry.
        check_file_geometry(m)?;
        let (precision, directions) = match precision {
            Some(p) => (p, p),
            None => (written_precision(m), written_direction_precision(m)),
        };
        Ok(GeometryUsed {
            mode: "file",
            seed: None,
            configuration: "the configuration written in the file".into(),
            note,
            precision: Some(precision),
            direction_precision: Some(directions),
            scale: Some(scale_of(m)),
            closure: Some(file_closure(m, precision)?),
        })
    };
    match source {
        GeometrySource::Random { seed } => Ok(random(seed, None)),
        GeometrySource::File => {
            let lack = lacking(m);
            let note = (!lack.is_empty()).then(|| {
                format!(
                    "no geometric model for {}: generic contact lines used",
                    lack.iter()
                        .map(|l| l.describe())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            });
            file(note)
        }
        GeometrySource::Auto { seed } if !m.joints.iter().any(|j| lacks(m, j)) => {
            match file(Some("every joint has its geometry".into())) {
                Ok(r) => Ok(r),
                // A configuration that is not assembled is the user's to fix, not a reason
                // to analyse another geometry.
                Err(e @ MotionError::NotClosed { .. }) => Err(e),
                Err(e) => Ok(random(
                    seed,
                    Some(format!(
                        "file geometry unusable ({e}); random realization used"
                    )),
                )),
            }
        }
        GeometrySource::Auto { seed } => {
            // The first few named, the rest counted (an entry per joint cost 10^6 strings).
            const SHOWN: usize = 5;
            let mut names: Vec<String> = m
                .joints
                .iter()
                .filter_map(|j| lacking_of(m, j))
                .take(SHOWN)
                .map(|l| l.describe())
                .collect();
            let total = m.joints.iter().filter(|j| lacks(m, j)).count();
            if total > SHOWN {
                names.push(format!("{} more", total - SHOWN));
            }
            Ok(random(
                seed,
                Some(format!(
                    "{total} joint(s) lack geometry: {}; `--geometry file` needs it",
                    names.join(", ")
                )),
            ))
        }
    }
}

/// The closure of the file's configuration ([`position::file_closure`]) at the
/// tolerance its numbers' `precision` gives; a gross miss is [`MotionError::NotClosed`].
fn file_closure(m: &Mechanism, precision: f64) -> Result<Closure, MotionError> {
    let scale = crate::position::residual::model_size(m);
    let tol = closure::tolerance_for(scale, precision);
    let c = position::file_closure(m, Some(tol)).map_err(MotionError::Closure)?;
    if c.status == ClosureStatus::Broken {
        let over: Vec<&closure::JointResidual> = c
            .worst(usize::MAX)
            .into_iter()
            .filter(|j| j.residual > c.gross_limit)
            .collect();
        let others = match over.len() {
            0 | 1 => String::new(),
            n => format!(
                " ({} other joint(s) too: {}{})",
                n - 1,
                over[1..]
                    .iter()
                    .take(closure::LISTED - 1)
                    .map(|j| format!("`{}` {:.3e}", j.joint, j.residual))
                    .collect::<Vec<_>>()
                    .join(", "),
                if n > closure::LISTED { ", ..." } else { "" }
            ),
        };
        return Err(MotionError::NotClosed {
            joint: over.first().map(|j| j.joint.clone()).unwrap_or_default(),
            residual: c.max_residual,
            limit: c.gross_limit,
            others,
        });
    }
    Ok(c)
}

/// The geometry of every joint at `source` (see [`realization`]): the file's, or a random
/// generic realization drawn per (seed, joint index) as [`realize`] does. Analyses that build
/// models per binary pair with their own driven share ([`pair_model`]) start from these.
pub fn geometries(
    m: &Mechanism,
    source: GeometrySource,
    precision: Option<f64>,
) -> Result<(Vec<Geometry>, GeometryUsed), MotionError> {
    let used = choose(m, source, precision)?;
    let geoms = match used.seed {
        Some(seed) => (0..m.joints.len())
            .map(|i| random_joint_geometry(m, seed, i))
            .collect(),
        None => file_geometries(m),
    };
    Ok((geoms, used))
}

/// The absolute rank threshold the file's rounding allows, at the dimensionless geometry the
/// rank decisions see ([`GeometryUsed::scale`]): a point rounded by δ (file units) moves a
/// joint's unit constraint rows by about δ/Lc, a direction rounded by δ_d by about
/// δ_d·(1 + L) with lever arm L ([`crate::motion::lever`], in units of Lc); twice the sum (see
/// [`FILE_TOL_FACTOR`]). The same model written in metres or millimetres, near the world
/// origin or far from it, gets the same threshold. `None` at a random realization.
pub fn file_threshold(m: &Mechanism, used: &GeometryUsed) -> Option<f64> {
    let delta = used.precision.filter(|&d| d > 0.0)?;
    let directions = used.direction_precision.unwrap_or(delta);
    let scale = used.scale.unwrap_or(Scale::IDENTITY);
    Some(FILE_TOL_FACTOR * (delta / scale.length + directions * lever(m, &scale)))
}
