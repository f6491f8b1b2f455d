//! The multifrontal elimination itself: group by group, a dense front of the rows on the
//! group, its pivots, the rows left over compressed into new blocks, and the record kept.

use super::super::field::{Fp, axpy_sub, scale};
use super::blocks::Blk;
use super::carried::{Carried, CarriedSet, PivotRows, set_aside_enabled};
use super::echelon::{echelon, echelon_tracked, two_rows};
use super::factor::{Factor, FactorStats};
use super::limits::FP_BYTES;
use super::order::{GroupQueue, Pool, WIDE_BLOCK};
use super::record::Record;
use super::tiers::tiers;
use super::trace::{CHOSEN, Combo, DEPENDENT, Trace};

/// How the steps of an elimination report their work and memory: `charge(work, bytes)`.
type Charge<'c, E> = &'c mut dyn FnMut(u64, u64) -> Result<(), E>;

impl Factor {
    /// The elimination. `charge(work, bytes)` is called with the work of each step and the
    /// memory held at its start (live blocks, the front about to be built, the records).
    /// Without `keep`, no record is kept (the factor then gives its rank and statistics,
    /// not its null space: for [`Factor::rank_of_rows_within`] only).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run<E>(
        sizes: Vec<usize>,
        blocks: Vec<Blk>,
        input_entries: usize,
        given_tiers: Option<&[u32]>,
        trace: Option<Trace>,
        keep: bool,
        charge: Charge<'_, E>,
    ) -> Result<Factor, E> {
        let n = sizes.len();
        let mut offsets = Vec::with_capacity(n);
        let mut acc = 0;
        for &s in &sizes {
            offsets.push(acc);
            acc += s;
        }
        let (tier, order_work) = match given_tiers {
            Some(t) => {
                let mut t = t.to_vec();
                t.resize(n, u32::MAX);
                (t, n as u64)
            }
            None => tiers(&sizes, &blocks),
        };
        charge(order_work, 0)?;
        // Rows set aside ([`Carried`]) only in the block triangular order found here: a
        // caller's tiers say nothing about square diagonal blocks.
        let set_aside = given_tiers.is_none() && set_aside_enabled();
        let mut el = Elimination::new(&sizes, &offsets, tier, blocks, keep, set_aside);
        el.records = Vec::with_capacity(if keep { n } else { 0 });
        el.stats.input_entries = input_entries;
        el.trace = trace;
        while let Some(g) = el.queue.pop() {
            el.eliminate_group(g, charge)?;
        }
        let Elimination {
            records,
            rank,
            stats,
            trace,
            ..
        } = el;
        Ok(Factor {
            sizes,
            offsets,
            records,
            rank,
            stats,
            trace,
        })
    }
}

/// The state of one elimination, shared by its steps.
struct Elimination<'a> {
    sizes: &'a [usize],
    offsets: &'a [usize],
    /// Each group's elimination tier.
    tier: Vec<u32>,
    pool: Pool<'a>,
    queue: GroupQueue,
    done: Vec<bool>,
    /// Bytes of the records kept so far.
    record_bytes: u64,
    /// Scratch: a stamp per group (dedup) and the front column of each group.
    stamp: Vec<usize>,
    clock: usize,
    pos: Vec<usize>,
    stamp_rescore: Vec<usize>,
    keep: bool,
    records: Vec<Record>,
    rank: usize,
    stats: FactorStats,
    trace: Option<Trace>,
    /// Whether rows left over by a square tier are set aside ([`Carried`]).
    set_aside: bool,
    /// The rows set aside, the ids of those touching each group (stale ids skipped), and
    /// their entries in all.
    carried: Vec<Option<Carried>>,
    carried_on: Vec<Vec<u32>>,
    carried_len: usize,
    scratch: Scratch,
}

/// Scratch vectors of one front, kept from front to front (a dozen allocations per front
/// were a tenth of the elimination at 10^6 bodies).
#[derive(Default)]
struct Scratch {
    others: Vec<usize>,
    front: Vec<Fp>,
    masks: Vec<u64>,
    order: Vec<usize>,
    in_ids: Vec<u32>,
    own: Vec<u32>,
    tr: Vec<Fp>,
    chosen: Vec<u32>,
    rows: Vec<Fp>,
}

