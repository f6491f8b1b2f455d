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

use super::count::{Decomposition, Equations, FlowRound, Part, decompose_next};
use super::{Isolated, Redundancy, Unchecked};
use crate::elimination::{Block, Elimination};
use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism, Space};
use crate::motion::{self, GeometryUsed};
use nalgebra::{DMatrix, DMatrixViewMut, Dyn, MatrixView, RawStorage};

/// A pair's rows as [`PairRows`] stores them (row-major).
type RowsView<'a> = MatrixView<'a, f64, Dyn, Dyn, Dyn, Dyn>;
use std::collections::{HashMap, HashSet};
use std::hash::{DefaultHasher, Hasher};
use std::sync::Mutex;

/// What the caller of [`check`] knows or needs beyond the plain check (`mbsa transform`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shortcut {
    /// The plain rank check.
    None,
    /// The whole system is known to have full row rank: no factorization is needed when the
    /// count has no over-determined part.
    Certified,
    /// Only whether the mechanism is determined matters: when the count does not find it
    /// determined, the check ends at once (`deficient`); when it does, the groups up to
    /// [`MAX_DENSE_UNKNOWNS`] are checked first, and a deficient one ends the check,
    /// unexplained (the larger groups would have been factorized for nothing).
    Determined,
}

/// What the rank check found, with the final decomposition.
pub(crate) struct RankResult {
    /// [`Shortcut::Determined`] stopped at a deficient group: the mechanism is not determined
    /// (the rest of the result is not meaningful).
    pub deficient: bool,
    /// Work units of the blocks' rank decisions this check made (a dense factorization of
    /// `n` unknowns `n^3`, an exact sparse one its factor's entries, the sparse screen
    /// `64 (rows + columns)`); blocks taken from the cache or certified cost nothing.
    pub work: u64,
    pub decomposition: Decomposition,
    /// Constraint equations set aside at the file's configuration, per joint.
    pub set_aside: Vec<u32>,
    pub isolated: Vec<Isolated>,
    pub redundant: Vec<Redundancy>,
    pub unchecked: Vec<Unchecked>,
    /// Decompositions of the whole mechanism the check ran (its rounds): the scale test's
    /// work measure.
    #[cfg_attr(not(test), allow(dead_code))]
    pub rounds: usize,
    /// Joints of a deficit that a second realization did not confirm (the draw was
    /// degenerate there), with the seed of a draw without the deficit: [`check`] draws them
    /// at it and starts over. Empty in a final result.
    suspects: Vec<(usize, u64)>,
    /// With suspects: what the next attempt can take over.
    kept_rows: Option<Kept>,
}

/// Each body's reduced unknowns (`None`: all `B`).
type Bases = Vec<Option<DMatrix<f64>>>;

/// What an attempt of [`check`] leaves to the next one: the rows, each pair's first row
/// count, and the bodies' reduced unknowns (recomputed only where a pair changed).
struct Kept {
    rows: PairRows,
    first: Vec<u8>,
    bases: Bases,
}

/// Largest block (unknowns, equations) the rank check factorizes densely. A dense SVD costs
/// O(n^3) time and O(n^2) memory: 1,200 unknowns is about a second and 20 MB, while the giant
/// groups of some generated mechanisms (tens of thousands of unknowns) would need gigabytes
/// to terabytes. Larger blocks keep the count's verdict and are reported as unchecked (the
/// sparse screen is not a way out: on the giant groups of variant B its fill-in grows
/// without bound, 10 minutes and more at 22,000 unknowns).
pub(crate) const MAX_DENSE_UNKNOWNS: usize = 1200;

/// Largest block whose rank is decided by exact sparse elimination (random realizations). The
/// giant group of a planar Assur II-B linkage of 10^5 bodies (21,603 unknowns) takes about a
/// second; the under-determined part of a random spatial mechanism of 2·10^4 bodies (111,000
/// unknowns, a random graph with little sparsity to exploit) took 45 s, so such blocks stay
/// with the count.
const MAX_EXACT_UNKNOWNS: usize = 50_000;

/// Relative tolerance on singular values (scaled by the largest one and the size). An exact
/// deficiency at random generic geometry leaves singular values near `n · ε` (numpy's
/// `matrix_rank` threshold, `ε` = 2.2e-16), 4,500 times below this; a long chain of loops is
/// nonsingular but can be badly conditioned: the 321-body group of a variant-B linkage of
/// 10^3 bodies has `σ_min / σ_max` below 1e-6, which a tolerance of 1e-9 took for a deficit.
const REL_TOL: f64 = 1e-12;

/// The rank threshold of one analysis: singular values at most `max(rel · n · σ_max, abs)`
/// count as zero. Random geometry: `rel` = [`REL_TOL`],
/// `abs` = 0. File geometry: `rel` = 1e-9 (its numbers are decimals rounded to double
/// precision) and `abs` the perturbation its written precision allows (see
/// `docs/algorithms.md`, "Tolerance").
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tol {
    pub rel: f64,
    pub abs: f64,
}

impl Tol {
    /// The threshold for a matrix of size `n` whose largest singular value is `smax`.
    fn cut(&self, smax: f64, n: usize) -> f64 {
        (smax * n.max(1) as f64 * self.rel)
            .max(self.abs)
            .max(1e-300)
    }
}

/// Singular values and vectors of `a` padded with zeros to a square matrix, so that the thin
/// SVD holds full bases of both null spaces.
struct Svd {
    sv: Vec<f64>,
    u: DMatrix<f64>,
    tol: f64,
}

impl Svd {
    /// Full SVD (singular values and both bases).
    fn of(a: &DMatrix<f64>, t: &Tol) -> Svd {
        // V as before, although unused: the deficit path stays exactly the original SVD.
        let (sv, tol, u, _) = svd_parts(a, true, true, t);
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
    t: &Tol,
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
    let tol = t.cut(max, n);
    (sv, tol, svd.u, svd.v_t)
}

/// Numerical rank (same decision as `Svd::of(a).rank()`), without the singular vectors.
fn rank_of(a: &DMatrix<f64>, t: &Tol) -> usize {
    if a.nrows() == 0 || a.ncols() == 0 {
        return 0;
    }
    let (sv, tol, _, _) = svd_parts(a, false, false, t);
    sv.iter().filter(|&&s| s > tol).count()
}

/// Stacks of more rows than this are reduced by a QR before the SVD in [`reduced_basis`].
const TALL_STACK_ROWS: usize = 96;

/// The reduced unknowns of a body whose pairs have the constraint rows `rows` (its neighbours
/// held fixed): `None` when the stacked rows have full column rank (no isolated freedom: the
/// body keeps all `b` unknowns, basis the identity), else an orthonormal basis of the
/// complement of their null space.
///
/// Full column rank is first screened by [`surely_full_rank`]: a singular value ratio above
/// 1e-6 is far from the SVD threshold of [`REL_TOL`], so the SVD would keep every direction
/// too. Anything else goes to the padded SVD.
fn reduced_basis<'a>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>> + Clone,
    t: &Tol,
) -> Option<DMatrix<f64>> {
    // The pairs' rows are loaded into the cache together (see [`warm`]) as they are counted.
    let mut touched = 0.0;
    let total: usize = rows
        .clone()
        .map(|r| {
            if r.ncols() > 0 {
                touched += (0..r.nrows())
                    .map(|i| r[(i, 0)] + r[(i, r.ncols() - 1)])
                    .sum::<f64>();
            }
            r.nrows()
        })
        .sum();
    std::hint::black_box(touched);
    if total == 0 {
        return Some(DMatrix::zeros(b, 0));
    }
    if total >= b && t.abs == 0.0 && surely_full_rank(b, total, rows.clone()) {
        return None;
    }
    let mut s = DMatrix::<f64>::zeros(total, b);
    let mut r0 = 0;
    for r in rows {
        s.view_mut((r0, 0), (r.nrows(), b)).copy_from(&r);
        r0 += r.nrows();
    }
    Some(row_space(b, s, t))
}

/// An orthonormal basis (`b × rank`) of the row space of the stacked rows `s` (`total × b`),
/// the right singular vectors above the threshold.
fn row_space(b: usize, s: DMatrix<f64>, t: &Tol) -> DMatrix<f64> {
    let total = s.nrows();
    // Only V is needed: skipping U leaves V and the singular values unchanged. A body held
    // by many pairs (the hub of a star: 10^5 pairs) first has its tall stack reduced to the
    // b × b triangle of its QR (same singular values and right singular vectors), instead of
    // an SVD padded to total × total; the threshold keeps the stack's size.
    let (sv, tol, v_t) = if total > TALL_STACK_ROWS {
        let r = s.qr().r();
        let (sv, _, _, v_t) = svd_parts(&r, false, true, t);
        let max = sv.iter().copied().fold(0.0, f64::max);
        (sv, t.cut(max, total), v_t)
    } else {
        let (sv, tol, _, v_t) = svd_parts(&s, false, true, t);
        (sv, tol, v_t)
    };
    let v_t = v_t.expect("requested V^T");
    let keep: Vec<usize> = (0..sv.len()).filter(|&i| sv[i] > tol).collect();
    let mut qb = DMatrix::<f64>::zeros(b, keep.len());
    for (c, &i) in keep.iter().enumerate() {
        for k in 0..b {
            qb[(k, c)] = v_t[(i, k)];
        }
    }
    qb
}

/// Body-local twists at the file's geometry. Each body's unknowns are written about its own
/// reference point (the mean of the origins of its pairs' joints, at the dimensionless
/// geometry), `t_centre = S_x · t_local`: an invertible change of columns per body, so ranks
/// and left null spaces (the redundancies and their weights) are unchanged, but the rows a body
/// sees carry lever arms of its own size instead of its distance from the centre. A bar of a
/// row of 1,000 windows sits 500 link lengths from the centre: its rotation about its two pins
/// then changes its rows by about 1/500 of their size, which the precision-derived threshold
/// (lever 500) took for an isolated freedom. The same change of coordinates as the sparse path
/// of the geometric analysis (`rigidity::geometric::sparse_float`).
pub(crate) struct LocalFrames {
    /// `S_x` per node (`None`: the frame, element nodes, bodies without a joint point).
    frame: Vec<Option<DMatrix<f64>>>,
    /// The largest lever arm of a joint point about its body's reference point (in
    /// characteristic lengths).
    lever: f64,
}

impl LocalFrames {
    /// The frames of `m`'s bodies at the (dimensionless) file geometry `geoms`; `None` for a
    /// spherical mechanism (no translations to move).
    fn new(m: &Mechanism, geoms: &[Geometry], eqs: &Equations) -> Option<LocalFrames> {
        if m.space == Space::Spherical || geoms.len() != m.joints.len() {
            return None;
        }
        let nb = eqs.nodes;
        let mut sum = vec![[0.0f64; 3]; nb];
        let mut count = vec![0usize; nb];
        let body = |x: usize| x != m.frame && !eqs.is_element(x);
        for e in 0..eqs.len() {
            let [h, o] = eqs.bodies(e);
            let Some(p) = geoms[eqs.joint[e]].origin else {
                continue;
            };
            if h == o || !p.iter().all(|v| v.is_finite()) {
                continue;
            }
            for x in [h, o] {
                if body(x) {
                    (0..3).for_each(|i| sum[x][i] += p[i]);
                    count[x] += 1;
                }
            }
        }
        let centre: Vec<Option<[f64; 3]>> = (0..nb)
            .map(|x| (count[x] > 0).then(|| sum[x].map(|v| v / count[x] as f64)))
            .collect();
        let mut lever = 0.0f64;
        for e in 0..eqs.len() {
            let [h, o] = eqs.bodies(e);
            let g = &geoms[eqs.joint[e]];
            for x in [h, o] {
                let Some(c) = centre[x] else {
                    continue;
                };
                for p in [g.origin, g.origin2].into_iter().flatten() {
                    for i in 0..3 {
                        let d = (p[i] - c[i]).abs();
                        if d.is_finite() {
                            lever = lever.max(d);
                        }
                    }
                }
            }
        }
        let frame = centre
            .into_iter()
            .map(|c| c.and_then(|c| motion::twist_shift(m.space, c)))
            .collect();
        Some(LocalFrames { frame, lever })
    }

    /// [`crate::motion::file_threshold`] with the body-local lever arm: a direction rounded by
    /// `δ_d` moves a row written about its body's reference point by `δ_d` times its distance
    /// from that point.
    fn threshold(&self, used: &GeometryUsed) -> f64 {
        let Some(delta) = used.precision.filter(|&d| d > 0.0) else {
            return 0.0;
        };
        let directions = used.direction_precision.unwrap_or(delta);
        let length = used.scale.map_or(1.0, |s| s.length);
        crate::motion::FILE_TOL_FACTOR * (delta / length + directions * self.lever)
    }
}

/// [`reduced_basis`] about the body's reference point: the stacked rows times `s` (its
/// [`LocalFrames`] change of coordinates), each scaled to unit norm, their null space by the
/// SVD at `t`; the unknowns kept are `s` times the complement (all of `s` when nothing is
/// isolated), so the blocks see the body's local twists.
fn local_basis<'a>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>> + Clone,
    s: &DMatrix<f64>,
    t: &Tol,
) -> DMatrix<f64> {
    let total: usize = rows.clone().map(|r| r.nrows()).sum();
    if total == 0 {
        return DMatrix::zeros(b, 0);
    }
    let mut a = DMatrix::<f64>::zeros(total, b);
    let mut r0 = 0;
    for r in rows {
        a.view_mut((r0, 0), (r.nrows(), b))
            .copy_from(&(r.into_owned() * s));
        r0 += r.nrows();
    }
    for mut row in a.row_iter_mut() {
        let n = row.norm();
        if n > 0.0 {
            row.unscale_mut(n);
        }
    }
    let ql = row_space(b, a, t);
    if ql.ncols() >= b {
        return s.clone();
    }
    s * ql
}

/// A block to check: its pairs, its bodies (ascending), its part, its signature and its
/// matrix's (rows, columns).
type Pending<'a> = (&'a [usize], &'a [usize], Part, Vec<u32>, (usize, usize));

/// Blocks with more unknowns than this are screened by the sparse elimination first.
const SCREEN_UNKNOWNS: usize = 8;

/// Margin of the sparse screen over the SVD threshold.
const SCREEN_MARGIN: f64 = 1e3;

/// The rank of a sound block without forming it densely: a block-sparse QR with column
/// pivoting (one body at a time, [`Elimination`]) with a pivot threshold [`SCREEN_MARGIN`]
/// times above the SVD's (whose `σ_max` is bounded by the Frobenius norm). `Some` only when
/// every needed pivot clears it (full row rank; for the over-determined block, full column
/// rank): the SVD would find the same rank. `None` leaves the decision to the SVD, so a
/// deficit is always found and explained by the dense path.
#[allow(clippy::too_many_arguments)]
fn screen(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
    part: Part,
    t: &Tol,
) -> Option<usize> {
    if t.abs > 0.0 {
        // A precision-derived threshold is not a multiple of σ_max: the SVD decides.
        return None;
    }
    sparse_full_rank(b, block_eqs, bodies, eqs, rows, q, part, t, false)
}

/// [`screen`]'s elimination, for any threshold: `Some(rank)` when every needed pivot clears
/// [`SCREEN_MARGIN`] times the SVD's threshold (bounding `σ_max` by the Frobenius norm), so
/// that the block surely has full rank. Blocks too large for the SVD at the file's geometry
/// (a precision-derived threshold) are decided here too; `None` leaves them unchecked.
#[allow(clippy::too_many_arguments)]
fn sparse_full_rank(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
    part: Part,
    t: &Tol,
    file: bool,
) -> Option<usize> {
    let sizes: Vec<usize> = bodies.iter().map(|&x| width(b, q, x)).collect();
    let ncols: usize = sizes.iter().sum();
    if ncols <= SCREEN_UNKNOWNS {
        return None;
    }
    let nrows: usize = block_eqs.iter().map(|&e| rows.nrows(e)).sum();
    let mut blocks = Vec::with_capacity(block_eqs.len());
    let mut frob2 = 0.0;
    for &e in block_eqs {
        let [h, o] = eqs.bodies(e);
        let n = rows.nrows(e);
        if h == o || n == 0 {
            continue;
        }
        let sides: Vec<(usize, usize, f64)> = [(h, -1.0), (o, 1.0)]
            .into_iter()
            .filter_map(|(x, sign)| {
                let k = bodies.binary_search(&x).ok()?;
                (sizes[k] > 0).then_some((x, k, sign))
            })
            .collect();
        if sides.is_empty() {
            continue;
        }
        let w: usize = sides.iter().map(|&(_, k, _)| sizes[k]).sum();
        let mut mat = DMatrix::<f64>::zeros(n, w);
        let mut c0 = 0;
        for &(x, k, sign) in &sides {
            put(
                &mut mat.view_mut((0, c0), (n, sizes[k])),
                rows.get(e),
                &q[x],
                sign,
            );
            c0 += sizes[k];
        }
        if file {
            // Rows on body-local twists are far from unit norm (a row written about the
            // centre, moved to the body): scaled rows, so that the threshold is relative to
            // unit rows as in the set-aside.
            for mut row in mat.row_iter_mut() {
                let n = row.norm();
                if n > 0.0 {
                    row.unscale_mut(n);
                }
            }
        }
        let groups = sides.iter().map(|&(_, k, _)| k).collect();
        frob2 += mat.norm_squared();
        blocks.push(Block { groups, mat });
    }
    let n = nrows.max(ncols);
    let tol = if file {
        // At the file's geometry: the threshold `rigid`'s sparse path decides with (QR pivots
        // against the SVD's threshold), `σ_max` bounded by `√(‖A‖₁ ‖A‖_∞)`, far tighter than
        // the Frobenius norm on long chains of unit rows.
        let mut col_sum = vec![0.0f64; ncols];
        let offsets: Vec<usize> = sizes
            .iter()
            .scan(0, |acc, &s| {
                let o = *acc;
                *acc += s;
                Some(o)
            })
            .collect();
        let mut row_max = 0.0f64;
        for blk in &blocks {
            for row in blk.mat.row_iter() {
                row_max = row_max.max(row.iter().map(|v| v.abs()).sum());
            }
            let mut c0 = 0;
            for &k in &blk.groups {
                for j in 0..sizes[k] {
                    col_sum[offsets[k] + j] +=
                        blk.mat.column(c0 + j).iter().map(|v| v.abs()).sum::<f64>();
                }
                c0 += sizes[k];
            }
        }
        let col_max = col_sum.iter().copied().fold(0.0, f64::max);
        t.cut((col_max * row_max).sqrt().min(frob2.sqrt()), n)
    } else {
        // At a random realization a margin above the SVD's threshold, so that the SVD would
        // agree.
        SCREEN_MARGIN * t.cut(frob2.sqrt(), n)
    };
    // Large blocks (file geometry: the screen sees dense-sized ones only) within the
    // set-aside's memory cap; past it the block is left unchecked.
    let rank = if file {
        Elimination::run_within(&sizes, blocks, tol, SPARSE_ASIDE_BYTES)
            .ok()?
            .rank
    } else {
        Elimination::run(&sizes, blocks, tol).rank
    };
    let needed = if part == Part::Over { ncols } else { nrows };
    (rank >= needed).then_some(rank)
}

