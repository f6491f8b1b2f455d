//! Command-line interface: argument parsing, input loading, output and exit codes.
//!
//! Exit codes: 0 success, 1 a check failed, 2 usage or input error.

mod analysis;
mod check;
mod completions;
mod export;
mod generate;
mod input;
mod position;
mod repair;
mod report;
mod schema;
mod transform;

use clap::{Parser, Subcommand, ValueEnum};
use mbsa::budget::Budget;
use std::io::{IsTerminal, Write};
use std::process::ExitCode;

pub use input::{FileArg, load};

/// Structural analysis of multibody systems: mobility, structural groups, input placements
/// and rigid subsystems of mechanisms written as TOML, YAML or JSON files.
#[derive(Parser, Debug)]
#[command(name = "mbsa", version = env!("MBSA_VERSION"), about, long_about = None, propagate_version = true)]
#[command(
    after_help = "Examples:\n  mbsa examples\n  mbsa mobility @rotor\n  mbsa check mechanisms/*.toml\n\nFILE is a path, `-` for standard input, or `@name` for a bundled example."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    #[command(flatten)]
    budget: BudgetArgs,
}

/// The budget flags, accepted by every command (`mbsa::budget`, docs/reliability.md).
#[derive(clap::Args, Debug, Clone)]
pub struct BudgetArgs {
    /// Scale every limit of the budget (input size, work, memory) by X, e.g. `--budget 10`.
    #[arg(long, global = true, value_name = "X", value_parser = parse_scale)]
    budget: Option<f64>,
    /// Largest input file accepted, in bytes (default 268435456 = 256 MiB).
    #[arg(long, global = true, value_name = "N")]
    max_input_bytes: Option<u64>,
    /// Most work units one analysis may spend (default 10^11, minutes of work).
    #[arg(long, global = true, value_name = "N")]
    max_work: Option<u64>,
    /// Largest memory estimate one step may allocate, in bytes (default 4294967296 = 4 GiB).
    #[arg(long, global = true, value_name = "N")]
    max_memory: Option<u64>,
}

fn parse_scale(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("`{s}` is not a positive number")),
    }
}

impl BudgetArgs {
    /// The budget the flags give.
    pub fn budget(&self) -> Budget {
        let mut b = Budget::DEFAULT.scaled(self.budget.unwrap_or(1.0));
        if let Some(n) = self.max_input_bytes {
            b.max_input_bytes = n;
        }
        if let Some(n) = self.max_work {
            b.max_work = n;
        }
        if let Some(n) = self.max_memory {
            b.max_memory_bytes = n;
        }
        b
    }
}

static BUDGET: std::sync::OnceLock<Budget> = std::sync::OnceLock::new();

/// The budget of this run (the flags', else the default).
pub fn budget() -> Budget {
    BUDGET.get().copied().unwrap_or_default()
}

