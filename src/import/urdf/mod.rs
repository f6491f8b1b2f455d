//! URDF reader: the link tree at zero joint positions; revolute/continuous, prismatic,
//! floating and planar joints; fixed joints merge links; `<transmission>` gives driven DOF;
//! `mimic` is reported. Loop closures, in the dialects robot users write: Drake's
//! `drake:ball_constraint`, Gazebo's `<gazebo><joint>` extension, the `<constraint>` and
//! `<loop>` elements of the proposed URDF extensions ([`constraint`]), and the Extended-URDF
//! YAML closure file read by Pinocchio users ([`sidecar`]).

mod constraint;
mod sidecar;
#[cfg(test)]
mod tests;

use super::{
    Builder, ImportError, ImportOptions, JointRec, Node, Pose, Src, Unique, arr, child, children,
    pose, rpy, unit,
};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::{Point3, Vector3};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// A joint of the file.
struct UJoint<'a> {
    n: Node<'a>,
    name: String,
    kind: &'a str,
    parent: String,
    child: String,
    origin: Pose,
    axis: Vector3<f64>,
    /// SDFormat's `use_parent_model_frame`: the axis is in the model (root) frame.
    axis_in_model: bool,
}

/// A link of the file: its name and element, in file order.
type Link<'a> = (String, Node<'a>);

/// The links of the file in file order, and their names (for lookups in constant time).
struct Links<'a> {
    list: Vec<Link<'a>>,
    names: HashSet<String>,
}

/// Where the tree puts each link and each joint frame at zero joint positions: what the
/// loop closures refer to.
pub(super) struct Frames {
    /// World pose of each link.
    links: HashMap<String, Pose>,
    /// Each joint (fixed ones too): its child link and the world pose of its frame.
    joints: HashMap<String, (String, Pose)>,
}

impl Frames {
    /// The world pose of a link.
    fn link(&self, name: &str) -> Option<Pose> {
        self.links.get(name).copied()
    }
}

/// Read a URDF document; `base_dir` and `options` locate the YAML closure file, if any.
pub(super) fn read(
    src: &Src,
    doc: &roxmltree::Document,
    base_dir: Option<&Path>,
    options: &ImportOptions,
) -> Result<Builder, ImportError> {
    let closures = sidecar::load(src, base_dir, options)?;
    let root = doc.root_element();
    let robot = root.attribute("name").unwrap_or("robot");
    let mut links = read_links(src, root)?;
    let implicit_world = add_implicit_world(root, &mut links);
    let mut joints: Vec<UJoint> = Vec::new();
    let mut joint_names = Unique::new("joint");
    for j in children(root, "joint") {
        let uj = parse_joint(src, j, &links, false)?;
        joint_names.add(src, j, "name", &uj.name)?;
        joints.push(uj);
    }
    let roots = tree_roots(src, &joints, &links.list)?;
    let Some(&frame) = roots.first() else {
        return Err(src
            .err(
                root,
                "no root link",
                "every link is the child of a joint: the tree has no root",
            )
            .with_help("one link (the base) must be the child of no joint"));
    };
    let mut b = Builder::new(robot, frame, "the URDF root link");
    b.configuration = "every joint at position 0 (URDF has no default positions)".into();
    if implicit_world {
        b.notes.push(
            "joints name the link `world`, which the file does not define: it is the world \
             (Drake's and Gazebo's convention)"
                .into(),
        );
    }
    let (world, joint_world) = world_poses(src, &joints, &roots)?;
    for (name, _) in &links.list {
        b.body(name, "");
    }
    for extra in roots.iter().skip(1) {
        let fb = b.frame;
        let e = b.body(extra, "");
        b.warn(format!(
            "link `{extra}` is a second root: given a free (F) joint to `{frame}`"
        ));
        b.joint(JointRec {
            id: format!("{extra}:free"),
            kind: JointType::F,
            bodies: vec![fb, e],
            driven: 0,
            geometry: Geometry::default(),
            comments: vec![format!("second root link `{extra}`: free")],
        });
    }
    let index = add_tree_joints(src, &mut b, &joints, &joint_world)?;
    read_transmissions(src, root, &mut b, &index);
    let frames = Frames {
        joints: joints
            .iter()
            .zip(&joint_world)
            .filter_map(|(j, w)| Some((j.name.clone(), (j.child.clone(), (*w)?))))
            .collect(),
        links: world,
    };
    read_closures(src, root, &mut b, &links, &frames)?;
    if let Some(c) = closures {
        c.apply(&mut b, &frames, &index)?;
    }
    Ok(b)
}

