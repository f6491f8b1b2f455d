//! The rounds of the rank check: decompose, check every block (over-determined part, groups,
//! under-determined part), lower a deficient one, and decompose again while anything was
//! lowered. [`Round`] is one round's groups lowered so far and the under-determined block
//! they grow.

use super::RankResult;
use super::Shortcut;
use super::attempt::Attempt;
use super::blocks::{Pending, Signatures, block_shape, block_signature, width};
use super::exact::{MAX_EXACT_UNKNOWNS, exact_rank};
use super::float::{MAX_DENSE_UNKNOWNS, block_rank};
use super::rows::PairRows;
use super::screen::sparse_full_rank;
use crate::structure::Unchecked;
use crate::structure::count::{Decomposition, Equations, FlowRound, Part, decompose_next};
use nalgebra::DMatrix;

/// What the rounds carry from one to the next.
#[derive(Default)]
struct Carried {
    /// Blocks already found sound, keyed by their bodies and their pairs with row counts (a
    /// block's rank depends on nothing else), so a repeat pass only checks what changed.
    verified: Signatures,
    /// Joints of deficits a second realization did not confirm (see [`check`](super::check)).
    suspects: Vec<(usize, u64)>,
    /// The pairs lowered since the last decomposition, with their counts then: the next
    /// decomposition starts from what the last one found.
    lowerings: Vec<(usize, u32)>,
}

/// Pairs listed by block, compressed: block `i`'s pairs are `pairs[start[i]..start[i + 1]]`,
/// ascending.
struct PairLists {
    start: Vec<usize>,
    pairs: Vec<usize>,
}

impl PairLists {
    /// The `npairs` pairs by their block (`None`: in none), in one pass.
    fn of(blocks: usize, npairs: usize, block_of: impl Fn(usize) -> Option<usize>) -> PairLists {
        let mut start = vec![0usize; blocks + 1];
        for e in 0..npairs {
            if let Some(i) = block_of(e) {
                start[i + 1] += 1;
            }
        }
        for i in 0..blocks {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut pairs = vec![0usize; start[blocks]];
        for e in 0..npairs {
            if let Some(i) = block_of(e) {
                pairs[fill[i]] = e;
                fill[i] += 1;
            }
        }
        PairLists { start, pairs }
    }

    fn get(&self, i: usize) -> &[usize] {
        &self.pairs[self.start[i]..self.start[i + 1]]
    }
}

impl Attempt<'_> {
    /// (b)-(c): decompose, check every block, lower, repeat until a round lowers nothing (or
    /// leaves deficits to confirm at another draw).
    pub(super) fn rounds(mut self, eqs: &mut Equations, u: &[u32]) -> RankResult {
        let nb = eqs.nodes;
        let mut carried = Carried::default();
        let mut prior: Option<FlowRound> = None;
        loop {
            self.rounds += 1;
            let (dec, flow) = decompose_next(
                self.m,
                eqs,
                u,
                prior.as_ref().map(|r| (r, &carried.lowerings[..])),
            );
            prior = flow;
            carried.lowerings.clear();
            // Blocks in triangular order: over-determined part, groups, under-determined part.
            let over: Vec<usize> = (0..nb)
                .filter(|&x| dec.body_part[x] == Part::Over)
                .collect();
            if self.shortcut == Shortcut::Certified && over.is_empty() && self.redundant.is_empty()
            {
                // The caller proved the whole system of full row rank: with no over-determined
                // part the blocks are square groups (nonsingular) and the under-determined
                // block (full row rank), in block triangular order. Nothing to factorize.
                return self.finish(dec, false, Vec::new());
            }
            if self.shortcut == Shortcut::Determined && self.rounds == 1 {
                if !over.is_empty() || (0..nb).any(|x| dec.body_part[x] == Part::Under) {
                    // Not determined by count: the check only lowers equations, so it cannot
                    // become determined (an over-determined block loses rows only when it
                    // hides a freedom, which then shows as missing DOF).
                    return self.finish(dec, true, Vec::new());
                }
                if let Some(suspects) = self.small_groups_first(eqs, &dec) {
                    let deficient = suspects.is_empty();
                    return self.finish(dec, deficient, suspects);
                }
            }
            let under: Vec<usize> = (0..nb)
                .filter(|&x| dec.body_part[x] == Part::Under)
                .collect();
            let changed = self.check_blocks(eqs, &dec, &over, &under, &mut carried);
            if !changed || !carried.suspects.is_empty() {
                let mut suspects = std::mem::take(&mut carried.suspects);
                suspects.sort_unstable();
                suspects.dedup();
                // Only the blocks of the final decomposition matter.
                self.unchecked
                    .sort_by_key(|x| (std::cmp::Reverse(x.unknowns), x.bodies, x.equations));
                self.unchecked.dedup();
                return self.finish(dec, false, suspects);
            }
        }
    }

