//! `mbsa analyze`, `mbsa dot` and `mbsa rigid`: the analyses over one FILE.

use super::{Failure, FileArg, OutputFormat, emit, keep_until_exit, load_with_inputs};
use clap::{Args, ValueEnum};
use mbsa::report::dot::View;
use mbsa::rigidity::{both as rigid_both, geometric};
use mbsa::structure::{self, Library, Method};

/// Options of the structural analysis shared by `analyze`, `dot` and `transform`.
#[derive(Args, Debug, Clone)]
pub struct StructureArgs {
    /// Replace the file's driven inputs: joint ids or body pairs, `:n` for n DOF (e.g. `1-2,1-13,13-15`).
    #[arg(long, value_name = "SPEC")]
    pub inputs: Option<String>,
    /// Pure counting, as the paper does: skip the rank check at random joint geometry.
    #[arg(long)]
    pub count_only: bool,
    /// Decomposition algorithm: `flow` (polynomial) or `exhaustive` (the paper's search; exponential, for reference).
    #[arg(long, value_enum, default_value_t = MethodArg::Flow)]
    pub method: MethodArg,
    /// Library of solvable group types: a TOML file `types = ["1R3D", ...]` (default: the built-in library).
    #[arg(long, value_name = "FILE")]
    pub library: Option<String>,
    #[command(flatten)]
    pub geometry: GeometryArgs,
}

/// Which joint geometry the analyses use: shared by every command that analyses.
#[derive(Args, Debug, Clone)]
pub struct GeometryArgs {
    /// Joint geometry: `auto` (the file's when every joint has it, else random), `file` (the
    /// configuration written in the file), or `random` (a seeded generic realization of the
    /// joint types).
    #[arg(long, value_enum, default_value_t = GeometryArg::Auto)]
    pub geometry: GeometryArg,
    /// Seed of the random realization (used when the geometry is random).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// File geometry: how precisely its numbers are known, e.g. 1e-4 for ±1e-4 (default: the
    /// file's `precision` key, else from the digits written: 0.7071 is known to ±5e-5; short
    /// numbers such as 2.5 are exact).
    #[arg(long, value_name = "DELTA")]
    pub tolerance: Option<f64>,
}

impl GeometryArgs {
    /// The geometry source these options ask for.
    pub fn source(&self) -> mbsa::geometry::GeometrySource {
        use mbsa::geometry::GeometrySource;
        match self.geometry {
            GeometryArg::Auto => GeometrySource::Auto { seed: self.seed },
            GeometryArg::File => GeometrySource::File,
            GeometryArg::Random => GeometrySource::Random { seed: self.seed },
        }
    }

    /// The closure check of a command about to use these options' geometry on `m`: nothing
    /// to say unless a joint carries `second` geometry (every other joint is closed by
    /// construction); then a warning on standard error when the file geometry is used and the
    /// configuration misses closure, and an input error (exit 2, the joint named) when it
    /// misses it grossly. The reports carry the closure section themselves.
    pub fn closure_check(&self, file: &str, m: &mbsa::Mechanism) -> Result<(), Failure> {
        if !m.joints.iter().any(|j| j.geometry.second.is_some()) {
            return Ok(());
        }
        match mbsa::geometry::choose(m, self.source(), self.precision()?) {
            Ok(used) => {
                if let Some(msg) = used.closure.as_ref().and_then(|c| c.message()) {
                    use std::io::Write;
                    let _ = writeln!(
                        std::io::stderr().lock(),
                        "warning: {file}: {msg}; first-order results use the first body's geometry of each joint"
                    );
                }
                Ok(())
            }
            Err(e @ mbsa::motion::MotionError::NotClosed { .. }) => {
                Err(Failure::Input(mbsa::diagnostic::render_plain(file, &e)))
            }
            // Other geometry errors are the analysis's to report.
            Err(_) => Ok(()),
        }
    }

    /// `--tolerance`, checked.
    pub fn precision(&self) -> Result<Option<f64>, Failure> {
        match self.tolerance {
            Some(t) if !(t.is_finite() && t >= 0.0) => Err(Failure::Input(format!(
                "error: --tolerance must be a finite number >= 0, not {t}"
            ))),
            t => Ok(t),
        }
    }
}

/// `--method` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Max flow + strongly connected components.
    Flow,
    /// The paper's smallest-first search (exponential).
    Exhaustive,
}

