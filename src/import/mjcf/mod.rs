//! MJCF (MuJoCo) reader: body tree with every orientation form, default classes and
//! childclass, `include`, joints (several in one body = a chain through massless virtual
//! bodies), equality `connect`/`weld`, actuators with a joint transmission, keyframes.

mod body_tree;
mod configuration;
mod equality;

use super::{Builder, ImportError, ImportOptions, JointRec, Node, Pose, Src, Unique, arr};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Deepest include nesting accepted.
const MAX_INCLUDE_DEPTH: usize = 16;

/// Deepest nesting of `<frame>` elements (and of default classes) accepted.
const MAX_FRAME_DEPTH: usize = 64;

/// A body element still to read: the element, its parent body, the frames between them, the
/// childclass it inherits.
type Pending<'d> = (E<'d>, usize, Pose, Option<String>);

/// An element and the index of the file that holds it.
#[derive(Clone, Copy)]
struct E<'d> {
    n: Node<'d>,
    f: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Hinge,
    Slide,
    Ball,
    Free,
}

impl Kind {
    /// The mbsa joint of this kind at the world `anchor` and `axis`.
    fn joint(self, anchor: Vector3<f64>, axis: Vector3<f64>) -> (JointType, Geometry) {
        match self {
            Kind::Hinge => (
                JointType::R,
                Geometry {
                    origin: Some(arr(anchor)),
                    axis: Some(arr(axis)),
                    ..Geometry::default()
                },
            ),
            Kind::Slide => (
                JointType::P,
                Geometry {
                    origin: Some(arr(anchor)),
                    axis: Some(arr(axis)),
                    ..Geometry::default()
                },
            ),
            Kind::Ball => (
                JointType::S,
                Geometry {
                    origin: Some(arr(anchor)),
                    ..Geometry::default()
                },
            ),
            Kind::Free => (JointType::F, Geometry::default()),
        }
    }

    /// The MJCF name of this kind.
    fn word(self) -> &'static str {
        match self {
            Kind::Hinge => "hinge",
            Kind::Slide => "slide",
            Kind::Ball => "ball",
            Kind::Free => "free",
        }
    }
}

struct MJoint<'d> {
    name: Option<String>,
    kind: Kind,
    pos: Vector3<f64>,
    axis: Vector3<f64>,
    reference: f64,
    qposadr: usize,
    e: E<'d>,
}

struct MBody<'d> {
    /// The body's `name`; for one without a name (`named` false) empty until the whole tree
    /// is read, then a name no named body has.
    name: String,
    named: bool,
    parent: usize,
    local: Pose,
    joints: Vec<MJoint<'d>>,
}

/// A named site: its body, its position in the body's frame, its `pos` numbers as written.
type Site = (usize, Vector3<f64>, [f64; 3]);

struct Ctx<'d> {
    srcs: &'d [Src<'d>],
    inc: HashMap<(usize, usize), usize>,
    degree: bool,
    eulerseq: [u8; 3],
    /// class -> (parent class, `<joint>` default elements of that class).
    classes: HashMap<String, (Option<String>, Vec<E<'d>>)>,
    bodies: Vec<MBody<'d>>,
    /// Named sites: body, position in its frame, the `pos` numbers as written.
    sites: HashMap<String, Site>,
    nq: usize,
    unsupported: Vec<String>,
    /// The named bodies and joints so far (each name once).
    body_names: Unique,
    joint_names: Unique,
}

/// The files of a model: (name, text) of the main file then each included one (in scan
/// order), where each `<include>` is (file index, the element's start, the path it names),
/// and the warnings for tolerated declarations.
type Files = (
    Vec<(String, String)>,
    Vec<(usize, usize, PathBuf)>,
    Vec<String>,
);

