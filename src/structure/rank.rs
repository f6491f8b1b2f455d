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
use super::{Isolated, Redundancy};
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::motion;
use nalgebra::DMatrix;

/// What the rank check found, with the final decomposition.
pub(crate) struct RankResult {
    pub decomposition: Decomposition,
    pub isolated: Vec<Isolated>,
    pub redundant: Vec<Redundancy>,
}

/// Relative tolerance on singular values (scaled by the largest one and the size).
const REL_TOL: f64 = 1e-9;

/// Singular values and vectors of `a` padded with zeros to a square matrix, so that the thin
/// SVD holds full bases of both null spaces.
struct Svd {
    sv: Vec<f64>,
    u: DMatrix<f64>,
    v_t: DMatrix<f64>,
    tol: f64,
}

impl Svd {
    fn of(a: &DMatrix<f64>) -> Svd {
        let n = a.nrows().max(a.ncols()).max(1);
        let mut p = DMatrix::<f64>::zeros(n, n);
        p.view_mut((0, 0), (a.nrows(), a.ncols())).copy_from(a);
        let svd = p.svd(true, true);
        let sv: Vec<f64> = svd.singular_values.iter().copied().collect();
        let max = sv.iter().copied().fold(0.0, f64::max);
        let tol = (max * n as f64 * REL_TOL).max(1e-300);
        Svd {
            sv,
            u: svd.u.expect("requested U"),
            v_t: svd.v_t.expect("requested V^T"),
            tol,
        }
    }

    fn rank(&self) -> usize {
        self.sv.iter().filter(|&&s| s > self.tol).count()
    }
}

fn rank_of(a: &DMatrix<f64>) -> usize {
    if a.nrows() == 0 || a.ncols() == 0 {
        return 0;
    }
    Svd::of(a).rank()
}

