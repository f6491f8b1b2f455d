//! Unit tests of the sparse factorization: against dense elimination, the former block
//! splitting and queue, and under budgets.

use super::super::dense;
use super::super::field::Fp;
use super::blocks::{blocks_of, blocks_of_reference};
use super::carried::SET_ASIDE;
use super::order::GroupQueue;
use super::*;
use crate::budget::Budget;
use crate::rng::SplitMix64;
use nalgebra::DMatrix;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The working blocks from the flat group sets are those of the former vector-per-row
/// sort, block for block and row for row: groups of 1 to 6 columns (or one group per
/// column), rows on 0 to 3 groups drawn from a few sets (so that blocks merge rows), a
/// few rows with their columns out of order (kept by hand, not by `push_row`).
#[test]
fn blocks_from_flat_group_sets_are_the_former_ones() {
    let mut rng = SplitMix64::new(0x626c_6b73);
    let same = |a: &SparseMatrix| {
        let (nb, no) = blocks_of(a);
        let (ob, oo) = blocks_of_reference(a);
        assert_eq!(no, oo);
        assert_eq!(nb.len(), ob.len());
        for (x, y) in nb.iter().zip(&ob) {
            assert_eq!(
                (&x.groups, x.nrows, &x.data, x.id),
                (&y.groups, y.nrows, &y.data, y.id)
            );
        }
        nb.len()
    };
    let mut merged = 0;
    for round in 0..80 {
        let ng = 1 + rng.below(40) as usize;
        let sizes: Vec<usize> = (0..ng).map(|_| 1 + rng.below(6) as usize).collect();
        let mut a = if round % 4 == 0 {
            SparseMatrix::new(sizes.iter().sum())
        } else {
            SparseMatrix::with_groups(sizes.clone())
        };
        let gsizes = a.groups();
        let offsets: Vec<usize> = gsizes
            .iter()
            .scan(0, |acc, &s| {
                *acc += s;
                Some(*acc - s)
            })
            .collect();
        let nsets = 1 + rng.below(8) as usize;
        let sets: Vec<Vec<usize>> = (0..nsets)
            .map(|_| {
                let mut s: Vec<usize> = (0..rng.below(4))
                    .map(|_| rng.below(gsizes.len() as u64) as usize)
                    .collect();
                s.sort_unstable();
                s.dedup();
                s
            })
            .collect();
        for _ in 0..rng.below(60) {
            let set = &sets[rng.below(nsets as u64) as usize];
            let mut row: SparseRow = Vec::new();
            for &g in set {
                for c in offsets[g]..offsets[g] + gsizes[g] {
                    if rng.below(3) > 0 {
                        row.push((c as u32, Fp::random_nonzero(&mut rng)));
                    }
                }
            }
            if rng.below(10) == 0 {
                row.reverse();
            }
            a.rows.push(row);
        }
        merged += a.rows.len() - same(&a);
    }
    assert!(merged > 100, "too few merged rows: {merged}");
    same(&random_pair_matrix(
        30,
        3,
        &[
            (0, 1, 2),
            (1, 2, 2),
            (2, 0, 1),
            (5, 7, 3),
            (7, 5, 2),
            (9, 9, 1),
        ],
        7,
    ));
    same(&square_dag(200, 3, 9, 4, 11));
}