    /// [`Shortcut::Determined`], determined by count: any deficient group makes it
    /// under-determined. The small groups first (most are in the cache), before any large
    /// one is factorized. `Some` when the check ends here: the joints of deficits a second
    /// draw did not confirm, or none (the mechanism is not determined).
    fn small_groups_first(
        &mut self,
        eqs: &Equations,
        dec: &Decomposition,
    ) -> Option<Vec<(usize, u64)>> {
        let ng = dec.groups.len();
        let groups = PairLists::of(ng, self.rows.len(), |e| match dec.eq_part[e] {
            Part::Group(g) if self.rows.nrows(e) > 0 && g < ng => Some(g),
            _ => None,
        });
        let small = self.small_groups(eqs, dec, &groups);
        let sound: Vec<(bool, u64)> = crate::par::map(small.len(), |i| {
            let g = small[i].0;
            let block_eqs = groups.get(g);
            let bodies = &dec.groups[g].bodies;
            let (nrows, ncols) = block_shape(self.b, block_eqs, bodies, &self.rows, &self.q);
            let (rank, cost) = block_rank(
                self.b,
                block_eqs,
                bodies,
                eqs,
                &self.rows,
                &self.q,
                Part::Group(g),
                &self.tol,
                (nrows, ncols),
            );
            (rank >= nrows, cost)
        });
        self.work = self.work.saturating_add(sound.iter().map(|s| s.1).sum());
        if sound.iter().any(|&(s, _)| !s) {
            // Each deficient group confirmed at a second realization first.
            let mut suspects = Vec::new();
            for (&(g, _), _) in small.iter().zip(&sound).filter(|(_, s)| !s.0) {
                let block_eqs = groups.get(g);
                let bodies = &dec.groups[g].bodies;
                let shape = block_shape(self.b, block_eqs, bodies, &self.rows, &self.q);
                if let Some(s) =
                    self.unconfirmed_deficit(eqs, block_eqs, bodies, Part::Group(g), shape)
                {
                    suspects.extend(block_eqs.iter().map(|&e| (eqs.joint[e], s)));
                }
            }
            suspects.sort_unstable();
            suspects.dedup();
            return Some(suspects);
        }
        if let Some(c) = self.cache {
            for &(_, key) in &small {
                c.put_block(key, None);
            }
        }
        None
    }

    /// The groups small enough for the dense check and not in the cache, with their cache
    /// keys (0 without a cache).
    fn small_groups(
        &self,
        eqs: &Equations,
        dec: &Decomposition,
        groups: &PairLists,
    ) -> Vec<(usize, u128)> {
        (0..dec.groups.len())
            .filter_map(|g| {
                let block_eqs = groups.get(g);
                let bodies = &dec.groups[g].bodies;
                if block_eqs.is_empty() {
                    return None;
                }
                let (nrows, ncols) = block_shape(self.b, block_eqs, bodies, &self.rows, &self.q);
                if nrows.max(ncols) > MAX_DENSE_UNKNOWNS {
                    return None;
                }
                let key = self.cache.map_or(0, |_| {
                    self.block_key(Part::Group(g), bodies, block_eqs, eqs)
                });
                if let Some(c) = self.cache
                    && c.get_block(key).is_some()
                {
                    return None;
                }
                Some((g, key))
            })
            .collect()
    }

