//! SDFormat reader (1.4 to 1.10): models (in `<sdf>` or a `<world>`), links, frames and joints
//! with each version's frame rules. Before 1.7 a link pose is relative to the model and a joint
//! pose to its child link; the joint axis is in the joint frame (1.5, 1.6) unless
//! `use_parent_model_frame`, in the model frame (1.4). From 1.7, `relative_to`, `<frame>`,
//! `attached_to` and `expressed_in` name the frames (defaults: model for links, child link for
//! joints, joint for axes).

use super::{
    Builder, ImportError, JointRec, Node, Pose, Src, Unique, arr, child, children, pose, rpy, unit,
    unit_quat,
};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::{UnitQuaternion, Vector3};
use std::collections::HashMap;

/// Read an SDFormat document.
pub(super) fn read(src: &Src, doc: &roxmltree::Document) -> Result<Builder, ImportError> {
    let root = doc.root_element();
    let version = match root.attribute("version") {
        Some(v) => parse_version(v).ok_or_else(|| {
            src.err_attr(
                root,
                "version",
                "not a version",
                format!("unknown SDFormat version `{v}`"),
            )
            .with_help("the importer reads SDFormat 1.4 to 1.10 (version=\"1.x\")")
        })?,
        None => {
            return Err(src
                .err(root, "no version", "<sdf> without a `version`")
                .with_help("write <sdf version=\"1.7\"> (1.4 to 1.10 are read)"));
        }
    };
    if !(4..=10).contains(&version) {
        return Err(src
            .err_attr(
                root,
                "version",
                "unsupported",
                format!("SDFormat 1.{version} is not supported"),
            )
            .with_help("the importer reads SDFormat 1.4 to 1.10"));
    }
    let mut models: Vec<(Node, Pose)> = Vec::new();
    for m in children(root, "model") {
        models.push((m, Pose::identity()));
    }
    for w in children(root, "world") {
        for m in children(w, "model") {
            models.push((m, Pose::identity()));
        }
    }
    // Models by URI are not resolved: said, also when nothing else is there to read.
    let includes: Vec<String> = root
        .descendants()
        .filter(|n| n.has_tag_name("include"))
        .map(|inc| {
            let uri = child(inc, "uri")
                .and_then(|u| u.text())
                .unwrap_or("")
                .trim();
            format!(
                "{}: <include> of a model by URI (`{uri}`) not resolved: not imported",
                src.loc(inc)
            )
        })
        .collect();
    let mut model_names = Unique::new("model");
    for (m, _) in &models {
        model_names.add(src, *m, "name", m.attribute("name").unwrap_or("model"))?;
    }
    let Some(first) = models.first() else {
        if !includes.is_empty() {
            return Err(src
                .err(root, "no model", "no <model> in the file: its models are <include>d by URI, which the importer does not resolve")
                .with_help(format!("{} (write the included models into the file)", includes.join("; "))));
        }
        return Err(src
            .err(root, "no model", "no <model> in the file")
            .with_help("the importer reads the <model> elements of <sdf> or of its <world>"));
    };
    let name = if models.len() == 1 {
        first.0.attribute("name").unwrap_or("model").to_string()
    } else {
        root.children()
            .find(|c| c.has_tag_name("world"))
            .and_then(|w| w.attribute("name"))
            .unwrap_or("world")
            .to_string()
    };
    let mut b = Builder::new(&name, "world", "the SDFormat world");
    b.configuration = "every joint at position 0 (the poses as written)".into();
    let scoped = models.len() > 1;
    for (m, _) in &models {
        read_model(src, *m, version, scoped, &mut b)?;
    }
    for w in includes {
        b.warn(w);
    }
    b.notes.push(format!("SDFormat 1.{version} frame rules"));
    // SDFormat has no actuator element: what drives a model's joints is plugin code (a Gazebo
    // controller), which nothing here reads. Said, so that "0 driven DOF" is not a surprise.
    b.notes.push(
        "SDFormat declares no actuators: no joint is driven (write `driven` on the driven \
         joints, or give them with `--inputs`)"
            .into(),
    );
    Ok(b)
}

fn parse_version(v: &str) -> Option<u32> {
    let (major, minor) = v.trim().split_once('.')?;
    (major == "1").then_some(())?;
    minor.parse().ok()
}