/// Drake and Gazebo read a joint whose parent is `world`, a link the file does not define, as
/// joined to the world: such a file gets that link, first (so it is the frame).
fn add_implicit_world<'a>(root: Node<'a>, links: &mut Links<'a>) -> bool {
    const WORLD: &str = "world";
    let named = children(root, "joint")
        .filter_map(|j| child(j, "parent"))
        .any(|p| p.attribute("link") == Some(WORLD));
    if !named || links.names.contains(WORLD) {
        return false;
    }
    links.list.insert(0, (WORLD.to_string(), root));
    links.names.insert(WORLD.to_string());
    true
}

/// The `<link>` elements, names unique and not empty.
fn read_links<'a>(src: &Src, root: Node<'a>) -> Result<Links<'a>, ImportError> {
    let mut list: Vec<Link> = Vec::new();
    let mut unique = Unique::new("link");
    for l in children(root, "link") {
        let Some(name) = l.attribute("name") else {
            return Err(src
                .err(l, "no name", "<link> without a `name`")
                .with_help("every URDF link has a unique name"));
        };
        if name.is_empty() {
            return Err(src
                .err_attr(l, "name", "empty", "<link> with an empty `name`")
                .with_help("every URDF link has a unique, non-empty name"));
        }
        unique.add(src, l, "name", name)?;
        list.push((name.to_string(), l));
    }
    let names = list.iter().map(|(n, _)| n.clone()).collect();
    Ok(Links { list, names })
}

/// The links that are the child of no joint, in link order; each link is the child of at most
/// one joint (the file is a tree).
fn tree_roots<'l>(
    src: &Src,
    joints: &[UJoint],
    links: &'l [Link],
) -> Result<Vec<&'l str>, ImportError> {
    let mut parent_of: HashMap<&str, usize> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        if let Some(&other) = parent_of.get(j.child.as_str()) {
            return Err(src
                .err(j.n, "second parent", format!("link `{}` is the child of joints `{}` and `{}`", j.child, joints[other].name, j.name))
                .with_help("URDF describes a tree; close loops with drake:ball_constraint or a <gazebo> joint"));
        }
        parent_of.insert(j.child.as_str(), k);
    }
    Ok(links
        .iter()
        .map(|(n, _)| n.as_str())
        .filter(|n| !parent_of.contains_key(n))
        .collect())
}

/// World poses of the links and of the joints' frames, walking down from the roots; a joint
/// never reached is on a cycle of parents.
#[allow(clippy::type_complexity)]
fn world_poses(
    src: &Src,
    joints: &[UJoint],
    roots: &[&str],
) -> Result<(HashMap<String, Pose>, Vec<Option<Pose>>), ImportError> {
    let mut world: HashMap<String, Pose> = HashMap::new();
    for r in roots {
        world.insert(r.to_string(), Pose::identity());
    }
    let mut joint_world: Vec<Option<Pose>> = vec![None; joints.len()];
    // Joints by parent link, then down from the roots (each link is the child of one joint).
    let mut by_parent: HashMap<&str, Vec<usize>> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        by_parent.entry(j.parent.as_str()).or_default().push(k);
    }
    let mut stack: Vec<&str> = roots.iter().rev().copied().collect();
    while let Some(link) = stack.pop() {
        let Some(&p) = world.get(link) else { continue };
        for &k in by_parent.get(link).map(Vec::as_slice).unwrap_or(&[]) {
            let j = &joints[k];
            let jw = p * j.origin;
            joint_world[k] = Some(jw);
            world.insert(j.child.clone(), jw);
            stack.push(j.child.as_str());
        }
    }
    for (k, j) in joints.iter().enumerate() {
        if joint_world[k].is_none() {
            return Err(src
                .err(
                    j.n,
                    "in a cycle",
                    format!("joint `{}` is on a cycle of parent links", j.name),
                )
                .with_help(
                    "URDF describes a tree: follow the parents of this joint to find the cycle",
                ));
        }
    }
    Ok((world, joint_world))
}