/// The indexed queue of the elimination pops the groups in the order of the heap it
/// replaced (a new entry per rescore, stale ones skipped), ties in the key included.
#[test]
fn group_queue_pops_in_the_order_of_the_versioned_heap() {
    let mut rng = SplitMix64::new(0x0071_7565_7565);
    for _ in 0..60 {
        let n = 1 + rng.below(200) as usize;
        let key = |rng: &mut SplitMix64| {
            (
                rng.below(3) as u32,
                rng.below(20) as usize,
                rng.below(20) as usize,
            )
        };
        let mut queue = GroupQueue::new(n);
        let mut heap = BinaryHeap::new();
        let mut version = vec![0usize; n];
        let mut done = vec![false; n];
        for g in 0..n {
            let k = key(&mut rng);
            queue.set(g, k);
            heap.push(Reverse((k.0, (k.1, k.2), g, 0usize)));
        }
        loop {
            let want = loop {
                match heap.pop() {
                    None => break None,
                    Some(Reverse((_, _, g, v))) if !done[g] && v == version[g] => {
                        break Some(g);
                    }
                    Some(_) => {}
                }
            };
            assert_eq!(queue.pop(), want);
            let Some(g) = want else { break };
            done[g] = true;
            for _ in 0..rng.below(5) {
                let h = rng.below(n as u64) as usize;
                if !done[h] {
                    version[h] += 1;
                    let k = key(&mut rng);
                    queue.set(h, k);
                    heap.push(Reverse((k.0, (k.1, k.2), h, version[h])));
                }
            }
        }
    }
}

fn tracked(a: &SparseMatrix) -> Factor {
    let budget = Budget::UNLIMITED;
    let mut meter = budget.meter("test");
    let what = || "test".to_string();
    Factor::new_tracked_within(
        a,
        &mut Limits {
            budget: &budget,
            meter: &mut meter,
            what: &what,
        },
    )
    .expect("unlimited")
}

fn check(a: &SparseMatrix) {
    let d = a.to_dense();
    let f = Factor::new(a);
    let r = dense::rank(&d);
    assert_eq!(f.rank(), r);
    let ns = f.null_space();
    assert_eq!(ns.len(), a.ncols - r);
    // Random null vectors: in the null space, and spanning it (k = nullity of them).
    let mut rng = SplitMix64::new(17);
    let rv = f.random_null_vectors(ns.len(), &mut rng);
    for x in &rv {
        assert!(a.mul_dense(x).iter().all(|v| v.is_zero()));
    }
    if !rv.is_empty() {
        let m = DMatrix::from_fn(a.ncols, rv.len(), |i, j| rv[j][i]);
        assert_eq!(dense::rank(&m), rv.len());
    }
    for x in &ns {
        assert!(a.mul_sparse(x).iter().all(|v| v.is_zero()));
    }
    // Independence: the free columns carry an identity.
    let free = f.free_columns();
    for (k, x) in ns.iter().enumerate() {
        for (l, &fc) in free.iter().enumerate() {
            let v = x.iter().find(|e| e.0 == fc).map_or(Fp::ZERO, |e| e.1);
            assert_eq!(v, if k == l { Fp::ONE } else { Fp::ZERO });
        }
    }
    let ln = left_null_space(a);
    assert_eq!(ln.len(), a.nrows() - r);
    for y in &ln {
        assert!(a.left_mul_sparse(y).iter().all(|v| v.is_zero()));
    }
    // The tracked factorization: same rank, and a random left null vector whose
    // support is that of the whole left null space.
    let t = tracked(a);
    assert_eq!(t.rank(), r);
    assert!(!f.is_tracked() && t.is_tracked());
    let y = t
        .random_left_null_vector(&mut SplitMix64::new(3))
        .expect("tracked");
    assert_eq!(y.len(), a.nrows());
    let ys: Vec<(u32, Fp)> = (0..y.len() as u32).map(|i| (i, y[i as usize])).collect();
    assert!(a.left_mul_sparse(&ys).iter().all(|v| v.is_zero()));
    let mut support = vec![false; a.nrows()];
    for v in &ln {
        for &(i, _) in v {
            support[i as usize] = true;
        }
    }
    let got: Vec<bool> = y.iter().map(|v| !v.is_zero()).collect();
    assert_eq!(got, support);
    let deps = dependent_rows(a);
    assert_eq!(deps.len(), a.nrows() - r);
    let greedy = dense::independent_rows(&d);
    for dep in &deps {
        assert!(!greedy.contains(&dep.row));
        assert_eq!(dep.support.last(), Some(&dep.row));
    }
    let keep: Vec<usize> = (0..a.nrows())
        .filter(|i| !deps.iter().any(|d| d.row == *i))
        .collect();
    let sub = DMatrix::from_fn(keep.len(), a.ncols, |i, j| d[(keep[i], j)]);
    assert_eq!(dense::rank(&sub), r);
    let mut basis = RowBasis::new(a.ncols);
    let kept: Vec<usize> = (0..a.nrows())
        .filter(|&i| basis.insert(&a.rows[i]))
        .collect();
    assert_eq!(kept, dense::independent_rows(&d));
    let mut ordered = RowBasis::with_column_order(&f.column_order());
    let kept2: Vec<usize> = (0..a.nrows())
        .filter(|&i| ordered.insert(&a.rows[i]))
        .collect();
    assert_eq!(kept2, kept);
    let mut tracked = RowBasis::with_column_order(&f.column_order()).with_tracking();
    for i in 0..a.nrows() {
        let k = tracked.insert(&a.rows[i]);
        assert_eq!(k, kept.contains(&i));
        match tracked.last_dependency() {
            Some(y) => {
                assert!(!k);
                assert_eq!(y.last(), Some(&(i as u32, Fp::ONE)));
                assert!(a.left_mul_sparse(y).iter().all(|v| v.is_zero()));
            }
            None => assert!(k),
        }
    }
}

