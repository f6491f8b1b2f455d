//! `mbsa check`: validate files and compare their `[expect]` tables.

use super::input::{self, Unreadable};
use super::{Failure, emit};
use clap::{Args, ValueEnum};
use mbsa::transform::shard::{ShardKind, ShardSpec, fnv1a};
use serde::Serialize;
use std::fmt::Write;

/// The arguments of `mbsa check`.
#[derive(Args, Debug, Clone)]
pub struct CheckArgs {
    /// Files to check (paths, `-`, or `@name`; `@all` checks every bundled example).
    #[arg(required_unless_present = "files_from", value_name = "FILE")]
    files: Vec<String>,
    /// Also check the files listed in LIST, one per line (`-`: standard input).
    #[arg(long, value_name = "LIST")]
    files_from: Option<String>,
    /// Output format: `text` for people, `json` one document, `jsonl` one record per file.
    #[arg(long, value_enum, default_value_t = CheckFormat::Text)]
    format: CheckFormat,
    /// Format of standard input (default: sniffed).
    #[arg(long, value_enum)]
    input_format: Option<input::InputFormat>,
    #[command(flatten)]
    geometry: super::analysis::GeometryArgs,
    /// Check only shard M of N of the files: `hash:M/N` (by a hash of each file's content)
    /// or `slice:M/N` (by its position in the list). docs/sharding.md.
    #[arg(long, value_name = "hash:M/N|slice:M/N", value_parser = super::transform::parse_partition)]
    partition: Option<ShardSpec>,
}

/// Output formats of `mbsa check`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CheckFormat {
    /// A line per file (and per mismatch) for people.
    Text,
    /// One JSON document with a record per file (docs/json.md).
    Json,
    /// One JSON record per file and line, written as each file is checked.
    Jsonl,
}

/// One file's result, as `--format json` and `jsonl` write it.
#[derive(Serialize)]
struct Record<'a> {
    file: &'a str,
    ok: bool,
    expect_table: bool,
    checks: Vec<Check>,
    mismatches: Vec<Check>,
    error: Option<ErrorAt>,
}

/// One expectation: the value written in the file and the value the analyses found.
#[derive(Clone, Serialize)]
struct Check {
    key: &'static str,
    expected: String,
    found: String,
    ok: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    note: Option<String>,
}

/// Why a file could not be checked, and where.
#[derive(Serialize)]
struct ErrorAt {
    file: String,
    line: Option<usize>,
    col: Option<usize>,
    message: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    help: Option<String>,
}

/// `--format json`: the records and their counts.
#[derive(Serialize)]
struct Document<'a> {
    ok: bool,
    files: Vec<Record<'a>>,
    checked: usize,
    failed: usize,
    unreadable: usize,
}

/// Check every file; exit 2 if any cannot be read, else 1 if any expectation fails.
pub fn run(args: &CheckArgs) -> Result<(), Failure> {
    let opts = mbsa::rigidity::geometric::GeometricOptions {
        geometry: args.geometry.source(),
        precision: args.geometry.precision()?,
        check_finite: false,
    };
    let mut names = names(args)?;
    if let Some(spec) = args.partition {
        names = shard_of(names, spec);
    }
    let (mut failed, mut broken, mut records) = (0usize, Vec::new(), Vec::new());
    for name in &names {
        let checked = check_one(name, args, &opts);
        if let Some(e) = checked.rendered_error {
            broken.push(e);
        } else if !checked.record.ok {
            failed += 1;
        }
        match args.format {
            CheckFormat::Text => emit(&checked.text)?,
            CheckFormat::Jsonl => emit(&mbsa::report::json::jsonl(&checked.record))?,
            CheckFormat::Json => records.push(checked.record),
        }
    }
    if args.format == CheckFormat::Json {
        emit(&mbsa::report::json(&Document {
            ok: failed == 0 && broken.is_empty(),
            files: records,
            checked: names.len(),
            failed,
            unreadable: broken.len(),
        }))?;
    }
    if !broken.is_empty() {
        return Err(Failure::Input(broken.join("\n")));
    }
    if failed > 0 {
        if args.format == CheckFormat::Text {
            emit(&format!(
                "{failed} of {} file(s) failed their expectations\n",
                names.len()
            ))?;
        }
        return Err(Failure::Check);
    }
    Ok(())
}

/// The files to check, `@all` expanded, `--files-from` appended. Standard input can be read
/// once only: a second `-` is refused before anything is read.
fn names(args: &CheckArgs) -> Result<Vec<String>, Failure> {
    let stdin_uses = args.files.iter().filter(|f| *f == "-").count()
        + usize::from(args.files_from.as_deref() == Some("-"));
    let repeated = || {
        Failure::Input(
            "error: standard input (`-`) is given more than once; it can be read once\n  help: save one of the inputs to a file".into(),
        )
    };
    if stdin_uses > 1 {
        return Err(repeated());
    }
    let mut given = args.files.clone();
    if let Some(list) = &args.files_from {
        let listed = read_list(list)?;
        if listed.is_empty() && given.is_empty() {
            return Err(Failure::Input(format!(
                "error: no files to check: the list in `{list}` is empty"
            )));
        }
        if stdin_uses + listed.iter().filter(|f| *f == "-").count() > 1 {
            return Err(repeated());
        }
        given.extend(listed);
    }
    let mut names = Vec::new();
    for f in given {
        if f == "@all" {
            names.extend(mbsa::examples::names().map(|n| format!("@{n}")));
        } else {
            names.push(f);
        }
    }
    Ok(names)
}

