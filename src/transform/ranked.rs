//! Ranking: the order of score sets, the listed placements best first, and their families
//! (placements with the same partition into groups).

use super::expansion::exps_default_inputs;
use super::partition::{Fingerprint, Partition, Repr};
use super::problem::Problem;
use super::{
    Criterion, Family, LIST_MEMORY, Placement, ProgressFn, Scores, Summary, Transform,
    TransformError, TransformOptions, enumerate_kept, list_cap,
};
use crate::mechanism::Mechanism;
use crate::structure::{Analysis, Library};
use serde::Serialize;
use std::cmp::Ordering;
use std::collections::HashMap;

/// The ranked result of [`ranked`]: [`Transform`] without the partitions the search's flow
/// gave, each made again when it is written (it serializes as [`Transform`] does, byte for
/// byte, streaming). A listed placement of a 10^6-body linkage held its partition (about
/// 10 MB with its bookkeeping), and each family a copy: 100 of them were over 1 GB of
/// `transform --limit 100`; held now is O(bodies) for the search's problem plus each
/// placement's inputs and scores.
#[derive(Debug)]
pub struct Ranked {
    /// Counts and notes.
    pub summary: Summary,
    /// The ranking criteria used.
    pub criteria: Vec<Criterion>,
    /// Rank of the file's own placement among the determined ones, if it is one of them.
    pub original_rank: Option<usize>,
    /// Every listed placement, best first; one whose groups came from the search's flow has
    /// an empty partition here ([`Ranked::partition`] makes it).
    pub placements: Vec<Placement>,
    /// Each family's members (ranks, best first), best family first (family `i + 1`).
    pub families: Vec<Vec<usize>>,
    /// The fingerprint of each placement's partition (a check on the ones made again).
    fingerprints: Vec<Fingerprint>,
    /// The search's problem, to make the partitions again.
    problem: Option<Problem>,
}

/// Enumerate, rank and group the determined placements as [`transform`] does, holding each
/// listed placement's partition only where it cannot be made again ([`Ranked`]).
pub fn ranked(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    progress: Option<ProgressFn<'_>>,
) -> Result<Ranked, TransformError> {
    let criteria = if opts.rank.is_empty() {
        Criterion::DEFAULT.to_vec()
    } else {
        opts.rank.clone()
    };
    let mut listing = Listing::new(criteria, list_cap(m, None));
    let mut problem: Option<Problem> = None;
    let summary = enumerate_kept(
        m,
        opts,
        lib,
        progress,
        &mut |p| listing.push(p),
        Some(&mut problem),
    )?;
    let own = exps_default_inputs(m, opts.max_expansions);
    Ok(listing.finish(summary, &own, problem))
}

/// The best placements of a run as they come, in any order, and their ranking: [`ranked`]
/// fills it from the search, a merge of shards from their files, so both rank alike.
pub(super) struct Listing {
    criteria: Vec<Criterion>,
    /// The most placements listed ([`list_cap`]).
    cap: usize,
    placements: Vec<(Placement, Fingerprint)>,
    /// The bytes `placements` hold ([`Placement::bytes`]).
    bytes: usize,
}

impl Listing {
    pub(super) fn new(criteria: Vec<Criterion>, cap: usize) -> Listing {
        Listing {
            criteria,
            cap,
            placements: Vec::new(),
            bytes: 0,
        }
    }

    /// The order of the ranking: the scores by the criteria, then the enumeration order.
    fn order(&mut self) {
        let c = &self.criteria;
        self.placements.sort_by(|a, b| {
            compare_scores(&a.0.scores, &b.0.scores, c).then(a.0.seq.cmp(&b.0.seq))
        });
    }