/// Read an MJCF document (the main file is re-parsed here together with its includes).
pub(super) fn read(
    src: &Src,
    _doc: &roxmltree::Document,
    base_dir: Option<&Path>,
    options: &ImportOptions,
) -> Result<Builder, ImportError> {
    let (texts, inc_paths, tolerated) = load_files(src, base_dir, options.byte_limit())?;
    // `texts` is in scan order: file i of `inc_paths` refers to texts[i].
    let srcs: Vec<Src> = texts.iter().map(|(n, t)| Src::new(n, t)).collect();
    let docs: Vec<roxmltree::Document> =
        srcs.iter().map(|s| s.parse()).collect::<Result<_, _>>()?;
    let mut cx = Ctx::new(&srcs, &texts, &inc_paths);
    let root = E {
        n: docs[0].root_element(),
        f: 0,
    };
    let top = cx.kids(root, &docs);
    // Compiler settings first (they apply to the whole model).
    for e in top.iter().filter(|e| e.n.has_tag_name("compiler")) {
        cx.compiler(*e)?;
    }
    for e in top.iter().filter(|e| e.n.has_tag_name("default")) {
        cx.defaults(*e, None, &docs, 0);
    }
    cx.bodies.push(MBody {
        name: "world".into(),
        named: true,
        parent: 0,
        local: Pose::identity(),
        joints: Vec::new(),
    });
    for e in top.iter().filter(|e| e.n.has_tag_name("worldbody")) {
        cx.walk(*e, &docs)?;
    }
    cx.name_unnamed_bodies();
    cx.check_keyframe_names(&top, &docs)?;
    cx.note_unsupported_sections(&top, &docs);

    let model_name = root
        .n
        .attribute("model")
        .map(str::to_string)
        .unwrap_or_else(|| stem(src.name));
    let mut b = Builder::new(&model_name, "world", "the MJCF world body");
    b.warnings.extend(tolerated);

    // The configuration.
    let (qpos, config) = cx.keyframe(&top, options, &docs)?;
    b.configuration = config;
    let at0 = cx.fk(None);
    let at = cx.fk(qpos.as_deref());

    let (ids, joint_index) = cx.add_bodies(&mut b, &at);
    let body_by_name: HashMap<String, usize> = cx
        .bodies
        .iter()
        .enumerate()
        .map(|(i, bd)| (bd.name.clone(), i))
        .collect();

    // Equality constraints.
    for sec in top.iter().filter(|e| e.n.has_tag_name("equality")) {
        for e in cx.kids(*sec, &docs) {
            cx.equality(e, &mut b, &body_by_name, &ids, &at0, &at)?;
        }
    }
    for sec in top.iter().filter(|e| e.n.has_tag_name("actuator")) {
        for e in cx.kids(*sec, &docs) {
            cx.actuator(e, &mut b, &joint_index)?;
        }
    }
    for sec in top.iter().filter(|e| e.n.has_tag_name("custom")) {
        for e in cx.kids(*sec, &docs) {
            if e.n.has_tag_name("numeric") && e.n.attribute("name") == Some(super::PRECISION_NAME) {
                let v = cx
                    .src(e)
                    .nums_attr_unnoted(e.n, "data", 0)?
                    .unwrap_or_default();
                super::declared_precision(cx.src(e), e.n, &v, &mut b)?;
            }
        }
    }
    for u in std::mem::take(&mut cx.unsupported) {
        b.warn(u);
    }
    for s in &srcs {
        b.note_rounding(s.rounding());
    }
    Ok(b)
}

/// The main file and every file it includes, read first (their texts must outlive the parsed
/// documents); includes nested at most [`MAX_INCLUDE_DEPTH`] deep, each file once, all of them
/// together at most `limit` bytes.
fn load_files(src: &Src, base_dir: Option<&Path>, limit: u64) -> Result<Files, ImportError> {
    let mut texts: Vec<(String, String)> = Vec::new();
    let mut inc_paths: Vec<(usize, usize, PathBuf)> = Vec::new(); // (file, include start, path)
    let mut scan = vec![(src.name.to_string(), src.text.to_string(), 0usize)];
    let mut seen: Vec<PathBuf> = Vec::new();
    let mut file_index = 0usize;
    let mut tolerated: Vec<String> = Vec::new();
    let mut used = src.text.len() as u64;
    while let Some((name, text, depth)) = scan.pop() {
        let s = Src::new(&name, &text);
        let doc = s.parse()?;
        for n in doc.descendants().filter(|n| n.has_tag_name("include")) {
            let path = include_path(&s, n, depth, base_dir, &seen)?;
            let text = read_include(&s, n, &path, limit.saturating_sub(used), limit)?;
            used += text.len() as u64;
            // An included file may begin with a spaced `<? xml ...?>` too (as MuJoCo reads it).
            let text = match super::tolerate_spaced_declarations(&path.display().to_string(), &text)
            {
                Some((t, w)) => {
                    tolerated.extend(w);
                    t
                }
                None => text,
            };
            seen.push(path.clone());
            inc_paths.push((file_index, n.range().start, path.clone()));
            scan.push((path.display().to_string(), text, depth + 1));
        }
        texts.push((name, text));
        file_index += 1;
    }
    Ok((texts, inc_paths, tolerated))
}

