//! FILE arguments: a path, `-` (standard input) or `@name` (a bundled example).

use super::Failure;
use clap::{Args, ValueEnum};
use mbsa::budget::ReadError;
use mbsa::format::Format;
use std::path::Path;

/// The FILE argument shared by the analysis commands.
#[derive(Args, Debug, Clone)]
pub struct FileArg {
    /// Mechanism file (.toml, .yaml, .yml, .json), `-` for standard input, or `@name` for a bundled example.
    #[arg(value_name = "FILE")]
    pub file: String,
    /// Format of standard input (default: sniffed from the content).
    #[arg(long, value_enum)]
    pub input_format: Option<InputFormat>,
    #[command(flatten)]
    pub import: ImportArgs,
}

/// Options for model files of other programs (MJCF, SDFormat, URDF, OpenSim).
#[derive(Args, Debug, Clone, Default)]
pub struct ImportArgs {
    /// Read FILE as this simulator format (default: from the root element and extension).
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub from: Option<FromFormat>,
    /// MJCF: the keyframe (name or index) whose qpos is the configuration (default: qpos0).
    #[arg(long, value_name = "NAME")]
    pub keyframe: Option<String>,
    /// Merge coincident coaxial revolute joints that share a body into multiple joints.
    #[arg(long)]
    pub merge_pins: bool,
    /// Merge each ball joint written as three revolute joints (axes meeting at one point,
    /// through two intermediate bodies nothing else holds, as CAD exporters write it) into
    /// one S joint.
    #[arg(long)]
    pub merge_balls: bool,
    /// URDF: the Extended-URDF YAML file of loop closures (default: STEM.yaml beside the URDF
    /// when it has a `closed_loop` key).
    #[arg(long, value_name = "FILE")]
    pub closures: Option<std::path::PathBuf>,
    /// URDF: read no YAML closure file, not even the one beside the URDF.
    #[arg(long, conflicts_with = "closures")]
    pub no_closures: bool,
}

impl ImportArgs {
    /// The library's import options.
    pub fn options(&self) -> mbsa::import::ImportOptions {
        mbsa::import::ImportOptions {
            format: self.from.map(Into::into),
            keyframe: self.keyframe.clone(),
            merge_pins: self.merge_pins,
            merge_balls: self.merge_balls,
            max_input_bytes: Some(super::budget().max_input_bytes),
            closures: match self.no_closures {
                true => Some(std::path::PathBuf::new()),
                false => self.closures.clone(),
            },
        }
    }
}

/// Simulator formats on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FromFormat {
    /// MuJoCo MJCF.
    Mjcf,
    /// SDFormat (Gazebo).
    Sdf,
    /// URDF.
    Urdf,
    /// OpenSim .osim.
    Osim,
}

impl From<FromFormat> for mbsa::import::SourceFormat {
    fn from(f: FromFormat) -> Self {
        use mbsa::import::SourceFormat as S;
        match f {
            FromFormat::Mjcf => S::Mjcf,
            FromFormat::Sdf => S::Sdf,
            FromFormat::Urdf => S::Urdf,
            FromFormat::Osim => S::Osim,
        }
    }
}

/// Input format names on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum InputFormat {
    /// TOML.
    Toml,
    /// YAML.
    Yaml,
    /// JSON.
    Json,
}

impl From<InputFormat> for Format {
    fn from(f: InputFormat) -> Format {
        match f {
            InputFormat::Toml => Format::Toml,
            InputFormat::Yaml => Format::Yaml,
            InputFormat::Json => Format::Json,
        }
    }
}

/// Read and parse a FILE argument. Errors are rendered diagnostics (exit code 2).
pub fn load(arg: &FileArg) -> Result<mbsa::Mechanism, Failure> {
    let xml = arg.import.from.is_some()
        || mbsa::import::SourceFormat::from_path(Path::new(&arg.file)).is_some();
    if xml && arg.input_format.is_none() {
        return import(&arg.file, &arg.import).map(|i| i.mechanism);
    }
    load_path(&arg.file, arg.input_format)
}

/// Import a simulator model file (`-` reads standard input); the warnings go to standard
/// error as one block.
pub fn import(file: &str, args: &ImportArgs) -> Result<mbsa::import::Import, Failure> {
    let (name, bytes, _) = read(file, None)?;
    import_read(file, &name, &bytes, args).map_err(Failure::from)
}

