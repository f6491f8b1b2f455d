//! `mbsa transform`: where else could the driven inputs go?

use super::analysis::StructureArgs;
use super::{Failure, FileArg, emit, load_with_inputs};
use clap::{Args, ValueEnum};
use mbsa::transform::shard::ShardSpec;
use mbsa::transform::{self, Criterion, Progress, TransformOptions};
use std::io::IsTerminal;

/// Options of `mbsa transform`.
#[derive(Args, Debug, Clone)]
pub struct TransformArgs {
    /// Ranking criteria, most important first: groups (more), library (more covered),
    /// max-size (smaller largest group), levels (fewer).
    #[arg(
        long,
        value_name = "LIST",
        default_value = "groups,library,max-size,levels"
    )]
    pub rank: String,
    /// How many families of placements the table shows.
    #[arg(long, default_value_t = 10)]
    pub top: usize,
    /// Only joints of these types may be driven (codes or names, e.g. `R,P`).
    #[arg(long, value_name = "TYPES")]
    pub on: Option<String>,
    /// Only joints to the frame may be driven.
    #[arg(long)]
    pub grounded: bool,
    /// Inputs that must stay (same syntax as --inputs).
    #[arg(long, value_name = "SPEC")]
    pub keep: Option<String>,
    /// Joints that may not be driven (same syntax as --inputs; counts are ignored).
    #[arg(long, value_name = "SPEC")]
    pub exclude: Option<String>,
    /// Take every free joint to the frame (F) as driven in full: the base's pose is given, as
    /// in a fixed-base analysis, and the other inputs are placed. By default this is done for
    /// a floating base, a free joint that is its part's only joint to the frame (every
    /// determined placement drives it in full anyway); the output names the joint.
    #[arg(long, conflicts_with = "keep_free_base")]
    pub fix_base: bool,
    /// Place inputs on a floating base's free joint like on any other joint (the search is
    /// longer and finds the same determined placements).
    #[arg(long)]
    pub keep_free_base: bool,
    /// How many binary expansions of multiple joints to explore.
    #[arg(long, default_value_t = 64)]
    pub max_expansions: usize,
    /// Examine at most this many count-valid placements (per independent part): the search
    /// stops there, and the output says when placements were left out.
    #[arg(long)]
    pub limit: Option<usize>,
    /// Output format: a ranked table, JSON with the placements and their scores, or JSON lines
    /// streamed one placement per line. The counts are exact; at most 100,000 placements are
    /// listed (fewer for large mechanisms), the best first when the mechanism has independent
    /// parts; a mechanism in one part streams every one as JSON lines.
    #[arg(long, value_enum, default_value_t = TransformFormat::Table)]
    pub format: TransformFormat,
    /// Write only shard M of N of the placements, as JSON lines for `mbsa merge`: `hash:M/N`
    /// (by a hash of each placement) or `slice:M/N` (by its position). docs/sharding.md.
    #[arg(long, value_name = "hash:M/N|slice:M/N", value_parser = parse_partition)]
    pub partition: Option<ShardSpec>,
}

/// Parse `--partition` (clap renders the error, exit code 2).
pub(super) fn parse_partition(text: &str) -> Result<ShardSpec, String> {
    ShardSpec::parse(text).map_err(|e| e.to_string())
}

/// `--format` values of `transform`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TransformFormat {
    /// Ranked table for people.
    Table,
    /// One JSON object with the placements (at most 100,000) and their scores.
    Json,
    /// One JSON object per line, streamed; the summary comes last.
    Jsonl,
}

fn spec(
    text: &Option<String>,
    flag: &str,
    m: &mbsa::Mechanism,
) -> Result<Option<mbsa::InputSpec>, Failure> {
    text.as_deref()
        .map(|t| mbsa::InputSpec::parse_in(t, m))
        .transpose()
        .map_err(|e| Failure::Input(mbsa::diagnostic::render_plain(flag, &e)))
}

