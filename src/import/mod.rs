//! Importing the models people already have: MJCF (MuJoCo), SDFormat, URDF and OpenSim.
//!
//! Each reader ([`mjcf`], [`urdf`], [`sdf`], [`osim`]) walks its XML (parsed by `roxmltree`,
//! which keeps text positions for the errors) into the shared intermediate model, a
//! [`Builder`]: bodies (welded bodies merged by union-find), joints with their geometry in one
//! world frame at the chosen configuration, driven DOF from the actuators, warnings. The
//! builder writes a format-v1 TOML file (with comments pointing back to the source elements)
//! and the [`Mechanism`] is read back from that text, so that `mbsa import` output and the
//! source file give the same analysis. `docs/import.md` is the user reference.

mod error;
mod mjcf;
mod osim;
mod sdf;
mod urdf;

pub use error::ImportError;

use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::cell::Cell;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

/// Largest source file accepted, in bytes.
pub const MAX_SOURCE_BYTES: usize = 64 * 1024 * 1024;

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

/// Import a file from disk. Files it includes are read relative to its directory.
pub fn import_file(path: &Path, options: &ImportOptions) -> Result<Import, ImportError> {
    let name = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| ImportError::new(format!("cannot read `{name}`: {e}")))?;
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
    if bytes.len() > MAX_SOURCE_BYTES {
        return Err(ImportError::new(format!(
            "`{name}` is {} MiB; the importer accepts at most {} MiB",
            bytes.len() / (1024 * 1024),
            MAX_SOURCE_BYTES / (1024 * 1024)
        )));
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
        SourceFormat::Urdf => urdf::read(&src, &doc)?,
        SourceFormat::Sdf => sdf::read(&src, &doc)?,
        SourceFormat::Osim => osim::read(&src, &doc)?,
    };
    // MJCF reads its files (includes too) itself and notes their rounding in the builder.
    builder.note_rounding(src.rounding());
    // The main file's tolerated prologue comes first: it is what a reader sees first.
    builder.warnings.splice(0..0, tolerated_warnings);
    builder.finish(name, format, options)
}

// ---------------------------------------------------------------------------------------------
// XML helpers

/// The declarations at the start of `text` written `<?` + white space (`<? xml version="1.0"?>`,
/// as the published Stewart platform SDF begins), which no XML parser that checks
/// well-formedness accepts (a processing instruction's target must follow `<?` at once). The
/// models' reference loaders all read them: tinyxml2 (sdformat, MuJoCo, newer urdfdom) takes
/// any `<?` … `?>` before the first other node as a declaration and never reads its content;
/// TinyXML 1 (older urdfdom, OpenSim's SimTK Xml) keeps it as an unknown node. So these
/// declarations, and only these (at the document's start, before any other node), are
/// blanked: replaced by spaces of the same length, line breaks kept, so every later
/// `file:line:column` is unchanged. Returns the blanked text and one warning per declaration
/// (with its location), or `None` when there is nothing to tolerate; a `<?` + white space
/// anywhere else stays an error (tinyxml2 rejects a declaration after another node too).
pub(crate) fn tolerate_spaced_declarations(
    name: &str,
    text: &str,
) -> Option<(String, Vec<String>)> {
    let file = Path::new(name)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| name.to_string());
    let mut spans: Vec<Range<usize>> = Vec::new();
    let mut at = text.len() - text.trim_start_matches('\u{FEFF}').len();
    loop {
        at += text[at..].len() - text[at..].trim_start_matches(is_xml_space).len();
        let rest = &text[at..];
        let Some(after) = rest.strip_prefix("<?") else {
            break;
        };
        if after.starts_with(is_xml_space) {
            // tinyxml2 ends a declaration at the first `?>`; without one it is an error.
            let end = at + 2 + after.find("?>")? + 2;
            spans.push(at..end);
            at = end;
        } else if after.starts_with("xml") && spans.is_empty() {
            // A well-formed declaration first: a spaced one after it is still tolerated.
            at += 2 + after.find("?>")? + 2;
        } else {
            break;
        }
    }
    if spans.is_empty() {
        return None;
    }
    let mut out = String::with_capacity(text.len());
    let mut warnings = Vec::with_capacity(spans.len());
    let mut last = 0;
    for r in spans {
        out.push_str(&text[last..r.start]);
        let decl = &text[r.clone()];
        out.extend(
            decl.chars()
                .map(|c| if c == '\n' || c == '\r' { c } else { ' ' }),
        );
        // Blanking keeps byte offsets only if every blanked character is one byte.
        out.extend(std::iter::repeat_n(' ', decl.len() - decl.chars().count()));
        let line = text[..r.start].matches('\n').count() + 1;
        let col = text[..r.start]
            .rsplit('\n')
            .next()
            .map_or(0, |l| l.chars().count())
            + 1;
        let shown: String = decl.chars().take(80).collect();
        let shown = shown.replace(['\n', '\r'], " ");
        warnings.push(format!(
            "{file}:{line}:{col}: `{shown}` is not a well-formed XML declaration (no space may \
             follow `<?`): read as a declaration with its content ignored, as the TinyXML parsers \
             of Gazebo (sdformat), MuJoCo, urdfdom and OpenSim read it; write `<?xml` to silence this"
        ));
        last = r.end;
    }
    out.push_str(&text[last..]);
    Some((out, warnings))
}