/// Largest square block [`surely_nonsingular`] decides (on the stack).
const SMALL_BLOCK: usize = 36;

/// Whether a small square block surely has full rank at the SVD's threshold, decided without
/// the heap: the block as [`block_matrix`] builds it, its inverse `X` by Gaussian elimination
/// with partial pivoting, and a check of the residual `‖I − A·X‖_F ≤ 1/2`, which proves `A`
/// invertible with `‖A⁻¹‖₂ ≤ 2‖X‖_F`, so `σ_min ≥ 1 / (2‖X‖_F)`. When that is
/// [`SCREEN_MARGIN`] times above the SVD threshold (`n · rel · σ_max`, `σ_max ≤ ‖A‖_F`), the
/// SVD would find full rank too. Anything else (or a precision-derived threshold) goes to
/// [`screen`] and the SVD, as before. The structural groups of generated mechanisms (one to
/// four bodies) all come here: the sparse screen allocated a few matrices per pair.
#[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
fn surely_nonsingular(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
    t: &Tol,
) -> bool {
    const N: usize = SMALL_BLOCK;
    if t.abs > 0.0 || bodies.len() > N {
        return false;
    }
    let mut col = [0usize; N];
    let mut n = 0;
    for (k, &x) in bodies.iter().enumerate() {
        col[k] = n;
        n += width(b, q, x);
    }
    // The arrays sized to the block (zeroing 36 × 36 arrays for a block of 12 cost more than
    // the elimination).
    let col = &col[..bodies.len()];
    let args = (b, block_eqs, bodies, eqs, rows, q, t);
    match n {
        0 => false,
        1..=6 => nonsingular_within::<6>(n, col, args),
        7..=12 => nonsingular_within::<12>(n, col, args),
        13..=18 => nonsingular_within::<18>(n, col, args),
        19..=24 => nonsingular_within::<24>(n, col, args),
        25..=N => nonsingular_within::<N>(n, col, args),
        _ => false,
    }
}

/// One row's nonzero columns in a small block ([`nonsingular_within`]): the columns of the (at
/// most two) bodies its pair acts on, as (first column, width), ascending. Every other entry
/// of the row is zero.
#[derive(Clone, Copy, Default)]
struct RowSpan {
    k: u8,
    c: [u8; 2],
    w: [u8; 2],
}

/// Loads the rows of the pairs `block_eqs` into the cache together, before they are read one
/// by one: the pairs of a block lie far apart in [`PairRows`] (and in `eqs`), so copying them
/// pair after pair waited for memory once per pair (a third of [`nonsingular_within`]'s time
/// and most of [`reduced_basis`]'s at 10^6 bodies). Changes no value.
fn warm(rows: &PairRows, eqs: &Equations, block_eqs: &[usize]) {
    let mut sum = 0.0;
    let mut ends = 0usize;
    for &e in block_eqs.iter().take(SMALL_BLOCK) {
        let [h, o] = eqs.bodies(e);
        ends ^= h ^ o;
        // One value per cache line (8 values), and the last one.
        let v = rows.values(e);
        sum += v.iter().step_by(8).sum::<f64>() + v.last().copied().unwrap_or(0.0);
    }
    std::hint::black_box((sum, ends));
}

/// [`surely_nonsingular`] with arrays of `N × N` (`n ≤ N`), `col` the first column of each
/// body.
#[allow(clippy::needless_range_loop, clippy::type_complexity)]
fn nonsingular_within<const N: usize>(
    n: usize,
    col: &[usize],
    (b, block_eqs, bodies, eqs, rows, q, t): (
        usize,
        &[usize],
        &[usize],
        &Equations,
        &PairRows,
        &[Option<DMatrix<f64>>],
        &Tol,
    ),
) -> bool {
    warm(rows, eqs, block_eqs);
    let mut a = [[0.0f64; N]; N];
    let mut spans = [RowSpan::default(); N];
    let mut r0 = 0;
    for &e in block_eqs {
        let [h, o] = eqs.bodies(e);
        let re = rows.get(e);
        if r0 + re.nrows() > n {
            return false;
        }
        let mut span = RowSpan::default();
        if h != o {
            for (x, sign) in [(h, -1.0), (o, 1.0)] {
                let Ok(k) = bodies.binary_search(&x) else {
                    continue;
                };
                let c0 = col[k];
                let w = match &q[x] {
                    None => {
                        for i in 0..re.nrows() {
                            for j in 0..b {
                                a[r0 + i][c0 + j] = sign * re[(i, j)];
                            }
                        }
                        b
                    }
                    Some(qx) => {
                        for i in 0..re.nrows() {
                            for j in 0..qx.ncols() {
                                let mut v = 0.0;
                                for l in 0..b {
                                    v += re[(i, l)] * qx[(l, j)];
                                }
                                a[r0 + i][c0 + j] = sign * v;
                            }
                        }
                        qx.ncols()
                    }
                };
                // n ≤ N ≤ 36: the columns fit a byte.
                span.c[usize::from(span.k)] = c0 as u8;
                span.w[usize::from(span.k)] = w as u8;
                span.k += 1;
            }
        }
        if span.k == 2 && span.c[1] < span.c[0] {
            span.c.swap(0, 1);
            span.w.swap(0, 1);
        }
        spans[r0..r0 + re.nrows()].fill(span);
        r0 += re.nrows();
    }
    if r0 != n {
        return false;
    }
    let frob: f64 = a[..n]
        .iter()
        .map(|r| r[..n].iter().map(|v| v * v).sum::<f64>())
        .sum::<f64>()
        .sqrt();
    if !(frob > 0.0 && frob.is_finite()) {
        return false;
    }
    // Every body of the block with all `b` unknowns: the Gram proof by blocks of `b`.
    let uniform = if n == b * bodies.len() { b } else { 0 };
    gram_proves::<N>(n, &a, &spans, uniform, frob, t) || inverse_proves::<N>(n, &a, frob, t)
}

/// The inverse's half of [`nonsingular_within`]: `X` by Gauss-Jordan elimination and the
/// residual `‖I − A·X‖_F ≤ 1/2` prove `σ_min ≥ 1 / (2‖X‖_F)`, accepted when that is
/// [`SCREEN_MARGIN`] times above the threshold.
#[allow(clippy::needless_range_loop)]
fn inverse_proves<const N: usize>(n: usize, a: &[[f64; N]; N], frob: f64, t: &Tol) -> bool {
    let a = *a;
    // Inverse: [A | I] reduced to [I | X] with partial pivoting.
    let mut lu = a;
    let mut x = [[0.0f64; N]; N];
    for i in 0..n {
        x[i][i] = 1.0;
    }
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| lu[i][c].abs().total_cmp(&lu[j][c].abs()))
            .unwrap_or(c);
        if lu[p][c] == 0.0 {
            return false;
        }
        lu.swap(c, p);
        x.swap(c, p);
        // Columns before `c` of row `c` are exact zeros by now: only `c..n` changes.
        let d = lu[c][c];
        for j in c..n {
            lu[c][j] /= d;
        }
        for j in 0..n {
            x[c][j] /= d;
        }
        for i in 0..n {
            if i == c {
                continue;
            }
            let f = lu[i][c];
            if f == 0.0 {
                continue;
            }
            for j in c..n {
                lu[i][j] -= f * lu[c][j];
            }
            for j in 0..n {
                x[i][j] -= f * x[c][j];
            }
        }
    }
    let xf: f64 = x[..n]
        .iter()
        .map(|r| r[..n].iter().map(|v| v * v).sum::<f64>())
        .sum::<f64>()
        .sqrt();
    if !xf.is_finite() {
        return false;
    }
    // ‖I − A·X‖_F, row by row (A has a few nonzeros per row: one or two bodies).
    let mut res = 0.0;
    for i in 0..n {
        let mut r = [0.0f64; N];
        r[i] = 1.0;
        for l in 0..n {
            let ail = a[i][l];
            if ail != 0.0 {
                for j in 0..n {
                    r[j] -= ail * x[l][j];
                }
            }
        }
        res += r[..n].iter().map(|v| v * v).sum::<f64>();
    }
    if res.is_nan() || res.sqrt() > 0.5 {
        return false;
    }
    let sigma_min = 0.5 / xf;
    sigma_min > SCREEN_MARGIN * t.cut(frob, n)
}

/// The cheap half of [`nonsingular_within`]: whether `AᵀA − β²I` (`a` the block, `n × n`,
/// Frobenius norm `frob`) has a Cholesky factor, which proves `σ_min(A) > β` with
/// `β = max(1e-4 · ‖A‖_F, 4√n · SCREEN_MARGIN · threshold)`; about a tenth of the work of the
/// inverse and its residual (the Gram matrix of a block whose rows touch one or two bodies is
/// cheap, its Cholesky factor `n³/6`).
///
/// Rounding: the Gram matrix is formed with an error below `γ_n ‖A‖_F²` and a floating-point
/// Cholesky that runs through proves the exact matrix positive definite when the shift exceeds
/// `γ_{n+1} · trace` (Rump, BIT 2006); both are below `1e-14 · ‖A‖_F²` for `n ≤ 36`, and the
/// shift carries `1e-12 · ‖A‖_F²` more than `β²`. It accepts only blocks that the inverse's
/// test accepts too (`σ_min > β` gives `0.5 / ‖X‖_F ≳ σ_min / (2√n)`, above the margin, and a
/// residual of about `κ ε`), so the rank, the work units and the output are the same as
/// without it; anything else goes on to the inverse.
///
/// `spans` gives each row's nonzero columns. The Gram matrix and its factor are computed with
/// the same operations in the same order as a product over the nonzeros found value by value
/// and a left-looking factorization (kept as the tests' reference): bit for bit the same
/// numbers, but in loops over consecutive columns (see [`gram_matrix`], [`cholesky_runs`];
/// [`gram_blocks`] and [`cholesky_blocks`] when every body has `width` unknowns).
#[allow(clippy::needless_range_loop)]
fn gram_proves<const N: usize>(
    n: usize,
    a: &[[f64; N]; N],
    spans: &[RowSpan; N],
    width: usize,
    frob: f64,
    t: &Tol,
) -> bool {
    let tr = frob * frob;
    if !(tr > 1e-200 && tr.is_finite()) {
        return false;
    }
    let beta = (1e-4 * frob).max(4.0 * (n as f64).sqrt() * SCREEN_MARGIN * t.cut(frob, n));
    let shift = beta * beta + 1e-12 * tr;
    let mut g = [[0.0f64; N]; N];
    let blocks = match width {
        6 => gram_blocks::<N, 6>(n, a, spans, &mut g),
        3 => gram_blocks::<N, 3>(n, a, spans, &mut g),
        _ => {
            gram_matrix::<N>(n, a, spans, &mut g);
            [0; N]
        }
    };
    for j in 0..n {
        g[j][j] -= shift;
    }
    match width {
        6 => cholesky_blocks::<N, 6>(n, &mut g, blocks),
        3 => cholesky_blocks::<N, 3>(n, &mut g, blocks),
        _ => cholesky_runs::<N>(n, &mut g),
    }
}

/// [`gram_matrix`] when every body of the block is `W` unknowns wide (body `I` the columns
/// `W·I .. W·I + W`): the products of each row in fixed `W × W` blocks, entries above the
/// diagonal of a diagonal block included (they are never read). Also which blocks are nonzero:
/// bit `J` of `blocks[I]` for the block of bodies `I ≥ J`. `g` starts at zero.
fn gram_blocks<const N: usize, const W: usize>(
    n: usize,
    a: &[[f64; N]; N],
    spans: &[RowSpan; N],
    g: &mut [[f64; N]; N],
) -> [u64; N] {
    let mut blocks = [0u64; N];
    for (row, s) in a[..n].iter().zip(&spans[..n]) {
        let k = usize::from(s.k);
        for p in 0..k {
            let cj = usize::from(s.c[p]);
            for qq in 0..=p {
                let cl = usize::from(s.c[qq]);
                blocks[cj / W] |= 1 << (cl / W);
                let src: &[f64; W] = row[cl..cl + W].try_into().expect("W columns");
                for jj in 0..W {
                    let v = row[cj + jj];
                    let dst: &mut [f64; W] =
                        (&mut g[cj + jj][cl..cl + W]).try_into().expect("W columns");
                    for (x, &y) in dst.iter_mut().zip(src) {
                        *x += v * y;
                    }
                }
            }
        }
    }
    blocks
}

/// The lower triangle of `AᵀA` (`n × n`), each entry `Σ_r a[r][j]·a[r][l]` summed in row order
/// over the rows' spans. Products with an entry outside the nonzeros found by value (an exact
/// zero inside a span) add a zero, which leaves a finite sum unchanged (no sum of finite
/// products is ever `−0`, the sums start at `+0`): the same numbers as summing the nonzeros
/// only. `g` starts at zero.
fn gram_matrix<const N: usize>(
    n: usize,
    a: &[[f64; N]; N],
    spans: &[RowSpan; N],
    g: &mut [[f64; N]; N],
) {
    for (row, s) in a[..n].iter().zip(&spans[..n]) {
        let k = usize::from(s.k);
        for p in 0..k {
            let (cj, wj) = (usize::from(s.c[p]), usize::from(s.w[p]));
            for qq in 0..=p {
                let (cl, wl) = (usize::from(s.c[qq]), usize::from(s.w[qq]));
                for j in cj..cj + wj {
                    let v = row[j];
                    // Lower triangle: `l ≤ j` within the same span.
                    let hi = if qq == p { j + 1 } else { cl + wl };
                    for (x, &y) in g[j][cl..hi].iter_mut().zip(&row[cl..hi]) {
                        *x += v * y;
                    }
                }
            }
        }
    }
}

/// Whether the symmetric `g` (its lower triangle, `n × n`) has a Cholesky factor, every pivot
/// positive. Right-looking: once column `k` is scaled, each later row `i` takes its update
/// `−l_ik·l_jk` from it over consecutive entries, and only where both factors are nonzero.
///
/// The same numbers as the left-looking order: every entry receives its updates for
/// `k = 0, 1, …` in order and then its division. A skipped update subtracts an exact zero (a
/// zero times a finite number; columns with a non-finite entry are updated in full), which
/// changes no entry: no entry is ever `−0` (the Gram sums start at `+0`, an exact cancellation
/// rounds to `+0`, and the pivots are positive). So the pivots, and the first failing one, are
/// bit for bit the same; a group of bodies joined in a tree factorizes without the zero blocks.
#[allow(clippy::needless_range_loop)]
fn cholesky_runs<const N: usize>(n: usize, g: &mut [[f64; N]; N]) -> bool {
    let mut lk = [0.0f64; N];
    // The nonzero runs `[start, end)` of column `k` below the diagonal.
    let mut runs = [(0usize, 0usize); N];
    for k in 0..n {
        let d = g[k][k];
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        g[k][k] = d;
        let mut finite = true;
        for i in k + 1..n {
            let v = g[i][k] / d;
            g[i][k] = v;
            lk[i] = v;
            finite &= v.is_finite();
        }
        let mut nr = 0;
        if finite {
            let mut i = k + 1;
            while i < n {
                if lk[i] == 0.0 {
                    i += 1;
                    continue;
                }
                let s = i;
                while i < n && lk[i] != 0.0 {
                    i += 1;
                }
                runs[nr] = (s, i);
                nr += 1;
            }
        } else if k + 1 < n {
            runs[0] = (k + 1, n);
            nr = 1;
        }
        for &(s, e) in &runs[..nr] {
            for i in s..e {
                let lik = lk[i];
                let row = &mut g[i];
                // The runs up to and including `i` (lower triangle).
                for &(s2, e2) in &runs[..nr] {
                    if s2 > i {
                        break;
                    }
                    let hi = e2.min(i + 1);
                    for (x, &y) in row[s2..hi].iter_mut().zip(&lk[s2..hi]) {
                        *x -= lik * y;
                    }
                }
            }
        }
    }
    true
}

