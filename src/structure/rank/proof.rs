//! Proofs, on the stack, that a small square block is nonsingular far from the SVD's threshold:
//! a Cholesky factor of the shifted Gram matrix, else an inverse with a small residual.

use super::blocks::width;
use super::float::Tol;
use super::rows::PairRows;
use super::screen::SCREEN_MARGIN;
use crate::structure::count::Equations;
use nalgebra::DMatrix;

/// Largest square block [`surely_nonsingular`] decides (on the stack).
const SMALL_BLOCK: usize = 36;

/// Whether a small square block surely has full rank at the SVD's threshold, decided without the
/// heap: the block as [`block_matrix`](super::blocks::block_matrix) builds it, its inverse `X` by
/// Gaussian elimination with partial pivoting, and a check of the residual `‖I − A·X‖_F ≤ 1/2`,
/// which proves `A` invertible with `‖A⁻¹‖₂ ≤ 2‖X‖_F`, so `σ_min ≥ 1 / (2‖X‖_F)`. When that is
/// [`SCREEN_MARGIN`] times above the SVD threshold (`n · rel · σ_max`, `σ_max ≤ ‖A‖_F`), the SVD
/// would find full rank too. Anything else (or a precision-derived threshold) goes to [`screen`]
/// and the SVD, as before. The structural groups of generated mechanisms (one to four bodies) all
/// come here: the sparse screen allocated a few matrices per pair.
#[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
pub(super) fn surely_nonsingular(
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

/// Loads the rows of the pairs `block_eqs` into the cache together, before they are read one by
/// one: the pairs of a block lie far apart in [`PairRows`] (and in `eqs`), so copying them pair
/// after pair waited for memory once per pair (a third of [`nonsingular_within`]'s time and most of
/// [`reduced_basis`](super::unknowns::reduced_basis)'s at 10^6 bodies). Changes no value.
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
        if !factor_diagonal_block::<N, W>(g, k0) {
            return false;
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

/// [`cholesky_blocks`]' diagonal block of the body whose columns start at `k0`, factorized in
/// place; whether every pivot is positive and every entry of the factor finite.
#[allow(clippy::needless_range_loop)]
#[inline]
fn factor_diagonal_block<const N: usize, const W: usize>(g: &mut [[f64; N]; N], k0: usize) -> bool {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::rank::float::REL_TOL;

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
                margins: None,
                rel: REL_TOL,
                abs: 0.0,
            },
            Tol {
                margins: None,
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
                margins: None,
                rel: REL_TOL,
                abs: 0.0,
            },
            Tol {
                margins: None,
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
}