/// XML white space (`S` in the XML grammar).
fn is_xml_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\n' | '\r')
}

/// One source file: its display name and text (for located errors).
pub(crate) struct Src<'a> {
    pub name: &'a str,
    pub text: &'a str,
    /// Byte offsets of the line starts (for `file:line:col` in warnings and comments).
    lines: Vec<usize>,
    /// The coarsest rounding ([`crate::motion::rounding_of`]) of the numbers read so far that
    /// enter the geometry: what the imported file's `precision` key says
    /// ([`Builder::source_rounding`]).
    rounding: Cell<f64>,
}

pub(crate) type Node<'a> = roxmltree::Node<'a, 'a>;

impl<'a> Src<'a> {
    /// A source file.
    pub fn new(name: &'a str, text: &'a str) -> Src<'a> {
        let lines = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Src {
            name,
            text,
            lines,
            rounding: Cell::new(0.0),
        }
    }

    /// Note numbers that enter the geometry, each known to ±its rounding times `unit` (π/180
    /// for an angle in degrees: the geometry sees radians).
    pub fn note(&self, xs: &[f64], unit: f64) {
        let r = xs
            .iter()
            .map(|&x| crate::motion::rounding_of(x) * unit)
            .fold(self.rounding.get(), f64::max);
        self.rounding.set(r);
    }

    /// The coarsest rounding noted ([`Src::note`]); 0 when every number read is exact.
    pub fn rounding(&self) -> f64 {
        self.rounding.get()
    }

    /// Parse the text (DTDs allowed, entities expanded by roxmltree's limits).
    pub fn parse(&self) -> Result<roxmltree::Document<'a>, ImportError> {
        let opts = roxmltree::ParsingOptions {
            allow_dtd: true,
            ..roxmltree::ParsingOptions::default()
        };
        roxmltree::Document::parse_with_options(self.text, opts).map_err(|e| {
            let pos = e.pos();
            let at = offset_of(self.text, pos.row as usize, pos.col as usize);
            ImportError::at(
                self.name,
                self.text,
                at..at,
                "here",
                format!("malformed XML: {e}"),
            )
            .with_help("the file must be well-formed XML")
        })
    }

    /// `file:line:col` of an element.
    pub fn loc(&self, n: Node) -> String {
        let at = n.range().start.min(self.text.len());
        let line = self.lines.partition_point(|&s| s <= at).max(1);
        let start = self.lines[line - 1];
        // Columns count characters; on very long lines (minified files) bytes, to stay linear.
        let col = match self.text.get(start..at) {
            Some(t) if t.len() <= 4096 => t.chars().count() + 1,
            _ => at - start + 1,
        };
        let file = Path::new(self.name)
            .file_name()
            .and_then(|f| f.to_str())
            .unwrap_or(self.name);
        format!("{file}:{line}:{col}")
    }

    /// The span of an element's start tag name (`<joint`).
    pub fn tag_span(n: Node) -> Range<usize> {
        let s = n.range().start;
        let len = n.tag_name().name().len() + 1;
        s..(s + len).min(n.range().end)
    }

    /// An error on an element's tag.
    pub fn err(
        &self,
        n: Node,
        label: impl Into<String>,
        message: impl Into<String>,
    ) -> ImportError {
        ImportError::at(self.name, self.text, Self::tag_span(n), label, message)
    }

    /// An error on an attribute's value (or the element's tag if the attribute is absent).
    pub fn err_attr(
        &self,
        n: Node,
        attr: &str,
        label: impl Into<String>,
        message: impl Into<String>,
    ) -> ImportError {
        let span = n
            .attributes()
            .find(|a| a.name() == attr)
            .map(|a| a.range_value())
            .unwrap_or_else(|| Self::tag_span(n));
        ImportError::at(self.name, self.text, span, label, message)
    }

    /// An error on the text of an element (or its tag if it has none).
    pub fn err_text(
        &self,
        n: Node,
        label: impl Into<String>,
        message: impl Into<String>,
    ) -> ImportError {
        let span = n
            .children()
            .find(|c| c.is_text())
            .map(|t| t.range())
            .unwrap_or_else(|| Self::tag_span(n));
        ImportError::at(self.name, self.text, span, label, message)
    }

    /// An attribute parsed as `len` numbers (`None` if absent; `len` 0 = any count), noted as
    /// geometry numbers ([`Src::note`]): the importers read no others.
    pub fn nums_attr(
        &self,
        n: Node,
        attr: &str,
        len: usize,
    ) -> Result<Option<Vec<f64>>, ImportError> {
        let v = self.nums_attr_unnoted(n, attr, len)?;
        if let Some(v) = &v {
            self.note(v, 1.0);
        }
        Ok(v)
    }

    /// [`Src::nums_attr`] without noting the numbers: for angles in degrees and for numbers
    /// that enter the geometry only when used (the caller notes them then).
    pub fn nums_attr_unnoted(
        &self,
        n: Node,
        attr: &str,
        len: usize,
    ) -> Result<Option<Vec<f64>>, ImportError> {
        let Some(v) = n.attribute(attr) else {
            return Ok(None);
        };
        parse_nums(v, len).map(Some).map_err(|what| {
            self.err_attr(
                n,
                attr,
                what.clone(),
                format!("`{attr}` of <{}>: {what}", n.tag_name().name()),
            )
            .with_help(if len > 0 {
                format!("`{attr}` takes {len} numbers separated by spaces")
            } else {
                format!("`{attr}` takes numbers separated by spaces")
            })
        })
    }

    /// An element's text parsed as `len` numbers (`len` 0 = any count), noted as geometry
    /// numbers ([`Src::nums_attr`]).
    pub fn nums_text(&self, n: Node, len: usize) -> Result<Vec<f64>, ImportError> {
        let v = self.nums_text_unnoted(n, len)?;
        self.note(&v, 1.0);
        Ok(v)
    }

    /// [`Src::nums_text`] without noting the numbers ([`Src::nums_attr_unnoted`]).
    pub fn nums_text_unnoted(&self, n: Node, len: usize) -> Result<Vec<f64>, ImportError> {
        let text = n.text().unwrap_or("");
        parse_nums(text, len).map_err(|what| {
            self.err_text(
                n,
                what.clone(),
                format!("<{}>: {what}", n.tag_name().name()),
            )
        })
    }
}

