//! Shards of one enumeration (`--partition hash:i/n | slice:i/n`, as cargo-nextest's) and
//! their merge.
//!
//! Every shard runs the whole search for count-valid placements, and analyses only its own:
//! by a fixed hash (FNV-1a, 64 bits) of the placement's canonical key (`hash:`), which does
//! not depend on where the placement comes in the enumeration, or by its number in the
//! enumeration (`slice:`); both are known before the analysis. Its summary carries the
//! partition, the counts (the run's count-valid placements, its own determined and excluded
//! ones) and a digest of the input and of the options that change the enumeration, so that a
//! merge refuses shards of different runs. [`merge`] adds the counts, says the run's notes
//! and ranks the union with the unsharded run's code ([`Listing`]).

use super::ranked::{Listing, Ranked};
use super::{
    Criterion, Input, Placement, Summary, TransformError, TransformOptions, enumerate_shard,
    finish_notes, list_cap,
};
use crate::mechanism::Mechanism;
use crate::structure::Library;
use serde::{Deserialize, Serialize};
use std::fmt;

/// How a shard picks its items.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardKind {
    /// By a stable hash of the item (a placement's key, a file's content).
    Hash,
    /// By the item's position: item `k` (0-based) belongs to shard `k mod n + 1`.
    Slice,
}

/// One shard of `n`: `hash:i/n` or `slice:i/n`, `i` from 1 to `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardSpec {
    /// Hash or slice.
    pub kind: ShardKind,
    /// Which shard, 1-based.
    pub index: u64,
    /// How many shards.
    pub count: u64,
}

/// A `--partition` that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("invalid partition `{text}`: {reason}; expected hash:M/N or slice:M/N with 1 <= M <= N")]
pub struct ShardSyntaxError {
    /// The text given.
    pub text: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

impl ShardSpec {
    /// Parse `hash:i/n` or `slice:i/n`.
    pub fn parse(text: &str) -> Result<ShardSpec, ShardSyntaxError> {
        let bad = |reason| ShardSyntaxError {
            text: text.to_string(),
            reason,
        };
        let (kind, rest) = text.split_once(':').ok_or(bad("no `:`"))?;
        let kind = match kind {
            "hash" => ShardKind::Hash,
            "slice" => ShardKind::Slice,
            _ => return Err(bad("the kind is neither `hash` nor `slice`")),
        };
        let (i, n) = rest.split_once('/').ok_or(bad("no `/`"))?;
        let num = |s: &str| {
            s.parse::<u64>()
                .map_err(|_| bad("M and N must be whole numbers"))
        };
        let (index, count) = (num(i)?, num(n)?);
        if count == 0 {
            return Err(bad("N must be at least 1"));
        }
        if index == 0 || index > count {
            return Err(bad("M must be between 1 and N"));
        }
        Ok(ShardSpec { kind, index, count })
    }

    /// Whether the item of this hash (`hash:`) or 0-based position (`slice:`) is this shard's.
    pub fn keeps(&self, hash: u64, position: u64) -> bool {
        let key = match self.kind {
            ShardKind::Hash => hash,
            ShardKind::Slice => position,
        };
        key % self.count + 1 == self.index
    }
}

impl fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = match self.kind {
            ShardKind::Hash => "hash",
            ShardKind::Slice => "slice",
        };
        write!(f, "{kind}:{}/{}", self.index, self.count)
    }
}

impl Serialize for ShardSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for ShardSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<ShardSpec, D::Error> {
        let text = String::deserialize(d)?;
        ShardSpec::parse(&text).map_err(serde::de::Error::custom)
    }
}

/// FNV-1a, 64 bits: a fixed hash, the same on every platform and in every version.
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Fnv1a {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    /// Hash more bytes.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// Hash one field: its length first, so that fields cannot run into each other.
    pub fn field(&mut self, bytes: &[u8]) {
        self.write(&(bytes.len() as u64).to_le_bytes());
        self.write(bytes);
    }

    /// The hash so far.
    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// [`Fnv1a`] of `bytes`.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a::default();
    h.write(bytes);
    h.finish()
}

/// The hash of a placement's canonical key: its driven joints with their DOF, sorted, and
/// its expansion of the multiple joints.
pub fn placement_hash(p: &Placement) -> u64 {
    key_hash(&p.inputs, p.expansion.as_deref())
}