/// [`cholesky_runs`] by blocks of `W × W` (every body `W` unknowns wide, `n = W · bodies`,
/// `blocks` as [`gram_blocks`] gives them): the diagonal block of body `K` factorized, the
/// blocks below it solved, and the later blocks updated from them, skipping the blocks that
/// are zero (and stay zero: no fill reaches them). Every entry still receives `−l_ik·l_jk`
/// for `k = 0, 1, …` in order and then its division, so the pivots are bit for bit those of
/// the left-looking order (see [`cholesky_runs`] for why a skipped zero block changes
/// nothing). A non-finite entry of the factor ends it: its square would make a later pivot
/// `−∞` or NaN, which the left-looking order rejects too.
#[allow(clippy::needless_range_loop)]
fn cholesky_blocks<const N: usize, const W: usize>(
    n: usize,
    g: &mut [[f64; N]; N],
    mut blocks: [u64; N],
) -> bool {
    let nb = n / W;
    if nb * W != n || nb > 64 {
        return cholesky_runs::<N>(n, g);
    }
    for kb in 0..nb {
        let k0 = kb * W;
        // The diagonal block (all updates from earlier bodies received).
        for k in k0..k0 + W {
            let d = g[k][k];
            if d.is_nan() || d <= 0.0 {
                return false;
            }
            let d = d.sqrt();
            g[k][k] = d;
            for i in k + 1..k0 + W {
                let v = g[i][k] / d;
                if !v.is_finite() {
                    return false;
                }
                g[i][k] = v;
            }
            for i in k + 1..k0 + W {
                let lik = g[i][k];
                for j in k + 1..=i {
                    g[i][j] -= lik * g[j][k];
                }
            }
        }
        // The blocks below it: `L_IK = G_IK · L_KK^-T`, entry by entry in column order.
        let below_mask = (kb + 1..nb)
            .filter(|&ib| blocks[ib] >> kb & 1 == 1)
            .fold(0u64, |m, ib| m | 1 << ib);
        let below = |ib: usize| below_mask >> ib & 1 == 1;
        for ib in kb + 1..nb {
            if !below(ib) {
                continue;
            }
            for i in ib * W..ib * W + W {
                for k in k0..k0 + W {
                    let mut v = g[i][k];
                    for kk in k0..k {
                        v -= g[i][kk] * g[k][kk];
                    }
                    let v = v / g[k][k];
                    if !v.is_finite() {
                        return false;
                    }
                    g[i][k] = v;
                }
            }
        }
        // The later blocks: `G_IJ −= L_IK · L_JKᵀ` (for `I ≥ J`, both below `K`).
        for jb in kb + 1..nb {
            if !below(jb) {
                continue;
            }
            let mut lt = [[0.0f64; W]; W];
            for jj in 0..W {
                for kk in 0..W {
                    lt[kk][jj] = g[jb * W + jj][k0 + kk];
                }
            }
            for ib in jb..nb {
                if !below(ib) {
                    continue;
                }
                blocks[ib] |= 1 << jb;
                for i in ib * W..ib * W + W {
                    let row = &mut g[i];
                    for kk in 0..W {
                        let lik = row[k0 + kk];
                        let dst: &mut [f64; W] = (&mut row[jb * W..jb * W + W])
                            .try_into()
                            .expect("W columns");
                        for (x, &y) in dst.iter_mut().zip(&lt[kk]) {
                            *x -= lik * y;
                        }
                    }
                }
            }
        }
    }
    true
}

/// The Gram proof as it was before [`gram_matrix`] and [`cholesky_runs`] (the nonzeros of
/// each row found by value, a left-looking factorization): the tests' reference.
#[cfg(test)]
#[allow(clippy::needless_range_loop)]
fn gram_proves_reference<const N: usize>(n: usize, a: &[[f64; N]; N], frob: f64, t: &Tol) -> bool {
    let tr = frob * frob;
    if !(tr > 1e-200 && tr.is_finite()) {
        return false;
    }
    let beta = (1e-4 * frob).max(4.0 * (n as f64).sqrt() * SCREEN_MARGIN * t.cut(frob, n));
    let shift = beta * beta + 1e-12 * tr;
    let mut g = gram_reference::<N>(n, a);
    for j in 0..n {
        g[j][j] -= shift;
    }
    cholesky_reference::<N>(n, &mut g)
}

/// The reference's Gram matrix: the lower triangle of `AᵀA`, row by row of `A` over the
/// nonzero columns found by value.
#[cfg(test)]
#[allow(clippy::needless_range_loop)]
fn gram_reference<const N: usize>(n: usize, a: &[[f64; N]; N]) -> [[f64; N]; N] {
    let mut g = [[0.0f64; N]; N];
    let mut nz = [0usize; N];
    for row in &a[..n] {
        let mut k = 0;
        for (j, &v) in row[..n].iter().enumerate() {
            if v != 0.0 {
                nz[k] = j;
                k += 1;
            }
        }
        for p in 0..k {
            let j = nz[p];
            let v = row[j];
            for &l in &nz[..=p] {
                g[j][l] += v * row[l];
            }
        }
    }
    g
}

/// The reference's factorization: left-looking, in place (the factor overwrites the lower
/// triangle); whether every pivot is positive.
#[cfg(test)]
#[allow(clippy::needless_range_loop)]
fn cholesky_reference<const N: usize>(n: usize, g: &mut [[f64; N]; N]) -> bool {
    for j in 0..n {
        let mut d = g[j][j];
        for k in 0..j {
            d -= g[j][k] * g[j][k];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        g[j][j] = d;
        for i in j + 1..n {
            let mut v = g[i][j];
            for k in 0..j {
                v -= g[i][k] * g[j][k];
            }
            g[i][j] = v / d;
        }
    }
    true
}

/// Whether the stacked `rows` (`b` columns) surely have full column rank, far from the SVD
/// threshold. Gaussian elimination with partial pivoting picks `b` rows, a square submatrix
/// `T` with `|det T|` the product of the pivots and `σ_min(T) ≥ |det T| / ‖T‖_F^(b−1)`;
/// removing rows never raises `σ_min`, and `σ_max ≤ F`, the Frobenius norm of all rows. So
/// `|det T| > 1e-6 · F · ‖T‖_F^(b−1)` means `σ_min > 1e-6 · σ_max`, far above the SVD
/// threshold (`n ·` [`REL_TOL`] with n ≤ 48 rows here). Runs for every body, on the stack.
fn surely_full_rank<'a>(b: usize, total: usize, rows: impl Iterator<Item = RowsView<'a>>) -> bool {
    // The arrays sized to the stack of rows (zeroing 48 rows for a body held by two pairs
    // cost as much as the elimination).
    match total {
        0..=8 => full_rank_within::<8>(b, rows),
        9..=16 => full_rank_within::<16>(b, rows),
        17..=24 => full_rank_within::<24>(b, rows),
        25..=32 => full_rank_within::<32>(b, rows),
        _ => full_rank_within::<48>(b, rows),
    }
}

/// [`surely_full_rank`] with arrays of `MAX_ROWS` rows (fewer rows than that in `rows`, or
/// the answer is `false`).
fn full_rank_within<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> bool {
    elimination::<MAX_ROWS>(b, rows).is_some_and(|e| e.proves(b))
}

/// What [`full_rank_within`] decides on: `|det T|` (the product of the pivots' magnitudes),
/// `F²` (all rows) and `‖T‖_F²` (the pivot rows).
#[derive(Clone, Copy, Debug)]
struct Eliminated {
    det: f64,
    frob2: f64,
    sub2: f64,
}

impl Eliminated {
    /// `|det T| > 1e-6 · F · ‖T‖_F^(b−1)`.
    fn proves(&self, b: usize) -> bool {
        self.det > 1e-6 * self.frob2.sqrt() * self.sub2.sqrt().powi(b as i32 - 1)
    }
}

/// The elimination of [`full_rank_within`]; `None` where it answers `false` before the test
/// (more than `MAX_ROWS` rows, fewer than `b`, all zero, a zero pivot).
///
/// The stack is held column by column (`a[k][row]`): a step's multipliers `row[c] / pivot`
/// and its updates `row[k] −= f · top[k]` run over consecutive rows, two to an instruction,
/// and only on the columns still to be read (`c + 1 .. b`). Every entry that is read gets
/// the operations of the row-major elimination it replaced (kept as the tests' reference,
/// `elimination_reference`) in the same order, and each pivot is the same row (the last of
/// the largest magnitudes, as `max_by` of `total_cmp` chose it), so the three numbers are
/// bit for bit the same. The row-major elimination divided one row at a time and updated
/// the dead columns too.
#[allow(clippy::needless_range_loop)]
fn elimination<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> Option<Eliminated> {
    if b > 6 {
        return None;
    }
    let mut a = [[0.0f64; MAX_ROWS]; 6];
    let mut norm2 = [0.0f64; MAX_ROWS];
    let mut n = 0;
    for r in rows {
        for i in 0..r.nrows() {
            if n == MAX_ROWS {
                return None;
            }
            let mut s = 0.0;
            for k in 0..b {
                let v = r[(i, k)];
                a[k][n] = v;
                s += v * v;
            }
            norm2[n] = s;
            n += 1;
        }
    }
    let frob2: f64 = norm2[..n].iter().sum();
    if n < b || frob2 == 0.0 {
        return None;
    }
    let mut det = 1.0f64;
    let mut sub2 = 0.0;
    let mut f = [0.0f64; MAX_ROWS];
    for c in 0..b {
        // Magnitudes have no sign bit: `total_cmp` orders them as their bits do. `>=` keeps
        // the last of equal ones, as `max_by` did.
        let mut p = c;
        let mut best = 0u64;
        for (i, v) in a[c][..n].iter().enumerate().skip(c) {
            let key = v.to_bits() & !(1u64 << 63);
            if key >= best {
                best = key;
                p = i;
            }
        }
        let pivot = a[c][p];
        if pivot == 0.0 {
            return None;
        }
        // Columns before `c` are never read again: only the live ones swap.
        for col in a[c..b].iter_mut() {
            col.swap(c, p);
        }
        norm2.swap(c, p);
        det *= pivot.abs();
        sub2 += norm2[c];
        for (fi, &x) in f[c + 1..n].iter_mut().zip(&a[c][c + 1..n]) {
            *fi = x / pivot;
        }
        for k in c + 1..b {
            let t = a[k][c];
            for (x, &fi) in a[k][c + 1..n].iter_mut().zip(&f[c + 1..n]) {
                *x -= fi * t;
            }
        }
    }
    Some(Eliminated { det, frob2, sub2 })
}

/// [`elimination`] as it was (row by row, the row updates over columns `c..b`): the tests'
/// reference.
#[cfg(test)]
fn elimination_reference<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> Option<Eliminated> {
    let mut a = [[0.0f64; 6]; MAX_ROWS];
    let mut norm2 = [0.0f64; MAX_ROWS];
    let mut n = 0;
    if b > 6 {
        return None;
    }
    for r in rows {
        for i in 0..r.nrows() {
            if n == MAX_ROWS {
                return None;
            }
            for k in 0..b {
                a[n][k] = r[(i, k)];
                norm2[n] += a[n][k] * a[n][k];
            }
            n += 1;
        }
    }
    let frob2: f64 = norm2[..n].iter().sum();
    if n < b || frob2 == 0.0 {
        return None;
    }
    let mut det = 1.0f64;
    let mut sub2 = 0.0;
    for c in 0..b {
        let p = (c..n)
            .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
            .unwrap_or(c);
        let pivot = a[p][c];
        if pivot == 0.0 {
            return None;
        }
        a.swap(c, p);
        norm2.swap(c, p);
        det *= pivot.abs();
        sub2 += norm2[c];
        let top = a[c];
        for row in a.iter_mut().take(n).skip(c + 1) {
            let f = row[c] / pivot;
            for k in c..b {
                row[k] -= f * top[k];
            }
        }
    }
    Some(Eliminated { det, frob2, sub2 })
}

/// [`full_rank_within`] as it was: the tests' reference.
#[cfg(test)]
fn full_rank_within_reference<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> bool {
    elimination_reference::<MAX_ROWS>(b, rows).is_some_and(|e| e.proves(b))
}

/// Decisions of the rank check kept across analyses of one mechanism under different inputs
/// (`mbsa transform` analyses many placements): a body's reduced unknowns and a sound block's
/// verdict are functions of the rows involved (and the tolerance), so they are keyed by a
/// 128-bit digest of exactly those rows and reused when the same rows come again. Deficient
/// blocks are never cached (their explanation is recomputed), so a hit only skips a
/// factorization whose result is known: the analysis is the same with or without a cache.
#[derive(Default)]
pub struct Cache {
    bases: Mutex<HashMap<u128, Option<DMatrix<f64>>>>,
    blocks: Mutex<HashMap<u128, Option<Unchecked>>>,
}

/// Entries a [`Cache`] keeps before it starts over (memory stays bounded).
const CACHE_ENTRIES: usize = 1 << 21;

impl Cache {
    fn get_basis(&self, k: u128) -> Option<Option<DMatrix<f64>>> {
        let g = self.bases.lock().unwrap_or_else(|e| e.into_inner());
        g.get(&k).cloned()
    }
    fn put_basis(&self, k: u128, v: &Option<DMatrix<f64>>) {
        let mut g = self.bases.lock().unwrap_or_else(|e| e.into_inner());
        if g.len() >= CACHE_ENTRIES {
            g.clear();
        }
        g.insert(k, v.clone());
    }
    fn get_block(&self, k: u128) -> Option<Option<Unchecked>> {
        let g = self.blocks.lock().unwrap_or_else(|e| e.into_inner());
        g.get(&k).cloned()
    }
    fn put_block(&self, k: u128, v: Option<Unchecked>) {
        let mut g = self.blocks.lock().unwrap_or_else(|e| e.into_inner());
        if g.len() >= CACHE_ENTRIES {
            g.clear();
        }
        g.insert(k, v);
    }
}

/// Two independent 64-bit SipHash streams (fixed keys: deterministic) fed the same words.
struct Digest(DefaultHasher, DefaultHasher);

impl Digest {
    fn new(tag: u64) -> Digest {
        let mut d = Digest(DefaultHasher::new(), DefaultHasher::new());
        d.1.write_u64(0x9e37_79b9_7f4a_7c15);
        d.word(tag);
        d
    }
    fn word(&mut self, v: u64) {
        self.0.write_u64(v);
        self.1.write_u64(v);
    }
    fn wide(&mut self, v: u128) {
        self.word(v as u64);
        self.word((v >> 64) as u64);
    }
    fn matrix<S: RawStorage<f64, Dyn, Dyn>>(&mut self, a: &nalgebra::Matrix<f64, Dyn, Dyn, S>) {
        self.word(a.nrows() as u64);
        self.word(a.ncols() as u64);
        for x in a.iter() {
            self.word(x.to_bits());
        }
    }
    fn finish(&self) -> u128 {
        (u128::from(self.0.finish()) << 64) | u128::from(self.1.finish())
    }
}

/// What a block's cache key is made of besides the block itself.
struct KeyContext<'a> {
    tol: &'a [u64; 3],
    seed: Option<u64>,
    qd: &'a [u128],
    rd: &'a [u128],
    orig_rows: &'a [u8],
}

impl KeyContext<'_> {
    /// The key of a block: everything its verdict depends on (its part, bodies with their
    /// unknowns, pairs with their bodies and rows, whether any pair was lowered).
    fn block(
        &self,
        part: Part,
        bodies: &[usize],
        block_eqs: &[usize],
        eqs: &Equations,
        rows: &PairRows,
    ) -> u128 {
        let mut d = Digest::new(3);
        self.tol.iter().for_each(|&w| d.word(w));
        d.word(match part {
            Part::Over => 0,
            Part::Under => 1,
            _ => 2,
        });
        d.word(self.seed.unwrap_or(u64::MAX));
        d.word(bodies.len() as u64);
        for &x in bodies {
            d.word(x as u64);
            d.wide(self.qd[x]);
        }
        d.word(block_eqs.len() as u64);
        for &e in block_eqs {
            let [h, o] = eqs.bodies(e);
            d.word(e as u64);
            d.word(h as u64);
            d.word(o as u64);
            d.wide(self.rd[e]);
            d.word(u64::from(rows.nrows(e) == usize::from(self.orig_rows[e])));
        }
        d.finish()
    }
}

fn matrix_digest<S: RawStorage<f64, Dyn, Dyn>>(a: &nalgebra::Matrix<f64, Dyn, Dyn, S>) -> u128 {
    let mut d = Digest::new(1);
    d.matrix(a);
    d.finish()
}

/// Realizations a deficit may be drawn at before it is reported without confirmation.
const MAX_DRAWS: u64 = 8;

/// The seed of the `attempt`-th independent redraw of a random realization `seed`.
fn fresh_seed(seed: u64, attempt: u64) -> u64 {
    seed ^ attempt.wrapping_mul(0x9e37_79b9_7f4a_7c15)
}

/// Which joints a random realization draws at another seed than the analysis's, and the
/// attempt whose draws confirm a deficit ([`confirm_seeds`]; `None`: deficits are reported as
/// found).
#[derive(Default)]
struct Redraw {
    joints: HashMap<usize, u64>,
    confirm: Option<u64>,
    /// The joints drawn again since the last attempt, and that attempt's rows with each pair's
    /// first row count: only their pairs and the pairs it lowered are built again.
    fresh: HashSet<usize>,
    rows: Option<Kept>,
}

