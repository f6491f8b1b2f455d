//! The constraint equations set aside at the file's configuration: those dependent there
//! (special geometry), chosen within each biconnected block in a solve order.

use super::float::{MAX_DENSE_UNKNOWNS, Margins, Tol};
use super::lowering::body_names;
use super::rows::{PairRows, input_rows};
use super::solve_order::{SolveKeys, Split, on_node};
use super::unknowns::LocalFrames;
use crate::elimination::{Block, Elimination};
use crate::mechanism::Mechanism;
use crate::structure::Redundancy;
use crate::structure::count::Equations;
use nalgebra::DMatrix;

/// Set aside the constraint equations that are dependent at the file's configuration: within
/// each biconnected block of the body graph (a dependency never spans two blocks: a
/// self-stress restricted to one block is one), constraint rows are taken pair by pair, each
/// kept when it is independent of the rows kept before it. The pairs' input rows are kept.
/// Returns the redundancies found, one per block.
///
/// The order decides which pairs pay for a dependency. Pairs are first taken by distance
/// from the frame; when that sets rows aside, the rows are chosen again in the solve order
/// of [`Split::solve_order`] (the groups of that first choice, each split into the groups
/// its own equations determine in turn), if it splits any group: taken in a solve order,
/// every group keeps rows that determine it, so a row a group needs is never spent on a
/// later one.
pub(super) fn redundant_at_configuration(
    m: &Mechanism,
    eqs: &Equations,
    rows: &mut PairRows,
    free: &PairRows,
    tol: &Tol,
    local: Option<&LocalFrames>,
    set_aside: &mut [u32],
) -> Vec<Redundancy> {
    let blocks: Vec<Vec<usize>> = biconnected_blocks(eqs.nodes, eqs, m.frame)
        .into_iter()
        .filter(|block| block.len() >= 2)
        .collect();
    let aside = Configuration {
        m,
        eqs,
        free,
        tol,
        local,
        depth: frame_depths(m, eqs),
    };
    let first: Vec<Option<BlockChoice>> = blocks
        .iter()
        .map(|block| aside.choose(block, Order::Frame))
        .collect();
    if first.iter().flatten().all(|c| c.dropped == 0) {
        return Vec::new();
    }
    let split = Split {
        m,
        eqs,
        rows,
        tol,
        local,
    };
    let Some(keys) = split.solve_order(&aside.kept_counts(&first, rows)) else {
        return aside.apply(&blocks, first, rows, set_aside);
    };
    let again: Vec<Option<BlockChoice>> = blocks
        .iter()
        .zip(first)
        .map(|(block, c)| match c {
            Some(c) if c.dropped > 0 => aside.choose(block, Order::Solve(&keys)),
            c => c,
        })
        .collect();
    aside.apply(&blocks, again, rows, set_aside)
}

/// The order in which a block's pairs are taken.
#[derive(Clone, Copy)]
enum Order<'a> {
    /// By frame distance, then pair number.
    Frame,
    /// By the larger [`SolveKeys`] of the pair's nodes, then the smaller, then as `Frame`.
    Solve(&'a SolveKeys),
}

/// One block's choice: the rows kept per pair, the number dropped, the block's movable bodies
/// and its number of constraint rows.
#[derive(Clone)]
struct BlockChoice {
    kept: Vec<(usize, Vec<usize>)>,
    dropped: usize,
    bodies: Vec<usize>,
    nrows: usize,
}

/// Distance of every node from the frame (breadth first over pairs).
fn frame_depths(m: &Mechanism, eqs: &Equations) -> Vec<usize> {
    let nb = eqs.nodes;
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        adj[h].push(o);
        adj[o].push(h);
    }
    let mut depth = vec![usize::MAX; nb];
    depth[m.frame] = 0;
    let mut queue = std::collections::VecDeque::from([m.frame]);
    while let Some(x) = queue.pop_front() {
        for &y in &adj[x] {
            if depth[y] == usize::MAX {
                depth[y] = depth[x] + 1;
                queue.push_back(y);
            }
        }
    }
    depth
}

