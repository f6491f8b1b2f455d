//! Property tests of the exact GF(p) engine: dense and sparse eliminations agree with each
//! other and with the real (SVD) rank on small integer matrices with planted dependencies.

use mbsa::exact::dense;
use mbsa::exact::sparse::{self, Factor, RowBasis, SparseMatrix};
use mbsa::exact::{Fp, FpBlock};
use nalgebra::DMatrix;
use proptest::prelude::*;

/// A small integer matrix (mostly zeros) with some rows and columns replaced by
/// combinations of others, and a grouping of its columns.
#[derive(Clone, Debug)]
struct Case {
    m: usize,
    n: usize,
    a: Vec<i64>,
    groups: Vec<usize>,
}

fn case() -> impl Strategy<Value = Case> {
    (1usize..9, 1usize..9)
        .prop_flat_map(|(m, n)| {
            (
                Just(m),
                Just(n),
                prop::collection::vec(prop_oneof![3 => Just(0i64), 2 => -3i64..=3], m * n),
                prop::collection::vec((0usize..m, 0usize..m, -2i64..=2, -2i64..=2), 0..3),
                prop::collection::vec((0usize..n, 0usize..n, -2i64..=2), 0..3),
                prop::collection::vec(1usize..4, n),
            )
        })
        .prop_map(|(m, n, mut a, rowdeps, coldeps, sizes)| {
            // Row i := x·row j + y·row k.
            for (t, &(j, k, x, y)) in rowdeps.iter().enumerate() {
                let i = (t * 7 + 3) % m;
                if i != j && i != k {
                    for c in 0..n {
                        a[i * n + c] = x * a[j * n + c] + y * a[k * n + c];
                    }
                }
            }
            // Column c := x·column d.
            for &(c, d, x) in &coldeps {
                if c != d {
                    for r in 0..m {
                        a[r * n + c] = x * a[r * n + d];
                    }
                }
            }
            // Group sizes cut to sum to n.
            let mut groups = Vec::new();
            let mut left = n;
            for s in sizes {
                if left == 0 {
                    break;
                }
                let s = s.min(left);
                groups.push(s);
                left -= s;
            }
            Case { m, n, a, groups }
        })
}

fn dense_of(c: &Case) -> DMatrix<Fp> {
    DMatrix::from_fn(c.m, c.n, |i, j| Fp::from_i64(c.a[i * c.n + j]))
}

fn sparse_of(c: &Case) -> SparseMatrix {
    let mut s = SparseMatrix::with_groups(c.groups.clone());
    for i in 0..c.m {
        s.push_row((0..c.n).map(|j| (j as u32, Fp::from_i64(c.a[i * c.n + j]))));
    }
    s
}

