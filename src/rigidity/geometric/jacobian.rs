//! The constraint Jacobian: the binary pairs and the pairs of each body, each body's reduced
//! coordinates (the complement of its isolated motions), the parts (biconnected blocks) the
//! rows split into, their row blocks, and their elimination within the budget.

use super::dense::small_null;
use crate::budget::{Budget, BudgetExceeded, Limit, Meter};
use crate::elimination::{Block, Elimination, Stop, sigma_max};
use crate::mechanism::Mechanism;
use crate::motion::JointModel;
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// A binary pair: joint index, hub body, other body.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pair {
    pub(super) joint: usize,
    pub(super) hub: usize,
    pub(super) other: usize,
}

/// The pairs incident to each body, in one flat array: `incident[body]` lists them in
/// increasing order, a pair on one body twice listed twice (as its hub, then as its other).
/// One `Vec` per body (an allocation each, 20 MB on the spatial Assur 10^5 file) was alive
/// through every phase of the analysis, at both of its peaks.
pub(super) struct Incidence {
    /// `list[start[body]..start[body + 1]]`: the pairs of `body`.
    pub(super) start: Vec<usize>,
    pub(super) list: Vec<usize>,
}

impl Incidence {
    pub(super) fn new(nb: usize, pairs: &[Pair]) -> Self {
        let mut start = vec![0usize; nb + 1];
        for p in pairs {
            start[p.hub + 1] += 1;
            start[p.other + 1] += 1;
        }
        for i in 0..nb {
            start[i + 1] += start[i];
        }
        let mut next = start.clone();
        let mut list = vec![0usize; start[nb]];
        for (pi, p) in pairs.iter().enumerate() {
            for x in [p.hub, p.other] {
                list[next[x]] = pi;
                next[x] += 1;
            }
        }
        Self { start, list }
    }
}

impl std::ops::Index<usize> for Incidence {
    type Output = [usize];
    fn index(&self, body: usize) -> &[usize] {
        &self.list[self.start[body]..self.start[body + 1]]
    }
}

pub(super) fn pairs_of(m: &Mechanism) -> Vec<Pair> {
    let mut out = Vec::new();
    for (ji, j) in m.joints.iter().enumerate() {
        if let Some((&hub, rest)) = j.bodies.split_first() {
            for &o in rest {
                out.push(Pair {
                    joint: ji,
                    hub,
                    other: o,
                });
            }
        }
    }
    out
}

/// Each body's orthonormal complement of its isolated motions ([`complement`]), indexed
/// like a `Vec<DMatrix<f64>>`. Most bodies have no isolated motion, and their complement,
/// the identity, is one matrix shared by all of them (a matrix each was 29 MB at 10^5
/// spatial bodies, alive through the whole analysis); the values read are the same.
pub(super) struct Complements {
    /// The identity of size B.
    pub(super) identity: DMatrix<f64>,
    /// `None`: the identity.
    pub(super) own: Vec<Option<DMatrix<f64>>>,
}

impl Complements {
    /// `n` bodies, each with the identity (no isolated motion).
    pub(super) fn new(n: usize, b: usize) -> Complements {
        Complements {
            identity: DMatrix::identity(b, b),
            own: vec![None; n],
        }
    }

    /// Body `body`'s complement is `c`.
    pub(super) fn set(&mut self, body: usize, c: DMatrix<f64>) {
        self.own[body] = Some(c);
    }

    /// The number of bodies.
    pub(super) fn len(&self) -> usize {
        self.own.len()
    }
}

impl std::ops::Index<usize> for Complements {
    type Output = DMatrix<f64>;
    fn index(&self, body: usize) -> &DMatrix<f64> {
        self.own[body].as_ref().unwrap_or(&self.identity)
    }
}

/// Orthonormal complement (columns) of orthonormal columns `q` in R^b.
pub(super) fn complement(q: &DMatrix<f64>, b: usize) -> DMatrix<f64> {
    if q.ncols() == 0 {
        return DMatrix::identity(b, b);
    }
    small_null(&q.transpose(), 1e-9)
}

/// A map from bodies to local indices within one part. A part holding a large share of the
/// mechanism's bodies takes a table over all bodies (a lookup per pair was a search through
/// a `BTreeMap` or the sorted body list: a cache miss per level at 10^6 bodies); a small one a
/// `BTreeMap`, so that the many small parts of a chain or a star cost no table each (the parts
/// share only cut bodies, so at most a few of them are large).
pub(super) enum BodyIndex {
    Table(Vec<u32>),
    Map(BTreeMap<usize, usize>),
}

impl BodyIndex {
    /// The index of `entries` (body, local index), `nb` bodies in all, `len` entries.
    pub(super) fn new(
        nb: usize,
        len: usize,
        entries: impl Iterator<Item = (usize, usize)>,
    ) -> BodyIndex {
        if len.saturating_mul(8) >= nb && u32::try_from(len).is_ok() {
            let mut t = vec![u32::MAX; nb];
            for (x, l) in entries {
                if let Some(v) = t.get_mut(x) {
                    *v = l as u32;
                }
            }
            BodyIndex::Table(t)
        } else {
            BodyIndex::Map(entries.collect())
        }
    }

    pub(super) fn get(&self, x: usize) -> Option<usize> {
        match self {
            BodyIndex::Table(t) => t
                .get(x)
                .copied()
                .filter(|&v| v != u32::MAX)
                .map(|v| v as usize),
            BodyIndex::Map(m) => m.get(&x).copied(),
        }
    }
}