/// The front of one group: the rows on it, side by side over the group's columns and the
/// other groups they touch.
struct Front {
    g: usize,
    /// The group's size.
    sg: usize,
    /// The rows set aside that reach the group.
    touching: Vec<u32>,
    /// The stamp of the neighbours to rescore after this front.
    rescore_mark: usize,
    /// The other groups of the rows, increasing.
    others: Vec<usize>,
    nrows: usize,
    width: usize,
    /// Row-major, `width` per row.
    data: Vec<Fp>,
    /// Tracking: each front row's input position (`own`, until it is chosen as a pivot) and
    /// its coefficients on the rows chosen so far (`tr`, `sg` per row), the chosen rows
    /// and the front's working ids.
    tracking: bool,
    in_ids: Vec<u32>,
    own: Vec<u32>,
    tr: Vec<Fp>,
    chosen: Vec<u32>,
    /// The local pivot columns and free columns, and the pivot rows (the first `r`).
    pivots: Vec<usize>,
    free: Vec<usize>,
    r: usize,
    /// Which of `others` each row touches, `words` per row.
    words: usize,
    masks: Vec<u64>,
}

impl<'a> Elimination<'a> {
    fn new(
        sizes: &'a [usize],
        offsets: &'a [usize],
        tier: Vec<u32>,
        blocks: Vec<Blk>,
        keep: bool,
        set_aside: bool,
    ) -> Elimination<'a> {
        let n = sizes.len();
        let mut pool = Pool::new(sizes, blocks.len() * 2);
        for b in blocks {
            pool.add(b);
        }
        let mut stamp = vec![0usize; n];
        let mut clock = 0usize;
        let mut queue = GroupQueue::new(n);
        for (g, &tg) in tier.iter().enumerate().take(n) {
            let s = pool.score(g, &mut stamp, &mut clock);
            queue.set(g, (tg, s.0, s.1));
        }
        Elimination {
            sizes,
            offsets,
            tier,
            pool,
            queue,
            done: vec![false; n],
            record_bytes: 0,
            stamp,
            clock,
            pos: vec![0usize; n],
            stamp_rescore: vec![0usize; n],
            keep,
            records: Vec::new(),
            rank: 0,
            stats: FactorStats::default(),
            trace: None,
            set_aside,
            carried: Vec::new(),
            carried_on: vec![Vec::new(); n],
            carried_len: 0,
            scratch: Scratch::default(),
        }
    }

    /// Eliminate group `g`: its front, its pivots, the rows left over, its record.
    fn eliminate_group<E>(&mut self, g: usize, charge: Charge<'_, E>) -> Result<(), E> {
        self.done[g] = true;
        let members = self.pool.take(g);
        let mut touching = std::mem::take(&mut self.carried_on[g]);
        touching.sort_unstable();
        touching.dedup();
        touching.retain(|&c| {
            self.carried[c as usize]
                .as_ref()
                .is_some_and(|w| w.parts.contains_key(&g))
        });
        // Neighbours to rescore: those on a narrow block of this front (a group reached
        // only through a wide block keeps its score, a heuristic that keeps long carried
        // rows from costing a pass over all their groups at every step).
        self.clock += 1;
        let rescore_mark = self.clock;
        for b in &members {
            if b.groups.len() <= WIDE_BLOCK {
                for &h in &b.groups {
                    self.stamp_rescore[h] = rescore_mark;
                }
            }
        }
        let mut f = self.assemble(g, members, touching, rescore_mark, charge)?;
        f.eliminate_pivots();
        self.rank += f.r;
        f.row_masks(self.sizes, &self.pos);
        if f.r < f.nrows {
            self.leftover_rows(&f, charge)?;
        }
        self.keep_pivot_rows(f, charge)
    }

    /// The front of group `g` from its blocks, charged its cost and memory.
    fn assemble<E>(
        &mut self,
        g: usize,
        mut members: Vec<Blk>,
        touching: Vec<u32>,
        rescore_mark: usize,
        charge: Charge<'_, E>,
    ) -> Result<Front, E> {
        let sizes = self.sizes;
        // Narrow blocks first: their rows are preferred as pivots, so that the rows left
        // over (and the pivot rows kept) stay narrow.
        members.sort_by_key(Blk::width);
        let (others, width) = self.front_columns(g, &members);
        let sg = sizes[g];
        let nrows: usize = members.iter().map(|b| b.nrows).sum();
        // The real cost of this front: the pivot loop passes over every row for each of
        // the group's columns (`sg` passes of nrows × width at most), and the memory held
        // while it is built (the blocks still live, the members and the front).
        let front_len = (nrows as u64).saturating_mul(width as u64);
        let member_bytes: u64 = members.iter().map(Blk::bytes).sum();
        charge(
            front_len.saturating_mul(sg as u64 + 1),
            self.pool
                .bytes
                .saturating_add(member_bytes)
                .saturating_add(self.record_bytes)
                .saturating_add(self.trace.as_ref().map_or(0, Trace::bytes))
                .saturating_add((self.carried_len as u64).saturating_mul(FP_BYTES))
                .saturating_add(front_len.saturating_mul(FP_BYTES)),
        )?;
        let sc = &mut self.scratch;
        let mut data = std::mem::take(&mut sc.front);
        data.clear();
        data.resize(nrows * width, Fp::ZERO);
        let tracking = self.trace.is_some();
        let mut in_ids = std::mem::take(&mut sc.in_ids);
        let mut own = std::mem::take(&mut sc.own);
        let mut tr = std::mem::take(&mut sc.tr);
        let mut chosen = std::mem::take(&mut sc.chosen);
        in_ids.clear();
        own.clear();
        tr.clear();
        chosen.clear();
        if tracking {
            charge((nrows as u64).saturating_mul((sg * (sg + 2)) as u64), 0)?;
            for b in &members {
                in_ids.extend(b.id..b.id + b.nrows as u32);
            }
            own.extend(0..nrows as u32);
            tr.resize(nrows * sg, Fp::ZERO);
        }
        scatter_rows(&mut data, width, &members, sizes, &self.pos);
        drop(members);
        let max = self.stats.max_front;
        self.stats.max_front = (max.0.max(nrows), max.1.max(width));
        Ok(Front {
            g,
            sg,
            touching,
            rescore_mark,
            others,
            nrows,
            width,
            data,
            tracking,
            in_ids,
            own,
            tr,
            chosen,
            pivots: Vec::new(),
            free: Vec::new(),
            r: 0,
            words: 0,
            masks: std::mem::take(&mut self.scratch.masks),
        })
    }

    /// The other groups of the front of `g` (increasing) and its width, with each group's
    /// front column in `pos`.
    fn front_columns(&mut self, g: usize, members: &[Blk]) -> (Vec<usize>, usize) {
        self.clock += 1;
        let clock = self.clock;
        self.stamp[g] = clock;
        let mut others = std::mem::take(&mut self.scratch.others);
        others.clear();
        for b in members {
            for &h in &b.groups {
                if self.stamp[h] != clock {
                    self.stamp[h] = clock;
                    others.push(h);
                }
            }
        }
        others.sort_unstable();
        self.pos[g] = 0;
        let mut width = self.sizes[g];
        for &h in &others {
            self.pos[h] = width;
            width += self.sizes[h];
        }
        (others, width)
    }

    /// The rows after the pivot rows, split by the groups they touch, each part
    /// compressed.
    fn leftover_rows<E>(&mut self, f: &Front, charge: Charge<'_, E>) -> Result<(), E> {
        let words = f.words;
        let masks = &f.masks;
        let mut order = std::mem::take(&mut self.scratch.order);
        order.clear();
        order.extend(f.r..f.nrows);
        order.sort_by(|&a, &b| {
            masks[a * words..(a + 1) * words].cmp(&masks[b * words..(b + 1) * words])
        });
        let mut i = 0;
        while i < order.len() {
            let key = &masks[order[i] * words..(order[i] + 1) * words];
            let mut j = i;
            while j < order.len() && masks[order[j] * words..(order[j] + 1) * words] == *key {
                j += 1;
            }
            let groups: Vec<usize> = (0..f.others.len())
                .filter(|&k| key[k / 64] >> (k % 64) & 1 == 1)
                .map(|k| f.others[k])
                .collect();
            self.leftover_part(f, &order[i..j], groups, charge)?;
            i = j;
        }
        self.scratch.order = order;
        Ok(())
    }

    /// Front rows `rows`, all on exactly the groups `groups`: dependent when those are
    /// none, else compressed to echelon form and set aside or made a new block.
    fn leftover_part<E>(
        &mut self,
        f: &Front,
        rows: &[usize],
        groups: Vec<usize>,
        charge: Charge<'_, E>,
    ) -> Result<(), E> {
        let sizes = self.sizes;
        let bw: usize = groups.iter().map(|&h| sizes[h]).sum();
        let n_in = rows.len();
        if bw == 0 {
            self.stats.dependent_rows += n_in;
            if let Some(t) = self.trace.as_mut() {
                for &ri in rows {
                    let mut combo = Combo::new(&f.in_ids);
                    combo.add_row(ri, Fp::ONE, &f.own, &f.tr, f.sg, &f.chosen);
                    combo.emit(t, DEPENDENT);
                }
            }
            return Ok(());
        }
        let mut data = Vec::with_capacity(n_in * bw);
        for &ri in rows {
            let row = &f.data[ri * f.width..(ri + 1) * f.width];
            for &h in &groups {
                data.extend_from_slice(&row[self.pos[h]..self.pos[h] + sizes[h]]);
            }
        }
        let kept = if n_in > bw {
            charge(
                (n_in as u64)
                    .saturating_mul(bw as u64)
                    .saturating_mul(bw as u64 + if f.tracking { f.sg as u64 + 2 } else { 0 }),
                0,
            )?;
            self.compress(f, rows, &mut data, bw)
        } else {
            if let Some(t) = self.trace.as_mut() {
                for (o, &ri) in rows.iter().enumerate() {
                    let mut combo = Combo::new(&f.in_ids);
                    combo.add_row(ri, Fp::ONE, &f.own, &f.tr, f.sg, &f.chosen);
                    combo.emit(t, t.nids + o as u32);
                }
                t.nids += n_in as u32;
            }
            n_in
        };
        self.stats.dependent_rows += n_in - kept;
        data.truncate(kept * bw);
        let id = self.trace.as_ref().map_or(0, |t| t.nids - kept as u32);
        if kept > 0 && self.set_aside && groups.iter().all(|&h| self.tier[h] > self.tier[f.g]) {
            // Left over by a square tier (the rows on its groups are all eliminated): set
            // aside rather than carried through the fronts.
            self.set_aside_rows(f, &data, bw, &groups, id);
        } else if kept > 0 {
            if groups.len() <= WIDE_BLOCK {
                for &h in &groups {
                    self.stamp_rescore[h] = f.rescore_mark;
                }
            }
            self.pool.add(Blk {
                groups,
                nrows: kept,
                data,
                id,
            });
        }
        Ok(())
    }

    /// Echelon form of the rows left over on one set of groups (`data`, `bw` per row, the
    /// front rows `rows`); returns how many are kept. Tracked as the front: each output row
    /// is a combination of the part's rows, each of those one of the front's rows.
    fn compress(&mut self, f: &Front, rows: &[usize], data: &mut [Fp], bw: usize) -> usize {
        let Some(t) = self.trace.as_mut() else {
            return echelon(data, bw);
        };
        let n_in = rows.len();
        let mut own2: Vec<u32> = (0..n_in as u32).collect();
        let mut tr2 = vec![Fp::ZERO; n_in * bw];
        let mut chosen2 = Vec::new();
        let kept = echelon_tracked(data, bw, &mut own2, &mut tr2, &mut chosen2);
        for o in 0..n_in {
            let mut combo = Combo::new(&f.in_ids);
            if own2[o] != CHOSEN {
                let ri = rows[own2[o] as usize];
                combo.add_row(ri, Fp::ONE, &f.own, &f.tr, f.sg, &f.chosen);
            }
            for (k, &l) in chosen2.iter().enumerate() {
                let c = tr2[o * bw + k];
                if !c.is_zero() {
                    let ri = rows[l as usize];
                    combo.add_row(ri, c, &f.own, &f.tr, f.sg, &f.chosen);
                }
            }
            let id = if o < kept {
                t.nids + o as u32
            } else {
                DEPENDENT
            };
            combo.emit(t, id);
        }
        t.nids += kept as u32;
        kept
    }

    /// The kept rows `data` (`bw` per row, over `groups`, working ids from `id`) set aside
    /// as [`Carried`] rows.
    fn set_aside_rows(&mut self, f: &Front, data: &[Fp], bw: usize, groups: &[usize], id: u32) {
        for (o, row) in data.chunks_exact(bw).enumerate() {
            let mut w = Carried {
                parts: std::collections::BTreeMap::new(),
                combo: std::collections::BTreeMap::new(),
                len: 0,
            };
            let c = self.carried.len() as u32;
            let mut c0 = 0;
            for &h in groups {
                let part = &row[c0..c0 + self.sizes[h]];
                c0 += self.sizes[h];
                if part.iter().any(|x| !x.is_zero()) {
                    w.len += part.len();
                    w.parts.insert(h, part.to_vec());
                    self.carried_on[h].push(c);
                }
            }
            if f.tracking {
                w.combo.insert(id + o as u32, Fp::ONE);
            }
            self.carried_len += w.entries();
            self.carried.push(Some(w));
        }
    }

    /// The pivot rows of the front, over the group's columns and the others they touch:
    /// they reduce the rows set aside that reach the group, and become its record.
    fn keep_pivot_rows<E>(&mut self, f: Front, charge: Charge<'_, E>) -> Result<(), E> {
        let (g, sg, r) = (f.g, f.sg, f.r);
        let (rec_others, rec_width, rows) = self.pivot_rows(&f);
        let Front {
            data,
            others,
            masks,
            in_ids,
            own,
            tr,
            chosen,
            pivots,
            free,
            touching,
            rescore_mark,
            tracking,
            ..
        } = f;
        self.scratch.front = data;
        // What the record keeps: the columns after the pivots' (`row[..sg]` is read only
        // by `meet` below, through `rows`).
        let kept_width = free.len() + rec_width - sg;
        let keep = self.keep;
        let mut kept = Vec::with_capacity(if keep { r * kept_width } else { 0 });
        for i in 0..if keep { r } else { 0 } {
            let row = &rows[i * rec_width..(i + 1) * rec_width];
            kept.extend(free.iter().map(|&q| row[q]));
            kept.extend_from_slice(&row[sg..]);
        }
        let extra = if touching.is_empty() {
            Vec::new()
        } else {
            let front_rows = PivotRows {
                g,
                pivots: &pivots,
                free: &free,
                others: &rec_others,
                rows: &rows,
                width: rec_width,
                tr: tracking.then_some((&tr[..], &chosen[..], &in_ids[..])),
            };
            self.meet_carried(&touching, &front_rows, charge)?
        };
        self.stats.factor_entries += rows.len();
        self.record_bytes = self.record_bytes.saturating_add(
            ((rows.len()
                + pivots.len()
                + free.len()
                + rec_others.len()
                + extra.iter().map(|e| 2 * e.1.len() + 1).sum::<usize>()) as u64)
                .saturating_mul(FP_BYTES),
        );
        self.rescore(&others, rescore_mark);
        self.scratch.rows = rows;
        if keep {
            let mut cols = Vec::with_capacity(pivots.len() + free.len() + rec_others.len());
            cols.extend(
                pivots
                    .iter()
                    .chain(&free)
                    .chain(&rec_others)
                    .map(|&c| c as u32),
            );
            self.records.push(Record {
                group: g as u32,
                width: kept_width as u32,
                npiv: pivots.len() as u32,
                nfree: free.len() as u32,
                cols: cols.into_boxed_slice(),
                rows: kept.into_boxed_slice(),
                extra: extra.into_boxed_slice(),
            });
        }
        let sc = &mut self.scratch;
        (sc.others, sc.masks) = (others, masks);
        (sc.in_ids, sc.own, sc.tr, sc.chosen) = (in_ids, own, tr, chosen);
        Ok(())
    }

    /// The front's pivot rows over the group's columns and the other groups they touch:
    /// those groups, the rows' width and the rows (row-major).
    fn pivot_rows(&mut self, f: &Front) -> (Vec<usize>, usize, Vec<Fp>) {
        let (sg, r, words, masks) = (f.sg, f.r, f.words, &f.masks);
        let mut used = vec![0u64; words];
        for i in 0..r {
            for w in 0..words {
                used[w] |= masks[i * words + w];
            }
        }
        let rec_others: Vec<usize> = (0..f.others.len())
            .filter(|&k| used[k / 64] >> (k % 64) & 1 == 1)
            .map(|k| f.others[k])
            .collect();
        let rec_width = sg + rec_others.iter().map(|&h| self.sizes[h]).sum::<usize>();
        let mut rows = std::mem::take(&mut self.scratch.rows);
        rows.clear();
        rows.reserve(r * rec_width);
        for i in 0..r {
            let row = &f.data[i * f.width..(i + 1) * f.width];
            rows.extend_from_slice(&row[..sg]);
            for &h in &rec_others {
                rows.extend_from_slice(&row[self.pos[h]..self.pos[h] + self.sizes[h]]);
            }
        }
        (rec_others, rec_width, rows)
    }

    /// New scores for the front's neighbours marked with `mark` not yet eliminated.
    fn rescore(&mut self, others: &[usize], mark: usize) {
        for &h in others {
            if !self.done[h] && self.stamp_rescore[h] == mark {
                let s = self.pool.score(h, &mut self.stamp, &mut self.clock);
                self.queue.set(h, (self.tier[h], s.0, s.1));
            }
        }
    }

    /// The rows set aside that reach the group met by its pivot rows ([`CarriedSet::meet`]);
    /// returns the extra rows of its record.
    fn meet_carried<E>(
        &mut self,
        touching: &[u32],
        front_rows: &PivotRows<'_>,
        charge: Charge<'_, E>,
    ) -> Result<Vec<(usize, super::matrix::SparseRow)>, E> {
        let mut set = CarriedSet {
            carried: &mut self.carried,
            carried_on: &mut self.carried_on,
            carried_len: &mut self.carried_len,
            sizes: self.sizes,
            offsets: self.offsets,
        };
        let (extra, dependent, work) = set.meet(touching, front_rows, self.trace.as_mut());
        charge(work, 0)?;
        self.rank += extra.len();
        self.stats.dependent_rows += dependent;
        self.stats.factor_entries += extra.iter().map(|e| e.1.len() + 1).sum::<usize>();
        Ok(extra)
    }
}

