//! One expansion as a bipartite matching problem: constraint equations and input slots of the
//! pairs against the unknowns of the bodies, with the augmenting paths the search uses.

use super::expansion::Expansion;
use super::groups::Lean;
use super::oracle::Oracle;
use super::rules::Rules;
use super::{TransformOptions, analysis_work};
use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use crate::structure::{self, Library};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Flow of every pair into its two bodies, and the units each body has received.
#[derive(Clone, Debug)]
pub(super) struct State {
    pub(super) flow: Vec<[u32; 2]>,
    used: Vec<u32>,
}

/// BFS buffers reused across augmentations.
pub(super) struct Scratch {
    pub(super) seen: Vec<u32>,
    pub(super) stamp: u32,
    pub(super) prev: Vec<(u32, u32)>,
    pub(super) queue: Vec<usize>,
}

pub(super) const NONE: u32 = u32::MAX;

/// One expansion as a bipartite matching problem.
pub(super) struct Problem {
    pub(super) frame: usize,
    pub(super) u: Vec<u32>,
    pub(super) a: Vec<usize>,
    pub(super) c: Vec<usize>,
    pub(super) touching: Vec<Vec<usize>>,
    pub(super) lo: Vec<u32>,
    pub(super) hi: Vec<u32>,
    /// Multiple joints with a kept minimum: their pairs and the minimum of their sum.
    pub(super) kept_groups: Vec<(Vec<usize>, u32)>,
    /// Pairs that may receive inputs beyond the kept ones, in joint order.
    pub(super) cand: Vec<usize>,
    pub(super) isolated: u32,
    pub(super) set_aside: u32,
    pub(super) f: i64,
    /// Units the search places beyond the kept ones.
    pub(super) need: usize,
    /// The matching of the constraint equations and the kept inputs; `None` when no
    /// placement can exist.
    pub(super) root: Option<State>,
    pub(super) note: Option<String>,
    /// The exact decision of each placement, where one is made before its analysis.
    pub(super) oracle: Oracle,
    /// A placement the oracle certifies is analysed from the search's own flow
    /// ([`Lean`]): random geometry, binary joints, the flow method, and an input-free
    /// analysis with no isolated freedom, no redundancy and nothing set aside.
    pub(super) lean: Option<Lean>,
}

impl Problem {
    pub(super) fn of(
        e: &Expansion,
        orig: &Mechanism,
        rules: &Rules,
        opts: &TransformOptions,
        cache: &structure::AnalysisCache,
        ids: &Arc<Vec<String>>,
        meter: &mut Meter,
    ) -> Result<Problem, BudgetExceeded> {
        let m = &e.mech;
        let nb = m.bodies.len();
        let un = Unknowns::of(m, opts, cache, ids, meter)?;
        let nq = m.joints.len();
        let mut p = Problem {
            frame: m.frame,
            u: un.u,
            a: Vec::with_capacity(nq),
            c: Vec::with_capacity(nq),
            touching: vec![Vec::new(); nb],
            lo: vec![0; nq],
            hi: vec![0; nq],
            kept_groups: Vec::new(),
            cand: Vec::new(),
            isolated: un.isolated,
            set_aside: un.set_aside.iter().sum(),
            f: 0,
            need: 0,
            root: None,
            note: None,
            oracle: un.oracle,
            lean: un.lean,
        };
        let cons = p.pairs(e, orig, rules, &un.set_aside);
        if !p.count(&cons) {
            return Ok(p);
        }
        p.root = p.route(m, &cons, meter)?;
        Ok(p)
    }