/// Run the check; `eqs.cap` and `u` are lowered in place.
pub(crate) fn check(m: &Mechanism, seed: u64, eqs: &mut Equations, u: &mut [u32]) -> RankResult {
    let b = m.b() as usize;
    let nb = m.bodies.len();
    let mut rows = pair_rows(m, seed, eqs);
    for (e, r) in rows.iter().enumerate() {
        eqs.cap[e] = r.nrows() as u32;
    }

    // Pairs touching each body.
    let mut touching: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        touching[h].push(e);
        if o != h {
            touching[o].push(e);
        }
    }

    // (a) Isolated freedoms and reduced unknowns.
    let mut q: Vec<DMatrix<f64>> = vec![DMatrix::zeros(b, 0); nb];
    let mut isolated = Vec::new();
    for body in 0..nb {
        if body == m.frame {
            continue;
        }
        let total: usize = touching[body]
            .iter()
            .filter(|&&e| {
                let [h, o] = eqs.bodies(e);
                h != o
            })
            .map(|&e| rows[e].nrows())
            .sum();
        let mut s = DMatrix::<f64>::zeros(total, b);
        let mut r0 = 0;
        for &e in &touching[body] {
            let [h, o] = eqs.bodies(e);
            if h == o {
                continue;
            }
            s.view_mut((r0, 0), (rows[e].nrows(), b))
                .copy_from(&rows[e]);
            r0 += rows[e].nrows();
        }
        let basis = if total == 0 {
            DMatrix::zeros(b, 0)
        } else {
            let svd = Svd::of(&s);
            let keep: Vec<usize> = (0..svd.sv.len()).filter(|&i| svd.sv[i] > svd.tol).collect();
            let mut qb = DMatrix::<f64>::zeros(b, keep.len());
            for (c, &i) in keep.iter().enumerate() {
                for k in 0..b {
                    qb[(k, c)] = svd.v_t[(i, k)];
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

    // (b)-(c) Decompose, check every block, lower, repeat.
    let mut redundant = Vec::new();
    let mut verified = std::collections::HashSet::new();
    loop {
        let dec = decompose(m, eqs, u);
        // Blocks in triangular order: over-determined part, groups, under-determined part.
        let over: Vec<usize> = (0..nb)
            .filter(|&x| dec.body_part[x] == Part::Over)
            .collect();
        let under: Vec<usize> = (0..nb)
            .filter(|&x| dec.body_part[x] == Part::Under)
            .collect();
        let mut blocks: Vec<(Vec<usize>, Part)> = Vec::with_capacity(dec.groups.len() + 2);
        if !over.is_empty() {
            blocks.push((over, Part::Over));
        }
        blocks.extend(
            dec.groups
                .iter()
                .enumerate()
                .map(|(g, grp)| (grp.bodies.clone(), Part::Group(g))),
        );
        if !under.is_empty() {
            blocks.push((under, Part::Under));
        }
        // Pairs of every block in one pass.
        let mut block_of_part = std::collections::HashMap::new();
        for (i, (_, part)) in blocks.iter().enumerate() {
            block_of_part.insert(*part, i);
        }
        let mut pairs_of: Vec<Vec<usize>> = vec![Vec::new(); blocks.len()];
        for (e, r) in rows.iter().enumerate() {
            if r.nrows() == 0 {
                continue;
            }
            if let Some(&i) = block_of_part.get(&dec.eq_part[e]) {
                pairs_of[i].push(e);
            }
        }
        let mut changed = false;
        for ((bodies, part), block_eqs) in blocks.into_iter().zip(pairs_of) {
            if block_eqs.is_empty() {
                continue;
            }
            // A block's rank depends only on its own pairs (with their rows) and bodies.
            let signature = (
                bodies.clone(),
                block_eqs
                    .iter()
                    .map(|&e| (e, rows[e].nrows()))
                    .collect::<Vec<_>>(),
            );
            if verified.contains(&signature) {
                continue;
            }
            let a = block_matrix(&block_eqs, &bodies, eqs, &rows, &q, nb);
            let svd = Svd::of(&a);
            let rank = svd.rank();
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
            // Weight of each pair in the left null space.
            let null: Vec<usize> = (0..svd.sv.len())
                .filter(|&i| svd.sv[i] <= svd.tol)
                .collect();
            let mut named: Vec<(usize, f64)> = Vec::new();
            let mut r0 = 0;
            for &e in &block_eqs {
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
                    e, deficit, &block_eqs, &bodies, eqs, &mut rows, &q, nb, rank,
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
                freedom: describe(m, &bodies, &joints, removed),
                joints: joints.iter().map(|&j| m.joints[j].id.clone()).collect(),
                count: removed as u32,
                lowered: m.joints[eqs.joint[lowered]].id.clone(),
            });
            // Later blocks were checked with this one assumed nonsingular: decompose again.
            break;
        }
        if !changed {
            return RankResult {
                decomposition: dec,
                isolated,
                redundant,
            };
        }
    }
}

/// Constraint rows of every pair at the seeded random geometry. A pair of a multiple joint
/// whose driven share differs from the joint's gets the same geometry with its own share.
fn pair_rows(m: &Mechanism, seed: u64, eqs: &Equations) -> Vec<DMatrix<f64>> {
    let base = motion::realize(m, seed);
    (0..eqs.len())
        .map(|e| {
            let ji = eqs.joint[e];
            let j = &m.joints[ji];
            if eqs.driven[e] == j.driven {
                return base[ji].rows.clone();
            }
            let mut rng = motion::SplitMix64::new(motion::joint_seed(seed, ji));
            let g = motion::random_geometry(j.kind, m.space, &mut rng);
            motion::joint_model(j.kind, &g, m.space, eqs.driven[e])
                .map(|jm| jm.rows)
                .unwrap_or_else(|_| base[ji].rows.clone())
        })
        .collect()
}

/// The block's matrix: rows of `block_eqs`, columns the reduced unknowns of `bodies`.
fn block_matrix(
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &[DMatrix<f64>],
    q: &[DMatrix<f64>],
    nb: usize,
) -> DMatrix<f64> {
    let mut col = vec![usize::MAX; nb];
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
                    let blk = &rows[e] * &q[x] * sign;
                    a.view_mut((r0, col[x]), (n, q[x].ncols())).copy_from(&blk);
                }
            }
        }
        r0 += n;
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
    nb: usize,
    rank: usize,
) -> usize {
    let mut removed = 0;
    let mut r = rows[e].nrows();
    while r > 0 && removed < count {
        r -= 1;
        let saved = rows[e].clone();
        rows[e] = saved.clone().remove_row(r);
        let a = block_matrix(block_eqs, bodies, eqs, rows, q, nb);
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
