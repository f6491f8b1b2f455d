//! The MJCF body tree: elements with `<include>` resolved, default classes, poses and
//! orientations, and the walk that numbers bodies and joints in MuJoCo's order.

use super::{Ctx, E, Kind, MAX_FRAME_DEPTH, MBody, MJoint, Pending};
use crate::import::{ImportError, Node, Pose, Src, pose, tame, unit, unit_quat};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};

impl<'d> Ctx<'d> {
    /// Child elements, `<include>` replaced by the children of the included file's root.
    pub(super) fn kids(&self, e: E<'d>, docs: &'d [roxmltree::Document<'d>]) -> Vec<E<'d>> {
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

    pub(super) fn defaults(
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

    pub(super) fn angle(&self, x: f64) -> f64 {
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
            return unit_quat(q[0], q[1], q[2], q[3]).ok_or_else(|| {
                s.err_attr(n, "quat", "zero", "a zero quaternion")
                    .with_help("quat is w x y z, not all zero")
            });
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
            return Ok(self.euler(&a));
        }
        if let Some(a) = s.nums_attr(n, "xyaxes", 6)? {
            return xyaxes(s, n, &a);
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
    pub(super) fn walk(
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
            let name = k.n.attribute("name").filter(|n| !n.is_empty());
            if name == Some("world") {
                return Err(s
                    .err_attr(k.n, "name", "reserved", "a body named `world`")
                    .with_help("`world` is MuJoCo's world body; rename this one"));
            }
            if let Some(n) = name {
                let srcs: &'d [Src<'d>] = self.srcs;
                self.body_names.add(&srcs[k.f], k.n, "name", n)?;
            }
            let cc =
                k.n.attribute("childclass")
                    .map(str::to_string)
                    .or(childclass);
            self.bodies.push(MBody {
                name: name.unwrap_or_default().to_string(),
                named: name.is_some(),
                parent,
                local,
                joints: Vec::new(),
            });
            self.walk_children(k, idx, Pose::identity(), cc, docs, &mut found, 0)?;
            stack.extend(found.drain(..).rev());
        }
        Ok(())
    }

    /// Name the bodies without a name `body<index>` (`#2`, `#3`... appended when a named body
    /// has that name): the names must not merge an unnamed body with a named one.
    pub(super) fn name_unnamed_bodies(&mut self) {
        let mut taken: std::collections::HashSet<String> = std::collections::HashSet::new();
        for i in 1..self.bodies.len() {
            if self.bodies[i].named {
                continue;
            }
            let base = format!("body{i}");
            let free = |n: &String| !self.body_names.contains(n) && !taken.contains(n);
            let name = std::iter::once(base.clone())
                .chain((2..).map(|k| format!("{base}#{k}")))
                .find(free)
                .unwrap_or(base);
            taken.insert(name.clone());
            self.bodies[i].name = name;
        }
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
                "joint" | "freejoint" => self.read_joint(k, body, rel, &childclass)?,
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

    /// A `<joint>` or `<freejoint>` of `body` (`rel`: the frames between the body and it), its
    /// attributes from its default class chain; its qpos address numbered in order.
    fn read_joint(
        &mut self,
        k: E<'d>,
        body: usize,
        rel: Pose,
        childclass: &Option<String>,
    ) -> Result<(), ImportError> {
        let s = self.src(k);
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
        if let Some(n) = k.n.attribute("name").filter(|n| !n.is_empty()) {
            let srcs: &'d [Src<'d>] = self.srcs;
            self.joint_names.add(&srcs[k.f], k.n, "name", n)?;
        }
        let kind = self.joint_kind(k, &class, free)?;
        let (pos, axis) = self.joint_pos_axis(k, &class, free, rel)?;
        let reference = self.joint_reference(k, &class, kind, free)?;
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
        Ok(())
    }

    /// A joint's position and unit axis in its body's frame (`rel`: the frames between them),
    /// own or by class; a free joint's are the origin and z.
    fn joint_pos_axis(
        &self,
        k: E<'d>,
        class: &str,
        free: bool,
        rel: Pose,
    ) -> Result<(Vector3<f64>, Vector3<f64>), ImportError> {
        let vec3 =
            |cx: &Self, attr: &str, default: [f64; 3]| -> Result<Vector3<f64>, ImportError> {
                match cx.joint_attr(k, class, attr) {
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
                let at = self.joint_attr(k, class, "axis").map(|x| x.1).unwrap_or(k);
                return Err(self
                    .src(at)
                    .err_attr(at.n, "axis", "zero", "a joint axis of zero length")
                    .with_help("axis gives the direction of the joint axis"));
            }
        };
        Ok((pos, axis))
    }

    /// A joint's kind: its `type` (own or by class); `free` for a `<freejoint>`.
    fn joint_kind(&self, k: E<'d>, class: &str, free: bool) -> Result<Kind, ImportError> {
        Ok(if free {
            Kind::Free
        } else {
            match self.joint_attr(k, class, "type") {
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
                        .with_help("MJCF joint types are hinge, slide, ball and free"));
                }
            }
        })
    }

    /// A joint's `ref` (the position of the model as written), in radians for a hinge.
    fn joint_reference(
        &self,
        k: E<'d>,
        class: &str,
        kind: Kind,
        free: bool,
    ) -> Result<f64, ImportError> {
        let reference = match self.joint_attr(k, class, "ref") {
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
        Ok(reference)
    }

    /// The rotation of `euler` angles `a`, composed by the compiler's `eulerseq`.
    fn euler(&self, a: &[f64]) -> UnitQuaternion<f64> {
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
        q
    }
}

/// The rotation of `xyaxes` (`a`: the x axis then the y axis, made orthonormal).
fn xyaxes(s: &Src, n: Node, a: &[f64]) -> Result<UnitQuaternion<f64>, ImportError> {
    let x = tame(Vector3::new(a[0], a[1], a[2]));
    let y = tame(Vector3::new(a[3], a[4], a[5]));
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
    Ok(UnitQuaternion::from_rotation_matrix(&r))
}
