//! One attempt of the rank check at one realization.

use super::blocks::{Pending, Signatures, block_matrix, block_shape, block_signature, width};
use super::cache::{Cache, Digest, KeyContext, matrix_digest};
use super::confirm::{confirm_seeds, unconfirmed};
use super::exact::{MAX_EXACT_UNKNOWNS, exact_rank};
use super::float::{MAX_DENSE_UNKNOWNS, REL_TOL, Svd, Tol, block_rank, cube};
use super::lowering::{body_names, describe, drop_rows};
use super::round::Round;
use super::rows::{Chunk, PAIRS_PER_CHUNK, PairRows, pair_rows, pair_rows_at};
use super::screen::sparse_full_rank;
use super::set_aside::redundant_at_configuration;
use super::unknowns::{LocalFrames, local_basis, reduced_basis};
use super::{Bases, Kept, RankResult, Redraw, Shortcut};
use crate::mechanism::{Geometry, Mechanism};
use crate::motion::GeometryUsed;
use crate::structure::count::{Decomposition, Equations, FlowRound, Part, decompose_next};
use crate::structure::{Isolated, Redundancy, Unchecked};
use nalgebra::DMatrix;

/// [`check`] at one realization: the joints in `redraw.joints` at their own seeds.
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
    let certified = shortcut == Shortcut::Certified;
    let b = m.b() as usize;
    let nb = eqs.nodes;
    // The last attempt's bases, and which pairs were built again since (their bodies' bases
    // are computed again; every other body's rows are as they were).
    let mut prev: Option<(Bases, Vec<bool>)> = None;
    let (mut rows, free) = match (redraw.rows.take(), used.seed) {
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
            prev = Some((bases, changed));
            (rows, PairRows::from_chunks(b, Vec::new()))
        }
        _ => pair_rows(m, geoms, used.seed, &redraw.joints, eqs, used.is_file()),
    };
    // Deficits are confirmed at the draws of this attempt (random geometry only).
    let confirm = redraw.confirm.filter(|_| used.seed.is_some());
    // At the file's geometry every body's unknowns are its twist about its own reference
    // point (see [`LocalFrames`]): the rank decisions no longer depend on how far the body
    // sits from the centre.
    let local = used
        .is_file()
        .then(|| LocalFrames::new(m, geoms, eqs))
        .flatten();
    let tol = match used.precision {
        Some(_) => Tol {
            rel: 1e-9,
            abs: match &local {
                Some(lf) => lf.threshold(used),
                None => crate::motion::file_threshold(m, used).unwrap_or(0.0),
            },
        },
        None => Tol {
            rel: REL_TOL,
            abs: 0.0,
        },
    };
    // At the file's configuration, constraints that are dependent there (a planar loop written
    // in space, a Bennett or Bricard linkage) are set aside first: the configuration satisfies
    // them, so they fix nothing, and the decomposition runs on what remains.
    let mut set_aside = vec![0u32; m.joints.len()];
    let configuration = if used.is_file() {
        redundant_at_configuration(
            m,
            eqs,
            &mut rows,
            &free,
            &tol,
            local.as_ref(),
            &mut set_aside,
        )
    } else {
        Vec::new()
    };
    for (e, cap) in eqs.cap.iter_mut().enumerate() {
        *cap = rows.nrows(e) as u32;
    }
    // Each pair's first row count (at most `b`, six: one byte a pair).
    let orig_rows: Vec<u8> = (0..rows.len())
        .map(|e| u8::try_from(rows.nrows(e)).expect("a pair has at most six rows"))
        .collect();
    // Digests of every pair's rows (only with a cache), and of the tolerance.
    let mut rd: Vec<u128> = match cache {
        Some(_) => crate::par::map(rows.len(), |e| matrix_digest(&rows.get(e))),
        None => Vec::new(),
    };
    let tol_words = [tol.rel.to_bits(), tol.abs.to_bits(), b as u64];

    // Pairs touching each body (compressed: `touch[start[x]..start[x + 1]]`), proper pairs
    // only (a pair of a body with itself constrains nothing). Four bytes an entry (a pair
    // number fits `u32`, as in the decomposition's lists): the pass that fills them writes at
    // random, and half the bytes are half the cache lines and pages it takes.
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
    drop(fill);
    let touching = |x: usize| &touch[start[x] as usize..start[x + 1] as usize];

    // (a) Isolated freedoms and reduced unknowns (each body on its own, in parallel).
    // The first pin pair of every element node.
    let mut pin_pair = vec![usize::MAX; eqs.elements.len()];
    for e in (0..eqs.len()).rev() {
        if eqs.is_element(eqs.hub[e]) && !eqs.input_only[e] {
            pin_pair[eqs.hub[e] - eqs.bodies] = e;
        }
    }
    let bases: Vec<Option<DMatrix<f64>>> = crate::par::map(nb, |body| {
        if body == m.frame {
            return Some(DMatrix::zeros(b, 0));
        }
        if eqs.is_element(body) {
            // The shared element moves only across its joint's constraint directions: its
            // unknowns are the row space of the joint's rows (orthonormal, so their transpose).
            // (At the file's configuration `rows` may already have lost dependent equations:
            // the joint's full rows are in `free` then.)
            let e = pin_pair[body - eqs.bodies];
            return Some(
                free.try_get(e)
                    .or(rows.try_get(e))
                    .map_or_else(|| DMatrix::zeros(b, 0), |r| r.transpose()),
            );
        }
        let mine = touching(body);
        if let Some((bases, changed)) = &prev
            && !mine.iter().any(|&e| changed[e as usize])
        {
            // Same rows, same tolerance: the last attempt's basis.
            return bases[body].clone();
        }
        let frame = local.as_ref().and_then(|lf| lf.frame[body].as_ref());
        // Isolated means undrivable: a motion across a cut of two or more constraining joints.
        // A body on one joint moves by that joint's own DOF, which an input drives.
        let mut joints = mine
            .iter()
            .map(|&e| e as usize)
            .filter(|&e| rows.nrows(e) > 0)
            .map(|e| eqs.joint[e]);
        let first = joints.next();
        if !joints.any(|j| Some(j) != first) {
            return frame.cloned();
        }
        let basis = |rows: &PairRows| match frame {
            Some(s) => Some(local_basis(
                b,
                mine.iter().map(|&e| rows.get(e as usize)),
                s,
                &tol,
            )),
            None => reduced_basis(b, mine.iter().map(|&e| rows.get(e as usize)), &tol),
        };
        let Some(c) = cache else {
            return basis(&rows);
        };
        let mut d = Digest::new(2);
        tol_words.iter().for_each(|&w| d.word(w));
        mine.iter().for_each(|&e| d.wide(rd[e as usize]));
        if let Some(s) = frame {
            d.matrix(s);
        }
        let k = d.finish();
        if let Some(hit) = c.get_basis(k) {
            return hit;
        }
        let v = basis(&rows);
        c.put_basis(k, &v);
        v
    });
    // The bases are the reduced unknowns as they are (moved into a second list of 10^6
    // entries, both were held at once).
    let q: Vec<Option<DMatrix<f64>>> = bases;
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
    // An isolated freedom at a random realization is confirmed at a second one: the body's
    // pairs drawn again (a generic nullity is the smallest over realizations).
    if let (Some(attempt), Some(seed)) = (confirm, used.seed) {
        let iso_bodies: Vec<usize> = (0..nb)
            .filter(|&x| x != m.frame && !eqs.is_element(x) && width(b, &q, x) < b)
            .collect();
        let spurious = crate::par::map(iso_bodies.len(), |i| {
            let x = iso_bodies[i];
            let mine = touching(x);
            confirm_seeds(seed, attempt).find(|&second| {
                let fresh = PairRows::from_chunks(
                    b,
                    mine.chunks(PAIRS_PER_CHUNK)
                        .map(|c| {
                            let mut chunk = Chunk::default();
                            c.iter().for_each(|&e| {
                                chunk.push_matrix(&pair_rows_at(m, eqs, e as usize, second))
                            });
                            chunk
                        })
                        .collect(),
                );
                let again = reduced_basis(b, (0..mine.len()).map(|i| fresh.get(i)), &tol);
                again.as_ref().map_or(b, |a| a.ncols()) > width(b, &q, x)
            })
        });
        let joint = &eqs.joint;
        let mut suspects: Vec<(usize, u64)> = iso_bodies
            .iter()
            .zip(spurious)
            .filter_map(|(&x, s)| s.map(|s| (x, s)))
            .flat_map(|(x, s)| touching(x).iter().map(move |&e| (joint[e as usize], s)))
            .collect();
        if !suspects.is_empty() {
            suspects.sort_unstable();
            suspects.dedup();
            // [`check`] starts over: the decomposition is never read.
            return RankResult {
                deficient: false,
                work: 0,
                decomposition: Decomposition {
                    body_part: Vec::new(),
                    eq_part: Vec::new(),
                    groups: Vec::new(),
                    eq_excess: Vec::new(),
                    body_missing: Vec::new(),
                },
                set_aside,
                isolated,
                redundant: configuration,
                unchecked: Vec::new(),
                rounds: 0,
                kept_rows: Some(Kept {
                    rows,
                    first: orig_rows,
                    bases: q,
                }),
                suspects,
            };
        }
    }
    drop(touch);
    drop(start);
    let qd: Vec<u128> = match cache {
        Some(_) => crate::par::map(nb, |x| {
            q[x].as_ref()
                .map_or(0, |a| matrix_digest(a).wrapping_add(1))
        }),
        None => Vec::new(),
    };
    // The key of a block for the cache: everything its verdict depends on (its part, bodies
    // with their unknowns, pairs with their bodies and rows, whether any pair was lowered).

    // (b)-(c) Decompose, check every block, lower, repeat.
    let mut redundant = configuration;
    let mut unchecked: Vec<Unchecked> = Vec::new();
    // Blocks already found sound, keyed by their bodies and their pairs with row counts (a
    // block's rank depends on nothing else), so a repeat pass only checks what changed.
    let mut verified = Signatures::default();
    let mut rounds = 0;
    let mut work = 0u64;
    // Joints of deficits a second realization did not confirm (see [`check`]).
    let mut suspects: Vec<(usize, u64)> = Vec::new();
    // The previous round's decomposition, and the pairs lowered since with their counts
    // then: a later round's decomposition starts from what it found.
    let mut prior: Option<FlowRound> = None;
    let mut lowerings: Vec<(usize, u32)> = Vec::new();
    loop {
        rounds += 1;
        let (dec, round) = decompose_next(m, eqs, u, prior.as_ref().map(|r| (r, &lowerings[..])));
        prior = round;
        lowerings.clear();
        // Blocks in triangular order: over-determined part, groups, under-determined part.
        let over: Vec<usize> = (0..nb)
            .filter(|&x| dec.body_part[x] == Part::Over)
            .collect();
        if certified && over.is_empty() && redundant.is_empty() {
            // The caller proved the whole system of full row rank: with no over-determined
            // part the blocks are square groups (nonsingular) and the under-determined block
            // (full row rank), in block triangular order. Nothing to factorize.
            return RankResult {
                deficient: false,
                work,
                decomposition: dec,
                set_aside,
                isolated,
                redundant,
                unchecked,
                rounds,
                suspects: Vec::new(),
                kept_rows: None,
            };
        }
        if shortcut == Shortcut::Determined
            && rounds == 1
            && (!over.is_empty() || (0..nb).any(|x| dec.body_part[x] == Part::Under))
        {
            // Not determined by count: the check only lowers equations, so it cannot become
            // determined (an over-determined block loses rows only when it hides a freedom,
            // which then shows as missing DOF).
            return RankResult {
                deficient: true,
                work,
                decomposition: dec,
                set_aside,
                isolated,
                redundant,
                unchecked,
                rounds,
                suspects: Vec::new(),
                kept_rows: None,
            };
        }
        if shortcut == Shortcut::Determined && rounds == 1 {
            // Determined by count: any deficient group makes it under-determined. The small
            // groups first (most are in the cache), before any large one is factorized.
            let mut gstart = vec![0usize; dec.groups.len() + 1];
            for e in 0..rows.len() {
                if rows.nrows(e) > 0
                    && let Part::Group(g) = dec.eq_part[e]
                    && g < dec.groups.len()
                {
                    gstart[g + 1] += 1;
                }
            }
            for g in 0..dec.groups.len() {
                gstart[g + 1] += gstart[g];
            }
            let mut gfill = gstart.clone();
            let mut geqs = vec![0usize; gstart[dec.groups.len()]];
            for e in 0..rows.len() {
                if rows.nrows(e) > 0
                    && let Part::Group(g) = dec.eq_part[e]
                    && g < dec.groups.len()
                {
                    geqs[gfill[g]] = e;
                    gfill[g] += 1;
                }
            }
            let small: Vec<(usize, u128)> = (0..dec.groups.len())
                .filter_map(|g| {
                    let block_eqs = &geqs[gstart[g]..gstart[g + 1]];
                    let bodies = &dec.groups[g].bodies;
                    if block_eqs.is_empty() {
                        return None;
                    }
                    let (nrows, ncols) = block_shape(b, block_eqs, bodies, &rows, &q);
                    if nrows.max(ncols) > MAX_DENSE_UNKNOWNS {
                        return None;
                    }
                    let key = cache.map_or(0, |_| {
                        KeyContext {
                            tol: &tol_words,
                            seed: used.seed,
                            qd: &qd,
                            rd: &rd,
                            orig_rows: &orig_rows,
                        }
                        .block(
                            Part::Group(g),
                            bodies,
                            block_eqs,
                            eqs,
                            &rows,
                        )
                    });
                    if let Some(c) = cache
                        && c.get_block(key).is_some()
                    {
                        return None;
                    }
                    Some((g, key))
                })
                .collect();
            let sound: Vec<(bool, u64)> = crate::par::map(small.len(), |i| {
                let g = small[i].0;
                let block_eqs = &geqs[gstart[g]..gstart[g + 1]];
                let bodies = &dec.groups[g].bodies;
                let (nrows, ncols) = block_shape(b, block_eqs, bodies, &rows, &q);
                let (rank, cost) = block_rank(
                    b,
                    block_eqs,
                    bodies,
                    eqs,
                    &rows,
                    &q,
                    Part::Group(g),
                    &tol,
                    (nrows, ncols),
                );
                (rank >= nrows, cost)
            });
            work = work.saturating_add(sound.iter().map(|s| s.1).sum());
            if sound.iter().any(|&(s, _)| !s) {
                // Each deficient group confirmed at a second realization first.
                let mut suspects = Vec::new();
                if let (Some(attempt), Some(seed)) = (confirm, used.seed) {
                    for (&(g, _), _) in small.iter().zip(&sound).filter(|(_, s)| !s.0) {
                        let block_eqs = &geqs[gstart[g]..gstart[g + 1]];
                        let bodies = &dec.groups[g].bodies;
                        let shape = block_shape(b, block_eqs, bodies, &rows, &q);
                        if let Some(s) = unconfirmed(
                            m,
                            eqs,
                            block_eqs,
                            bodies,
                            &rows,
                            &orig_rows,
                            shape,
                            shape.0,
                            confirm_seeds(seed, attempt),
                            &mut work,
                        ) {
                            suspects.extend(block_eqs.iter().map(|&e| (eqs.joint[e], s)));
                        }
                    }
                }
                if !suspects.is_empty() {
                    suspects.sort_unstable();
                    suspects.dedup();
                    return RankResult {
                        deficient: false,
                        work,
                        decomposition: dec,
                        set_aside,
                        isolated,
                        redundant,
                        unchecked,
                        rounds,
                        kept_rows: Some(Kept {
                            rows,
                            first: orig_rows,
                            bases: q,
                        }),
                        suspects,
                    };
                }
                return RankResult {
                    deficient: true,
                    work,
                    decomposition: dec,
                    set_aside,
                    isolated,
                    redundant,
                    unchecked,
                    rounds,
                    suspects: Vec::new(),
                    kept_rows: None,
                };
            }
            if let Some(c) = cache {
                for &(_, key) in &small {
                    c.put_block(key, None);
                }
            }
        }
        let under: Vec<usize> = (0..nb)
            .filter(|&x| dec.body_part[x] == Part::Under)
            .collect();
        let first_group = usize::from(!over.is_empty());
        let ng = dec.groups.len();
        let nblocks = first_group + ng + usize::from(!under.is_empty());
        let block_of = |part: Part| -> Option<usize> {
            match part {
                Part::Over if !over.is_empty() => Some(0),
                Part::Group(g) if g < ng => Some(first_group + g),
                Part::Under if !under.is_empty() => Some(first_group + ng),
                _ => None,
            }
        };
        // Pairs of every block in one pass (compressed by block).
        let mut bstart = vec![0usize; nblocks + 1];
        for e in 0..rows.len() {
            if rows.nrows(e) == 0 {
                continue;
            }
            if let Some(i) = block_of(dec.eq_part[e]) {
                bstart[i + 1] += 1;
            }
        }
        for i in 0..nblocks {
            bstart[i + 1] += bstart[i];
        }
        let mut bfill = bstart.clone();
        let mut beqs = vec![0usize; bstart[nblocks]];
        for e in 0..rows.len() {
            if rows.nrows(e) == 0 {
                continue;
            }
            if let Some(i) = block_of(dec.eq_part[e]) {
                beqs[bfill[i]] = e;
                bfill[i] += 1;
            }
        }
        // Blocks to check, in triangular order; already verified and oversized ones skipped.
        let mut todo: Vec<Pending> = Vec::new();
        let mut keys: Vec<Option<u128>> = Vec::new();
        for i in 0..nblocks {
            let block_eqs = &beqs[bstart[i]..bstart[i + 1]];
            if block_eqs.is_empty() {
                continue;
            }
            let (bodies, part): (&[usize], Part) = if i < first_group {
                (&over, Part::Over)
            } else if i < first_group + ng {
                (
                    &dec.groups[i - first_group].bodies,
                    Part::Group(i - first_group),
                )
            } else {
                (&under, Part::Under)
            };
            let signature = block_signature(bodies, block_eqs, &rows);
            if verified.contains(&signature) {
                continue;
            }
            let key = cache.map(|_| {
                let ctx = KeyContext {
                    tol: &tol_words,
                    seed: used.seed,
                    qd: &qd,
                    rd: &rd,
                    orig_rows: &orig_rows,
                };
                ctx.block(part, bodies, block_eqs, eqs, &rows)
            });
            if let (Some(c), Some(k)) = (cache, key)
                && let Some(hit) = c.get_block(k)
            {
                unchecked.extend(hit);
                verified.insert(signature);
                continue;
            }
            let (nrows, ncols) = block_shape(b, block_eqs, bodies, &rows, &q);
            if nrows.max(ncols) > MAX_DENSE_UNKNOWNS {
                // Too large for the dense SVD. At a random realization its rank is decided
                // exactly, by sparse elimination over GF(2^61 − 1), unless a pair of it was
                // already lowered (its exact rows would not be the ones kept).
                let needed = if part == Part::Over { ncols } else { nrows };
                let untouched = block_eqs
                    .iter()
                    .all(|&e| rows.nrows(e) == usize::from(orig_rows[e]));
                if let Some(seed) = used.seed
                    && untouched
                    && needed <= nrows.min(ncols)
                    && ncols <= MAX_EXACT_UNKNOWNS
                    && exact_rank(m, eqs, block_eqs, bodies, seed, &mut work) >= needed
                {
                    if let (Some(c), Some(k)) = (cache, key) {
                        c.put_block(k, None);
                    }
                    verified.insert(signature);
                    continue;
                }
                // At the file's geometry: a sparse elimination that proves full rank.
                if used.seed.is_none()
                    && sparse_full_rank(b, block_eqs, bodies, eqs, &rows, &q, part, &tol, true)
                        .is_some_and(|r| r >= needed)
                {
                    if let (Some(c), Some(k)) = (cache, key) {
                        c.put_block(k, None);
                    }
                    verified.insert(signature);
                    continue;
                }
                let u = Unchecked {
                    bodies: bodies.len(),
                    unknowns: ncols,
                    equations: nrows,
                };
                if let (Some(c), Some(k)) = (cache, key) {
                    c.put_block(k, Some(u.clone()));
                }
                unchecked.push(u);
                verified.insert(signature);
                continue;
            }
            keys.push(key);
            todo.push((block_eqs, bodies, part, signature, (nrows, ncols)));
        }
        // Ranks of all of them in parallel (each depends on its own rows only); the first
        // deficient one in order is then explained and lowered, as a serial pass would.
        let ranks: Vec<(usize, u64)> = crate::par::map(todo.len(), |i| {
            let (block_eqs, bodies, part, ..) = &todo[i];
            block_rank(b, block_eqs, bodies, eqs, &rows, &q, *part, &tol, todo[i].4)
        });
        work = work.saturating_add(ranks.iter().map(|r| r.1).sum());
        let ranks: Vec<usize> = ranks.into_iter().map(|r| r.0).collect();
        // Most blocks are found sound: room for all of them at once (grown by doubling, the
        // set rehashed every signature about once more, 2 % of `analyze` at 10^6 bodies).
        verified.reserve(todo.len());
        let mut changed = false;
        // Several groups can lose rows in one round (see `Round`); what a lowered group
        // reaches (its dependents, then the under-determined block) waits for the next one.
        let mut round = Round::new(
            b,
            &q,
            &rows,
            &orig_rows,
            &dec,
            first_group,
            &bstart,
            &beqs,
            &under,
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
            let sound = |verified: &mut Signatures, signature: Vec<u32>| {
                if let (Some(c), Some(k)) = (cache, key) {
                    c.put_block(k, None);
                }
                verified.insert(signature);
            };
            // The over-determined block is tall: its surplus rows are the count's business
            // unless it also hides a freedom (a column deficit); then every dependent row goes,
            // so that the count sees the freedom.
            if part == Part::Over && rank >= ncols {
                sound(&mut verified, signature);
                continue;
            }
            let deficit = nrows.saturating_sub(rank);
            if deficit == 0 {
                sound(&mut verified, signature);
                continue;
            }
            if let (Some(attempt), Some(seed)) = (confirm, used.seed) {
                let needed = if part == Part::Over { ncols } else { nrows };
                if let Some(s) = unconfirmed(
                    m,
                    eqs,
                    block_eqs,
                    bodies,
                    &rows,
                    &orig_rows,
                    (nrows, ncols),
                    needed,
                    confirm_seeds(seed, attempt),
                    &mut work,
                ) {
                    // Drawn again with the other unconfirmed deficits of this pass.
                    suspects.extend(block_eqs.iter().map(|&e| (eqs.joint[e], s)));
                    continue;
                }
            }
            let a = block_matrix(b, block_eqs, bodies, eqs, &rows, &q);
            let svd = Svd::of(&a, &tol);
            work = work.saturating_add(cube(a.nrows().max(a.ncols())));
            debug_assert_eq!(
                svd.rank(),
                rank,
                "same singular values with or without vectors"
            );
            // Weight of each pair in the left null space.
            let null: Vec<usize> = (0..svd.sv.len())
                .filter(|&i| svd.sv[i] <= svd.tol)
                .collect();
            let mut named: Vec<(usize, f64)> = Vec::new();
            let mut r0 = 0;
            for &e in block_eqs {
                let n = rows.nrows(e);
                let w: f64 = (r0..r0 + n)
                    .map(|r| null.iter().map(|&k| svd.u[(r, k)].powi(2)).sum::<f64>())
                    .sum();
                if w > 1e-6 {
                    named.push((e, w));
                }
                r0 += n;
            }
            // Lower the pair that carries most of the dependency (ties: the later pair).
            let mut order = named.clone();
            order.sort_by(|a, b| b.1.total_cmp(&a.1).then(b.0.cmp(&a.0)));
            let mut lowered = usize::MAX;
            let mut removed = 0;
            for &(e, _) in &order {
                removed = drop_rows(
                    b, e, deficit, block_eqs, bodies, eqs, &mut rows, &q, rank, &tol,
                );
                if removed > 0 {
                    lowered = e;
                    break;
                }
            }
            if removed == 0 {
                continue;
            }
            let named: Vec<usize> = named.iter().map(|&(e, _)| e).collect();
            lowerings.push((lowered, eqs.cap[lowered]));
            eqs.cap[lowered] = rows.nrows(lowered) as u32;
            if let Some(d) = rd.get_mut(lowered) {
                *d = matrix_digest(&rows.get(lowered));
            }
            changed = true;
            let mut joints: Vec<usize> = named.iter().map(|&e| eqs.joint[e]).collect();
            joints.sort_unstable();
            joints.dedup();
            redundant.push(Redundancy {
                bodies: body_names(m, eqs, bodies),
                freedom: describe(m, eqs, bodies, &joints, removed),
                joints: joints.iter().map(|&j| m.joints[j].id.clone()).collect(),
                count: removed as u32,
                lowered: m.joints[eqs.joint[lowered]].id.clone(),
                configuration: false,
            });
            // Later blocks were checked with this one assumed nonsingular: decompose again,
            // unless it was a group (then only its dependents are affected: `Round`).
            let Part::Group(g) = part else {
                break;
            };
            // The lowered group and its dependents join the under-determined block. A round
            // per lowering checked that grown block before anything else: when it is too
            // large for the dense check, do what that round's first step did.
            let Some((nrows, ncols, untouched)) = round.lower(b, g, &q, &rows, &orig_rows) else {
                continue;
            };
            let mut exact = false;
            if let Some(seed) = used.seed
                && untouched
                && nrows <= ncols
                && ncols <= MAX_EXACT_UNKNOWNS
            {
                let (block_eqs, bodies) = round.under_lists(&rows);
                let signature = block_signature(&bodies, &block_eqs, &rows);
                if verified.contains(&signature) {
                    continue;
                }
                if exact_rank(m, eqs, &block_eqs, &bodies, seed, &mut work) >= nrows {
                    verified.insert(signature);
                    exact = true;
                }
            }
            if !exact {
                unchecked.push(Unchecked {
                    bodies: round.under_bodies,
                    unknowns: ncols,
                    equations: nrows,
                });
            }
        }
        if !changed || !suspects.is_empty() {
            suspects.sort_unstable();
            suspects.dedup();
            // Only the blocks of the final decomposition matter.
            unchecked.sort_by_key(|x| (std::cmp::Reverse(x.unknowns), x.bodies, x.equations));
            unchecked.dedup();
            return RankResult {
                deficient: false,
                work,
                decomposition: dec,
                set_aside,
                isolated,
                redundant,
                unchecked,
                rounds,
                kept_rows: (!suspects.is_empty()).then_some(Kept {
                    rows,
                    first: orig_rows,
                    bases: q,
                }),
                suspects,
            };
        }
    }
}