impl StructureArgs {
    /// The library options resolve to.
    pub fn library(&self) -> Result<Library, Failure> {
        match &self.library {
            None => Ok(Library::builtin()),
            Some(path) => {
                let what = format!("library `{path}`");
                let bytes = super::budget()
                    .read_file(std::path::Path::new(path))
                    .map_err(|e| super::input::read_failure(&what, e))?;
                let text = String::from_utf8(bytes).map_err(|e| {
                    Failure::Input(format!(
                        "error: cannot read {what}: not UTF-8 text (invalid byte at offset {})",
                        e.utf8_error().valid_up_to()
                    ))
                })?;
                Library::from_toml(&text)
                    .map_err(|e| Failure::Input(mbsa::diagnostic::render_plain(path, &e)))
            }
        }
    }

    /// The analysis options.
    pub fn options(&self) -> Result<structure::Options, Failure> {
        Ok(structure::Options {
            count_only: self.count_only,
            method: match self.method {
                MethodArg::Flow => Method::Flow,
                MethodArg::Exhaustive => Method::Exhaustive,
            },
            geometry: self.geometry.source(),
            precision: self.geometry.precision()?,
        })
    }
}

/// `mbsa analyze`.
pub fn analyze(file: &FileArg, args: &StructureArgs, format: OutputFormat) -> Result<(), Failure> {
    let m = load_with_inputs(file, args.inputs.as_deref())?;
    let lib = args.library()?;
    if !args.count_only {
        args.geometry.closure_check(&file.file, &m)?;
    }
    let mut a = structure_within(file, &m, args, &lib)?;
    structure::check_finite(
        &m,
        &mut a,
        args.geometry.precision()?,
        super::budget().max_work,
    );
    let out = match format {
        // Streamed: at 10^6 bodies the table is hundreds of megabytes.
        OutputFormat::Table => emit_with(|w| mbsa::report::structure::write_table(w, &a)),
        OutputFormat::Json => emit_json(&a),
    };
    keep_until_exit((m, a));
    out
}

/// [`emit`] of [`mbsa::report::json`], the same bytes, written as they are serialized: the
/// text of a 10^6-body analysis is over 100 MB, and held whole it was the largest allocation
/// after the analysis (with the copies of its growth).
fn emit_json<T: serde::Serialize>(value: &T) -> Result<(), Failure> {
    emit_with(|out| {
        serde_json::to_writer_pretty(&mut *out, &mbsa::report::Versioned::new(value))
            .map_err(std::io::Error::from)
            .and_then(|()| out.write_all(b"\n"))
    })
}

/// [`emit`] of the text `write` writes, through a buffer, as it is written (a closed pipe
/// ends the program quietly).
fn emit_with(
    write: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
    match write(&mut out).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => Err(Failure::Input(format!("error: cannot write output: {e}"))),
    }
}

/// `--view` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ViewArg {
    /// The structural diagram: one node per structural group, one row per level.
    Diagram,
    /// The structural graph: bodies clustered by group, edges in the direction DOF pass.
    Structure,
    /// The topological graph: bodies and joints.
    Topology,
    /// Rigid parts (geometric analysis): clusters per rigid part, redundant joints in red.
    Rigid,
}

/// `mbsa dot`.
pub fn dot(file: &FileArg, args: &StructureArgs, view: ViewArg) -> Result<(), Failure> {
    let mut m = load_with_inputs(file, args.inputs.as_deref())?;
    if !args.count_only || view == ViewArg::Rigid {
        args.geometry.closure_check(&file.file, &m)?;
    }
    if view == ViewArg::Rigid {
        // The same analysis as `mbsa rigid` (inputs not counted), so the picture's mobility
        // and redundancies are the numbers `rigid` prints.
        for j in &mut m.joints {
            j.driven = 0;
        }
        let opts = geometric::GeometricOptions {
            geometry: args.geometry.source(),
            precision: args.geometry.precision()?,
            check_finite: false,
        };
        let r = geometric_within(file, &m, &opts)?;
        return emit(&mbsa::report::dot::rigid(&m, &r));
    }
    let lib = args.library()?;
    let a = structure_within(file, &m, args, &lib)?;
    let view = match view {
        ViewArg::Diagram => View::Diagram,
        ViewArg::Structure => View::Structure,
        ViewArg::Topology => View::Topology,
        ViewArg::Rigid => View::Rigid,
    };
    let out = match view {
        // The diagram is written as it is made (tens of MB at 10^6 bodies, not held whole).
        View::Diagram => emit_with(|out| {
            let mut w = FmtToIo { out, error: None };
            mbsa::report::dot::write_diagram(&a, &mut w).map_err(|_| {
                w.error
                    .take()
                    .unwrap_or_else(|| std::io::Error::other("formatting failed"))
            })
        }),
        _ => emit(&mbsa::report::dot::render(view, &m, &a)),
    };
    keep_until_exit((m, a));
    out
}