/// Parse whitespace-separated finite numbers, exactly `len` of them (`len` 0 = any count).
fn parse_nums(text: &str, len: usize) -> Result<Vec<f64>, String> {
    let mut out = Vec::new();
    for w in text.split_whitespace() {
        match w.parse::<f64>() {
            Ok(x) if x.is_finite() => out.push(x),
            _ => return Err(format!("`{w}` is not a finite number")),
        }
    }
    if len != 0 && out.len() != len {
        return Err(format!("expected {len} numbers, found {}", out.len()));
    }
    Ok(out)
}

/// Child elements of `n` with local name `tag`.
pub(crate) fn children<'a>(n: Node<'a>, tag: &'a str) -> impl Iterator<Item = Node<'a>> + 'a {
    n.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// The first child element of `n` with local name `tag`.
pub(crate) fn child<'a>(n: Node<'a>, tag: &str) -> Option<Node<'a>> {
    n.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// Byte offset of a 1-based line and 1-based column (in characters).
fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let mut start = 0;
    for _ in 1..line {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => return text.len(),
        }
    }
    let line_text = &text[start..];
    let mut at = start;
    for (i, (b, _)) in line_text.char_indices().enumerate() {
        if i + 1 >= col {
            return start + b;
        }
        at = start + b;
    }
    at.min(text.len())
}

