//! Binary expansions of multiple joints: each multiple joint as the pairs of one spanning tree
//! of its bodies (Prüfer sequences), and the driven joints of a placement named on them.

use super::Input;
use crate::mechanism::{Joint, Mechanism};

/// The mechanism with every joint binary: a multiple joint of n bodies becomes the n − 1 pairs
/// of one spanning tree of its bodies. The first pair takes the joint's place (so the other
/// joints keep their index, and their random geometry in the rank check); the rest are
/// appended after the last joint.
pub(super) struct Expansion<'a> {
    pub(super) label: Option<String>,
    /// [`Expansion::label`] with each joint's pairs cut to [`BRIEF_PAIRS`] and a count, for
    /// the table; `None` when no joint has more.
    pub(super) brief: Option<String>,
    /// The file's mechanism itself when it has no multiple joint and no driven joint: a
    /// 10^6-body mechanism was held three times (the file's, a copy without inputs, and the
    /// expansion's copy of that).
    pub(super) mech: std::borrow::Cow<'a, Mechanism>,
    /// Original joint of each joint of `mech`.
    pub(super) origin: Vec<usize>,
}

/// Pairs of one multiple joint the brief label of an expansion lists (the table's): the rest
/// are counted. In full, a joint of n bodies gave an n-character-wide column in every line of
/// the table, whose inputs take n lines: n^2 bytes, 6.5 GB at 10^4 bodies.
pub(super) const BRIEF_PAIRS: usize = 8;

/// An expansion's label, `id: a-b, c-d; id2: ...`, from each multiple joint's id and pair
/// labels, and its brief form ([`BRIEF_PAIRS`]; `None` when it is the same).
fn labels<'x>(joints: impl Iterator<Item = (&'x str, Vec<String>)>) -> (String, Option<String>) {
    let mut full = Vec::new();
    let mut brief = Vec::new();
    let mut cut = false;
    for (id, pairs) in joints {
        full.push(format!("{id}: {}", pairs.join(", ")));
        if pairs.len() > BRIEF_PAIRS {
            cut = true;
            brief.push(format!(
                "{id}: {} (+{} more pairs)",
                pairs[..BRIEF_PAIRS].join(", "),
                pairs.len() - BRIEF_PAIRS
            ));
        } else {
            brief.push(full[full.len() - 1].clone());
        }
    }
    (full.join("; "), cut.then(|| brief.join("; ")))
}

/// `n^(n−2)`, saturating.
pub(super) fn trees(n: usize) -> u64 {
    if n < 3 {
        return 1;
    }
    let mut t: u64 = 1;
    for _ in 0..n - 2 {
        t = t.saturating_mul(n as u64);
    }
    t
}

/// The spanning tree with Prüfer sequence number `index` (base-n digits, most significant
/// first), as sorted edges `(a, b)`, `a < b`, over local vertices `0..n`. Index 0 is the star on
/// vertex 0.
fn prufer_tree(n: usize, mut index: u64) -> Vec<(usize, usize)> {
    if n < 2 {
        return Vec::new();
    }
    if n == 2 {
        return vec![(0, 1)];
    }
    let mut seq = vec![0usize; n - 2];
    for s in seq.iter_mut().rev() {
        *s = (index % n as u64) as usize;
        index /= n as u64;
    }
    let mut degree = vec![1usize; n];
    for &s in &seq {
        degree[s] += 1;
    }
    let mut edges = Vec::with_capacity(n - 1);
    // The smallest leaf at each step, in linear time: `ptr` only moves up; a vertex below it
    // that becomes a leaf is taken at once (it is then the smallest). Was a scan from 0 at
    // each step, quadratic: 40 % of `transform` on a 10^4-body shared joint.
    let mut ptr = (0..n).find(|&v| degree[v] == 1).unwrap_or(0);
    let mut leaf = ptr;
    for &s in &seq {
        edges.push((leaf.min(s), leaf.max(s)));
        degree[leaf] = 0;
        degree[s] -= 1;
        if degree[s] == 1 && s < ptr {
            leaf = s;
        } else {
            ptr += 1;
            while ptr < n && degree[ptr] != 1 {
                ptr += 1;
            }
            leaf = ptr.min(n - 1);
        }
    }
    let last: Vec<usize> = (0..n).filter(|&v| degree[v] == 1).collect();
    if let [a, b] = last[..] {
        edges.push((a, b));
    }
    edges.sort_unstable();
    edges
}

