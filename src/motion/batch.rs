//! Many joints' constraint rows at once: the Gram-Schmidt steps of [`super::stack_model`] run
//! for [`LANES`] joints in lockstep ([`HALF`] for the jobs left over). Each step is one
//! dependent chain of dot products per joint (its latency, not its arithmetic, was the cost);
//! the lanes are independent chains, laid out lane-innermost so that one instruction serves
//! several joints (eight lanes are four two-wide chains at once: four left the core waiting on
//! the sums' latency more often). Every lane does
//! the same operations in the same order as the one-joint code, so the rows are bit for bit
//! those of [`super::pair_stack_model`] (tested against it); a
//! lane that leaves the common path (a vector dropped, a non-finite value) is computed again
//! by the one-joint code.

use super::gram::{CANDIDATE_GAP, MAX_B, Vb, Vecs, complement_of, norm, orthonormal, project_unit};
use super::model::{fallback_model, kept_twists, mix_seed, stack_model_in};
use super::modelled;
use super::twists::{TwistSpec, twist_spec};
use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism, Space};
use crate::rng::indexed_seed;
use std::borrow::Borrow;

/// Joints per lockstep step where enough jobs share a length.
const LANES: usize = 8;

/// Joints per lockstep step for the jobs left over from groups of [`LANES`].
const HALF: usize = 4;

/// One coordinate of `L` vectors.
type Lane<const L: usize> = [f64; L];

/// `L` vectors of the motion space, coordinate by coordinate (`v[x][lane]`).
type Wide<const L: usize> = [Lane<L>; MAX_B];

/// `L` zero vectors.
const fn wide_zero<const L: usize>() -> Wide<L> {
    [[0.0; L]; MAX_B]
}

#[cfg(test)]
thread_local! {
    /// Gram-Schmidt runs (orthonormal bases and complements) done in lanes, and done one
    /// joint at a time, on this thread (the tests' measure of how much runs in lanes).
    pub(super) static RUNS: std::cell::Cell<[usize; 2]> = const { std::cell::Cell::new([0; 2]) };
}

