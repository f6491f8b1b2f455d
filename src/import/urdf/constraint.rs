//! The loop-closure elements of the proposed URDF extensions, each a cut joint between two
//! links, its frame given on each side:
//!
//! - URDF+ (Chignoli et al., the `generalized_rbda` parser): `<constraint type="position">`
//!   (the two points coincide: a ball joint) or `type="rolling"` (a gear ratio between the
//!   two links: not representable), with `<predecessor link>` and `<successor link>`, each
//!   holding an `<origin>`; its later form `<loop type="revolute|continuous|prismatic|planar|
//!   fixed">` with the same sides and an `<axis>` in the predecessor's frame, and
//!   `<coupling>` (a gear ratio: not representable).
//! - The urdfdom proposal for closed loops (ros/urdfdom#264): `<constraint
//!   type="revolute|prismatic|universal|spherical|link">` with `<parent link>`,
//!   `<parent_origin>`, `<parent_axis>`, `<child link>`, `<child_origin>`, `<child_axis>`
//!   (a `link` constraint is a cut link: a weld).

use super::Frames;
use crate::import::toml_text::num;
use crate::import::{Builder, ImportError, JointRec, Node, Pose, Src, arr, child, pose, rpy, unit};
use crate::joint::JointType;
use crate::mechanism::{Geometry, Second};
use nalgebra::Vector3;

/// One side of a closure: the link and the world pose of its closure frame.
pub(super) struct Side {
    pub link: String,
    pub frame: Pose,
}

/// What a closure becomes: a joint kind with its axes (in the first side's frame, and the
/// second axis of a universal joint in the second side's), or a weld.
pub(super) enum Cut {
    Joint(JointType, Option<Vector3<f64>>, Option<Vector3<f64>>),
    Weld,
}

/// Read a `<constraint>`, `<loop>` or `<coupling>` element.
pub(super) fn read(
    src: &Src,
    e: Node,
    b: &mut Builder,
    frames: &Frames,
) -> Result<(), ImportError> {
    let tag = e.tag_name().name();
    let Some(name) = e.attribute("name") else {
        return Err(src
            .err(e, "no name", format!("<{tag}> without a `name`"))
            .with_help(format!("every <{tag}> has a unique name")));
    };
    let loc = src.loc(e);
    if tag == "coupling" {
        b.warn(format!(
            "{loc}: <coupling name=\"{name}\"> (a gear ratio between two links) is not representable: not imported"
        ));
        return Ok(());
    }
    let Some(kind) = e.attribute("type") else {
        return Err(src
            .err(
                e,
                "no type",
                format!("<{tag} name=\"{name}\"> has no `type`"),
            )
            .with_help(types_help(tag, child(e, "parent").is_some())));
    };
    let (first, second, cut) = if let Some(p) = child(e, "predecessor") {
        let s = required(src, e, name, "successor")?;
        let first = side(src, p, child(p, "origin"), frames)?;
        let second = side(src, s, child(s, "origin"), frames)?;
        (first, second, urdf_plus_cut(src, e, name, kind)?)
    } else if let Some(p) = child(e, "parent") {
        let c = required(src, e, name, "child")?;
        let first = side(src, p, child(e, "parent_origin"), frames)?;
        let second = side(src, c, child(e, "child_origin"), frames)?;
        (first, second, proposal_cut(src, e, name, kind)?)
    } else {
        return Err(src
            .err(
                e,
                "no links",
                format!("<{tag} name=\"{name}\"> names no links"),
            )
            .with_help(
                "write <predecessor link=\"...\"> and <successor link=\"...\"> (URDF+), or \
                 <parent link=\"...\"/> and <child link=\"...\"/> (the urdfdom proposal)",
            ));
    };
    let Some(cut) = cut else {
        b.warn(format!(
            "{loc}: <{tag} name=\"{name}\" type=\"{kind}\"> (a gear ratio between `{}` and `{}`) is not representable: not imported",
            first.link, second.link
        ));
        return Ok(());
    };
    let what = format!("<{tag} name=\"{name}\" type=\"{kind}\">");
    close(b, name, &cut, &first, &second, &what, &loc);
    Ok(())
}