/// A text sink ([`std::fmt::Write`]) over an output stream, keeping the stream's first error.
struct FmtToIo<'a> {
    out: &'a mut dyn std::io::Write,
    error: Option<std::io::Error>,
}

impl std::fmt::Write for FmtToIo<'_> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        if self.error.is_some() {
            return Err(std::fmt::Error);
        }
        self.out.write_all(s.as_bytes()).map_err(|e| {
            self.error = Some(e);
            std::fmt::Error
        })
    }
}

/// Which rigidity analyses `mbsa rigid` runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RigidMethod {
    /// Counting (pebble game) and geometry (constraint Jacobian rank).
    Both,
    /// Counting only: generic rigidity from the topology (pebble game).
    Counting,
    /// Geometry only: true mobility, redundant constraints, isolated DOF.
    Geometric,
}

/// Options of `mbsa rigid`.
#[derive(Args, Debug, Clone)]
pub struct RigidArgs {
    /// Which analyses to run.
    #[arg(long, value_enum, default_value_t = RigidMethod::Both)]
    pub method: RigidMethod,
    /// Count driven inputs as constraints (default: analyse the chain alone).
    #[arg(long)]
    pub with_inputs: bool,
    /// Also the finite mobility at the file's configuration: the local dimension of the
    /// solution set (first-order motions followed and projected back), telling a mechanism
    /// that really moves from one that only wiggles at a singular pose.
    #[arg(long)]
    pub finite: bool,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Replace the file's driven inputs (with `--with-inputs`).
    #[arg(long, value_name = "SPEC")]
    pub inputs: Option<String>,
}

/// `--geometry` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum GeometryArg {
    /// The file's geometry when every joint has its fields, else a random realization.
    Auto,
    /// The file's geometry (an error names a joint lacking a field).
    File,
    /// A random generic realization of the joint types.
    Random,
}

/// A joint-model error of FILE, rendered (exit 2).
pub fn input_error(file: &FileArg, e: mbsa::motion::MotionError) -> Failure {
    Failure::Input(mbsa::diagnostic::render_plain(&file.file, &e))
}

/// The structural analysis within this run's budget (the exhaustive search stops at the work
/// limit, exit code 2).
fn structure_within(
    file: &FileArg,
    m: &mbsa::mechanism::Mechanism,
    args: &StructureArgs,
    lib: &Library,
) -> Result<structure::Analysis, Failure> {
    structure::analyze_within(m, &args.options()?, lib, &super::budget()).map_err(|e| match e {
        structure::AnalyzeError::Motion(e) => input_error(file, e),
        structure::AnalyzeError::Budget(e) => super::budget_failure(&e),
    })
}

/// The geometric analysis within this run's budget (a budget error exits with code 2).
fn geometric_within(
    file: &FileArg,
    m: &mbsa::mechanism::Mechanism,
    opts: &geometric::GeometricOptions,
) -> Result<geometric::GeometricReport, Failure> {
    geometric::analyze_within(m, opts, &super::budget()).map_err(|e| match e {
        geometric::GeometricError::Motion(e) => input_error(file, e),
        geometric::GeometricError::Budget(e) => super::budget_failure(&e),
    })
}

/// `mbsa rigid`.
pub fn rigid(file: &FileArg, args: &RigidArgs, format: OutputFormat) -> Result<(), Failure> {
    let mut m = load_with_inputs(file, args.inputs.as_deref())?;
    if !args.with_inputs {
        for j in &mut m.joints {
            j.driven = 0;
        }
    }
    // The closure of the file's configuration, for the geometric analysis or the finite test
    // (a warning, or an error when grossly open).
    if args.method != RigidMethod::Counting || args.finite {
        args.geometry.closure_check(&file.file, &m)?;
    }
    let opts = rigid_both::RigidOptions {
        methods: match args.method {
            RigidMethod::Both => rigid_both::Methods::Both,
            RigidMethod::Counting => rigid_both::Methods::Counting,
            RigidMethod::Geometric => rigid_both::Methods::Geometric,
        },
        with_inputs: args.with_inputs,
        finite: args.finite,
        geometry: args.geometry.source(),
        precision: args.geometry.precision()?,
        budget: super::budget(),
    };
    let r = rigid_both::analyze(&m, &opts).map_err(|e| match e {
        rigid_both::RigidError::Motion(e) => input_error(file, e),
        rigid_both::RigidError::Budget(e) => super::budget_failure(&e),
        e => Failure::Input(format!("error: {}: {e}", file.file)),
    })?;
    emit(&match format {
        OutputFormat::Json => mbsa::report::rigid::json(&r),
        OutputFormat::Table => mbsa::report::rigid::table(&r),
    })
}