/// The tree's joints (a `mimic` warned); gives the index of each joint not fixed, by name.
fn add_tree_joints(
    src: &Src,
    b: &mut Builder,
    joints: &[UJoint],
    joint_world: &[Option<Pose>],
) -> Result<HashMap<String, usize>, ImportError> {
    let mut index: HashMap<String, usize> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        let Some(jw) = joint_world[k] else { continue };
        if let Some(ji) = add_joint(src, b, j, jw, "<joint")? {
            index.insert(j.name.clone(), ji);
        }
        if let Some(m) = child(j.n, "mimic") {
            b.warn(format!(
                "{}: joint `{}` mimics `{}` (multiplier {}, offset {}): the coupling is not representable; the joint is imported as independent",
                src.loc(m),
                j.name,
                m.attribute("joint").unwrap_or("?"),
                m.attribute("multiplier").unwrap_or("1"),
                m.attribute("offset").unwrap_or("0")
            ));
        }
    }
    Ok(index)
}

/// `<transmission>`: one driven DOF for each joint it names (up to the joint's grade).
fn read_transmissions(src: &Src, root: Node, b: &mut Builder, index: &HashMap<String, usize>) {
    for t in children(root, "transmission") {
        let tname = t
            .attribute("name")
            .map(|n| format!(" name=\"{n}\""))
            .unwrap_or_default();
        for tj in children(t, "joint") {
            let Some(jn) = tj.attribute("name") else {
                continue;
            };
            match index.get(jn) {
                Some(&ji) => {
                    let j = &mut b.joints[ji];
                    if j.driven < j.kind.grade() as u32 {
                        j.driven += 1;
                        j.comments
                            .push(format!("driven by <transmission{tname}> at {}", src.loc(t)));
                    }
                }
                None => {
                    let loc = src.loc(tj);
                    b.warn(format!("{loc}: <transmission{tname}> names joint `{jn}`, which is fixed or not defined: not counted"));
                }
            }
        }
    }
}

/// Loop closures (Drake ball constraints, Gazebo joints, `<constraint>` and `<loop>`
/// elements); other unknown elements warned.
fn read_closures(
    src: &Src,
    root: Node,
    b: &mut Builder,
    links: &Links,
    frames: &Frames,
) -> Result<(), ImportError> {
    for e in root.children().filter(|c| c.is_element()) {
        match e.tag_name().name() {
            "ball_constraint" => ball_constraint(src, e, b, &frames.links)?,
            "distance_constraint" => constraint::drake_distance(src, e, b, frames)?,
            "gazebo" if e.attribute("reference").is_none() => {
                for gj in children(e, "joint") {
                    let j = parse_joint(src, gj, links, true)?;
                    let Some(child_world) = frames.link(&j.child) else {
                        continue;
                    };
                    // SDFormat semantics: the joint pose is in the child link's frame.
                    let jw = child_world * j.origin;
                    add_joint(src, b, &j, jw, "<gazebo><joint")?;
                }
            }
            "constraint" | "loop" | "coupling" => constraint::read(src, e, b, frames)?,
            "joint" | "link" | "transmission" | "material" | "gazebo" => {}
            other => {
                let loc = src.loc(e);
                b.warn(format!("{loc}: <{other}> not imported"));
            }
        }
    }
    Ok(())
}

