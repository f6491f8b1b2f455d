//! The rank check: the count decomposition evaluated at a random generic realization of the
//! joint geometry ([`crate::motion::realize`]).
//!
//! 1. Isolated freedoms: for each body, the nullity of the stacked constraint rows of every pair
//!    touching it, its neighbours held fixed (a bar between two S joints has 1). Its unknowns
//!    become the complement `Q_b` of that null space, so `u_b = B − iso_b`.
//! 2. The count decomposition with those capacities.
//! 3. Each well-determined group's own square system (rows of the pairs whose flow goes into
//!    the group, columns the group's reduced unknowns, earlier groups known), and the
//!    under-determined block, must have full row rank; the over-determined block must have
//!    full column rank. A deficit names redundant equations (the pairs with weight in the left
//!    null space); one of them loses rows (chosen so the block keeps its rank) and steps 2-3
//!    run again. In a tall over-determined block that hides a freedom, all dependent rows go,
//!    so the count then shows the freedom as missing DOF.
//!
//! The Jacobian is block lower triangular (over-determined part, groups, under-determined part
//! in that order). When the over block has full column rank, every group block is nonsingular
//! and the under block has full row rank, its rank is exactly `rows − surplus` =
//! `unknowns − missing`: the per-block checks decide the whole mechanism.

use super::count::{Decomposition, Equations, Part, decompose};
use super::{Isolated, Redundancy, Unchecked};
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::motion;
use nalgebra::DMatrix;
use std::collections::HashSet;

/// What the rank check found, with the final decomposition.
pub(crate) struct RankResult {
    pub decomposition: Decomposition,
    pub isolated: Vec<Isolated>,
    pub redundant: Vec<Redundancy>,
    pub unchecked: Vec<Unchecked>,
}

/// Largest block (unknowns, equations) the rank check factorizes densely. A dense SVD costs
/// O(n^3) time and O(n^2) memory: 1,200 unknowns is about a second and 20 MB, while the giant
/// groups of some generated mechanisms (tens of thousands of unknowns) would need gigabytes
/// to terabytes. Larger blocks keep the count's verdict and are reported as unchecked.
pub(crate) const MAX_DENSE_UNKNOWNS: usize = 1200;

/// Relative tolerance on singular values (scaled by the largest one and the size).
const REL_TOL: f64 = 1e-9;

/// Singular values and vectors of `a` padded with zeros to a square matrix, so that the thin
/// SVD holds full bases of both null spaces.
struct Svd {
    sv: Vec<f64>,
    u: DMatrix<f64>,
    tol: f64,
}

impl Svd {
    /// Full SVD (singular values and both bases).
    fn of(a: &DMatrix<f64>) -> Svd {
        // V as before, although unused: the deficit path stays exactly the original SVD.
        let (sv, tol, u, _) = svd_parts(a, true, true);
        Svd {
            sv,
            u: u.expect("requested U"),
            tol,
        }
    }

    fn rank(&self) -> usize {
        self.sv.iter().filter(|&&s| s > self.tol).count()
    }
}

/// The padded SVD behind [`Svd`]; `compute_u` / `compute_v` only decide which bases are
/// accumulated: the singular values come out bit for bit the same either way (the rotations
/// are computed regardless), so rank decisions agree with the full SVD.
#[allow(clippy::type_complexity)]
fn svd_parts(
    a: &DMatrix<f64>,
    compute_u: bool,
    compute_v: bool,
) -> (Vec<f64>, f64, Option<DMatrix<f64>>, Option<DMatrix<f64>>) {
    let n = a.nrows().max(a.ncols()).max(1);
    let p = if a.nrows() == n && a.ncols() == n {
        a.clone()
    } else {
        let mut p = DMatrix::<f64>::zeros(n, n);
        p.view_mut((0, 0), (a.nrows(), a.ncols())).copy_from(a);
        p
    };
    let svd = p.svd(compute_u, compute_v);
    let sv: Vec<f64> = svd.singular_values.iter().copied().collect();
    let max = sv.iter().copied().fold(0.0, f64::max);
    let tol = (max * n as f64 * REL_TOL).max(1e-300);
    (sv, tol, svd.u, svd.v_t)
}

/// Numerical rank (same decision as `Svd::of(a).rank()`), without the singular vectors.
fn rank_of(a: &DMatrix<f64>) -> usize {
    if a.nrows() == 0 || a.ncols() == 0 {
        return 0;
    }
    let (sv, tol, _, _) = svd_parts(a, false, false);
    sv.iter().filter(|&&s| s > tol).count()
}