#[test]
fn chain_and_loop() {
    // Planar: 4 movable bodies on R joints (2 rows per pair), a chain to the frame.
    let chain = [(0, 1, 2), (1, 2, 2), (2, 3, 2), (3, 4, 2)];
    let a = random_pair_matrix(5, 3, &chain, 1);
    check(&a);
    assert_eq!(Factor::new(&a).nullity(), 4);
    // Close the loop twice over: a redundant pair.
    let looped = [(0, 1, 2), (1, 2, 2), (2, 0, 2), (1, 2, 2)];
    let a = random_pair_matrix(3, 3, &looped, 2);
    check(&a);
    let f = Factor::new(&a);
    assert_eq!(f.rank(), 6);
    assert_eq!(f.stats().dependent_rows, 2);
}

/// Random mechanism-like patterns (trees with extra pairs, repeated pairs, pairs to the
/// frame): fronts with rows left over, compressions with dependent rows, rows on no
/// group; the tracked factorization's left null vector against the basis.
#[test]
fn tracked_left_null_space_on_random_patterns() {
    for seed in 0..40u64 {
        let mut rng = SplitMix64::new(seed);
        let nb = 2 + rng.below(30) as usize;
        let b = 1 + rng.below(6) as usize;
        let mut pairs = Vec::new();
        for x in 1..nb {
            pairs.push((
                rng.below(x as u64) as usize,
                x,
                1 + rng.below(b as u64) as usize,
            ));
        }
        for _ in 0..rng.below(2 * nb as u64) {
            let (i, j) = (rng.below(nb as u64) as usize, rng.below(nb as u64) as usize);
            pairs.push((i, j, 1 + rng.below(b as u64 + 2) as usize));
        }
        let a = random_pair_matrix(nb, b, &pairs, seed);
        check(&a);
    }
}

