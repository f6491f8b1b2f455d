//! Input values: `JOINT=VALUE[,VALUE...]` and `JOINT=FROM..TO:STEP`, and the driven targets
//! they give each pair.
//!
//! A value is measured from the file's configuration (value 0), for the second listed body
//! relative to the first, positive by the right-hand rule about the joint's axis. Angles are
//! in degrees unless written with `rad` (`0.5rad`); `deg` may be written; slides are lengths.

use super::newton::Targets;
use super::pose::Pose;
use super::residual::PositionModel;
use crate::mechanism::{InputSpecError, Mechanism, resolve_ref};

/// A value as written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Value {
    /// The number.
    pub number: f64,
    /// `Some(true)` for `rad`, `Some(false)` for `deg`, `None` when no unit was written.
    pub radians: Option<bool>,
}

/// Why an input value is invalid.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InputError {
    /// Bad syntax.
    #[error("invalid value `{text}`: {reason}")]
    Syntax {
        /// What was written.
        text: String,
        /// Why.
        reason: String,
    },
    /// Unknown joint.
    #[error(transparent)]
    Joint(#[from] InputSpecError),
    /// More values than the joint has DOF.
    #[error("joint `{joint}` has {grade} DOF but {given} value(s) were given")]
    TooMany {
        /// Joint id.
        joint: String,
        /// DOF.
        grade: usize,
        /// Values.
        given: usize,
    },
    /// A value too large to mean anything.
    #[error(
        "joint `{joint}`: value {index} ({text}) is out of range: at most 1e6 radians or 1e6 model sizes"
    )]
    OutOfRange {
        /// Joint id.
        joint: String,
        /// 1-based DOF.
        index: usize,
        /// The value.
        text: String,
    },
    /// A sweep with too many steps.
    #[error("the sweep `{text}` has {steps:.0e} steps; at most 100000")]
    TooManySteps {
        /// What was written.
        text: String,
        /// Its steps.
        steps: f64,
    },
    /// A unit on a slide.
    #[error("joint `{joint}`: value {index} is a slide (a length), not an angle: drop `{unit}`")]
    UnitOnSlide {
        /// Joint id.
        joint: String,
        /// 1-based DOF.
        index: usize,
        /// The unit written.
        unit: &'static str,
    },
}

fn parse_value(text: &str) -> Result<Value, InputError> {
    let t = text.trim();
    let (num, radians) = if let Some(n) = t.strip_suffix("rad") {
        (n, Some(true))
    } else if let Some(n) = t.strip_suffix("deg") {
        (n, Some(false))
    } else {
        (t, None)
    };
    let number: f64 = num.trim().parse().map_err(|_| InputError::Syntax {
        text: text.into(),
        reason: "not a number (write e.g. `30`, `0.5rad`, `0.01`)".into(),
    })?;
    if !number.is_finite() {
        return Err(InputError::Syntax {
            text: text.into(),
            reason: "not a finite number".into(),
        });
    }
    Ok(Value { number, radians })
}

/// Parse `JOINT=V[,V...]`: the joint index and the values.
pub fn parse_set(m: &Mechanism, text: &str) -> Result<(usize, Vec<Value>), InputError> {
    let (name, vals) = text.split_once('=').ok_or_else(|| InputError::Syntax {
        text: text.into(),
        reason: "expected JOINT=VALUE".into(),
    })?;
    let j = resolve_ref(m, name.trim())?;
    let values = vals
        .split(',')
        .map(parse_value)
        .collect::<Result<Vec<_>, _>>()?;
    let grade = m.joints[j].grade() as usize * m.joints[j].pairs() as usize;
    if values.len() > grade {
        return Err(InputError::TooMany {
            joint: m.joints[j].id.clone(),
            grade,
            given: values.len(),
        });
    }
    Ok((j, values))
}

/// A sweep `JOINT=FROM..TO:STEP`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// Joint index.
    pub joint: usize,
    /// First value.
    pub from: Value,
    /// Last value.
    pub to: Value,
    /// Step (its sign is taken from FROM..TO).
    pub step: Value,
}