/// Run the check; `eqs.cap` and `u` are lowered in place.
pub(crate) fn check(m: &Mechanism, seed: u64, eqs: &mut Equations, u: &mut [u32]) -> RankResult {
    let b = m.b() as usize;
    let nb = m.bodies.len();
    let mut rows = pair_rows(m, seed, eqs);
    for (e, r) in rows.iter().enumerate() {
        eqs.cap[e] = r.nrows() as u32;
    }

    // Pairs touching each body (compressed: `touch[start[x]..start[x + 1]]`), proper pairs
    // only (a pair of a body with itself constrains nothing).
    let mut start = vec![0usize; nb + 1];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        if h != o {
            start[h + 1] += 1;
            start[o + 1] += 1;
        }
    }
    for i in 0..nb {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut touch = vec![0usize; start[nb]];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        if h != o {
            for x in [h, o] {
                touch[fill[x]] = e;
                fill[x] += 1;
            }
        }
    }
    drop(fill);

    // (a) Isolated freedoms and reduced unknowns.
    let mut q: Vec<DMatrix<f64>> = vec![DMatrix::zeros(b, 0); nb];
    let mut isolated = Vec::new();
    for body in 0..nb {
        if body == m.frame {
            continue;
        }
        let mine = &touch[start[body]..start[body + 1]];
        let total: usize = mine.iter().map(|&e| rows[e].nrows()).sum();
        let basis = if total == 0 {
            DMatrix::zeros(b, 0)
        } else {
            let mut s = DMatrix::<f64>::zeros(total, b);
            let mut r0 = 0;
            for &e in mine {
                s.view_mut((r0, 0), (rows[e].nrows(), b))
                    .copy_from(&rows[e]);
                r0 += rows[e].nrows();
            }
            // Only V is needed: skipping U leaves V and the singular values unchanged.
            let (sv, tol, _, v_t) = svd_parts(&s, false, true);
            let v_t = v_t.expect("requested V^T");
            let keep: Vec<usize> = (0..sv.len()).filter(|&i| sv[i] > tol).collect();
            let mut qb = DMatrix::<f64>::zeros(b, keep.len());
            for (c, &i) in keep.iter().enumerate() {
                for k in 0..b {
                    qb[(k, c)] = v_t[(i, k)];
                }
            }
            qb
        };
        let iso = b - basis.ncols();
        if iso > 0 {
            isolated.push(Isolated {
                body: m.body_id(body).to_string(),
                dimension: iso as u32,
            });
        }
        u[body] = basis.ncols() as u32;
        q[body] = basis;
    }
    drop(touch);
    drop(start);

    // (b)-(c) Decompose, check every block, lower, repeat.
    let mut redundant = Vec::new();
    let mut unchecked: Vec<Unchecked> = Vec::new();
    // Blocks already found sound, keyed by their bodies and their pairs with row counts (a
    // block's rank depends on nothing else), so a repeat pass only checks what changed.
    let mut verified: HashSet<Vec<usize>> = HashSet::new();
    // Column offset of each body in the block being built (`usize::MAX` outside it).
    let mut col = vec![usize::MAX; nb];
    loop {
        let dec = decompose(m, eqs, u);
        // Blocks in triangular order: over-determined part, groups, under-determined part.
        let over: Vec<usize> = (0..nb)
            .filter(|&x| dec.body_part[x] == Part::Over)
            .collect();
        let under: Vec<usize> = (0..nb)
            .filter(|&x| dec.body_part[x] == Part::Under)
            .collect();
        let first_group = usize::from(!over.is_empty());
        let ng = dec.groups.len();
        let nblocks = first_group + ng + usize::from(!under.is_empty());
        let block_of = |part: Part| -> Option<usize> {
            match part {
                Part::Over if !over.is_empty() => Some(0),
                Part::Group(g) if g < ng => Some(first_group + g),
                Part::Under if !under.is_empty() => Some(first_group + ng),
                _ => None,
            }
        };
        // Pairs of every block in one pass (compressed by block).
        let mut bstart = vec![0usize; nblocks + 1];
        for (e, r) in rows.iter().enumerate() {
            if r.nrows() == 0 {
                continue;
            }
            if let Some(i) = block_of(dec.eq_part[e]) {
                bstart[i + 1] += 1;
            }
        }
        for i in 0..nblocks {
            bstart[i + 1] += bstart[i];
        }
        let mut bfill = bstart.clone();
        let mut beqs = vec![0usize; bstart[nblocks]];
        for (e, r) in rows.iter().enumerate() {
            if r.nrows() == 0 {
                continue;
            }
            if let Some(i) = block_of(dec.eq_part[e]) {
                beqs[bfill[i]] = e;
                bfill[i] += 1;
            }
        }
        let mut changed = false;
        for i in 0..nblocks {
            let block_eqs = &beqs[bstart[i]..bstart[i + 1]];
            if block_eqs.is_empty() {
                continue;
            }
            let (bodies, part): (&[usize], Part) = if i < first_group {
                (&over, Part::Over)
            } else if i < first_group + ng {
                (
                    &dec.groups[i - first_group].bodies,
                    Part::Group(i - first_group),
                )
            } else {
                (&under, Part::Under)
            };
            let mut signature = Vec::with_capacity(bodies.len() + 1 + 2 * block_eqs.len());
            signature.extend_from_slice(bodies);
            signature.push(usize::MAX);
            for &e in block_eqs {
                signature.push(e);
                signature.push(rows[e].nrows());
            }
            if verified.contains(&signature) {
                continue;
            }
            let unknowns: usize = bodies.iter().map(|&x| u[x] as usize).sum();
            let equations: usize = block_eqs.iter().map(|&e| rows[e].nrows()).sum();
            if unknowns.max(equations) > MAX_DENSE_UNKNOWNS {
                unchecked.push(Unchecked {
                    bodies: bodies.len(),
                    unknowns,
                    equations,
                });
                verified.insert(signature);
                continue;
            }
            let a = block_matrix(block_eqs, bodies, eqs, &rows, &q, &mut col);
            // Singular values first; the vectors only when a deficit must be explained.
            let rank = rank_of(&a);
            // The over-determined block is tall: its surplus rows are the count's business
            // unless it also hides a freedom (a column deficit); then every dependent row goes,
            // so that the count sees the freedom.
            if part == Part::Over && rank >= a.ncols() {
                verified.insert(signature);
                continue;
            }
            let deficit = a.nrows().saturating_sub(rank);
            if deficit == 0 {
                verified.insert(signature);
                continue;
            }
            let svd = Svd::of(&a);
            debug_assert_eq!(
                svd.rank(),
                rank,
                "same singular values with or without vectors"
            );
            // Weight of each pair in the left null space.
            let null: Vec<usize> = (0..svd.sv.len())
                .filter(|&i| svd.sv[i] <= svd.tol)
                .collect();
            let mut named: Vec<(usize, f64)> = Vec::new();
            let mut r0 = 0;
            for &e in block_eqs {
                let n = rows[e].nrows();
                let w: f64 = (r0..r0 + n)
                    .map(|r| null.iter().map(|&k| svd.u[(r, k)].powi(2)).sum::<f64>())
                    .sum();
                if w > 1e-6 {
                    named.push((e, w));
                }
                r0 += n;
            }
            // Lower the pair that carries most of the dependency (ties: the later pair).
            let mut order = named.clone();
            order.sort_by(|a, b| b.1.total_cmp(&a.1).then(b.0.cmp(&a.0)));
            let mut lowered = usize::MAX;
            let mut removed = 0;
            for &(e, _) in &order {
                removed = drop_rows(
                    e, deficit, block_eqs, bodies, eqs, &mut rows, &q, &mut col, rank,
                );
                if removed > 0 {
                    lowered = e;
                    break;
                }
            }
            if removed == 0 {
                continue;
            }
            let named: Vec<usize> = named.iter().map(|&(e, _)| e).collect();
            eqs.cap[lowered] = rows[lowered].nrows() as u32;
            changed = true;
            let mut joints: Vec<usize> = named.iter().map(|&e| eqs.joint[e]).collect();
            joints.sort_unstable();
            joints.dedup();
            redundant.push(Redundancy {
                bodies: bodies.iter().map(|&x| m.body_id(x).to_string()).collect(),
                freedom: describe(m, bodies, &joints, removed),
                joints: joints.iter().map(|&j| m.joints[j].id.clone()).collect(),
                count: removed as u32,
                lowered: m.joints[eqs.joint[lowered]].id.clone(),
            });
            // Later blocks were checked with this one assumed nonsingular: decompose again.
            break;
        }
        if !changed {
            // Only the blocks of the final decomposition matter.
            unchecked.sort_by_key(|x| (std::cmp::Reverse(x.unknowns), x.bodies, x.equations));
            unchecked.dedup();
            return RankResult {
                decomposition: dec,
                isolated,
                redundant,
                unchecked,
            };
        }
    }
}