    /// One round over the decomposition `dec`: every block not yet verified checked, the
    /// ranks in parallel (each depends on its own rows only); then the deficient ones in
    /// order are explained and lowered, as a serial pass would. Whether anything was lowered.
    fn check_blocks(
        &mut self,
        eqs: &mut Equations,
        dec: &Decomposition,
        over: &[usize],
        under: &[usize],
        carried: &mut Carried,
    ) -> bool {
        let first_group = usize::from(!over.is_empty());
        let (layout, lists) = self.blocks_of(dec, over, under);
        let (todo, keys) = self.pending(eqs, &lists, &layout, &mut carried.verified);
        let ranks: Vec<(usize, u64)> = crate::par::map(todo.len(), |i| {
            let (block_eqs, bodies, part, ..) = &todo[i];
            let (b, rows, q) = (self.b, &self.rows, &self.q);
            block_rank(
                b, block_eqs, bodies, eqs, rows, q, *part, &self.tol, todo[i].4,
            )
        });
        self.work = self.work.saturating_add(ranks.iter().map(|r| r.1).sum());
        let ranks: Vec<usize> = ranks.into_iter().map(|r| r.0).collect();
        // Most blocks are found sound: room for all of them at once (grown by doubling, the
        // set rehashed every signature about once more, 2 % of `analyze` at 10^6 bodies).
        carried.verified.reserve(todo.len());
        let mut changed = false;
        // Several groups can lose rows in one round (see `Round`); what a lowered group
        // reaches (its dependents, then the under-determined block) waits for the next one.
        let mut round = Round::new(
            self.b,
            &self.q,
            &self.rows,
            &self.orig_rows,
            dec,
            first_group,
            &lists.start,
            &lists.pairs,
            under,
        );
        for (((block_eqs, bodies, part, signature, (nrows, ncols)), rank), key) in
            todo.into_iter().zip(ranks).zip(keys)
        {
            match part {
                Part::Group(g) if round.is_dead(g) => continue,
                Part::Group(_) => {}
                _ if changed => break,
                _ => {}
            }
            // The over-determined block is tall: its surplus rows are the count's business
            // unless it also hides a freedom (a column deficit); then every dependent row goes,
            // so that the count sees the freedom.
            let deficit = nrows.saturating_sub(rank);
            if (part == Part::Over && rank >= ncols) || deficit == 0 {
                if let (Some(c), Some(k)) = (self.cache, key) {
                    c.put_block(k, None);
                }
                carried.verified.insert(signature);
                continue;
            }
            if let Some(s) = self.unconfirmed_deficit(eqs, block_eqs, bodies, part, (nrows, ncols))
            {
                // Drawn again with the other unconfirmed deficits of this pass.
                carried
                    .suspects
                    .extend(block_eqs.iter().map(|&e| (eqs.joint[e], s)));
                continue;
            }
            let lowerings = &mut carried.lowerings;
            if !self.lower_deficient(eqs, block_eqs, bodies, rank, deficit, lowerings) {
                continue;
            }
            changed = true;
            // Later blocks were checked with this one assumed nonsingular: decompose again,
            // unless it was a group (then only its dependents are affected: `Round`).
            let Part::Group(g) = part else {
                break;
            };
            self.grown_under(eqs, &mut round, g, &mut carried.verified);
        }
        changed
    }

