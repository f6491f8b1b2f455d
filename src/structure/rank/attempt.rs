//! One attempt of the rank check at one realization: the pairs' rows, the rank threshold, the
//! equations set aside at the file's configuration and each body's reduced unknowns, then the
//! rounds of decomposing and checking ([`Attempt::rounds`]).

use super::cache::{Cache, KeyContext, matrix_digest};
use super::float::{REL_TOL, Tol};
use super::rows::{PairRows, pair_rows, pair_rows_at};
use super::set_aside::redundant_at_configuration;
use super::unknowns::LocalFrames;
use super::{Bases, Kept, RankResult, Redraw, Shortcut};
use crate::geometry::GeometryUsed;
use crate::mechanism::{Geometry, Mechanism};
use crate::structure::count::{Decomposition, Equations, Part};
use crate::structure::{Isolated, Redundancy, Unchecked};

/// What one attempt works with once its rows are drawn (the mechanism, the threshold, the
/// rows as lowered so far, each body's reduced unknowns), and what it has found so far.
pub(super) struct Attempt<'a> {
    pub(super) m: &'a Mechanism,
    pub(super) used: &'a GeometryUsed,
    pub(super) cache: Option<&'a Cache>,
    pub(super) shortcut: Shortcut,
    pub(super) b: usize,
    pub(super) tol: Tol,
    /// The tolerance and `b` as the cache keys take them.
    pub(super) tol_words: [u64; 3],
    /// Deficits are confirmed at the draws of this attempt (random geometry only).
    pub(super) confirm: Option<u64>,
    /// At the file's geometry, each body's twist about its own reference point.
    pub(super) local: Option<LocalFrames>,
    pub(super) rows: PairRows,
    /// Each pair's first row count (at most `b`, six: one byte a pair).
    pub(super) orig_rows: Vec<u8>,
    /// Digests of every pair's rows (only with a cache).
    pub(super) rd: Vec<u128>,
    /// Each body's reduced unknowns, and their digests (only with a cache).
    pub(super) q: Bases,
    pub(super) qd: Vec<u128>,
    pub(super) set_aside: Vec<u32>,
    pub(super) isolated: Vec<Isolated>,
    pub(super) redundant: Vec<Redundancy>,
    pub(super) unchecked: Vec<Unchecked>,
    pub(super) work: u64,
    pub(super) rounds: usize,
    /// The bodies others reach the frame through ([`crate::mobility::separating_bodies`]),
    /// found when a body first needs it.
    pub(super) separating: std::sync::OnceLock<Vec<bool>>,
}

/// [`check`](super::check) at one realization: the joints in `redraw.joints` at their own
/// seeds.
#[allow(clippy::too_many_arguments)]
pub(super) fn check_at(
    m: &Mechanism,
    geoms: &[Geometry],
    used: &GeometryUsed,
    eqs: &mut Equations,
    u: &mut [u32],
    cache: Option<&Cache>,
    shortcut: Shortcut,
    redraw: &mut Redraw,
) -> RankResult {
    let b = m.b() as usize;
    let (mut rows, free, prev) = attempt_rows(m, geoms, used, eqs, redraw);
    let confirm = redraw.confirm.filter(|_| used.seed.is_some());
    let (local, tol) = tolerance(m, geoms, used, eqs);
    let (set_aside, configuration) = if used.is_file() {
        set_aside_at_configuration(m, eqs, &mut rows, &free, &tol, local.as_ref())
    } else {
        (vec![0u32; m.joints.len()], Vec::new())
    };
    if let Some(lf) = &local {
        lf.orthonormalize_rows(m, eqs, &mut rows);
    }
    for (e, cap) in eqs.cap.iter_mut().enumerate() {
        *cap = rows.nrows(e) as u32;
    }
    let orig_rows: Vec<u8> = (0..rows.len())
        .map(|e| u8::try_from(rows.nrows(e)).expect("a pair has at most six rows"))
        .collect();
    let rd: Vec<u128> = match cache {
        Some(_) => crate::par::map(rows.len(), |e| matrix_digest(&rows.get(e))),
        None => Vec::new(),
    };
    let mut a = Attempt {
        m,
        used,
        cache,
        shortcut,
        b,
        tol_words: [tol.rel.to_bits(), tol.abs.to_bits(), b as u64],
        tol,
        confirm,
        local,
        rows,
        orig_rows,
        rd,
        q: Vec::new(),
        qd: Vec::new(),
        set_aside,
        isolated: Vec::new(),
        redundant: configuration,
        unchecked: Vec::new(),
        work: 0,
        rounds: 0,
        separating: std::sync::OnceLock::new(),
    };
    // (a) Isolated freedoms and reduced unknowns (each body on its own, in parallel).
    let touching = Touching::of(eqs);
    a.q = a.reduced_unknowns(eqs, &free, &touching, prev);
    a.isolated = isolated_freedoms(m, eqs, &a.q, u, b);
    let suspects = a.unconfirmed_isolated(eqs, &touching);
    if !suspects.is_empty() {
        // [`check`](super::check) starts over: the decomposition is never read.
        return a.finish(Decomposition::default(), false, suspects);
    }
    drop(touching);
    a.qd = match cache {
        Some(_) => crate::par::map(eqs.nodes, |x| {
            a.q[x]
                .as_ref()
                .map_or(0, |q| matrix_digest(q).wrapping_add(1))
        }),
        None => Vec::new(),
    };
    // (b)-(c) Decompose, check every block, lower, repeat.
    a.rounds(eqs, u)
}