/// A square block triangular pattern like `generate random` with its inputs: body `x`
/// (a group of `b` columns) has `b` rows on itself and one or two earlier bodies; one
/// body in `every` has a singular diagonal block (its last row's part on itself a
/// combination of its other rows' parts), so the tier leaves a row over. Parents are
/// among the `reach` bodies before.
fn square_dag(nb: usize, b: usize, every: u64, reach: u64, seed: u64) -> SparseMatrix {
    let mut rng = SplitMix64::new(seed);
    let mut a = SparseMatrix::with_groups(vec![b; nb]);
    for x in 0..nb {
        let parents: Vec<usize> = match x {
            0 => vec![],
            1 => vec![0],
            _ => {
                // Near earlier bodies: long chains of ancestors, as `generate random`.
                let near = (x as u64).min(reach);
                let p1 = x - 1 - rng.below(near) as usize;
                let p2 = x - 1 - rng.below(near) as usize;
                if p1 == p2 { vec![p1] } else { vec![p1, p2] }
            }
        };
        let singular = x > 0 && b > 1 && rng.below(every) == 0;
        let mut own: Vec<Vec<Fp>> = Vec::new();
        for k in 0..b {
            let v: Vec<Fp> = if singular && k == b - 1 {
                let mut v = vec![Fp::ZERO; b];
                for o in &own {
                    let c = Fp::random(&mut rng);
                    for (vi, oi) in v.iter_mut().zip(o) {
                        *vi += c * *oi;
                    }
                }
                v
            } else {
                (0..b).map(|_| Fp::random(&mut rng)).collect()
            };
            own.push(v.clone());
            let mut e: Vec<(u32, Fp)> = Vec::new();
            for (c, &val) in v.iter().enumerate() {
                e.push(((x * b + c) as u32, val));
            }
            if !parents.is_empty() {
                let p = parents[k % parents.len()];
                for c in 0..b {
                    e.push(((p * b + c) as u32, Fp::random(&mut rng)));
                }
            }
            a.push_row(e);
        }
    }
    a
}

/// Rows left over by singular square tiers, set aside and met by later groups: the
/// rank, null vectors, free columns and the tracked left null vector against dense
/// elimination, and the same rank as carrying them through the fronts.
#[test]
fn square_tiers_with_singular_blocks() {
    for seed in 0..30u64 {
        let mut rng = SplitMix64::new(100 + seed);
        let nb = 2 + rng.below(40) as usize;
        let b = 1 + rng.below(4) as usize;
        let every = 1 + rng.below(4);
        let a = square_dag(nb, b, every, 1 + rng.below(nb as u64), seed);
        check(&a);
        check(&a.transpose());
        let r = Factor::new(&a).rank();
        SET_ASIDE.with(|c| c.set(false));
        let carried = Factor::new(&a).rank();
        SET_ASIDE.with(|c| c.set(true));
        assert_eq!(r, carried, "seed {seed}");
    }
}

/// The rank without the records is the factorization's rank, and under a budget it
/// stops (or not) where the full factorization stops, having charged the same work:
/// random pair matrices with dependent rows, empty rows and a square block triangular
/// matrix whose set-aside rows meet records, under no limit and under memory and work
/// limits around what the factorization needs.
#[test]
fn rank_without_records_is_the_factor_rank_within_the_same_budget() {
    let mut mats = vec![square_dag(300, 3, 7, 300, 3)];
    for seed in 0..6u64 {
        let mut rng = SplitMix64::new(seed);
        let nb = 30 + rng.below(40) as usize;
        let pairs: Vec<(usize, usize, usize)> = (0..2 * nb)
            .map(|_| {
                let i = rng.below(nb as u64) as usize;
                let j = rng.below(nb as u64) as usize;
                (i, j, 1 + rng.below(5) as usize)
            })
            .collect();
        let mut a = random_pair_matrix(nb, 3 + (seed % 4) as usize, &pairs, seed);
        a.push_row([]);
        mats.push(a);
    }
    let run = |a: &SparseMatrix, budget: &Budget, records: bool| {
        let mut meter = budget.meter("test");
        let what = || "test".to_string();
        let mut limits = Limits {
            budget,
            meter: &mut meter,
            what: &what,
        };
        let r = if records {
            Factor::new_within(a, &mut limits).map(|f| f.rank())
        } else {
            Factor::rank_of_rows_within(a.clone(), &mut limits)
        };
        (r.map_err(|e| e.limit), meter.used())
    };
    let mut stopped = 0;
    for a in &mats {
        let full = run(a, &Budget::UNLIMITED, true);
        assert_eq!(full, run(a, &Budget::UNLIMITED, false));
        assert_eq!(full.0, Ok(dense::rank(&a.to_dense())));
        let work = full.1;
        for k in [1u64, 2, 3, 5, 8] {
            for budget in [
                Budget {
                    max_memory_bytes: 400 * k * a.nrows() as u64,
                    ..Budget::UNLIMITED
                },
                Budget {
                    max_work: work * k / 8,
                    ..Budget::UNLIMITED
                },
            ] {
                let got = run(a, &budget, true);
                stopped += usize::from(got.0.is_err());
                assert_eq!(got, run(a, &budget, false));
            }
        }
    }
    assert!(stopped >= 10, "{stopped} stopped");
}