/// What the set-aside reads: the pairs' rows without input (`free`), the threshold, the
/// bodies' local frames and their distances from the frame.
struct Configuration<'a> {
    m: &'a Mechanism,
    eqs: &'a Equations,
    free: &'a PairRows,
    tol: &'a Tol,
    local: Option<&'a LocalFrames>,
    depth: Vec<usize>,
}

impl Configuration<'_> {
    /// The rows of one biconnected block (its pairs) kept at the configuration, the pairs
    /// taken in `order`; `None` when the sparse choice is past its memory.
    fn choose(&self, block: &[usize], order: Order<'_>) -> Option<BlockChoice> {
        let (m, eqs, free) = (self.m, self.eqs, self.free);
        let b = m.b() as usize;
        let mut bodies: Vec<usize> = block
            .iter()
            .flat_map(|&e| eqs.bodies(e))
            .filter(|&x| x != m.frame)
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        let ncols = b * bodies.len();
        let mut pairs = block.to_vec();
        match order {
            Order::Frame => pairs.sort_by_key(|&e| {
                let [h, o] = eqs.bodies(e);
                (self.depth[h].max(self.depth[o]), e)
            }),
            Order::Solve(k) => pairs.sort_by_key(|&e| {
                let [h, o] = eqs.bodies(e);
                (
                    k[h].max(k[o]),
                    k[h].min(k[o]),
                    self.depth[h].max(self.depth[o]),
                    e,
                )
            }),
        }
        let order = pairs;
        let nrows: usize = block.iter().map(|&e| free.nrows(e)).sum();
        let cut = self.tol.cut(1.0, nrows.max(ncols));
        // Pair `e`'s row `i` on the block's columns: (column of each side, the row on that
        // body's own twist about its reference point, signed).
        let side =
            |e: usize, i: usize, x: usize, sign: f64| on_node(self.local, &free.get(e), i, x, sign);
        let (kept, dropped) = if ncols <= MAX_DENSE_UNKNOWNS && !force_sparse_aside() {
            let margins = self.tol.margins.as_ref();
            independent_rows_dense(eqs, free, &order, &bodies, b, (cut, margins), &side)
        } else {
            let margins = self.tol.margins.as_ref();
            independent_rows_sparse(eqs, free, &order, &bodies, b, (cut, margins), &side)?
        };
        Some(BlockChoice {
            kept,
            dropped,
            bodies,
            nrows,
        })
    }

    /// Each block's `chosen` rows kept (the pairs' `rows` replaced, the count per joint added
    /// to `set_aside`); the redundancies, one per block that lost rows.
    fn apply(
        &self,
        blocks: &[Vec<usize>],
        chosen: Vec<Option<BlockChoice>>,
        rows: &mut PairRows,
        set_aside: &mut [u32],
    ) -> Vec<Redundancy> {
        let mut out = Vec::new();
        for (block, choice) in blocks.iter().zip(chosen) {
            let Some(c) = choice.filter(|c| c.dropped > 0) else {
                continue;
            };
            let lowered = self.keep_rows(&c.kept, rows, set_aside);
            out.push(self.redundancy(block, &c.bodies, lowered, c.nrows, c.dropped));
        }
        out
    }

    /// The rows each pair keeps with the rows `chosen` kept (and every input).
    fn kept_counts(&self, chosen: &[Option<BlockChoice>], rows: &PairRows) -> Vec<u32> {
        let mut kept: Vec<u32> = (0..self.eqs.len()).map(|e| rows.nrows(e) as u32).collect();
        for (e, mine) in chosen.iter().flatten().flat_map(|c| &c.kept) {
            let inputs = rows.nrows(*e).saturating_sub(self.free.nrows(*e));
            kept[*e] = (mine.len() + inputs) as u32;
        }
        kept
    }

    /// Replace each pair's rows by its kept constraint rows plus its input rows; the joints
    /// that lost rows (with repeats).
    fn keep_rows(
        &self,
        kept: &[(usize, Vec<usize>)],
        rows: &mut PairRows,
        set_aside: &mut [u32],
    ) -> Vec<usize> {
        let (eqs, free) = (self.eqs, self.free);
        let b = self.m.b() as usize;
        let mut lowered: Vec<usize> = Vec::new();
        for (e, mine) in kept {
            if mine.len() == free.nrows(*e) {
                continue;
            }
            lowered.push(eqs.joint[*e]);
            set_aside[eqs.joint[*e]] += (free.nrows(*e) - mine.len()) as u32;
            let inputs = input_rows(rows.get(*e), free.get(*e));
            let mut r = DMatrix::<f64>::zeros(mine.len() + inputs.nrows(), b);
            for (k, &i) in mine.iter().enumerate() {
                r.set_row(k, &free.get(*e).row(i));
            }
            for i in 0..inputs.nrows() {
                r.set_row(mine.len() + i, &inputs.row(i));
            }
            rows.set(*e, &r);
        }
        lowered
    }

    /// The redundancy of a block whose `nrows` constraint equations lost `dropped`, on the
    /// joints `lowered`.
    fn redundancy(
        &self,
        block: &[usize],
        bodies: &[usize],
        mut lowered: Vec<usize>,
        nrows: usize,
        dropped: usize,
    ) -> Redundancy {
        let (m, eqs) = (self.m, self.eqs);
        let mut joints: Vec<usize> = block.iter().map(|&e| eqs.joint[e]).collect();
        joints.sort_unstable();
        joints.dedup();
        lowered.sort_unstable();
        lowered.dedup();
        let ids =
            |js: &[usize]| -> Vec<String> { js.iter().map(|&j| m.joints[j].id.clone()).collect() };
        Redundancy {
            bodies: body_names(m, eqs, bodies),
            joints: ids(&joints),
            count: dropped as u32,
            lowered: ids(&lowered).join(", "),
            freedom: format!(
                "at the file's configuration the joints {} constrain only {} of their {} \
                 equations independently (special geometry: parallel or concurrent axes, a \
                 planar or spherical loop written in space); the configuration satisfies the \
                 other {dropped}, so they fix nothing",
                crate::structure::capped(&ids(&joints)),
                nrows - dropped,
                nrows
            ),
            configuration: true,
        }
    }
}