impl Sweep {
    /// The values of the sweep, FROM to TO inclusive ([`parse_sweep`] allows at most 100 000
    /// steps).
    pub fn values(&self) -> Vec<Value> {
        let (a, b) = (self.from.number, self.to.number);
        let s = self.step.number.abs();
        let n = ((b - a).abs() / s + 1e-9).floor() as usize;
        let dir = if b >= a { 1.0 } else { -1.0 };
        (0..=n.min(100_000))
            .map(|i| Value {
                number: a + dir * s * i as f64,
                radians: self.from.radians,
            })
            .collect()
    }
}

/// Parse `JOINT=FROM..TO:STEP`.
pub fn parse_sweep(m: &Mechanism, text: &str) -> Result<Sweep, InputError> {
    let bad = |reason: &str| InputError::Syntax {
        text: text.into(),
        reason: reason.into(),
    };
    let (name, range) = text
        .split_once('=')
        .ok_or_else(|| bad("expected JOINT=FROM..TO:STEP"))?;
    let joint = resolve_ref(m, name.trim())?;
    let (span, step) = range
        .rsplit_once(':')
        .ok_or_else(|| bad("expected FROM..TO:STEP"))?;
    let (from, to) = span
        .split_once("..")
        .ok_or_else(|| bad("expected FROM..TO:STEP"))?;
    let (from, to, step) = (parse_value(from)?, parse_value(to)?, parse_value(step)?);
    if step.number == 0.0 {
        return Err(bad("STEP is zero"));
    }
    let steps = (to.number - from.number).abs() / step.number.abs();
    if steps.is_nan() || steps > 100_000.0 {
        return Err(InputError::TooManySteps {
            text: text.into(),
            steps,
        });
    }
    Ok(Sweep {
        joint,
        from,
        to,
        step,
    })
}

/// Make every joint with set values driven by at least that many DOF.
pub fn drive(m: &mut Mechanism, sets: &[(usize, Vec<Value>)]) {
    for (j, v) in sets {
        let joint = &mut m.joints[*j];
        joint.driven = joint.driven.max(v.len() as u32);
    }
}

/// Whether each driven DOF of joint `j` is an angle, in driven order.
pub fn angle_flags(model: &PositionModel, j: usize) -> Vec<bool> {
    let id = Pose::identity();
    model
        .pairs
        .iter()
        .enumerate()
        .filter(|(_, p)| p.joint == j)
        .flat_map(|(i, _)| model.pair_values(i, &id, &id).into_iter().map(|(_, a)| a))
        .collect()
}

/// The driven targets of every pair (model units): the set values, 0 (the file's
/// configuration) for driven DOF without one.
pub fn targets(
    m: &Mechanism,
    model: &PositionModel,
    sets: &[(usize, Vec<Value>)],
) -> Result<Targets, InputError> {
    let mut out: Targets = vec![Vec::new(); model.pairs.len()];
    let mut per_joint: Vec<Vec<f64>> = m
        .joints
        .iter()
        .map(|j| vec![0.0; j.driven as usize])
        .collect();
    for (j, values) in sets {
        let flags = angle_flags(model, *j);
        for (i, v) in values.iter().enumerate() {
            let angle = flags.get(i).copied().unwrap_or(false);
            let x = match (angle, v.radians) {
                (true, Some(true)) => v.number,
                (true, _) => v.number.to_radians(),
                (false, None) => v.number / model.scale,
                (false, Some(r)) => {
                    return Err(InputError::UnitOnSlide {
                        joint: m.joints[*j].id.clone(),
                        index: i + 1,
                        unit: if r { "rad" } else { "deg" },
                    });
                }
            };
            if x.is_nan() || x.abs() > 1e6 {
                return Err(InputError::OutOfRange {
                    joint: m.joints[*j].id.clone(),
                    index: i + 1,
                    text: format!("{:?}", v.number),
                });
            }
            if let Some(slot) = per_joint[*j].get_mut(i) {
                *slot = x;
            }
        }
    }
    for (p, pair) in model.pairs.iter().enumerate() {
        let k = m.joints[pair.joint].grade() as usize;
        let vals = &per_joint[pair.joint];
        let start = (pair.index * k).min(vals.len());
        let end = (start + pair.driven).min(vals.len());
        out[p] = vals[start..end].to_vec();
    }
    Ok(out)
}
