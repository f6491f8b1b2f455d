//! The search for joint changes: greedy on the self-stress basis, from several first steps.
//!
//! Each step takes, among the joints the stresses load (neither driven nor multiple nor
//! changed already), the relaxation that removes the most rows while the stresses reach every
//! row it removes (the rank, so the motion, is kept: [`super::stress`]); at equal rows, the
//! joint the stresses load most, then the kind simulators offer most directly
//! ([`changes::preference`]), then the file's joint order. The weights are compared to six
//! significant digits, so rounding does not decide a tie. A step removes its rows from the
//! stresses; the search stops when none is left or no change removes any.

use super::changes::{self, Proposal};
use super::stress::{Stresses, smallest_singular};
use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use crate::motion::Scale;
use nalgebra::DMatrix;
use std::cmp::Reverse;

/// Below this smallest singular value of `Q Λ`, the stresses do not reach a removed row.
const REACH: f64 = 1e-6;

/// One change the search makes.
#[derive(Clone, Debug)]
pub(super) struct Step {
    /// Joint index.
    pub joint: usize,
    /// The new kind and geometry.
    pub proposal: Proposal,
    /// Rows removed.
    pub rows: usize,
    /// How much the stresses loaded the joint (before the step).
    pub weight: f64,
}

/// A step with what it removes from the stresses.
struct Option_ {
    step: Step,
    q_loads: DMatrix<f64>,
}

/// The possible steps at the current stresses, best first.
fn options(
    m: &Mechanism,
    st: &Stresses,
    done: &[usize],
    scale: &Scale,
    meter: &mut Meter,
) -> Result<Vec<Option_>, BudgetExceeded> {
    let r = st.basis.ncols();
    let mut out = Vec::new();
    for (j, joint) in m.joints.iter().enumerate() {
        if done.contains(&j) || joint.driven > 0 {
            continue;
        }
        let Some(loads) = st.loads(j) else { continue };
        let weight = st.weight(j);
        if weight < 1e-9 {
            continue;
        }
        meter.charge(64 * r as u64 + 64)?;
        for proposal in changes::relaxations(joint.kind, &joint.geometry, &loads, scale) {
            let Some(q) = changes::removed_rows(&st.rows[j], &proposal.model.rows) else {
                continue;
            };
            if q.nrows() > r {
                continue;
            }
            let q_loads = &q * &loads;
            if smallest_singular(&q_loads) < REACH {
                continue;
            }
            out.push(Option_ {
                step: Step {
                    joint: j,
                    rows: q.nrows(),
                    weight,
                    proposal,
                },
                q_loads,
            });
        }
    }
    out.sort_by_key(|o| {
        (
            Reverse(o.step.rows),
            Reverse(six_digits(o.step.weight)),
            changes::preference(o.step.proposal.kind),
            o.step.joint,
        )
    });
    Ok(out)
}

/// `x > 0` to six significant digits, as an integer key.
fn six_digits(x: f64) -> i64 {
    if x <= 0.0 {
        return 0;
    }
    let e = x.log10().floor() as i32;
    let mantissa = (x / 10f64.powi(e) * 1e5).round() as i64;
    (e as i64 + 400) * 1_000_000 + mantissa
}

/// The greedy search from the stresses `st`, its first step the `first`-th best (`None`
/// when there is no such first step). Returns the steps and the stresses left.
pub(super) fn greedy(
    m: &Mechanism,
    mut st: Stresses,
    first: usize,
    scale: &Scale,
    meter: &mut Meter,
) -> Result<Option<(Vec<Step>, usize)>, BudgetExceeded> {
    let mut steps: Vec<Step> = Vec::new();
    let mut done: Vec<usize> = Vec::new();
    let mut pick = first;
    while st.basis.ncols() > 0 {
        let mut opts = options(m, &st, &done, scale, meter)?;
        if opts.is_empty() {
            break;
        }
        if pick >= opts.len() {
            return Ok(None);
        }
        let o = opts.swap_remove(pick);
        pick = 0;
        st.restrict(&o.q_loads);
        done.push(o.step.joint);
        steps.push(o.step);
    }
    if steps.is_empty() && first > 0 {
        return Ok(None);
    }
    Ok(Some((steps, st.basis.ncols())))
}

/// The first steps the search may start from that change different joints: the indices of
/// the best option of each of the first `k` distinct joints.
pub(super) fn first_steps(
    m: &Mechanism,
    st: &Stresses,
    scale: &Scale,
    k: usize,
    meter: &mut Meter,
) -> Result<Vec<usize>, BudgetExceeded> {
    let opts = options(m, st, &[], scale, meter)?;
    let mut seen = Vec::new();
    let mut out = Vec::new();
    for (i, o) in opts.iter().enumerate() {
        if out.len() == k {
            break;
        }
        // Only the steps as good as the best: another start that removes fewer rows makes a
        // longer repair, never a better one.
        if o.step.rows < opts[0].step.rows {
            break;
        }
        if !seen.contains(&o.step.joint) {
            seen.push(o.step.joint);
            out.push(i);
        }
    }
    if out.is_empty() {
        out.push(0);
    }
    Ok(out)
}