    /// Each pair's bodies and bounds under `rules`, and its constraint equations (the joint's
    /// less those `set_aside`).
    fn pairs(
        &mut self,
        e: &Expansion,
        orig: &Mechanism,
        rules: &Rules,
        set_aside: &[u32],
    ) -> Vec<u32> {
        let m = &e.mech;
        let b = m.b();
        let nq = m.joints.len();
        let mut cons = vec![0u32; nq];
        let mut group_pairs: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for (q, j) in m.joints.iter().enumerate() {
            let (x, y) = match j.bodies[..] {
                [x, y] => (x, y),
                // Every joint of an expansion is binary; anything else would have no pair.
                _ => (m.frame, m.frame),
            };
            self.a.push(x);
            self.c.push(y);
            for z in [x, y] {
                if z != m.frame && !self.touching[z].contains(&q) {
                    self.touching[z].push(q);
                }
            }
            cons[q] = b.saturating_sub(j.grade()).saturating_sub(set_aside[q]);
            let o = e.origin[q];
            let k = j.grade();
            let ok = rules.allowed[o] && (!rules.grounded || x == m.frame || y == m.frame);
            let kept = rules.keep[o];
            if orig.joints[o].bodies.len() > 2 {
                self.hi[q] = if ok || kept > 0 { k } else { 0 };
                if kept > 0 {
                    group_pairs.entry(o).or_default().push(q);
                }
            } else {
                self.lo[q] = kept.min(k);
                self.hi[q] = if ok { k } else { self.lo[q] };
            }
        }
        self.kept_groups = group_pairs
            .into_iter()
            .map(|(o, qs)| (qs, rules.keep[o]))
            .collect();
        // Pairs on a body with an isolated spin come last: a unit there generically drives
        // the spin, which no determined placement does (its `f` inputs leave exactly the
        // isolated freedoms free), so the first placements found, and those `--limit`
        // examines, are the others (a Delta robot's rods). The placements are the same.
        let spun = |q: usize| {
            [self.a[q], self.c[q]]
                .into_iter()
                .any(|x| x != m.frame && self.u[x] < b)
        };
        let (mut cand, last): (Vec<usize>, Vec<usize>) = (0..nq)
            .filter(|&q| self.hi[q] > self.lo[q])
            .partition(|&q| !spun(q));
        cand.extend(last);
        self.cand = cand;
        cons
    }

    /// The inputs to place by count (`f`, and `need` beyond the kept ones); `false` with a
    /// note when no placement can exist by count.
    fn count(&mut self, cons: &[u32]) -> bool {
        let total_u: i64 = self.u.iter().map(|&x| x as i64).sum();
        let total_c: i64 = cons.iter().map(|&x| x as i64).sum();
        self.f = total_u - total_c;
        let kept: i64 = self.lo.iter().map(|&x| x as i64).sum();
        if self.f < 0 {
            self.note = Some(format!(
                "the joints remove {} DOF more than the bodies have: no placement of inputs \
                 can determine the mechanism",
                -self.f
            ));
            return false;
        }
        if kept > self.f {
            self.note = Some(format!(
                "the kept inputs ({kept}) are more than the {} the mechanism takes",
                self.f
            ));
            return false;
        }
        self.need = (self.f - kept) as usize;
        // Without this the search finds nothing and the user reads "0 placements" with no
        // reason (a Stewart platform with --on P: 6 pistons for 11 inputs).
        let capacity: i64 = self
            .hi
            .iter()
            .zip(&self.lo)
            .map(|(&h, &l)| i64::from(h.saturating_sub(l)))
            .sum();
        if capacity < self.need as i64 {
            self.note = Some(format!(
                "the joints that may be driven carry {capacity} DOF in all, fewer than the {} \
                 input(s) to place: no placement exists",
                self.need
            ));
            return false;
        }
        true
    }

    /// The matching of the constraint equations `cons` and the kept inputs; `None` with a
    /// note when some of them over-determine the bodies.
    fn route(
        &mut self,
        m: &Mechanism,
        cons: &[u32],
        meter: &mut Meter,
    ) -> Result<Option<State>, BudgetExceeded> {
        let nq = m.joints.len();
        let mut s = State {
            flow: vec![[0; 2]; nq],
            used: vec![0; m.bodies.len()],
        };
        let mut scratch = self.scratch();
        for (q, &n) in cons.iter().enumerate() {
            for _ in 0..n {
                let r = self.augment(&mut s, &[q], &mut scratch);
                meter.charge(scratch.queue.len() as u64 + 1)?;
                if r.is_none() {
                    self.note = Some(format!(
                        "the joints' own equations over-determine the bodies near joint {} (by \
                         count): no placement of inputs can determine the mechanism",
                        m.joints[q].id
                    ));
                    return Ok(None);
                }
            }
        }
        for q in 0..nq {
            for _ in 0..self.lo[q] {
                let r = self.augment(&mut s, &[q], &mut scratch);
                meter.charge(scratch.queue.len() as u64 + 1)?;
                if r.is_none() {
                    self.note = Some(format!(
                        "the kept input on joint {} over-determines the bodies it joins: no \
                         placement keeping it is determined",
                        m.joints[q].id
                    ));
                    return Ok(None);
                }
            }
        }
        Ok(Some(s))
    }