/// The binary expansions of `m`'s multiple joints, built one at a time ([`Expansions::get`]):
/// only one expansion's mechanism is held at once.
pub(super) struct Expansions<'a> {
    m: &'a Mechanism,
    /// Multiple joints, and their spanning trees.
    pub(super) multi: Vec<usize>,
    counts: Vec<u64>,
    /// Expansions to explore (at least one).
    pub(super) len: usize,
    /// Expansions there are (saturating).
    pub(super) total: u64,
}

impl<'a> Expansions<'a> {
    /// Up to `max` expansions (at least one) and how many there are.
    pub(super) fn of(m: &'a Mechanism, max: usize) -> Expansions<'a> {
        let multi: Vec<usize> = (0..m.joints.len())
            .filter(|&j| m.joints[j].bodies.len() > 2)
            .collect();
        let counts: Vec<u64> = multi
            .iter()
            .map(|&j| trees(m.joints[j].bodies.len()))
            .collect();
        let total = counts.iter().fold(1u64, |t, &c| t.saturating_mul(c));
        let len = (max.max(1) as u64).min(total) as usize;
        Expansions {
            m,
            multi,
            counts,
            len,
            total,
        }
    }

    /// The pairs of expansion `k` ([`Skeleton`]): [`Expansions::get`] without the mechanism.
    pub(super) fn skeleton(&self, k: usize) -> Skeleton<'a> {
        let m = self.m;
        let nj = m.joints.len();
        let mut ends: Vec<[usize; 2]> = m
            .joints
            .iter()
            .map(|j| [j.bodies[0], j.bodies[j.bodies.len() - 1]])
            .collect();
        let mut origin: Vec<usize> = (0..nj).collect();
        let mut multi = Vec::with_capacity(self.multi.len());
        for (&j, &d) in self.multi.iter().zip(&self.digits(k)) {
            let joint = &m.joints[j];
            let edges = prufer_tree(joint.bodies.len(), d);
            let mut pairs = Vec::with_capacity(edges.len());
            for (i, &(a, b)) in edges.iter().enumerate() {
                let e = [joint.bodies[a], joint.bodies[b]];
                if i == 0 {
                    ends[j] = e;
                    pairs.push(j);
                } else {
                    pairs.push(ends.len());
                    ends.push(e);
                    origin.push(j);
                }
            }
            multi.push((j, pairs));
        }
        Skeleton {
            m,
            ends,
            origin,
            multi,
        }
    }

    /// The tree of each multiple joint in expansion `k` (mixed radix, the last varying
    /// fastest).
    fn digits(&self, k: usize) -> Vec<u64> {
        let mut rest = k as u64;
        let mut digits = vec![0u64; self.multi.len()];
        for (d, &c) in digits.iter_mut().zip(&self.counts).rev() {
            *d = rest % c.max(1);
            rest /= c.max(1);
        }
        digits
    }

    /// Expansion `k` (mixed radix over the multiple joints' trees, the last varying fastest).
    pub(super) fn get(&self, k: usize) -> Expansion<'a> {
        let m = self.m;
        if self.multi.is_empty() && m.joints.iter().all(|j| j.driven == 0) {
            return Expansion {
                label: None,
                brief: None,
                mech: std::borrow::Cow::Borrowed(m),
                origin: (0..m.joints.len()).collect(),
            };
        }
        // `m` with no joint driven.
        let mut mech = m.clone();
        for j in &mut mech.joints {
            j.driven = 0;
        }
        if self.multi.is_empty() {
            return Expansion {
                label: None,
                brief: None,
                mech: std::borrow::Cow::Owned(mech),
                origin: (0..m.joints.len()).collect(),
            };
        }
        let digits = self.digits(k);
        let mut origin: Vec<usize> = (0..m.joints.len()).collect();
        let mut named: Vec<(&str, Vec<String>)> = Vec::new();
        let mut appended: Vec<Joint> = Vec::new();
        for (&j, &d) in self.multi.iter().zip(&digits) {
            let joint = &m.joints[j];
            let edges = prufer_tree(joint.bodies.len(), d);
            let mut pairs = Vec::new();
            for (i, &(a, b)) in edges.iter().enumerate() {
                let (ba, bb) = (joint.bodies[a], joint.bodies[b]);
                let label = format!("{}-{}", m.body_id(ba), m.body_id(bb));
                let pj = Joint {
                    id: format!("{}[{label}]", joint.id),
                    kind: joint.kind,
                    bodies: [ba, bb].into(),
                    driven: 0,
                    geometry: joint.geometry.clone(),
                };
                pairs.push(label);
                if i == 0 {
                    mech.joints[j] = pj;
                } else {
                    appended.push(pj);
                    origin.push(j);
                }
            }
            named.push((&joint.id, pairs));
        }
        mech.joints.extend(appended);
        let (label, brief) = labels(named.into_iter());
        Expansion {
            label: Some(label),
            brief,
            mech: std::borrow::Cow::Owned(mech),
            origin,
        }
    }
}

