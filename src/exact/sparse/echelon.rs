//! Dense row echelon forms of row-major arrays, plain and keeping the row combinations.

use super::super::field::{Fp, axpy_sub, scale};
use super::trace::CHOSEN;

fn swap_rows(m: &mut [Fp], w: usize, i: usize, k: usize) {
    if i != k {
        let (a, b) = (i.min(k), i.max(k));
        let (lo, hi) = m.split_at_mut(b * w);
        lo[a * w..(a + 1) * w].swap_with_slice(&mut hi[..w]);
    }
}

/// Row `i` (mutable) and row `k` (shared) of a row-major matrix of width `w`, `i != k`.
pub(super) fn two_rows(m: &mut [Fp], w: usize, i: usize, k: usize) -> (&mut [Fp], &[Fp]) {
    if i < k {
        let (lo, hi) = m.split_at_mut(k * w);
        (&mut lo[i * w..(i + 1) * w], &hi[..w])
    } else {
        let (lo, hi) = m.split_at_mut(i * w);
        (&mut hi[..w], &lo[k * w..(k + 1) * w])
    }
}

/// Row echelon form in place (row-major, width `w`); returns the rank (rows `0..rank` span
/// the row space).
pub(super) fn echelon(m: &mut [Fp], w: usize) -> usize {
    let nr = m.len() / w;
    let mut r = 0;
    for c in 0..w {
        if r == nr {
            break;
        }
        let Some(p) = (r..nr).find(|&i| !m[i * w + c].is_zero()) else {
            continue;
        };
        swap_rows(m, w, r, p);
        let inv = m[r * w + c].inv();
        scale(&mut m[r * w + c..(r + 1) * w], inv);
        for i in r + 1..nr {
            let f = m[i * w + c];
            if !f.is_zero() {
                let (dst, src) = two_rows(m, w, i, r);
                axpy_sub(&mut dst[c..], f, &src[c..]);
            }
        }
        r += 1;
    }
    r
}

/// [`echelon`] keeping each row's combination of the input rows: `own[i]` its own input row
/// (until chosen as a pivot, then [`CHOSEN`]), `tr` (`w` per row) its coefficients on the
/// rows chosen so far, listed in `chosen` (input rows).
pub(super) fn echelon_tracked(
    m: &mut [Fp],
    w: usize,
    own: &mut [u32],
    tr: &mut [Fp],
    chosen: &mut Vec<u32>,
) -> usize {
    let nr = m.len() / w;
    let mut r = 0;
    for c in 0..w {
        if r == nr {
            break;
        }
        let Some(p) = (r..nr).find(|&i| !m[i * w + c].is_zero()) else {
            continue;
        };
        swap_rows(m, w, r, p);
        swap_rows(tr, w, r, p);
        own.swap(r, p);
        tr[r * w + chosen.len()] = Fp::ONE;
        chosen.push(own[r]);
        own[r] = CHOSEN;
        let inv = m[r * w + c].inv();
        scale(&mut m[r * w + c..(r + 1) * w], inv);
        scale(&mut tr[r * w..(r + 1) * w], inv);
        for i in r + 1..nr {
            let f = m[i * w + c];
            if !f.is_zero() {
                let (dst, src) = two_rows(m, w, i, r);
                axpy_sub(&mut dst[c..], f, &src[c..]);
                let (dst, src) = two_rows(tr, w, i, r);
                axpy_sub(dst, f, src);
            }
        }
        r += 1;
    }
    r
}
