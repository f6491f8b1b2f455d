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
    load_path(&arg.file, arg.input_format)
}

/// Read and parse `file` (path, `-` or `@name`).
pub fn load_path(
    file: &str,
    input_format: Option<InputFormat>,
) -> Result<mbsa::Mechanism, Failure> {
    let (name, bytes, format) = read(file, input_format)?;
    // Sniff on the valid UTF-8 prefix; load_bytes reports any bad byte at its location.
    let format = format.unwrap_or_else(|| {
        let valid = match std::str::from_utf8(&bytes) {
            Ok(s) => s,
            Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default(),
        };
        Format::sniff(valid)
    });
    mbsa::format::load_bytes_within(&name, &bytes, format, &super::budget())
        .map_err(|e| Failure::Input(mbsa::diagnostic::render(&e, super::color_stderr())))
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