    /// The blocks of `dec` in triangular order (over-determined part, groups, under-determined
    /// part), each with its bodies and part, and the pairs (with rows) of every block.
    fn blocks_of<'d>(
        &self,
        dec: &'d Decomposition,
        over: &'d [usize],
        under: &'d [usize],
    ) -> (Vec<(&'d [usize], Part)>, PairLists) {
        let first_group = usize::from(!over.is_empty());
        let ng = dec.groups.len();
        let mut layout: Vec<(&[usize], Part)> = Vec::with_capacity(ng + 2);
        if !over.is_empty() {
            layout.push((over, Part::Over));
        }
        layout.extend((0..ng).map(|g| (&dec.groups[g].bodies[..], Part::Group(g))));
        if !under.is_empty() {
            layout.push((under, Part::Under));
        }
        let block_of = |part: Part| -> Option<usize> {
            match part {
                Part::Over if !over.is_empty() => Some(0),
                Part::Group(g) if g < ng => Some(first_group + g),
                Part::Under if !under.is_empty() => Some(first_group + ng),
                _ => None,
            }
        };
        // Pairs of every block in one pass (compressed by block).
        let lists = PairLists::of(layout.len(), self.rows.len(), |e| {
            (self.rows.nrows(e) > 0)
                .then(|| block_of(dec.eq_part[e]))
                .flatten()
        });
        (layout, lists)
    }

    /// The blocks of a round to check, in triangular order, with their cache keys; blocks
    /// already verified, in the cache, or too large for the dense check are settled here.
    fn pending<'l>(
        &mut self,
        eqs: &Equations,
        lists: &'l PairLists,
        layout: &[(&'l [usize], Part)],
        verified: &mut Signatures,
    ) -> (Vec<Pending<'l>>, Vec<Option<u128>>) {
        let mut todo: Vec<Pending> = Vec::new();
        let mut keys: Vec<Option<u128>> = Vec::new();
        for (i, &(bodies, part)) in layout.iter().enumerate() {
            let block_eqs = lists.get(i);
            if block_eqs.is_empty() {
                continue;
            }
            let signature = block_signature(bodies, block_eqs, &self.rows);
            if verified.contains(&signature) {
                continue;
            }
            let key = self
                .cache
                .map(|_| self.block_key(part, bodies, block_eqs, eqs));
            if let (Some(c), Some(k)) = (self.cache, key)
                && let Some(hit) = c.get_block(k)
            {
                self.unchecked.extend(hit);
                verified.insert(signature);
                continue;
            }
            let (nrows, ncols) = block_shape(self.b, block_eqs, bodies, &self.rows, &self.q);
            if nrows.max(ncols) > MAX_DENSE_UNKNOWNS {
                let sound = self.large_block_sound(eqs, block_eqs, bodies, part, (nrows, ncols));
                let verdict = (!sound).then_some(Unchecked {
                    bodies: bodies.len(),
                    unknowns: ncols,
                    equations: nrows,
                });
                if let (Some(c), Some(k)) = (self.cache, key) {
                    c.put_block(k, verdict.clone());
                }
                self.unchecked.extend(verdict);
                verified.insert(signature);
                continue;
            }
            keys.push(key);
            todo.push((block_eqs, bodies, part, signature, (nrows, ncols)));
        }
        (todo, keys)
    }

    /// Whether a block too large for the dense SVD surely has full rank (else it is reported
    /// unchecked). At a random realization its rank is decided exactly, by sparse elimination
    /// over GF(2^61 − 1), unless a pair of it was already lowered (its exact rows would not be
    /// the ones kept); at the file's geometry, by a sparse elimination that proves full rank.
    fn large_block_sound(
        &mut self,
        eqs: &Equations,
        block_eqs: &[usize],
        bodies: &[usize],
        part: Part,
        (nrows, ncols): (usize, usize),
    ) -> bool {
        let needed = if part == Part::Over { ncols } else { nrows };
        let untouched = block_eqs
            .iter()
            .all(|&e| self.rows.nrows(e) == usize::from(self.orig_rows[e]));
        if let Some(seed) = self.used.seed
            && untouched
            && needed <= nrows.min(ncols)
            && ncols <= MAX_EXACT_UNKNOWNS
            && exact_rank(self.m, eqs, block_eqs, bodies, seed, &mut self.work) >= needed
        {
            return true;
        }
        let (b, rows, q) = (self.b, &self.rows, &self.q);
        self.used.seed.is_none()
            && sparse_full_rank(b, block_eqs, bodies, eqs, rows, q, part, &self.tol, true)
                .is_some_and(|r| r >= needed)
    }

    /// Group `g` lost rows: it and its dependents join the under-determined block. A round per
    /// lowering checked that grown block before anything else: when it is too large for the
    /// dense check, do what that round's first step did (decide it exactly, or report it
    /// unchecked).
    fn grown_under(
        &mut self,
        eqs: &Equations,
        round: &mut Round,
        g: usize,
        verified: &mut Signatures,
    ) {
        let Some((nrows, ncols, untouched)) =
            round.lower(self.b, g, &self.q, &self.rows, &self.orig_rows)
        else {
            return;
        };
        if let Some(seed) = self.used.seed
            && untouched
            && nrows <= ncols
            && ncols <= MAX_EXACT_UNKNOWNS
        {
            let (block_eqs, bodies) = round.under_lists(&self.rows);
            let signature = block_signature(&bodies, &block_eqs, &self.rows);
            if verified.contains(&signature) {
                return;
            }
            if exact_rank(self.m, eqs, &block_eqs, &bodies, seed, &mut self.work) >= nrows {
                verified.insert(signature);
                return;
            }
        }
        self.unchecked.push(Unchecked {
            bodies: round.under_bodies,
            unknowns: ncols,
            equations: nrows,
        });
    }
}

/// One round of the rank check over one decomposition: the groups lowered so far and the
/// under-determined block they grow.
///
/// Lowering a pair of a group leaves every other block as it was but the group's dependents:
/// the flow less the lowered units is still maximum (the group's bodies are not reachable from
/// the source), so the over-determined part stays, and the group with everything that depends
/// on it, transitively, now reaches the sink: it joins the under-determined part. The other
/// groups keep their bodies, pairs and levels, hence their order, so a round that goes on with
/// them finds the deficits, in the order, that a new decomposition after each lowering would
/// (that was quadratic: one decomposition of the whole mechanism per redundancy, 37 rounds
/// on a random spatial mechanism of 10^5 bodies). The under-determined block itself waits for
/// the next round.
pub(super) struct Round<'a> {
    pub(super) dec: &'a Decomposition,
    pub(super) first_group: usize,
    pub(super) bstart: &'a [usize],
    pub(super) beqs: &'a [usize],
    /// Groups that joined the under-determined part in this round (and the order they did).
    dead: Vec<bool>,
    joined: Vec<usize>,
    /// Groups that depend on each group (CSR), built at the first lowering.
    dependents: Vec<usize>,
    dependents_start: Vec<usize>,
    /// The under-determined block as it grows: bodies, rows, columns, and how many of its
    /// pairs have fewer rows than they started with.
    pub(super) under_bodies: usize,
    under_rows: usize,
    under_cols: usize,
    under_touched: usize,
    pub(super) under: &'a [usize],
    under_eqs: &'a [usize],
}