/// Constraint rows of every pair at the seeded random geometry. A pair of a multiple joint
/// whose driven share differs from the joint's gets the same geometry with its own share.
fn pair_rows(m: &Mechanism, seed: u64, eqs: &Equations) -> Vec<DMatrix<f64>> {
    let mut base = motion::realize(m, seed);
    (0..eqs.len())
        .map(|e| {
            let ji = eqs.joint[e];
            let j = &m.joints[ji];
            // A joint's pairs are consecutive: its last pair may take the rows instead of
            // copying them.
            let last = e + 1 == eqs.len() || eqs.joint[e + 1] != ji;
            let own = |base: &mut Vec<motion::JointModel>| {
                if last {
                    std::mem::replace(&mut base[ji].rows, DMatrix::zeros(0, 0))
                } else {
                    base[ji].rows.clone()
                }
            };
            if eqs.driven[e] == j.driven {
                return own(&mut base);
            }
            let mut rng = motion::SplitMix64::new(motion::joint_seed(seed, ji));
            let g = motion::random_geometry(j.kind, m.space, &mut rng);
            match motion::joint_model(j.kind, &g, m.space, eqs.driven[e]) {
                Ok(jm) => jm.rows,
                Err(_) => own(&mut base),
            }
        })
        .collect()
}