/// The child element `tag` of a closure element, required.
fn required<'a>(src: &Src, e: Node<'a>, name: &str, tag: &str) -> Result<Node<'a>, ImportError> {
    child(e, tag).ok_or_else(|| {
        let t = e.tag_name().name();
        src.err(
            e,
            format!("no <{tag}>"),
            format!("<{t} name=\"{name}\"> has no <{tag}>"),
        )
        .with_help(format!("write <{tag} link=\"...\"/>"))
    })
}

/// A side: the link an element names (`link`), which must be defined, and its closure frame
/// (`origin`: `xyz`, `rpy`; identity when absent).
fn side(src: &Src, n: Node, origin: Option<Node>, frames: &Frames) -> Result<Side, ImportError> {
    let link = n.attribute("link").unwrap_or("");
    let Some(at) = frames.link(link) else {
        return Err(src
            .err_attr(
                n,
                "link",
                "no such link",
                format!("link `{link}` is not defined"),
            )
            .with_help("name a <link> of the robot"));
    };
    let local = match origin {
        Some(o) => {
            let xyz = src.nums_attr(o, "xyz", 3)?.unwrap_or_else(|| vec![0.0; 3]);
            let r = src.nums_attr(o, "rpy", 3)?.unwrap_or_else(|| vec![0.0; 3]);
            pose([xyz[0], xyz[1], xyz[2]], rpy(r[0], r[1], r[2]))
        }
        None => Pose::identity(),
    };
    Ok(Side {
        link: link.to_string(),
        frame: at * local,
    })
}

/// URDF+: `position` is a ball joint, `rolling` a gear (`None`); the later `<loop>` types are
/// the URDF joint types.
fn urdf_plus_cut(src: &Src, e: Node, name: &str, kind: &str) -> Result<Option<Cut>, ImportError> {
    let tag = e.tag_name().name();
    let axis = || axis_of(src, e, "axis", name, true);
    Ok(Some(match (tag, kind) {
        ("constraint", "position") => Cut::Joint(JointType::S, None, None),
        ("constraint", "rolling") => return Ok(None),
        ("loop", "revolute" | "continuous") => Cut::Joint(JointType::R, Some(axis()?), None),
        ("loop", "prismatic") => Cut::Joint(JointType::P, Some(axis()?), None),
        ("loop", "planar") => Cut::Joint(JointType::PL, Some(axis()?), None),
        ("loop", "fixed") => Cut::Weld,
        _ => return Err(unknown_type(src, e, name, kind, false)),
    }))
}

/// The urdfdom proposal: the cut joint's kind; its axes in the parent's (and, for a universal
/// joint, the child's) closure frame.
fn proposal_cut(src: &Src, e: Node, name: &str, kind: &str) -> Result<Option<Cut>, ImportError> {
    let parent_axis = || axis_of(src, e, "parent_axis", name, false);
    Ok(Some(match kind {
        "revolute" => Cut::Joint(JointType::R, Some(parent_axis()?), None),
        "prismatic" => Cut::Joint(JointType::P, Some(parent_axis()?), None),
        "universal" => Cut::Joint(
            JointType::U,
            Some(parent_axis()?),
            Some(axis_of(src, e, "child_axis", name, false)?),
        ),
        "spherical" => Cut::Joint(JointType::S, None, None),
        "link" => Cut::Weld,
        _ => return Err(unknown_type(src, e, name, kind, true)),
    }))
}

