//! Scale measurements of the exact GF(p) elimination (docs/benchmarks.md, "Exact
//! arithmetic"): `cargo run --release --example exact_scale -- [family] [bodies...]`.
//!
//! Families: `chain` (serial chain of spatial R joints), `star` (a hub body with n bodies on
//! spatial R joints), `assur` (planar Assur II linkage, variant A), `giant` (the giant
//! structural group of planar Assur II variant B with `bodies` = number of groups). Rows
//! have random field entries in the sparsity pattern of the joints (B − k rows per pair over
//! the two bodies' B columns). Prints one line per size: rank, nullity, times, fill.

use mbsa::exact::sparse::{Factor, RowBasis, SparseMatrix, random_pair_matrix};
use mbsa::exact::{Fp, dense};
use mbsa::generate::{self, Variant};
use mbsa::mechanism::Mechanism;
use mbsa::rng::SplitMix64;
use mbsa::structure::{self, Library, Options};
use std::time::Instant;

fn pairs_of(m: &Mechanism) -> Vec<(usize, usize, usize)> {
    // Body index → 0 for the frame, 1.. for the others (random_pair_matrix's numbering).
    let num = |i: usize| {
        if i == m.frame {
            0
        } else if i < m.frame {
            i + 1
        } else {
            i
        }
    };
    let b = m.b() as usize;
    m.joints
        .iter()
        .map(|j| (num(j.bodies[0]), num(j.bodies[1]), b - j.grade() as usize))
        .collect()
}

fn family(name: &str, n: usize) -> (SparseMatrix, String) {
    match name {
        "chain" => {
            let pairs: Vec<_> = (1..=n).map(|i| (i - 1, i, 5)).collect();
            (
                random_pair_matrix(n + 1, 6, &pairs, 1),
                format!("chain {n}"),
            )
        }
        "star" => {
            let mut pairs = vec![(0, 1, 5)];
            pairs.extend((2..=n).map(|i| (1, i, 5)));
            (random_pair_matrix(n + 1, 6, &pairs, 1), format!("star {n}"))
        }
        "assurB" | "spatialB" => {
            let groups = (n.saturating_sub(2) / 4).max(1) as u64;
            let (m, b) = if name == "assurB" {
                (
                    generate::assur(2, groups, 364, Variant::B).expect("valid"),
                    3,
                )
            } else {
                (
                    generate::assur_spatial(2, groups, 364, Variant::B).expect("valid"),
                    6,
                )
            };
            let label = format!("{name} II {} bodies (whole, inputs omitted)", m.movable());
            (
                random_pair_matrix(m.bodies.len(), b, &pairs_of(&m), 1),
                label,
            )
        }
        "assur" => {
            let groups = (n.saturating_sub(2) / 4).max(1) as u64;
            let m = generate::assur(2, groups, 1, Variant::A).expect("valid");
            let label = format!("assur II {} bodies", m.movable());
            (
                random_pair_matrix(m.bodies.len(), 3, &pairs_of(&m), 1),
                label,
            )
        }
        _ => giant(n as u64),
    }
}