/// Write `text` to `path` (`-o` of `import`): refused when `path` is the input `file` (it
/// would be lost); written to a new file beside it, then renamed over it, so that a reader or
/// another writer never sees a half-written file.
pub fn write_output(file: &str, path: &Path, text: &str) -> Result<(), Failure> {
    let fail = |e: std::io::Error| {
        Failure::Input(format!("error: cannot write `{}`: {e}", path.display()))
    };
    let same = match (std::fs::canonicalize(file), std::fs::canonicalize(path)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same {
        return Err(Failure::Input(format!(
            "error: `-o {}` is the input file: writing it would overwrite the model\n  help: \
             write the imported model to another file",
            path.display()
        )));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let stem = path
        .file_name()
        .map_or("out".into(), |n| n.to_string_lossy());
    static COUNT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = dir.join(format!(".{stem}.{}-{n}.tmp", std::process::id()));
    let written = (|| {
        use std::io::Write as _;
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(fail(e));
    }
    Ok(())
}

/// Import bytes already read from FILE.
fn import_read(
    file: &str,
    name: &str,
    bytes: &[u8],
    args: &ImportArgs,
) -> Result<mbsa::import::Import, Unreadable> {
    let base = (file != "-" && !file.starts_with('@'))
        .then(|| Path::new(file).parent())
        .flatten();
    let result = mbsa::import::import_bytes(name, bytes, base, &args.options())
        .map_err(|e| Unreadable::of(&e))?;
    let block = result.warning_block();
    if !block.is_empty() {
        eprint!("{block}");
    }
    Ok(result)
}

/// A file that could not be read or parsed: the diagnostic for people, and where it points
/// for `mbsa check --format json`.
pub struct Unreadable {
    /// The rendered diagnostic (what standard error shows).
    pub rendered: String,
    /// The message alone.
    pub message: String,
    /// The hint, if any.
    pub help: Option<String>,
    /// The source name, 1-based line and column the diagnostic points at, if it has a location.
    pub at: Option<(String, usize, usize)>,
}

impl Unreadable {
    /// A diagnostic with its location (its first label).
    pub fn of(diag: &dyn miette::Diagnostic) -> Self {
        let at = mbsa::diagnostic::location(diag).map(|l| (l.file, l.line, l.column));
        Unreadable {
            rendered: mbsa::diagnostic::render(diag, super::color_stderr()),
            message: diag.to_string(),
            help: diag.help().map(|h| h.to_string()),
            at,
        }
    }

    /// An error already rendered as `error: message` (and `  help: hint` lines), without a
    /// location.
    pub fn rendered(text: String) -> Self {
        let mut lines = text.lines();
        let first = lines.next().unwrap_or_default();
        let message = first.strip_prefix("error: ").unwrap_or(first).to_string();
        let help = lines.find_map(|l| l.trim_start().strip_prefix("help: ").map(String::from));
        Unreadable {
            rendered: text,
            message,
            help,
            at: None,
        }
    }
}

impl From<Unreadable> for Failure {
    fn from(u: Unreadable) -> Failure {
        Failure::Input(u.rendered)
    }
}

impl From<Failure> for Unreadable {
    fn from(f: Failure) -> Unreadable {
        match f {
            Failure::Input(text) => Unreadable::rendered(text),
            Failure::Check => Unreadable::rendered("error: check failed".into()),
        }
    }
}

/// Read and parse `file` (path, `-` or `@name`).
pub fn load_path(
    file: &str,
    input_format: Option<InputFormat>,
) -> Result<mbsa::Mechanism, Failure> {
    load_path_located(file, input_format).map_err(Failure::from)
}

/// [`load_path`], its errors with their location.
pub fn load_path_located(
    file: &str,
    input_format: Option<InputFormat>,
) -> Result<mbsa::Mechanism, Unreadable> {
    let (name, bytes, format) = read(file, input_format)?;
    // Simulator models (MJCF, SDFormat, URDF, OpenSim) sniffed by their root element.
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]);
    if format.is_none() && mbsa::import::SourceFormat::sniff(&head).is_some() {
        return import_read(file, &name, &bytes, &ImportArgs::default()).map(|i| i.mechanism);
    }
    // Sniff on the valid UTF-8 prefix; load_bytes reports any bad byte at its location.
    let format = format.unwrap_or_else(|| {
        let valid = match std::str::from_utf8(&bytes) {
            Ok(s) => s,
            Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default(),
        };
        Format::sniff(valid)
    });
    mbsa::format::load_bytes_within(&name, &bytes, format, &super::budget())
        .map_err(|e| Unreadable::of(&e))
}

/// The display name, raw bytes and format (if known) of a FILE argument.
fn read(
    file: &str,
    input_format: Option<InputFormat>,
) -> Result<(String, Vec<u8>, Option<Format>), Failure> {
    if file == "-" {
        let buf = super::budget()
            .read_to_end(std::io::stdin().lock(), "standard input")
            .map_err(|e| read_failure("standard input", e))?;
        return Ok(("<stdin>".into(), buf, input_format.map(Into::into)));
    }
    if let Some(name) = file.strip_prefix('@') {
        return match mbsa::examples::find(name) {
            Some((file_name, text)) => Ok((
                format!("@{name} ({file_name})"),
                text.as_bytes().to_vec(),
                Some(Format::Toml),
            )),
            None => {
                let names: Vec<&str> = mbsa::examples::names().collect();
                let near = names
                    .iter()
                    .map(|n| (strsim::jaro_winkler(name, n), *n))
                    .filter(|(s, _)| *s > 0.7)
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(_, n)| format!(" (did you mean `@{n}`?)"))
                    .unwrap_or_default();
                Err(Failure::Input(format!(
                    "error: no bundled example named `{name}`{near}\n  help: `mbsa examples` lists them: {}",
                    names.join(", ")
                )))
            }
        };
    }
    let path = Path::new(file);
    let bytes = super::budget()
        .read_file(path)
        .map_err(|e| read_failure(&format!("`{file}`"), e))?;
    let format = input_format
        .map(Into::into)
        .or_else(|| Format::from_path(path));
    Ok((file.to_string(), bytes, format))
}

/// Render a failed bounded read: the operating system's error, or the input limit.
pub fn read_failure(what: &str, e: ReadError) -> Failure {
    match e {
        ReadError::Io(e) => Failure::Input(format!("error: cannot read {what}: {e}")),
        ReadError::TooLarge(e) => super::budget_failure(&e),
    }
}