/// The unit axis `<tag xyz>` of a closure element: (1, 0, 0) when absent if `default`, else
/// required.
fn axis_of(
    src: &Src,
    e: Node,
    tag: &str,
    name: &str,
    default: bool,
) -> Result<Vector3<f64>, ImportError> {
    let t = e.tag_name().name();
    let node = child(e, tag);
    let v = match node {
        Some(a) => src.nums_attr(a, "xyz", 3)?,
        None => None,
    };
    let v = match v {
        Some(v) => v,
        None if default => vec![1.0, 0.0, 0.0],
        None => {
            return Err(src
                .err(
                    e,
                    format!("no <{tag}>"),
                    format!("<{t} name=\"{name}\"> needs <{tag} xyz=\"...\"/>"),
                )
                .with_help(format!(
                    "<{tag} xyz> gives the joint axis in that side's closure frame"
                )));
        }
    };
    unit(&v).ok_or_else(|| {
        src.err_attr(
            node.unwrap_or(e),
            "xyz",
            "zero axis",
            format!("<{t} name=\"{name}\"> has an axis of zero length"),
        )
        .with_help("the axis is a direction: give it a non-zero length")
    })
}

fn types_help(tag: &str, proposal: bool) -> String {
    match (tag, proposal) {
        ("loop", _) => "<loop> types: revolute, continuous, prismatic, planar, fixed".into(),
        (_, true) => "<constraint> types: revolute, prismatic, universal, spherical, link".into(),
        _ => "URDF+ <constraint> types: position (a ball joint), rolling (a gear ratio)".into(),
    }
}

fn unknown_type(src: &Src, e: Node, name: &str, kind: &str, proposal: bool) -> ImportError {
    let tag = e.tag_name().name();
    src.err_attr(
        e,
        "type",
        "unknown type",
        format!("<{tag} name=\"{name}\"> has the unknown type `{kind}`"),
    )
    .with_help(types_help(tag, proposal))
}

/// Gaps below this (length, or angle in radians) are closed.
const CLOSED: f64 = 1e-6;

/// Close a loop between two sides with `cut`: a weld merges the links (whatever its gap: a
/// warning gives it), a joint gets the first side's frame, and the second side's features in
/// `second` when they differ (`mbsa assemble` closes it; a warning gives the gap).
pub(super) fn close(
    b: &mut Builder,
    name: &str,
    cut: &Cut,
    first: &Side,
    second: &Side,
    what: &str,
    loc: &str,
) {
    let (a, c) = (&first.link, &second.link);
    let (ia, ic) = (b.body(a, ""), b.body(c, ""));
    // A link a weld before this one moved sits where that weld put it.
    let (fa, fc) = (b.moved(ia) * first.frame, b.moved(ic) * second.frame);
    let gap = (fa.translation.vector - fc.translation.vector).norm();
    let (kind, axis, axis2) = match cut {
        Cut::Weld => {
            b.weld_cut(ia, ic, &first.frame, &second.frame, what, loc);
            return;
        }
        Cut::Joint(kind, axis, axis2) => (*kind, *axis, *axis2),
    };
    let p1 = fa.translation.vector;
    let p2 = fc.translation.vector;
    let ax1 = axis.map(|v| fa.rotation * v);
    let ax2 = axis.map(|v| fc.rotation * v);
    let mut g = Geometry {
        origin: Some(arr(p1)),
        ..Geometry::default()
    };
    match kind {
        JointType::PL => g.normal = ax1.map(arr),
        JointType::U => {
            g.axis = ax1.map(arr);
            g.axis2 = axis2.map(|v| arr(fc.rotation * v));
        }
        _ => g.axis = ax1.map(arr),
    }
    let differs = |x: Vector3<f64>, y: Vector3<f64>| {
        arr(x).iter().zip(arr(y)).any(|(p, q)| num(*p) != num(q))
    };
    let mut s = Second::default();
    if differs(p1, p2) {
        s.origin = Some(arr(p2));
    }
    if let (Some(x), Some(y)) = (ax1, ax2)
        && kind != JointType::U
        && differs(x, y)
    {
        if kind == JointType::PL {
            s.normal = Some(arr(y));
        } else {
            s.axis = Some(arr(y));
        }
    }
    if s != Second::default() {
        b.warn(format!("{loc}: {what} between `{a}` and `{c}` is not closed at this configuration (gap {gap:.3e}): its joint carries `{c}`'s frame in `second` (`mbsa assemble` closes the loop)"));
        g.second = Some(Box::new(s));
    }
    b.joint(JointRec {
        id: name.to_string(),
        kind,
        bodies: vec![ia, ic],
        driven: 0,
        geometry: g,
        comments: vec![format!("{what} (loop closure) at {loc}")],
    });
}

