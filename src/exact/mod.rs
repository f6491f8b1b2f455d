//! Exact linear algebra over the prime field GF(p), p = 2^61 − 1, for decisions on random
//! realizations: a rank, null space or left null space over GF(p) involves no tolerance,
//! and for entries drawn at random from the field it equals the generic (real) one except
//! with probability at most (number of rows)/p by the Schwartz–Zippel lemma.
//!
//! - [`field`]: the element type [`Fp`] (usable in `nalgebra::DMatrix`).
//! - [`dense`]: rank, null spaces, complement rows, greedy independent rows of `DMatrix<Fp>`.
//! - [`sparse`]: block-sparse multifrontal elimination ([`Factor`]) and an incremental row
//!   basis ([`RowBasis`]) for matrices of 10^5 bodies and more.

pub mod dense;
pub mod field;
pub mod sparse;

pub use field::{Fp, P};
pub use sparse::{Factor, FpBlock, RowBasis, SparseMatrix};