// ---------------------------------------------------------------------------------------------
// Geometry helpers

/// A pose: rotation then translation (maps body coordinates to world coordinates).
pub(crate) type Pose = Isometry3<f64>;

/// A pose from a position and a rotation.
pub(crate) fn pose(p: [f64; 3], q: UnitQuaternion<f64>) -> Pose {
    Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), q)
}

/// Roll-pitch-yaw (fixed axes x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll)), as URDF and SDFormat.
pub(crate) fn rpy(r: f64, p: f64, y: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(r, p, y)
}

/// A unit vector from three numbers, `None` if it is zero.
pub(crate) fn unit(v: &[f64]) -> Option<Vector3<f64>> {
    let v = Vector3::new(v[0], v[1], v[2]);
    let n = v.norm();
    (n > 1e-12 && n.is_finite()).then(|| v / n)
}

pub(crate) fn arr(v: Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// The geometry of a point joint (S) of a loop closure whose point is `p1` on the first body
/// and `p2` on the second at the configuration: `origin` = `p1`, and `second.origin` = `p2`
/// when the two differ as written (the loop is open there; `mbsa assemble` closes it).
pub(crate) fn point_closure(p1: Vector3<f64>, p2: Vector3<f64>) -> Geometry {
    let (a, b) = (arr(p1), arr(p2));
    let differ = a.iter().zip(&b).any(|(x, y)| num(*x) != num(*y));
    Geometry {
        origin: Some(a),
        second: differ.then(|| {
            Box::new(crate::mechanism::Second {
                origin: Some(b),
                ..Default::default()
            })
        }),
        ..Geometry::default()
    }
}

// ---------------------------------------------------------------------------------------------
// The intermediate model

/// A joint of the intermediate model.
#[derive(Clone, Debug)]
pub(crate) struct JointRec {
    pub id: String,
    pub kind: JointType,
    /// Body indices into [`Builder::names`].
    pub bodies: Vec<usize>,
    pub driven: u32,
    pub geometry: Geometry,
    /// Comment lines naming the source element(s).
    pub comments: Vec<String>,
}

/// The shared intermediate model the readers fill.
pub(crate) struct Builder {
    pub model_name: String,
    /// The configuration, in words (`qpos0`, `keyframe "home"`, ...).
    pub configuration: String,
    names: Vec<String>,
    comments: Vec<String>,
    index: HashMap<String, usize>,
    uf: Vec<usize>,
    pub frame: usize,
    pub joints: Vec<JointRec>,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
    /// The coarsest rounding of the source numbers that enter the geometry ([`Src::note`]):
    /// the written model's `precision` (with at least the importer's own rounding).
    source_rounding: f64,
}

impl Builder {
    /// A new model whose fixed frame is the body `frame`.
    pub fn new(model_name: &str, frame: &str, frame_comment: &str) -> Builder {
        let mut b = Builder {
            model_name: model_name.to_string(),
            configuration: String::new(),
            names: Vec::new(),
            comments: Vec::new(),
            index: HashMap::new(),
            uf: Vec::new(),
            frame: 0,
            joints: Vec::new(),
            warnings: Vec::new(),
            notes: Vec::new(),
            source_rounding: 0.0,
        };
        b.frame = b.body(frame, frame_comment);
        b
    }

    /// The body named `name` (created if new).
    pub fn body(&mut self, name: &str, comment: &str) -> usize {
        if let Some(&i) = self.index.get(name) {
            return i;
        }
        let i = self.names.len();
        self.names.push(name.to_string());
        self.comments.push(comment.to_string());
        self.index.insert(name.to_string(), i);
        self.uf.push(i);
        i
    }

    /// A body name not used yet, from `base`.
    pub fn fresh_name(&self, base: &str) -> String {
        if !self.index.contains_key(base) {
            return base.to_string();
        }
        (2..)
            .map(|k| format!("{base}#{k}"))
            .find(|n| !self.index.contains_key(n))
            .unwrap_or_else(|| base.to_string())
    }

    /// The body named `name`, if it exists.
    pub fn find_body(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }

    fn root(&self, mut i: usize) -> usize {
        while self.uf[i] != i {
            i = self.uf[i];
        }
        i
    }

    /// Weld `other` to `keep` (they become one body, named as `keep`'s group unless `other`'s
    /// group holds the frame).
    pub fn weld(&mut self, keep: usize, other: usize, why: &str) {
        let (a, b) = (self.root(keep), self.root(other));
        if a == b {
            return;
        }
        let (keep_root, gone) = if b == self.root(self.frame) {
            (b, a)
        } else {
            (a, b)
        };
        self.uf[gone] = keep_root;
        let (kn, gn) = (self.names[other].clone(), self.names[keep].clone());
        let _ = (kn, gn);
        self.notes.push(format!(
            "`{}` welded to `{}` ({why})",
            self.names[other], self.names[keep]
        ));
    }

    /// Add a joint; returns its index.
    pub fn joint(&mut self, j: JointRec) -> usize {
        self.joints.push(j);
        self.joints.len() - 1
    }

    /// Note the rounding of source numbers that enter the geometry (a [`Src::rounding`]).
    pub fn note_rounding(&mut self, rounding: f64) {
        self.source_rounding = self.source_rounding.max(rounding);
    }

    /// Record a warning (an element not imported or not representable).
    pub fn warn(&mut self, message: impl Into<String>) {
        self.warnings.push(message.into());
    }

    /// Resolve welds, merge pins, write the TOML and read it back.
    pub fn finish(
        mut self,
        source_name: &str,
        format: SourceFormat,
        options: &ImportOptions,
    ) -> Result<Import, ImportError> {
        // Bodies through the welds.
        let mut joints = std::mem::take(&mut self.joints);
        let mut kept = Vec::with_capacity(joints.len());
        for mut j in joints.drain(..) {
            for b in &mut j.bodies {
                *b = self.root(*b);
            }
            let mut seen = j.bodies.clone();
            seen.sort_unstable();
            seen.dedup();
            if seen.len() < j.bodies.len() {
                self.warnings.push(format!(
                    "joint `{}` joins bodies welded together ({}): left out",
                    j.id,
                    j.bodies
                        .iter()
                        .map(|&b| format!("`{}`", self.names[b]))
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
                continue;
            }
            kept.push(j);
        }
        let mut joints = kept;
        let merged_pins = if options.merge_pins {
            merge_pins(&mut joints)
        } else {
            0
        };
        if merged_pins > 0 {
            self.notes.push(format!(
                "--merge-pins: {merged_pins} coaxial revolute joint(s) merged into multiple joints"
            ));
        }
        // Unique joint ids.
        let mut used: HashMap<String, usize> = HashMap::new();
        for j in &mut joints {
            if j.id.is_empty() {
                j.id = "joint".into();
            }
            let n = used.entry(j.id.clone()).or_insert(0);
            *n += 1;
            if *n > 1 {
                let mut k = *n;
                let mut id = format!("{}#{k}", j.id);
                while used.contains_key(&id) {
                    k += 1;
                    id = format!("{}#{k}", j.id);
                }
                used.insert(id.clone(), 1);
                j.id = id;
            }
        }
        let frame = self.root(self.frame);
        if joints.is_empty() {
            return Err(ImportError::new(format!(
                "`{source_name}`: no joints to analyse (every body is welded to the frame or \
                 the model has no joints)"
            ))
            .with_help("the analyses need at least one joint between two bodies"));
        }
        if !joints.iter().any(|j| j.bodies.contains(&frame)) {
            self.warnings.push(format!(
                "no joint touches the frame `{}`: the bodies are not linked to it",
                self.names[frame]
            ));
        }
        // Bodies that disappear because no joint names them.
        let mut used_bodies = vec![false; self.names.len()];
        for j in &joints {
            for &b in &j.bodies {
                used_bodies[b] = true;
            }
        }
        used_bodies[frame] = true;
        for (i, &u) in used_bodies.iter().enumerate() {
            if !u && self.root(i) == i {
                self.warnings.push(format!(
                    "body `{}` is joined to nothing: left out",
                    self.names[i]
                ));
            }
        }
        let toml = self.write_toml(source_name, format, &joints, frame);
        if !self.notes.is_empty() || !self.warnings.is_empty() {
            // Already in the text as comments.
        }
        let mechanism = crate::format::load(source_name, &toml, crate::format::Format::Toml)
            .map_err(|e| {
                ImportError::new(format!(
                    "internal error: the imported model does not read back: {e}"
                ))
                .with_help("please report this with the source file")
            })?;
        Ok(Import {
            mechanism,
            toml,
            format,
            warnings: self.warnings,
            notes: self.notes,
            merged_pins,
        })
    }

    fn write_toml(
        &self,
        source_name: &str,
        format: SourceFormat,
        joints: &[JointRec],
        frame: usize,
    ) -> String {
        let mut t = String::new();
        let file = Path::new(source_name)
            .file_name()
            .and_then(|f| f.to_str())
            .unwrap_or(source_name);
        let _ = writeln!(
            t,
            "# Imported by `mbsa import` from {} ({}).",
            comment_text(file),
            format.name()
        );
        if !self.configuration.is_empty() {
            let _ = writeln!(
                t,
                "# Configuration: {}. Joint origins and axes are in the world frame there.",
                comment_text(&self.configuration)
            );
        }
        for n in &self.notes {
            let _ = writeln!(t, "# note: {}", comment_text(n));
        }
        for w in &self.warnings {
            let _ = writeln!(t, "# warning: {}", comment_text(w));
        }
        let _ = writeln!(t, "name = {}", toml_str(&self.model_name));
        let _ = writeln!(t, "space = \"spatial\"");
        let _ = writeln!(t, "frame = {}", toml_str(&self.names[frame]));
        let _ = writeln!(
            t,
            "# How precisely the numbers are known (±): the coarsest rounding of the source's \
             numbers."
        );
        let _ = writeln!(
            t,
            "precision = {}",
            precision_text(self.source_rounding.max(written_rounding(joints)))
        );
        for j in joints {
            t.push('\n');
            let _ = writeln!(t, "[[joint]]");
            for c in &j.comments {
                let _ = writeln!(t, "# {}", comment_text(c));
            }
            let _ = writeln!(t, "id = {}", toml_str(&j.id));
            let _ = writeln!(t, "type = \"{}\"", j.kind.code());
            let bodies: Vec<String> = j.bodies.iter().map(|&b| toml_str(&self.names[b])).collect();
            let _ = writeln!(t, "bodies = [{}]", bodies.join(", "));
            if j.driven > 0 {
                let _ = writeln!(t, "driven = {}", j.driven);
            }
            let g = &j.geometry;
            for (key, v) in [
                ("origin", g.origin),
                ("axis", g.axis),
                ("axis2", g.axis2),
                ("normal", g.normal),
            ] {
                if let Some(v) = v {
                    let _ = writeln!(t, "{key} = [{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]));
                }
            }
            if let Some(p) = g.pitch {
                let _ = writeln!(t, "pitch = {}", num(p));
            }
            if let Some(s) = &g.second {
                let fields: Vec<String> = s
                    .vectors()
                    .into_iter()
                    .filter_map(|(key, v)| {
                        v.map(|v| format!("{key} = [{}, {}, {}]", num(v[0]), num(v[1]), num(v[2])))
                    })
                    .collect();
                let _ = writeln!(t, "second = {{ {} }}", fields.join(", "));
            }
        }
        t
    }
}

/// A number as written in the output: 10 decimals at most, trailing zeros trimmed (float noise
/// such as 6e-17 from cos 90° becomes 0).
pub(crate) fn num(x: f64) -> String {
    let s = format!("{x:.10}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" { "0".into() } else { s }
}

/// The rounding [`num`] adds to the numbers written: ±0.5·10^−10 when it rounds one, 0 when
/// every number is written exactly. Float noise of the composition (cos 90° = 6e-17 written
/// 0; below 1e-14 of the number) is not a rounding: what is written is the exact value.
fn written_rounding(joints: &[JointRec]) -> f64 {
    let exact = |x: &f64| {
        num(*x)
            .parse::<f64>()
            .is_ok_and(|w| (w - x).abs() <= 1e-14 * x.abs().max(1.0))
    };
    let all_exact = joints.iter().all(|j| {
        let g = &j.geometry;
        let second = g.second.as_ref().map(|s| s.vectors()).unwrap_or_default();
        [g.origin, g.origin2, g.axis, g.axis2, g.normal]
            .into_iter()
            .chain(second.into_iter().map(|(_, v)| v))
            .flatten()
            .all(|v| v.iter().all(exact))
            && g.pitch.as_ref().is_none_or(exact)
    });
    if all_exact { 0.0 } else { 0.5e-10 }
}

/// A precision as written in the output: 3 significant digits at most (`5e-7`, `8.73e-5`).
fn precision_text(p: f64) -> String {
    if p <= 0.0 || !p.is_finite() {
        return "0".into();
    }
    let s = format!("{p:.2e}");
    match s.split_once('e') {
        Some((mantissa, exp)) if mantissa.contains('.') => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{mantissa}e{exp}")
        }
        _ => s,
    }
}

/// A TOML basic string.
fn toml_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Text safe inside a `#` comment (one line).
fn comment_text(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// Merge coincident coaxial revolute joints sharing exactly one body into multiple joints;
/// returns how many joints were merged into others.
fn merge_pins(joints: &mut Vec<JointRec>) -> usize {
    let coaxial = |a: &Geometry, b: &Geometry| -> bool {
        let (Some(oa), Some(aa), Some(ob), Some(ab)) = (a.origin, a.axis, b.origin, b.axis) else {
            return false;
        };
        let (oa, ob) = (Vector3::from(oa), Vector3::from(ob));
        let (Some(ua), Some(ub)) = (unit(&aa), unit(&ab)) else {
            return false;
        };
        let scale = 1.0 + oa.norm().max(ob.norm());
        let tol = 1e-6 * scale;
        ua.cross(&ub).norm() < 1e-6 && (ob - oa).cross(&ua).norm() < tol
    };
    let mut merged = 0;
    let mut alive = vec![true; joints.len()];
    // The joints on each body (only pairs sharing a body can merge).
    let mut on: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        if j.kind == JointType::R {
            for &b in &j.bodies {
                on.entry(b).or_default().push(k);
            }
        }
    }
    loop {
        let mut changed = false;
        for i in 0..joints.len() {
            if !alive[i] || joints[i].kind != JointType::R {
                continue;
            }
            let mut candidates: Vec<usize> = joints[i]
                .bodies
                .iter()
                .flat_map(|b| on.get(b).map(Vec::as_slice).unwrap_or(&[]))
                .copied()
                .filter(|&k| k != i && alive[k])
                .collect();
            candidates.sort_unstable();
            candidates.dedup();
            let mut members: std::collections::HashSet<usize> =
                joints[i].bodies.iter().copied().collect();
            // A worklist: joints on bodies that merging brings in are candidates too.
            let mut queue = candidates;
            while let Some(k) = queue.pop() {
                if k == i || !alive[k] {
                    continue;
                }
                let shared = joints[k]
                    .bodies
                    .iter()
                    .filter(|b| members.contains(b))
                    .count();
                if shared != 1 || !coaxial(&joints[i].geometry, &joints[k].geometry) {
                    continue;
                }
                let extra: Vec<usize> = joints[k]
                    .bodies
                    .iter()
                    .copied()
                    .filter(|b| !members.contains(b))
                    .collect();
                for &b in &extra {
                    queue.extend(on.get(&b).map(Vec::as_slice).unwrap_or(&[]).iter().copied());
                    on.entry(b).or_default().push(i);
                    members.insert(b);
                }
                let other = joints[k].clone();
                let j = &mut joints[i];
                j.bodies.extend(extra);
                j.driven += other.driven;
                j.id = format!("{}+{}", j.id, other.id);
                j.comments.extend(other.comments);
                alive[k] = false;
                merged += 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let mut idx = 0;
    joints.retain(|_| {
        let keep = alive[idx];
        idx += 1;
        keep
    });
    merged
}

#[cfg(test)]
mod tests;
