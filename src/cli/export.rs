//! `mbsa cut` (the tree and the cut joints) and `mbsa export` (MJCF, SDFormat).

use super::analysis::{GeometryArg, GeometryArgs, input_error};
use super::{Failure, FileArg, OutputFormat, emit, load};
use clap::{Args, ValueEnum};
use mbsa::cut::{self, CutError, CutOptions};
use mbsa::export::{self, ExportError, ExportOptions, Target};

/// Options of `mbsa cut`.
#[derive(Args, Debug, Clone)]
pub struct CutArgs {
    #[command(flatten)]
    file: FileArg,
    #[command(flatten)]
    geometry: GeometryArgs,
    /// Output format.
    #[arg(long, value_enum, default_value_t = OutputFormat::Table)]
    format: OutputFormat,
}

/// `mbsa cut`.
pub fn cut(args: &CutArgs) -> Result<(), Failure> {
    let m = load(&args.file)?;
    args.geometry.closure_check(&args.file.file, &m)?;
    let opts = CutOptions {
        geometry: args.geometry.source(),
        precision: args.geometry.precision()?,
    };
    let r = cut::analyze_within(&m, &opts, &super::budget()).map_err(|e| match e {
        CutError::Motion(e) => input_error(&args.file, e),
        CutError::Budget(e) => super::budget_failure(&e),
    })?;
    emit(&match args.format {
        OutputFormat::Table => mbsa::report::cut::table(&r),
        OutputFormat::Json => mbsa::report::json(&r),
    })
}

/// Simulator formats `mbsa export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ToFormat {
    /// MuJoCo MJCF.
    Mjcf,
    /// SDFormat 1.7 (Gazebo).
    Sdf,
}

/// Options of `mbsa export`.
#[derive(Args, Debug, Clone)]
pub struct ExportArgs {
    #[command(flatten)]
    file: FileArg,
    /// The simulator format.
    #[arg(long, value_enum)]
    to: ToFormat,
    /// Write the model here (default: standard output).
    #[arg(short, long, value_name = "OUT")]
    output: Option<std::path::PathBuf>,
    /// Joint geometry written: `file` (the configuration written in the file; joints lacking
    /// theirs are named), `random` (a seeded generic realization of the joint types), or
    /// `auto` (the file's when every joint has it, else random).
    #[arg(long, value_enum, default_value_t = GeometryArg::File)]
    geometry: GeometryArg,
    /// Seed of the random realization.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// File geometry: how precisely its numbers are known (for the cuts' rank decisions).
    #[arg(long, value_name = "DELTA")]
    tolerance: Option<f64>,
}

/// `mbsa export`.
pub fn export(args: &ExportArgs) -> Result<(), Failure> {
    let m = load(&args.file)?;
    let geometry = GeometryArgs {
        geometry: args.geometry,
        seed: args.seed,
        tolerance: args.tolerance,
    };
    geometry.closure_check(&args.file.file, &m)?;
    let opts = ExportOptions {
        target: match args.to {
            ToFormat::Mjcf => Target::Mjcf,
            ToFormat::Sdf => Target::Sdf,
        },
        geometry: geometry.source(),
        precision: geometry.precision()?,
        source: args.file.file.clone(),
    };
    let e = export::export_within(&m, &opts, &super::budget()).map_err(|e| failure(args, e))?;
    for w in &e.warnings {
        eprintln!("warning: {w}");
    }
    match &args.output {
        Some(path) => {
            super::input::write_output(&args.file.file, path, &e.text)?;
            eprintln!(
                "exported {} ({}): {} loop(s) closed; written to {}",
                args.file.file,
                opts.target.name(),
                e.cuts.loops,
                path.display()
            );
            Ok(())
        }
        None => emit(&e.text),
    }
}

fn failure(args: &ExportArgs, e: ExportError) -> Failure {
    match e {
        ExportError::Motion(e) => input_error(&args.file, e),
        ExportError::Budget(e) => super::budget_failure(&e),
        e => {
            let help = e
                .help()
                .map(|h| format!("\n  help: {h}"))
                .unwrap_or_default();
            Failure::Input(format!("error: {}: {e}{help}", args.file.file))
        }
    }
}