/// Render a budget error (exit code 2).
pub fn budget_failure(e: &mbsa::budget::BudgetExceeded) -> Failure {
    Failure::Input(format!("error: {e}\n  help: {}", e.help()))
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Structural analysis: the structural groups, their solve levels and types.
    ///
    /// Splits the mechanism into structural groups (the smallest kinematically determined
    /// chains) by max flow and strongly connected components, orders them in levels that can
    /// be solved in parallel, and prints the paper's Table 8 columns (type, pairs that bring
    /// DOF in, internal pairs, pairs that hand DOF on) and the library coverage of each type.
    /// A rank check at random joint geometry catches what counting misses (isolated spins,
    /// redundant equations); when the inputs do not determine the mechanism, it says which
    /// part is over- or under-determined and where an input would help.
    #[command(
        after_help = "Examples:\n  mbsa analyze @rotor\n  mbsa analyze @rotor --inputs 1-2,1-13,13-15\n  mbsa analyze @micro-manipulator --count-only\n  mbsa analyze my-robot.yaml --format json"
    )]
    Analyze {
        #[command(flatten)]
        file: FileArg,
        #[command(flatten)]
        structure: analysis::StructureArgs,
        /// Output format.
        #[arg(long, value_enum, default_value_t = OutputFormat::Table)]
        format: OutputFormat,
    },
    /// Graphviz DOT of the kinematic structure (pipe into `dot -Tsvg`).
    ///
    /// Views: `diagram` (the paper's structural diagram: one node per group, one row per
    /// level), `structure` (bodies clustered by group, edges in the direction DOF pass, driven
    /// joints bold) and `topology` (bodies and joints). Parts the analysis cannot determine are
    /// coloured, with a legend.
    #[command(
        after_help = "Examples:\n  mbsa dot @rotor | dot -Tsvg > rotor.svg\n  mbsa dot @rotor --view structure | dot -Tpng > rotor.png"
    )]
    Dot {
        #[command(flatten)]
        file: FileArg,
        /// Which picture.
        #[arg(long, value_enum, default_value_t = analysis::ViewArg::Diagram)]
        view: analysis::ViewArg,
        #[command(flatten)]
        structure: analysis::StructureArgs,
    },
    /// Rigid subsystems: generic rigidity by counting and true mobility from the geometry.
    ///
    /// Counting (pebble game on the body-bar graph) gives maximal rigid components,
    /// overconstrained regions and the generic DOF from the topology alone. The geometric
    /// analysis (rank of the constraint Jacobian at the file's geometry, or at a random
    /// realization of the joint types when the file has none) gives the true instantaneous
    /// mobility, the redundant constraints and the joints involved, isolated freedoms (a bar
    /// spinning between two spherical joints) and the rigid clusters.
    #[command(
        after_help = "Examples:\n  mbsa rigid @rig-double-banana\n  mbsa rigid @rig-stacked-four-bars --method counting\n  mbsa rigid frame.toml --geometry random --seed 7 --format json"
    )]
    Rigid {
        #[command(flatten)]
        file: FileArg,
        #[command(flatten)]
        rigid: analysis::RigidArgs,
        /// Output format.
        #[arg(long, value_enum, default_value_t = OutputFormat::Table)]
        format: OutputFormat,
    },
    /// One self-contained HTML page of the analyses: summary, groups, diagram, rigid parts, motion.
    ///
    /// Writes the summary (mobility, true mobility, status, diagnosis), the group table, the
    /// structural diagram and the rigid parts as inline SVG, and, where the file has joint
    /// geometry, the mechanism drawn in projection and animated through a sweep of its first
    /// driven input (slider and play button). No network, no Graphviz: one file to open in a
    /// browser. The same input gives the same bytes. docs/report.md.
    #[command(
        after_help = "Examples:\n  mbsa report @rig-bennett -o bennett.html\n  mbsa report cassie.xml -o cassie.html\n  mbsa report @rotor > rotor.html"
    )]
    Report {
        #[command(flatten)]
        file: FileArg,
        /// Write the page here (default: standard output).
        #[arg(short, long, value_name = "OUT.html")]
        output: Option<std::path::PathBuf>,
        #[command(flatten)]
        structure: analysis::StructureArgs,
    },
    /// Repair: the joint changes that make the model simulate, its motion unchanged.
    ///
    /// At the file's configuration: relaxes joints (R -> C, U, S, SC, ...) whose removed
    /// constraint rows are implied by the others (redundant constraints), and stiffens a ball
    /// into a universal joint where a rod or part spins about the line through its balls
    /// (isolated freedoms). Each candidate is checked by analysing the changed model again:
    /// no redundant constraint, the same proper and finite mobility. `--apply N` writes the
    /// repaired file, each changed joint with a comment. docs/repair.md.
    #[command(
        after_help = "Examples:\n  mbsa repair @rig-planar-four-bar-3d\n  mbsa repair @bricard --format json\n  mbsa repair cassie.xml --apply 1 -o cassie-repaired.toml"
    )]
    Repair {
        #[command(flatten)]
        file: FileArg,
        #[command(flatten)]
        args: repair::RepairArgs,
    },
    /// Loop cuts: a spanning tree from the frame and the joints cut to open every loop.
    ///
    /// For a tree-based simulator: grows a spanning tree of the joint graph from the frame
    /// (driven joints first, spherical joints last, the joint order within each), cuts the
    /// joints that would close loops (at a spherical joint where a loop has one), exchanges a
    /// cut whose closure rows repeat other loops' when another joint of its loop gives
    /// independent ones, and prints each cut's loop, its closure rows and how many are
    /// redundant, at the file's geometry or a random one. The same file gives the same cuts.
    /// docs/cut.md.
    #[command(
        after_help = "Examples:\n  mbsa cut @bricard\n  mbsa cut @stewart --format json\n  mbsa cut cassie.xml"
    )]
    Cut(export::CutArgs),
    /// Write the model for a simulator: MJCF (MuJoCo) or SDFormat (Gazebo).
    ///
    /// The tree of `mbsa cut` as nested bodies and the cut joints as closures (MJCF: a ball
    /// as <connect>, any other joint as a light body with its joints welded to the other
    /// side; SDFormat: the loop joints directly), the driven inputs as actuators, the file's
    /// configuration as the reference pose (MJCF keyframe `file`), unit masses. A joint kind
    /// with several freedoms becomes several joints composed in order; gears, cams, rolling
    /// and point contacts are refused by name. Redundant closure rows are said on standard
    /// error and in the file. Reading the file back (`mbsa import`) gives the same analysis.
    #[command(
        after_help = "Examples:\n  mbsa export @bricard --to mjcf -o bricard.xml\n  mbsa export four_bar.sdf --to mjcf\n  mbsa export @stewart --to mjcf --geometry random --seed 1 -o stewart.xml\n  mbsa export robot.toml --to sdf -o robot.sdf"
    )]
    Export(export::ExportArgs),
    /// Structural transformations: every placement of the driven inputs that determines the mechanism, ranked.
    ///
    /// Enumerates the placements of f driven DOF over the joints' DOF (f = the mobility count
    /// less isolated spins) that make the mechanism kinematically determined, as bases of a
    /// matroid (incremental matching, pruning as soon as a partial placement over-determines
    /// a part), checks each with the structural analysis (placements the rank check rejects are
    /// excluded and counted), groups placements with the same partition into families and
    /// ranks them. A floating base (a free joint, its part's only joint to the frame, as an
    /// imported robot's) is taken as driven in full, its pose given; the output names it.
    /// `--inputs SPEC` instead compares one placement with the file's own.
    #[command(
        after_help = "Examples:\n  mbsa transform @rotor\n  mbsa transform @rotor --inputs 1-2,1-13,13-15\n  mbsa transform @stewart --on P,F --top 5\n  mbsa transform cassie.xml --limit 50\n  mbsa transform @stewart --fix-base\n  mbsa transform @micro-manipulator --grounded --format jsonl > placements.jsonl\n  mbsa transform @stewart --partition hash:1/4 --format jsonl > shard1.jsonl"
    )]
    Transform {
        #[command(flatten)]
        file: FileArg,
        #[command(flatten)]
        structure: analysis::StructureArgs,
        #[command(flatten)]
        transform: transform::TransformArgs,
    },
    /// Merge the shards of `transform --partition` into the unsharded run's output.
    ///
    /// Reads the JSON-lines shards that `mbsa transform FILE --partition hash:M/N --format
    /// jsonl` wrote (any order), refuses shards of different inputs or a partition with a
    /// shard missing or given twice, and writes what `mbsa transform FILE` writes with the
    /// same options: the same ranking, families and counts, byte for byte. docs/sharding.md.
    #[command(
        after_help = "Example (four shards, one after the other, then their merge):\n  for i in 1 2 3 4; do mbsa transform @stewart --partition hash:$i/4 --format jsonl > shard$i.jsonl; done\n  mbsa merge shard*.jsonl --format json > ranked.json"
    )]
    Merge(transform::MergeArgs),
    /// Positions: every body's pose for given input values, group by group.
    ///
    /// Solves the position equations of the joints (the file's geometry is the reference
    /// configuration, value 0 of every joint) for the values given with `--set`, group by
    /// group in the level order of the structural analysis (groups of one level in
    /// parallel), each by Gauss-Newton from the file's configuration. `--sweep` traces a
    /// motion and stops at a dead point or branch change; `--format toml` writes the
    /// mechanism at the solved configuration. `--inputs` replaces the file's driven inputs
    /// (as for `analyze`); a joint given a value with `--set` is driven too.
    #[command(
        after_help = "Examples:\n  mbsa solve @slider-crank-geometry --set O=30\n  mbsa solve @slider-crank-geometry --sweep O=0..360:30\n  mbsa solve @rig-bennett --set A=20 --format json\n  mbsa solve @rig-bennett --set A=20 --format toml > moved.toml\n  mbsa solve gripper.xml --inputs left_driver_joint,right_driver_joint --set left_driver_joint=10"
    )]
    Solve {
        #[command(flatten)]
        file: FileArg,
        #[command(flatten)]
        args: position::SolveArgs,
    },
    /// Close a configuration: project it onto the joint constraints and write the mechanism file.
    ///
    /// Gauss-Newton with minimum-norm steps (least change) from the file's configuration or
    /// from `--poses`; writes the mechanism with its joint geometry at the closed
    /// configuration, with the residuals before and after in a comment.
    #[command(
        after_help = "Example:\n  mbsa assemble robot.toml --poses keyframe.json > closed.toml"
    )]
    Assemble {
        #[command(flatten)]
        file: FileArg,
        #[command(flatten)]
        args: position::AssembleArgs,
    },
    /// Convert a simulator model (MJCF, SDFormat, URDF, OpenSim) into a mechanism file.
    ///
    /// Writes a format-v1 TOML file: the bodies (bodies welded together merged), the joints
    /// with their origins and axes in one world frame at the chosen configuration, the driven
    /// DOF from the actuators, and comments that point back to the source elements. What is
    /// not representable is listed in one warning block on standard error. The analysing
    /// commands also read these model files directly (`mbsa analyze robot.urdf`).
    #[command(
        after_help = "Examples:\n  mbsa import cassie.xml -o cassie.toml\n  mbsa import cassie.xml --keyframe home\n  mbsa import four_bar.sdf --merge-pins\n  mbsa import model.txt --from urdf"
    )]
    Import {
        /// Model file (.xml/.mjcf, .sdf/.world, .urdf, .osim) or `-` for standard input.
        #[arg(value_name = "FILE")]
        file: String,
        /// Write the mechanism file here (default: standard output).
        #[arg(short, long, value_name = "OUT.toml")]
        output: Option<std::path::PathBuf>,
        #[command(flatten)]
        import: input::ImportArgs,
    },
    /// Write a generated mechanism file (benchmark families) to standard output.
    #[command(subcommand)]
    Generate(generate::Family),
    /// Mobility count (Chebyshev-Gruebler-Kutzbach) and connectivity.
    ///
    /// Computes f = B·Nm − Σ(B − k) over the binary pairs (a multiple joint of n bodies counts
    /// n − 1 pairs), compares it with the driven inputs, counts independent loops and lists
    /// bodies not linked to the frame.
    #[command(
        after_help = "Example:\n  mbsa mobility @rotor\n  mbsa mobility my-linkage.toml --format json"
    )]
    Mobility {
        #[command(flatten)]
        file: FileArg,
        /// Replace the file's driven inputs: joint ids or body pairs, `:n` for n DOF (e.g. `1-2,1-13,A:2`).
        #[arg(long, value_name = "SPEC")]
        inputs: Option<String>,
        /// Output format.
        #[arg(long, value_enum, default_value_t = OutputFormat::Table)]
        format: OutputFormat,
    },
    /// Validate mechanism files and compare their `[expect]` tables with the analyses.
    ///
    /// Exit code 0 when every file is valid and meets its expectations, 1 when an expectation
    /// fails (expected and actual values are printed), 2 when a file cannot be read.
    #[command(
        after_help = "Examples:\n  mbsa check @rotor\n  mbsa check mechanisms/*.toml\n  git ls-files '*.toml' | mbsa check --files-from -\n  mbsa check @all --format jsonl"
    )]
    Check(check::CheckArgs),
    /// Print a shell completion script (bash, zsh, fish, powershell, elvish).
    #[command(
        after_help = "Examples:\n  mbsa completions bash > ~/.local/share/bash-completion/completions/mbsa\n  mbsa completions zsh > ~/.zfunc/_mbsa\n  mbsa completions fish > ~/.config/fish/completions/mbsa.fish"
    )]
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff) of mbsa or of one command.
    #[command(
        after_help = "Examples:\n  mbsa man | man -l -\n  mbsa man check > ~/.local/share/man/man1/mbsa-check.1"
    )]
    Man {
        /// The command (default: mbsa itself).
        #[arg(value_name = "COMMAND")]
        command: Option<String>,
    },
    /// List the bundled example mechanisms (use them as `@name`).
    #[command(after_help = "Example:\n  mbsa examples\n  mbsa mobility @stewart")]
    Examples,
    /// List the joint catalogue: codes, long names, grades, where each is valid.
    #[command(after_help = "Example:\n  mbsa joints")]
    Joints,
    /// Print the JSON Schema of the mechanism file format (for editor completion) or of a report.
    ///
    /// Save it and point your editor at it: in TOML with a `#:schema ./mbsa.schema.json` first
    /// line (taplo, Even Better TOML); in YAML with `# yaml-language-server: $schema=./mbsa.schema.json`.
    /// `--output REPORT` prints the schema of that command's `--format json` output instead.
    #[command(
        after_help = "Examples:\n  mbsa schema > mbsa.schema.json\n  mbsa schema --output analyze > analyze.schema.json"
    )]
    Schema {
        /// Which schema: the input file format, or a report.
        #[arg(long, value_enum, value_name = "WHAT", default_value_t = schema::Output::Input)]
        output: schema::Output,
    },
}