#[cfg(test)]
thread_local! {
    /// Lockstep steps of [`LANES`] joints on this thread.
    pub(super) static WIDE_STEPS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

#[cfg(test)]
fn count(in_lanes: usize, single: usize) {
    RUNS.with(|c| {
        let [a, b] = c.get();
        c.set([a + in_lanes, b + single]);
    });
    if in_lanes == LANES {
        WIDE_STEPS.with(|c| c.set(c.get() + 1));
    }
}

#[cfg(not(test))]
fn count(_: usize, _: usize) {}

fn wide_dot<const N: usize, const L: usize>(a: &Wide<L>, b: &Wide<L>) -> Lane<L> {
    // The sum of each lane in index order from 0, as [`dot`].
    let mut r = [0.0; L];
    for (x, y) in a.iter().zip(b).take(N) {
        for l in 0..L {
            r[l] += x[l] * y[l];
        }
    }
    r
}

/// `v -= q d` lane by lane (as the loops of [`super::project_out`]).
fn wide_sub<const N: usize, const L: usize>(v: &mut Wide<L>, q: &Wide<L>, d: &Lane<L>) {
    for (x, y) in v.iter_mut().zip(q).take(N) {
        for l in 0..L {
            x[l] -= y[l] * d[l];
        }
    }
}

/// [`super::project_out`] in lanes.
fn wide_project_out<const N: usize, const L: usize>(v: &mut Wide<L>, basis: &[Wide<L>]) {
    for _ in 0..2 {
        for q in basis {
            let d = wide_dot::<N, L>(q, v);
            wide_sub::<N, L>(v, q, &d);
        }
    }
}

fn wide_sqrt<const L: usize>(a: Lane<L>) -> Lane<L> {
    a.map(f64::sqrt)
}

/// The vectors of lane `l` (the coordinates past `N` zero, as [`super::normalized`] leaves
/// them).
fn lane_of<const N: usize, const L: usize>(vs: &[Wide<L>], l: usize) -> Vecs {
    let mut out = Vecs::EMPTY;
    for w in vs {
        let mut v = [0.0; MAX_B];
        for (o, x) in v.iter_mut().zip(w).take(N) {
            *o = x[l];
        }
        out.push(v);
    }
    out
}

/// Lane vectors from one list of vectors per lane (all of the same length `k`).
fn widen<const L: usize>(lists: [&[Vb]; L], out: &mut [Wide<L>; MAX_B]) -> usize {
    let k = lists[0].len();
    for (i, w) in out.iter_mut().enumerate().take(k) {
        for (x, coord) in w.iter_mut().enumerate() {
            for l in 0..L {
                coord[l] = lists[l][i][x];
            }
        }
    }
    k
}

/// [`orthonormal`] of the `k` lane vectors `cols` into `out`: per lane, whether it kept every
/// vector (a lane that drops one has a shorter basis than the others: not this result).
fn orthonormal_wide<const N: usize, const L: usize>(
    cols: &[Wide<L>; MAX_B],
    k: usize,
    out: &mut [Wide<L>; MAX_B],
) -> [bool; L] {
    let mut sq = [0.0; L];
    for c in &cols[..k] {
        let d = wide_dot::<N, L>(c, c);
        for l in 0..L {
            sq[l] += d[l];
        }
    }
    let scale = wide_sqrt(sq).map(|s| s.max(1e-300));
    let mut kept = [true; L];
    for i in 0..k {
        let mut v = cols[i];
        wide_project_out::<N, L>(&mut v, &out[..i]);
        let n = wide_sqrt(wide_dot::<N, L>(&v, &v));
        let q = &mut out[i];
        *q = wide_zero();
        for (o, x) in q.iter_mut().zip(&v).take(N) {
            for l in 0..L {
                o[l] = x[l] / n[l];
            }
        }
        for l in 0..L {
            kept[l] &= n[l] > 1e-10 * scale[l];
        }
    }
    kept
}

/// [`complement_of`] of the lanes' orthonormal bases (`basis[..k]`, `k` at least 1), the
/// complement appended (`basis[k..N]`): per lane, whether its squared norms stayed finite
/// (else the one-joint code projects every unit vector: not this result). The first
/// candidate unit vector of every lane is projected in lockstep, the others (ties, rare at
/// generic geometry) one at a time, each exactly as [`project_unit`].
fn complement_wide<const N: usize, const L: usize>(
    basis: &mut [Wide<L>; MAX_B],
    k: usize,
) -> [bool; L] {
    let mut sq = wide_zero::<L>();
    for q in &basis[..k] {
        for (s, x) in sq.iter_mut().zip(q).take(N) {
            for l in 0..L {
                s[l] += x[l] * x[l];
            }
        }
    }
    let mut regular = [true; L];
    for n in k..N {
        // The candidates of each lane, as [`complement_of`] chooses them, without a branch
        // per unit vector (which one is first is as random as the geometry: the branches
        // were mispredicted). The candidates' bits: the lowest is the first one, the others
        // are the ties. With finite sums, the largest `1 − s` is a candidate (no set is
        // empty); otherwise all are.
        let mut top = [f64::NEG_INFINITY; L];
        let mut finite = [true; L];
        for s in sq.iter().take(N) {
            for l in 0..L {
                finite[l] &= s[l].is_finite();
                top[l] = top[l].max(1.0 - s[l]);
            }
        }
        let cut = top.map(|t| t - CANDIDATE_GAP);
        let mut set = [0u8; L];
        for (i, s) in sq.iter().enumerate().take(N) {
            for l in 0..L {
                let skip = finite[l] & (1.0 - s[l] < cut[l]);
                set[l] |= u8::from(!skip) << i;
            }
        }
        let mut first = [0usize; L];
        let mut more = [0u8; L];
        for l in 0..L {
            regular[l] &= finite[l];
            let c = set[l];
            first[l] = if c == 0 {
                0
            } else {
                c.trailing_zeros() as usize
            };
            more[l] = c & c.wrapping_sub(1);
        }
        // [`project_unit`] of each lane's first candidate (the first basis vector is finite:
        // its squares are terms of finite sums).
        let mut v = wide_zero::<L>();
        let mut d = [0.0; L];
        for l in 0..L {
            v[first[l]][l] = 1.0;
            d[l] = basis[0][first[l]][l] + 0.0;
        }
        wide_sub::<N, L>(&mut v, &basis[0], &d);
        for q in &basis[1..n] {
            let d = wide_dot::<N, L>(q, &v);
            wide_sub::<N, L>(&mut v, q, &d);
        }
        for q in &basis[..n] {
            let d = wide_dot::<N, L>(q, &v);
            wide_sub::<N, L>(&mut v, q, &d);
        }
        let mut len = wide_sqrt(wide_dot::<N, L>(&v, &v));
        // The other candidates, one lane at a time; the first largest is kept.
        for l in 0..L {
            if more[l] == 0 || !regular[l] {
                continue;
            }
            let mine = lane_of::<N, L>(&basis[..n], l);
            for i in (0..N).filter(|&i| more[l] & (1 << i) != 0) {
                let w = project_unit::<N>(i, mine.as_slice());
                let wn = norm::<N>(&w);
                if wn > len[l] {
                    len[l] = wn;
                    for (x, c) in v.iter_mut().zip(&w).take(N) {
                        x[l] = *c;
                    }
                }
            }
        }
        let q = &mut basis[n];
        *q = wide_zero();
        for (o, x) in q.iter_mut().zip(&v).take(N) {
            for l in 0..L {
                o[l] = x[l] / len[l];
            }
        }
        for (s, x) in sq.iter_mut().zip(q.iter()).take(N) {
            for l in 0..L {
                s[l] += x[l] * x[l];
            }
        }
    }
    regular
}

/// Up to [`MAX_B`] vectors per job, each job in its own slot (no vector list is moved
/// around whole: copies of them were a fifth of the time).
#[derive(Default)]
pub(crate) struct Slots {
    v: Vec<Vb>,
    n: Vec<u8>,
}

impl Slots {
    /// Room for `jobs` jobs (the memory kept: scratch reused from chunk to chunk).
    fn reserve(&mut self, jobs: usize) {
        if self.n.len() < jobs {
            self.v.resize(jobs * MAX_B, [0.0; MAX_B]);
            self.n.resize(jobs, 0);
        }
    }

    /// Job `j`'s vectors.
    pub(crate) fn get(&self, j: usize) -> &[Vb] {
        &self.v[j * MAX_B..j * MAX_B + self.n[j] as usize]
    }

    fn set(&mut self, j: usize, vs: &[Vb]) {
        let k = vs.len().min(MAX_B);
        self.v[j * MAX_B..j * MAX_B + k].copy_from_slice(&vs[..k]);
        self.n[j] = k as u8;
    }

    /// Lane `l` of `vs` as job `j`'s vectors.
    fn set_lane<const N: usize, const L: usize>(&mut self, j: usize, vs: &[Wide<L>], l: usize) {
        let slot = &mut self.v[j * MAX_B..j * MAX_B + vs.len()];
        for (o, w) in slot.iter_mut().zip(vs) {
            *o = [0.0; MAX_B];
            for (x, c) in o.iter_mut().zip(w).take(N) {
                *x = c[l];
            }
        }
        self.n[j] = vs.len() as u8;
    }
}

/// Jobs grouped for the lanes: by [`LANES`], by [`HALF`], and one by one.
struct Groups {
    wide: Vec<[usize; LANES]>,
    half: Vec<[usize; HALF]>,
    single: Vec<usize>,
}

/// The items in groups of [`LANES`] of the same `len` where `takes` that length, the rest of
/// a length in groups of [`HALF`], and what is left (fewer than [`HALF`] of a length, or of
/// a length not taken) one by one.
fn grouped(items: &[usize], len: impl Fn(usize) -> usize, takes: impl Fn(usize) -> bool) -> Groups {
    let mut by_len: [Vec<usize>; MAX_B + 1] = Default::default();
    let mut single = Vec::new();
    for &i in items {
        match by_len.get_mut(len(i)) {
            Some(v) => v.push(i),
            None => single.push(i),
        }
    }
    let mut wide = Vec::with_capacity(items.len() / LANES);
    let mut half = Vec::new();
    for (k, group) in by_len.iter().enumerate() {
        if !takes(k) {
            single.extend_from_slice(group);
            continue;
        }
        let mut it = group.chunks_exact(LANES);
        wide.extend((&mut it).map(|c| std::array::from_fn(|l| c[l])));
        let mut it = it.remainder().chunks_exact(HALF);
        half.extend((&mut it).map(|c| std::array::from_fn(|l| c[l])));
        single.extend_from_slice(it.remainder());
    }
    Groups { wide, half, single }
}

/// [`orthonormal`] of `src`'s vectors into `dst` for the jobs `items`, in lanes where it can.
fn orthonormal_many<const N: usize>(src: &Slots, dst: &mut Slots, items: &[usize]) {
    let g = grouped(items, |j| src.get(j).len(), |k| k >= 1);
    orthonormal_lanes::<N, LANES>(src, dst, &g.wide);
    orthonormal_lanes::<N, HALF>(src, dst, &g.half);
    for j in g.single {
        count(0, 1);
        dst.set(j, orthonormal::<N>(src.get(j)).as_slice());
    }
}

/// [`orthonormal_many`] of the groups of `L` jobs `groups`.
fn orthonormal_lanes<const N: usize, const L: usize>(
    src: &Slots,
    dst: &mut Slots,
    groups: &[[usize; L]],
) {
    let (mut cols, mut out) = ([wide_zero::<L>(); MAX_B], [wide_zero::<L>(); MAX_B]);
    for js in groups {
        let k = widen(js.map(|j| src.get(j)), &mut cols);
        let kept = orthonormal_wide::<N, L>(&cols, k, &mut out);
        count(L, 0);
        for (l, &j) in js.iter().enumerate() {
            if kept[l] {
                dst.set_lane::<N, L>(j, &out[..k], l);
            } else {
                dst.set(j, orthonormal::<N>(src.get(j)).as_slice());
            }
        }
    }
}

/// [`complement_of`] of `src`'s orthonormal bases into `dst` for the jobs `items`, in lanes
/// where it can.
fn complement_many<const N: usize>(src: &Slots, dst: &mut Slots, items: &[usize]) {
    let g = grouped(items, |j| src.get(j).len(), |k| (1..N).contains(&k));
    complement_lanes::<N, LANES>(src, dst, &g.wide);
    complement_lanes::<N, HALF>(src, dst, &g.half);
    for j in g.single {
        count(0, 1);
        dst.set(j, complement_of::<N>(Vecs::of(src.get(j))).as_slice());
    }
}

/// [`complement_many`] of the groups of `L` jobs `groups`.
fn complement_lanes<const N: usize, const L: usize>(
    src: &Slots,
    dst: &mut Slots,
    groups: &[[usize; L]],
) {
    let mut basis = [wide_zero::<L>(); MAX_B];
    for js in groups {
        let k = widen(js.map(|j| src.get(j)), &mut basis);
        let regular = complement_wide::<N, L>(&mut basis, k);
        count(L, 0);
        for (l, &j) in js.iter().enumerate() {
            if regular[l] {
                dst.set_lane::<N, L>(j, &basis[k..N], l);
            } else {
                dst.set(j, complement_of::<N>(Vecs::of(src.get(j))).as_slice());
            }
        }
    }
}

/// Where a model is in its construction.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Step {
    /// Its rows are built.
    Done,
    /// SPSP: the line whose annihilator is its twists.
    Line,
    /// Its full twists are built.
    Full,
}