    /// Take one placement; only the best `cap` are kept, so memory stays bounded however
    /// many there are.
    pub(super) fn push(&mut self, mut p: Placement) {
        let fp = p.partition.fingerprint();
        if p.lean.is_some() {
            p.partition = Partition(Repr::Text(Vec::new()));
        }
        // Bookkeeping only the joining of parts reads (a whole's placement is never a
        // part's): one record a group.
        p.groups_at = Vec::new();
        p.kinds = Vec::new();
        p.in_lib = Vec::new();
        self.bytes += p.bytes();
        self.placements.push((p, fp));
        if self.placements.len() >= 2 * self.cap || self.bytes > LIST_MEMORY + LIST_MEMORY / 2 {
            self.keep_best();
        }
    }

    /// Keep the best placements, at most `cap` of them and [`LIST_MEMORY`] bytes (the best
    /// one always): a placement of a mechanism of 10^5 bodies holds megabytes, so a count
    /// alone does not bound the listing's memory.
    fn keep_best(&mut self) {
        self.order();
        self.placements.truncate(self.cap);
        let mut bytes = 0;
        let mut keep = 0;
        for (p, _) in &self.placements {
            let b = p.bytes();
            if keep > 0 && bytes + b > LIST_MEMORY {
                break;
            }
            bytes += b;
            keep += 1;
        }
        self.placements.truncate(keep);
        self.bytes = bytes;
    }

    /// Rank the best `cap`, group them into families and find the file's own placement
    /// (`own`: its inputs in the default expansion) among them.
    pub(super) fn finish(
        mut self,
        mut summary: Summary,
        own: &[super::Input],
        problem: Option<Problem>,
    ) -> Ranked {
        self.keep_best();
        let mut placements = self.placements;
        if summary.listed != placements.len() {
            summary.notes.retain(|n| !n.contains("are listed"));
            summary.listed = placements.len();
            super::push_listing_note(&mut summary);
        }
        let mut index: HashMap<Fingerprint, usize> = HashMap::new();
        let mut families: Vec<Vec<usize>> = Vec::new();
        for (i, (p, fp)) in placements.iter_mut().enumerate() {
            p.rank = Some(i + 1);
            let f = *index.entry(*fp).or_insert_with(|| {
                families.push(Vec::new());
                families.len()
            });
            families[f - 1].push(i + 1);
            p.family = Some(f);
        }
        let original_rank = placements
            .iter()
            .find(|(p, _)| p.exp == 0 && p.inputs == own)
            .and_then(|(p, _)| p.rank);
        let (placements, fingerprints) = placements.into_iter().unzip();
        Ranked {
            summary,
            criteria: self.criteria,
            original_rank,
            placements,
            families,
            fingerprints,
            problem,
        }
    }
}

impl Ranked {
    /// The partition of the placement at index `i` (rank `i + 1`): held, or made again from
    /// its inputs and the search's problem (checked against the fingerprint taken when it
    /// was first made).
    pub fn partition(&self, i: usize) -> Result<std::borrow::Cow<'_, Partition>, TransformError> {
        use std::borrow::Cow;
        let failed = TransformError::Regenerate { rank: i + 1 };
        let p = self.placements.get(i).ok_or(failed.clone())?;
        let Some(w) = &p.lean else {
            return Ok(Cow::Borrowed(&p.partition));
        };
        let made = self.problem.as_ref().and_then(|pr| {
            let l = pr.lean.as_ref()?;
            let flow = pr.flow_of(w)?;
            Some(Partition::indexed(
                &l.ids,
                l.raw(&flow)
                    .into_iter()
                    .map(|(_, g)| g.into_iter().map(|x| x as u32).collect()),
            ))
        });
        match made {
            Some(part) if Some(&part.fingerprint()) == self.fingerprints.get(i) => {
                Ok(Cow::Owned(part))
            }
            _ => Err(failed),
        }
    }

    /// The placement at index `i` with its partition, as [`Transform`] lists it.
    fn full(&self, i: usize) -> Result<std::borrow::Cow<'_, Placement>, TransformError> {
        use std::borrow::Cow;
        let failed = TransformError::Regenerate { rank: i + 1 };
        let p = self.placements.get(i).ok_or(failed)?;
        Ok(match self.partition(i)? {
            Cow::Borrowed(_) => Cow::Borrowed(p),
            Cow::Owned(part) => {
                let mut q = p.clone();
                q.partition = part;
                q.lean = None;
                Cow::Owned(q)
            }
        })
    }

    /// Every partition made: the [`Transform`].
    pub fn into_transform(self) -> Result<Transform, TransformError> {
        let mut placements = Vec::with_capacity(self.placements.len());
        for i in 0..self.placements.len() {
            placements.push(self.full(i)?.into_owned());
        }
        let mut families = Vec::with_capacity(self.families.len());
        for (f, members) in self.families.iter().enumerate() {
            let best = members.first().and_then(|&r| placements.get(r - 1));
            let Some(best) = best else {
                return Err(TransformError::Regenerate { rank: 0 });
            };
            families.push(Family {
                id: f + 1,
                partition: best.partition.clone(),
                placements: members.clone(),
            });
        }
        Ok(Transform {
            summary: self.summary,
            criteria: self.criteria,
            original_rank: self.original_rank,
            placements,
            families,
        })
    }
}