/// A `drake:ball_constraint`: an S joint between body A's point and body B's.
fn ball_constraint(
    src: &Src,
    e: Node,
    b: &mut Builder,
    world: &HashMap<String, Pose>,
) -> Result<(), ImportError> {
    let find = |name: &str| -> Option<Pose> { world.get(name).copied() };
    let part = |tag: &str| child(e, tag);
    let (Some(ba), Some(pa), Some(bb), Some(pb)) = (
        part("ball_constraint_body_A"),
        part("ball_constraint_p_AP"),
        part("ball_constraint_body_B"),
        part("ball_constraint_p_BQ"),
    ) else {
        return Err(src
            .err(
                e,
                "incomplete",
                "drake:ball_constraint needs body_A, p_AP, body_B and p_BQ",
            )
            .with_help("see Drake's URDF extension reference"));
    };
    let name_of = |n: Node| -> Result<(String, Pose), ImportError> {
        let name = n.attribute("name").unwrap_or("");
        match find(name) {
            Some(p) => Ok((name.to_string(), p)),
            None => Err(src
                .err_attr(
                    n,
                    "name",
                    "no such link",
                    format!("link `{name}` is not defined"),
                )
                .with_help("name a <link> of the robot")),
        }
    };
    let (na, wa) = name_of(ba)?;
    let (nb, wb) = name_of(bb)?;
    let pa = src
        .nums_attr(pa, "value", 3)?
        .unwrap_or_else(|| vec![0.0; 3]);
    let pb = src
        .nums_attr(pb, "value", 3)?
        .unwrap_or_else(|| vec![0.0; 3]);
    let p1 = wa * Point3::new(pa[0], pa[1], pa[2]);
    let p2 = wb * Point3::new(pb[0], pb[1], pb[2]);
    let loc = src.loc(e);
    if (p1 - p2).norm() > 1e-6 {
        b.warn(format!("{loc}: drake:ball_constraint between `{na}` and `{nb}` is not closed at this configuration (gap {:.3e}): its joint carries body B's point in `second` (`mbsa assemble` closes the loop)", (p1 - p2).norm()));
    }
    let (ia, ib) = (b.body(&na, ""), b.body(&nb, ""));
    b.joint(JointRec {
        id: format!("ball:{na}-{nb}"),
        kind: JointType::S,
        bodies: vec![ia, ib],
        driven: 0,
        geometry: super::point_closure(p1.coords, p2.coords),
        comments: vec![format!("<drake:ball_constraint> (loop closure) at {loc}")],
    });
    Ok(())
}

/// Parse a `<joint>` (URDF attributes, or SDFormat-style children inside `<gazebo>`).
fn parse_joint<'a>(
    src: &Src,
    j: Node<'a>,
    links: &Links,
    sdf_style: bool,
) -> Result<UJoint<'a>, ImportError> {
    let Some(name) = j.attribute("name") else {
        return Err(src
            .err(j, "no name", "<joint> without a `name`")
            .with_help("every URDF joint has a unique name"));
    };
    let Some(kind) = j.attribute("type") else {
        return Err(src
            .err(j, "no type", format!("joint `{name}` has no `type`"))
            .with_help(
                "URDF joint types: revolute, continuous, prismatic, fixed, floating, planar",
            ));
    };
    let parent = joint_link(src, j, name, "parent", links, sdf_style)?;
    let child_link = joint_link(src, j, name, "child", links, sdf_style)?;
    let origin = joint_origin(src, j, sdf_style)?;
    let axis_node = child(j, "axis");
    let axis_in_model = sdf_style
        && axis_node
            .and_then(|a| child(a, "use_parent_model_frame"))
            .and_then(|u| u.text())
            .is_some_and(|t| matches!(t.trim(), "1" | "true"));
    // urdfdom reads no axis for fixed and floating joints (nor SDFormat for ball joints): a
    // zero axis there (CAD exporters write `0 0 0`) is no error.
    let axis_node = axis_node.filter(|_| !matches!(kind, "fixed" | "floating" | "ball"));
    let axis_v = match axis_node {
        Some(a) if sdf_style => match child(a, "xyz") {
            Some(x) => src.nums_text(x, 3)?,
            None => vec![1.0, 0.0, 0.0],
        },
        Some(a) => src
            .nums_attr(a, "xyz", 3)?
            .unwrap_or_else(|| vec![1.0, 0.0, 0.0]),
        None => vec![1.0, 0.0, 0.0],
    };
    let Some(axis) = unit(&axis_v) else {
        let a = axis_node.unwrap_or(j);
        return Err(src
            .err(
                a,
                "zero axis",
                format!("joint `{name}` has an axis of zero length"),
            )
            .with_help("axis xyz gives the joint axis direction"));
    };
    Ok(UJoint {
        n: j,
        name: name.to_string(),
        kind,
        parent,
        child: child_link,
        origin,
        axis,
        axis_in_model,
    })
}

