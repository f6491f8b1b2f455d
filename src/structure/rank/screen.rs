//! The sparse screen: a block-sparse QR with column pivoting that proves full rank without
//! forming the block densely.

use super::blocks::{put, width};
use super::float::Tol;
use super::rows::PairRows;
use super::set_aside::SPARSE_ASIDE_BYTES;
use crate::elimination::{Block, Elimination};
use crate::structure::count::{Equations, Part};
use nalgebra::DMatrix;

/// Blocks with more unknowns than this are screened by the sparse elimination first.
const SCREEN_UNKNOWNS: usize = 8;

/// Margin of the sparse screen over the SVD threshold.
pub(super) const SCREEN_MARGIN: f64 = 1e3;

/// The rank of a sound block without forming it densely: a block-sparse QR with column
/// pivoting (one body at a time, [`Elimination`]) with a pivot threshold [`SCREEN_MARGIN`]
/// times above the SVD's (whose `σ_max` is bounded by the Frobenius norm). `Some` only when
/// every needed pivot clears it (full row rank; for the over-determined block, full column
/// rank): the SVD would find the same rank. `None` leaves the decision to the SVD, so a
/// deficit is always found and explained by the dense path.
#[allow(clippy::too_many_arguments)]
pub(super) fn screen(
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
pub(super) fn sparse_full_rank(
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
    let (blocks, frob2) = pair_blocks(block_eqs, bodies, eqs, rows, q, &sizes, file);
    let n = nrows.max(ncols);
    let tol = if file {
        // At the file's geometry: the threshold `rigid`'s sparse path decides with (QR pivots
        // against the SVD's threshold), `σ_max` bounded by `√(‖A‖₁ ‖A‖_∞)`, far tighter than
        // the Frobenius norm on long chains of unit rows.
        t.cut(norm_bound(&sizes, &blocks, ncols).min(frob2.sqrt()), n)
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

/// The block's pairs as the sparse elimination takes them: each pair's rows on the reduced
/// unknowns of its bodies in the block (`sizes` columns each), and the block's squared
/// Frobenius norm.
fn pair_blocks(
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
    sizes: &[usize],
    file: bool,
) -> (Vec<Block>, f64) {
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
    (blocks, frob2)
}

/// `√(‖A‖₁ ‖A‖_∞)`, a bound on `σ_max` of the block made of `blocks` (`ncols` columns, `sizes`
/// per body).
fn norm_bound(sizes: &[usize], blocks: &[Block], ncols: usize) -> f64 {
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
    for blk in blocks {
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
    (col_max * row_max).sqrt()
}