/// Run the check; `eqs.cap` and `u` are lowered in place. With a `cache`, bodies' reduced
/// unknowns and sound blocks seen in an earlier analysis (same rows, same tolerance) are
/// taken from it instead of being factorized again. `geoms` is the joints' geometry when the
/// file's is used; a random realization (`used.seed`) is drawn joint by joint instead.
///
/// At a random realization a deficit (an isolated freedom, a deficient block) is reported only
/// when a second, independent realization of the joints involved has it too: a generic rank is
/// the largest over realizations, and one draw can be degenerate (the synthetic contact lines
/// of the count-only kinds). Only the deficits are drawn again (a body's own rows, a block's
/// exact rank over GF(2^61 − 1) at another seed), so a check without deficits costs nothing
/// more. When the second draw has the larger rank, the joints involved are drawn at it and the
/// check starts over (at most [`MAX_DRAWS`] draws); everything stays a function of `--seed`.
pub(crate) fn check(
    m: &Mechanism,
    geoms: &[Geometry],
    used: &GeometryUsed,
    eqs: &mut Equations,
    u: &mut [u32],
    cache: Option<&Cache>,
    shortcut: Shortcut,
) -> RankResult {
    if used.seed.is_none() {
        return check_at(
            m,
            geoms,
            used,
            eqs,
            u,
            cache,
            shortcut,
            &mut Redraw::default(),
        );
    }
    let (cap0, u0) = (eqs.cap.clone(), u.to_vec());
    let mut redraw = Redraw::default();
    let mut work = 0u64;
    let mut attempt = 1;
    loop {
        redraw.confirm = (attempt < MAX_DRAWS).then_some(attempt);
        let mut r = check_at(m, geoms, used, eqs, u, cache, shortcut, &mut redraw);
        work = work.saturating_add(r.work);
        if redraw.confirm.is_none() || r.suspects.is_empty() {
            r.work = work;
            return r;
        }
        redraw.fresh.clear();
        for &(j, s) in &r.suspects {
            redraw.joints.insert(j, s);
            redraw.fresh.insert(j);
        }
        redraw.rows = r.kept_rows.take();
        eqs.cap.copy_from_slice(&cap0);
        u.copy_from_slice(&u0);
        attempt += 1;
    }
}

/// Signatures of the blocks found sound (bodies, then pairs with their rows), hashed word by
/// word: the under- and over-determined blocks' signatures have millions of words at 10^6
/// bodies, and SipHash over them (again at every growth of the set) was 2 % of `analyze`.
type Signatures = HashSet<Vec<u32>, std::hash::BuildHasherDefault<SignatureHasher>>;

/// A block's signature: its bodies, a separator, then each pair with its row count, four
/// bytes a word (every index fits: the flow network numbers its nodes and edges in `u32`).
/// The sound blocks' signatures are held through the next rounds' decompositions.
fn block_signature(bodies: &[usize], block_eqs: &[usize], rows: &PairRows) -> Vec<u32> {
    let word = |x: usize| {
        debug_assert!(x < u32::MAX as usize);
        x as u32
    };
    let mut signature = Vec::with_capacity(bodies.len() + 1 + 2 * block_eqs.len());
    signature.extend(bodies.iter().map(|&x| word(x)));
    signature.push(u32::MAX);
    for &e in block_eqs {
        signature.push(word(e));
        signature.push(word(rows.nrows(e)));
    }
    signature
}

/// A multiplicative hash of 64-bit words (Fx-like; the keys are our own indices, not input
/// an attacker chooses to collide).
#[derive(Default)]
struct SignatureHasher(u64);

impl SignatureHasher {
    fn word(&mut self, w: u64) {
        self.0 = (self.0.rotate_left(5) ^ w).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for SignatureHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.word(u64::from_le_bytes(w.try_into().expect("8 bytes")));
        }
        let rest = words.remainder();
        if !rest.is_empty() {
            let mut w = [0u8; 8];
            w[..rest.len()].copy_from_slice(rest);
            self.word(u64::from_le_bytes(w));
        }
    }

    fn write_usize(&mut self, x: usize) {
        self.word(x as u64);
    }

    fn finish(&self) -> u64 {
        // The high bits mixed into the low ones (the table indexes by the low bits).
        self.0 ^ (self.0 >> 29)
    }
}

/// [`check`] at one realization: the joints in `redraw.joints` at their own seeds.
#[allow(clippy::too_many_arguments)]
fn check_at(
    m: &Mechanism,
    geoms: &[Geometry],
    used: &GeometryUsed,
    eqs: &mut Equations,
    u: &mut [u32],
    cache: Option<&Cache>,
    shortcut: Shortcut,
    redraw: &mut Redraw,
) -> RankResult {
    let certified = shortcut == Shortcut::Certified;
    let b = m.b() as usize;
    let nb = eqs.nodes;
    // The last attempt's bases, and which pairs were built again since (their bodies' bases
    // are computed again; every other body's rows are as they were).
    let mut prev: Option<(Bases, Vec<bool>)> = None;
    let (mut rows, free) = match (redraw.rows.take(), used.seed) {
        (Some(kept), Some(seed)) => {
            // The last attempt's rows (random realizations only): the pairs of the joints
            // drawn again and the pairs it lowered are built again, the rest is as drawn.
            let Kept {
                mut rows,
                first,
                bases,
            } = kept;
            let mut changed = vec![false; first.len()];
            for (e, &n) in first.iter().enumerate() {
                let ji = eqs.joint[e];
                if rows.nrows(e) != usize::from(n) || redraw.fresh.contains(&ji) {
                    let s = redraw.joints.get(&ji).copied().unwrap_or(seed);
                    rows.set(e, &pair_rows_at(m, eqs, e, s));
                    changed[e] = true;
                }
            }
            prev = Some((bases, changed));
            (rows, PairRows::from_chunks(b, Vec::new()))
        }
        _ => pair_rows(m, geoms, used.seed, &redraw.joints, eqs, used.is_file()),
    };
    // Deficits are confirmed at the draws of this attempt (random geometry only).
    let confirm = redraw.confirm.filter(|_| used.seed.is_some());
    // At the file's geometry every body's unknowns are its twist about its own reference
    // point (see [`LocalFrames`]): the rank decisions no longer depend on how far the body
    // sits from the centre.
    let local = used
        .is_file()
        .then(|| LocalFrames::new(m, geoms, eqs))
        .flatten();
    let tol = match used.precision {
        Some(_) => Tol {
            rel: 1e-9,
            abs: match &local {
                Some(lf) => lf.threshold(used),
                None => crate::motion::file_threshold(m, used).unwrap_or(0.0),
            },
        },
        None => Tol {
            rel: REL_TOL,
            abs: 0.0,
        },
    };
    // At the file's configuration, constraints that are dependent there (a planar loop written
    // in space, a Bennett or Bricard linkage) are set aside first: the configuration satisfies
    // them, so they fix nothing, and the decomposition runs on what remains.
    let mut set_aside = vec![0u32; m.joints.len()];
    let configuration = if used.is_file() {
        redundant_at_configuration(
            m,
            eqs,
            &mut rows,
            &free,
            &tol,
            local.as_ref(),
            &mut set_aside,
        )
    } else {
        Vec::new()
    };
    for (e, cap) in eqs.cap.iter_mut().enumerate() {
        *cap = rows.nrows(e) as u32;
    }
    // Each pair's first row count (at most `b`, six: one byte a pair).
    let orig_rows: Vec<u8> = (0..rows.len())
        .map(|e| u8::try_from(rows.nrows(e)).expect("a pair has at most six rows"))
        .collect();
    // Digests of every pair's rows (only with a cache), and of the tolerance.
    let mut rd: Vec<u128> = match cache {
        Some(_) => crate::par::map(rows.len(), |e| matrix_digest(&rows.get(e))),
        None => Vec::new(),
    };
    let tol_words = [tol.rel.to_bits(), tol.abs.to_bits(), b as u64];

    // Pairs touching each body (compressed: `touch[start[x]..start[x + 1]]`), proper pairs
    // only (a pair of a body with itself constrains nothing). Four bytes an entry (a pair
    // number fits `u32`, as in the decomposition's lists): the pass that fills them writes at
    // random, and half the bytes are half the cache lines and pages it takes.
    let mut start = vec![0u32; nb + 1];
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
    let mut touch = vec![0u32; start[nb] as usize];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        if h != o {
            for x in [h, o] {
                touch[fill[x] as usize] = e as u32;
                fill[x] += 1;
            }
        }
    }
    drop(fill);
    let touching = |x: usize| &touch[start[x] as usize..start[x + 1] as usize];

    // (a) Isolated freedoms and reduced unknowns (each body on its own, in parallel).
    // The first pin pair of every element node.
    let mut pin_pair = vec![usize::MAX; eqs.elements.len()];
    for e in (0..eqs.len()).rev() {
        if eqs.is_element(eqs.hub[e]) && !eqs.input_only[e] {
            pin_pair[eqs.hub[e] - eqs.bodies] = e;
        }
    }
    let bases: Vec<Option<DMatrix<f64>>> = crate::par::map(nb, |body| {
        if body == m.frame {
            return Some(DMatrix::zeros(b, 0));
        }
        if eqs.is_element(body) {
            // The shared element moves only across its joint's constraint directions: its
            // unknowns are the row space of the joint's rows (orthonormal, so their transpose).
            // (At the file's configuration `rows` may already have lost dependent equations:
            // the joint's full rows are in `free` then.)
            let e = pin_pair[body - eqs.bodies];
            return Some(
                free.try_get(e)
                    .or(rows.try_get(e))
                    .map_or_else(|| DMatrix::zeros(b, 0), |r| r.transpose()),
            );
        }
        let mine = touching(body);
        if let Some((bases, changed)) = &prev
            && !mine.iter().any(|&e| changed[e as usize])
        {
            // Same rows, same tolerance: the last attempt's basis.
            return bases[body].clone();
        }
        let frame = local.as_ref().and_then(|lf| lf.frame[body].as_ref());
        // Isolated means undrivable: a motion across a cut of two or more constraining joints.
        // A body on one joint moves by that joint's own DOF, which an input drives.
        let mut joints = mine
            .iter()
            .map(|&e| e as usize)
            .filter(|&e| rows.nrows(e) > 0)
            .map(|e| eqs.joint[e]);
        let first = joints.next();
        if !joints.any(|j| Some(j) != first) {
            return frame.cloned();
        }
        let basis = |rows: &PairRows| match frame {
            Some(s) => Some(local_basis(
                b,
                mine.iter().map(|&e| rows.get(e as usize)),
                s,
                &tol,
            )),
            None => reduced_basis(b, mine.iter().map(|&e| rows.get(e as usize)), &tol),
        };
        let Some(c) = cache else {
            return basis(&rows);
        };
        let mut d = Digest::new(2);
        tol_words.iter().for_each(|&w| d.word(w));
        mine.iter().for_each(|&e| d.wide(rd[e as usize]));
        if let Some(s) = frame {
            d.matrix(s);
        }
        let k = d.finish();
        if let Some(hit) = c.get_basis(k) {
            return hit;
        }
        let v = basis(&rows);
        c.put_basis(k, &v);
        v
    });
    // The bases are the reduced unknowns as they are (moved into a second list of 10^6
    // entries, both were held at once).
    let q: Vec<Option<DMatrix<f64>>> = bases;
    let mut isolated = Vec::new();
    for (body, basis) in q.iter().enumerate() {
        let kept = basis.as_ref().map_or(b, |x| x.ncols());
        let iso = b - kept;
        if body != m.frame && iso > 0 && !eqs.is_element(body) {
            isolated.push(Isolated {
                body: m.body_id(body).to_string(),
                dimension: iso as u32,
            });
        }
        u[body] = kept as u32;
    }
    // An isolated freedom at a random realization is confirmed at a second one: the body's
    // pairs drawn again (a generic nullity is the smallest over realizations).
    if let (Some(attempt), Some(seed)) = (confirm, used.seed) {
        let iso_bodies: Vec<usize> = (0..nb)
            .filter(|&x| x != m.frame && !eqs.is_element(x) && width(b, &q, x) < b)
            .collect();
        let spurious = crate::par::map(iso_bodies.len(), |i| {
            let x = iso_bodies[i];
            let mine = touching(x);
            confirm_seeds(seed, attempt).find(|&second| {
                let fresh = PairRows::from_chunks(
                    b,
                    mine.chunks(PAIRS_PER_CHUNK)
                        .map(|c| {
                            let mut chunk = Chunk::default();
                            c.iter().for_each(|&e| {
                                chunk.push_matrix(&pair_rows_at(m, eqs, e as usize, second))
                            });
                            chunk
                        })
                        .collect(),
                );
                let again = reduced_basis(b, (0..mine.len()).map(|i| fresh.get(i)), &tol);
                again.as_ref().map_or(b, |a| a.ncols()) > width(b, &q, x)
            })
        });
        let joint = &eqs.joint;
        let mut suspects: Vec<(usize, u64)> = iso_bodies
            .iter()
            .zip(spurious)
            .filter_map(|(&x, s)| s.map(|s| (x, s)))
            .flat_map(|(x, s)| touching(x).iter().map(move |&e| (joint[e as usize], s)))
            .collect();
        if !suspects.is_empty() {
            suspects.sort_unstable();
            suspects.dedup();
            // [`check`] starts over: the decomposition is never read.
            return RankResult {
                deficient: false,
                work: 0,
                decomposition: Decomposition {
                    body_part: Vec::new(),
                    eq_part: Vec::new(),
                    groups: Vec::new(),
                    eq_excess: Vec::new(),
                    body_missing: Vec::new(),
                },
                set_aside,
                isolated,
                redundant: configuration,
                unchecked: Vec::new(),
                rounds: 0,
                kept_rows: Some(Kept {
                    rows,
                    first: orig_rows,
                    bases: q,
                }),
                suspects,
            };
        }
    }
    drop(touch);
    drop(start);
    let qd: Vec<u128> = match cache {
        Some(_) => crate::par::map(nb, |x| {
            q[x].as_ref()
                .map_or(0, |a| matrix_digest(a).wrapping_add(1))
        }),
        None => Vec::new(),
    };
    // The key of a block for the cache: everything its verdict depends on (its part, bodies
    // with their unknowns, pairs with their bodies and rows, whether any pair was lowered).

    // (b)-(c) Decompose, check every block, lower, repeat.
    let mut redundant = configuration;
    let mut unchecked: Vec<Unchecked> = Vec::new();
    // Blocks already found sound, keyed by their bodies and their pairs with row counts (a
    // block's rank depends on nothing else), so a repeat pass only checks what changed.
    let mut verified = Signatures::default();
    let mut rounds = 0;
    let mut work = 0u64;
    // Joints of deficits a second realization did not confirm (see [`check`]).
    let mut suspects: Vec<(usize, u64)> = Vec::new();
    // The previous round's decomposition, and the pairs lowered since with their counts
    // then: a later round's decomposition starts from what it found.
    let mut prior: Option<FlowRound> = None;
    let mut lowerings: Vec<(usize, u32)> = Vec::new();
    loop {
        rounds += 1;
        let (dec, round) = decompose_next(m, eqs, u, prior.as_ref().map(|r| (r, &lowerings[..])));
        prior = round;
        lowerings.clear();
        // Blocks in triangular order: over-determined part, groups, under-determined part.
        let over: Vec<usize> = (0..nb)
            .filter(|&x| dec.body_part[x] == Part::Over)
            .collect();
        if certified && over.is_empty() && redundant.is_empty() {
            // The caller proved the whole system of full row rank: with no over-determined
            // part the blocks are square groups (nonsingular) and the under-determined block
            // (full row rank), in block triangular order. Nothing to factorize.
            return RankResult {
                deficient: false,
                work,
                decomposition: dec,
                set_aside,
                isolated,
                redundant,
                unchecked,
                rounds,
                suspects: Vec::new(),
                kept_rows: None,
            };
        }
        if shortcut == Shortcut::Determined
            && rounds == 1
            && (!over.is_empty() || (0..nb).any(|x| dec.body_part[x] == Part::Under))
        {
            // Not determined by count: the check only lowers equations, so it cannot become
            // determined (an over-determined block loses rows only when it hides a freedom,
            // which then shows as missing DOF).
            return RankResult {
                deficient: true,
                work,
                decomposition: dec,
                set_aside,
                isolated,
                redundant,
                unchecked,
                rounds,
                suspects: Vec::new(),
                kept_rows: None,
            };
        }
        if shortcut == Shortcut::Determined && rounds == 1 {
            // Determined by count: any deficient group makes it under-determined. The small
            // groups first (most are in the cache), before any large one is factorized.
            let mut gstart = vec![0usize; dec.groups.len() + 1];
            for e in 0..rows.len() {
                if rows.nrows(e) > 0
                    && let Part::Group(g) = dec.eq_part[e]
                    && g < dec.groups.len()
                {
                    gstart[g + 1] += 1;
                }
            }
            for g in 0..dec.groups.len() {
                gstart[g + 1] += gstart[g];
            }
            let mut gfill = gstart.clone();
            let mut geqs = vec![0usize; gstart[dec.groups.len()]];
            for e in 0..rows.len() {
                if rows.nrows(e) > 0
                    && let Part::Group(g) = dec.eq_part[e]
                    && g < dec.groups.len()
                {
                    geqs[gfill[g]] = e;
                    gfill[g] += 1;
                }
            }
            let small: Vec<(usize, u128)> = (0..dec.groups.len())
                .filter_map(|g| {
                    let block_eqs = &geqs[gstart[g]..gstart[g + 1]];
                    let bodies = &dec.groups[g].bodies;
                    if block_eqs.is_empty() {
                        return None;
                    }
                    let (nrows, ncols) = block_shape(b, block_eqs, bodies, &rows, &q);
                    if nrows.max(ncols) > MAX_DENSE_UNKNOWNS {
                        return None;
                    }
                    let key = cache.map_or(0, |_| {
                        KeyContext {
                            tol: &tol_words,
                            seed: used.seed,
                            qd: &qd,
                            rd: &rd,
                            orig_rows: &orig_rows,
                        }
                        .block(
                            Part::Group(g),
                            bodies,
                            block_eqs,
                            eqs,
                            &rows,
                        )
                    });
                    if let Some(c) = cache
                        && c.get_block(key).is_some()
                    {
                        return None;
                    }
                    Some((g, key))
                })
                .collect();
            let sound: Vec<(bool, u64)> = crate::par::map(small.len(), |i| {
                let g = small[i].0;
                let block_eqs = &geqs[gstart[g]..gstart[g + 1]];
                let bodies = &dec.groups[g].bodies;
                let (nrows, ncols) = block_shape(b, block_eqs, bodies, &rows, &q);
                let (rank, cost) = block_rank(
                    b,
                    block_eqs,
                    bodies,
                    eqs,
                    &rows,
                    &q,
                    Part::Group(g),
                    &tol,
                    (nrows, ncols),
                );
                (rank >= nrows, cost)
            });
            work = work.saturating_add(sound.iter().map(|s| s.1).sum());
            if sound.iter().any(|&(s, _)| !s) {
                // Each deficient group confirmed at a second realization first.
                let mut suspects = Vec::new();
                if let (Some(attempt), Some(seed)) = (confirm, used.seed) {
                    for (&(g, _), _) in small.iter().zip(&sound).filter(|(_, s)| !s.0) {
                        let block_eqs = &geqs[gstart[g]..gstart[g + 1]];
                        let bodies = &dec.groups[g].bodies;
                        let shape = block_shape(b, block_eqs, bodies, &rows, &q);
                        if let Some(s) = unconfirmed(
                            m,
                            eqs,
                            block_eqs,
                            bodies,
                            &rows,
                            &orig_rows,
                            shape,
                            shape.0,
                            confirm_seeds(seed, attempt),
                            &mut work,
                        ) {
                            suspects.extend(block_eqs.iter().map(|&e| (eqs.joint[e], s)));
                        }
                    }
                }
                if !suspects.is_empty() {
                    suspects.sort_unstable();
                    suspects.dedup();
                    return RankResult {
                        deficient: false,
                        work,
                        decomposition: dec,
                        set_aside,
                        isolated,
                        redundant,
                        unchecked,
                        rounds,
                        kept_rows: Some(Kept {
                            rows,
                            first: orig_rows,
                            bases: q,
                        }),
                        suspects,
                    };
                }
                return RankResult {
                    deficient: true,
                    work,
                    decomposition: dec,
                    set_aside,
                    isolated,
                    redundant,
                    unchecked,
                    rounds,
                    suspects: Vec::new(),
                    kept_rows: None,
                };
            }
            if let Some(c) = cache {
                for &(_, key) in &small {
                    c.put_block(key, None);
                }
            }
        }
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
        for e in 0..rows.len() {
            if rows.nrows(e) == 0 {
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
        for e in 0..rows.len() {
            if rows.nrows(e) == 0 {
                continue;
            }
            if let Some(i) = block_of(dec.eq_part[e]) {
                beqs[bfill[i]] = e;
                bfill[i] += 1;
            }
        }
        // Blocks to check, in triangular order; already verified and oversized ones skipped.
        let mut todo: Vec<Pending> = Vec::new();
        let mut keys: Vec<Option<u128>> = Vec::new();
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
            let signature = block_signature(bodies, block_eqs, &rows);
            if verified.contains(&signature) {
                continue;
            }
            let key = cache.map(|_| {
                let ctx = KeyContext {
                    tol: &tol_words,
                    seed: used.seed,
                    qd: &qd,
                    rd: &rd,
                    orig_rows: &orig_rows,
                };
                ctx.block(part, bodies, block_eqs, eqs, &rows)
            });
            if let (Some(c), Some(k)) = (cache, key)
                && let Some(hit) = c.get_block(k)
            {
                unchecked.extend(hit);
                verified.insert(signature);
                continue;
            }
            let (nrows, ncols) = block_shape(b, block_eqs, bodies, &rows, &q);
            if nrows.max(ncols) > MAX_DENSE_UNKNOWNS {
                // Too large for the dense SVD. At a random realization its rank is decided
                // exactly, by sparse elimination over GF(2^61 − 1), unless a pair of it was
                // already lowered (its exact rows would not be the ones kept).
                let needed = if part == Part::Over { ncols } else { nrows };
                let untouched = block_eqs
                    .iter()
                    .all(|&e| rows.nrows(e) == usize::from(orig_rows[e]));
                if let Some(seed) = used.seed
                    && untouched
                    && needed <= nrows.min(ncols)
                    && ncols <= MAX_EXACT_UNKNOWNS
                    && exact_rank(m, eqs, block_eqs, bodies, seed, &mut work) >= needed
                {
                    if let (Some(c), Some(k)) = (cache, key) {
                        c.put_block(k, None);
                    }
                    verified.insert(signature);
                    continue;
                }
                // At the file's geometry: a sparse elimination that proves full rank.
                if used.seed.is_none()
                    && sparse_full_rank(b, block_eqs, bodies, eqs, &rows, &q, part, &tol, true)
                        .is_some_and(|r| r >= needed)
                {
                    if let (Some(c), Some(k)) = (cache, key) {
                        c.put_block(k, None);
                    }
                    verified.insert(signature);
                    continue;
                }
                let u = Unchecked {
                    bodies: bodies.len(),
                    unknowns: ncols,
                    equations: nrows,
                };
                if let (Some(c), Some(k)) = (cache, key) {
                    c.put_block(k, Some(u.clone()));
                }
                unchecked.push(u);
                verified.insert(signature);
                continue;
            }
            keys.push(key);
            todo.push((block_eqs, bodies, part, signature, (nrows, ncols)));
        }
        // Ranks of all of them in parallel (each depends on its own rows only); the first
        // deficient one in order is then explained and lowered, as a serial pass would.
        let ranks: Vec<(usize, u64)> = crate::par::map(todo.len(), |i| {
            let (block_eqs, bodies, part, ..) = &todo[i];
            block_rank(b, block_eqs, bodies, eqs, &rows, &q, *part, &tol, todo[i].4)
        });
        work = work.saturating_add(ranks.iter().map(|r| r.1).sum());
        let ranks: Vec<usize> = ranks.into_iter().map(|r| r.0).collect();
        // Most blocks are found sound: room for all of them at once (grown by doubling, the
        // set rehashed every signature about once more, 2 % of `analyze` at 10^6 bodies).
        verified.reserve(todo.len());
        let mut changed = false;
        // Several groups can lose rows in one round (see `Round`); what a lowered group
        // reaches (its dependents, then the under-determined block) waits for the next one.
        let mut round = Round::new(
            b,
            &q,
            &rows,
            &orig_rows,
            &dec,
            first_group,
            &bstart,
            &beqs,
            &under,
        );
        for (((block_eqs, bodies, part, signature, (nrows, ncols)), rank), key) in
            todo.into_iter().zip(ranks).zip(keys)
        {
            match part {
                Part::Group(g) if round.is_dead(g) => continue,
                Part::Group(_) => {}
                _ if changed => break,
                _ => {}
            }
            let sound = |verified: &mut Signatures, signature: Vec<u32>| {
                if let (Some(c), Some(k)) = (cache, key) {
                    c.put_block(k, None);
                }
                verified.insert(signature);
            };
            // The over-determined block is tall: its surplus rows are the count's business
            // unless it also hides a freedom (a column deficit); then every dependent row goes,
            // so that the count sees the freedom.
            if part == Part::Over && rank >= ncols {
                sound(&mut verified, signature);
                continue;
            }
            let deficit = nrows.saturating_sub(rank);
            if deficit == 0 {
                sound(&mut verified, signature);
                continue;
            }
            if let (Some(attempt), Some(seed)) = (confirm, used.seed) {
                let needed = if part == Part::Over { ncols } else { nrows };
                if let Some(s) = unconfirmed(
                    m,
                    eqs,
                    block_eqs,
                    bodies,
                    &rows,
                    &orig_rows,
                    (nrows, ncols),
                    needed,
                    confirm_seeds(seed, attempt),
                    &mut work,
                ) {
                    // Drawn again with the other unconfirmed deficits of this pass.
                    suspects.extend(block_eqs.iter().map(|&e| (eqs.joint[e], s)));
                    continue;
                }
            }
            let a = block_matrix(b, block_eqs, bodies, eqs, &rows, &q);
            let svd = Svd::of(&a, &tol);
            work = work.saturating_add(cube(a.nrows().max(a.ncols())));
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
                let n = rows.nrows(e);
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
                    b, e, deficit, block_eqs, bodies, eqs, &mut rows, &q, rank, &tol,
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
            lowerings.push((lowered, eqs.cap[lowered]));
            eqs.cap[lowered] = rows.nrows(lowered) as u32;
            if let Some(d) = rd.get_mut(lowered) {
                *d = matrix_digest(&rows.get(lowered));
            }
            changed = true;
            let mut joints: Vec<usize> = named.iter().map(|&e| eqs.joint[e]).collect();
            joints.sort_unstable();
            joints.dedup();
            redundant.push(Redundancy {
                bodies: body_names(m, eqs, bodies),
                freedom: describe(m, eqs, bodies, &joints, removed),
                joints: joints.iter().map(|&j| m.joints[j].id.clone()).collect(),
                count: removed as u32,
                lowered: m.joints[eqs.joint[lowered]].id.clone(),
                configuration: false,
            });
            // Later blocks were checked with this one assumed nonsingular: decompose again,
            // unless it was a group (then only its dependents are affected: `Round`).
            let Part::Group(g) = part else {
                break;
            };
            // The lowered group and its dependents join the under-determined block. A round
            // per lowering checked that grown block before anything else: when it is too
            // large for the dense check, do what that round's first step did.
            let Some((nrows, ncols, untouched)) = round.lower(b, g, &q, &rows, &orig_rows) else {
                continue;
            };
            let mut exact = false;
            if let Some(seed) = used.seed
                && untouched
                && nrows <= ncols
                && ncols <= MAX_EXACT_UNKNOWNS
            {
                let (block_eqs, bodies) = round.under_lists(&rows);
                let signature = block_signature(&bodies, &block_eqs, &rows);
                if verified.contains(&signature) {
                    continue;
                }
                if exact_rank(m, eqs, &block_eqs, &bodies, seed, &mut work) >= nrows {
                    verified.insert(signature);
                    exact = true;
                }
            }
            if !exact {
                unchecked.push(Unchecked {
                    bodies: round.under_bodies,
                    unknowns: ncols,
                    equations: nrows,
                });
            }
        }
        if !changed || !suspects.is_empty() {
            suspects.sort_unstable();
            suspects.dedup();
            // Only the blocks of the final decomposition matter.
            unchecked.sort_by_key(|x| (std::cmp::Reverse(x.unknowns), x.bodies, x.equations));
            unchecked.dedup();
            return RankResult {
                deficient: false,
                work,
                decomposition: dec,
                set_aside,
                isolated,
                redundant,
                unchecked,
                rounds,
                kept_rows: (!suspects.is_empty()).then_some(Kept {
                    rows,
                    first: orig_rows,
                    bases: q,
                }),
                suspects,
            };
        }
    }
}

