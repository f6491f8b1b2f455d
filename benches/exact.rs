//! Benchmarks of the exact GF(p) elimination (divan): `cargo bench --bench exact`.
//!
//! Constraint Jacobians with random field entries in the sparsity pattern of the joints
//! (B − k rows per pair over the two bodies' B columns), for n = 10^3 to 10^5 bodies:
//!
//! - `chain`: a serial chain of n spatial R joints (nullity n);
//! - `star`: one body on the frame with n − 1 bodies on R joints to it;
//! - `assur`: the planar Assur II linkage of `mbsa::generate::assur`, variant A;
//! - `row_basis`: the same matrices through an incremental [`RowBasis`] in the factor's
//!   column order (greedy redundancy removal).
//!
//! Inputs are built outside the timed closures. See docs/benchmarks.md ("Exact
//! arithmetic") and `examples/exact_scale.rs` for the giant group of variant B.

use divan::{Bencher, black_box};
use mbsa::exact::sparse::{Factor, RowBasis, SparseMatrix, random_pair_matrix};
use mbsa::generate::{self, Variant};

fn main() {
    divan::main();
}

const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

fn chain(n: usize) -> SparseMatrix {
    let pairs: Vec<_> = (1..=n).map(|i| (i - 1, i, 5)).collect();
    random_pair_matrix(n + 1, 6, &pairs, 1)
}

fn star(n: usize) -> SparseMatrix {
    let mut pairs = vec![(0, 1, 5)];
    pairs.extend((2..=n).map(|i| (1, i, 5)));
    random_pair_matrix(n + 1, 6, &pairs, 1)
}

fn assur(n: usize) -> SparseMatrix {
    let m = generate::assur(2, (n as u64 - 2) / 4, 1, Variant::A).expect("valid parameters");
    let num = |i: usize| {
        if i == m.frame {
            0
        } else if i < m.frame {
            i + 1
        } else {
            i
        }
    };
    let pairs: Vec<_> = m
        .joints
        .iter()
        .map(|j| (num(j.bodies[0]), num(j.bodies[1]), 2))
        .collect();
    random_pair_matrix(m.bodies.len(), 3, &pairs, 1)
}

fn build(family: &str, n: usize) -> SparseMatrix {
    match family {
        "chain" => chain(n),
        "star" => star(n),
        _ => assur(n),
    }
}

/// Rank (the factorization) of each family.
#[divan::bench_group(sample_size = 1, sample_count = 5)]
mod factor {
    use super::*;

    fn run(bencher: Bencher, family: &str, n: usize) {
        let a = build(family, n);
        bencher.bench_local(|| Factor::new(black_box(&a)).rank());
    }

    #[divan::bench(args = SIZES)]
    fn chain(bencher: Bencher, n: usize) {
        run(bencher, "chain", n);
    }

    #[divan::bench(args = SIZES)]
    fn star(bencher: Bencher, n: usize) {
        run(bencher, "star", n);
    }

    #[divan::bench(args = SIZES)]
    fn assur(bencher: Bencher, n: usize) {
        run(bencher, "assur", n);
    }
}

/// The null space from a factorization (output-bound on the chain: its n vectors are long).
#[divan::bench_group(sample_size = 1, sample_count = 5)]
mod null_space {
    use super::*;

    fn run(bencher: Bencher, family: &str, n: usize) {
        let a = build(family, n);
        let f = Factor::new(&a);
        bencher.bench_local(|| black_box(&f).null_space().len());
    }

    #[divan::bench(args = [1_000, 3_000])]
    fn chain(bencher: Bencher, n: usize) {
        run(bencher, "chain", n);
    }

    #[divan::bench(args = SIZES)]
    fn star(bencher: Bencher, n: usize) {
        run(bencher, "star", n);
    }

    #[divan::bench(args = SIZES)]
    fn assur(bencher: Bencher, n: usize) {
        run(bencher, "assur", n);
    }
}

/// Greedy independent rows, inserted one at a time in the factor's column order.
#[divan::bench_group(sample_size = 1, sample_count = 5)]
mod row_basis {
    use super::*;

    fn run(bencher: Bencher, family: &str, n: usize) {
        let a = build(family, n);
        let order = Factor::new(&a).column_order();
        bencher.bench_local(|| {
            let mut b = RowBasis::with_column_order(&order);
            a.rows.iter().filter(|r| b.insert(r)).count()
        });
    }

    #[divan::bench(args = SIZES)]
    fn chain(bencher: Bencher, n: usize) {
        run(bencher, "chain", n);
    }

    #[divan::bench(args = SIZES)]
    fn star(bencher: Bencher, n: usize) {
        run(bencher, "star", n);
    }

    #[divan::bench(args = SIZES)]
    fn assur(bencher: Bencher, n: usize) {
        run(bencher, "assur", n);
    }
}
