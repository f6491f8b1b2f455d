//! MJCF (MuJoCo) reader: body tree with every orientation form, default classes and
//! childclass, `include`, joints (several in one body = a chain through massless virtual
//! bodies), equality `connect`/`weld`, actuators with a joint transmission, keyframes.

use super::{Builder, ImportError, ImportOptions, JointRec, Node, Pose, Src, arr, pose, unit};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::{Rotation3, Translation3, UnitQuaternion, Vector3};
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
    name: String,
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
}

/// Read an MJCF document (the main file is re-parsed here together with its includes).
pub(super) fn read(
    src: &Src,
    _doc: &roxmltree::Document,
    base_dir: Option<&Path>,
    options: &ImportOptions,
) -> Result<Builder, ImportError> {
    // Load every included file first (their texts must outlive the parsed documents).
    let mut texts: Vec<(String, String)> = Vec::new();
    let mut pending: Vec<(String, String, usize)> = Vec::new(); // (name, text, depth)
    let mut inc_paths: Vec<(usize, usize, PathBuf)> = Vec::new(); // (file, include start, path)
    let mut scan = vec![(src.name.to_string(), src.text.to_string(), 0usize)];
    let mut seen: Vec<PathBuf> = Vec::new();
    let mut file_index = 0usize;
    let mut tolerated: Vec<String> = Vec::new();
    while let Some((name, text, depth)) = scan.pop() {
        let s = Src::new(&name, &text);
        let doc = s.parse()?;
        for n in doc.descendants().filter(|n| n.has_tag_name("include")) {
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
            let text = std::fs::read_to_string(&path).map_err(|e| {
                s.err_attr(
                    n,
                    "file",
                    "cannot read",
                    format!("cannot read included file `{}`: {e}", path.display()),
                )
                .with_help("include paths are relative to the directory of the main model file")
            })?;
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
            pending.push((path.display().to_string(), text.clone(), depth + 1));
            scan.push((path.display().to_string(), text, depth + 1));
        }
        texts.push((name, text));
        file_index += 1;
        let _ = &pending;
    }
    // `texts` is in scan order: file i of `inc_paths` refers to texts[i].
    let srcs: Vec<Src> = texts.iter().map(|(n, t)| Src::new(n, t)).collect();
    let docs: Vec<roxmltree::Document> =
        srcs.iter().map(|s| s.parse()).collect::<Result<_, _>>()?;
    let mut inc = HashMap::new();
    for (f, start, path) in &inc_paths {
        let name = path.display().to_string();
        if let Some(k) = texts.iter().position(|(n, _)| *n == name) {
            inc.insert((*f, *start), k);
        }
    }
    let mut cx = Ctx {
        srcs: &srcs,
        inc,
        degree: true,
        eulerseq: *b"xyz",
        classes: HashMap::new(),
        bodies: Vec::new(),
        sites: HashMap::new(),
        nq: 0,
        unsupported: Vec::new(),
    };
    let root = E {
        n: docs[0].root_element(),
        f: 0,
    };
    let top = cx.kids(root, &docs);
    // Compiler settings first (they apply to the whole model).
    for e in top.iter().filter(|e| e.n.has_tag_name("compiler")) {
        if let Some(a) = e.n.attribute("angle") {
            match a {
                "degree" => cx.degree = true,
                "radian" => cx.degree = false,
                _ => {
                    return Err(cx
                        .src(*e)
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
                return Err(cx
                    .src(*e)
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
            cx.eulerseq = [b[0], b[1], b[2]];
        }
        if e.n.attribute("coordinate") == Some("global") {
            return Err(cx
                .src(*e)
                .err_attr(e.n, "coordinate", "not supported", "global coordinates are not supported")
                .with_help("MuJoCo itself removed coordinate=\"global\" (2.3.3); convert the model to local coordinates"));
        }
    }
    for e in top.iter().filter(|e| e.n.has_tag_name("default")) {
        cx.defaults(*e, None, &docs, 0);
    }
    cx.bodies.push(MBody {
        name: "world".into(),
        parent: 0,
        local: Pose::identity(),
        joints: Vec::new(),
    });
    for e in top.iter().filter(|e| e.n.has_tag_name("worldbody")) {
        cx.walk(*e, &docs)?;
    }
    for e in &top {
        let tag = e.n.tag_name().name();
        if matches!(tag, "deformable" | "contact" | "tendon")
            && cx
                .kids(*e, &docs)
                .iter()
                .any(|k| !k.n.has_tag_name("exclude") && !k.n.has_tag_name("pair"))
            && tag != "contact"
        {
            let loc = cx.src(*e).loc(e.n);
            cx.unsupported.push(format!(
                "{loc}: <{tag}> not represented (only its equality couplings and actuators would matter)"
            ));
        }
    }

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

    // Bodies and joints.
    let mut joint_index: HashMap<String, usize> = HashMap::new();
    let mut ids: Vec<usize> = vec![0; cx.bodies.len()];
    ids[0] = b.frame;
    for i in 1..cx.bodies.len() {
        let body = &cx.bodies[i];
        let me = b.body(&body.name, "");
        ids[i] = me;
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
            let (anchor, axis) = at.1[i][k];
            let (kind, geometry) = match j.kind {
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
            };
            let kind_word = match j.kind {
                Kind::Hinge => "hinge",
                Kind::Slide => "slide",
                Kind::Ball => "ball",
                Kind::Free => "free",
            };
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
                cx.src(j.e).loc(j.e.n)
            )];
            if n > 1 {
                comments.push(format!(
                    "joint {} of {} in body `{}`: chained through massless virtual bodies",
                    k + 1,
                    n,
                    body.name
                ));
            }
            let ji = b.joint(JointRec {
                id,
                kind,
                bodies: vec![prev, next],
                driven: 0,
                geometry,
                comments,
            });
            if let Some(name) = &j.name {
                joint_index.insert(name.clone(), ji);
            }
            prev = next;
        }
    }
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
    // Actuators.
    for sec in top.iter().filter(|e| e.n.has_tag_name("actuator")) {
        for e in cx.kids(*sec, &docs) {
            let s = cx.src(e);
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

fn stem(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(name)
        .to_string()
}

/// World poses of the bodies and world (anchor, axis) of every joint.
type Fk = (Vec<Pose>, Vec<Vec<(Vector3<f64>, Vector3<f64>)>>);

impl<'d> Ctx<'d> {
    fn src(&self, e: E) -> &Src<'d> {
        &self.srcs[e.f]
    }

    /// Child elements, `<include>` replaced by the children of the included file's root.
    fn kids(&self, e: E<'d>, docs: &'d [roxmltree::Document<'d>]) -> Vec<E<'d>> {
        let mut out = Vec::new();
        for c in e.n.children().filter(|c| c.is_element()) {
            if c.has_tag_name("include") {
                if let Some(&k) = self.inc.get(&(e.f, c.range().start)) {
                    let r = E {
                        n: docs[k].root_element(),
                        f: k,
                    };
                    out.extend(self.kids(r, docs));
                }
            } else {
                out.push(E { n: c, f: e.f });
            }
        }
        out
    }

    fn defaults(
        &mut self,
        e: E<'d>,
        parent: Option<String>,
        docs: &'d [roxmltree::Document<'d>],
        depth: usize,
    ) {
        if depth > MAX_FRAME_DEPTH {
            let loc = self.src(e).loc(e.n);
            self.unsupported.push(format!(
                "{loc}: default classes nested deeper than {MAX_FRAME_DEPTH}: this one and deeper ones ignored"
            ));
            return;
        }
        let class =
            e.n.attribute("class")
                .map(str::to_string)
                .unwrap_or_else(|| {
                    if parent.is_none() {
                        "main".into()
                    } else {
                        String::new()
                    }
                });
        let kids = self.kids(e, docs);
        let joints: Vec<E> = kids
            .iter()
            .copied()
            .filter(|k| k.n.has_tag_name("joint"))
            .collect();
        self.classes.insert(class.clone(), (parent, joints));
        for k in kids.into_iter().filter(|k| k.n.has_tag_name("default")) {
            self.defaults(k, Some(class.clone()), docs, depth + 1);
        }
    }

    /// A joint attribute: its own, else its class chain's.
    fn joint_attr(&self, e: E<'d>, class: &str, attr: &str) -> Option<(&'d str, E<'d>)> {
        if let Some(v) = e.n.attribute(attr) {
            return Some((v, e));
        }
        let mut c = Some(class.to_string());
        let mut guard = 0;
        while let Some(name) = c {
            guard += 1;
            if guard > 64 {
                break;
            }
            let (parent, joints) = self.classes.get(&name)?;
            for d in joints.iter().rev() {
                if let Some(v) = d.n.attribute(attr) {
                    return Some((v, *d));
                }
            }
            c = parent.clone();
        }
        None
    }

    fn angle(&self, x: f64) -> f64 {
        if self.degree { x.to_radians() } else { x }
    }

    /// The pose an element's pos and orientation attributes give (relative to its parent).
    fn pose_of(&self, e: E<'d>) -> Result<Pose, ImportError> {
        let s = self.src(e);
        let p = s.nums_attr(e.n, "pos", 3)?.unwrap_or_else(|| vec![0.0; 3]);
        let q = self.orientation(e)?;
        Ok(pose([p[0], p[1], p[2]], q))
    }

    fn orientation(&self, e: E<'d>) -> Result<UnitQuaternion<f64>, ImportError> {
        let s = self.src(e);
        let n = e.n;
        let given: Vec<&str> = ["quat", "axisangle", "euler", "xyaxes", "zaxis"]
            .into_iter()
            .filter(|a| n.attribute(*a).is_some())
            .collect();
        if given.len() > 1 {
            return Err(s
                .err_attr(
                    n,
                    given[1],
                    "second orientation",
                    format!(
                        "<{}> gives its orientation twice ({})",
                        n.tag_name().name(),
                        given.join(", ")
                    ),
                )
                .with_help(
                    "MJCF allows one of quat, axisangle, euler, xyaxes, zaxis per element",
                ));
        }
        if let Some(q) = s.nums_attr(n, "quat", 4)? {
            let v = nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]);
            if v.norm() < 1e-12 {
                return Err(s
                    .err_attr(n, "quat", "zero", "a zero quaternion")
                    .with_help("quat is w x y z, not all zero"));
            }
            return Ok(UnitQuaternion::from_quaternion(v));
        }
        if let Some(a) = s.nums_attr_unnoted(n, "axisangle", 4)? {
            s.note(&a[..3], 1.0);
            s.note(&a[3..], self.angle(1.0));
            let Some(axis) = unit(&a[..3]) else {
                return Err(s
                    .err_attr(n, "axisangle", "zero axis", "axisangle with a zero axis")
                    .with_help("axisangle is x y z angle"));
            };
            return Ok(UnitQuaternion::from_axis_angle(
                &nalgebra::Unit::new_unchecked(axis),
                self.angle(a[3]),
            ));
        }
        if let Some(a) = s.nums_attr_unnoted(n, "euler", 3)? {
            s.note(&a, self.angle(1.0));
            let mut q = UnitQuaternion::identity();
            for (i, &c) in self.eulerseq.iter().enumerate() {
                let axis = match c.to_ascii_lowercase() {
                    b'x' => Vector3::x_axis(),
                    b'y' => Vector3::y_axis(),
                    _ => Vector3::z_axis(),
                };
                let r = UnitQuaternion::from_axis_angle(&axis, self.angle(a[i]));
                q = if c.is_ascii_lowercase() { q * r } else { r * q };
            }
            return Ok(q);
        }
        if let Some(a) = s.nums_attr(n, "xyaxes", 6)? {
            let x = Vector3::new(a[0], a[1], a[2]);
            let y = Vector3::new(a[3], a[4], a[5]);
            let bad = || {
                s.err_attr(
                    n,
                    "xyaxes",
                    "degenerate",
                    "xyaxes with a zero or repeated axis",
                )
                .with_help("xyaxes is the x axis then the y axis of the frame, not parallel")
            };
            if x.norm() < 1e-12 {
                return Err(bad());
            }
            let x = x.normalize();
            let y = y - x * x.dot(&y);
            if y.norm() < 1e-12 {
                return Err(bad());
            }
            let y = y.normalize();
            let z = x.cross(&y);
            let r = Rotation3::from_basis_unchecked(&[x, y, z]);
            return Ok(UnitQuaternion::from_rotation_matrix(&r));
        }
        if let Some(a) = s.nums_attr(n, "zaxis", 3)? {
            let Some(z) = unit(&a) else {
                return Err(s
                    .err_attr(n, "zaxis", "zero", "a zero zaxis")
                    .with_help("zaxis is the direction of the frame's z axis"));
            };
            return Ok(
                UnitQuaternion::rotation_between(&Vector3::z(), &z).unwrap_or_else(|| {
                    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
                }),
            );
        }
        Ok(UnitQuaternion::identity())
    }

    /// Walk a body (or the worldbody, or a frame) `e`: `body` is the MuJoCo body it belongs to,
    /// `rel` the frames between that body and `e`'s children.
    fn walk(
        &mut self,
        root: E<'d>,
        docs: &'d [roxmltree::Document<'d>],
    ) -> Result<(), ImportError> {
        // Depth first with an explicit stack (deep body chains must not overflow the call
        // stack); bodies are numbered in preorder, as MuJoCo numbers them (qpos order).
        let mut found: Vec<Pending<'d>> = Vec::new();
        self.walk_children(root, 0, Pose::identity(), None, docs, &mut found, 0)?;
        let mut stack: Vec<Pending<'d>> = found.drain(..).rev().collect();
        while let Some((k, parent, rel, childclass)) = stack.pop() {
            let s = self.src(k);
            let local = rel * self.pose_of(k)?;
            let idx = self.bodies.len();
            let name = match k.n.attribute("name") {
                Some(n) if !n.is_empty() => n.to_string(),
                _ => format!("body{idx}"),
            };
            if name == "world" {
                return Err(s
                    .err_attr(k.n, "name", "reserved", "a body named `world`")
                    .with_help("`world` is MuJoCo's world body; rename this one"));
            }
            let cc =
                k.n.attribute("childclass")
                    .map(str::to_string)
                    .or(childclass);
            self.bodies.push(MBody {
                name,
                parent,
                local,
                joints: Vec::new(),
            });
            self.walk_children(k, idx, Pose::identity(), cc, docs, &mut found, 0)?;
            stack.extend(found.drain(..).rev());
        }
        Ok(())
    }

    /// The children of a body (or the worldbody, or a frame) `e`: joints and sites go to
    /// `body`, child bodies to `found` (in document order); `rel` is the pose of the frames
    /// between `body` and `e`'s children.
    #[allow(clippy::too_many_arguments)]
    fn walk_children(
        &mut self,
        e: E<'d>,
        body: usize,
        rel: Pose,
        childclass: Option<String>,
        docs: &'d [roxmltree::Document<'d>],
        found: &mut Vec<Pending<'d>>,
        frame_depth: usize,
    ) -> Result<(), ImportError> {
        for k in self.kids(e, docs) {
            let s = self.src(k);
            match k.n.tag_name().name() {
                "body" => found.push((k, body, rel, childclass.clone())),
                "frame" => {
                    if frame_depth >= MAX_FRAME_DEPTH {
                        return Err(s
                            .err(
                                k.n,
                                "too deep",
                                format!("<frame> elements nested deeper than {MAX_FRAME_DEPTH}"),
                            )
                            .with_help("flatten the frames: compose their poses"));
                    }
                    let f = rel * self.pose_of(k)?;
                    let cc =
                        k.n.attribute("childclass")
                            .map(str::to_string)
                            .or_else(|| childclass.clone());
                    self.walk_children(k, body, f, cc, docs, found, frame_depth + 1)?;
                }
                "joint" | "freejoint" => {
                    if body == 0 {
                        return Err(s
                            .err(k.n, "in the world body", "a joint in <worldbody>")
                            .with_help("joints belong to a <body> inside <worldbody>"));
                    }
                    let free = k.n.has_tag_name("freejoint");
                    let class =
                        k.n.attribute("class")
                            .map(str::to_string)
                            .or_else(|| childclass.clone())
                            .unwrap_or_else(|| "main".into());
                    if !free && !self.classes.contains_key(&class) && class != "main" {
                        return Err(s
                            .err(
                                k.n,
                                "unknown class",
                                format!("default class `{class}` is not defined"),
                            )
                            .with_help("define it with <default class=\"...\"> inside <default>"));
                    }
                    let kind = if free {
                        Kind::Free
                    } else {
                        match self.joint_attr(k, &class, "type") {
                            None | Some(("hinge", _)) => Kind::Hinge,
                            Some(("slide", _)) => Kind::Slide,
                            Some(("ball", _)) => Kind::Ball,
                            Some(("free", _)) => Kind::Free,
                            Some((t, at)) => {
                                return Err(self
                                    .src(at)
                                    .err_attr(
                                        at.n,
                                        "type",
                                        "not a joint type",
                                        format!("unknown joint type `{t}`"),
                                    )
                                    .with_help(
                                        "MJCF joint types are hinge, slide, ball and free",
                                    ));
                            }
                        }
                    };
                    let vec3 = |cx: &Self,
                                attr: &str,
                                default: [f64; 3]|
                     -> Result<Vector3<f64>, ImportError> {
                        match cx.joint_attr(k, &class, attr) {
                            Some((_, at)) => {
                                let v = cx
                                    .src(at)
                                    .nums_attr(at.n, attr, 3)?
                                    .unwrap_or_else(|| default.to_vec());
                                Ok(Vector3::new(v[0], v[1], v[2]))
                            }
                            None => Ok(Vector3::from(default)),
                        }
                    };
                    let pos = if free {
                        Vector3::zeros()
                    } else {
                        (rel * nalgebra::Point3::from(vec3(self, "pos", [0.0; 3])?)).coords
                    };
                    let axis_local = if free {
                        Vector3::z()
                    } else {
                        vec3(self, "axis", [0.0, 0.0, 1.0])?
                    };
                    let axis = match unit(axis_local.as_slice()) {
                        Some(a) => rel.rotation * a,
                        None => {
                            let at = self.joint_attr(k, &class, "axis").map(|x| x.1).unwrap_or(k);
                            return Err(self
                                .src(at)
                                .err_attr(at.n, "axis", "zero", "a joint axis of zero length")
                                .with_help("axis gives the direction of the joint axis"));
                        }
                    };
                    let reference = match self.joint_attr(k, &class, "ref") {
                        Some((_, at)) if !free => {
                            let src = self.src(at);
                            let r = src.nums_attr_unnoted(at.n, "ref", 1)?;
                            let r = r.map_or(0.0, |r| r[0]);
                            let unit = if kind == Kind::Hinge {
                                self.angle(1.0)
                            } else {
                                1.0
                            };
                            src.note(&[r], unit);
                            r
                        }
                        _ => 0.0,
                    };
                    let reference = if kind == Kind::Hinge {
                        self.angle(reference)
                    } else {
                        reference
                    };
                    let qposadr = self.nq;
                    self.nq += match kind {
                        Kind::Free => 7,
                        Kind::Ball => 4,
                        _ => 1,
                    };
                    self.bodies[body].joints.push(MJoint {
                        name: k
                            .n
                            .attribute("name")
                            .filter(|n| !n.is_empty())
                            .map(str::to_string),
                        kind,
                        pos,
                        axis,
                        reference,
                        qposadr,
                        e: k,
                    });
                }
                "site" => {
                    if let Some(name) = k.n.attribute("name") {
                        // Noted only when a loop closure uses the site (sensor sites abound).
                        let p = s
                            .nums_attr_unnoted(k.n, "pos", 3)?
                            .unwrap_or_else(|| vec![0.0; 3]);
                        let written = [p[0], p[1], p[2]];
                        let p = rel * nalgebra::Point3::from(written);
                        self.sites
                            .insert(name.to_string(), (body, p.coords, written));
                    }
                }
                t @ ("composite" | "flexcomp" | "replicate" | "attach" | "plugin") => {
                    let loc = s.loc(k.n);
                    self.unsupported.push(format!(
                        "{loc}: <{t}> not supported: its bodies and joints are not imported"
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The keyframe's qpos (`None` = qpos0) and the configuration in words.
    fn keyframe(
        &self,
        top: &[E<'d>],
        options: &ImportOptions,
        docs: &'d [roxmltree::Document<'d>],
    ) -> Result<(Option<Vec<f64>>, String), ImportError> {
        let Some(want) = options.keyframe.as_deref() else {
            return Ok((None, "qpos0 (the model as written)".into()));
        };
        let keys: Vec<E> = top
            .iter()
            .filter(|e| e.n.has_tag_name("keyframe"))
            .flat_map(|e| self.kids(*e, docs))
            .filter(|k| k.n.has_tag_name("key"))
            .collect();
        let found = keys
            .iter()
            .find(|k| k.n.attribute("name") == Some(want))
            .or_else(|| want.parse::<usize>().ok().and_then(|i| keys.get(i)));
        let Some(k) = found else {
            let names: Vec<String> = keys
                .iter()
                .enumerate()
                .map(|(i, k)| {
                    k.n.attribute("name")
                        .map(|n| format!("`{n}`"))
                        .unwrap_or_else(|| format!("#{i}"))
                })
                .collect();
            return Err(
                ImportError::new(format!("no keyframe `{want}` in the model")).with_help(
                    if names.is_empty() {
                        "the model has no <key> elements; leave out --keyframe to use qpos0"
                            .to_string()
                    } else {
                        format!(
                            "its keyframes are {} (a name or an index)",
                            names.join(", ")
                        )
                    },
                ),
            );
        };
        let s = self.src(*k);
        let Some(q) = s.nums_attr(k.n, "qpos", 0)? else {
            return Ok((None, format!("keyframe `{want}` (no qpos: qpos0)")));
        };
        if q.len() != self.nq {
            return Err(s
                .err_attr(k.n, "qpos", format!("{} numbers", q.len()), format!("keyframe `{want}` has {} qpos values; the model has {}", q.len(), self.nq))
                .with_help("qpos lists every joint's coordinates in body order (free 7, ball 4, hinge and slide 1)"));
        }
        Ok((Some(q), format!("keyframe `{want}` at {}", s.loc(k.n))))
    }

    /// Forward kinematics at `qpos` (`None` = qpos0: the tree as written).
    fn fk(&self, qpos: Option<&[f64]>) -> Fk {
        let mut poses: Vec<Pose> = Vec::with_capacity(self.bodies.len());
        let mut joints = Vec::with_capacity(self.bodies.len());
        for (i, b) in self.bodies.iter().enumerate() {
            if i == 0 {
                poses.push(Pose::identity());
                joints.push(Vec::new());
                continue;
            }
            let mut p = poses[b.parent] * b.local;
            let mut js = Vec::with_capacity(b.joints.len());
            for j in &b.joints {
                // MuJoCo's xanchor: before the joint's own motion (it only matters for slides).
                let anchor = (p * nalgebra::Point3::from(j.pos)).coords;
                let q = |k: usize| qpos.map(|v| v[j.qposadr + k]);
                let about = |p: Pose, r: UnitQuaternion<f64>| -> Pose {
                    p * Translation3::from(j.pos) * r * Translation3::from(-j.pos)
                };
                match j.kind {
                    Kind::Hinge => {
                        if let Some(x) = q(0) {
                            let r = UnitQuaternion::from_axis_angle(
                                &nalgebra::Unit::new_unchecked(j.axis),
                                x - j.reference,
                            );
                            p = about(p, r);
                        }
                    }
                    Kind::Slide => {
                        if let Some(x) = q(0) {
                            p *= Translation3::from(j.axis * (x - j.reference));
                        }
                    }
                    Kind::Ball => {
                        if let (Some(w), Some(x), Some(y), Some(z)) = (q(0), q(1), q(2), q(3)) {
                            let v = nalgebra::Quaternion::new(w, x, y, z);
                            if v.norm() > 1e-12 {
                                p = about(p, UnitQuaternion::from_quaternion(v));
                            }
                        }
                    }
                    Kind::Free => {
                        if let Some(v) = qpos {
                            let a = &v[j.qposadr..j.qposadr + 7];
                            let quat = nalgebra::Quaternion::new(a[3], a[4], a[5], a[6]);
                            let r = if quat.norm() > 1e-12 {
                                UnitQuaternion::from_quaternion(quat)
                            } else {
                                UnitQuaternion::identity()
                            };
                            p = pose([a[0], a[1], a[2]], r);
                        }
                    }
                }
                let anchor = if j.kind == Kind::Slide {
                    anchor
                } else {
                    (p * nalgebra::Point3::from(j.pos)).coords
                };
                js.push((anchor, p.rotation * j.axis));
            }
            joints.push(js);
            poses.push(p);
        }
        (poses, joints)
    }

    #[allow(clippy::too_many_arguments)]
    fn equality(
        &self,
        e: E<'d>,
        b: &mut Builder,
        body_by_name: &HashMap<String, usize>,
        ids: &[usize],
        at0: &Fk,
        at: &Fk,
    ) -> Result<(), ImportError> {
        let s = self.src(e);
        let tag = e.n.tag_name().name();
        let name = e.n.attribute("name");
        let name_attr = name.map(|n| format!(" name=\"{n}\"")).unwrap_or_default();
        let loc = s.loc(e.n);
        if matches!(e.n.attribute("active"), Some("false")) {
            b.warn(format!(
                "{loc}: <{tag}{name_attr}> is inactive (active=\"false\"): left out"
            ));
            return Ok(());
        }
        let body = |attr: &str, default_world: bool| -> Result<Option<usize>, ImportError> {
            match e.n.attribute(attr) {
                Some(n) => match body_by_name.get(n) {
                    Some(&i) => Ok(Some(i)),
                    None => Err(s
                        .err_attr(
                            e.n,
                            attr,
                            "no such body",
                            format!("<{tag}> names body `{n}`, which the model does not define"),
                        )
                        .with_help("body1 and body2 name <body> elements (or `world`)")),
                },
                None => Ok(default_world.then_some(0)),
            }
        };
        let site = |attr: &str| -> Result<Option<Site>, ImportError> {
            match e.n.attribute(attr) {
                Some(n) => match self.sites.get(n) {
                    Some(&v) => Ok(Some(v)),
                    None => Err(s
                        .err_attr(
                            e.n,
                            attr,
                            "no such site",
                            format!("<{tag}> names site `{n}`, which the model does not define"),
                        )
                        .with_help("site1 and site2 name <site> elements")),
                },
                None => Ok(None),
            }
        };
        match tag {
            "connect" => {
                // (body1, point on it in its frame, body2, the same point in body2's frame).
                let (b1, b2, p1, p2) =
                    if let (Some(s1), Some(s2)) = (site("site1")?, site("site2")?) {
                        s.note(&s1.2, 1.0);
                        s.note(&s2.2, 1.0);
                        (s1.0, s2.0, s1.1, s2.1)
                    } else {
                        let Some(b1) = body("body1", false)? else {
                            return Err(s
                                .err(
                                    e.n,
                                    "no body1",
                                    "<connect> needs body1 and anchor, or site1 and site2",
                                )
                                .with_help(
                                    "write <connect body1=\"a\" body2=\"b\" anchor=\"x y z\"/>",
                                ));
                        };
                        let b2 = body("body2", true)?.unwrap_or(0);
                        let Some(a) = s.nums_attr(e.n, "anchor", 3)? else {
                            return Err(s
                                .err(e.n, "no anchor", "<connect body1=...> without `anchor`")
                                .with_help("anchor is the point in body1's frame"));
                        };
                        let a = Vector3::new(a[0], a[1], a[2]);
                        let world0 = at0.0[b1] * nalgebra::Point3::from(a);
                        let local2 = at0.0[b2].inverse() * world0;
                        (b1, b2, a, local2.coords)
                    };
                let w1 = at.0[b1] * nalgebra::Point3::from(p1);
                let w2 = at.0[b2] * nalgebra::Point3::from(p2);
                let gap = (w1 - w2).norm();
                if gap > 1e-6 {
                    b.warn(format!(
                        "{loc}: <connect{name_attr}> between `{}` and `{}` is not closed at this configuration (gap {:.3e}): its joint carries body2's point in `second` (`mbsa assemble` closes the loop)",
                        self.bodies[b1].name, self.bodies[b2].name, gap
                    ));
                }
                let id = name.map(str::to_string).unwrap_or_else(|| {
                    format!("connect:{}-{}", self.bodies[b1].name, self.bodies[b2].name)
                });
                b.joint(JointRec {
                    id,
                    kind: JointType::S,
                    bodies: vec![ids[b1], ids[b2]],
                    driven: 0,
                    geometry: super::point_closure(w1.coords, w2.coords),
                    comments: vec![format!("<connect{name_attr}> (loop closure) at {loc}")],
                });
            }
            "weld" => {
                let (b1, b2) = if let (Some(s1), Some(s2)) = (site("site1")?, site("site2")?) {
                    (s1.0, s2.0)
                } else {
                    let Some(b1) = body("body1", false)? else {
                        return Err(s
                            .err(
                                e.n,
                                "no body1",
                                "<weld> needs body1 (and body2), or site1 and site2",
                            )
                            .with_help("write <weld body1=\"a\" body2=\"b\"/>"));
                    };
                    (b1, body("body2", true)?.unwrap_or(0))
                };
                b.weld(ids[b1], ids[b2], &format!("<weld{name_attr}> at {loc}"));
            }
            "joint" | "tendon" | "flex" | "distance" => {
                b.warn(format!(
                    "{loc}: <{tag}{name_attr}> equality coupling: not representable (left out)"
                ));
            }
            _ => {}
        }
        Ok(())
    }
}