/// A model's request and its progress.
struct Job {
    kind: JointType,
    driven: u32,
    fallback: u64,
    mix: u64,
    step: Step,
}

/// Jobs built together: enough of each length to fill the lanes, few enough that their
/// vectors stay in cache.
const BATCH: usize = 256;

/// The buffers of [`pair_rows_many`], kept by the caller from one call to the next: a
/// chunk's worth of them allocated and freed 2,500 times at 10^6 joints left the heap
/// fragmented (200 MB more at the peak).
#[derive(Default)]
pub(crate) struct Scratch {
    rows: Slots,
    work: Slots,
    basis: Slots,
    full: Slots,
    done: Slots,
    jobs: Vec<Job>,
}

/// The constraint rows of [`super::pair_stack_model`] for every `(joint, driven)` of `jobs`, in
/// order, bit for bit (job `j`'s rows are `get(j)`); `geometry` gives a joint's geometry.
pub(crate) fn pair_rows_many<'s, G: Borrow<Geometry>>(
    m: &Mechanism,
    jobs: &[(usize, u32)],
    geometry: impl Fn(usize) -> G,
    scratch: &'s mut Scratch,
) -> &'s Slots {
    let requests = |i: usize| {
        let (ji, driven) = jobs[i];
        (m.joints[ji].kind, geometry(ji), driven, indexed_seed(0, ji))
    };
    match m.space {
        Space::Spatial => rows_many::<6, G>(m.space, jobs.len(), requests, scratch),
        Space::Planar | Space::Spherical => {
            rows_many::<3, G>(m.space, jobs.len(), requests, scratch)
        }
    }
}