/// A pose element: `x y z roll pitch yaw` (or 1.9+ `rotation_format="quat_xyzw"`, `degrees`).
fn parse_pose(src: &Src, p: Node) -> Result<Pose, ImportError> {
    let text = p.text().unwrap_or("").trim();
    if text.is_empty() {
        return Ok(Pose::identity());
    }
    if p.attribute("rotation_format") == Some("quat_xyzw") {
        let v = src.nums_text(p, 7)?;
        let Some(q) = unit_quat(v[6], v[3], v[4], v[5]) else {
            return Err(src
                .err_text(p, "zero quaternion", "a zero quaternion")
                .with_help("quat_xyzw poses are x y z qx qy qz qw"));
        };
        return Ok(pose([v[0], v[1], v[2]], q));
    }
    let v = src.nums_text_unnoted(p, 6)?;
    let k = if p.attribute("degrees") == Some("true") {
        std::f64::consts::PI / 180.0
    } else {
        1.0
    };
    src.note(&v[..3], 1.0);
    src.note(&v[3..], k);
    Ok(pose([v[0], v[1], v[2]], rpy(v[3] * k, v[4] * k, v[5] * k)))
}

/// A frame's pose: relative to `relative_to` (None: the element's default frame).
struct FrameDef<'a> {
    pose: Pose,
    relative_to: Option<String>,
    default: String,
    n: Node<'a>,
}

/// A joint of a model: its element, name, type and the frames it joins.
struct SJoint<'a> {
    n: Node<'a>,
    name: String,
    kind: String,
    parent: String,
    child: String,
}

/// One `<model>` being read: its frames (links, `<frame>`s, joints) and their poses resolved
/// to the model frame.
struct ModelRead<'a, 's> {
    src: &'s Src<'s>,
    m: Node<'a>,
    mname: &'a str,
    version: u32,
    /// Names scoped `model::name` (several models in one world).
    scoped: bool,
    model_pose: Pose,
    frames: HashMap<String, FrameDef<'a>>,
    links: Vec<(String, Node<'a>)>,
    /// Frames resolved to the model frame so far.
    resolved: HashMap<String, Pose>,
}

/// Read one `<model>` into the builder: links as bodies, joints, and a free joint for each
/// part not joined to the world.
fn read_model(
    src: &Src,
    m: Node,
    version: u32,
    scoped: bool,
    b: &mut Builder,
) -> Result<(), ImportError> {
    let mname = m.attribute("name").unwrap_or("model");
    let model_pose = match child(m, "pose") {
        Some(p) => parse_pose(src, p)?,
        None => Pose::identity(),
    };
    let is_static = child(m, "static")
        .and_then(|s| s.text())
        .map(|t| t.trim() == "true" || t.trim() == "1")
        .unwrap_or(false);
    warn_plugins_and_nested(src, m, b);
    for p in m.children().filter(|c| {
        c.tag_name().namespace() == Some(super::MBSA_NAMESPACE)
            && c.tag_name().name() == "precision"
    }) {
        let v = src.nums_text_unnoted(p, 0)?;
        super::declared_precision(src, p, &v, b)?;
    }
    let mut r = ModelRead {
        src,
        m,
        mname,
        version,
        scoped,
        model_pose,
        frames: HashMap::new(),
        links: Vec::new(),
        resolved: HashMap::new(),
    };
    r.read_links()?;
    r.read_frames()?;
    let joints = r.read_joints()?;
    // Resolve every frame to the model frame.
    r.resolved.insert("__model__".into(), Pose::identity());
    r.resolved.insert("world".into(), model_pose.inverse());
    for (l, _) in &r.links {
        b.body(&r.scope(l), "");
    }
    let frame_body = b.frame;
    let mut bodies_of_joint: Vec<(usize, usize)> = Vec::new();
    for j in &joints {
        let (p, c) = r.joint_bodies(b, j, frame_body)?;
        bodies_of_joint.push((p, c));
        r.add_joint(b, j, p, c)?;
    }
    r.float_unjoined(b, &bodies_of_joint, is_static, frame_body);
    Ok(())
}

/// Warnings for the model's plugins (code, not read) and nested models (not supported).
fn warn_plugins_and_nested(src: &Src, m: Node, b: &mut Builder) {
    for plugin in m.descendants().filter(|n| n.has_tag_name("plugin")) {
        let loc = src.loc(plugin);
        b.warn(format!(
            "{loc}: <plugin> `{}` ({}) not read: a plugin is code, and one that drives joints \
             drives none here; give the driven joints with `--inputs` or `driven`",
            plugin.attribute("name").unwrap_or(""),
            plugin.attribute("filename").unwrap_or("no filename")
        ));
    }
    for nested in children(m, "model") {
        let loc = src.loc(nested);
        b.warn(format!(
            "{loc}: nested <model> `{}` not supported: not imported",
            nested.attribute("name").unwrap_or("")
        ));
    }
}

/// A frame name to its resolved pose in the model frame, through `relative_to` or the default
/// frame of each element.
fn resolve(
    name: &str,
    frames: &HashMap<String, FrameDef>,
    resolved: &mut HashMap<String, Pose>,
    src: &Src,
    depth: usize,
) -> Result<Pose, ImportError> {
    if let Some(p) = resolved.get(name) {
        return Ok(*p);
    }
    let Some(f) = frames.get(name) else {
        return Err(ImportError::new(format!("unknown frame `{name}`")));
    };
    if depth > frames.len() + 2 {
        return Err(src
            .err(
                f.n,
                "in a cycle",
                format!("the poses of frame `{name}` refer to each other in a cycle"),
            )
            .with_help("relative_to and attached_to must lead to the model frame"));
    }
    let base_name = f.relative_to.clone().unwrap_or_else(|| f.default.clone());
    if base_name != "world" && base_name != "__model__" && !frames.contains_key(&base_name) {
        let e = match &f.relative_to {
            Some(_) => child(f.n, "pose").map(|p| {
                src.err_attr(
                    p,
                    "relative_to",
                    "no such frame",
                    format!("relative_to names `{base_name}`, which is not a frame of the model"),
                )
            }),
            None => None,
        };
        return Err(e
            .unwrap_or_else(|| {
                src.err(
                    f.n,
                    "no such frame",
                    format!("`{base_name}` is not a frame of the model"),
                )
            })
            .with_help("name a link, joint or frame of the same model, `__model__` or `world`"));
    }
    let base = resolve(&base_name, frames, resolved, src, depth + 1)?;
    let p = base * f.pose;
    resolved.insert(name.to_string(), p);
    Ok(p)
}

impl<'a> ModelRead<'a, '_> {
    /// A name as a body or joint id: `model::name` when several models are read.
    fn scope(&self, n: &str) -> String {
        if self.scoped && n != "world" {
            format!("{}::{n}", self.mname)
        } else {
            n.to_string()
        }
    }

