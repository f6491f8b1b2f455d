//! Importing the models people already have: MJCF (MuJoCo), SDFormat, URDF and OpenSim.
//!
//! Each reader ([`mjcf`], [`urdf`], [`sdf`], [`osim`]) walks its XML (parsed by `roxmltree`,
//! which keeps text positions for the errors) into the shared intermediate model, a
//! [`Builder`]: bodies (welded bodies merged by union-find), joints with their geometry in one
//! world frame at the chosen configuration, driven DOF from the actuators, warnings. The
//! builder writes a format-v1 TOML file (with comments pointing back to the source elements)
//! and the [`Mechanism`] is read back from that text, so that `mbsa import` output and the
//! source file give the same analysis. `docs/import.md` is the user reference.

mod balls;
mod builder;
mod error;
mod mjcf;
mod names;
mod osim;
mod pins;
mod pose;
mod sdf;
mod shift;
mod toml_text;
mod urdf;
mod xml;

pub use error::ImportError;

pub(crate) use builder::{Builder, JointRec};
pub(crate) use names::Unique;
pub(crate) use pose::{Pose, arr, point_closure, pose, rpy, tame, unit, unit_quat};
pub(crate) use xml::{Node, Src, child, children, tolerate_spaced_declarations};

#[cfg(test)]
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use std::fmt::Write as _;
use std::path::Path;
#[cfg(test)]
use toml_text::{num, precision_text};

/// Largest source accepted by default, in bytes: the main file and the files it includes
/// together ([`ImportOptions::max_input_bytes`] sets another limit).
pub const MAX_SOURCE_BYTES: usize = 64 * 1024 * 1024;

/// The name of the declared precision `mbsa export` writes (a mechanism's `precision` key,
/// which no number's digits carry): MJCF `<custom><numeric name="mbsa:precision" data=..>`,
/// SDFormat `<mbsa:precision>` in the model (namespace [`MBSA_NAMESPACE`]). The MJCF and
/// SDFormat readers take it as the source's rounding.
pub const PRECISION_NAME: &str = "mbsa:precision";

/// The XML namespace of the elements `mbsa export` adds to SDFormat.
pub const MBSA_NAMESPACE: &str = "urn:mbsa";

/// A declared precision read from `text` at `n`: a finite number >= 0, noted in `b`.
pub(crate) fn declared_precision(
    src: &Src,
    n: Node,
    v: &[f64],
    b: &mut Builder,
) -> Result<(), ImportError> {
    match v {
        [p] if p.is_finite() && *p >= 0.0 => {
            b.note_rounding(*p);
            Ok(())
        }
        _ => Err(src
            .err(
                n,
                "not a precision",
                format!("`{PRECISION_NAME}` is not one number >= 0"),
            )
            .with_help("it is the mechanism's `precision` (±, file units), e.g. 5e-06")),
    }
}

/// A source format the importer reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum SourceFormat {
    /// MuJoCo MJCF (`.xml`, `.mjcf`; root `<mujoco>`).
    Mjcf,
    /// SDFormat 1.4 to 1.10 (`.sdf`, `.world`; root `<sdf>`).
    Sdf,
    /// URDF (`.urdf`; root `<robot>`).
    Urdf,
    /// OpenSim (`.osim`; root `<OpenSimDocument>`).
    Osim,
}