/// Rows of every pair at the given joint geometry: its constraint rows with its share of the
/// driven DOF fixed, and (when `with_free`, for the file's configuration) its constraint rows
/// alone (no input; empty otherwise).
/// One round of the rank check over one decomposition: the groups lowered so far and the
/// under-determined block they grow.
///
/// Lowering a pair of a group leaves every other block as it was but the group's dependents:
/// the flow less the lowered units is still maximum (the group's bodies are not reachable from
/// the source), so the over-determined part stays, and the group with everything that depends
/// on it, transitively, now reaches the sink: it joins the under-determined part. The other
/// groups keep their bodies, pairs and levels, hence their order, so a round that goes on with
/// them finds the deficits, in the order, that a new decomposition after each lowering would
/// (that was quadratic: one decomposition of the whole mechanism per redundancy, 37 rounds
/// on a random spatial mechanism of 10^5 bodies). The under-determined block itself waits for
/// the next round.
struct Round<'a> {
    dec: &'a Decomposition,
    first_group: usize,
    bstart: &'a [usize],
    beqs: &'a [usize],
    /// Groups that joined the under-determined part in this round (and the order they did).
    dead: Vec<bool>,
    joined: Vec<usize>,
    /// Groups that depend on each group (CSR), built at the first lowering.
    dependents: Vec<usize>,
    dependents_start: Vec<usize>,
    /// The under-determined block as it grows: bodies, rows, columns, and how many of its
    /// pairs have fewer rows than they started with.
    under_bodies: usize,
    under_rows: usize,
    under_cols: usize,
    under_touched: usize,
    under: &'a [usize],
    under_eqs: &'a [usize],
}

impl<'a> Round<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        b: usize,
        q: &[Option<DMatrix<f64>>],
        rows: &PairRows,
        orig_rows: &[u8],
        dec: &'a Decomposition,
        first_group: usize,
        bstart: &'a [usize],
        beqs: &'a [usize],
        under: &'a [usize],
    ) -> Round<'a> {
        let ub = first_group + dec.groups.len();
        let under_eqs: &[usize] = if under.is_empty() {
            &[]
        } else {
            &beqs[bstart[ub]..bstart[ub + 1]]
        };
        Round {
            dec,
            first_group,
            bstart,
            beqs,
            dead: vec![false; dec.groups.len()],
            joined: Vec::new(),
            dependents: Vec::new(),
            dependents_start: Vec::new(),
            under_bodies: under.len(),
            under_rows: under_eqs.iter().map(|&e| rows.nrows(e)).sum(),
            under_cols: under.iter().map(|&x| width(b, q, x)).sum(),
            under_touched: under_eqs
                .iter()
                .filter(|&&e| rows.nrows(e) != usize::from(orig_rows[e]))
                .count(),
            under,
            under_eqs,
        }
    }

    fn is_dead(&self, g: usize) -> bool {
        self.dead[g]
    }

    /// The pairs (with rows) of group `g`.
    fn group_eqs(&self, g: usize) -> &'a [usize] {
        let i = self.first_group + g;
        &self.beqs[self.bstart[i]..self.bstart[i + 1]]
    }

    /// Group `g` lost rows: it and its dependents join the under-determined block. Returns
    /// that block's (rows, columns, untouched) when it is too large for the dense check.
    fn lower(
        &mut self,
        b: usize,
        g: usize,
        q: &[Option<DMatrix<f64>>],
        rows: &PairRows,
        orig_rows: &[u8],
    ) -> Option<(usize, usize, bool)> {
        let groups = &self.dec.groups;
        if self.dependents_start.is_empty() {
            let mut start = vec![0usize; groups.len() + 1];
            for grp in groups {
                for &d in &grp.deps {
                    start[d + 1] += 1;
                }
            }
            for i in 0..groups.len() {
                start[i + 1] += start[i];
            }
            let mut fill = start.clone();
            let mut dependents = vec![0usize; start[groups.len()]];
            for (h, grp) in groups.iter().enumerate() {
                for &d in &grp.deps {
                    dependents[fill[d]] = h;
                    fill[d] += 1;
                }
            }
            self.dependents = dependents;
            self.dependents_start = start;
        }
        let mut stack = Vec::new();
        if !self.dead[g] {
            self.dead[g] = true;
            stack.push(g);
        }
        while let Some(h) = stack.pop() {
            self.joined.push(h);
            self.under_bodies += groups[h].bodies.len();
            self.under_cols += groups[h]
                .bodies
                .iter()
                .map(|&x| width(b, q, x))
                .sum::<usize>();
            for &e in self.group_eqs(h) {
                let n = rows.nrows(e);
                if n > 0 {
                    self.under_rows += n;
                    self.under_touched += usize::from(n != usize::from(orig_rows[e]));
                }
            }
            for &d in &self.dependents[self.dependents_start[h]..self.dependents_start[h + 1]] {
                if !self.dead[d] {
                    self.dead[d] = true;
                    stack.push(d);
                }
            }
        }
        (self.under_rows.max(self.under_cols) > MAX_DENSE_UNKNOWNS).then_some((
            self.under_rows,
            self.under_cols,
            self.under_touched == 0,
        ))
    }

    /// The grown under-determined block's pairs (with rows) and bodies, ascending, as a new
    /// decomposition would list them.
    fn under_lists(&self, rows: &PairRows) -> (Vec<usize>, Vec<usize>) {
        let mut block_eqs = self.under_eqs.to_vec();
        let mut bodies = self.under.to_vec();
        for &h in &self.joined {
            block_eqs.extend(self.group_eqs(h).iter().filter(|&&e| rows.nrows(e) > 0));
            bodies.extend_from_slice(&self.dec.groups[h].bodies);
        }
        block_eqs.sort_unstable();
        bodies.sort_unstable();
        (block_eqs, bodies)
    }
}