    /// The frame an element's pose is relative to (1.7+ `relative_to`).
    fn rel(&self, n: Node) -> Option<String> {
        if self.version >= 7 {
            child(n, "pose")
                .and_then(|p| p.attribute("relative_to"))
                .filter(|s| !s.is_empty())
                .map(str::to_string)
        } else {
            None
        }
    }

    /// An element's own `<pose>` (identity when none).
    fn own_pose(&self, n: Node) -> Result<Pose, ImportError> {
        let src = self.src;
        match child(n, "pose") {
            Some(p) => {
                if self.version < 7 && p.attribute("frame").is_some_and(|f| !f.is_empty()) {
                    return Err(src
                        .err_attr(
                            p,
                            "frame",
                            "not supported",
                            "<pose frame=...> (SDFormat 1.5/1.6) is not supported",
                        )
                        .with_help(
                            "use SDFormat 1.7 relative_to, or poses relative to the default frames",
                        ));
                }
                parse_pose(src, p)
            }
            None => Ok(Pose::identity()),
        }
    }

    /// The `<link>` elements, each a frame relative to the model by default.
    fn read_links(&mut self) -> Result<(), ImportError> {
        let mut names = Unique::new("link");
        for l in children(self.m, "link") {
            let Some(name) = l.attribute("name") else {
                return Err(self
                    .src
                    .err(l, "no name", "<link> without a `name`")
                    .with_help("every link has a unique name"));
            };
            if name.is_empty() || name == "world" || name == "__model__" {
                return Err(self
                    .src
                    .err_attr(l, "name", "reserved", format!("a link named `{name}`"))
                    .with_help("`world` and `__model__` are frames of SDFormat, and a link needs a name: rename this one"));
            }
            names.add(self.src, l, "name", name)?;
            self.links.push((name.to_string(), l));
            let def = FrameDef {
                pose: self.own_pose(l)?,
                relative_to: self.rel(l),
                default: "__model__".into(),
                n: l,
            };
            self.frames.insert(name.to_string(), def);
        }
        Ok(())
    }