/// [`placement_hash`] of a placement's inputs and expansion label (known before its analysis).
pub fn key_hash(inputs: &[Input], expansion: Option<&str>) -> u64 {
    let mut inputs: Vec<String> = inputs
        .iter()
        .map(|i| format!("{}:{}", i.joint, i.driven))
        .collect();
    inputs.sort();
    let mut h = Fnv1a::default();
    for i in &inputs {
        h.field(i.as_bytes());
    }
    h.field(expansion.unwrap_or("").as_bytes());
    h.finish()
}

/// The digest of a run's input: the mechanism file's bytes, the options that change the
/// enumeration (not `--top`, not the budget) and `extra` (the caller's reading options).
pub fn digest(source: &[u8], opts: &TransformOptions, extra: &str) -> String {
    let mut h = Fnv1a::default();
    h.field(source);
    let enumeration = format!(
        "{:?}|{:?}|{}|{:?}|{:?}|{}|{:?}|{}|{:?}",
        opts.rank,
        opts.on,
        opts.grounded,
        opts.keep,
        opts.exclude,
        opts.max_expansions,
        opts.limit,
        opts.split,
        opts.analysis
    );
    h.field(enumeration.as_bytes());
    // The default adds nothing, so a run without the flags keeps its digest.
    if opts.base != super::BaseMode::Auto {
        h.field(format!("{:?}", opts.base).as_bytes());
    }
    h.field(extra.as_bytes());
    format!("{:016x}", h.finish())
}

/// [`GeometryUsed`](crate::geometry::GeometryUsed) as a report writes it.
#[derive(Deserialize)]
struct GeometryRead {
    mode: String,
    seed: Option<u64>,
    configuration: String,
    note: Option<String>,
    precision: Option<f64>,
    closure: Option<crate::position::Closure>,
}

/// A summary's `geometry` read back from a shard (what the analyses alone use is not written,
/// and the merge does not analyse).
pub(super) fn geometry_read<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<crate::geometry::GeometryUsed>, D::Error> {
    let Some(g) = Option::<GeometryRead>::deserialize(d)? else {
        return Ok(None);
    };
    let mode = ["file", "random"]
        .into_iter()
        .find(|m| *m == g.mode)
        .ok_or_else(|| serde::de::Error::custom(format!("unknown geometry `{}`", g.mode)))?;
    Ok(Some(crate::geometry::GeometryUsed {
        mode,
        seed: g.seed,
        configuration: g.configuration,
        note: g.note,
        precision: g.precision,
        direction_precision: None,
        scale: None,
        closure: g.closure,
    }))
}

/// What a shard's summary line carries beside the run's summary: enough to check the shards
/// of a merge against each other and to rank their union as the unsharded run does.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// This shard (`hash:2/4`).
    pub partition: ShardSpec,
    /// [`digest`] of the input and options: every shard of one run has the same.
    pub digest: String,
    /// Placements this shard wrote.
    pub placements: usize,
    /// Whose counts `excluded_by_rank` and `determined` are.
    #[serde(default)]
    pub counts: Counts,
    /// The whole run's count-valid placements, exactly, in decimal ([`Summary`] writes huge
    /// ones in words).
    pub count_valid: String,
    /// The placements excluded by the rank check: this shard's own, or the run's ([`Counts`]).
    pub excluded_by_rank: String,
    /// The determined placements: this shard's own, or the run's ([`Counts`]).
    pub determined: String,
    /// The ranking criteria.
    pub criteria: Vec<Criterion>,
    /// The most placements a ranked listing holds.
    pub list_cap: usize,
    /// The file's own inputs in the default expansion (to find its rank).
    pub own: Vec<Input>,
}

/// Whose counts a shard's summary carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Counts {
    /// The whole run's (each shard analysed every placement: a mechanism of independent
    /// parts, placed part by part and combined).
    #[default]
    Run,
    /// The shard's own (it analysed only its placements): the merge adds them up.
    Shard,
}

/// The keys a shard's placement line adds to the placement's own: the order and the
/// expansion's index the ranking reads, and the table's brief expansion label.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacementExtra {
    /// Position in the enumeration (the ranking's final tie-break).
    pub index: usize,
    /// Index of the binary expansion (0: every multiple joint a star on its hub).
    pub expansion_index: usize,
    /// The expansion with long lists cut (the table's), when it differs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expansion_brief: Option<String>,
}

impl PlacementExtra {
    /// The extra keys of `p`.
    pub fn of(p: &Placement) -> PlacementExtra {
        PlacementExtra {
            index: p.seq,
            expansion_index: p.exp,
            expansion_brief: p.brief.clone(),
        }
    }

    /// `p` as the shard's run had it.
    pub fn apply(self, mut p: Placement) -> Placement {
        p.seq = self.index;
        p.exp = self.expansion_index;
        p.brief = self.expansion_brief;
        p
    }
}