/// The files of shard `spec`: by position, or by the hash of each file's bytes (of its name
/// where it cannot be read, or is standard input, which is read once).
fn shard_of(names: Vec<String>, spec: ShardSpec) -> Vec<String> {
    let hash = |name: &str| {
        if spec.kind == ShardKind::Slice {
            return 0;
        }
        let bytes = match name.strip_prefix('@') {
            Some(n) => mbsa::examples::find(n).map(|(_, text)| text.as_bytes().to_vec()),
            None if name == "-" => None,
            None => super::budget().read_file(std::path::Path::new(name)).ok(),
        };
        fnv1a(bytes.as_deref().unwrap_or(name.as_bytes()))
    };
    names
        .into_iter()
        .enumerate()
        .filter(|(i, name)| spec.keeps(hash(name), *i as u64))
        .map(|(_, name)| name)
        .collect()
}

/// The non-empty lines of LIST (a path, or `-` for standard input).
fn read_list(list: &str) -> Result<Vec<String>, Failure> {
    let budget = super::budget();
    let bytes = if list == "-" {
        budget.read_to_end(std::io::stdin().lock(), "standard input")
    } else {
        budget.read_file(std::path::Path::new(list))
    }
    .map_err(|e| input::read_failure(&format!("--files-from `{list}`"), e))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        Failure::Input(format!(
            "error: --files-from `{list}` is not UTF-8 (byte {})",
            e.utf8_error().valid_up_to()
        ))
    })?;
    Ok(text
        .lines()
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .filter(|l| !l.trim().is_empty())
        .map(String::from)
        .collect())
}

/// One file's record, its text lines, and its rendered error if it could not be read.
struct Checked<'a> {
    record: Record<'a>,
    text: String,
    rendered_error: Option<String>,
}

/// Load and check one file.
fn check_one<'a>(
    name: &'a str,
    args: &CheckArgs,
    opts: &mbsa::rigidity::geometric::GeometricOptions,
) -> Checked<'a> {
    let loaded = input::load_path_located(name, args.input_format).and_then(|m| {
        args.geometry
            .closure_check(name, &m)
            .map_err(Unreadable::from)
            .map(|()| m)
    });
    let m = match loaded {
        Ok(m) => m,
        Err(u) => {
            let (file, line, col) = match u.at {
                Some((f, l, c)) => (f, Some(l), Some(c)),
                None => (name.to_string(), None, None),
            };
            let record = Record {
                file: name,
                ok: false,
                expect_table: false,
                checks: Vec::new(),
                mismatches: Vec::new(),
                error: Some(ErrorAt {
                    file,
                    line,
                    col,
                    message: u.message,
                    help: u.help,
                }),
            };
            return Checked {
                record,
                text: String::new(),
                rendered_error: Some(u.rendered),
            };
        }
    };
    let outcomes = mbsa::expect::evaluate(&m, opts);
    let checks: Vec<Check> = outcomes
        .iter()
        .map(|o| Check {
            key: o.key,
            expected: o.expected.clone(),
            found: o.actual.clone(),
            ok: o.ok,
            note: o.note.clone(),
        })
        .collect();
    let mismatches: Vec<Check> = checks.iter().filter(|c| !c.ok).cloned().collect();
    let text = text_of(name, &checks, m.expect.written);
    Checked {
        record: Record {
            file: name,
            ok: mismatches.is_empty(),
            expect_table: !checks.is_empty() || m.expect.written,
            checks,
            mismatches,
            error: None,
        },
        text,
        rendered_error: None,
    }
}

/// The text lines of one checked file.
fn text_of(name: &str, checks: &[Check], written: bool) -> String {
    let mut text = String::new();
    if checks.iter().all(|c| c.ok) {
        let summary: Vec<String> = checks
            .iter()
            .map(|c| format!("{} {}", c.key, c.found))
            .collect();
        let summary = if summary.is_empty() && written {
            "valid (empty [expect] table: nothing checked)".to_string()
        } else if summary.is_empty() {
            "valid (no [expect] table)".to_string()
        } else {
            summary.join(", ")
        };
        let _ = writeln!(text, "ok      {name}: {summary}");
        for c in checks {
            if let Some(n) = &c.note {
                let _ = writeln!(text, "        note: {}: {n}", c.key);
            }
        }
    } else {
        let _ = writeln!(text, "FAILED  {name}:");
        for c in checks {
            let mark = if c.ok { "ok" } else { "MISMATCH" };
            let _ = writeln!(
                text,
                "        {mark:<8} {}: expected {}, got {}",
                c.key, c.expected, c.found
            );
            if let Some(n) = &c.note {
                let _ = writeln!(text, "                 note: {n}");
            }
        }
    }
    text
}