impl Serialize for Ranked {
    /// As [`Transform`] serializes, each partition made when it is written.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{Error, SerializeSeq, SerializeStruct};
        struct Placements<'a>(&'a Ranked);
        impl Serialize for Placements<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let mut seq = s.serialize_seq(Some(self.0.placements.len()))?;
                for i in 0..self.0.placements.len() {
                    let p = self.0.full(i).map_err(S::Error::custom)?;
                    seq.serialize_element(&*p)?;
                }
                seq.end()
            }
        }
        /// A family as [`Family`] serializes.
        #[derive(Serialize)]
        struct FamilyRef<'a> {
            id: usize,
            partition: &'a Partition,
            placements: &'a [usize],
        }
        struct Families<'a>(&'a Ranked);
        impl Serialize for Families<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let r = self.0;
                let mut seq = s.serialize_seq(Some(r.families.len()))?;
                for (f, members) in r.families.iter().enumerate() {
                    let best = members.first().map_or(0, |&r| r - 1);
                    let part = r.partition(best).map_err(S::Error::custom)?;
                    seq.serialize_element(&FamilyRef {
                        id: f + 1,
                        partition: &part,
                        placements: members,
                    })?;
                }
                seq.end()
            }
        }
        let mut st = s.serialize_struct("Transform", 5)?;
        st.serialize_field("summary", &self.summary)?;
        st.serialize_field("criteria", &self.criteria)?;
        st.serialize_field("original_rank", &self.original_rank)?;
        st.serialize_field("placements", &Placements(self))?;
        st.serialize_field("families", &Families(self))?;
        st.end()
    }
}

/// Order two score sets by `criteria` (`Less`: `a` ranks before `b`).
pub fn compare_scores(a: &Scores, b: &Scores, criteria: &[Criterion]) -> Ordering {
    for c in criteria {
        let o = match c {
            Criterion::Groups => b.groups.cmp(&a.groups),
            Criterion::Library => b
                .all_covered
                .cmp(&a.all_covered)
                .then(b.covered.cmp(&a.covered)),
            Criterion::MaxSize => a.largest.cmp(&b.largest),
            Criterion::Levels => a.levels.cmp(&b.levels),
        };
        if o != Ordering::Equal {
            return o;
        }
    }
    Ordering::Equal
}

/// The scores of an analysis.
pub fn scores(a: &Analysis) -> Scores {
    let covered = a.groups.iter().filter(|g| g.in_library).count();
    Scores {
        groups: a.groups.len(),
        largest: a.groups.iter().map(|g| g.nm).max().unwrap_or(0),
        levels: a.levels,
        covered,
        all_covered: covered == a.groups.len(),
    }
}
