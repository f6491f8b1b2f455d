//! The restrictions of a run (`--on`, `--grounded`, `--keep`, `--exclude`) resolved on the
//! original joints.

use super::{TransformError, TransformOptions};
use crate::mechanism::{InputSpecError, Mechanism, resolve_ref};

/// The restrictions resolved on the original joints.
pub(super) struct Rules {
    /// May joint j be driven (type, exclusion)? `grounded` is checked per binary pair.
    pub(super) allowed: Vec<bool>,
    pub(super) grounded: bool,
    /// Driven DOF joint j must keep at least.
    pub(super) keep: Vec<u32>,
    pub(super) notes: Vec<String>,
    /// Whether the analyses use no geometry or a random realization (drawn joint by joint):
    /// then the independent parts of an expansion may be analysed apart ([`ExpansionParts`]).
    /// The file's geometry is made dimensionless by the whole mechanism's scale, so a part
    /// alone would not be analysed at the same configuration.
    pub(super) random: bool,
}

impl Rules {
    /// The rules of one part, whose joints are `joints` of the whole.
    pub(super) fn restrict(&self, joints: &[usize]) -> Rules {
        Rules {
            allowed: joints.iter().map(|&j| self.allowed[j]).collect(),
            grounded: self.grounded,
            keep: joints.iter().map(|&j| self.keep[j]).collect(),
            notes: Vec::new(),
            random: self.random,
        }
    }

    pub(super) fn of(m: &Mechanism, opts: &TransformOptions) -> Result<Rules, TransformError> {
        let n = m.joints.len();
        let mut allowed = vec![true; n];
        let mut notes = Vec::new();
        if let Some(on) = &opts.on {
            for (a, j) in allowed.iter_mut().zip(&m.joints) {
                *a &= on.contains(&j.kind);
            }
            let codes: Vec<&str> = on.iter().map(|k| k.code()).collect();
            notes.push(format!(
                "only joints of type {} may be driven",
                codes.join(", ")
            ));
        }
        if opts.grounded {
            notes.push("only joints to the frame may be driven".into());
        }
        let mut excluded = vec![false; n];
        if let Some(spec) = &opts.exclude {
            for r in &spec.refs {
                excluded[resolve_ref(m, &r.text)?] = true;
            }
            let ids: Vec<&str> = (0..n)
                .filter(|&j| excluded[j])
                .map(|j| m.joints[j].id.as_str())
                .collect();
            if !ids.is_empty() {
                notes.push(format!("never driven: {}", ids.join(", ")));
            }
        }
        let mut keep = vec![0u32; n];
        if let Some(spec) = &opts.keep {
            for (j, c) in spec.resolve(m)? {
                keep[j] = keep[j].saturating_add(c);
            }
            for (j, joint) in m.joints.iter().enumerate() {
                let max = joint.grade() * joint.pairs();
                if keep[j] > max {
                    return Err(InputSpecError::AboveGrade {
                        joint: joint.id.clone(),
                        driven: u64::from(keep[j]),
                        grade: max,
                    }
                    .into());
                }
                if keep[j] > 0 && excluded[j] {
                    return Err(TransformError::KeepExcluded {
                        joint: joint.id.clone(),
                    });
                }
            }
            let kept: Vec<String> = (0..n)
                .filter(|&j| keep[j] > 0)
                .map(|j| format!("{}:{}", m.joints[j].id, keep[j]))
                .collect();
            if !kept.is_empty() {
                notes.push(format!("kept inputs: {}", kept.join(", ")));
            }
        }
        for (a, x) in allowed.iter_mut().zip(&excluded) {
            *a &= !x;
        }
        Ok(Rules {
            allowed,
            grounded: opts.grounded,
            keep,
            notes,
            random: false,
        })
    }
}
