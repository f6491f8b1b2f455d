//! The exact analysis of one large part at a random realization: its rank, locked DOF, rigid
//! clusters and self-stress support over GF(2^61 − 1).

use super::clusters::{Local, merge_across_joints};
use super::jacobian::{BodyIndex, Incidence, Pair, Part};
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::exact::Fp;
use crate::exact::sparse::Limits;
use crate::motion::JointModel;
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// Parts with more unknowns than this are analysed exactly when the realization is random
/// ([`ExactPart`]); smaller ones by the floating-point elimination and dense motions.
pub(super) const EXACT_PART_COLUMNS: usize = 1800;

/// The rank of `d` with the columns of some more matrices beside it (over GF(p)).
pub(super) fn rank_with(d: DMatrix<Fp>, more: [Option<&DMatrix<Fp>>; 2]) -> usize {
    let extra: usize = more.iter().flatten().map(|m| m.ncols()).sum();
    if extra == 0 {
        return crate::exact::dense::rank(&d);
    }
    let (b, k) = d.shape();
    let mut a = d.resize_horizontally(k + extra, Fp::ZERO);
    let mut c = k;
    for m in more.into_iter().flatten() {
        a.view_mut((0, c), (b, m.ncols())).copy_from(m);
        c += m.ncols();
    }
    crate::exact::dense::rank(&a)
}

/// The exact analysis of one part at a random realization, for parts too large for dense
/// motions: the rank, the locked DOF of its joints and its rigid clusters, over GF(p), from
/// the sparse exact factorization of its rows (B columns per body, its root and the frame
/// fixed) and `B` random motions (vectors of its null space). Cost: the factorization plus
/// `B` back substitutions, then linear in the part's pairs and bodies.
///
/// Why `B` random motions are enough: every decision is about a linear map from the motions
/// to one body's (or one pair's) twists, of rank at most `B`: the rank of the relative twist
/// of a pair (used DOF of its joint), whether the twist difference of two bodies lies in the
/// span of their own isolated motions (rigid together). Such a map has the same rank on `B`
/// random vectors of its domain, except with probability at most `B / p` (p = 2^61 − 1). The
/// full null space (isolated motions included) gives the same spans as the reduced one plus
/// each body's isolated motions (what the floating-point path adds explicitly).
pub(super) struct ExactPart<'a> {
    pub(super) part: &'a Part,
    pub(super) pairs: &'a [Pair],
    pub(super) models: &'a [JointModel],
    pub(super) rows: &'a [DMatrix<Fp>],
    pub(super) iso: &'a [DMatrix<f64>],
    pub(super) incident: &'a Incidence,
    pub(super) frame: usize,
    pub(super) b: usize,
}

/// What [`ExactPart::run`] finds: the rank, the local union-find, the self-stress support.
pub(super) type ExactOutcome = (usize, Vec<usize>, Option<Vec<bool>>);

/// Each body's twists over the `k` sampled motions: `B` field elements per motion, motion
/// after motion, one body after another in the part's order (zero for a fixed body).
struct Sampled {
    sig: Vec<Fp>,
    b: usize,
    k: usize,
}

impl Sampled {
    /// The twists of `bodies` (by their unknowns' index `local`, none when fixed) over the
    /// `k` motions `samples`.
    fn new(
        samples: &[Vec<Fp>],
        local: &BodyIndex,
        bodies: &[usize],
        b: usize,
        k: usize,
    ) -> Sampled {
        let bk = b * k;
        let mut sig = vec![Fp::ZERO; bodies.len() * bk];
        for (li, &x) in bodies.iter().enumerate() {
            if let Some(g) = local.get(x) {
                for (j, v) in samples.iter().enumerate() {
                    sig[li * bk + j * b..li * bk + (j + 1) * b]
                        .copy_from_slice(&v[g * b..(g + 1) * b]);
                }
            }
        }
        Sampled { sig, b, k }
    }

    /// Body `li`'s twists.
    fn of(&self, li: usize) -> &[Fp] {
        let bk = self.b * self.k;
        &self.sig[li * bk..(li + 1) * bk]
    }

    /// The twists of body `x` minus those of body `y` (B × k).
    fn diff(&self, x: usize, y: usize) -> DMatrix<Fp> {
        let (sx, sy, b) = (self.of(x), self.of(y), self.b);
        DMatrix::from_fn(b, self.k, |i, j| sx[j * b + i] - sy[j * b + i])
    }
}