fn pair_rows(
    m: &Mechanism,
    geoms: &[Geometry],
    seed: Option<u64>,
    redrawn: &HashMap<usize, u64>,
    eqs: &Equations,
    with_free: bool,
) -> (PairRows, PairRows) {
    use rayon::prelude::*;
    let b = m.b() as usize;
    let n = eqs.len();
    // Chunks of consecutive pairs, each built on its own (in parallel): a joint's models are
    // built once per chunk (its pairs are consecutive), on the stack, all of a chunk's
    // together ([`motion::pair_rows_many`] runs several joints' Gram-Schmidt in lockstep).
    let chunk = |c: usize| {
        let pairs = c * PAIRS_PER_CHUNK..n.min((c + 1) * PAIRS_PER_CHUNK);
        // The models the pairs need (joint, driven), and which of them each pair reads: a
        // pair's own, and the free one (nothing driven) where it needs it.
        let mut jobs: Vec<(usize, u32)> = Vec::with_capacity(pairs.len());
        let mut reads: Vec<[usize; 2]> = Vec::with_capacity(pairs.len());
        let mut memo: [Option<(usize, u32, usize)>; 2] = [None, None];
        let mut model = |ji: usize, driven: u32| {
            let slot = usize::from(driven == 0);
            match memo[slot] {
                Some((j, d, k)) if j == ji && d == driven => k,
                _ => {
                    jobs.push((ji, driven));
                    memo[slot] = Some((ji, driven, jobs.len() - 1));
                    jobs.len() - 1
                }
            }
        };
        for e in pairs.clone() {
            let ji = eqs.joint[e];
            let own = model(ji, eqs.driven[e]);
            let free = if eqs.input_only[e] || with_free {
                model(ji, 0)
            } else {
                usize::MAX
            };
            reads.push([own, free]);
        }
        // Room for the rows the count gives each pair (the models give that many): a chunk
        // grown by doubling copied its rows about twice over.
        let expected: usize = eqs.cap[pairs.clone()].iter().map(|&k| k as usize).sum();
        let mut rows = Chunk::with_capacity(pairs.len(), expected * b);
        let mut free = if with_free {
            Chunk::with_capacity(pairs.len(), expected * b)
        } else {
            Chunk::default()
        };
        SCRATCH.with_borrow_mut(|scratch| {
            let models = match seed {
                Some(seed) => motion::pair_rows_many(
                    m,
                    &jobs,
                    |ji| {
                        let seed = redrawn.get(&ji).copied().unwrap_or(seed);
                        motion::random_pair_geometry(m, seed, ji)
                    },
                    scratch,
                ),
                None => motion::pair_rows_many(m, &jobs, |ji| &geoms[ji], scratch),
            };
            for (e, [own, f]) in pairs.zip(reads) {
                let own = models.get(own);
                if eqs.input_only[e] {
                    // A multiple joint's inputs between two of its bodies: the driven rows alone.
                    let f = models.get(f);
                    let flat = |v: &[[f64; 6]]| -> Vec<f64> {
                        v.iter().flat_map(|r| r[..b].iter().copied()).collect()
                    };
                    let (dv, fv) = (flat(own), flat(f));
                    let r = input_rows(
                        RowsView::from_slice_with_strides(&dv, own.len(), b, b, 1),
                        RowsView::from_slice_with_strides(&fv, f.len(), b, b, 1),
                    );
                    rows.push_matrix(&r);
                    if with_free {
                        free.push_rows(&[], b);
                    }
                } else {
                    // A pair's rows with its own share of the driven DOF fixed; without input.
                    rows.push_rows(own, b);
                    if with_free {
                        free.push_rows(models.get(f), b);
                    }
                }
            }
        });
        (rows, free)
    };
    let chunks = n.div_ceil(PAIRS_PER_CHUNK);
    let built: Vec<(Chunk, Chunk)> = if n >= 2 * PAIRS_PER_CHUNK {
        (0..chunks).into_par_iter().map(chunk).collect()
    } else {
        (0..chunks).map(chunk).collect()
    };
    let (rows, free): (Vec<Chunk>, Vec<Chunk>) = built.into_iter().unzip();
    let free = if with_free {
        PairRows::from_chunks(b, free)
    } else {
        PairRows::from_chunks(b, Vec::new())
    };
    (PairRows::from_chunks(b, rows), free)
}

thread_local! {
    /// [`pair_rows`]' model buffers, one per thread, reused from chunk to chunk.
    static SCRATCH: std::cell::RefCell<motion::Scratch> = std::cell::RefCell::default();
}

/// Pairs per chunk of [`PairRows`].
const PAIRS_PER_CHUNK: usize = 1024;

/// The rows of consecutive pairs, as they are built.
#[derive(Default)]
struct Chunk {
    values: Vec<f64>,
    counts: Vec<u32>,
}

impl Chunk {
    /// A chunk with room for `pairs` pairs and `values` values.
    fn with_capacity(pairs: usize, values: usize) -> Chunk {
        Chunk {
            values: Vec::with_capacity(values),
            counts: Vec::with_capacity(pairs),
        }
    }

    fn push_rows(&mut self, rows: &[[f64; 6]], b: usize) {
        if b == 6 {
            // Full rows lie back to back: one copy for all of them (a copy call a row was
            // the larger part of the copies of the rank check's rows at 10^6 bodies).
            self.values.extend_from_slice(rows.as_flattened());
        } else {
            for r in rows {
                self.values.extend_from_slice(&r[..b]);
            }
        }
        self.counts.push(rows.len() as u32);
    }

    fn push_matrix(&mut self, a: &DMatrix<f64>) {
        for i in 0..a.nrows() {
            self.values.extend(a.row(i).iter().copied());
        }
        self.counts.push(a.nrows() as u32);
    }
}

/// Every pair's constraint rows (`n × B`, row-major), stored flat in chunks of
/// [`PAIRS_PER_CHUNK`] consecutive pairs: a small heap matrix per pair cost seconds at 10^6
/// pairs. A pair keeps the room of its first rows; rows that replace them and need more room
/// move to the end of its chunk.
pub(crate) struct PairRows {
    b: usize,
    /// Per pair: its first value within its chunk, its rows now, the rows its room holds.
    start: Vec<u32>,
    n: Vec<u32>,
    room: Vec<u32>,
    chunks: Vec<Vec<f64>>,
}

impl PairRows {
    fn from_chunks(b: usize, built: Vec<Chunk>) -> PairRows {
        let total: usize = built.iter().map(|c| c.counts.len()).sum();
        let mut start = Vec::with_capacity(total);
        let mut n = Vec::with_capacity(total);
        let mut chunks = Vec::with_capacity(built.len());
        for c in built {
            let mut at = 0u32;
            for &k in &c.counts {
                start.push(at);
                n.push(k);
                at += k * b as u32;
            }
            chunks.push(c.values);
        }
        PairRows {
            b,
            start,
            room: n.clone(),
            n,
            chunks,
        }
    }

    /// Number of pairs.
    fn len(&self) -> usize {
        self.n.len()
    }

    /// Rows of pair `e`.
    fn nrows(&self, e: usize) -> usize {
        self.n[e] as usize
    }

    fn values(&self, e: usize) -> &[f64] {
        let s = self.start[e] as usize;
        &self.chunks[e / PAIRS_PER_CHUNK][s..s + self.nrows(e) * self.b]
    }

    /// Pair `e`'s rows as a matrix.
    fn get(&self, e: usize) -> RowsView<'_> {
        RowsView::from_slice_with_strides(self.values(e), self.nrows(e), self.b, self.b, 1)
    }

    /// [`PairRows::get`], `None` past the last pair.
    fn try_get(&self, e: usize) -> Option<RowsView<'_>> {
        (e < self.len()).then(|| self.get(e))
    }

    /// Replace pair `e`'s rows by those of `a` (`B` columns).
    fn set(&mut self, e: usize, a: &DMatrix<f64>) {
        let b = self.b;
        let k = a.nrows();
        let chunk = &mut self.chunks[e / PAIRS_PER_CHUNK];
        if k > self.room[e] as usize {
            self.start[e] = chunk.len() as u32;
            self.room[e] = k as u32;
            chunk.resize(chunk.len() + k * b, 0.0);
        }
        let s = self.start[e] as usize;
        for i in 0..k {
            for j in 0..b {
                chunk[s + i * b + j] = a[(i, j)];
            }
        }
        self.n[e] = k as u32;
    }

    /// Remove row `r` of pair `e`.
    fn remove_row(&mut self, e: usize, r: usize) {
        let b = self.b;
        let (s, k) = (self.start[e] as usize, self.nrows(e));
        if r >= k {
            return;
        }
        self.chunks[e / PAIRS_PER_CHUNK].copy_within(s + (r + 1) * b..s + k * b, s + r * b);
        self.n[e] -= 1;
    }
}

/// Draws a deficit is confirmed at (each independent of the analysis's and of the others).
const CONFIRM_DRAWS: u64 = 4;

/// The seeds of the draws that confirm a deficit in attempt `attempt` of [`check`].
fn confirm_seeds(seed: u64, attempt: u64) -> impl Iterator<Item = u64> {
    (0..CONFIRM_DRAWS).map(move |i| fresh_seed(seed, attempt * CONFIRM_DRAWS + i))
}

/// A draw at which a block found deficient has full rank (`needed`: its rows, or its columns
/// for the over-determined block), among [`CONFIRM_DRAWS`] independent ones: then the first
/// draw was degenerate there. Each draw builds the block's pairs with their joints drawn at
/// its seed, on every body's `B` columns (an isolated freedom is a null direction of every
/// pair touching the body, so the rank is the one on the reduced unknowns), rank by the dense
/// SVD, or exactly ([`exact_rank`]) beyond [`MAX_DENSE_UNKNOWNS`]. A lowered pair keeps its
/// first rows at the other draw; beyond [`MAX_DENSE_UNKNOWNS`] a block with a lowered pair
/// keeps its deficit (the exact path builds whole pairs).
#[allow(clippy::too_many_arguments)]
fn unconfirmed(
    m: &Mechanism,
    eqs: &Equations,
    block_eqs: &[usize],
    bodies: &[usize],
    rows: &PairRows,
    orig_rows: &[u8],
    (nrows, ncols): (usize, usize),
    needed: usize,
    seeds: impl Iterator<Item = u64>,
    work: &mut u64,
) -> Option<u64> {
    let untouched = block_eqs
        .iter()
        .all(|&e| rows.nrows(e) == usize::from(orig_rows[e]));
    if needed > nrows.min(ncols) {
        return None;
    }
    let b = m.b() as usize;
    let full = b * bodies.len();
    let col = |x: usize| bodies.binary_search(&x).ok().map(|k| k * b);
    for second in seeds {
        let rank = if full.max(nrows) <= MAX_DENSE_UNKNOWNS {
            // A lowered pair keeps as many rows at the other draw as it has here: lowering
            // drops rows from the end, so its first ones (a block can hold a pair an earlier
            // redundancy lowered, and its deficit is then as much a draw's as any other).
            let drawn: Vec<DMatrix<f64>> = block_eqs
                .iter()
                .map(|&e| {
                    let r = pair_rows_at(m, eqs, e, second);
                    let k = rows.nrows(e).min(r.nrows());
                    if k < r.nrows() {
                        r.rows(0, k).into_owned()
                    } else {
                        r
                    }
                })
                .collect();
            let n: usize = drawn.iter().map(|r| r.nrows()).sum();
            let mut a = DMatrix::<f64>::zeros(n, full);
            let mut r0 = 0;
            for (&e, r) in block_eqs.iter().zip(&drawn) {
                let [h, o] = eqs.bodies(e);
                if h != o {
                    for (x, sign) in [(h, -1.0), (o, 1.0)] {
                        if let Some(c) = col(x) {
                            let mut v = a.view_mut((r0, c), (r.nrows(), b));
                            v += r * sign;
                        }
                    }
                }
                r0 += r.nrows();
            }
            *work = work.saturating_add(cube(n.max(full)));
            rank_of(
                &a,
                &Tol {
                    rel: REL_TOL,
                    abs: 0.0,
                },
            )
        } else if untouched && ncols <= MAX_EXACT_UNKNOWNS {
            exact_rank(m, eqs, block_eqs, bodies, second, work)
        } else {
            return None;
        };
        if rank >= needed {
            return Some(second);
        }
    }
    None
}

/// Pair `e`'s rows as [`pair_rows`] builds them at a random realization, its joint drawn at
/// `seed`.
fn pair_rows_at(m: &Mechanism, eqs: &Equations, e: usize, seed: u64) -> DMatrix<f64> {
    let b = m.b() as usize;
    let ji = eqs.joint[e];
    let g = motion::random_joint_geometry(m, seed, ji);
    let flat = |driven: u32| -> (Vec<f64>, usize) {
        let v = motion::pair_stack_model(m, ji, &g, driven).rows;
        let n = v.len();
        let values = v
            .as_slice()
            .iter()
            .flat_map(|r| r[..b].iter().copied())
            .collect();
        (values, n)
    };
    let (own, n) = flat(eqs.driven[e]);
    let own = RowsView::from_slice_with_strides(&own, n, b, b, 1);
    if eqs.input_only[e] {
        let (free, k) = flat(0);
        input_rows(own, RowsView::from_slice_with_strides(&free, k, b, b, 1))
    } else {
        own.into_owned()
    }
}

/// The exact rank, over GF(2^61 − 1) at the random realization `seed`, of a block's rows
/// (its pairs acting on the full B columns of its bodies; bodies outside the block known).
/// An isolated freedom of a body is a null direction of every pair touching it, so the rank is
/// the one on the reduced unknowns.
fn exact_rank(
    m: &Mechanism,
    eqs: &Equations,
    block_eqs: &[usize],
    bodies: &[usize],
    seed: u64,
    work: &mut u64,
) -> usize {
    use crate::exact::{Fp, SparseMatrix, dense, models};
    let b = m.b() as usize;
    let col = |x: usize| bodies.binary_search(&x).ok().map(|k| k * b);
    let mut a = SparseMatrix::with_groups(vec![b; bodies.len()]);
    for &e in block_eqs {
        let ji = eqs.joint[e];
        let rows = if eqs.input_only[e] {
            // The inputs alone: the driven model's rows beyond the free model's.
            let free = models::joint_rows(m, ji, seed, 0);
            let own = models::joint_rows(m, ji, seed, eqs.driven[e]);
            let stacked = DMatrix::from_fn(free.nrows() + own.nrows(), b, |i, k| {
                if i < free.nrows() {
                    free[(i, k)]
                } else {
                    own[(i - free.nrows(), k)]
                }
            });
            let extra: Vec<usize> = dense::independent_rows(&stacked)
                .into_iter()
                .filter(|&i| i >= free.nrows())
                .collect();
            DMatrix::from_fn(extra.len(), b, |i, k| stacked[(extra[i], k)])
        } else {
            models::joint_rows(m, ji, seed, eqs.driven[e])
        };
        let [h, o] = eqs.bodies(e);
        for r in 0..rows.nrows() {
            let mut entries: Vec<(u32, Fp)> = Vec::with_capacity(2 * b);
            for (x, negate) in [(h, true), (o, false)] {
                if h == o {
                    break;
                }
                let Some(c) = col(x) else {
                    continue;
                };
                for k in 0..b {
                    let v = rows[(r, k)];
                    entries.push(((c + k) as u32, if negate { Fp::ZERO - v } else { v }));
                }
            }
            a.push_row(entries);
        }
    }
    let f = crate::exact::Factor::new(&a);
    let st = f.stats();
    *work = work.saturating_add((st.factor_entries + st.input_entries) as u64);
    f.rank()
}

/// `n^3`, the work units of a dense factorization of `n` unknowns.
fn cube(n: usize) -> u64 {
    (n as u64).saturating_mul(n as u64).saturating_mul(n as u64)
}

/// The rank of a block that is not too large for the dense check, and its work units: small
/// square blocks on the stack, then the sparse screen, then the dense SVD.
#[allow(clippy::too_many_arguments)]
fn block_rank(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
    part: Part,
    tol: &Tol,
    (nrows, ncols): (usize, usize),
) -> (usize, u64) {
    if nrows == ncols && surely_nonsingular(b, block_eqs, bodies, eqs, rows, q, tol) {
        return (nrows, cube(nrows));
    }
    match screen(b, block_eqs, bodies, eqs, rows, q, part, tol) {
        Some(r) => (r, 64 * (nrows + ncols) as u64),
        None => (
            rank_of(&block_matrix(b, block_eqs, bodies, eqs, rows, q), tol),
            64 * (nrows + ncols) as u64 + cube(nrows.max(ncols)),
        ),
    }
}

/// Set aside the constraint equations that are dependent at the file's configuration, keeping
/// those nearest the frame: constraint rows are taken pair by pair in order of distance from
/// the frame (then pair order), each kept when it is independent of the rows kept before it,
/// within its biconnected block of the body graph (a dependency never spans two blocks: a
/// self-stress restricted to one block is one). The pairs' input rows are kept. Returns the
/// redundancies found, one per block.
fn redundant_at_configuration(
    m: &Mechanism,
    eqs: &Equations,
    rows: &mut PairRows,
    free: &PairRows,
    tol: &Tol,
    local: Option<&LocalFrames>,
    set_aside: &mut [u32],
) -> Vec<Redundancy> {
    let b = m.b() as usize;
    let nb = eqs.nodes;
    let blocks = biconnected_blocks(nb, eqs, m.frame);
    // Distance of every body from the frame (breadth first over pairs).
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        adj[h].push(o);
        adj[o].push(h);
    }
    let mut depth = vec![usize::MAX; nb];
    depth[m.frame] = 0;
    let mut queue = std::collections::VecDeque::from([m.frame]);
    while let Some(x) = queue.pop_front() {
        for &y in &adj[x] {
            if depth[y] == usize::MAX {
                depth[y] = depth[x] + 1;
                queue.push_back(y);
            }
        }
    }
    let mut out = Vec::new();
    for block in blocks {
        if block.len() < 2 {
            continue;
        }
        let mut bodies: Vec<usize> = block
            .iter()
            .flat_map(|&e| eqs.bodies(e))
            .filter(|&x| x != m.frame)
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        let ncols = b * bodies.len();
        let mut order = block.clone();
        order.sort_by_key(|&e| {
            let [h, o] = eqs.bodies(e);
            (depth[h].max(depth[o]), e)
        });
        let nrows: usize = block.iter().map(|&e| free.nrows(e)).sum();
        let cut = tol.cut(1.0, nrows.max(ncols));
        // Pair `e`'s row `i` on the block's columns: (column of each side, the row on that
        // body's own twist about its reference point, signed).
        let side = |e: usize, i: usize, x: usize, sign: f64| -> Vec<f64> {
            let r = free.get(e);
            match local.and_then(|lf| lf.frame[x].as_ref()) {
                Some(s) => (0..b)
                    .map(|k| sign * (0..b).map(|l| r[(i, l)] * s[(l, k)]).sum::<f64>())
                    .collect(),
                None => (0..b).map(|k| sign * r[(i, k)]).collect(),
            }
        };
        let chosen = if ncols <= MAX_DENSE_UNKNOWNS && !force_sparse_aside() {
            Some(independent_rows_dense(
                eqs, free, &order, &bodies, b, cut, &side,
            ))
        } else {
            independent_rows_sparse(eqs, free, &order, &bodies, b, cut, &side)
        };
        let Some((kept, dropped)) = chosen else {
            continue;
        };
        if dropped == 0 {
            continue;
        }
        // Replace each pair's rows by its kept constraint rows plus its input rows.
        let mut lowered: Vec<usize> = Vec::new();
        for (e, mine) in &kept {
            if mine.len() == free.nrows(*e) {
                continue;
            }
            lowered.push(eqs.joint[*e]);
            set_aside[eqs.joint[*e]] += (free.nrows(*e) - mine.len()) as u32;
            let inputs = input_rows(rows.get(*e), free.get(*e));
            let mut r = DMatrix::<f64>::zeros(mine.len() + inputs.nrows(), b);
            for (k, &i) in mine.iter().enumerate() {
                r.set_row(k, &free.get(*e).row(i));
            }
            for i in 0..inputs.nrows() {
                r.set_row(mine.len() + i, &inputs.row(i));
            }
            rows.set(*e, &r);
        }
        let mut joints: Vec<usize> = block.iter().map(|&e| eqs.joint[e]).collect();
        joints.sort_unstable();
        joints.dedup();
        lowered.sort_unstable();
        lowered.dedup();
        let ids =
            |js: &[usize]| -> Vec<String> { js.iter().map(|&j| m.joints[j].id.clone()).collect() };
        out.push(Redundancy {
            bodies: body_names(m, eqs, &bodies),
            joints: ids(&joints),
            count: dropped as u32,
            lowered: ids(&lowered).join(", "),
            freedom: format!(
                "at the file's configuration the joints {} constrain only {} of their {} \
                 equations independently (special geometry: parallel or concurrent axes, a \
                 planar or spherical loop written in space); the configuration satisfies the \
                 other {dropped}, so they fix nothing",
                ids(&joints).join(", "),
                nrows - dropped,
                nrows
            ),
            configuration: true,
        });
    }
    out
}