/// The rows of this attempt, the rows without input (at the file's geometry), and, when the
/// last attempt's rows are taken over, its bases and which pairs were built again since
/// (their bodies' bases are computed again; every other body's rows are as they were).
#[allow(clippy::type_complexity)]
fn attempt_rows(
    m: &Mechanism,
    geoms: &[Geometry],
    used: &GeometryUsed,
    eqs: &Equations,
    redraw: &mut Redraw,
) -> (PairRows, PairRows, Option<(Bases, Vec<bool>)>) {
    let b = m.b() as usize;
    match (redraw.rows.take(), used.seed) {
        (Some(kept), Some(seed)) => {
            // The last attempt's rows (random realizations only): the pairs of the joints
            // drawn again and the pairs it lowered are built again, the rest is as drawn.
            let Kept {
                mut rows,
                first,
                bases,
            } = kept;
            let mut changed = vec![false; first.len()];
            for (e, &n) in first.iter().enumerate() {
                let ji = eqs.joint[e];
                if rows.nrows(e) != usize::from(n) || redraw.fresh.contains(&ji) {
                    let s = redraw.joints.get(&ji).copied().unwrap_or(seed);
                    rows.set(e, &pair_rows_at(m, eqs, e, s));
                    changed[e] = true;
                }
            }
            (
                rows,
                PairRows::from_chunks(b, Vec::new()),
                Some((bases, changed)),
            )
        }
        _ => {
            let (rows, free) = pair_rows(m, geoms, used.seed, &redraw.joints, eqs, used.is_file());
            (rows, free, None)
        }
    }
}

/// At the file's configuration, constraints that are dependent there (a planar loop written in
/// space, a Bennett or Bricard linkage) are set aside first: the configuration satisfies them,
/// so they fix nothing, and the decomposition runs on what remains. The equations set aside
/// per joint, and the redundancies.
fn set_aside_at_configuration(
    m: &Mechanism,
    eqs: &Equations,
    rows: &mut PairRows,
    free: &PairRows,
    tol: &Tol,
    local: Option<&LocalFrames>,
) -> (Vec<u32>, Vec<Redundancy>) {
    let mut set_aside = vec![0u32; m.joints.len()];
    let configuration = redundant_at_configuration(m, eqs, rows, free, tol, local, &mut set_aside);
    (set_aside, configuration)
}