    /// A flow routing the equations and the inputs of placement `w` (units per pair, sparse,
    /// kept units included), clipped to a byte as the search's flows are: the root's, then
    /// each input unit beyond the kept ones augmented. Any such flow gives the same groups
    /// ([`Lean`]). `None` if a unit does not fit (never expected: `w` is a count-valid
    /// placement of this problem, so a flow with all its units exists and every partial one
    /// has an augmenting path from the pair of a missing unit).
    pub(super) fn flow_of(&self, w: &[(usize, u32)]) -> Option<Vec<[u8; 2]>> {
        let mut s = self.root.clone()?;
        let mut sc = self.scratch();
        for &(q, n) in w {
            for _ in *self.lo.get(q)?..n {
                self.augment(&mut s, &[q], &mut sc)?;
            }
        }
        Some(
            s.flow
                .iter()
                .map(|f| [f[0].min(255) as u8, f[1].min(255) as u8])
                .collect(),
        )
    }

    /// Pairs that may be driven (including kept ones).
    pub(super) fn drivable(&self) -> usize {
        self.hi.iter().filter(|&&h| h > 0).count()
    }

    pub(super) fn scratch(&self) -> Scratch {
        let nb = self.u.len();
        Scratch {
            seen: vec![0; nb],
            stamp: 0,
            prev: vec![(NONE, NONE); nb],
            queue: Vec::with_capacity(nb),
        }
    }

    pub(super) fn side(&self, q: usize, x: usize) -> usize {
        usize::from(self.a[q] != x)
    }

    pub(super) fn other(&self, q: usize, x: usize) -> usize {
        if self.a[q] == x { self.c[q] } else { self.a[q] }
    }

    /// Route one more equation unit from one of `sources` to a body with spare unknowns,
    /// rerouting earlier units along an augmenting path. Returns the source used.
    fn augment(&self, s: &mut State, sources: &[usize], sc: &mut Scratch) -> Option<usize> {
        self.augment_marked(s, sources, sc, None)
    }

    /// [`Problem::augment`]; with `dead`, bodies from which an earlier call found no spare
    /// unknown are skipped, and a failed call marks every body it reached. Sound while only
    /// augmentations happen in between: an augmenting path changes flows between bodies that
    /// all reach a spare unknown, so a body that reached none still reaches none (and spare
    /// unknowns only get used up). A run of failures then costs one pass, not one each.
    pub(super) fn augment_marked(
        &self,
        s: &mut State,
        sources: &[usize],
        sc: &mut Scratch,
        dead: Option<&mut [bool]>,
    ) -> Option<usize> {
        let alive = |dead: &Option<&mut [bool]>, x: usize| dead.as_ref().is_none_or(|d| !d[x]);
        sc.stamp = sc.stamp.wrapping_add(1);
        if sc.stamp == 0 {
            sc.seen.iter_mut().for_each(|v| *v = 0);
            sc.stamp = 1;
        }
        sc.queue.clear();
        for &q in sources {
            for x in [self.a[q], self.c[q]] {
                if x != self.frame && sc.seen[x] != sc.stamp && alive(&dead, x) {
                    sc.seen[x] = sc.stamp;
                    sc.prev[x] = (q as u32, NONE);
                    sc.queue.push(x);
                }
            }
        }
        let mut qi = 0;
        while qi < sc.queue.len() {
            let x = sc.queue[qi];
            qi += 1;
            if s.used[x] < self.u[x] {
                s.used[x] += 1;
                let mut t = x;
                loop {
                    let (q, from) = sc.prev[t];
                    let q = q as usize;
                    s.flow[q][self.side(q, t)] += 1;
                    if from == NONE {
                        return Some(q);
                    }
                    let from = from as usize;
                    s.flow[q][self.side(q, from)] -= 1;
                    t = from;
                }
            }
            for &q in &self.touching[x] {
                if s.flow[q][self.side(q, x)] == 0 {
                    continue;
                }
                let y = self.other(q, x);
                if y != self.frame && y != x && sc.seen[y] != sc.stamp && alive(&dead, y) {
                    sc.seen[y] = sc.stamp;
                    sc.prev[y] = (q as u32, x as u32);
                    sc.queue.push(y);
                }
            }
        }
        if let Some(d) = dead {
            for &x in &sc.queue {
                d[x] = true;
            }
        }
        None
    }
}

