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
        mut trace: Option<Trace>,
        keep: bool,
        charge: &mut dyn FnMut(u64, u64) -> Result<(), E>,
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
        let mut pool = Pool::new(&sizes, blocks.len() * 2);
        for b in blocks {
            pool.add(b);
        }
        // Bytes of the records kept so far.
        let mut record_bytes = 0u64;
        // Scratch: a stamp per group (dedup) and the front column of each group.
        let mut stamp = vec![0usize; n];
        let mut clock = 0usize;
        let mut pos = vec![0usize; n];
        let mut stamp_rescore = vec![0usize; n];
        let mut queue = GroupQueue::new(n);
        for (g, &tg) in tier.iter().enumerate().take(n) {
            let s = pool.score(g, &mut stamp, &mut clock);
            queue.set(g, (tg, s.0, s.1));
        }
        let mut done = vec![false; n];
        let mut records = Vec::with_capacity(if keep { n } else { 0 });
        let mut rank = 0;
        let mut stats = FactorStats {
            input_entries,
            ..FactorStats::default()
        };
        // Rows set aside ([`Carried`]; only in the block triangular order found here: a
        // caller's tiers say nothing about square diagonal blocks), the ids of those touching
        // each group (stale ids skipped), and their entries in all.
        let set_aside = given_tiers.is_none() && set_aside_enabled();
        let mut carried: Vec<Option<Carried>> = Vec::new();
        let mut carried_on: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut carried_len = 0usize;
        // Scratch vectors of one front, kept from front to front (a dozen allocations per
        // front were a tenth of the elimination at 10^6 bodies).
        let mut sc_others: Vec<usize> = Vec::new();
        let mut sc_front: Vec<Fp> = Vec::new();
        let mut sc_masks: Vec<u64> = Vec::new();
        let mut sc_order: Vec<usize> = Vec::new();
        let mut sc_in: Vec<u32> = Vec::new();
        let mut sc_own: Vec<u32> = Vec::new();
        let mut sc_tr: Vec<Fp> = Vec::new();
        let mut sc_chosen: Vec<u32> = Vec::new();
        let mut sc_rows: Vec<Fp> = Vec::new();
        while let Some(g) = queue.pop() {
            done[g] = true;
            let mut members = pool.take(g);
            let mut touching = std::mem::take(&mut carried_on[g]);
            touching.sort_unstable();
            touching.dedup();
            touching.retain(|&c| {
                carried[c as usize]
                    .as_ref()
                    .is_some_and(|w| w.parts.contains_key(&g))
            });
            // Neighbours to rescore: those on a narrow block of this front (a group reached
            // only through a wide block keeps its score, a heuristic that keeps long
            // carried rows from costing a pass over all their groups at every step).
            clock += 1;
            let rescore_mark = clock;
            for b in &members {
                if b.groups.len() <= WIDE_BLOCK {
                    for &h in &b.groups {
                        stamp_rescore[h] = rescore_mark;
                    }
                }
            }
            // Narrow blocks first: their rows are preferred as pivots, so that the rows
            // left over (and the pivot rows kept) stay narrow.
            members.sort_by_key(Blk::width);
            clock += 1;
            stamp[g] = clock;
            let mut others = std::mem::take(&mut sc_others);
            others.clear();
            for b in &members {
                for &h in &b.groups {
                    if stamp[h] != clock {
                        stamp[h] = clock;
                        others.push(h);
                    }
                }
            }
            others.sort_unstable();
            let sg = sizes[g];
            pos[g] = 0;
            let mut width = sg;
            for &h in &others {
                pos[h] = width;
                width += sizes[h];
            }
            let nrows: usize = members.iter().map(|b| b.nrows).sum();
            // The real cost of this front: the pivot loop passes over every row for each of
            // the group's columns (`sg` passes of nrows × width at most), and the memory
            // held while it is built (the blocks still live, the members and the front).
            let front_len = (nrows as u64).saturating_mul(width as u64);
            let member_bytes: u64 = members.iter().map(Blk::bytes).sum();
            charge(
                front_len.saturating_mul(sg as u64 + 1),
                pool.bytes
                    .saturating_add(member_bytes)
                    .saturating_add(record_bytes)
                    .saturating_add(trace.as_ref().map_or(0, Trace::bytes))
                    .saturating_add((carried_len as u64).saturating_mul(FP_BYTES))
                    .saturating_add(front_len.saturating_mul(FP_BYTES)),
            )?;
            let mut front = std::mem::take(&mut sc_front);
            front.clear();
            front.resize(nrows * width, Fp::ZERO);
            // Tracking: each front row's input position (`own`, until it is chosen as a
            // pivot) and its coefficients on the rows chosen so far (`tr`, `sg` per row).
            let tracking = trace.is_some();
            let mut in_ids = std::mem::take(&mut sc_in);
            let mut own = std::mem::take(&mut sc_own);
            let mut tr = std::mem::take(&mut sc_tr);
            let mut chosen = std::mem::take(&mut sc_chosen);
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
            let mut r0 = 0;
            for b in &members {
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
            drop(members);
            stats.max_front = (stats.max_front.0.max(nrows), stats.max_front.1.max(width));
            // Eliminate the group's columns: reduced echelon on them among the pivot rows.
            let mut pivots = Vec::new();
            let mut free = Vec::new();
            let mut r = 0;
            for c in 0..sg {
                let Some(p) = (r..nrows).find(|&i| !front[i * width + c].is_zero()) else {
                    free.push(c);
                    continue;
                };
                // Keep the row order otherwise (narrow rows stay first).
                front[r * width..(p + 1) * width].rotate_right(width);
                let inv = front[r * width + c].inv();
                scale(&mut front[r * width + c..(r + 1) * width], inv);
                if tracking {
                    tr[r * sg..(p + 1) * sg].rotate_right(sg);
                    own[r..=p].rotate_right(1);
                    tr[r * sg + chosen.len()] = Fp::ONE;
                    chosen.push(own[r]);
                    own[r] = CHOSEN;
                    scale(&mut tr[r * sg..(r + 1) * sg], inv);
                }
                for i in 0..nrows {
                    if i == r {
                        continue;
                    }
                    let f = front[i * width + c];
                    if !f.is_zero() {
                        let (dst, src) = two_rows(&mut front, width, i, r);
                        axpy_sub(&mut dst[c..], f, &src[c..]);
                        // Rows above are pivot rows: their combinations are needed only
                        // to reduce the rows set aside that reach this group.
                        if tracking && (i > r || !touching.is_empty()) {
                            let (dst, src) = two_rows(&mut tr, sg, i, r);
                            axpy_sub(dst, f, src);
                        }
                    }
                }
                pivots.push(c);
                r += 1;
            }
            rank += r;
            // Which of the others' groups each row touches.
            let words = others.len().div_ceil(64);
            let mut masks = std::mem::take(&mut sc_masks);
            masks.clear();
            masks.resize(nrows * words, 0);
            for i in 0..nrows {
                let row = &front[i * width..(i + 1) * width];
                for (k, &h) in others.iter().enumerate() {
                    if row[pos[h]..pos[h] + sizes[h]].iter().any(|x| !x.is_zero()) {
                        masks[i * words + k / 64] |= 1 << (k % 64);
                    }
                }
            }
            // The rest: rows r.. split by the groups they touch, each part compressed.
            if r < nrows {
                let mut order = std::mem::take(&mut sc_order);
                order.clear();
                order.extend(r..nrows);
                order.sort_by(|&a, &b| {
                    masks[a * words..(a + 1) * words].cmp(&masks[b * words..(b + 1) * words])
                });
                let mut i = 0;
                while i < order.len() {
                    let key = &masks[order[i] * words..(order[i] + 1) * words];
                    let mut j = i;
                    while j < order.len() && masks[order[j] * words..(order[j] + 1) * words] == *key
                    {
                        j += 1;
                    }
                    let groups: Vec<usize> = (0..others.len())
                        .filter(|&k| key[k / 64] >> (k % 64) & 1 == 1)
                        .map(|k| others[k])
                        .collect();
                    let bw: usize = groups.iter().map(|&h| sizes[h]).sum();
                    let n_in = j - i;
                    if bw == 0 {
                        stats.dependent_rows += n_in;
                        if let Some(t) = trace.as_mut() {
                            for &ri in &order[i..j] {
                                let mut combo = Combo::new(&in_ids);
                                combo.add_row(ri, Fp::ONE, &own, &tr, sg, &chosen);
                                combo.emit(t, DEPENDENT);
                            }
                        }
                        i = j;
                        continue;
                    }
                    let mut data = Vec::with_capacity(n_in * bw);
                    for &ri in &order[i..j] {
                        let row = &front[ri * width..(ri + 1) * width];
                        for &h in &groups {
                            data.extend_from_slice(&row[pos[h]..pos[h] + sizes[h]]);
                        }
                    }
                    let kept = if n_in > bw {
                        charge(
                            (n_in as u64).saturating_mul(bw as u64).saturating_mul(
                                bw as u64 + if tracking { sg as u64 + 2 } else { 0 },
                            ),
                            0,
                        )?;
                        if let Some(t) = trace.as_mut() {
                            // The compression tracked as the front: each output row is a
                            // combination of the group's rows, each of those one of the
                            // front's rows.
                            let mut own2: Vec<u32> = (0..n_in as u32).collect();
                            let mut tr2 = vec![Fp::ZERO; n_in * bw];
                            let mut chosen2 = Vec::new();
                            let kept =
                                echelon_tracked(&mut data, bw, &mut own2, &mut tr2, &mut chosen2);
                            for o in 0..n_in {
                                let mut combo = Combo::new(&in_ids);
                                if own2[o] != CHOSEN {
                                    let ri = order[i + own2[o] as usize];
                                    combo.add_row(ri, Fp::ONE, &own, &tr, sg, &chosen);
                                }
                                for (k, &l) in chosen2.iter().enumerate() {
                                    let c = tr2[o * bw + k];
                                    if !c.is_zero() {
                                        let ri = order[i + l as usize];
                                        combo.add_row(ri, c, &own, &tr, sg, &chosen);
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
                        } else {
                            echelon(&mut data, bw)
                        }
                    } else {
                        if let Some(t) = trace.as_mut() {
                            for (o, &ri) in order[i..j].iter().enumerate() {
                                let mut combo = Combo::new(&in_ids);
                                combo.add_row(ri, Fp::ONE, &own, &tr, sg, &chosen);
                                combo.emit(t, t.nids + o as u32);
                            }
                            t.nids += n_in as u32;
                        }
                        n_in
                    };
                    stats.dependent_rows += n_in - kept;
                    data.truncate(kept * bw);
                    let id = trace.as_ref().map_or(0, |t| t.nids - kept as u32);
                    if kept > 0 && set_aside && groups.iter().all(|&h| tier[h] > tier[g]) {
                        // Left over by a square tier (the rows on its groups are all
                        // eliminated): set aside rather than carried through the fronts.
                        for o in 0..kept {
                            let row = &data[o * bw..(o + 1) * bw];
                            let mut w = Carried {
                                parts: std::collections::BTreeMap::new(),
                                combo: std::collections::BTreeMap::new(),
                                len: 0,
                            };
                            let c = carried.len() as u32;
                            let mut c0 = 0;
                            for &h in &groups {
                                let part = &row[c0..c0 + sizes[h]];
                                c0 += sizes[h];
                                if part.iter().any(|x| !x.is_zero()) {
                                    w.len += part.len();
                                    w.parts.insert(h, part.to_vec());
                                    carried_on[h].push(c);
                                }
                            }
                            if tracking {
                                w.combo.insert(id + o as u32, Fp::ONE);
                            }
                            carried_len += w.entries();
                            carried.push(Some(w));
                        }
                    } else if kept > 0 {
                        if groups.len() <= WIDE_BLOCK {
                            for &h in &groups {
                                stamp_rescore[h] = rescore_mark;
                            }
                        }
                        pool.add(Blk {
                            groups,
                            nrows: kept,
                            data,
                            id,
                        });
                    }
                    i = j;
                }
                sc_order = order;
            }
            // The pivot rows, over the group's columns and the others they touch.
            let mut used = vec![0u64; words];
            for i in 0..r {
                for w in 0..words {
                    used[w] |= masks[i * words + w];
                }
            }
            let rec_others: Vec<usize> = (0..others.len())
                .filter(|&k| used[k / 64] >> (k % 64) & 1 == 1)
                .map(|k| others[k])
                .collect();
            let rec_width = sg + rec_others.iter().map(|&h| sizes[h]).sum::<usize>();
            let mut rows = std::mem::take(&mut sc_rows);
            rows.clear();
            rows.reserve(r * rec_width);
            for i in 0..r {
                let row = &front[i * width..(i + 1) * width];
                rows.extend_from_slice(&row[..sg]);
                for &h in &rec_others {
                    rows.extend_from_slice(&row[pos[h]..pos[h] + sizes[h]]);
                }
            }
            sc_front = front;
            // What the record keeps: the columns after the pivots' (`row[..sg]` is read only
            // by `meet` below, through `rows`).
            let kept_width = free.len() + rec_width - sg;
            let mut kept = Vec::with_capacity(if keep { r * kept_width } else { 0 });
            for i in 0..if keep { r } else { 0 } {
                let row = &rows[i * rec_width..(i + 1) * rec_width];
                kept.extend(free.iter().map(|&q| row[q]));
                kept.extend_from_slice(&row[sg..]);
            }
            let extra = if touching.is_empty() {
                Vec::new()
            } else {
                let mut set = CarriedSet {
                    carried: &mut carried,
                    carried_on: &mut carried_on,
                    carried_len: &mut carried_len,
                    sizes: &sizes,
                    offsets: &offsets,
                };
                let front_rows = PivotRows {
                    g,
                    pivots: &pivots,
                    free: &free,
                    others: &rec_others,
                    rows: &rows,
                    width: rec_width,
                    tr: tracking.then_some((&tr[..], &chosen[..], &in_ids[..])),
                };
                let (extra, dependent, work) = set.meet(&touching, &front_rows, trace.as_mut());
                charge(work, 0)?;
                rank += extra.len();
                stats.dependent_rows += dependent;
                stats.factor_entries += extra.iter().map(|e| e.1.len() + 1).sum::<usize>();
                extra
            };
            stats.factor_entries += rows.len();
            record_bytes = record_bytes.saturating_add(
                ((rows.len()
                    + pivots.len()
                    + free.len()
                    + rec_others.len()
                    + extra.iter().map(|e| 2 * e.1.len() + 1).sum::<usize>())
                    as u64)
                    .saturating_mul(FP_BYTES),
            );
            for &h in &others {
                if !done[h] && stamp_rescore[h] == rescore_mark {
                    let s = pool.score(h, &mut stamp, &mut clock);
                    queue.set(h, (tier[h], s.0, s.1));
                }
            }
            sc_rows = rows;
            if keep {
                let mut cols = Vec::with_capacity(pivots.len() + free.len() + rec_others.len());
                cols.extend(
                    pivots
                        .iter()
                        .chain(&free)
                        .chain(&rec_others)
                        .map(|&c| c as u32),
                );
                records.push(Record {
                    group: g as u32,
                    width: kept_width as u32,
                    npiv: pivots.len() as u32,
                    nfree: free.len() as u32,
                    cols: cols.into_boxed_slice(),
                    rows: kept.into_boxed_slice(),
                    extra: extra.into_boxed_slice(),
                });
            }
            (sc_others, sc_masks) = (others, masks);
            (sc_in, sc_own, sc_tr, sc_chosen) = (in_ids, own, tr, chosen);
        }
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
