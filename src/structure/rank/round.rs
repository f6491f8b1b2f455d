//! One round of the rank check over one decomposition: the groups lowered so far and the
//! under-determined block they grow.

use super::blocks::width;
use super::float::MAX_DENSE_UNKNOWNS;
use super::rows::PairRows;
use crate::structure::count::Decomposition;
use nalgebra::DMatrix;

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