/// A part of the Jacobian: the pairs of one biconnected block of the body graph, its bodies
/// (ascending, root included) and its root (the body held fixed: the frame, or the block's
/// cut body nearest the frame or the first body of a floating component).
pub(super) struct Part {
    pub(super) root: usize,
    pub(super) pairs: Vec<usize>,
    pub(super) bodies: Vec<usize>,
}

/// A part's row blocks over its own groups (its bodies with a non-empty complement, root and
/// frame excluded, in body order).
pub(super) struct Built {
    pub(super) groups: Vec<usize>,
    pub(super) sizes: Vec<usize>,
    pub(super) offsets: Vec<usize>,
    pub(super) blocks: Vec<Block>,
    pub(super) smax: f64,
}

/// The block of pair `pi` on `body` (sign: + other, − hub), in `body`'s reduced coordinates.
pub(super) fn pair_block(
    pairs: &[Pair],
    models: &[JointModel],
    comp: &Complements,
    pi: usize,
    body: usize,
) -> DMatrix<f64> {
    let p = pairs[pi];
    let x = &models[p.joint].rows * &comp[body];
    if body == p.hub { -x } else { x }
}

pub(super) fn build_part(
    part: &Part,
    pairs: &[Pair],
    models: &[JointModel],
    comp: &Complements,
    frame: usize,
) -> Built {
    let mut groups = Vec::new();
    let mut sizes = Vec::new();
    let mut offsets = Vec::new();
    let mut acc = 0;
    for &x in &part.bodies {
        if x != frame && x != part.root && comp[x].ncols() > 0 {
            groups.push(x);
            sizes.push(comp[x].ncols());
            offsets.push(acc);
            acc += comp[x].ncols();
        }
    }
    let local = BodyIndex::new(
        comp.len(),
        groups.len(),
        groups.iter().enumerate().map(|(g, &x)| (x, g)),
    );
    let mut blocks = Vec::new();
    for &pi in &part.pairs {
        let p = pairs[pi];
        let mut bodies: Vec<usize> = [p.hub, p.other]
            .into_iter()
            .filter(|&x| local.get(x).is_some())
            .collect();
        bodies.sort_by_key(|&x| local.get(x));
        bodies.dedup();
        let r = models[p.joint].rows.nrows();
        if bodies.is_empty() || r == 0 {
            continue;
        }
        let width: usize = bodies.iter().map(|&x| comp[x].ncols()).sum();
        let mut mat = DMatrix::zeros(r, width);
        let mut c = 0;
        for &x in &bodies {
            let blk = pair_block(pairs, models, comp, pi, x);
            mat.view_mut((0, c), (r, blk.ncols())).copy_from(&blk);
            c += blk.ncols();
        }
        blocks.push(Block {
            groups: bodies.iter().filter_map(|&x| local.get(x)).collect(),
            mat,
        });
    }
    let smax = sigma_max(&sizes, &offsets, &blocks);
    Built {
        groups,
        sizes,
        offsets,
        blocks,
        smax,
    }
}

/// The biconnected blocks of the body graph with the pairs as edges (Hopcroft–Tarjan,
/// iterative, from the frame first, then from each floating component's first body), each
/// with its root: the body through which the search entered it. A pair joining a body to
/// itself is a part of its own.
pub(super) fn biconnected_parts(nb: usize, pairs: &[Pair], frame: usize) -> Vec<Part> {
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nb];
    let mut out: Vec<Part> = Vec::new();
    for (e, p) in pairs.iter().enumerate() {
        if p.hub != p.other {
            adj[p.hub].push((p.other, e));
            adj[p.other].push((p.hub, e));
        } else {
            out.push(Part {
                root: p.hub,
                pairs: vec![e],
                bodies: vec![p.hub],
            });
        }
    }
    for (root, block) in crate::elimination::biconnected_blocks(&adj, frame) {
        let mut bodies: Vec<usize> = block
            .iter()
            .flat_map(|&e| [pairs[e].hub, pairs[e].other])
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        out.push(Part {
            root,
            pairs: block,
            bodies,
        });
    }
    out.sort_by_key(|p| p.pairs.first().copied());
    out
}

/// [`Elimination::run`] within the memory budget: fill-in on a large, densely coupled block
/// can exceed any estimate made before eliminating, so the elimination stops itself. It may
/// hold half the memory limit: the blocks it eliminates (and their copy kept for a retry at
/// another threshold) and the joint models stay alive beside it. Its real work (fronts built,
/// Householder steps, compressions) is charged to `meter` as it goes
/// ([`Elimination::run_metered`]), so the work limit stops it too; then its triangular
/// factors ([`Elimination::work`]) as before, so no charge went down.
pub(super) fn eliminate(
    sizes: &[usize],
    blocks: Vec<Block>,
    abs_tol: f64,
    budget: &Budget,
    bodies: u64,
    meter: &mut Meter,
) -> Result<Elimination, BudgetExceeded> {
    let cap = budget.max_memory_bytes / 2;
    let elim = Elimination::run_metered(sizes, blocks, abs_tol, cap, meter).map_err(|stop| match stop {
        Stop::Work(e) => e,
        Stop::Memory(held) => BudgetExceeded {
            limit: Limit::Memory,
            what: format!(
                "the geometric rigidity analysis (the elimination of one rigid block of {bodies} \
                 bodies over {} unknowns, with its fill-in)",
                sizes.iter().sum::<usize>()
            ),
            // Past half the limit with fill still growing: at least twice that in all.
            needed: held.saturating_mul(2),
            at_least: true,
            allowed: budget.max_memory_bytes,
        },
    })?;
    meter.charge(elim.work())?;
    Ok(elim)
}