/// The block's matrix: rows of `block_eqs`, columns the reduced unknowns of `bodies`.
/// `col` is scratch of one entry per body, `usize::MAX` on entry and on return.
fn block_matrix(
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &[DMatrix<f64>],
    q: &[DMatrix<f64>],
    col: &mut [usize],
) -> DMatrix<f64> {
    let mut ncols = 0;
    for &x in bodies {
        col[x] = ncols;
        ncols += q[x].ncols();
    }
    let nrows: usize = block_eqs.iter().map(|&e| rows[e].nrows()).sum();
    let mut a = DMatrix::<f64>::zeros(nrows, ncols);
    let mut r0 = 0;
    for &e in block_eqs {
        let [h, o] = eqs.bodies(e);
        let n = rows[e].nrows();
        if h != o {
            for (x, sign) in [(h, -1.0), (o, 1.0)] {
                if col[x] != usize::MAX && q[x].ncols() > 0 {
                    let blk = &rows[e] * &q[x];
                    let c0 = col[x];
                    for c in 0..blk.ncols() {
                        for r in 0..n {
                            a[(r0 + r, c0 + c)] = blk[(r, c)] * sign;
                        }
                    }
                }
            }
        }
        r0 += n;
    }
    for &x in bodies {
        col[x] = usize::MAX;
    }
    a
}

/// Remove up to `count` rows of pair `e` that the block can lose without losing rank.
#[allow(clippy::too_many_arguments)]
fn drop_rows(
    e: usize,
    count: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &mut [DMatrix<f64>],
    q: &[DMatrix<f64>],
    col: &mut [usize],
    rank: usize,
) -> usize {
    let mut removed = 0;
    let mut r = rows[e].nrows();
    while r > 0 && removed < count {
        r -= 1;
        let saved = rows[e].clone();
        rows[e] = saved.clone().remove_row(r);
        let a = block_matrix(block_eqs, bodies, eqs, rows, q, col);
        if rank_of(&a) == rank {
            removed += 1;
        } else {
            rows[e] = saved;
        }
    }
    removed
}

/// The freedom a redundancy hides, in words.
fn describe(m: &Mechanism, bodies: &[usize], joints: &[usize], count: usize) -> String {
    let ids: Vec<String> = bodies.iter().map(|&x| m.body_id(x).to_string()).collect();
    let all_s = joints.iter().all(|&j| m.joints[j].kind == JointType::S);
    if bodies.len() == 1 && joints.len() == 2 && all_s {
        return format!(
            "body {} turns about the line through the centres of the spherical joints {} and {}, \
             a freedom no input controls",
            ids[0], m.joints[joints[0]].id, m.joints[joints[1]].id
        );
    }
    format!(
        "bodies {{{}}} keep {count} freedom(s) that no input controls",
        ids.join(", ")
    )
}