/// The link a joint's `<parent>` or `<child>` (`tag`) names, defined in `links`.
fn joint_link(
    src: &Src,
    j: Node,
    name: &str,
    tag: &str,
    links: &Links,
    sdf_style: bool,
) -> Result<String, ImportError> {
    let Some(n) = child(j, tag) else {
        return Err(src
            .err(
                j,
                format!("no <{tag}>"),
                format!("joint `{name}` has no <{tag}>"),
            )
            .with_help(format!("write <{tag} link=\"...\"/>")));
    };
    let l = if sdf_style {
        n.text().unwrap_or("").trim()
    } else {
        n.attribute("link").unwrap_or("")
    };
    if !links.names.contains(l) {
        let at = if sdf_style {
            src.err_text(
                n,
                "no such link",
                format!("joint `{name}` names link `{l}`, which is not defined"),
            )
        } else {
            src.err_attr(
                n,
                "link",
                "no such link",
                format!("joint `{name}` names link `{l}`, which is not defined"),
            )
        };
        return Err(at.with_help("name a <link> of the robot"));
    }
    Ok(l.to_string())
}

/// A joint's pose in its parent link: `<origin xyz rpy>`, or SDFormat's `<pose>`.
fn joint_origin(src: &Src, j: Node, sdf_style: bool) -> Result<Pose, ImportError> {
    Ok(if sdf_style {
        match child(j, "pose") {
            Some(p) => {
                let v = src.nums_text(p, 6)?;
                pose([v[0], v[1], v[2]], rpy(v[3], v[4], v[5]))
            }
            None => Pose::identity(),
        }
    } else {
        match child(j, "origin") {
            Some(o) => {
                let xyz = src.nums_attr(o, "xyz", 3)?.unwrap_or_else(|| vec![0.0; 3]);
                let r = src.nums_attr(o, "rpy", 3)?.unwrap_or_else(|| vec![0.0; 3]);
                pose([xyz[0], xyz[1], xyz[2]], rpy(r[0], r[1], r[2]))
            }
            None => Pose::identity(),
        }
    })
}

/// Add a parsed joint whose frame is at `jw` in the world; `None` for a fixed joint (merged).
fn add_joint(
    src: &Src,
    b: &mut Builder,
    j: &UJoint,
    jw: Pose,
    tag: &str,
) -> Result<Option<usize>, ImportError> {
    let p = b.body(&j.parent, "");
    let c = b.body(&j.child, "");
    let origin = arr(jw.translation.vector);
    // SDFormat 1.5/1.6 `use_parent_model_frame`: the URDF root link is the model frame.
    let axis = arr(if j.axis_in_model {
        j.axis
    } else {
        jw.rotation * j.axis
    });
    let (kind, geometry) = match j.kind {
        "revolute" | "continuous" => (
            JointType::R,
            Geometry {
                origin: Some(origin),
                axis: Some(axis),
                ..Geometry::default()
            },
        ),
        "prismatic" => (
            JointType::P,
            Geometry {
                origin: Some(origin),
                axis: Some(axis),
                ..Geometry::default()
            },
        ),
        "floating" | "free" => (JointType::F, Geometry::default()),
        "planar" => (
            JointType::PL,
            Geometry {
                origin: Some(origin),
                normal: Some(axis),
                ..Geometry::default()
            },
        ),
        "ball" => (
            JointType::S,
            Geometry {
                origin: Some(origin),
                ..Geometry::default()
            },
        ),
        "fixed" => {
            b.weld(p, c, &format!("fixed joint `{}`", j.name));
            return Ok(None);
        }
        other => {
            return Err(src
                .err_attr(
                    j.n,
                    "type",
                    "unknown type",
                    format!("joint `{}` has the unknown type `{other}`", j.name),
                )
                .with_help(
                    "URDF joint types: revolute, continuous, prismatic, fixed, floating, planar",
                ));
        }
    };
    Ok(Some(b.joint(JointRec {
        id: j.name.clone(),
        kind,
        bodies: vec![p, c],
        driven: 0,
        geometry,
        comments: vec![format!(
            "{tag} name=\"{}\" type=\"{}\"> at {}",
            j.name,
            j.kind,
            src.loc(j.n)
        )],
    })))
}