    /// The `<frame>` elements (1.7+), each relative to what it is attached to by default.
    fn read_frames(&mut self) -> Result<(), ImportError> {
        if self.version < 7 {
            return Ok(());
        }
        for f in children(self.m, "frame") {
            let Some(name) = f.attribute("name") else {
                return Err(self
                    .src
                    .err(f, "no name", "<frame> without a `name`")
                    .with_help("every frame has a unique name"));
            };
            let attached = f
                .attribute("attached_to")
                .filter(|s| !s.is_empty())
                .unwrap_or("__model__");
            let def = FrameDef {
                pose: self.own_pose(f)?,
                relative_to: self.rel(f),
                default: attached.to_string(),
                n: f,
            };
            self.frames.insert(name.to_string(), def);
        }
        Ok(())
    }

    /// The `<joint>` elements, each a frame relative to its child link by default.
    fn read_joints(&mut self) -> Result<Vec<SJoint<'a>>, ImportError> {
        let mut joints: Vec<SJoint> = Vec::new();
        let mut names = Unique::new("joint");
        for j in children(self.m, "joint") {
            let Some(name) = j.attribute("name") else {
                return Err(self
                    .src
                    .err(j, "no name", "<joint> without a `name`")
                    .with_help("every joint has a unique name"));
            };
            names.add(self.src, j, "name", name)?;
            let kind = j.attribute("type").unwrap_or("").to_string();
            let parent = self.joint_link(j, name, "parent")?;
            let child_link = self.joint_link(j, name, "child")?;
            let def = FrameDef {
                pose: self.own_pose(j)?,
                relative_to: self.rel(j),
                default: child_link.clone(),
                n: j,
            };
            self.frames.insert(name.to_string(), def);
            joints.push(SJoint {
                n: j,
                name: name.to_string(),
                kind,
                parent,
                child: child_link,
            });
        }
        Ok(joints)
    }

    /// The link or frame a joint's `<parent>` or `<child>` (`tag`) names (or `world`).
    fn joint_link(&self, j: Node, name: &str, tag: &str) -> Result<String, ImportError> {
        let src = self.src;
        let Some(n) = child(j, tag) else {
            return Err(src
                .err(
                    j,
                    format!("no <{tag}>"),
                    format!("joint `{name}` has no <{tag}>"),
                )
                .with_help(format!("write <{tag}>link name</{tag}>")));
        };
        let l = n.text().unwrap_or("").trim().to_string();
        if l != "world" && !self.frames.contains_key(&l) {
            return Err(src
                .err_text(
                    n,
                    "no such link",
                    format!(
                        "joint `{name}` names `{l}`, which is not a link or frame of model `{}`",
                        self.mname
                    ),
                )
                .with_help("name a <link> of the model, or `world`"));
        }
        Ok(l)
    }

    /// The world pose of a frame.
    fn world_of(&mut self, name: &str) -> Result<Pose, ImportError> {
        Ok(self.model_pose * resolve(name, &self.frames, &mut self.resolved, self.src, 0)?)
    }

    /// The bodies a joint joins: the link each of its frames is attached to (`world`: the
    /// frame body).
    fn joint_bodies(
        &self,
        b: &mut Builder,
        j: &SJoint,
        frame_body: usize,
    ) -> Result<(usize, usize), ImportError> {
        // Link a frame name to its body (a frame attached to a link belongs to that link).
        let body_of = |n: &str| -> String {
            let mut cur = n.to_string();
            for _ in 0..=self.frames.len() {
                if cur == "world" || self.links.iter().any(|(l, _)| *l == cur) {
                    return cur;
                }
                match self.frames.get(&cur) {
                    Some(f) => cur = f.default.clone(),
                    None => break,
                }
            }
            cur
        };
        let (pn, cn) = (body_of(&j.parent), body_of(&j.child));
        if pn == "__model__" || cn == "__model__" {
            return Err(self
                .src
                .err(
                    j.n,
                    "not a link",
                    format!("joint `{}` joins a frame not attached to a link", j.name),
                )
                .with_help("attach the frame to a link"));
        }
        let p = if pn == "world" {
            frame_body
        } else {
            b.body(&self.scope(&pn), "")
        };
        let c = if cn == "world" {
            frame_body
        } else {
            b.body(&self.scope(&cn), "")
        };
        Ok((p, c))
    }

    /// A joint's axis `<tag><xyz>` in the world, by the version's rules for the frame it is
    /// expressed in (`jw`: the joint's world pose); `None` when not written.
    fn axis_of(
        &mut self,
        j: &SJoint,
        jw: &Pose,
        tag: &str,
    ) -> Result<Option<Vector3<f64>>, ImportError> {
        let src = self.src;
        let Some(a) = child(j.n, tag) else {
            return Ok(None);
        };
        let Some(x) = child(a, "xyz") else {
            return Ok(None);
        };
        let v = src.nums_text(x, 3)?;
        let Some(v) = unit(&v) else {
            return Err(src
                .err_text(
                    x,
                    "zero",
                    format!("joint `{}`: an axis of zero length", j.name),
                )
                .with_help("xyz gives the axis direction"));
        };
        let frame_rot = if self.version >= 7 {
            match x.attribute("expressed_in").filter(|s| !s.is_empty()) {
                Some("__model__") => self.model_pose.rotation,
                Some("world") => UnitQuaternion::identity(),
                Some(f) => {
                    if !self.frames.contains_key(f) {
                        return Err(src
                            .err_attr(
                                x,
                                "expressed_in",
                                "no such frame",
                                format!(
                                    "expressed_in names `{f}`, which is not a frame of the model"
                                ),
                            )
                            .with_help(
                                "name a link, joint or frame of the model, `__model__` or `world`",
                            ));
                    }
                    self.world_of(f)?.rotation
                }
                None => jw.rotation,
            }
        } else if self.version == 4 {
            self.model_pose.rotation
        } else {
            let upm = child(a, "use_parent_model_frame")
                .and_then(|u| u.text())
                .map(|t| t.trim() == "true" || t.trim() == "1")
                .unwrap_or(false);
            if upm {
                self.model_pose.rotation
            } else {
                jw.rotation
            }
        };
        Ok(Some(frame_rot * v))
    }

    /// Add joint `j` between bodies `p` and `c` by its type (a fixed joint welds them, a
    /// gearbox is left out).
    fn add_joint(
        &mut self,
        b: &mut Builder,
        j: &SJoint,
        p: usize,
        c: usize,
    ) -> Result<(), ImportError> {
        let src = self.src;
        let jw = self.world_of(&j.name)?;
        let origin = Some(arr(jw.translation.vector));
        let axis = self.axis_of(j, &jw, "axis")?;
        let axis2 = self.axis_of(j, &jw, "axis2")?;
        let Some((kind, geometry)) = joint_geometry(src, b, j, origin, axis, axis2)? else {
            if j.kind == "fixed" {
                b.weld(p, c, &format!("fixed joint `{}`", j.name));
            }
            return Ok(());
        };
        b.joint(JointRec {
            id: self.scope(&j.name),
            kind,
            bodies: vec![p, c],
            driven: 0,
            geometry,
            comments: vec![format!(
                "<joint name=\"{}\" type=\"{}\"> at {}",
                j.name,
                j.kind,
                src.loc(j.n)
            )],
        });
        Ok(())
    }

    /// Links not joined to the world float (Gazebo), unless the model is static (then welded
    /// to it): a free joint for the first link of each floating part.
    fn float_unjoined(
        &self,
        b: &mut Builder,
        bodies_of_joint: &[(usize, usize)],
        is_static: bool,
        frame_body: usize,
    ) {
        let mut adj: HashMap<usize, Vec<usize>> = HashMap::new();
        for &(p, c) in bodies_of_joint {
            adj.entry(p).or_default().push(c);
            adj.entry(c).or_default().push(p);
        }
        let mut reached: Vec<usize> = vec![frame_body];
        let mut stack = vec![frame_body];
        while let Some(x) = stack.pop() {
            for &y in adj.get(&x).map(Vec::as_slice).unwrap_or(&[]) {
                if !reached.contains(&y) {
                    reached.push(y);
                    stack.push(y);
                }
            }
        }
        for (l, _) in &self.links {
            let id = b.body(&self.scope(l), "");
            if reached.contains(&id) {
                continue;
            }
            if is_static {
                b.weld(frame_body, id, &format!("model `{}` is static", self.mname));
                reached.push(id);
                continue;
            }
            let mut part = vec![id];
            let mut st = vec![id];
            while let Some(x) = st.pop() {
                for &y in adj.get(&x).map(Vec::as_slice).unwrap_or(&[]) {
                    if !part.contains(&y) {
                        part.push(y);
                        st.push(y);
                    }
                }
            }
            reached.extend(&part);
            b.joint(JointRec {
                id: format!("{}:free", self.scope(l)),
                kind: JointType::F,
                bodies: vec![frame_body, id],
                driven: 0,
                geometry: Geometry::default(),
                comments: vec![format!("link `{l}` and the links joined to it are not joined to the world: free (as Gazebo simulates it)")],
            });
        }
    }
}