impl SourceFormat {
    /// The format a file extension names, if it is one of the importer's. `.xml` is MJCF
    /// unless the root element says otherwise (see [`SourceFormat::sniff`]).
    pub fn from_path(path: &Path) -> Option<SourceFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "xml" | "mjcf" => Some(SourceFormat::Mjcf),
            "sdf" | "world" => Some(SourceFormat::Sdf),
            "urdf" => Some(SourceFormat::Urdf),
            "osim" => Some(SourceFormat::Osim),
            "xacro" => Some(SourceFormat::Urdf),
            _ => None,
        }
    }

    /// The format named by the root element of XML text (`mujoco`, `sdf`, `robot`,
    /// `OpenSimDocument`), if the text looks like XML and the root is one of them.
    pub fn sniff(text: &str) -> Option<SourceFormat> {
        let mut rest = text.trim_start_matches('\u{FEFF}').trim_start();
        // Skip the declaration, comments, processing instructions and a DOCTYPE.
        loop {
            if let Some(r) = rest.strip_prefix("<?") {
                rest = r.split_once("?>")?.1.trim_start();
            } else if let Some(r) = rest.strip_prefix("<!--") {
                rest = r.split_once("-->")?.1.trim_start();
            } else if let Some(r) = rest.strip_prefix("<!") {
                rest = r.split_once('>')?.1.trim_start();
            } else {
                break;
            }
        }
        let tag = rest.strip_prefix('<')?;
        let end = tag
            .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
            .unwrap_or(tag.len());
        let name = &tag[..end];
        let local = name.rsplit(':').next().unwrap_or(name);
        match local {
            "mujoco" => Some(SourceFormat::Mjcf),
            "sdf" => Some(SourceFormat::Sdf),
            "robot" => Some(SourceFormat::Urdf),
            "OpenSimDocument" => Some(SourceFormat::Osim),
            _ => None,
        }
    }

    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            SourceFormat::Mjcf => "MJCF",
            SourceFormat::Sdf => "SDFormat",
            SourceFormat::Urdf => "URDF",
            SourceFormat::Osim => "OpenSim",
        }
    }

    /// Its root element.
    pub fn root(self) -> &'static str {
        match self {
            SourceFormat::Mjcf => "mujoco",
            SourceFormat::Sdf => "sdf",
            SourceFormat::Urdf => "robot",
            SourceFormat::Osim => "OpenSimDocument",
        }
    }
}

/// Options of an import.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Force the source format (default: sniffed from the root element, then the extension).
    pub format: Option<SourceFormat>,
    /// MJCF: the keyframe (name, or index) whose `qpos` gives the configuration (default qpos0).
    pub keyframe: Option<String>,
    /// Merge coincident coaxial revolute joints that share a body into multiple joints.
    pub merge_pins: bool,
    /// Merge each ball joint written as three revolute joints (axes meeting at one point,
    /// through two bodies nothing else holds) into one S joint.
    pub merge_balls: bool,
    /// Largest input accepted, in bytes: the main file and every file it includes together
    /// (default [`MAX_SOURCE_BYTES`]; the command line gives its `--max-input-bytes`).
    pub max_input_bytes: Option<u64>,
    /// URDF: the Extended-URDF YAML file of loop closures (`closed_loop`, `type`, `name_mot`,
    /// `joint_name`, `joint_type`). Default: `STEM.yaml` (or `.yml`) beside the URDF when it
    /// has a `closed_loop` key, as Pinocchio users keep `robot.urdf` and `robot.yaml`
    /// together. An empty path reads none.
    pub closures: Option<std::path::PathBuf>,
}

impl ImportOptions {
    /// The input limit in force ([`ImportOptions::max_input_bytes`]).
    pub fn byte_limit(&self) -> u64 {
        self.max_input_bytes.unwrap_or(MAX_SOURCE_BYTES as u64)
    }
}

/// The error of an input over the limit `allowed` (`needed` bytes, or more when `at_least`).
pub(crate) fn too_large(what: String, needed: u64, at_least: bool, allowed: u64) -> ImportError {
    let e = crate::budget::BudgetExceeded {
        limit: crate::budget::Limit::InputBytes,
        what,
        needed,
        at_least,
        allowed,
    };
    ImportError::new(e.to_string()).with_help(e.help())
}

/// The result of an import.
#[derive(Debug)]
pub struct Import {
    /// The mechanism (read back from [`Import::toml`]).
    pub mechanism: Mechanism,
    /// The format-v1 TOML text.
    pub toml: String,
    /// The source format.
    pub format: SourceFormat,
    /// What was not imported or not representable, one line each (with `file:line:col`).
    pub warnings: Vec<String>,
    /// What the import did that a reader should know (bodies welded, configuration).
    pub notes: Vec<String>,
    /// How many joints `--merge-pins` merged into others.
    pub merged_pins: usize,
    /// How many ball joints `--merge-balls` made of three revolute joints each.
    pub merged_balls: usize,
}

impl Import {
    /// The warnings as one block of text (empty when there are none).
    pub fn warning_block(&self) -> String {
        if self.warnings.is_empty() {
            return String::new();
        }
        let mut out = format!(
            // Each line says what happened to its element (left out, not representable,
            // not closed at the configuration), so the header does not guess.
            "warning: {} {} import warning(s):\n",
            self.warnings.len(),
            self.format.name()
        );
        for w in &self.warnings {
            let _ = writeln!(out, "  - {w}");
        }
        out
    }
}