/// The pairs of one expansion without its mechanism ([`Expansions::skeleton`]): each pair's
/// two bodies and original joint, numbered as [`Expansions::get`] numbers them; ids, labels
/// and joints are made only for what is asked (building every expansion's mechanism, two
/// strings a pair, was 60 % of placing a 10^5-body shared joint part by part).
pub(super) struct Skeleton<'a> {
    pub(super) m: &'a Mechanism,
    pub(super) ends: Vec<[usize; 2]>,
    pub(super) origin: Vec<usize>,
    /// Each multiple joint and its pairs in the order of its tree's edges.
    multi: Vec<(usize, Vec<usize>)>,
}

impl Skeleton<'_> {
    fn is_pair(&self, q: usize) -> bool {
        self.m.joints[self.origin[q]].bodies.len() > 2
    }

    /// Pair `q`'s bodies as a label, `a-b`.
    fn label(&self, q: usize) -> String {
        let [a, b] = self.ends[q];
        format!("{}-{}", self.m.body_id(a), self.m.body_id(b))
    }

    /// Joint `q` of the expansion, as [`Expansions::get`] builds it.
    pub(super) fn joint(&self, q: usize) -> Joint {
        let o = &self.m.joints[self.origin[q]];
        if !self.is_pair(q) {
            let mut j = o.clone();
            j.driven = 0;
            return j;
        }
        Joint {
            id: format!("{}[{}]", o.id, self.label(q)),
            kind: o.kind,
            bodies: self.ends[q].into(),
            driven: 0,
            geometry: o.geometry.clone(),
        }
    }

    /// Joint `q`'s id and its bodies' label.
    pub(super) fn names(&self, q: usize) -> (String, String) {
        let o = &self.m.joints[self.origin[q]];
        if self.is_pair(q) {
            let label = self.label(q);
            (format!("{}[{label}]", o.id), label)
        } else {
            (o.id.clone(), self.m.joint_bodies_label(o))
        }
    }

    /// The expansion's label and brief label, as [`Expansions::get`] writes them.
    pub(super) fn expansion_label(&self) -> (Option<String>, Option<String>) {
        if self.multi.is_empty() {
            return (None, None);
        }
        let (label, brief) = labels(self.multi.iter().map(|(j, pairs)| {
            let pairs: Vec<String> = pairs.iter().map(|&q| self.label(q)).collect();
            (self.m.joints[*j].id.as_str(), pairs)
        }));
        (Some(label), brief)
    }
}

/// The file's own placement on the default expansion, as the analysis distributes a multiple
/// joint's driven DOF: its pairs in order, at most k each, the last taking the rest.
pub(super) fn exps_default_inputs(m: &Mechanism, max: usize) -> Vec<Input> {
    let e = &Expansions::of(m, max.min(1)).get(0);
    let mut w: Vec<(usize, u32)> = Vec::new();
    // The pairs of each joint, in pair order (one pass: was a scan of every pair per joint,
    // quadratic: 88 % of `transform --limit 3` on a 10^5-body linkage).
    let mut pairs_of: Vec<Vec<usize>> = vec![Vec::new(); m.joints.len()];
    for (q, &o) in e.origin.iter().enumerate() {
        if let Some(v) = pairs_of.get_mut(o) {
            v.push(q);
        }
    }
    for (j, joint) in m.joints.iter().enumerate() {
        let pairs = &pairs_of[j];
        let mut left = joint.driven;
        for (p, &q) in pairs.iter().enumerate() {
            let share = if p + 1 == pairs.len() {
                left
            } else {
                left.min(joint.grade())
            };
            left -= share;
            if share > 0 {
                w.push((q, share));
            }
        }
    }
    inputs_of(&e.mech, e, &w)
}