/// Run the search and hand `sink` the placements of shard `spec`, in enumeration order:
/// only the shard's own placements are analysed (a mechanism of independent parts is
/// analysed whole, and the shard keeps its own of the combined placements). Returns the
/// summary (without the notes made from the counts, which the merge makes: [`merge`]) and
/// the shard's keys.
pub fn run_shard(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    spec: ShardSpec,
    digest: String,
    sink: &mut dyn FnMut(&Placement),
) -> Result<(Summary, ShardInfo), TransformError> {
    let mut kept = 0usize;
    let opts = TransformOptions {
        shard: Some(spec),
        ..opts.clone()
    };
    let summary = enumerate_shard(m, &opts, lib, &mut |p| {
        if spec.keeps(placement_hash(&p), p.seq as u64) {
            sink(&p);
            kept += 1;
        }
    })?;
    let criteria = if opts.rank.is_empty() {
        Criterion::DEFAULT.to_vec()
    } else {
        opts.rank.clone()
    };
    let counts = if summary.parts <= 1 {
        Counts::Shard
    } else {
        Counts::Run
    };
    let info = ShardInfo {
        partition: spec,
        digest,
        placements: kept,
        counts,
        count_valid: summary.count_valid.to_string(),
        excluded_by_rank: summary.excluded_by_rank.to_string(),
        determined: summary.determined.to_string(),
        criteria,
        list_cap: list_cap(m, None),
        own: super::expansion::exps_default_inputs(m, opts.max_expansions),
    };
    Ok((summary, info))
}

/// One shard as read from its file.
#[derive(Clone, Debug)]
pub struct Shard {
    /// The file it was read from (for messages).
    pub file: String,
    /// Its summary line's shard keys.
    pub info: ShardInfo,
    /// The run's summary (its counts are taken from `info`).
    pub summary: Summary,
    /// Its placements, with their [`PlacementExtra`] applied.
    pub placements: Vec<Placement>,
}

/// Why shards cannot be merged.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MergeError {
    /// Nothing to merge.
    #[error("no shard to merge")]
    Empty,
    /// Shards of different inputs or options.
    #[error(
        "`{first}` and `{other}` are shards of different runs (input digests {a} and {b}): \
         they differ in the mechanism file or in an option that changes the enumeration"
    )]
    Different {
        /// A shard of the first run.
        first: String,
        /// A shard of another.
        other: String,
        /// Their digests.
        a: String,
        /// See `a`.
        b: String,
    },
    /// Shards of different partitions (`hash:1/4` and `slice:2/4`, or `/3` and `/4`).
    #[error("`{first}` is shard {a} and `{other}` is shard {b}: not one partition")]
    Mixed {
        /// A shard.
        first: String,
        /// Another of a different partition.
        other: String,
        /// Their partitions.
        a: String,
        /// See `a`.
        b: String,
    },
    /// A shard given twice.
    #[error("shard {partition} is given twice: `{first}` and `{other}`")]
    Duplicate {
        /// The shard.
        partition: String,
        /// Its files.
        first: String,
        /// See `first`.
        other: String,
    },
    /// Shards missing.
    #[error("the partition is incomplete: shard(s) {missing} of {count} missing (given: {given})")]
    Missing {
        /// The missing shards, `hash:2/4, hash:3/4`.
        missing: String,
        /// How many shards the partition has.
        count: u64,
        /// The files given.
        given: String,
    },
    /// A count that is not a number (a damaged summary line).
    #[error("`{file}`: the count `{text}` is not a number")]
    Count {
        /// The shard.
        file: String,
        /// The text.
        text: String,
    },
}

/// Shards checked to make one whole run: the union of their placements and the run's summary.
#[derive(Debug)]
pub struct Merged {
    /// The run's summary, its counts exact.
    pub summary: Summary,
    /// The shard keys of the first shard (criteria, cap, own inputs are every shard's).
    pub info: ShardInfo,
    /// Every placement of the run, in enumeration order.
    pub placements: Vec<Placement>,
}

