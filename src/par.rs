//! Data parallelism that pays for itself: small inputs stay on the calling thread, since
//! handing work to the thread pool costs tens of microseconds (the whole analysis of a
//! Table 16 linkage takes about as long).

use rayon::prelude::*;

/// Below this many items, [`map`] runs serially.
const MIN_PARALLEL: usize = 256;

/// `(0..n).map(f).collect()`, in order, on all cores when `n` is large.
pub(crate) fn map<T, F>(n: usize, f: F) -> Vec<T>
where
    T: Send,
    F: Fn(usize) -> T + Sync + Send,
{
    if n < MIN_PARALLEL {
        (0..n).map(f).collect()
    } else {
        (0..n).into_par_iter().map(f).collect()
    }
}
