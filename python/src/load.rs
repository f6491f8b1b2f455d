//! `mbsa.load`: a path, a bundled `@name`, or the text of a file, as `mbsa FILE` reads it.

use crate::errors;
use crate::mechanism::RawMechanism;
use mbsa::budget::{Budget, ReadError};
use mbsa::format::Format;
use mbsa::import::{ImportOptions, SourceFormat};
use pyo3::prelude::*;
use std::path::Path;

/// The bundled examples: `(name, file name)` pairs.
#[pyfunction]
pub fn examples() -> Vec<(String, String)> {
    mbsa::examples::EXAMPLES
        .iter()
        .map(|(name, file, _)| (name.to_string(), file.to_string()))
        .collect()
}

/// Read a mechanism. `source` is a path (`is_path`), `@name`, or the text of a file (named
/// `<string>` in errors). `format`: toml, yaml, json; `from_`: mjcf, sdf, urdf, osim.
#[pyfunction]
#[pyo3(signature = (source, is_path, format=None, from_=None, keyframe=None, merge_pins=false))]
pub fn load(
    py: Python<'_>,
    source: String,
    is_path: bool,
    format: Option<String>,
    from_: Option<String>,
    keyframe: Option<String>,
    merge_pins: bool,
) -> PyResult<RawMechanism> {
    let format = format.map(|f| text_format(&f)).transpose()?;
    let from = from_.map(|f| source_format(&f)).transpose()?;
    let options = ImportOptions {
        format: from,
        keyframe,
        merge_pins,
        max_input_bytes: Some(Budget::DEFAULT.max_input_bytes),
        ..ImportOptions::default()
    };
    let (name, bytes, known, base) = read(py, &source, is_path, format)?;
    let xml = from.is_some()
        || (is_path && SourceFormat::from_path(Path::new(&source)).is_some())
        || (known.is_none() && {
            let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]);
            SourceFormat::sniff(&head).is_some()
        });
    let mechanism = py.detach(|| {
        if xml && format.is_none() {
            return mbsa::import::import_bytes(&name, &bytes, base.as_deref(), &options)
                .map(|i| i.mechanism)
                .map_err(|e| errors::diagnostic(&e));
        }
        let format = known.unwrap_or_else(|| {
            let valid = match std::str::from_utf8(&bytes) {
                Ok(s) => s,
                Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default(),
            };
            Format::sniff(valid)
        });
        mbsa::format::load_bytes_within(&name, &bytes, format, &Budget::DEFAULT)
            .map_err(|e| errors::diagnostic(&e))
    })?;
    Ok(RawMechanism::new(mechanism, name))
}

fn text_format(f: &str) -> PyResult<Format> {
    match f.to_ascii_lowercase().as_str() {
        "toml" => Ok(Format::Toml),
        "yaml" | "yml" => Ok(Format::Yaml),
        "json" => Ok(Format::Json),
        _ => Err(errors::input_error(
            None,
            None,
            None,
            &format!("unknown format `{f}` (toml, yaml, json)"),
            None,
            format!("error: unknown format `{f}`\n"),
        )),
    }
}

fn source_format(f: &str) -> PyResult<SourceFormat> {
    match f.to_ascii_lowercase().as_str() {
        "mjcf" => Ok(SourceFormat::Mjcf),
        "sdf" => Ok(SourceFormat::Sdf),
        "urdf" => Ok(SourceFormat::Urdf),
        "osim" => Ok(SourceFormat::Osim),
        _ => Err(errors::input_error(
            None,
            None,
            None,
            &format!("unknown model format `{f}` (mjcf, sdf, urdf, osim)"),
            None,
            format!("error: unknown model format `{f}`\n"),
        )),
    }
}

type Read = (String, Vec<u8>, Option<Format>, Option<std::path::PathBuf>);

/// The display name, bytes, known format and base directory (for included files) of a source,
/// named as the command line names it.
fn read(py: Python<'_>, source: &str, is_path: bool, format: Option<Format>) -> PyResult<Read> {
    if !is_path {
        if let Some(name) = source.strip_prefix('@') {
            return match mbsa::examples::find(name) {
                Some((file, text)) => Ok((
                    format!("@{name} ({file})"),
                    text.as_bytes().to_vec(),
                    Some(Format::Toml),
                    None,
                )),
                None => {
                    let names: Vec<&str> = mbsa::examples::names().collect();
                    let msg = format!("no bundled example named `{name}`");
                    Err(errors::input_error(
                        None,
                        None,
                        None,
                        &msg,
                        Some(format!("mbsa.examples() lists them: {}", names.join(", "))),
                        format!("error: {msg}\n"),
                    ))
                }
            };
        }
        return Ok(("<string>".into(), source.as_bytes().to_vec(), format, None));
    }
    let path = Path::new(source);
    let bytes = py
        .detach(|| Budget::DEFAULT.read_file(path))
        .map_err(|e| match e {
            ReadError::Io(e) => {
                let msg = format!("cannot read `{source}`: {e}");
                errors::input_error(
                    Some(source),
                    None,
                    None,
                    &msg,
                    None,
                    format!("error: {msg}\n"),
                )
            }
            ReadError::TooLarge(e) => errors::budget(&e),
        })?;
    let known = format.or_else(|| Format::from_path(path));
    Ok((
        source.to_string(),
        bytes,
        known,
        path.parent().map(Path::to_path_buf),
    ))
}
