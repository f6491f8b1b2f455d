//! `mbsa repair`: the joint changes that make a model simulate with the same motion
//! ([`mbsa::repair`]), and the repaired file (`--apply N`).

use super::input::write_output;
use super::{Failure, FileArg, emit, load};
use clap::{Args, ValueEnum};
use mbsa::repair::{self, RepairError, RepairOptions};
use mbsa::write::TextFormat as Format;
use std::path::PathBuf;

/// What `--format` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RepairFormat {
    /// The candidates as a table for people.
    Table,
    /// The candidates as JSON; with `--apply`, the repaired file as JSON.
    Json,
    /// With `--apply`: the repaired file as TOML (the default then).
    Toml,
    /// With `--apply`: the repaired file as YAML.
    Yaml,
}

/// `mbsa repair`'s options.
#[derive(Args, Debug)]
pub struct RepairArgs {
    /// Write the model repaired by candidate N (1 = the first listed) instead of the list.
    #[arg(long, value_name = "N")]
    apply: Option<usize>,
    /// Output: `table` or `json` for the list; `toml`, `yaml` or `json` for `--apply`.
    #[arg(long, value_enum)]
    format: Option<RepairFormat>,
    /// Write to this file instead of standard output (written whole, then renamed into place).
    #[arg(short, long, value_name = "OUT")]
    output: Option<PathBuf>,
    /// Most candidates searched, each starting from a different first change.
    #[arg(long, default_value_t = 4, value_name = "N")]
    candidates: usize,
}

/// `mbsa repair`.
pub fn run(file: &FileArg, args: &RepairArgs) -> Result<(), Failure> {
    let m = load(file)?;
    let opts = RepairOptions {
        candidates: args.candidates.clamp(1, 64),
        budget: super::budget(),
    };
    let r = repair::repair(&m, &opts).map_err(|e| match e {
        RepairError::Budget(e) => super::budget_failure(&e),
        RepairError::Motion(e) => super::analysis::input_error(file, e),
        RepairError::NoGeometry(_) => Failure::Input(format!(
            "error: {}: {e}\n  help: a repair keeps the joints' points and axes: give them in \
             the file (docs/format.md), or import a model that has them",
            file.file
        )),
        e => Failure::Input(format!("error: {}: {e}", file.file)),
    })?;
    let text = match args.apply {
        Some(n) => {
            let Some(c) = n.checked_sub(1).and_then(|i| r.candidates.get(i)) else {
                return Err(Failure::Input(format!(
                    "error: --apply {n}: {} candidate{} listed\n  help: run `mbsa repair {}` \
                     to see them",
                    r.candidates.len(),
                    if r.candidates.len() == 1 {
                        " is"
                    } else {
                        "s are"
                    },
                    file.file
                )));
            };
            let format = match args.format {
                None | Some(RepairFormat::Toml) => Format::Toml,
                Some(RepairFormat::Yaml) => Format::Yaml,
                Some(RepairFormat::Json) => Format::Json,
                Some(RepairFormat::Table) => {
                    return Err(Failure::Input(
                        "error: --apply writes a file: --format toml, yaml or json".into(),
                    ));
                }
            };
            let repaired = repair::apply(&m, c);
            let comments: Vec<Option<String>> = repaired
                .joints
                .iter()
                .map(|j| {
                    c.changes
                        .iter()
                        .find(|ch| ch.joint == j.id)
                        .map(mbsa::report::repair::comment)
                })
                .collect();
            mbsa::write::write(&repaired, format, &comments)
        }
        None => match args.format {
            None | Some(RepairFormat::Table) => mbsa::report::repair::table(&r, &file.file),
            Some(RepairFormat::Json) => mbsa::report::repair::json(&r),
            Some(f) => {
                return Err(Failure::Input(format!(
                    "error: --format {}: only with --apply (the list is `table` or `json`)",
                    f.to_possible_value()
                        .map_or("?".into(), |v| v.get_name().to_string())
                )));
            }
        },
    };
    match &args.output {
        Some(path) => write_output(&file.file, path, &text),
        None => emit(&text),
    }
}