/// Run `mbsa transform`.
pub fn run(file: &FileArg, structure: &StructureArgs, args: &TransformArgs) -> Result<(), Failure> {
    if args.partition.is_some() {
        shard_usage(file, structure, args)?;
    }
    // The file's own inputs stay in the model: `--inputs` is compared against them.
    let m = load_with_inputs(file, None)?;
    let lib = structure.library()?;
    let bad = |flag: &str, e: &dyn std::error::Error| {
        Failure::Input(mbsa::diagnostic::render_plain(flag, e))
    };
    // Past the work budget: the budget's own message and exit code.
    // The search's own bounds come first in the help: `--limit` answers at once where the
    // whole search would take the budget (a 24-body leg ran 120 s to the work limit).
    let failed = |e: transform::TransformError| match e {
        transform::TransformError::Budget(b) => match super::budget_failure(&b) {
            super::Failure::Input(text) if args.limit.is_none() => super::Failure::Input(format!(
                "{text}\n  help: or bound the search: `--limit N` examines the first N \
                 placements; `--keep SPEC` places the others around the inputs you keep"
            )),
            f => f,
        },
        e => bad("transform", &e),
    };
    let opts = TransformOptions {
        rank: Criterion::parse_list(&args.rank).map_err(|e| bad("--rank", &e))?,
        top: args.top,
        on: args
            .on
            .as_deref()
            .map(TransformOptions::parse_on)
            .transpose()
            .map_err(|e| bad("--on", &e))?,
        grounded: args.grounded,
        keep: spec(&args.keep, "--keep", &m)?,
        exclude: spec(&args.exclude, "--exclude", &m)?,
        inputs: spec(&structure.inputs, "--inputs", &m)?,
        base: match (args.fix_base, args.keep_free_base) {
            (true, _) => transform::BaseMode::Fixed,
            (false, true) => transform::BaseMode::Free,
            (false, false) => transform::BaseMode::Auto,
        },
        max_expansions: args.max_expansions,
        limit: args.limit,
        budget: super::budget(),
        split: true,
        full_analyses: false,
        analysis: structure.options()?,
        // `run_shard` sets it from `--partition`.
        shard: None,
    };
    if !structure.count_only {
        structure.geometry.closure_check(&file.file, &m)?;
    }
    if let Some(spec) = args.partition {
        let extra = format!(
            "{:?}|{:?}|{:?}",
            file.input_format, file.import, structure.library
        );
        let digest = transform::shard::digest(&source_bytes(&file.file)?, &opts, &extra);
        return write_shard(&m, &opts, &lib, spec, digest, failed);
    }
    if let Some(given) = &opts.inputs {
        let c = transform::compare(&m, given, &opts, &lib).map_err(|e| bad("--inputs", &e))?;
        return emit(&match args.format {
            TransformFormat::Table => mbsa::report::transform::comparison(&c),
            TransformFormat::Json | TransformFormat::Jsonl => mbsa::report::json(&c),
        });
    }
    // A progress bar only for people: a terminal on stderr and the table format.
    let bar = (args.format == TransformFormat::Table && std::io::stderr().is_terminal()).then(|| {
        let bar = indicatif::ProgressBar::new(0);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} analysing placements {pos}/{len} ({percent}%), {msg} determined, eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let report = |p: Progress| {
        if let Some(bar) = &bar {
            bar.set_length(p.total as u64);
            bar.set_position(p.examined as u64);
            bar.set_message(p.determined.to_string());
        }
    };
    let progress: Option<transform::ProgressFn<'_>> = bar.as_ref().map(|_| &report as _);
    match args.format {
        TransformFormat::Jsonl => {
            let mut failed_emit = None;
            let summary = transform::enumerate(&m, &opts, &lib, None, &mut |p| {
                if failed_emit.is_none()
                    && let Err(e) = emit(&mbsa::report::transform::jsonl(&p))
                {
                    failed_emit = Some(e);
                }
            })
            .map_err(failed)?;
            if let Some(e) = failed_emit {
                return Err(e);
            }
            emit(&mbsa::report::transform::jsonl(&summary))
        }
        TransformFormat::Json | TransformFormat::Table => {
            // Partitions are made as they are written (none for the table): not held.
            let t = transform::ranked(&m, &opts, &lib, progress).map_err(failed)?;
            if let Some(bar) = &bar {
                bar.finish_and_clear();
            }
            match args.format {
                TransformFormat::Table => {
                    emit(&mbsa::report::transform::table_of_ranked(&t, args.top))
                }
                _ => emit_json(&t),
            }
        }
    }
}

/// Write shard `spec` of the placements and its summary line.
fn write_shard(
    m: &mbsa::Mechanism,
    opts: &TransformOptions,
    lib: &mbsa::structure::Library,
    spec: ShardSpec,
    digest: String,
    failed: impl Fn(transform::TransformError) -> Failure,
) -> Result<(), Failure> {
    use mbsa::report::transform::shard;
    let mut failed_emit = None;
    let (summary, info) = transform::shard::run_shard(m, opts, lib, spec, digest, &mut |p| {
        if failed_emit.is_none()
            && let Err(e) = emit(&shard::placement_line(p))
        {
            failed_emit = Some(e);
        }
    })
    .map_err(failed)?;
    if let Some(e) = failed_emit {
        return Err(e);
    }
    emit(&shard::summary_line(&summary, &info))
}

/// Options of `mbsa merge`.
#[derive(Args, Debug, Clone)]
pub struct MergeArgs {
    /// The shards' files (`mbsa transform --partition ... --format jsonl`), in any order.
    #[arg(value_name = "SHARD", required = true)]
    pub shards: Vec<String>,
    /// How many families of placements the table shows.
    #[arg(long, default_value_t = 10)]
    pub top: usize,
    /// Output format, as `transform --format` (the unsharded run's output, byte for byte).
    #[arg(long, value_enum, default_value_t = TransformFormat::Table)]
    pub format: TransformFormat,
}

/// Run `mbsa merge`: check that the shards make one whole run and write its output.
pub fn merge(args: &MergeArgs) -> Result<(), Failure> {
    let mut shards = Vec::with_capacity(args.shards.len());
    for name in &args.shards {
        let bytes = super::budget()
            .read_file(std::path::Path::new(name))
            .map_err(|e| super::input::read_failure(&format!("`{name}`"), e))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| Failure::Input(format!("error: `{name}` is not UTF-8: not a shard")))?;
        let shard = mbsa::report::transform::shard::read_shard(name, &text)
            .map_err(|e| Failure::Input(format!("error: {e}")))?;
        shards.push(shard);
    }
    let merged = transform::shard::merge(shards).map_err(|e| {
        Failure::Input(format!(
            "error: {e}\n  help: merge the N shards of one `transform --partition KIND:M/N` run"
        ))
    })?;
    match args.format {
        TransformFormat::Jsonl => {
            for p in &merged.placements {
                emit(&mbsa::report::transform::jsonl(p))?;
            }
            emit(&mbsa::report::transform::jsonl(&merged.summary))
        }
        TransformFormat::Table => emit(&mbsa::report::transform::table_of_ranked(
            &merged.ranked(),
            args.top,
        )),
        TransformFormat::Json => emit_json(&merged.ranked()),
    }
}