impl Front {
    /// Eliminate the group's columns: reduced echelon on them among the pivot rows.
    fn eliminate_pivots(&mut self) {
        let (sg, width, nrows) = (self.sg, self.width, self.nrows);
        let front = &mut self.data;
        let tr = &mut self.tr;
        let mut r = 0;
        for c in 0..sg {
            let Some(p) = (r..nrows).find(|&i| !front[i * width + c].is_zero()) else {
                self.free.push(c);
                continue;
            };
            // Keep the row order otherwise (narrow rows stay first).
            front[r * width..(p + 1) * width].rotate_right(width);
            let inv = front[r * width + c].inv();
            scale(&mut front[r * width + c..(r + 1) * width], inv);
            if self.tracking {
                tr[r * sg..(p + 1) * sg].rotate_right(sg);
                self.own[r..=p].rotate_right(1);
                tr[r * sg + self.chosen.len()] = Fp::ONE;
                self.chosen.push(self.own[r]);
                self.own[r] = CHOSEN;
                scale(&mut tr[r * sg..(r + 1) * sg], inv);
            }
            for i in 0..nrows {
                if i == r {
                    continue;
                }
                let f = front[i * width + c];
                if !f.is_zero() {
                    let (dst, src) = two_rows(front, width, i, r);
                    axpy_sub(&mut dst[c..], f, &src[c..]);
                    // Rows above are pivot rows: their combinations are needed only to
                    // reduce the rows set aside that reach this group.
                    if self.tracking && (i > r || !self.touching.is_empty()) {
                        let (dst, src) = two_rows(tr, sg, i, r);
                        axpy_sub(dst, f, src);
                    }
                }
            }
            self.pivots.push(c);
            r += 1;
        }
        self.r = r;
    }