/// A pair's row on one body's columns (see [`redundant_at_configuration`]).
type Side<'a> = dyn Fn(usize, usize, usize, f64) -> Vec<f64> + 'a;

/// The rows kept per pair and the number dropped, by [`redundant_at_configuration`]'s rule.
type Chosen = (Vec<(usize, Vec<usize>)>, usize);

/// [`redundant_at_configuration`]'s greedy choice on a dense block (at most
/// [`MAX_DENSE_UNKNOWNS`] columns): Gram-Schmidt against the kept rows, a row kept when its
/// residual exceeds `cut` relative to its own norm on the bodies' local twists.
fn independent_rows_dense(
    eqs: &Equations,
    free: &PairRows,
    order: &[usize],
    bodies: &[usize],
    b: usize,
    (cut, margins): (f64, Option<&Margins>),
    side: &Side<'_>,
) -> Chosen {
    let ncols = b * bodies.len();
    let col = |x: usize| bodies.binary_search(&x).ok().map(|k| k * b);
    let mut basis: Vec<(Vec<f64>, (usize, usize))> = Vec::new();
    let mut kept: Vec<(usize, Vec<usize>)> = Vec::new();
    let mut dropped = 0usize;
    for &e in order {
        let [h, o] = eqs.bodies(e);
        let mut mine = Vec::new();
        for i in 0..free.nrows(e) {
            let mut v = vec![0.0; ncols];
            for (x, sign) in [(h, -1.0), (o, 1.0)] {
                let Some(c) = col(x) else {
                    continue;
                };
                for (k, t) in side(e, i, x, sign).into_iter().enumerate() {
                    v[c + k] += t;
                }
            }
            let n0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            // Only the basis vectors whose nonzero columns meet the row's take part (the
            // others' products are exact zeros): along a chain both stay within a few bodies.
            let mut span = support(&v);
            for _ in 0..2 {
                for (q, (lo, hi)) in &basis {
                    let (a, z) = ((*lo).max(span.0), (*hi).min(span.1));
                    if a >= z {
                        continue;
                    }
                    let d: f64 = q[a..z].iter().zip(&v[a..z]).map(|(a, c)| a * c).sum();
                    for (x, qk) in v[*lo..*hi].iter_mut().zip(&q[*lo..*hi]) {
                        *x -= d * qk;
                    }
                    span = (span.0.min(*lo), span.1.max(*hi));
                }
            }
            let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if let Some(mg) = margins {
                mg.note(n, cut * n0);
            }
            if n > cut * n0 {
                let q: Vec<f64> = v.iter().map(|x| x / n).collect();
                let span = support(&q);
                basis.push((q, span));
                mine.push(i);
            } else {
                dropped += 1;
            }
        }
        kept.push((e, mine));
    }
    (kept, dropped)
}