/// Refuse the options a shard cannot keep, saying why.
fn shard_usage(
    file: &FileArg,
    structure: &StructureArgs,
    args: &TransformArgs,
) -> Result<(), Failure> {
    let refuse = |why: &str| Err(Failure::Input(format!("error: --partition {why}")));
    if args.format != TransformFormat::Jsonl {
        return refuse(
            "writes a shard as JSON lines for `mbsa merge`: add --format jsonl (the merge \
             writes the table or JSON)",
        );
    }
    if structure.inputs.is_some() {
        return refuse(
            "shards the enumeration, and --inputs compares one placement: nothing to shard",
        );
    }
    if file.file == "-" {
        return refuse(
            "needs the same input in every shard, and standard input is read once: save it to a file",
        );
    }
    Ok(())
}

/// The bytes of FILE (a path or `@name`) for a shard's input digest.
fn source_bytes(file: &str) -> Result<Vec<u8>, Failure> {
    if let Some(name) = file.strip_prefix('@') {
        return Ok(mbsa::examples::find(name)
            .map(|(_, text)| text.as_bytes().to_vec())
            .unwrap_or_default());
    }
    super::budget()
        .read_file(std::path::Path::new(file))
        .map_err(|e| super::input::read_failure(&format!("`{file}`"), e))
}

/// [`mbsa::report::json`] written as it is made: the JSON of 100 placements of a 10^5-body
/// linkage is 430 MB, which the text held on top of the placements.
fn emit_json<T: serde::Serialize>(value: &T) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
    let r = serde_json::to_writer_pretty(&mut out, &mbsa::report::Versioned::new(value))
        .map_err(|e| match e.io_error_kind() {
            Some(kind) => std::io::Error::from(kind),
            None => std::io::Error::other(e),
        })
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
    match r {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => Err(Failure::Input(format!("error: cannot write output: {e}"))),
    }
}