    /// Which of the others' groups each row touches.
    fn row_masks(&mut self, sizes: &[usize], pos: &[usize]) {
        let words = self.others.len().div_ceil(64);
        let mut masks = std::mem::take(&mut self.masks);
        masks.clear();
        masks.resize(self.nrows * words, 0);
        for i in 0..self.nrows {
            let row = &self.data[i * self.width..(i + 1) * self.width];
            for (k, &h) in self.others.iter().enumerate() {
                if row[pos[h]..pos[h] + sizes[h]].iter().any(|x| !x.is_zero()) {
                    masks[i * words + k / 64] |= 1 << (k % 64);
                }
            }
        }
        (self.words, self.masks) = (words, masks);
    }
}

/// The blocks' rows copied into the front (`width` per row), each group's columns at its
/// front column `pos`.
fn scatter_rows(front: &mut [Fp], width: usize, members: &[Blk], sizes: &[usize], pos: &[usize]) {
    let mut r0 = 0;
    for b in members {
        let bw = b.width();
        for i in 0..b.nrows {
            let src = &b.data[i * bw..(i + 1) * bw];
            let dst = &mut front[(r0 + i) * width..(r0 + i + 1) * width];
            let mut c0 = 0;
            for &h in &b.groups {
                let s = sizes[h];
                dst[pos[h]..pos[h] + s].copy_from_slice(&src[c0..c0 + s]);
                c0 += s;
            }
        }
        r0 += b.nrows;
    }
}