/// The driven joints of a placement, in original joint order.
pub(super) fn inputs_of(mech: &Mechanism, e: &Expansion, w: &[(usize, u32)]) -> Vec<Input> {
    let mut w: Vec<(usize, u32)> = w.iter().copied().filter(|&(_, n)| n > 0).collect();
    w.sort_by_key(|&(q, _)| (e.origin[q], q));
    w.iter()
        .map(|&(q, n)| Input {
            joint: mech.joints[q].id.clone(),
            pair: mech.joint_bodies_label(&mech.joints[q]),
            driven: n,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mechanism with only binary joints and none driven is its own one expansion,
    /// borrowed (not copied); with a driven joint the expansion is a copy without inputs.
    #[test]
    fn expansion_borrows_an_undriven_binary_mechanism() {
        let text = "space = \"planar\"\nframe = 1\n\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n\n[[joint]]\ntype = \"R\"\nbodies = [2, 3]\n\n[[joint]]\ntype = \"R\"\nbodies = [3, 1]\n";
        let mut m = crate::format::load("t", text, crate::format::Format::Toml).expect("loads");
        let exps = Expansions::of(&m, 8);
        assert_eq!(exps.len, 1);
        let e = exps.get(0);
        assert!(matches!(e.mech, std::borrow::Cow::Borrowed(_)));
        assert!(std::ptr::eq(e.mech.as_ref(), &m));
        assert_eq!(e.origin, vec![0, 1, 2]);
        m.joints[0].driven = 1;
        let exps = Expansions::of(&m, 8);
        let e = exps.get(0);
        assert!(matches!(e.mech, std::borrow::Cow::Owned(_)));
        assert!(e.mech.joints.iter().all(|j| j.driven == 0));
        assert_eq!(e.mech.joints.len(), 3);
    }

    #[test]
    fn prufer_trees_are_spanning_and_distinct() {
        for n in 2..=5 {
            let mut seen = std::collections::BTreeSet::new();
            for i in 0..trees(n) {
                let t = prufer_tree(n, i);
                assert_eq!(t.len(), n - 1);
                // Connected: union-find over the edges.
                let mut p: Vec<usize> = (0..n).collect();
                fn root(p: &mut [usize], mut x: usize) -> usize {
                    while p[x] != x {
                        x = p[x];
                    }
                    x
                }
                for &(a, b) in &t {
                    let (ra, rb) = (root(&mut p, a), root(&mut p, b));
                    assert_ne!(ra, rb, "cycle in tree {i} of K{n}");
                    p[ra] = rb;
                }
                assert!(seen.insert(t));
            }
            assert_eq!(seen.len() as u64, trees(n));
        }
        // Index 0 is the star on the hub.
        assert_eq!(prufer_tree(4, 0), vec![(0, 1), (0, 2), (0, 3)]);
    }

    /// The linear decoding takes the smallest leaf at each step, as the scan from 0 did.
    #[test]
    fn prufer_decoding_takes_the_smallest_leaf() {
        fn reference(n: usize, mut index: u64) -> Vec<(usize, usize)> {
            let mut seq = vec![0usize; n - 2];
            for s in seq.iter_mut().rev() {
                *s = (index % n as u64) as usize;
                index /= n as u64;
            }
            let mut degree = vec![1usize; n];
            for &s in &seq {
                degree[s] += 1;
            }
            let mut edges = Vec::new();
            for &s in &seq {
                let leaf = (0..n).find(|&v| degree[v] == 1).unwrap();
                edges.push((leaf.min(s), leaf.max(s)));
                degree[leaf] = 0;
                degree[s] -= 1;
            }
            let last: Vec<usize> = (0..n).filter(|&v| degree[v] == 1).collect();
            edges.push((last[0], last[1]));
            edges.sort_unstable();
            edges
        }
        let mut rng = crate::rng::SplitMix64::new(3);
        for n in 3..=9 {
            for i in 0..trees(n).min(2000) {
                assert_eq!(prufer_tree(n, i), reference(n, i), "tree {i} of K{n}");
            }
        }
        for n in [10, 17, 40, 200] {
            for _ in 0..300 {
                let i = rng.next_u64() % trees(n);
                assert_eq!(prufer_tree(n, i), reference(n, i), "tree {i} of K{n}");
            }
        }
    }
}