/// The columns from the first nonzero entry of `v` to past its last (empty: `(0, 0)`).
fn support(v: &[f64]) -> (usize, usize) {
    match v.iter().position(|&x| x != 0.0) {
        Some(lo) => (lo, v.iter().rposition(|&x| x != 0.0).map_or(lo, |h| h + 1)),
        None => (0, 0),
    }
}

#[cfg(test)]
thread_local! {
    /// Tests: the sparse choice on every block, to compare it with the dense one.
    static FORCE_SPARSE_ASIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
fn force_sparse_aside() -> bool {
    FORCE_SPARSE_ASIDE.with(|f| f.get())
}

#[cfg(not(test))]
fn force_sparse_aside() -> bool {
    false
}

/// Memory for [`independent_rows_sparse`]'s fronts: the choice is skipped (the block left to
/// the count, as before) past it.
pub(super) const SPARSE_ASIDE_BYTES: u64 = 1 << 30;

/// [`independent_rows_dense`]'s choice on a large block, sparse: the block's transpose (one
/// unknown per constraint row, one equation per body coordinate) eliminated one row at a time
/// in the same order, a Householder QR without pivoting, which is the same Gram-Schmidt (a row
/// is kept when its residual against the rows kept before it exceeds `cut` times its norm,
/// the rows scaled to unit norm). Fronts stay local when the order walks along the
/// mechanism, as the frame-distance order does on a row of windows. `None` past
/// [`SPARSE_ASIDE_BYTES`].
fn independent_rows_sparse(
    eqs: &Equations,
    free: &PairRows,
    order: &[usize],
    bodies: &[usize],
    b: usize,
    (cut, margins): (f64, Option<&Margins>),
    side: &Side<'_>,
) -> Option<Chosen> {
    let at = |x: usize| bodies.binary_search(&x).ok();
    // Unknown `u` = the u-th row in the order; per body, its rows' coefficients.
    let mut per_body: Vec<(Vec<usize>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); bodies.len()];
    let mut first = Vec::with_capacity(order.len());
    let mut u = 0usize;
    for &e in order {
        let [h, o] = eqs.bodies(e);
        first.push(u);
        for i in 0..free.nrows(e) {
            let sides: Vec<(usize, Vec<f64>)> = [(h, -1.0), (o, 1.0)]
                .into_iter()
                .filter_map(|(x, sign)| Some((at(x)?, side(e, i, x, sign))))
                .collect();
            let n0 = sides
                .iter()
                .flat_map(|(_, v)| v.iter())
                .map(|t| t * t)
                .sum::<f64>()
                .sqrt();
            // Unit rows: the residual is then relative to the row's own norm, as in the dense
            // choice. A pair's rows are orthonormal about the centre; moved to the body's
            // reference point, a row of a joint at distance d from the centre shrinks to about
            // 1/d, so an absolute threshold on it (`cut` grows with the block) set aside sound
            // rows of a long mechanism's far ends.
            let scale = if n0 > 0.0 { 1.0 / n0 } else { 0.0 };
            for (k, v) in sides {
                per_body[k].0.push(u);
                per_body[k].1.extend(v.iter().map(|t| t * scale));
            }
            u += 1;
        }
    }
    let blocks: Vec<Block> = per_body
        .into_iter()
        .filter(|(us, _)| !us.is_empty())
        .map(|(us, vals)| Block {
            mat: DMatrix::from_fn(b, us.len(), |r, c| vals[c * b + r]),
            groups: us,
        })
        .collect();
    let sizes = vec![1usize; u];
    let all: Vec<usize> = (0..u).collect();
    let el = Elimination::run_in_order(&sizes, blocks, cut, SPARSE_ASIDE_BYTES, &all).ok()?;
    if let Some(mg) = margins {
        // The pivots are the unit rows' residuals, as the dense choice measures them.
        mg.note_all(&[el.kept_min, el.dropped_max], cut);
    }
    let mut kept_unknown = vec![false; u];
    for r in &el.records {
        kept_unknown[r.group] = r.rank == 1;
    }
    let mut kept = Vec::with_capacity(order.len());
    let mut dropped = 0usize;
    for (k, &e) in order.iter().enumerate() {
        let mine: Vec<usize> = (0..free.nrows(e))
            .filter(|&i| kept_unknown[first[k] + i])
            .collect();
        dropped += free.nrows(e) - mine.len();
        kept.push((e, mine));
    }
    Some((kept, dropped))
}

