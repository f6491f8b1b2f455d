//! `transform --partition` shards as JSON lines: writing a shard's lines and reading them
//! back for a merge.

use crate::transform::shard::{PlacementExtra, Shard, ShardInfo};
use crate::transform::{Placement, Summary};
use serde::{Deserialize, Serialize};

/// A shard's placement line: the placement's keys as the unsharded stream writes them, then
/// [`PlacementExtra`]'s.
pub fn placement_line(p: &Placement) -> String {
    #[derive(Serialize)]
    struct Line<'a> {
        #[serde(flatten)]
        placement: &'a Placement,
        #[serde(flatten)]
        extra: PlacementExtra,
    }
    super::jsonl(&Line {
        placement: p,
        extra: PlacementExtra::of(p),
    })
}

/// A shard's last line: the run's summary as the unsharded stream writes it, and `shard`.
pub fn summary_line(s: &Summary, info: &ShardInfo) -> String {
    #[derive(Serialize)]
    struct Line<'a> {
        #[serde(flatten)]
        summary: &'a Summary,
        shard: &'a ShardInfo,
    }
    super::jsonl(&Line {
        summary: s,
        shard: info,
    })
}

/// A shard file that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{file}:{line}: {message}")]
pub struct ShardReadError {
    /// The file.
    pub file: String,
    /// The line (1-based; the last line for a missing summary).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// The `shard` key of a summary line.
#[derive(Deserialize)]
struct Head {
    shard: ShardInfo,
}

/// Whether a line is a shard's summary line (it has the key `shard`).
#[derive(Deserialize)]
struct Probe {
    #[serde(default)]
    shard: Option<serde::de::IgnoredAny>,
}

/// Read the lines a shard wrote (`file` names it in errors): its placements, then its summary
/// line, which must come last and count the placements before it (a cut file is refused).
pub fn read_shard(file: &str, text: &str) -> Result<Shard, ShardReadError> {
    let err = |line: usize, message: String| ShardReadError {
        file: file.to_string(),
        line,
        message,
    };
    let mut placements = Vec::new();
    let mut head: Option<(Summary, ShardInfo)> = None;
    let mut last = 0;
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let n = i + 1;
        last = n;
        if head.is_some() {
            return Err(err(n, "a line after the summary line".into()));
        }
        let bad = |e: serde_json::Error| err(n, format!("not a shard line: {e}"));
        let probe: Probe = serde_json::from_str(line).map_err(bad)?;
        if probe.shard.is_some() {
            let h: Head = serde_json::from_str(line).map_err(bad)?;
            head = Some((serde_json::from_str(line).map_err(bad)?, h.shard));
        } else {
            let p: Placement = serde_json::from_str(line).map_err(bad)?;
            let extra: PlacementExtra = serde_json::from_str(line).map_err(bad)?;
            placements.push(extra.apply(p));
        }
    }
    let Some((summary, info)) = head else {
        return Err(err(
            last,
            "no summary line: not a `transform --partition` shard, or a cut one".into(),
        ));
    };
    if info.placements != placements.len() {
        return Err(err(
            last,
            format!(
                "the summary counts {} placement(s) but the file has {}: a cut or edited shard",
                info.placements,
                placements.len()
            ),
        ));
    }
    Ok(Shard {
        file: file.to_string(),
        info,
        summary,
        placements,
    })
}
