//! The restrictions of a run (`--on`, `--grounded`, `--keep`, `--exclude`) resolved on the
//! original joints.

use super::{BaseMode, TransformError, TransformOptions};
use crate::mechanism::{InputSpecError, Mechanism, resolve_ref};

/// The restrictions resolved on the original joints.
pub(super) struct Rules {
    /// May joint j be driven (type, exclusion)? `grounded` is checked per binary pair.
    pub(super) allowed: Vec<bool>,
    pub(super) grounded: bool,
    /// Driven DOF joint j must keep at least.
    pub(super) keep: Vec<u32>,
    /// Ids of the free joints to the frame driven in full ([`BaseMode`]).
    pub(super) fixed_base: Vec<String>,
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
            fixed_base: Vec::new(),
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
        let fixed_base = fix_bases(m, opts.base, &excluded, &mut keep, &mut notes)?;
        for (a, x) in allowed.iter_mut().zip(&excluded) {
            *a &= !x;
        }
        Ok(Rules {
            allowed,
            grounded: opts.grounded,
            keep,
            fixed_base,
            notes,
            random: false,
        })
    }
}

/// The free joints to the frame that `mode` drives in full: each gets its grade as kept
/// inputs, and a note names them. [`BaseMode::Auto`] takes those that are the only joint
/// between their part (bodies connected without the frame) and the frame, and leaves an
/// excluded one alone (no placement then exists, as without the rule); [`BaseMode::Fixed`]
/// takes every one, and an excluded one is an error.
fn fix_bases(
    m: &Mechanism,
    mode: BaseMode,
    excluded: &[bool],
    keep: &mut [u32],
    notes: &mut Vec<String>,
) -> Result<Vec<String>, TransformError> {
    let free: Vec<usize> = (0..m.joints.len())
        .filter(|&j| m.free_to_frame(j))
        .collect();
    let chosen: Vec<usize> = match mode {
        BaseMode::Free => Vec::new(),
        BaseMode::Fixed => free,
        BaseMode::Auto => {
            let to_frame = frame_joints_per_part(m);
            let part = part_roots(m);
            free.into_iter()
                .filter(|&j| !excluded[j])
                .filter(|&j| {
                    let x = m.joints[j].bodies.iter().find(|&&x| x != m.frame);
                    x.is_some_and(|&x| to_frame[part[x]] == 1)
                })
                .collect()
        }
    };
    for &j in &chosen {
        if excluded[j] {
            return Err(TransformError::KeepExcluded {
                joint: m.joints[j].id.clone(),
            });
        }
        keep[j] = keep[j].max(m.joints[j].grade());
    }
    if chosen.is_empty() {
        return Ok(Vec::new());
    }
    let named: Vec<String> = chosen
        .iter()
        .map(|&j| format!("{} ({} DOF)", m.joints[j].id, m.joints[j].grade()))
        .collect();
    notes.push(match mode {
        BaseMode::Fixed => format!(
            "base taken as driven in full (--fix-base), its pose given as in a fixed-base \
             analysis: {}; the other inputs are placed",
            named.join(", ")
        ),
        _ => format!(
            "floating base taken as driven in full, its pose given as in a fixed-base analysis: \
             {}; no other input fixes its pose, so every determined placement drives it in full \
             (--keep-free-base searches without this)",
            named.join(", ")
        ),
    });
    Ok(chosen.iter().map(|&j| m.joints[j].id.clone()).collect())
}

/// The part (a root body) of each body: bodies joined by joints that do not touch the frame.
fn part_roots(m: &Mechanism) -> Vec<usize> {
    let mut up: Vec<usize> = (0..m.bodies.len()).collect();
    fn root(up: &mut [usize], mut x: usize) -> usize {
        while up[x] != x {
            up[x] = up[up[x]];
            x = up[x];
        }
        x
    }
    for j in m.joints.iter().filter(|j| !j.bodies.contains(&m.frame)) {
        let Some((&first, rest)) = j.bodies.split_first() else {
            continue;
        };
        for &y in rest {
            let (a, b) = (root(&mut up, first), root(&mut up, y));
            if a != b {
                up[a.max(b)] = a.min(b);
            }
        }
    }
    (0..up.len()).map(|x| root(&mut up, x)).collect()
}

/// How many joints join each part (indexed by its root, [`part_roots`]) to the frame.
fn frame_joints_per_part(m: &Mechanism) -> Vec<usize> {
    let part = part_roots(m);
    let mut n = vec![0usize; m.bodies.len()];
    for j in m.joints.iter().filter(|j| j.bodies.contains(&m.frame)) {
        let mut roots: Vec<usize> = j
            .bodies
            .iter()
            .filter(|&&x| x != m.frame)
            .map(|&x| part[x])
            .collect();
        roots.sort_unstable();
        roots.dedup();
        for r in roots {
            n[r] += 1;
        }
    }
    n
}