/// A `drake:distance_constraint` (body_A, p_AP, body_B, p_BQ, distance; its stiffness and
/// damping are dynamics): a sphere-sphere joint, the two points keeping their distance. The
/// distance is the points' at the configuration: one that differs from the written
/// `distance` is warned.
pub(super) fn drake_distance(
    src: &Src,
    e: Node,
    b: &mut Builder,
    frames: &Frames,
) -> Result<(), ImportError> {
    const TAG: &str = "drake:distance_constraint";
    let part = |tag: &str| {
        child(e, &format!("distance_constraint_{tag}")).ok_or_else(|| {
            src.err(
                e,
                "incomplete",
                format!("{TAG} needs body_A, p_AP, body_B, p_BQ and distance"),
            )
            .with_help(format!(
                "<drake:distance_constraint_{tag}> is missing; see Drake's URDF extension reference"
            ))
        })
    };
    let point = |body: &str, p: &str| -> Result<(String, Vector3<f64>), ImportError> {
        let (bn, pn) = (part(body)?, part(p)?);
        let name = bn.attribute("name").unwrap_or("");
        let Some(at) = frames.link(name) else {
            return Err(src
                .err_attr(
                    bn,
                    "name",
                    "no such link",
                    format!("link `{name}` is not defined"),
                )
                .with_help("name a <link> of the robot"));
        };
        let v = src
            .nums_attr(pn, "value", 3)?
            .unwrap_or_else(|| vec![0.0; 3]);
        Ok((
            name.to_string(),
            (at * nalgebra::Point3::new(v[0], v[1], v[2])).coords,
        ))
    };
    let (na, p1) = point("body_A", "p_AP")?;
    let (nb, p2) = point("body_B", "p_BQ")?;
    let dn = part("distance")?;
    let written = match src.nums_attr(dn, "value", 1)? {
        Some(v) if v[0] > 0.0 => v[0],
        _ => {
            return Err(src
                .err_attr(
                    dn,
                    "value",
                    "not positive",
                    format!(
                        "{TAG} between `{na}` and `{nb}`: the distance must be a positive number"
                    ),
                )
                .with_help(
                    "drake:distance_constraint_distance value=\"...\" is the distance in meters",
                ));
        }
    };
    let loc = src.loc(e);
    let d = (p1 - p2).norm();
    if (d - written).abs() > CLOSED * written.max(1.0) {
        b.warn(format!("{loc}: {TAG} between `{na}` and `{nb}` keeps {written}, but its points are {d:.6e} apart at this configuration: the joint keeps the configuration's distance"));
    }
    let (ia, ib) = (b.body(&na, ""), b.body(&nb, ""));
    let (kind, origin2) = if d > CLOSED {
        (JointType::SPSP, Some(arr(p2)))
    } else {
        b.warn(format!("{loc}: {TAG} between `{na}` and `{nb}`: its points coincide at this configuration: imported as a ball joint"));
        (JointType::S, None)
    };
    b.joint(JointRec {
        id: format!("distance:{na}-{nb}"),
        kind,
        bodies: vec![ia, ib],
        driven: 0,
        geometry: Geometry {
            origin: Some(arr(p1)),
            origin2,
            ..Geometry::default()
        },
        comments: vec![format!("<{TAG}> (loop closure) at {loc}")],
    });
    Ok(())
}