/// Output format of the reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    /// A table for people.
    Table,
    /// JSON (documented keys, stable order).
    Json,
}

/// Why a command did not succeed.
pub enum Failure {
    /// An input or usage error, already rendered (exit code 2).
    Input(String),
    /// A check failed (exit code 1); the report was already written.
    Check,
}

/// Parse arguments, run, map the result to an exit code.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Check) => ExitCode::from(1),
        Err(Failure::Input(msg)) => {
            let mut err = std::io::stderr().lock();
            let _ = err.write_all(msg.as_bytes());
            if !msg.ends_with('\n') {
                let _ = err.write_all(b"\n");
            }
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<(), Failure> {
    let _ = BUDGET.set(cli.budget.budget());
    match cli.command {
        Command::Analyze {
            file,
            structure,
            format,
        } => analysis::analyze(&file, &structure, format),
        Command::Dot {
            file,
            view,
            structure,
        } => analysis::dot(&file, &structure, view),
        Command::Rigid {
            file,
            rigid,
            format,
        } => analysis::rigid(&file, &rigid, format),
        Command::Report {
            file,
            output,
            structure,
        } => report::run(&file, &structure, output.as_deref()),
        Command::Transform {
            file,
            structure,
            transform,
        } => transform::run(&file, &structure, &transform),
        Command::Merge(args) => transform::merge(&args),
        Command::Repair { file, args } => repair::run(&file, &args),
        Command::Cut(args) => export::cut(&args),
        Command::Export(args) => export::export(&args),
        Command::Solve { file, args } => position::solve(&file, &args),
        Command::Assemble { file, args } => position::assemble(&file, &args),
        Command::Generate(family) => generate::run(&family),
        Command::Import {
            file,
            output,
            import,
        } => {
            let result = input::import(&file, &import)?;
            let m = &result.mechanism;
            let mut summary = format!(
                "imported {} ({}): {} bodies, {} joints, {} driven DOF",
                file,
                result.format.name(),
                m.bodies.len(),
                m.joints.len(),
                m.inputs()
            );
            if import.merge_pins {
                summary.push_str(&format!("; {} pin joint(s) merged", result.merged_pins));
            }
            if import.merge_balls {
                summary.push_str(&format!(
                    "; {} ball joint(s) made of revolute triples",
                    result.merged_balls
                ));
            }
            match output {
                Some(path) => {
                    input::write_output(&file, &path, &result.toml)?;
                    eprintln!("{summary}; written to {}", path.display());
                    Ok(())
                }
                None => {
                    eprintln!("{summary}");
                    emit(&result.toml)
                }
            }
        }
        Command::Mobility {
            file,
            inputs,
            format,
        } => {
            let m = load_with_inputs(&file, inputs.as_deref())?;
            let r = mbsa::mobility::mobility(&m);
            let out = emit(&match format {
                OutputFormat::Table => {
                    mbsa::report::mobility::table(&r, mbsa::motion::has_geometry(&m))
                }
                OutputFormat::Json => mbsa::report::json(&r),
            });
            keep_until_exit((m, r));
            out
        }
        Command::Check(args) => check::run(&args),
        Command::Examples => {
            let width = mbsa::examples::names().map(str::len).max().unwrap_or(0) + 1;
            let mut text = String::new();
            for (name, _, toml) in mbsa::examples::EXAMPLES {
                let summary = mbsa::examples::summary(toml);
                text.push_str(&format!("{:<width$}  {summary}\n", format!("@{name}")));
            }
            text.push_str("\nUse one as FILE, e.g. `mbsa analyze @rotor`.\n");
            emit(&text)
        }
        Command::Completions { shell } => completions::completions(shell),
        Command::Man { command } => completions::man(command.as_deref()),
        Command::Joints => emit(&mbsa::report::joints_table()),
        Command::Schema { output } => schema::run(output),
    }
}

/// Load FILE and apply an `--inputs` spec if given.
pub fn load_with_inputs(file: &FileArg, inputs: Option<&str>) -> Result<mbsa::Mechanism, Failure> {
    let mut m = load(file)?;
    if let Some(spec) = inputs {
        apply_inputs(&mut m, spec)?;
    }
    Ok(m)
}

/// Apply an `--inputs` spec, rendering its errors.
pub fn apply_inputs(m: &mut mbsa::Mechanism, spec: &str) -> Result<(), Failure> {
    mbsa::InputSpec::parse_in(spec, m)
        .and_then(|s| m.apply_inputs(&s))
        .map_err(|e| Failure::Input(mbsa::diagnostic::render_plain("--inputs", &e)))
}

/// Leave `value` to the end of the process instead of freeing it: the command returns and
/// the process exits next, and freeing the structures of a 10^5-body mechanism one by one
/// costs tens of milliseconds for nothing.
pub fn keep_until_exit<T>(value: T) {
    std::mem::forget(value);
}

/// Write to standard output. A closed pipe (`| head`) ends the program quietly.
pub fn emit(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => Err(Failure::Input(format!("error: cannot write output: {e}"))),
    }
}

/// Whether diagnostics on standard error may use colour.
pub fn color_stderr() -> bool {
    std::env::var_os("NO_COLOR").is_none() && std::io::stderr().is_terminal()
}