/// The work of factoring a square block triangular matrix whose singular diagonal blocks
/// leave rows over (`rigid --with-inputs` on a random spatial mechanism):
/// carried through the fronts, such a row met every earlier body it reached, each front
/// as wide as their union; set aside, it costs the records it meets.
#[test]
fn rows_left_over_by_square_tiers_cost_the_records_they_meet() {
    let a = square_dag(20000, 3, 500, 20000, 7);
    let work = |set_aside: bool| {
        SET_ASIDE.with(|c| c.set(set_aside));
        let budget = Budget::UNLIMITED;
        let mut meter = budget.meter("test");
        let what = || "test".to_string();
        let f = Factor::new_tracked_within(
            &a,
            &mut Limits {
                budget: &budget,
                meter: &mut meter,
                what: &what,
            },
        )
        .expect("unlimited");
        SET_ASIDE.with(|c| c.set(true));
        (f.rank(), f.stats(), meter.used())
    };
    let (r0, s0, w0) = work(false);
    let (r1, s1, w1) = work(true);
    eprintln!("carried: rank {r0} {s0:?} work {w0}; set aside: rank {r1} {s1:?} work {w1}");
    assert_eq!(r0, r1);
    assert!(r1 < a.nrows());
    assert!(w1 < 30 * s1.input_entries as u64, "{w1} units");
    assert!(s1.max_front.1 <= 9 * 3, "{:?}", s1.max_front);
}

#[test]
fn planted_dependencies() {
    let mut rng = SplitMix64::new(5);
    let mut a = SparseMatrix::with_groups(vec![2, 3, 1, 2]);
    for _ in 0..5 {
        let mut e: Vec<(u32, Fp)> = Vec::new();
        for c in 0..8 {
            if rng.below(3) == 0 {
                e.push((c, Fp::random(&mut rng)));
            }
        }
        a.push_row(e);
    }
    let (r0, r1) = (a.rows[0].clone(), a.rows[1].clone());
    let k = Fp::from_i64(-3);
    a.push_row(r0.iter().map(|&(c, v)| (c, v * k)).chain(r1));
    a.push_row(vec![]);
    check(&a);
    check(&a.transpose());
}

#[test]
fn blocks_interface() {
    let mut rng = SplitMix64::new(4);
    let mat = DMatrix::from_fn(2, 6, |_, _| Fp::random(&mut rng));
    let f = Factor::from_blocks(
        &[3, 3],
        vec![FpBlock {
            groups: vec![1, 0],
            mat,
        }],
    );
    assert_eq!(f.rank(), 2);
    assert_eq!(f.null_space().len(), 4);
}

#[test]
fn row_basis_greedy() {
    let mut b = RowBasis::new(4);
    let one = Fp::ONE;
    assert!(b.insert(&[(1, one), (2, one)]));
    assert!(!b.insert(&[(2, Fp::from_i64(2)), (1, Fp::from_i64(2))]));
    assert!(b.insert(&[(2, one), (3, one)]));
    assert!(!b.insert(&[(1, one), (3, -one)]));
    assert!(!b.insert(&[]));
    assert!(b.insert(&[(0, one), (0, one)]));
    assert_eq!(b.rank(), 3);
}