/// The text of the file an `<include>` `n` names: a regular file (a device or FIFO would be
/// read without end), of at most `room` bytes (what the input limit `limit` leaves), UTF-8
/// text that begins like XML (anything else is refused without quoting it).
fn read_include(
    s: &Src,
    n: Node,
    path: &Path,
    room: u64,
    limit: u64,
) -> Result<String, ImportError> {
    use std::io::Read as _;
    let shown = path.display();
    let fail = |label: &str, message: String| {
        s.err_attr(n, "file", label, message)
            .with_help("include paths are relative to the directory of the main model file")
    };
    let cannot = |e: std::io::Error| {
        fail(
            "cannot read",
            format!("cannot read included file `{shown}`: {e}"),
        )
    };
    // The kind first, from the path (opening a FIFO would wait for a writer), then again from
    // the open file.
    let not_regular = || {
        fail(
            "not a regular file",
            format!("included file `{shown}` is not a regular file (a directory, device or FIFO)"),
        )
    };
    if !std::fs::metadata(path).map_err(cannot)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path).map_err(cannot)?;
    let meta = file.metadata().map_err(cannot)?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    let over = |needed: u64, at_least: bool| {
        let e = super::too_large(
            format!("reading `{shown}` (included; with the files before it)"),
            needed,
            at_least,
            limit,
        );
        fail("over the input limit", e.message().to_string())
            .with_help(e.hint().unwrap_or_default())
    };
    // Its size before reading it; then at most what is left (it may grow meanwhile).
    let used = limit - room;
    if meta.len() > room {
        return Err(over(used.saturating_add(meta.len()), false));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(room.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > room {
        return Err(over(used.saturating_add(bytes.len() as u64), true));
    }
    let text = String::from_utf8(bytes).map_err(|_| {
        cannot(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        ))
    })?;
    let start = text.trim_start_matches('\u{FEFF}').trim_start();
    if !start.is_empty() && !start.starts_with('<') {
        return Err(fail(
            "not XML",
            format!("included file `{shown}` is not XML (it does not begin with `<`)"),
        )
        .with_help("<include file> names an MJCF (XML) file"));
    }
    Ok(text)
}

/// The path an `<include>` at `depth` names, relative to `base_dir`: not too deep, not seen.
fn include_path(
    s: &Src,
    n: Node,
    depth: usize,
    base_dir: Option<&Path>,
    seen: &[PathBuf],
) -> Result<PathBuf, ImportError> {
    let Some(file) = n.attribute("file") else {
        return Err(s
            .err(n, "no `file`", "<include> without a `file` attribute")
            .with_help("write <include file=\"other.xml\"/>"));
    };
    if depth + 1 > MAX_INCLUDE_DEPTH {
        return Err(s.err_attr(
            n,
            "file",
            "too deep",
            format!("includes nested deeper than {MAX_INCLUDE_DEPTH}"),
        ));
    }
    let Some(dir) = base_dir else {
        return Err(s
            .err_attr(
                n,
                "file",
                "cannot resolve",
                format!("cannot include `{file}` from standard input"),
            )
            .with_help("give the model as a file path so that its includes can be found"));
    };
    let path = dir.join(file);
    if seen.contains(&path) {
        return Err(s
            .err_attr(
                n,
                "file",
                "included before",
                format!("`{file}` is included twice"),
            )
            .with_help("MuJoCo rejects repeated includes too"));
    }
    Ok(path)
}