/// What the input-free analysis of an expansion tells its [`Problem`]: each body's unknowns
/// (less its isolated spins), the equations set aside, and the exact decision of the
/// placements.
struct Unknowns {
    u: Vec<u32>,
    isolated: u32,
    /// Constraint equations of each pair dependent at the file's configuration.
    set_aside: Vec<u32>,
    oracle: Oracle,
    lean: Option<Lean>,
}

impl Unknowns {
    fn of(
        m: &Mechanism,
        opts: &TransformOptions,
        cache: &structure::AnalysisCache,
        ids: &Arc<Vec<String>>,
        meter: &mut Meter,
    ) -> Result<Unknowns, BudgetExceeded> {
        let nb = m.bodies.len();
        let b = m.b();
        let mut u = vec![b; nb];
        u[m.frame] = 0;
        let mut isolated = 0u32;
        let mut oracle = Oracle::Undecided;
        let mut lean = None;
        // Constraint equations dependent at the file's configuration fix nothing: inputs take
        // their place (a planar four-bar written in space takes one input, not none).
        let mut set_aside = vec![0u32; m.joints.len()];
        if !opts.analysis.count_only {
            // Spins no input can drive (a bar between two spherical joints): the rank check's
            // isolated freedoms with no input at all, on bodies held by two pairs or more. A
            // body hanging on a single joint also moves with its neighbours held, but that is
            // the joint's own freedom, which an input on it drives.
            let mut pairs = vec![0usize; nb];
            for j in &m.joints {
                for &x in &j.bodies {
                    pairs[x] += 1;
                }
            }
            // The geometry was checked before the enumeration: this analysis cannot fail. It
            // is charged like the analysis of one placement.
            meter.charge(analysis_work(m))?;
            let a =
                structure::analyze_cached(m, &opts.analysis, &Library::empty(), Some(cache), None)
                    .ok();
            let a = a.as_ref();
            if let Some(a) = a {
                for (q, &n) in a.set_aside.iter().enumerate() {
                    set_aside[q] = n;
                }
                oracle = Oracle::of(m, a, opts.full_analyses, meter)?;
                if matches!(oracle, Oracle::Motions { .. })
                    && !opts.full_analyses
                    && opts.analysis.method == structure::Method::Flow
                    && a.isolated.is_empty()
                    && a.redundant.is_empty()
                    && a.set_aside.iter().all(|&n| n == 0)
                {
                    lean = Some(Lean::of(m, ids));
                }
            }
            for iso in a.map(|a| &a.isolated[..]).unwrap_or(&[]) {
                let id = crate::mechanism::BodyId::from_text(&iso.body);
                if let Some(x) = m.body_index(&id)
                    && pairs[x] >= 2
                {
                    u[x] = u[x].saturating_sub(iso.dimension);
                    isolated += iso.dimension;
                }
            }
        }
        Ok(Unknowns {
            u,
            isolated,
            set_aside,
            oracle,
            lean,
        })
    }
}

impl std::fmt::Debug for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Problem")
            .field("pairs", &self.a.len())
            .finish_non_exhaustive()
    }
}

impl Scratch {
    /// A fresh BFS: a new stamp (clearing on wrap-around) and an empty queue.
    pub(super) fn next_stamp(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.seen.iter_mut().for_each(|v| *v = 0);
            self.stamp = 1;
        }
        self.queue.clear();
    }
}