/// The giant group of planar Assur II variant B with `groups` groups: its bodies' unknowns,
/// the rows of its internal pairs, of its pairs to bodies solved before it, and the input.
fn giant(groups: u64) -> (SparseMatrix, String) {
    let seed = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(364);
    let m = generate::assur(2, groups, seed, Variant::B).expect("valid");
    let index: std::collections::BTreeMap<String, usize> = (0..m.bodies.len())
        .map(|i| (m.body_id(i).to_string(), i))
        .collect();
    let opts = Options {
        count_only: true,
        ..Options::default()
    };
    let a = structure::analyze(&m, &opts, &Library::builtin())
        .expect("generated mechanisms need no geometry");
    let (gi, g) = a
        .groups
        .iter()
        .enumerate()
        .max_by_key(|(_, g)| g.nm)
        .expect("a group");
    let mut col = vec![usize::MAX; m.bodies.len()];
    let mut nb = 0;
    for id in &g.bodies {
        let i = index[id];
        col[i] = nb;
        nb += 1;
    }
    // Bodies solved before the group: the frame and the bodies of the groups it depends on.
    let mut before = vec![false; m.bodies.len()];
    before[m.frame] = true;
    for &d in &a.groups[gi].depends_on {
        for id in &a.groups[d].bodies {
            before[index[id]] = true;
        }
    }
    let mut rng = SplitMix64::new(7);
    let mut s = SparseMatrix::with_groups(vec![3; nb]);
    for j in &m.joints {
        let (x, y) = (j.bodies[0], j.bodies[1]);
        let (cx, cy) = (col[x] != usize::MAX, col[y] != usize::MAX);
        let ok = (cx && (cy || before[y])) || (cy && before[x]);
        if !ok {
            continue;
        }
        let rows = 2 + j.driven as usize;
        for _ in 0..rows {
            let mut e = Vec::new();
            for side in [x, y] {
                if col[side] != usize::MAX {
                    for k in 0..3 {
                        e.push(((3 * col[side] + k) as u32, Fp::random_nonzero(&mut rng)));
                    }
                }
            }
            s.push_row(e);
        }
    }
    let label = format!(
        "giant group of II-{groups}B (seed {seed}): {nb} bodies, {} unknowns, {} rows",
        s.ncols,
        s.nrows()
    );
    (s, label)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fam = args.first().map_or("chain", String::as_str).to_string();
    let sizes: Vec<usize> = args[1.min(args.len())..]
        .iter()
        .filter_map(|s| s.parse().ok())
        .collect();
    let with_null = std::env::var("NULL").is_ok();
    let with_basis = std::env::var("BASIS").is_ok();
    for n in sizes {
        let t0 = Instant::now();
        let (mut a, label) = family(&fam, n);
        // DUP=k: k planted dependent rows, each a random combination of 10 rows spread
        // over a window of 50 consecutive rows (a redundant loop's rows), inserted inside.
        let dup: usize = std::env::var("DUP")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        let mut rng = SplitMix64::new(99);
        for _ in 0..dup {
            let m = a.nrows();
            let start = rng.below(m.saturating_sub(50).max(1) as u64) as usize;
            let mut e = Vec::new();
            for _ in 0..10 {
                let i = (start + rng.below(50) as usize).min(m - 1);
                let k = Fp::random_nonzero(&mut rng);
                e.extend(a.rows[i].iter().map(|&(c, v)| (c, v * k)));
            }
            a.push_row(e);
        }
        let build = t0.elapsed();
        let t = Instant::now();
        let f = Factor::new(&a);
        let tf = t.elapsed();
        let st = f.stats();
        print!(
            "{label}: {} x {}, input {} entries, built {:.2?}; factor {:.3?}, rank {}, nullity {}, \
             max front {:?}, factor entries {} ({:.1}x input)",
            a.nrows(),
            a.ncols,
            st.input_entries,
            build,
            tf,
            f.rank(),
            f.nullity(),
            st.max_front,
            st.factor_entries,
            st.factor_entries as f64 / st.input_entries.max(1) as f64,
        );
        if with_null {
            let t = Instant::now();
            let ns = f.null_space();
            let nnz: usize = ns.iter().map(|x| x.len()).sum();
            print!(
                "; null space {:.3?} ({} vectors, {nnz} entries)",
                t.elapsed(),
                ns.len()
            );
        }
        if with_basis {
            let t = Instant::now();
            let mut rb = RowBasis::with_column_order(&f.column_order());
            let kept = a.rows.iter().filter(|r| rb.insert(r)).count();
            print!(
                "; row basis in factor order {:.3?} (kept {kept}, {} entries)",
                t.elapsed(),
                rb.entries()
            );
        }
        if std::env::var("TRACK").is_ok() {
            let t = Instant::now();
            let mut rb = RowBasis::with_column_order(&f.column_order()).with_tracking();
            let mut deps = 0;
            let mut dep_entries = 0;
            for r in &a.rows {
                if !rb.insert(r) {
                    deps += 1;
                    dep_entries += rb.last_dependency().map_or(0, |y| y.len());
                }
            }
            print!(
                "; tracked row basis {:.3?} ({deps} dependent rows, {dep_entries} entries in their dependencies, {} combination entries)",
                t.elapsed(),
                rb.combination_entries()
            );
        }
        if std::env::var("LEFT").is_ok() {
            let t = Instant::now();
            let ft = Factor::new(&a.transpose()); // the transpose, for comparison
            let tt = t.elapsed();
            let t = Instant::now();
            let ln = ft.null_space();
            let nnz: usize = ln.iter().map(|x| x.len()).sum();
            print!(
                "; transpose factor {tt:.3?} (max front {:?}, {} entries), left null space {:.3?} ({} vectors, {nnz} entries)",
                ft.stats().max_front,
                ft.stats().factor_entries,
                t.elapsed(),
                ln.len()
            );
        }
        if a.ncols <= 600 {
            assert_eq!(dense::rank(&a.to_dense()), f.rank());
            print!("; dense rank agrees");
        }
        println!();
    }
}