/// The pairs of every biconnected block of the body graph (pairs as edges; Hopcroft–Tarjan,
/// iterative), each block's pairs ascending, blocks ordered by their first pair.
fn biconnected_blocks(nb: usize, eqs: &Equations, root: usize) -> Vec<Vec<usize>> {
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nb];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        if h != o {
            adj[h].push((o, e));
            adj[o].push((h, e));
        }
    }
    let mut blocks: Vec<Vec<usize>> = crate::elimination::biconnected_blocks(&adj, root)
        .into_iter()
        .map(|(_, block)| block)
        .collect();
    blocks.sort();
    blocks
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::GeometrySource;

    /// A row of `n` windows written in space (R joints, parallel axes), two decimals in mm.
    fn windows_in_space(n: usize) -> String {
        let (s, ox, oy) = (100.3, 1000.17, 500.23);
        let mut out = String::from("space = \"spatial\"\nframe = 1\n");
        let mut joint = |id: String, a: usize, b: usize, x: f64, y: f64| {
            let (x, y) = (
                ((ox + s * x) * 100.0_f64).round() / 100.0,
                ((oy + s * y) * 100.0_f64).round() / 100.0,
            );
            out.push_str(&format!(
                "\n[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, {y}, 250.5]\naxis = [0, 0, 1]\n"
            ));
        };
        joint("A0".into(), 1, 2, 0.0, 0.0);
        for k in 1..=n {
            let kf = k as f64;
            joint(format!("VB{}", k - 1), 2 * k, 2 * k + 1, kf - 0.4, 0.8);
            joint(format!("B{k}"), 2 * k + 1, 2 * k + 2, kf + 0.6, 0.8);
            joint(format!("P{k}"), 1, 2 * k + 2, kf, 0.0);
        }
        out
    }

    /// A planar strip of `dyads` RRR dyads at right angles, each pinned to the two bodies of
    /// the one before, exact coordinates; the crank is driven (mobility 1, one input).
    fn dyad_strip(dyads: usize) -> String {
        let mut out = String::from("precision = 0\nspace = \"planar\"\nframe = 1\n");
        let mut joint = |id: String, a: usize, b: usize, x: f64, y: f64, driven: &str| {
            out.push_str(&format!(
                "\n[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, {y}]\n{driven}"
            ));
        };
        joint("A0".into(), 1, 2, 0.0, 0.5, "driven = 1\n");
        for k in 1..=dyads {
            let (a, b, kf) = (2 * k + 1, 2 * k + 2, k as f64);
            let (ta, tb) = if k == 1 { (2, 1) } else { (a - 2, b - 2) };
            joint(format!("T{k}"), ta, a, kf, 1.0, "");
            joint(format!("C{k}"), a, b, kf + 0.5, 0.5, "");
            joint(format!("B{k}"), tb, b, kf, 0.0, "");
        }
        out
    }

    /// A long, well-conditioned strip keeps every constraint at the file's configuration:
    /// its rows far from the centre, short once moved to their bodies' reference points, are
    /// judged relative to their own norm, not against a threshold that grows with the strip
    /// (30,000 bodies, the sparse choice).
    #[test]
    fn a_long_strip_sets_nothing_aside() {
        let text = dyad_strip(14_999);
        let m = crate::format::load("strip", &text, crate::format::Format::Toml).expect("loads");
        assert_eq!(m.bodies.len(), 30_000);
        let opts = crate::structure::Options {
            geometry: GeometrySource::File,
            ..Default::default()
        };
        let lib = crate::structure::Library::empty();
        let a = crate::structure::analyze(&m, &opts, &lib).expect("analyzes");
        let text = format!("{a:?}");
        assert!(
            !text.contains("configuration: true"),
            "constraints set aside"
        );
        assert_eq!(a.status, crate::structure::Status::Determined);
        assert_eq!(a.groups.len(), 15_000, "the crank and one group per dyad");
    }

    /// The sparse choice of the constraints set aside at the file's configuration keeps the
    /// same rows as the dense Gram-Schmidt on every block the dense one takes: the bundled
    /// mechanisms with geometry (Bennett, Bricard, planar loops written in space, the 40-window
    /// N-four-bar in space) and rows of windows written in space.
    #[test]
    fn sparse_set_aside_keeps_the_dense_rows() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("mechanisms");
        let mut files: Vec<(String, String)> = std::fs::read_dir(&dir)
            .expect("mechanisms/")
            .filter_map(|e| {
                let p = e.ok()?.path();
                (p.extension()? == "toml").then(|| {
                    (
                        p.display().to_string(),
                        std::fs::read_to_string(&p).expect("readable"),
                    )
                })
            })
            .collect();
        files.sort();
        for n in [1, 3, 10, 60] {
            files.push((format!("{n} windows in space"), windows_in_space(n)));
        }
        let opts = crate::structure::Options {
            geometry: GeometrySource::File,
            ..Default::default()
        };
        let lib = crate::structure::Library::empty();
        let mut compared = 0;
        let mut with_aside = 0;
        for (name, text) in &files {
            let m = crate::format::load(name, text, crate::format::Format::Toml).expect("loads");
            let run = |sparse: bool| {
                FORCE_SPARSE_ASIDE.with(|f| f.set(sparse));
                let a = crate::structure::analyze(&m, &opts, &lib);
                FORCE_SPARSE_ASIDE.with(|f| f.set(false));
                a.map(|a| format!("{a:?}"))
            };
            let (Ok(dense), Ok(sparse)) = (run(false), run(true)) else {
                continue;
            };
            compared += 1;
            with_aside += usize::from(dense.contains("configuration: true"));
            assert_eq!(dense, sparse, "{name}");
        }
        assert!(compared >= 20, "{compared} files compared");
        assert!(with_aside >= 5, "{with_aside} with constraints set aside");
    }
}