impl<'a> Round<'a> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        b: usize,
        q: &[Option<DMatrix<f64>>],
        rows: &PairRows,
        orig_rows: &[u8],
        dec: &'a Decomposition,
        first_group: usize,
        bstart: &'a [usize],
        beqs: &'a [usize],
        under: &'a [usize],
    ) -> Round<'a> {
        let ub = first_group + dec.groups.len();
        let under_eqs: &[usize] = if under.is_empty() {
            &[]
        } else {
            &beqs[bstart[ub]..bstart[ub + 1]]
        };
        Round {
            dec,
            first_group,
            bstart,
            beqs,
            dead: vec![false; dec.groups.len()],
            joined: Vec::new(),
            dependents: Vec::new(),
            dependents_start: Vec::new(),
            under_bodies: under.len(),
            under_rows: under_eqs.iter().map(|&e| rows.nrows(e)).sum(),
            under_cols: under.iter().map(|&x| width(b, q, x)).sum(),
            under_touched: under_eqs
                .iter()
                .filter(|&&e| rows.nrows(e) != usize::from(orig_rows[e]))
                .count(),
            under,
            under_eqs,
        }
    }

    pub(super) fn is_dead(&self, g: usize) -> bool {
        self.dead[g]
    }

    /// The pairs (with rows) of group `g`.
    fn group_eqs(&self, g: usize) -> &'a [usize] {
        let i = self.first_group + g;
        &self.beqs[self.bstart[i]..self.bstart[i + 1]]
    }

    /// Group `g` lost rows: it and its dependents join the under-determined block. Returns
    /// that block's (rows, columns, untouched) when it is too large for the dense check.
    pub(super) fn lower(
        &mut self,
        b: usize,
        g: usize,
        q: &[Option<DMatrix<f64>>],
        rows: &PairRows,
        orig_rows: &[u8],
    ) -> Option<(usize, usize, bool)> {
        let groups = &self.dec.groups;
        if self.dependents_start.is_empty() {
            let mut start = vec![0usize; groups.len() + 1];
            for grp in groups {
                for &d in &grp.deps {
                    start[d + 1] += 1;
                }
            }
            for i in 0..groups.len() {
                start[i + 1] += start[i];
            }
            let mut fill = start.clone();
            let mut dependents = vec![0usize; start[groups.len()]];
            for (h, grp) in groups.iter().enumerate() {
                for &d in &grp.deps {
                    dependents[fill[d]] = h;
                    fill[d] += 1;
                }
            }
            self.dependents = dependents;
            self.dependents_start = start;
        }
        let mut stack = Vec::new();
        if !self.dead[g] {
            self.dead[g] = true;
            stack.push(g);
        }
        while let Some(h) = stack.pop() {
            self.joined.push(h);
            self.under_bodies += groups[h].bodies.len();
            self.under_cols += groups[h]
                .bodies
                .iter()
                .map(|&x| width(b, q, x))
                .sum::<usize>();
            for &e in self.group_eqs(h) {
                let n = rows.nrows(e);
                if n > 0 {
                    self.under_rows += n;
                    self.under_touched += usize::from(n != usize::from(orig_rows[e]));
                }
            }
            for &d in &self.dependents[self.dependents_start[h]..self.dependents_start[h + 1]] {
                if !self.dead[d] {
                    self.dead[d] = true;
                    stack.push(d);
                }
            }
        }
        (self.under_rows.max(self.under_cols) > MAX_DENSE_UNKNOWNS).then_some((
            self.under_rows,
            self.under_cols,
            self.under_touched == 0,
        ))
    }

    /// The grown under-determined block's pairs (with rows) and bodies, ascending, as a new
    /// decomposition would list them.
    pub(super) fn under_lists(&self, rows: &PairRows) -> (Vec<usize>, Vec<usize>) {
        let mut block_eqs = self.under_eqs.to_vec();
        let mut bodies = self.under.to_vec();
        for &h in &self.joined {
            block_eqs.extend(self.group_eqs(h).iter().filter(|&&e| rows.nrows(e) > 0));
            bodies.extend_from_slice(&self.dec.groups[h].bodies);
        }
        block_eqs.sort_unstable();
        bodies.sort_unstable();
        (block_eqs, bodies)
    }
}
