//! Sparse exact elimination over GF(p) for large block-structured matrices.
//!
//! The columns are grouped in consecutive blocks (a body's B columns); rows are sparse. A
//! [`Factor`] eliminates one column group at a time (multifrontal Gaussian elimination): the
//! rows touching the group are gathered into a dense front, its columns are eliminated with
//! any nonzero pivot (exact, so pivot choice is only about sparsity), and the remaining rows,
//! compressed to echelon form, become a new block on the group's neighbours.
//!
//! Order: first the block triangular form. A maximum matching of the rows to the column
//! groups (a b-matching: a group takes as many rows as it has columns) and the strongly
//! connected components of "the rows matched to `k` touch `h`" order the groups so that,
//! when a group is eliminated, the only rows left on it are its own matched rows (and rows
//! the matching left over): a mechanism built body by body onto earlier bodies (every
//! generated random mechanism, an Assur linkage) is eliminated last body first with no fill
//! at all. Within a component the next group is the one with the smallest front (greedy
//! minimum degree over the groups, ties by index), as in the floating-point elimination of
//! the rank check.
//!
//! Rows a tier leaves over (its diagonal block is singular at this matrix: a square
//! mechanism Jacobian with its inputs, where a body's block loses rank) are set aside as
//! sparse rows rather than carried through the fronts of every later group they reach (each
//! such front was as wide as the union of the pivot rows the row had met: 19 × 7,470 on a
//! random spatial mechanism of 10^4 bodies). Each is reduced by a later group's pivot rows
//! once that group is eliminated, and becomes the pivot of the first free column it meets
//! or a dependent row (see `Carried`).
//!
//! Budget: [`Factor::new_within`] charges the real work (every front's rows × width per
//! pivot, the compression of the rows left over) to a work [`Meter`] and checks the real
//! memory (live blocks, the front being eliminated and the records kept) against the memory
//! limit before each front, so that a matrix whose fill explodes stops with a
//! [`BudgetExceeded`] instead of running on.
//!
//! [`RowBasis`] is the incremental counterpart for greedy redundancy removal: insert sparse
//! rows one at a time and learn whether each is independent of the rows kept so far.
//!
//! Everything is deterministic: no hash maps, ties broken by index.

mod blocks;
mod carried;
mod echelon;
mod eliminate;
mod factor;
mod limits;
mod matrix;
mod null_space;
mod order;
mod record;
mod row_basis;
mod tiers;
mod trace;

pub use factor::{Factor, FactorStats};
pub use limits::Limits;
pub(crate) use matrix::Rows;
pub use matrix::{FpBlock, SparseMatrix, SparseRow, random_pair_matrix};
pub use row_basis::{DependentRow, RowBasis, dependent_rows, left_null_space};
pub use tiers::elimination_tiers;

#[cfg(test)]
mod tests;