fn is_zero(v: &[Fp]) -> bool {
    v.iter().all(|x| x.is_zero())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn dense_matches_svd_rank(c in case()) {
        let d = dense_of(&c);
        let f = DMatrix::from_fn(c.m, c.n, |i, j| c.a[i * c.n + j] as f64);
        let smax = f.clone().svd(false, false).singular_values.max();
        let real = f.rank(1e-9 * smax.max(1.0));
        let r = dense::rank(&d);
        prop_assert_eq!(r, real);
        let ns = dense::null_space(&d);
        prop_assert_eq!(ns.ncols(), c.n - r);
        prop_assert!(is_zero((&d * &ns).as_slice()));
        prop_assert_eq!(dense::rank(&ns), c.n - r);
        let ls = dense::left_null_space(&d);
        prop_assert_eq!(ls.ncols(), c.m - r);
        prop_assert!(is_zero((ls.transpose() * &d).as_slice()));
        let cr = dense::complement_rows(&d);
        prop_assert_eq!(cr.nrows(), c.m - r);
        prop_assert!(is_zero((&cr * &d).as_slice()));
        prop_assert_eq!(dense::rank(&cr), c.m - r);
        let kept = dense::independent_rows(&d);
        prop_assert_eq!(kept.len(), r);
        // Greedy: each row is kept iff the earlier rows do not span it.
        for i in 0..c.m {
            let before = dense::rank(&d.rows(0, i).into_owned());
            let with = dense::rank(&d.rows(0, i + 1).into_owned());
            prop_assert_eq!(kept.contains(&i), with > before);
        }
    }

    #[test]
    fn sparse_matches_dense(c in case()) {
        let d = dense_of(&c);
        let s = sparse_of(&c);
        let r = dense::rank(&d);
        let f = Factor::new(&s);
        prop_assert_eq!(f.rank(), r);
        let ns = f.null_space();
        prop_assert_eq!(ns.len(), c.n - r);
        for x in &ns {
            prop_assert!(is_zero(&s.mul_sparse(x)));
        }
        let basis = DMatrix::from_fn(c.n, ns.len(), |i, k| {
            ns[k].iter().find(|e| e.0 as usize == i).map_or(Fp::ZERO, |e| e.1)
        });
        prop_assert_eq!(dense::rank(&basis), c.n - r);
        let ln = sparse::left_null_space(&s);
        prop_assert_eq!(ln.len(), c.m - r);
        for y in &ln {
            prop_assert!(is_zero(&s.left_mul_sparse(y)));
        }
        let deps = sparse::dependent_rows(&s);
        prop_assert_eq!(deps.len(), c.m - r);
        let keep: Vec<usize> = (0..c.m).filter(|i| !deps.iter().any(|x| x.row == *i)).collect();
        let sub = DMatrix::from_fn(keep.len(), c.n, |i, j| d[(keep[i], j)]);
        prop_assert_eq!(dense::rank(&sub), r);
        let greedy = dense::independent_rows(&d);
        for dep in &deps {
            prop_assert!(!greedy.contains(&dep.row));
            prop_assert_eq!(dep.support.last(), Some(&dep.row));
            prop_assert!(is_zero(&s.left_mul_sparse(&dep.vector)));
        }
        let mut rb = RowBasis::new(c.n);
        let kept: Vec<usize> = (0..c.m).filter(|&i| rb.insert(&s.rows[i])).collect();
        prop_assert_eq!(&kept, &dense::independent_rows(&d));
        let mut ordered = RowBasis::with_column_order(&f.column_order());
        let kept2: Vec<usize> = (0..c.m).filter(|&i| ordered.insert(&s.rows[i])).collect();
        prop_assert_eq!(kept2, kept);
        // The block interface gives the same rank (one block per row).
        let mut offsets = vec![0];
        for g in &c.groups {
            offsets.push(offsets.last().copied().unwrap_or(0) + g);
        }
        let blocks: Vec<FpBlock> = (0..c.m)
            .map(|i| FpBlock {
                groups: (0..c.groups.len()).rev().collect(),
                mat: DMatrix::from_fn(1, c.n, |_, j| {
                    // Groups listed in reverse: map local column j back.
                    let mut acc = 0;
                    for g in (0..c.groups.len()).rev() {
                        if j < acc + c.groups[g] {
                            return d[(i, offsets[g] + j - acc)];
                        }
                        acc += c.groups[g];
                    }
                    Fp::ZERO
                }),
            })
            .collect();
        prop_assert_eq!(Factor::from_blocks(&c.groups, blocks).rank(), r);
    }
}

#[test]
fn deterministic() {
    let pairs: Vec<(usize, usize, usize)> = (1..200)
        .map(|i| (i / 2, i, 2))
        .chain((1..50).map(|i| (i, 3 * i % 200, 2)))
        .collect();
    let a = sparse::random_pair_matrix(200, 3, &pairs, 11);
    let (f1, f2) = (Factor::new(&a), Factor::new(&a));
    assert_eq!(f1.rank(), f2.rank());
    assert_eq!(f1.null_space(), f2.null_space());
    assert_eq!(sparse::dependent_rows(&a), sparse::dependent_rows(&a));
    let ns = f1.null_space();
    assert_eq!(ns.len(), f1.nullity());
    for x in &ns {
        assert!(is_zero(&a.mul_sparse(x)));
    }
    assert_eq!(f1.rank(), dense::rank(&a.to_dense()));
}