/// [`pair_rows_many`] on `(kind, geometry, driven, fallback seed)` requests: `request(i)` for
/// `i` in `0..total`, asked for one at a time where it is used (through an iterator chain
/// each request, with its geometry of nearly 200 bytes, was copied three times more).
pub(super) fn rows_many<const N: usize, G: Borrow<Geometry>>(
    space: Space,
    total: usize,
    request: impl Fn(usize) -> (JointType, G, u32, u64),
    scratch: &mut Scratch,
) -> &Slots {
    let Scratch {
        rows,
        work,
        basis,
        full,
        done,
        jobs,
    } = scratch;
    rows.reserve(total);
    for s in [&mut *work, &mut *basis, &mut *full, &mut *done] {
        s.reserve(BATCH);
    }
    for base in (0..total).step_by(BATCH) {
        jobs.clear();
        for i in base..total.min(base + BATCH) {
            let (kind, g, driven, fallback) = request(i);
            let g = g.borrow();
            let j = i - base;
            let step = first_step::<N>(kind, g, space, driven, fallback, j, done, work, full);
            jobs.push(Job {
                kind,
                driven,
                fallback,
                // Only a driven SPSP mixes its twists ([`kept_twists`]).
                mix: if kind == JointType::SPSP && driven > 0 {
                    mix_seed(g)
                } else {
                    0
                },
                step,
            });
        }
        let at = |f: Step, jobs: &[Job]| -> Vec<usize> {
            (0..jobs.len()).filter(|&j| jobs[j].step == f).collect()
        };
        // SPSP: its twists, the complement of its line.
        let lines = at(Step::Line, jobs);
        orthonormal_many::<N>(work, basis, &lines);
        complement_many::<N>(basis, full, &lines);
        // The basis of the full twists; with driven DOF, the twists kept.
        let built = (0..jobs.len())
            .filter(|&j| jobs[j].step != Step::Done)
            .collect::<Vec<_>>();
        orthonormal_many::<N>(full, basis, &built);
        let mut kept = Vec::new();
        let mut last = Vec::with_capacity(built.len());
        for &j in &built {
            let job = &jobs[j];
            let f = full.get(j);
            if basis.get(j).len() != f.len() {
                // Degenerate: the fallback model.
                let r = fallback_model(job.kind, space, job.driven, job.fallback).rows;
                done.set(j, r.as_slice());
            } else if job.driven == 0 {
                last.push(j);
            } else {
                if job.kind == JointType::SPSP {
                    let t = kept_twists::<N>(&Vecs::of(f), job.driven as usize, job.mix);
                    work.set(j, t.as_slice());
                } else {
                    work.set(j, f.get(job.driven as usize..).unwrap_or(&[]));
                }
                kept.push(j);
            }
        }
        orthonormal_many::<N>(work, basis, &kept);
        last.extend_from_slice(&kept);
        complement_many::<N>(basis, done, &last);
        for j in 0..jobs.len() {
            rows.set(base + j, done.get(j));
        }
    }
    rows
}