impl<'d> Ctx<'d> {
    /// A context over the files `srcs` (`texts`: their names and texts, in scan order), each
    /// `<include>` of `inc_paths` mapped to the file it names.
    fn new(
        srcs: &'d [Src<'d>],
        texts: &[(String, String)],
        inc_paths: &[(usize, usize, PathBuf)],
    ) -> Ctx<'d> {
        let mut inc = HashMap::new();
        for (f, start, path) in inc_paths {
            let name = path.display().to_string();
            if let Some(k) = texts.iter().position(|(n, _)| *n == name) {
                inc.insert((*f, *start), k);
            }
        }
        Ctx {
            srcs,
            inc,
            degree: true,
            eulerseq: *b"xyz",
            classes: HashMap::new(),
            bodies: Vec::new(),
            sites: HashMap::new(),
            nq: 0,
            unsupported: Vec::new(),
            body_names: Unique::new("body"),
            joint_names: Unique::new("joint"),
        }
    }

    fn src(&self, e: E) -> &Src<'d> {
        &self.srcs[e.f]
    }

    /// A `<compiler>` element: the angle unit and Euler sequence (global coordinates refused).
    fn compiler(&mut self, e: E<'d>) -> Result<(), ImportError> {
        if let Some(a) = e.n.attribute("angle") {
            match a {
                "degree" => self.degree = true,
                "radian" => self.degree = false,
                _ => {
                    return Err(self
                        .src(e)
                        .err_attr(
                            e.n,
                            "angle",
                            "not an angle unit",
                            format!("unknown angle unit `{a}`"),
                        )
                        .with_help("MJCF angle units are `degree` (the default) and `radian`"));
                }
            }
        }
        if let Some(s) = e.n.attribute("eulerseq") {
            let b = s.as_bytes();
            if b.len() != 3 || !b.iter().all(|c| b"xyzXYZ".contains(c)) {
                return Err(self
                    .src(e)
                    .err_attr(
                        e.n,
                        "eulerseq",
                        "three of x, y, z, X, Y, Z",
                        format!("invalid eulerseq `{s}`"),
                    )
                    .with_help(
                        "lower case: axes that rotate with the frame; upper case: fixed axes",
                    ));
            }
            self.eulerseq = [b[0], b[1], b[2]];
        }
        if e.n.attribute("coordinate") == Some("global") {
            return Err(self
                .src(e)
                .err_attr(e.n, "coordinate", "not supported", "global coordinates are not supported")
                .with_help("MuJoCo itself removed coordinate=\"global\" (2.3.3); convert the model to local coordinates"));
        }
        Ok(())
    }

    /// Top-level sections not represented (deformables, tendons), noted for the warnings.
    fn note_unsupported_sections(&mut self, top: &[E<'d>], docs: &'d [roxmltree::Document<'d>]) {
        for e in top {
            let tag = e.n.tag_name().name();
            if matches!(tag, "deformable" | "contact" | "tendon")
                && self
                    .kids(*e, docs)
                    .iter()
                    .any(|k| !k.n.has_tag_name("exclude") && !k.n.has_tag_name("pair"))
                && tag != "contact"
            {
                let loc = self.src(*e).loc(e.n);
                self.unsupported.push(format!(
                    "{loc}: <{tag}> not represented (only its equality couplings and actuators would matter)"
                ));
            }
        }
    }

    /// The bodies and their joints at the configuration `at` (several joints in one body
    /// chained through massless virtual bodies; a body without joints welded to its parent).
    /// Gives the builder's body of each MJCF body, and the joints by name.
    fn add_bodies(&self, b: &mut Builder, at: &Fk) -> (Vec<usize>, HashMap<String, usize>) {
        let mut joint_index: HashMap<String, usize> = HashMap::new();
        let mut ids: Vec<usize> = vec![0; self.bodies.len()];
        ids[0] = b.frame;
        // Every body first, so that the virtual bodies' names avoid all of theirs.
        for (id, body) in ids.iter_mut().zip(&self.bodies).skip(1) {
            *id = b.body(&body.name, "");
        }
        for i in 1..self.bodies.len() {
            let body = &self.bodies[i];
            let me = ids[i];
            let parent = ids[body.parent];
            if body.joints.is_empty() {
                b.weld(parent, me, "MJCF body without joints");
                continue;
            }
            let n = body.joints.len();
            let mut prev = parent;
            for (k, j) in body.joints.iter().enumerate() {
                let next = if k + 1 == n {
                    me
                } else {
                    let v = b.fresh_name(&format!("{}~{}", body.name, k + 1));
                    b.body(&v, "massless virtual body")
                };
                let rec = self.joint_rec(body, k, j, at.1[i][k], [prev, next]);
                let ji = b.joint(rec);
                if let Some(name) = &j.name {
                    joint_index.insert(name.clone(), ji);
                }
                prev = next;
            }
        }
        (ids, joint_index)
    }

    /// Joint `k` of `body` at its world (anchor, axis), between `bodies`.
    fn joint_rec(
        &self,
        body: &MBody,
        k: usize,
        j: &MJoint,
        (anchor, axis): (Vector3<f64>, Vector3<f64>),
        bodies: [usize; 2],
    ) -> JointRec {
        let n = body.joints.len();
        let (kind, geometry) = j.kind.joint(anchor, axis);
        let kind_word = j.kind.word();
        let id = j.name.clone().unwrap_or_else(|| {
            format!(
                "{}:{kind_word}{}",
                body.name,
                if n > 1 {
                    (k + 1).to_string()
                } else {
                    String::new()
                }
            )
        });
        let tag = if j.e.n.has_tag_name("freejoint") {
            "<freejoint".to_string()
        } else {
            "<joint".to_string()
        };
        let name_attr = j
            .name
            .as_deref()
            .map(|s| format!(" name=\"{s}\""))
            .unwrap_or_default();
        let mut comments = vec![format!(
            "{tag}{name_attr}> ({kind_word}) of body `{}` at {}",
            body.name,
            self.src(j.e).loc(j.e.n)
        )];
        if n > 1 {
            comments.push(format!(
                "joint {} of {} in body `{}`: chained through massless virtual bodies",
                k + 1,
                n,
                body.name
            ));
        }
        JointRec {
            id,
            kind,
            bodies: bodies.to_vec(),
            driven: 0,
            geometry,
            comments,
        }
    }

    /// An actuator: one driven DOF of the joint it names (up to the joint's grade); one that
    /// acts through a tendon, site or body is warned.
    fn actuator(
        &self,
        e: E<'d>,
        b: &mut Builder,
        joint_index: &HashMap<String, usize>,
    ) -> Result<(), ImportError> {
        let s = self.src(e);
        let tag = e.n.tag_name().name();
        let name =
            e.n.attribute("name")
                .map(|n| format!(" name=\"{n}\""))
                .unwrap_or_default();
        let target =
            e.n.attribute("joint")
                .or_else(|| e.n.attribute("jointinparent"));
        if let Some(jn) = target {
            let Some(&ji) = joint_index.get(jn) else {
                return Err(s
                    .err_attr(e.n, if e.n.attribute("joint").is_some() { "joint" } else { "jointinparent" }, "no such joint", format!("actuator <{tag}{name}> names joint `{jn}`, which the model does not define"))
                    .with_help("the joint attribute must name a <joint> of the model"));
            };
            let j = &mut b.joints[ji];
            if j.driven < j.kind.grade() as u32 {
                j.driven += 1;
                j.comments
                    .push(format!("driven by <{tag}{name}> at {}", s.loc(e.n)));
            } else {
                let loc = s.loc(e.n);
                b.warn(format!("{loc}: <{tag}{name}> on joint `{jn}`, whose DOF are all driven already: not counted"));
            }
        } else {
            let via = ["tendon", "site", "body", "slidersite", "cranksite"]
                .into_iter()
                .find(|a| e.n.attribute(*a).is_some())
                .unwrap_or("no transmission");
            let loc = s.loc(e.n);
            b.warn(format!(
                "{loc}: actuator <{tag}{name}> acts through {via}: not representable as a driven joint"
            ));
        }
        Ok(())
    }
}

fn stem(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(name)
        .to_string()
}

/// World poses of the bodies and world (anchor, axis) of every joint.
type Fk = (Vec<Pose>, Vec<Vec<(Vector3<f64>, Vector3<f64>)>>);