/// The bodies' local frames (file geometry only) and the rank threshold.
///
/// At the file's geometry every body's unknowns are its twist about its own reference point
/// (see [`LocalFrames`]): the rank decisions no longer depend on how far the body sits from
/// the centre.
fn tolerance(
    m: &Mechanism,
    geoms: &[Geometry],
    used: &GeometryUsed,
    eqs: &Equations,
) -> (Option<LocalFrames>, Tol) {
    let local = used
        .is_file()
        .then(|| LocalFrames::new(m, geoms, eqs))
        .flatten();
    let tol = match used.precision {
        Some(_) => Tol {
            margins: used.is_file().then(Default::default),
            rel: 1e-9,
            abs: match &local {
                Some(lf) => lf.threshold(used),
                None => crate::geometry::file_threshold(m, used).unwrap_or(0.0),
            },
        },
        None => Tol {
            margins: None,
            rel: REL_TOL,
            abs: 0.0,
        },
    };
    (local, tol)
}

/// The isolated freedoms of the bodies (elements and the frame left out); each node's
/// unknowns `u` become its reduced ones.
fn isolated_freedoms(
    m: &Mechanism,
    eqs: &Equations,
    q: &Bases,
    u: &mut [u32],
    b: usize,
) -> Vec<Isolated> {
    let mut isolated = Vec::new();
    for (body, basis) in q.iter().enumerate() {
        let kept = basis.as_ref().map_or(b, |x| x.ncols());
        let iso = b - kept;
        if body != m.frame && iso > 0 && !eqs.is_element(body) {
            isolated.push(Isolated {
                body: m.body_id(body).to_string(),
                dimension: iso as u32,
            });
        }
        u[body] = kept as u32;
    }
    isolated
}

/// Pairs touching each body (compressed: `touch[start[x]..start[x + 1]]`), proper pairs only
/// (a pair of a body with itself constrains nothing). Four bytes an entry (a pair number fits
/// `u32`, as in the decomposition's lists): the pass that fills them writes at random, and
/// half the bytes are half the cache lines and pages it takes.
pub(super) struct Touching {
    start: Vec<u32>,
    touch: Vec<u32>,
}

impl Touching {
    fn of(eqs: &Equations) -> Touching {
        let nb = eqs.nodes;
        let mut start = vec![0u32; nb + 1];
        for e in 0..eqs.len() {
            let [h, o] = eqs.bodies(e);
            if h != o {
                start[h + 1] += 1;
                start[o + 1] += 1;
            }
        }
        for i in 0..nb {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut touch = vec![0u32; start[nb] as usize];
        for e in 0..eqs.len() {
            let [h, o] = eqs.bodies(e);
            if h != o {
                for x in [h, o] {
                    touch[fill[x] as usize] = e as u32;
                    fill[x] += 1;
                }
            }
        }
        Touching { start, touch }
    }

    /// The pairs touching body `x`.
    pub(super) fn pairs(&self, x: usize) -> &[u32] {
        &self.touch[self.start[x] as usize..self.start[x + 1] as usize]
    }
}

impl Attempt<'_> {
    /// The result as it stands, with `decomposition`; with `suspects`, what the next attempt
    /// takes over.
    pub(super) fn finish(
        self,
        decomposition: Decomposition,
        deficient: bool,
        suspects: Vec<(usize, u64)>,
    ) -> RankResult {
        RankResult {
            deficient,
            work: self.work,
            decomposition,
            set_aside: self.set_aside,
            isolated: self.isolated,
            redundant: self.redundant,
            unchecked: self.unchecked,
            rounds: self.rounds,
            near: self.tol.margins.as_ref().and_then(|m| m.near()),
            kept_rows: (!suspects.is_empty()).then_some(Kept {
                rows: self.rows,
                first: self.orig_rows,
                bases: self.q,
            }),
            suspects,
        }
    }

    /// The cache key of a block: everything its verdict depends on (its part, bodies with
    /// their unknowns, pairs with their bodies and rows, whether any pair was lowered).
    pub(super) fn block_key(
        &self,
        part: Part,
        bodies: &[usize],
        block_eqs: &[usize],
        eqs: &Equations,
    ) -> u128 {
        KeyContext {
            tol: &self.tol_words,
            seed: self.used.seed,
            qd: &self.qd,
            rd: &self.rd,
            orig_rows: &self.orig_rows,
        }
        .block(part, bodies, block_eqs, eqs, &self.rows)
    }
}