/// Check that `shards` are the whole partition of one run, each shard once, and join them.
pub fn merge(shards: Vec<Shard>) -> Result<Merged, MergeError> {
    let first = shards.first().ok_or(MergeError::Empty)?;
    let (head, spec) = (first.file.clone(), first.info.partition);
    let mut seen: Vec<Option<String>> = vec![None; spec.count.min(1 << 20) as usize];
    for s in &shards {
        let p = s.info.partition;
        if s.info.digest != first.info.digest {
            return Err(MergeError::Different {
                first: head,
                other: s.file.clone(),
                a: first.info.digest.clone(),
                b: s.info.digest.clone(),
            });
        }
        if s.info.counts != first.info.counts || s.info.count_valid != first.info.count_valid {
            return Err(MergeError::Different {
                first: head,
                other: s.file.clone(),
                a: first.info.digest.clone(),
                b: s.info.digest.clone(),
            });
        }
        if p.kind != spec.kind || p.count != spec.count || p.count as usize > seen.len() {
            return Err(MergeError::Mixed {
                first: head,
                other: s.file.clone(),
                a: spec.to_string(),
                b: p.to_string(),
            });
        }
        let slot = &mut seen[p.index as usize - 1];
        if let Some(f) = slot {
            return Err(MergeError::Duplicate {
                partition: p.to_string(),
                first: f.clone(),
                other: s.file.clone(),
            });
        }
        *slot = Some(s.file.clone());
    }
    check_complete(&shards, spec, &seen)?;
    join(shards)
}

/// Every shard of the partition present.
fn check_complete(
    shards: &[Shard],
    spec: ShardSpec,
    seen: &[Option<String>],
) -> Result<(), MergeError> {
    let missing: Vec<String> = (1..=spec.count)
        .filter(|i| seen[*i as usize - 1].is_none())
        .map(|index| ShardSpec { index, ..spec }.to_string())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let given: Vec<&str> = shards.iter().map(|s| s.file.as_str()).collect();
    Err(MergeError::Missing {
        missing: missing.join(", "),
        count: spec.count,
        given: given.join(", "),
    })
}

/// The union of checked shards, in enumeration order, with the run's exact counts.
fn join(shards: Vec<Shard>) -> Result<Merged, MergeError> {
    let mut iter = shards.into_iter();
    let Some(first) = iter.next() else {
        return Err(MergeError::Empty);
    };
    let count = |text: &str| {
        text.parse::<u128>().map_err(|_| MergeError::Count {
            file: first.file.clone(),
            text: text.to_string(),
        })
    };
    let mut summary = first.summary;
    summary.count_valid = count(&first.info.count_valid)?;
    summary.excluded_by_rank = count(&first.info.excluded_by_rank)?;
    summary.determined = count(&first.info.determined)?;
    let own = first.info.counts == Counts::Shard;
    let mut placements = first.placements;
    for s in iter {
        if own {
            // Each shard counted its own placements: the run's are their sum.
            let add = |total: u128, text: &str| {
                text.parse::<u128>()
                    .map(|n| total.saturating_add(n))
                    .map_err(|_| MergeError::Count {
                        file: s.file.clone(),
                        text: text.to_string(),
                    })
            };
            summary.excluded_by_rank = add(summary.excluded_by_rank, &s.info.excluded_by_rank)?;
            summary.determined = add(summary.determined, &s.info.determined)?;
        }
        placements.extend(s.placements);
    }
    placements.sort_by_key(|p| p.seq);
    if own {
        summary.listed = usize::try_from(summary.determined).unwrap_or(usize::MAX);
        finish_notes(&mut summary);
    }
    Ok(Merged {
        summary,
        info: first.info,
        placements,
    })
}

impl Merged {
    /// Rank and group the placements as the unsharded run does.
    pub fn ranked(self) -> Ranked {
        let mut listing = Listing::new(self.info.criteria, self.info.list_cap);
        for p in self.placements {
            listing.push(p);
        }
        listing.finish(self.summary, &self.info.own, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_partitions() {
        let s = ShardSpec::parse("hash:2/4").unwrap();
        assert_eq!((s.kind, s.index, s.count), (ShardKind::Hash, 2, 4));
        assert_eq!(s.to_string(), "hash:2/4");
        assert_eq!(
            ShardSpec::parse("slice:1/1").unwrap().kind,
            ShardKind::Slice
        );
        for bad in [
            "hash:0/3", "hash:4/3", "x:1/2", "hash:1/0", "hash:1", "hash:a/2", "1/2",
        ] {
            assert!(ShardSpec::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn shards_cover_every_item_once() {
        for kind in ["hash", "slice"] {
            let specs: Vec<ShardSpec> = (1..=7)
                .map(|i| ShardSpec::parse(&format!("{kind}:{i}/7")).unwrap())
                .collect();
            for k in 0..1000u64 {
                let h = fnv1a(&k.to_le_bytes());
                assert_eq!(specs.iter().filter(|s| s.keeps(h, k)).count(), 1);
            }
        }
    }

    #[test]
    fn fnv1a_is_the_published_function() {
        // Test vectors of the FNV reference (64-bit FNV-1a).
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