/// A pair's row on one body's columns (see [`redundant_at_configuration`]).
type Side<'a> = dyn Fn(usize, usize, usize, f64) -> Vec<f64> + 'a;

/// The rows kept per pair and the number dropped, by [`redundant_at_configuration`]'s rule.
type Chosen = (Vec<(usize, Vec<usize>)>, usize);

/// [`redundant_at_configuration`]'s greedy choice on a dense block (at most
/// [`MAX_DENSE_UNKNOWNS`] columns): Gram-Schmidt against the kept rows, a row kept when its
/// residual exceeds `cut` relative to its norm (at least 1).
fn independent_rows_dense(
    eqs: &Equations,
    free: &PairRows,
    order: &[usize],
    bodies: &[usize],
    b: usize,
    cut: f64,
    side: &Side<'_>,
) -> Chosen {
    let ncols = b * bodies.len();
    let col = |x: usize| bodies.binary_search(&x).ok().map(|k| k * b);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut kept: Vec<(usize, Vec<usize>)> = Vec::new();
    let mut dropped = 0usize;
    for &e in order {
        let [h, o] = eqs.bodies(e);
        let mut mine = Vec::new();
        for i in 0..free.nrows(e) {
            let mut v = vec![0.0; ncols];
            for (x, sign) in [(h, -1.0), (o, 1.0)] {
                let Some(c) = col(x) else {
                    continue;
                };
                for (k, t) in side(e, i, x, sign).into_iter().enumerate() {
                    v[c + k] += t;
                }
            }
            let n0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            for _ in 0..2 {
                for q in &basis {
                    let d: f64 = q.iter().zip(&v).map(|(a, c)| a * c).sum();
                    for (x, qk) in v.iter_mut().zip(q) {
                        *x -= d * qk;
                    }
                }
            }
            let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if n > cut * n0.max(1.0) {
                basis.push(v.iter().map(|x| x / n).collect());
                mine.push(i);
            } else {
                dropped += 1;
            }
        }
        kept.push((e, mine));
    }
    (kept, dropped)
}

#[cfg(test)]
thread_local! {
    /// Tests: the sparse choice on every block, to compare it with the dense one.
    static FORCE_SPARSE_ASIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
fn force_sparse_aside() -> bool {
    FORCE_SPARSE_ASIDE.with(|f| f.get())
}

#[cfg(not(test))]
fn force_sparse_aside() -> bool {
    false
}

/// Memory for [`independent_rows_sparse`]'s fronts: the choice is skipped (the block left to
/// the count, as before) past it.
const SPARSE_ASIDE_BYTES: u64 = 1 << 30;

/// [`independent_rows_dense`]'s choice on a large block, sparse: the block's transpose (one
/// unknown per constraint row, one equation per body coordinate) eliminated one row at a time
/// in the same order, a Householder QR without pivoting, which is the same Gram-Schmidt (a row
/// is kept when its residual against the rows kept before it exceeds `cut` times its norm,
/// the rows scaled to norm at most 1). Fronts stay local when the order walks along the
/// mechanism, as the frame-distance order does on a row of windows. `None` past
/// [`SPARSE_ASIDE_BYTES`].
fn independent_rows_sparse(
    eqs: &Equations,
    free: &PairRows,
    order: &[usize],
    bodies: &[usize],
    b: usize,
    cut: f64,
    side: &Side<'_>,
) -> Option<Chosen> {
    let at = |x: usize| bodies.binary_search(&x).ok();
    // Unknown `u` = the u-th row in the order; per body, its rows' coefficients.
    let mut per_body: Vec<(Vec<usize>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); bodies.len()];
    let mut first = Vec::with_capacity(order.len());
    let mut u = 0usize;
    for &e in order {
        let [h, o] = eqs.bodies(e);
        first.push(u);
        for i in 0..free.nrows(e) {
            let sides: Vec<(usize, Vec<f64>)> = [(h, -1.0), (o, 1.0)]
                .into_iter()
                .filter_map(|(x, sign)| Some((at(x)?, side(e, i, x, sign))))
                .collect();
            let n0 = sides
                .iter()
                .flat_map(|(_, v)| v.iter())
                .map(|t| t * t)
                .sum::<f64>()
                .sqrt();
            let scale = 1.0 / n0.max(1.0);
            for (k, v) in sides {
                per_body[k].0.push(u);
                per_body[k].1.extend(v.iter().map(|t| t * scale));
            }
            u += 1;
        }
    }
    let blocks: Vec<Block> = per_body
        .into_iter()
        .filter(|(us, _)| !us.is_empty())
        .map(|(us, vals)| Block {
            mat: DMatrix::from_fn(b, us.len(), |r, c| vals[c * b + r]),
            groups: us,
        })
        .collect();
    let sizes = vec![1usize; u];
    let all: Vec<usize> = (0..u).collect();
    let el = Elimination::run_in_order(&sizes, blocks, cut, SPARSE_ASIDE_BYTES, &all).ok()?;
    let mut kept_unknown = vec![false; u];
    for r in &el.records {
        kept_unknown[r.group] = r.rank == 1;
    }
    let mut kept = Vec::with_capacity(order.len());
    let mut dropped = 0usize;
    for (k, &e) in order.iter().enumerate() {
        let mine: Vec<usize> = (0..free.nrows(e))
            .filter(|&i| kept_unknown[first[k] + i])
            .collect();
        dropped += free.nrows(e) - mine.len();
        kept.push((e, mine));
    }
    Some((kept, dropped))
}

/// The rows of `own` (a pair's rows with its driven DOF fixed) outside the span of `free` (its
/// rows with no input): its input rows, orthonormal.
fn input_rows(own: RowsView<'_>, free: RowsView<'_>) -> DMatrix<f64> {
    let b = own.ncols();
    let mut basis: Vec<Vec<f64>> = (0..free.nrows())
        .map(|i| free.row(i).iter().copied().collect())
        .collect();
    let base = basis.len();
    for i in 0..own.nrows() {
        let mut v: Vec<f64> = own.row(i).iter().copied().collect();
        for _ in 0..2 {
            for q in &basis {
                let d: f64 = q.iter().zip(&v).map(|(a, c)| a * c).sum();
                for (x, qk) in v.iter_mut().zip(q) {
                    *x -= d * qk;
                }
            }
        }
        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n > 1e-8 {
            basis.push(v.iter().map(|x| x / n).collect());
        }
    }
    let extra = basis.len() - base;
    DMatrix::from_fn(extra, b, |i, k| basis[base + i][k])
}

/// The pairs of every biconnected block of the body graph (pairs as edges; Hopcroft–Tarjan,
/// iterative), each block's pairs ascending, blocks ordered by their first pair.
fn biconnected_blocks(nb: usize, eqs: &Equations, root: usize) -> Vec<Vec<usize>> {
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nb];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        if h != o {
            adj[h].push((o, e));
            adj[o].push((h, e));
        }
    }
    let mut blocks: Vec<Vec<usize>> = crate::elimination::biconnected_blocks(&adj, root)
        .into_iter()
        .map(|(_, block)| block)
        .collect();
    blocks.sort();
    blocks
}

/// Rows and columns of the block's matrix ([`block_matrix`]) without building it.
fn block_shape(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
) -> (usize, usize) {
    let nrows = block_eqs.iter().map(|&e| rows.nrows(e)).sum();
    let ncols = bodies.iter().map(|&x| width(b, q, x)).sum();
    (nrows, ncols)
}

/// Body `x`'s reduced unknowns: its basis's columns, all `b` for the identity.
fn width(b: usize, q: &[Option<DMatrix<f64>>], x: usize) -> usize {
    q[x].as_ref().map_or(b, |m| m.ncols())
}

/// A pair's rows acting on one body's reduced unknowns (`rows · Q_x`, the rows themselves for
/// the identity basis), times `sign`, written into `dst`.
fn put(
    dst: &mut DMatrixViewMut<'_, f64>,
    rows: RowsView<'_>,
    qx: &Option<DMatrix<f64>>,
    sign: f64,
) {
    match qx {
        None => dst.copy_from(&rows),
        // An owned copy: nalgebra's product reads a row-major view's columns past the slice it
        // makes of them (a debug build's bounds check stops it); the same product as before.
        Some(qx) => dst.copy_from(&(rows.into_owned() * qx)),
    }
    *dst *= sign;
}

/// The block's matrix: rows of `block_eqs`, columns the reduced unknowns of `bodies`
/// (ascending body indices).
fn block_matrix(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
) -> DMatrix<f64> {
    debug_assert!(bodies.is_sorted());
    let width = |x: usize| width(b, q, x);
    let mut col = Vec::with_capacity(bodies.len());
    let mut ncols = 0;
    for &x in bodies {
        col.push(ncols);
        ncols += width(x);
    }
    let nrows: usize = block_eqs.iter().map(|&e| rows.nrows(e)).sum();
    let mut a = DMatrix::<f64>::zeros(nrows, ncols);
    let mut r0 = 0;
    for &e in block_eqs {
        let [h, o] = eqs.bodies(e);
        let n = rows.nrows(e);
        if h != o {
            for (x, sign) in [(h, -1.0), (o, 1.0)] {
                let Ok(k) = bodies.binary_search(&x) else {
                    continue;
                };
                if width(x) == 0 {
                    continue;
                }
                put(
                    &mut a.view_mut((r0, col[k]), (n, width(x))),
                    rows.get(e),
                    &q[x],
                    sign,
                );
            }
        }
        r0 += n;
    }
    a
}

/// Remove up to `count` rows of pair `e` that the block can lose without losing rank.
#[allow(clippy::too_many_arguments)]
fn drop_rows(
    b: usize,
    e: usize,
    count: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &mut PairRows,
    q: &[Option<DMatrix<f64>>],
    rank: usize,
    t: &Tol,
) -> usize {
    let mut removed = 0;
    let mut r = rows.nrows(e);
    while r > 0 && removed < count {
        r -= 1;
        let saved = rows.get(e).into_owned();
        rows.remove_row(e, r);
        let a = block_matrix(b, block_eqs, bodies, eqs, rows, q);
        if rank_of(&a, t) == rank {
            removed += 1;
        } else {
            rows.set(e, &saved);
        }
    }
    removed
}

/// The ids of the bodies among `nodes` (element nodes left out).
fn body_names(m: &Mechanism, eqs: &Equations, nodes: &[usize]) -> Vec<String> {
    nodes
        .iter()
        .filter(|&&x| !eqs.is_element(x))
        .map(|&x| m.body_id(x).to_string())
        .collect()
}