impl ExactPart<'_> {
    /// The rank, the part's local union-find (a parent per body of `part.bodies`, each
    /// pointing to its cluster's smallest member) and, when its rows are dependent, the flags
    /// of its pairs carrying its self-stresses (from the same factorization,
    /// [`crate::motion::exact::pairs_stress_support_from`]); locked DOF are added to
    /// `locked`.
    pub(super) fn run(
        &self,
        budget: &Budget,
        meter: &mut Meter,
        locked: &mut BTreeMap<usize, usize>,
    ) -> Result<ExactOutcome, BudgetExceeded> {
        let part = self.part;
        let nb = self.iso.len();
        let (rank, support, tw) = self.sample(budget, meter)?;
        #[cfg(test)]
        self.check_motions(&tw);
        let nl = part.bodies.len();
        let lpos = BodyIndex::new(
            nb,
            nl,
            part.bodies.iter().enumerate().map(|(li, &x)| (x, li)),
        );
        let lidx = |x: usize| lpos.get(x).unwrap_or(0);
        let eiso = self.own_isolated(meter)?;
        self.locked(&tw, &eiso, &lidx, meter, locked)?;
        let luf = self.clusters(&tw, &eiso, &lidx, meter)?;
        Ok((rank, luf, support))
    }

    /// The part's exact factorization (B columns per body, its root and the frame fixed):
    /// its rank, the support of its self-stresses when its rows are dependent, and each
    /// body's twists over `B` random motions. Over 80 lines: one factorization read three
    /// ways, its checks and charges in their order.
    #[allow(clippy::type_complexity)]
    fn sample(
        &self,
        budget: &Budget,
        meter: &mut Meter,
    ) -> Result<(usize, Option<Vec<bool>>, Sampled), BudgetExceeded> {
        let (part, pairs, b) = (self.part, self.pairs, self.b);
        let fixed = |x: usize| x == self.frame || x == part.root;
        let nb = self.iso.len();
        let ng = part.bodies.iter().filter(|&&x| !fixed(x)).count();
        let local = BodyIndex::new(
            nb,
            ng,
            part.bodies
                .iter()
                .copied()
                .filter(|&x| !fixed(x))
                .enumerate()
                .map(|(g, x)| (x, g)),
        );
        let k = b;
        let nl = part.bodies.len();
        let what = || {
            format!(
                "the geometric rigidity analysis (exact motions of one rigid block of {nl} \
                 bodies over {} unknowns)",
                ng * b
            )
        };
        // The sampled motions and each body's twists over them (k · B field elements each).
        budget.check_memory(((ng * b * k + nl * b * k) as u64).saturating_mul(8), what)?;
        meter.charge((part.pairs.len() * b * b * 8) as u64)?;
        let list: Vec<(usize, usize, usize)> = part
            .pairs
            .iter()
            .map(|&pi| (pairs[pi].joint, pairs[pi].hub, pairs[pi].other))
            .collect();
        let factor = crate::motion::exact::pairs_factor(
            b,
            ng,
            self.rows,
            list.iter().copied(),
            |x| local.get(x),
            true,
            &mut Limits {
                budget,
                meter,
                what: &what,
            },
        )?;
        let rank = factor.as_ref().map_or(0, |f| f.rank());
        let seed = part.pairs.first().copied().unwrap_or(0) as u64;
        // The self-stresses live on the pairs a random exact self-stress reaches.
        let prow: usize = list
            .iter()
            .map(|&(j, _, _)| self.models[j].rows.nrows())
            .sum();
        let support = if prow > rank {
            crate::motion::exact::pairs_stress_support_from(
                factor.as_ref(),
                self.rows,
                &list,
                |x| local.get(x),
                0x7374_7265_7373 ^ seed,
                meter,
            )?
        } else {
            None
        };
        let mut rng = crate::rng::SplitMix64::new(0x6765_6f72_6967_6964 ^ seed);
        let samples: Vec<Vec<Fp>> = match &factor {
            Some(f) => {
                meter.charge((f.stats().factor_entries as u64 + (ng * b) as u64) * k as u64)?;
                f.random_null_vectors(k, &mut rng)
            }
            None => (0..k)
                .map(|_| (0..ng * b).map(|_| Fp::random(&mut rng)).collect())
                .collect(),
        };
        drop(factor);
        Ok((
            rank,
            support,
            Sampled::new(&samples, &local, &part.bodies, b, k),
        ))
    }

    /// Every sampled motion satisfies every row of the part.
    #[cfg(test)]
    fn check_motions(&self, tw: &Sampled) {
        let (part, pairs, b, k) = (self.part, self.pairs, self.b, tw.k);
        let (sig, bk) = (&tw.sig, b * k);
        for &pi in &part.pairs {
            let p = pairs[pi];
            let (x, y) = (
                part.bodies.binary_search(&p.hub).unwrap_or(0),
                part.bodies.binary_search(&p.other).unwrap_or(0),
            );
            let r = &self.rows[p.joint];
            for j in 0..k {
                for i in 0..r.nrows() {
                    let mut s = Fp::ZERO;
                    for c in 0..b {
                        s += r[(i, c)] * (sig[y * bk + j * b + c] - sig[x * bk + j * b + c]);
                    }
                    assert!(s.is_zero(), "pair {pi} motion {j} row {i}");
                }
            }
        }
    }

    /// Each body's own isolated motions, exactly, by its index in the part (bodies the
    /// floating-point analysis found some for: the null space of its joints' rows with its
    /// neighbours fixed).
    fn own_isolated(
        &self,
        meter: &mut Meter,
    ) -> Result<BTreeMap<usize, DMatrix<Fp>>, BudgetExceeded> {
        let (part, pairs, b) = (self.part, self.pairs, self.b);
        let mut eiso: BTreeMap<usize, DMatrix<Fp>> = BTreeMap::new();
        for (li, &x) in part.bodies.iter().enumerate() {
            if self.iso[x].ncols() == 0 {
                continue;
            }
            let nrows: usize = self.incident[x]
                .iter()
                .map(|&pi| self.rows[pairs[pi].joint].nrows())
                .sum();
            meter.charge((nrows * b * b) as u64)?;
            let mut a = DMatrix::from_element(nrows, b, Fp::ZERO);
            let mut r0 = 0;
            for &pi in &self.incident[x] {
                let r = &self.rows[pairs[pi].joint];
                a.view_mut((r0, 0), (r.nrows(), b)).copy_from(r);
                r0 += r.nrows();
            }
            let n = crate::exact::dense::null_space(&a);
            if n.ncols() > 0 {
                eiso.insert(li, n);
            }
        }
        Ok(eiso)
    }

    /// Locked DOF per joint: its allowed DOF minus the rank of the relative twist, with both
    /// bodies' own isolated motions (those of a fixed body, the frame or the part's root, are
    /// not among the part's motions).
    fn locked(
        &self,
        tw: &Sampled,
        eiso: &BTreeMap<usize, DMatrix<Fp>>,
        lidx: &impl Fn(usize) -> usize,
        meter: &mut Meter,
        locked: &mut BTreeMap<usize, usize>,
    ) -> Result<(), BudgetExceeded> {
        let (part, pairs, b) = (self.part, self.pairs, self.b);
        meter.charge((part.pairs.len() as u64).saturating_mul((b * b * tw.k) as u64))?;
        for &pi in &part.pairs {
            let p = pairs[pi];
            let (h, o) = (lidx(p.hub), lidx(p.other));
            let used = rank_with(tw.diff(o, h), [eiso.get(&h), eiso.get(&o)]);
            let allowed = self.models[p.joint].twists.ncols();
            *locked.entry(p.joint).or_insert(0) += allowed.saturating_sub(used);
        }
        Ok(())
    }

    /// The part's local union-find of rigid clusters: bodies whose twist difference lies in
    /// the span of both bodies' isolated motions, for every motion.
    fn clusters(
        &self,
        tw: &Sampled,
        eiso: &BTreeMap<usize, DMatrix<Fp>>,
        lidx: &impl Fn(usize) -> usize,
        meter: &mut Meter,
    ) -> Result<Vec<usize>, BudgetExceeded> {
        let (part, pairs, b) = (self.part, self.pairs, self.b);
        let (nl, bk) = (part.bodies.len(), b * tw.k);
        let same = |x: usize, y: usize| {
            let d = tw.diff(x, y);
            let (ix, iy) = (eiso.get(&x), eiso.get(&y));
            if ix.is_none() && iy.is_none() {
                return d.iter().all(|v| v.is_zero());
            }
            rank_with(d, [ix, iy]) == rank_with(DMatrix::from_element(b, 0, Fp::ZERO), [ix, iy])
        };
        let mut cl = Local::new(
            (0..nl)
                .map(|x| eiso.get(&x).map_or(0, |m| m.ncols()))
                .collect(),
        );
        meter.charge((part.pairs.len() as u64).saturating_mul((b * b * tw.k) as u64))?;
        // Neighbours first (as the floating-point path does).
        for &pi in &part.pairs {
            let p = pairs[pi];
            cl.join_if(lidx(p.hub), lidx(p.other), &same);
        }
        // Then any two clusters whose representatives move alike: without isolated motions
        // that is equal twists, found by sorting (the floating-point path compares every two
        // representatives); a representative with isolated motions of its own is compared
        // with the representatives of the clusters that share a joint with it.
        let reps: Vec<usize> = (0..nl).filter(|&x| cl.root(x) == x).collect();
        meter.charge((reps.len() as u64).saturating_mul((bk * 20) as u64))?;
        // Each cluster by its representative's twists.
        let mut plain: Vec<(usize, usize)> = reps
            .iter()
            .map(|&r| (r, cl.rep(r)))
            .filter(|&(_, x)| !eiso.contains_key(&x))
            .collect();
        plain.sort_by(|&(_, x), &(_, y)| tw.of(x).cmp(tw.of(y)).then(x.cmp(&y)));
        for w in plain.windows(2) {
            if tw.of(w[0].1) == tw.of(w[1].1) {
                cl.join(w[0].0, w[1].0);
            }
        }
        if !eiso.is_empty() {
            merge_across_joints(part, pairs, lidx, &mut cl, same, meter)?;
        }
        let luf = (0..nl).map(|x| cl.root(x)).collect();
        Ok(luf)
    }
}