/// The first step of job `j`: its rows into `done` when no lane helps (count-only kinds,
/// errors: the one-joint code), else its twists into `full` or SPSP's line into `work`.
#[allow(clippy::too_many_arguments)]
fn first_step<const N: usize>(
    kind: JointType,
    g: &Geometry,
    space: Space,
    driven: u32,
    fallback: u64,
    j: usize,
    done: &mut Slots,
    work: &mut Slots,
    full: &mut Slots,
) -> Step {
    let fall = || fallback_model(kind, space, driven, fallback).rows;
    let one = || {
        count(0, 1);
        stack_model_in::<N>(kind, g, space, driven).map_or_else(|_| fall(), |s| s.rows)
    };
    let grade = kind.grade() as u32;
    if grade as usize > N || driven > grade || !modelled(kind, space) {
        done.set(j, one().as_slice());
        return Step::Done;
    }
    match twist_spec(kind, g, space) {
        Ok(TwistSpec::Listed(t)) => {
            full.set(j, t.as_slice());
            Step::Full
        }
        // SPSP is modelled in space only (`N` = 6).
        Ok(TwistSpec::AnnihilatorOf(line)) if N == 6 => {
            work.set(j, &[line]);
            Step::Line
        }
        Ok(TwistSpec::AnnihilatorOf(_)) => {
            done.set(j, one().as_slice());
            Step::Done
        }
        // The model's error: the fallback model, as [`super::pair_stack_model`] gives.
        Err(_) => {
            done.set(j, fall().as_slice());
            Step::Done
        }
    }
}

#[cfg(test)]
mod tests;