/// Import a file from disk. Files it includes are read relative to its directory. A regular
/// file over the input limit is refused before it is read, any other file read up to it.
pub fn import_file(path: &Path, options: &ImportOptions) -> Result<Import, ImportError> {
    let name = path.display().to_string();
    let budget = crate::budget::Budget {
        max_input_bytes: options.byte_limit(),
        ..crate::budget::Budget::UNLIMITED
    };
    let bytes = budget.read_file(path).map_err(|e| match e {
        crate::budget::ReadError::Io(e) => ImportError::new(format!("cannot read `{name}`: {e}")),
        crate::budget::ReadError::TooLarge(e) => too_large(e.what, e.needed, e.at_least, e.allowed),
    })?;
    import_bytes(&name, &bytes, path.parent(), options)
}

/// Import raw bytes named `name`; `base_dir` resolves relative includes (none: includes are
/// an error).
pub fn import_bytes(
    name: &str,
    bytes: &[u8],
    base_dir: Option<&Path>,
    options: &ImportOptions,
) -> Result<Import, ImportError> {
    if bytes.len() as u64 > options.byte_limit() {
        return Err(too_large(
            format!("reading `{name}`"),
            bytes.len() as u64,
            false,
            options.byte_limit(),
        ));
    }
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let text = std::str::from_utf8(bytes).map_err(|e| {
        ImportError::new(format!(
            "`{name}` is not UTF-8 text: invalid byte at offset {}",
            e.valid_up_to()
        ))
        .with_help("model files are XML text in UTF-8")
    })?;
    import_str(name, text, base_dir, options)
}

/// Import XML text named `name` (see [`import_bytes`]).
pub fn import_str(
    name: &str,
    text: &str,
    base_dir: Option<&Path>,
    options: &ImportOptions,
) -> Result<Import, ImportError> {
    let format = match options.format {
        Some(f) => f,
        None => SourceFormat::sniff(text)
            .or_else(|| SourceFormat::from_path(Path::new(name)))
            .ok_or_else(|| {
                ImportError::new(format!("cannot tell the format of `{name}`")).with_help(
                    "the importer reads MJCF (<mujoco>), SDFormat (<sdf>), URDF (<robot>) and \
                     OpenSim (<OpenSimDocument>); force one with --from mjcf|sdf|urdf|osim",
                )
            })?,
    };
    // What the reference loaders tolerate at the start (a spaced `<? xml ...?>`), blanked.
    let tolerated = tolerate_spaced_declarations(name, text);
    let (text, tolerated_warnings) = match &tolerated {
        Some((t, w)) => (t.as_str(), w.clone()),
        None => (text, Vec::new()),
    };
    let qualified = match format {
        SourceFormat::Osim => xml::qualified_osim_tags(text),
        _ => None,
    };
    let text = qualified.as_deref().unwrap_or(text);
    let src = Src::new(name, text);
    if Path::new(name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xacro"))
        || text.contains("http://www.ros.org/wiki/xacro")
    {
        return Err(ImportError::new(format!(
            "`{name}` is a xacro file (URDF macros): xacro is out of scope of the importer"
        ))
        .with_help(
            "expand it first: `xacro robot.urdf.xacro > robot.urdf`, then import robot.urdf",
        ));
    }
    let doc = src.parse()?;
    let root = doc.root_element();
    if root.tag_name().name() != format.root() {
        return Err(src
            .err(
                root,
                format!("not <{}>", format.root()),
                format!(
                    "expected a <{}> root element ({}), found <{}>",
                    format.root(),
                    format.name(),
                    root.tag_name().name()
                ),
            )
            .with_help(
                "the root element tells the format: <mujoco> MJCF, <sdf> SDFormat, <robot> \
                 URDF, <OpenSimDocument> OpenSim; --from forces one",
            ));
    }
    let mut builder = match format {
        SourceFormat::Mjcf => mjcf::read(&src, &doc, base_dir, options)?,
        SourceFormat::Urdf => urdf::read(&src, &doc, base_dir, options)?,
        SourceFormat::Sdf => sdf::read(&src, &doc)?,
        SourceFormat::Osim => osim::read(&src, &doc)?,
    };
    // MJCF reads its files (includes too) itself and notes their rounding in the builder.
    builder.note_rounding(src.rounding());
    // The main file's tolerated prologue comes first: it is what a reader sees first.
    builder.warnings.splice(0..0, tolerated_warnings);
    builder.finish(name, format, options)
}

#[cfg(test)]
mod tests;