/// The freedom a redundancy hides, in words.
fn describe(
    m: &Mechanism,
    eqs: &Equations,
    bodies: &[usize],
    joints: &[usize],
    count: usize,
) -> String {
    let ids = body_names(m, eqs, bodies);
    let all_s = joints.iter().all(|&j| m.joints[j].kind == JointType::S);
    if ids.len() == 1 && bodies.len() == 1 && joints.len() == 2 && all_s {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::GeometrySource;

    /// The Gram matrix's Cholesky proof accepts only blocks the inverse's proof accepts (so
    /// the rank check's answers and work units are the same with it), and accepts the
    /// well-conditioned blocks it is there for: random square blocks of 6 to 36 unknowns with
    /// the sparsity of a group (two bodies a row), columns scaled by 1 to 10^-9, singular ones
    /// (a repeated row) and both thresholds (random and file geometry).
    #[test]
    fn gram_proof_accepts_only_what_the_inverse_accepts() {
        fn case<const N: usize>(
            rng: &mut crate::rng::SplitMix64,
            n: usize,
            t: &Tol,
        ) -> (bool, bool) {
            let mut a = [[0.0f64; N]; N];
            let bodies = n.div_ceil(6);
            for row in a.iter_mut().take(n) {
                let x = rng.below(bodies as u64) as usize;
                let y = rng.below(bodies as u64) as usize;
                for body in [x, y] {
                    for v in &mut row[6 * body..(6 * body + 6).min(n)] {
                        *v = rng.next_signed();
                    }
                }
            }
            match rng.below(4) {
                0 => {
                    let c = rng.below(n as u64) as usize;
                    let f = 10f64.powi(-(rng.below(10) as i32));
                    for row in a.iter_mut().take(n) {
                        row[c] *= f;
                    }
                }
                1 if n > 1 => a[n - 1] = a[0],
                _ => {}
            }
            let frob = a[..n]
                .iter()
                .map(|r| r[..n].iter().map(|v| v * v).sum::<f64>())
                .sum::<f64>()
                .sqrt();
            if frob == 0.0 {
                return (false, false);
            }
            (
                gram_proves_reference::<N>(n, &a, frob, t),
                inverse_proves::<N>(n, &a, frob, t),
            )
        }
        let mut rng = crate::rng::SplitMix64::new(16);
        let mut accepted = 0;
        let mut inverse_accepted = 0;
        for t in [
            Tol {
                rel: REL_TOL,
                abs: 0.0,
            },
            Tol {
                rel: 1e-9,
                abs: 0.0,
            },
        ] {
            for i in 0..4000 {
                let n = 6 + i % 31;
                let (gram, inverse) = if n <= 12 {
                    case::<12>(&mut rng, n, &t)
                } else if n <= 24 {
                    case::<24>(&mut rng, n, &t)
                } else {
                    case::<36>(&mut rng, n, &t)
                };
                assert!(!gram || inverse, "case {i}: the Gram proof accepted alone");
                accepted += usize::from(gram);
                inverse_accepted += usize::from(inverse);
            }
        }
        // Most blocks the inverse accepts, the Gram matrix proves too.
        assert!(
            accepted * 10 >= inverse_accepted * 6,
            "{accepted} of {inverse_accepted}"
        );
    }

    /// The Gram proof as [`nonsingular_within`] runs it (Gram matrix over the rows' spans, by
    /// blocks of `b` when every body has all its unknowns, factorized by runs or by blocks
    /// skipping zeros) computes bit for bit the Gram matrix and the factor of the reference (the
    /// nonzeros found by value, left-looking), and so decides the same: random blocks of bodies
    /// 3 or 6 wide or of mixed widths, joined in a chain or at random, with exact zeros inside
    /// the spans, scaled columns, repeated rows, huge entries (non-finite factors) and both
    /// thresholds.
    #[test]
    fn gram_proof_by_spans_and_blocks_is_the_reference() {
        #[allow(clippy::needless_range_loop)]
        fn case<const N: usize>(rng: &mut crate::rng::SplitMix64, t: &Tol, seen: &mut [usize; 4]) {
            let uniform = [0, 3, 6][rng.below(3) as usize];
            let mut widths = Vec::new();
            let mut n = 0;
            loop {
                let w = if uniform > 0 {
                    uniform
                } else {
                    1 + rng.below(6) as usize
                };
                if n + w > N || (n > 0 && rng.below(5) == 0) {
                    break;
                }
                widths.push(w);
                n += w;
            }
            let col: Vec<usize> = widths
                .iter()
                .scan(0, |c, &w| {
                    *c += w;
                    Some(*c - w)
                })
                .collect();
            let nb = widths.len();
            let chain = rng.below(2) == 0;
            let mut a = [[0.0f64; N]; N];
            let mut spans = [RowSpan::default(); N];
            for r in 0..n {
                let x = rng.below(nb as u64) as usize;
                let y = if chain {
                    (x + 1).min(nb - 1)
                } else {
                    rng.below(nb as u64) as usize
                };
                let mut span = RowSpan::default();
                for body in if x == y || rng.below(3) == 0 {
                    vec![x]
                } else {
                    vec![x.min(y), x.max(y)]
                } {
                    for v in &mut a[r][col[body]..col[body] + widths[body]] {
                        *v = match rng.below(10) {
                            0 => 0.0,
                            1 => -0.0,
                            _ => rng.next_signed(),
                        };
                    }
                    span.c[usize::from(span.k)] = col[body] as u8;
                    span.w[usize::from(span.k)] = widths[body] as u8;
                    span.k += 1;
                }
                spans[r] = span;
            }
            match rng.below(6) {
                0 => {
                    let c = rng.below(n as u64) as usize;
                    let f = 10f64.powi(-(rng.below(12) as i32));
                    for row in a.iter_mut().take(n) {
                        row[c] *= f;
                    }
                }
                1 if n > 1 => {
                    a[n - 1] = a[0];
                    spans[n - 1] = spans[0];
                }
                2 => {
                    let r = rng.below(n as u64) as usize;
                    for v in &mut a[r][..n] {
                        *v *= 1e150;
                    }
                }
                _ => {}
            }
            let frob = a[..n]
                .iter()
                .map(|r| r[..n].iter().map(|v| v * v).sum::<f64>())
                .sum::<f64>()
                .sqrt();
            let width = if uniform > 0 && widths.iter().all(|&w| w == uniform) {
                uniform
            } else {
                0
            };
            // The Gram matrices, lower triangles bit for bit.
            let reference = gram_reference::<N>(n, &a);
            let mut by_blocks = [[0.0f64; N]; N];
            let blocks = match width {
                6 => gram_blocks::<N, 6>(n, &a, &spans, &mut by_blocks),
                3 => gram_blocks::<N, 3>(n, &a, &spans, &mut by_blocks),
                _ => {
                    gram_matrix::<N>(n, &a, &spans, &mut by_blocks);
                    [0; N]
                }
            };
            let mut by_spans = [[0.0f64; N]; N];
            gram_matrix::<N>(n, &a, &spans, &mut by_spans);
            for j in 0..n {
                for l in 0..=j {
                    assert_eq!(reference[j][l].to_bits(), by_spans[j][l].to_bits());
                    assert_eq!(reference[j][l].to_bits(), by_blocks[j][l].to_bits());
                }
            }
            // The factors, from the shifted reference Gram matrix.
            let shift = if frob > 0.0 && frob.is_finite() {
                let beta =
                    (1e-4 * frob).max(4.0 * (n as f64).sqrt() * SCREEN_MARGIN * t.cut(frob, n));
                beta * beta + 1e-12 * frob * frob
            } else {
                0.0
            };
            let mut g = reference;
            for j in 0..n {
                g[j][j] -= shift;
            }
            let (mut r, mut runs, mut blk) = (g, g, g);
            let ok = cholesky_reference::<N>(n, &mut r);
            assert_eq!(ok, cholesky_runs::<N>(n, &mut runs));
            let ok_blocks = match width {
                6 => cholesky_blocks::<N, 6>(n, &mut blk, blocks),
                3 => cholesky_blocks::<N, 3>(n, &mut blk, blocks),
                _ => cholesky_runs::<N>(n, &mut blk),
            };
            assert_eq!(ok, ok_blocks);
            if ok {
                for j in 0..n {
                    for l in 0..=j {
                        assert_eq!(r[j][l].to_bits(), runs[j][l].to_bits(), "runs ({j}, {l})");
                        assert_eq!(r[j][l].to_bits(), blk[j][l].to_bits(), "blocks ({j}, {l})");
                    }
                }
            }
            if frob > 0.0 {
                assert_eq!(
                    gram_proves_reference::<N>(n, &a, frob, t),
                    gram_proves::<N>(n, &a, &spans, width, frob, t)
                );
            }
            seen[usize::from(ok) + 2 * usize::from(width > 0)] += 1;
        }
        let mut rng = crate::rng::SplitMix64::new(11);
        let mut seen = [0usize; 4];
        for t in [
            Tol {
                rel: REL_TOL,
                abs: 0.0,
            },
            Tol {
                rel: 1e-9,
                abs: 0.0,
            },
        ] {
            for i in 0..3000 {
                match i % 3 {
                    0 => case::<12>(&mut rng, &t, &mut seen),
                    1 => case::<24>(&mut rng, &t, &mut seen),
                    _ => case::<36>(&mut rng, &t, &mut seen),
                }
            }
        }
        // Accepted and rejected blocks, by blocks and by runs.
        assert!(seen.iter().all(|&c| c > 100), "{seen:?}");
    }

    /// The body screen's elimination over fixed-width rows decides as the reference (updates
    /// over the live columns only): random stacks of 3 or 6 columns and 1 to 48 rows, of full
    /// rank, rank deficient (repeated or combined rows), scaled and near the screen's bound.
    #[test]
    fn body_screen_is_the_reference() {
        fn stack<const M: usize>(rows: &DMatrix<f64>, b: usize) -> (bool, bool) {
            let view = view(rows);
            let new = full_rank_within::<M>(b, std::iter::once(view));
            let old = full_rank_within_reference::<M>(b, std::iter::once(view));
            (new, old)
        }
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut seen = [0usize; 2];
        for i in 0..6000 {
            let b = if i % 2 == 0 { 6 } else { 3 };
            let n = 1 + rng.below(48) as usize;
            let mut a = DMatrix::<f64>::from_fn(n, b, |_, _| rng.next_signed());
            match rng.below(5) {
                0 if n > 1 => {
                    let (x, y) = (rng.below(n as u64) as usize, rng.below(n as u64) as usize);
                    let row = a.row(x).clone_owned();
                    a.row_mut(y).copy_from(&row);
                }
                1 => {
                    // A column nearly dependent on another: near the 1e-6 bound.
                    let (c, d) = (rng.below(b as u64) as usize, rng.below(b as u64) as usize);
                    let f = 10f64.powi(-(rng.below(10) as i32));
                    for r in 0..n {
                        let v = a[(r, d)] + f * rng.next_signed();
                        a[(r, c)] = v;
                    }
                }
                2 => {
                    let c = rng.below(b as u64) as usize;
                    let f = 10f64.powi(-(rng.below(9) as i32));
                    a.column_mut(c).scale_mut(f);
                }
                _ => {}
            }
            let (new, old) = match n {
                0..=8 => stack::<8>(&a, b),
                9..=16 => stack::<16>(&a, b),
                _ => stack::<48>(&a, b),
            };
            assert_eq!(new, old, "case {i}");
            seen[usize::from(new)] += 1;
        }
        assert!(seen.iter().all(|&c| c > 500), "{seen:?}");
    }

    /// The column-major elimination gives the numbers of the row-major one bit for bit
    /// (`|det T|`, `F²`, `‖T‖_F²`, or the same early stop), on stacks of 3 or 6 columns and 1
    /// to 50 rows: random, small integers (ties between pivot candidates of either sign),
    /// exact zeros (zero pivots), repeated rows, tiny, huge, infinite and NaN entries.
    #[test]
    fn column_major_elimination_is_the_reference() {
        fn numbers<const M: usize>(a: &DMatrix<f64>, b: usize) -> [Option<[u64; 3]>; 2] {
            let bits = |e: Option<Eliminated>| {
                e.map(|e| [e.det.to_bits(), e.frob2.to_bits(), e.sub2.to_bits()])
            };
            // Split into pairs of one to three rows, as the bodies' stacks come.
            let split = |a: &DMatrix<f64>| -> Vec<DMatrix<f64>> {
                let mut out = Vec::new();
                let mut r = 0;
                while r < a.nrows() {
                    let k = (1 + r % 3).min(a.nrows() - r);
                    out.push(a.rows(r, k).into_owned());
                    r += k;
                }
                out
            };
            let parts = split(a);
            [
                bits(elimination::<M>(b, parts.iter().map(view))),
                bits(elimination_reference::<M>(b, parts.iter().map(view))),
            ]
        }
        let mut rng = crate::rng::SplitMix64::new(11);
        let mut seen = [0usize; 3];
        for i in 0..30_000 {
            let b = if i % 2 == 0 { 6 } else { 3 };
            let n = 1 + rng.below(50) as usize;
            let style = rng.below(8);
            let a = DMatrix::<f64>::from_fn(n, b, |_, _| {
                let r = rng.next_signed();
                match (style, rng.below(16)) {
                    (0, _) => (r * 3.0).round(),
                    (1, 0..=7) => 0.0,
                    (2, 0) => [f64::NAN, f64::INFINITY, -f64::INFINITY][rng.below(3) as usize],
                    (3, _) => r * 1e-160,
                    (4, _) => r * 1e160,
                    (5, 0..=3) => -0.0,
                    _ => r,
                }
            });
            let a = if style == 6 && n > 1 {
                // Repeated rows (a deficient stack).
                DMatrix::from_fn(n, b, |r, c| a[(r / 2, c)])
            } else {
                a
            };
            let [new, old] = match n {
                0..=8 => numbers::<8>(&a, b),
                9..=16 => numbers::<16>(&a, b),
                17..=24 => numbers::<24>(&a, b),
                25..=32 => numbers::<32>(&a, b),
                _ => numbers::<48>(&a, b),
            };
            assert_eq!(new, old, "case {i}");
            let k = match new {
                None => 0,
                Some(e) if f64::from_bits(e[0]).is_finite() => 1,
                Some(_) => 2,
            };
            seen[k] += 1;
        }
        assert!(seen.iter().all(|&c| c > 200), "{seen:?}");
    }

    /// The flat rows of every pair (built chunk by chunk, each joint's model once per chunk,
    /// the random geometry drawn where it is used) are exactly the rows of the pair's own
    /// model, the heap matrix per pair they replaced: random mechanisms of mixed joint types,
    /// and a shared joint with inputs (element pairs and input-only pairs).
    #[test]
    fn pair_rows_are_the_pair_models() {
        let mut cases = Vec::new();
        for (planar, seed) in [(false, 2), (true, 5)] {
            cases.push(
                crate::generate::random(3000, planar, seed)
                    .expect("valid")
                    .0,
            );
        }
        cases.push(crate::generate::star(2500, JointType::S, false, true, true).expect("valid"));
        for m in &cases {
            let eqs = Equations::of(m);
            let (geoms, used) =
                motion::geometries(m, GeometrySource::Random { seed: 3 }, None).expect("random");
            assert!(eqs.len() > 2 * PAIRS_PER_CHUNK, "several chunks");
            let (rows, free) = pair_rows(m, &[], used.seed, &HashMap::new(), &eqs, false);
            assert_eq!(rows.len(), eqs.len());
            assert_eq!(free.len(), 0);
            // The file's geometry (here the same values, given), with the rows without input.
            let (file_rows, free) = pair_rows(m, &geoms, None, &HashMap::new(), &eqs, true);
            assert_eq!(free.len(), eqs.len());
            for e in 0..eqs.len() {
                let ji = eqs.joint[e];
                let want = if eqs.input_only[e] {
                    let own = motion::pair_model(m, ji, &geoms[ji], eqs.driven[e]).rows;
                    let f = motion::pair_model(m, ji, &geoms[ji], 0).rows;
                    input_rows(view(&own), view(&f))
                } else {
                    motion::pair_model(m, ji, &geoms[ji], eqs.driven[e]).rows
                };
                // Bit for bit (the rows are built several joints at a time).
                let bits = |a: &DMatrix<f64>| a.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(rows.get(e).into_owned(), want, "pair {e}");
                assert_eq!(bits(&rows.get(e).into_owned()), bits(&want), "pair {e}");
                assert_eq!(
                    bits(&file_rows.get(e).into_owned()),
                    bits(&want),
                    "pair {e}"
                );
                let want_free = if eqs.input_only[e] {
                    DMatrix::zeros(0, m.b() as usize)
                } else {
                    motion::pair_model(m, ji, &geoms[ji], 0).rows
                };
                assert_eq!(free.get(e).into_owned(), want_free, "pair {e}");
            }
        }
    }

    /// Every chunk of rows is built in the room the count gives its pairs (its equations: the
    /// models give as many rows at a random realization), never grown: grown by doubling, the
    /// chunks of a 10^6-body mechanism copied their 330 MB of rows about once more and held up
    /// to twice the room.
    #[test]
    fn pair_rows_chunks_are_sized_once() {
        let cases = [
            crate::generate::random(3000, false, 2).expect("valid").0,
            crate::generate::random(3000, true, 5).expect("valid").0,
            crate::generate::star(2500, JointType::S, false, true, true).expect("valid"),
        ];
        for m in &cases {
            let eqs = Equations::of(m);
            let (_, used) =
                motion::geometries(m, GeometrySource::Random { seed: 3 }, None).expect("random");
            let (rows, _) = pair_rows(m, &[], used.seed, &HashMap::new(), &eqs, false);
            assert!(rows.chunks.len() > 2, "several chunks");
            for (c, chunk) in rows.chunks.iter().enumerate() {
                assert!(!chunk.is_empty());
                assert_eq!(chunk.capacity(), chunk.len(), "chunk {c} of {}", m.name);
            }
        }
    }

    fn view(a: &DMatrix<f64>) -> RowsView<'_> {
        RowsView::from_slice_with_strides(a.as_slice(), a.nrows(), a.ncols(), 1, a.nrows())
    }

    /// A chunk holds each pair's rows row by row, the first `b` values of each (full rows
    /// copied at once, narrower ones a row at a time), and reads them back as they were.
    #[test]
    fn chunk_rows_are_row_major() {
        let r = |k: f64| [k, k + 0.5, k + 1.0, k + 1.5, k + 2.0, k + 2.5];
        for b in [6, 3, 5] {
            let mut c = Chunk::default();
            c.push_rows(&[r(1.0), r(10.0)], b);
            c.push_rows(&[], b);
            c.push_rows(&[r(20.0)], b);
            let want: Vec<f64> = [r(1.0), r(10.0), r(20.0)]
                .iter()
                .flat_map(|x| x[..b].to_vec())
                .collect();
            assert_eq!(c.values, want, "b = {b}");
            assert_eq!(c.counts, [2, 0, 1]);
            let rows = PairRows::from_chunks(b, vec![c]);
            assert_eq!(rows.get(0).nrows(), 2);
            assert_eq!(rows.get(0)[(1, b - 1)], r(10.0)[b - 1]);
            assert_eq!(rows.get(2)[(0, 0)], 20.0);
        }
    }

    /// Rows replaced by more than their room, and rows removed, read back as a matrix would.
    #[test]
    fn pair_rows_set_and_remove() {
        let mut c = Chunk::default();
        c.push_rows(&[[1.0, 2.0, 3.0, 0.0, 0.0, 0.0]], 3);
        c.push_rows(
            &[
                [4.0, 5.0, 6.0, 0.0, 0.0, 0.0],
                [7.0, 8.0, 9.0, 0.0, 0.0, 0.0],
            ],
            3,
        );
        let mut rows = PairRows::from_chunks(3, vec![c]);
        let bigger = DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        rows.set(0, &bigger);
        assert_eq!(rows.get(0).into_owned(), bigger);
        assert_eq!(
            rows.get(1).into_owned(),
            DMatrix::from_row_slice(2, 3, &[4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
        );
        rows.remove_row(0, 1);
        assert_eq!(rows.get(0).into_owned(), bigger.clone().remove_row(1));
        rows.remove_row(1, 0);
        assert_eq!(
            rows.get(1).into_owned(),
            DMatrix::from_row_slice(1, 3, &[7.0, 8.0, 9.0])
        );
        assert_eq!(rows.nrows(1), 1);
        assert!(rows.try_get(2).is_none());
    }

    /// A row of `n` windows written in space (R joints, parallel axes), two decimals in mm.
    fn windows_in_space(n: usize) -> String {
        let (s, ox, oy) = (100.3, 1000.17, 500.23);
        let mut out = String::from("space = \"spatial\"\nframe = 1\n");
        let mut joint = |id: String, a: usize, b: usize, x: f64, y: f64| {
            let (x, y) = (
                ((ox + s * x) * 100.0_f64).round() / 100.0,
                ((oy + s * y) * 100.0_f64).round() / 100.0,
            );
            out.push_str(&format!(
                "\n[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, {y}, 250.5]\naxis = [0, 0, 1]\n"
            ));
        };
        joint("A0".into(), 1, 2, 0.0, 0.0);
        for k in 1..=n {
            let kf = k as f64;
            joint(format!("VB{}", k - 1), 2 * k, 2 * k + 1, kf - 0.4, 0.8);
            joint(format!("B{k}"), 2 * k + 1, 2 * k + 2, kf + 0.6, 0.8);
            joint(format!("P{k}"), 1, 2 * k + 2, kf, 0.0);
        }
        out
    }

    /// The sparse choice of the constraints set aside at the file's configuration keeps the
    /// same rows as the dense Gram-Schmidt on every block the dense one takes: the bundled
    /// mechanisms with geometry (Bennett, Bricard, planar loops written in space, the 40-window
    /// N-four-bar in space) and rows of windows written in space.
    #[test]
    fn sparse_set_aside_keeps_the_dense_rows() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("mechanisms");
        let mut files: Vec<(String, String)> = std::fs::read_dir(&dir)
            .expect("mechanisms/")
            .filter_map(|e| {
                let p = e.ok()?.path();
                (p.extension()? == "toml").then(|| {
                    (
                        p.display().to_string(),
                        std::fs::read_to_string(&p).expect("readable"),
                    )
                })
            })
            .collect();
        files.sort();
        for n in [1, 3, 10, 60] {
            files.push((format!("{n} windows in space"), windows_in_space(n)));
        }
        let opts = super::super::Options {
            geometry: GeometrySource::File,
            ..Default::default()
        };
        let lib = super::super::library::Library::empty();
        let mut compared = 0;
        let mut with_aside = 0;
        for (name, text) in &files {
            let m = crate::format::load(name, text, crate::format::Format::Toml).expect("loads");
            let run = |sparse: bool| {
                FORCE_SPARSE_ASIDE.with(|f| f.set(sparse));
                let a = super::super::analyze(&m, &opts, &lib);
                FORCE_SPARSE_ASIDE.with(|f| f.set(false));
                a.map(|a| format!("{a:?}"))
            };
            let (Ok(dense), Ok(sparse)) = (run(false), run(true)) else {
                continue;
            };
            compared += 1;
            with_aside += usize::from(dense.contains("configuration: true"));
            assert_eq!(dense, sparse, "{name}");
        }
        assert!(compared >= 20, "{compared} files compared");
        assert!(with_aside >= 5, "{with_aside} with constraints set aside");
    }
}