/// A joint's type and geometry by its SDFormat type (`origin`, `axis`, `axis2` in the world);
/// `None` for a fixed joint (welded) and a gearbox (warned, left out).
fn joint_geometry(
    src: &Src,
    b: &mut Builder,
    j: &SJoint,
    origin: Option<[f64; 3]>,
    axis: Option<Vector3<f64>>,
    axis2: Option<Vector3<f64>>,
) -> Result<Option<(JointType, Geometry)>, ImportError> {
    let need_axis = |a: Option<Vector3<f64>>, tag: &str| -> Result<[f64; 3], ImportError> {
        match a {
            Some(a) => Ok(arr(a)),
            None => Err(src
                .err(
                    j.n,
                    format!("no <{tag}>"),
                    format!("joint `{}` ({}) has no <{tag}><xyz>", j.name, j.kind),
                )
                .with_help(format!("write <{tag}><xyz>0 0 1</xyz></{tag}>"))),
        }
    };
    Ok(Some(match j.kind.as_str() {
        "revolute" | "continuous" => (
            JointType::R,
            Geometry {
                origin,
                axis: Some(need_axis(axis, "axis")?),
                ..Geometry::default()
            },
        ),
        "prismatic" => (
            JointType::P,
            Geometry {
                origin,
                axis: Some(need_axis(axis, "axis")?),
                ..Geometry::default()
            },
        ),
        "ball" => (
            JointType::S,
            Geometry {
                origin,
                ..Geometry::default()
            },
        ),
        "universal" | "revolute2" => (
            JointType::U,
            Geometry {
                origin,
                axis: Some(need_axis(axis, "axis")?),
                axis2: Some(need_axis(axis2, "axis2")?),
                ..Geometry::default()
            },
        ),
        "screw" => {
            let pitch = screw_pitch(src, j)?;
            (
                JointType::H,
                Geometry {
                    origin,
                    axis: Some(need_axis(axis, "axis")?),
                    pitch: Some(pitch),
                    ..Geometry::default()
                },
            )
        }
        "fixed" => return Ok(None),
        "gearbox" => {
            let loc = src.loc(j.n);
            b.warn(format!(
                "{loc}: gearbox joint `{}` couples two joints: not representable (left out)",
                j.name
            ));
            return Ok(None);
        }
        other => {
            return Err(src.err_attr(j.n, "type", "unknown type", format!("joint `{}` has the unknown type `{other}`", j.name)).with_help("SDFormat joint types: revolute, prismatic, ball, universal, revolute2, screw, fixed, continuous, gearbox"));
        }
    }))
}

/// A screw joint's pitch (length per radian): 1.10 `screw_thread_pitch` in metres per
/// revolution; earlier `thread_pitch` in radians per metre (Gazebo's reading).
fn screw_pitch(src: &Src, j: &SJoint) -> Result<f64, ImportError> {
    Ok(if let Some(p) = child(j.n, "screw_thread_pitch") {
        src.nums_text(p, 1)?[0] / (2.0 * std::f64::consts::PI)
    } else if let Some(p) = child(j.n, "thread_pitch") {
        let v = src.nums_text(p, 1)?[0];
        if v == 0.0 { 0.0 } else { 1.0 / v }
    } else {
        1.0
    })
}
