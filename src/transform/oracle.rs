//! The exact rank of a placement's whole system at the analysis's random realization: the
//! decision made for every placement of an expansion before its analysis.

use super::null_space::{JacobianRows, block_null_vectors, jacobian};
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::exact::Fp;
use crate::mechanism::Mechanism;
use crate::structure::Analysis;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Null vectors of the constraint system an [`Oracle`] keeps at most (its per-placement test is
/// a dense rank of about `6 f` rows by this many columns).
pub(super) const ORACLE_NULLITY: usize = 64;

/// What the exact rank at the analysis's random realization (over GF(p), as the rank check's
/// large blocks and the geometric rigidity use it) decides for every placement of one
/// expansion, before its analysis. A placement `P` is determined exactly when its square
/// system `M_P` (every pair's constraint rows and its inputs' rows, frame fixed) is
/// nonsingular on the reduced unknowns; that needs `M_P` of full row rank (reducing the
/// unknowns of a body by its isolated freedom keeps the rank). With `J` the constraint rows
/// alone: `rank M_P = rank J + rank` of the inputs' rows on the null space of `J`.
/// - `J` has dependent rows: no placement is determined (each `M_P` has them too).
/// - `J` has full row rank and a small null space (`mbsa` keeps `N ≤` [`ORACLE_NULLITY`]
///   random null vectors, which span it except with probability `N / p`): a placement is
///   rejected when its inputs' rows on those vectors have rank below `f`, and otherwise
///   certified: its analysis skips the rank check's factorizations
///   ([`structure::analyze_placement`]).
/// - Otherwise the analysis decides alone, as before.
///
/// Each decision is the generic rank (probability of error at most rows / p), which the
/// floating-point rank check also finds except on a block so badly conditioned that its
/// tolerance takes it for singular.
pub(super) enum Oracle {
    Undecided,
    Reject,
    /// A large null space: undecided, until a placement is rejected; then the exact rank of
    /// `J` ([`Oracle::dependent`]) may reject every other one at once.
    Later {
        seed: u64,
    },
    Motions {
        seed: u64,
        /// Column of each body's first unknown (`usize::MAX`: the frame).
        col: Vec<usize>,
        /// Random null vectors of `J`.
        v: Vec<Vec<crate::exact::Fp>>,
        /// The lines of a joint's rows on the null vectors, by (joint, driven DOF), as the
        /// placements ask for them ([`Lines`]).
        lines: Lines,
    },
}

/// Each (joint, driven DOF)'s rows on an [`Oracle::Motions`]' null vectors, kept as the
/// placements of an expansion ask for them: a joint's exact rows are a function of the joint,
/// the realization and its driven DOF, and every placement that drives it so reads the same
/// lines. At most [`LINES_KEPT`] entries are kept (then it starts over: memory stays bounded).
#[derive(Default)]
pub(super) struct Lines(Mutex<HashMap<(usize, u32), JointLines>>);

/// One (joint, driven DOF)'s lines, shared by the placements that read them.
type JointLines = Arc<[Vec<Fp>]>;

/// Entries a [`Lines`] keeps before it starts over.
const LINES_KEPT: usize = 1 << 14;

impl Lines {
    /// The lines of joint `q` with `d` driven DOF, made by `make` when not kept.
    fn get(&self, q: usize, d: u32, make: impl FnOnce() -> Vec<Vec<Fp>>) -> JointLines {
        let kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(l) = kept.get(&(q, d)) {
            return Arc::clone(l);
        }
        drop(kept);
        let l: JointLines = make().into();
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if kept.len() >= LINES_KEPT {
            kept.clear();
        }
        kept.insert((q, d), Arc::clone(&l));
        l
    }
}

impl Oracle {
    /// The oracle of `m` (an expansion, binary joints, no inputs) given its first analysis `a`
    /// (no inputs either). `cols_minus_rows` is the count's nullity of `J`.
    pub(super) fn of(
        m: &Mechanism,
        a: &Analysis,
        full_analyses: bool,
        meter: &mut Meter,
    ) -> Result<Oracle, BudgetExceeded> {
        use crate::exact::Factor;
        let Some(seed) = a.geometry.as_ref().and_then(|g| g.seed) else {
            return Ok(Oracle::Undecided);
        };
        let b = m.b() as usize;
        if m.joints.iter().any(|j| j.bodies.len() != 2) {
            return Ok(Oracle::Undecided);
        }
        // A dependency the analysis named among the constraint rows alone.
        if named_dependency(m, a, seed, meter)? {
            return Ok(Oracle::Reject);
        }
        // The count's nullity of J: unknowns less constraint rows.
        let movable = m.bodies.len().saturating_sub(1);
        let cons: usize = m
            .joints
            .iter()
            .map(|j| b.saturating_sub(j.grade() as usize))
            .sum();
        let ncols = movable * b;
        if cons > ncols {
            return Ok(Oracle::Undecided);
        }
        // A large null space: no per-placement test, but dependent rows of `J` still reject
        // every placement; that is decided once a placement is rejected ([`Oracle::Later`],
        // [`Oracle::dependent`]), so a mechanism with one placement (a serial chain, each
        // expansion of a shared joint) never pays for it.
        if ncols - cons > ORACLE_NULLITY {
            return Ok(if full_analyses {
                Oracle::Undecided
            } else {
                Oracle::Later { seed }
            });
        }
        meter.charge(50 * (m.bodies.len() + m.joints.len()) as u64)?;
        // A basis of the null space by back-substitution along the routing's blocks, when
        // they are nonsingular (then `J` has full row rank); else the whole factorization.
        // Either basis gives the same decisions: [`Oracle::decide`] uses only the rank of
        // the inputs' rows on the vectors, the same for any basis of the null space.
        if let Some((col, v)) = block_null_vectors(m, seed) {
            return Ok(Oracle::Motions {
                seed,
                col,
                v,
                lines: Lines::default(),
            });
        }
        let (j, col) = jacobian(m, seed);
        let nrows = j.nrows();
        let f = Factor::new(&j);
        if f.rank() < nrows {
            return Ok(Oracle::Reject);
        }
        let n = f.nullity();
        if n > ORACLE_NULLITY {
            return Ok(Oracle::Undecided);
        }
        let mut rng = crate::rng::SplitMix64::new(seed ^ 0x7A4E_5F0B_0C1E_0000);
        let v = f.random_null_vectors(n, &mut rng);
        Ok(Oracle::Motions {
            seed,
            col,
            v,
            lines: Lines::default(),
        })
    }

    /// For [`Oracle::Later`], once a placement was rejected: [`Oracle::Reject`] when the
    /// constraint rows `J` of `m` are dependent (then no placement is determined: the
    /// random families, whose redundancy among the constraints the input-free analysis
    /// cannot see, its under-determined block being too large to check), else
    /// [`Oracle::Undecided`]. The exact rank runs within a work and memory cap of its own;
    /// past it the analyses decide, as before. Its work is charged to `meter`.
    pub(super) fn dependent(&self, m: &Mechanism, budget: &Budget, meter: &mut Meter) -> Oracle {
        let Oracle::Later { seed } = self else {
            return Oracle::Undecided;
        };
        let b = m.b() as usize;
        let units = 50 * (m.bodies.len() + m.joints.len()) as u64;
        if meter.charge(units).is_err() {
            return Oracle::Undecided;
        }
        // The rows made one at a time as the factorization reads them (the same rows as
        // `jacobian`'s, so the same factorization), unless their indices outgrow `u32`.
        let rows = JacobianRows::of(m, *seed);
        let j = match rows {
            Some(_) => None,
            None => Some(jacobian(m, *seed).0),
        };
        let nrows = match (&rows, &j) {
            (Some(r), _) => crate::exact::sparse::Rows::nrows(r),
            (_, Some(j)) => j.nrows(),
            _ => 0,
        };
        let entries = (nrows * 2 * b + m.bodies.len() * b) as u64;
        let cap = Budget {
            max_work: budget.max_work.min(400 * entries + 1_000_000),
            max_memory_bytes: budget.max_memory_bytes.min(1 << 30),
            ..*budget
        };
        let mut own = cap.meter("the exact rank of the constraints");
        let what = || "the exact rank of the constraints".to_string();
        let mut limits = crate::exact::sparse::Limits {
            budget: &cap,
            meter: &mut own,
            what: &what,
        };
        // Only the rank is read: the factor's records (its null space) are not kept.
        let r = match (rows, j) {
            (Some(r), _) => crate::exact::Factor::rank_of_rows_within(r, &mut limits),
            (_, Some(j)) => crate::exact::Factor::rank_of_rows_within(j, &mut limits),
            _ => return Oracle::Undecided,
        };
        if meter.charge(own.used()).is_err() {
            return Oracle::Undecided;
        }
        match r {
            Ok(rank) if rank < nrows => Oracle::Reject,
            _ => Oracle::Undecided,
        }
    }

    /// Work units of [`Oracle::decide`] on placement `w`: its inputs' rows on the null
    /// vectors (`f × N` numbers and their rank).
    pub(super) fn work(&self, w: &[(usize, u32)]) -> u64 {
        match self {
            Oracle::Motions { v, .. } => {
                let f: u64 = w.iter().map(|&(_, n)| u64::from(n)).sum();
                f.saturating_mul(v.len() as u64).saturating_mul(8) + 1
            }
            _ => 1,
        }
    }

    /// `Some(false)`: placement `w` (units per pair of `m`) is not determined; `Some(true)`:
    /// its whole system has full row rank; `None`: the analysis decides.
    pub(super) fn decide(&self, m: &Mechanism, w: &[(usize, u32)]) -> Option<bool> {
        use crate::exact::dense;
        use crate::motion::exact as models;
        match self {
            Oracle::Undecided | Oracle::Later { .. } => None,
            Oracle::Reject => Some(false),
            Oracle::Motions {
                seed,
                col,
                v,
                lines,
            } => {
                let b = m.b() as usize;
                let f: usize = w.iter().map(|&(_, n)| n as usize).sum();
                if f > v.len() {
                    return Some(false);
                }
                let mut stacked: Vec<JointLines> = Vec::with_capacity(w.len());
                for &(q, d) in w {
                    let [x, y] = m.joints[q].bodies[..] else {
                        return None;
                    };
                    stacked.push(lines.get(q, d, || {
                        let rows = models::joint_rows(m, q, *seed, d);
                        (0..rows.nrows())
                            .map(|r| {
                                v.iter()
                                    .map(|vl| {
                                        let mut s = Fp::ZERO;
                                        for k in 0..b {
                                            let ty = if col[y] == usize::MAX {
                                                Fp::ZERO
                                            } else {
                                                vl[col[y] + k]
                                            };
                                            let tx = if col[x] == usize::MAX {
                                                Fp::ZERO
                                            } else {
                                                vl[col[x] + k]
                                            };
                                            s += rows[(r, k)] * (ty - tx);
                                        }
                                        s
                                    })
                                    .collect()
                            })
                            .collect()
                    }));
                }
                let stacked: Vec<&Vec<Fp>> = stacked.iter().flat_map(|l| l.iter()).collect();
                if stacked.is_empty() {
                    return Some(f == 0);
                }
                let a = nalgebra::DMatrix::from_fn(stacked.len(), v.len(), |i, l| stacked[i][l]);
                Some(dense::rank(&a) == f)
            }
        }
    }
}

/// Whether a dependency the analysis `a` named among the constraint rows alone holds: the
/// rows of the named joints at realization `seed`, exactly, of rank below their number.
fn named_dependency(
    m: &Mechanism,
    a: &Analysis,
    seed: u64,
    meter: &mut Meter,
) -> Result<bool, BudgetExceeded> {
    use crate::motion::exact as models;
    let b = m.b() as usize;
    let pair = |q: usize| match m.joints[q].bodies[..] {
        [x, y] => Some((x, y)),
        _ => None,
    };
    for r in a.redundant.iter().filter(|r| !r.configuration) {
        let named: std::collections::HashSet<&str> = r.joints.iter().map(String::as_str).collect();
        let qs: Vec<usize> = (0..m.joints.len())
            .filter(|&q| named.contains(m.joints[q].id.as_str()))
            .collect();
        meter.charge(m.joints.len() as u64 / 8 + 1)?;
        let mut bodies: Vec<usize> = qs
            .iter()
            .filter_map(|&q| pair(q))
            .flat_map(|(x, y)| [x, y])
            .filter(|&x| x != m.frame)
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        let rows: Vec<_> = qs
            .iter()
            .map(|&q| models::joint_rows(m, q, seed, 0))
            .collect();
        let total: usize = rows.iter().map(|r| r.nrows()).sum();
        let rank = models::pairs_rank(
            b,
            bodies.len(),
            &rows,
            qs.iter().enumerate().filter_map(|(i, &q)| {
                let (x, y) = pair(q)?;
                Some((i, x, y))
            }),
            |x| bodies.binary_search(&x).ok(),
        );
        if rank < total {
            return Ok(true);
        }
    }
    Ok(false)
}
