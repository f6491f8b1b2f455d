//! OpenSim joints: their bodies and frames (3.x inside bodies, 4.x with offset frames), their
//! coordinates, and their motion at the default coordinates down the tree from the ground.

use super::custom::custom;
use super::{Motion, OJoint, Single, last, text_of, vec3, xyz_body};
use crate::import::{Builder, ImportError, JointRec, Node, Pose, Src, arr, child, children, pose};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::{Point3, Translation3, UnitQuaternion, Vector3};
use std::collections::HashMap;

/// One joint element (`owner`: its body in 3.x): the bodies it joins (each of the model or the
/// ground), its frames, its coordinates (a locked one and a reversed joint warned).
pub(super) fn read_joint<'a>(
    src: &Src,
    b: &mut Builder,
    j: Node<'a>,
    owner: &Option<String>,
    bodies: &[Node],
    ground: &str,
) -> Result<OJoint<'a>, ImportError> {
    let name = j.attribute("name").unwrap_or("").to_string();
    let tag = j.tag_name().name().to_string();
    let (parent, child_b, x_pf, x_bm) = if let Some(owner) = owner {
        joint_frames_3(src, j, &name, owner)?
    } else {
        joint_frames_4(src, j, &name)?
    };
    for (who, bn) in [("parent", &parent), ("child", &child_b)] {
        if *bn != ground
            && !bodies
                .iter()
                .any(|x| x.attribute("name") == Some(bn.as_str()))
        {
            return Err(src
                .err(
                    j,
                    format!("no body `{bn}`"),
                    format!("joint `{name}`: its {who} `{bn}` is not a body of the model"),
                )
                .with_help("name a Body of the BodySet, or the ground"));
        }
    }
    let coords = joint_coords(src, b, j)?;
    if text_of(j, "reverse") == Some("true") {
        let loc = src.loc(j);
        b.warn(format!(
            "{loc}: joint `{name}` is reversed (child to parent): imported as written"
        ));
    }
    Ok(OJoint {
        n: j,
        name,
        tag,
        parent,
        child: child_b,
        x_pf,
        x_bm,
        coords,
    })
}

/// The parent and child bodies and frames of a joint.
type JointFrames = (String, String, Pose, Pose);

/// An OpenSim 3 joint in body `owner`: its parent body and its poses in both bodies.
fn joint_frames_3(src: &Src, j: Node, name: &str, owner: &str) -> Result<JointFrames, ImportError> {
    let Some(p) = text_of(j, "parent_body") else {
        return Err(src
            .err(
                j,
                "no parent_body",
                format!("joint `{name}` has no <parent_body>"),
            )
            .with_help("OpenSim 3 joints name their parent body"));
    };
    let x_pf = pose(
        vec3(src, j, "location_in_parent")?,
        xyz_body(&vec3(src, j, "orientation_in_parent")?),
    );
    let x_bm = pose(
        vec3(src, j, "location")?,
        xyz_body(&vec3(src, j, "orientation")?),
    );
    Ok((p.to_string(), owner.to_string(), x_pf, x_bm))
}

/// An OpenSim 4 joint: its parent and child frames, each resolved through the joint's offset
/// frames to a body and a pose in it.
fn joint_frames_4(src: &Src, j: Node, name: &str) -> Result<JointFrames, ImportError> {
    let resolve = |tag_a: &str, tag_b: &str| -> Result<(String, Pose), ImportError> {
        let Some(s) = text_of(j, tag_a).or_else(|| text_of(j, tag_b)) else {
            return Err(src
                .err(
                    j,
                    format!("no <{tag_a}>"),
                    format!("joint `{name}` has no <{tag_a}>"),
                )
                .with_help("OpenSim 4 joints name their parent and child frames"));
        };
        offset_frame(src, j, s)
    };
    let (p, x_pf) = resolve("socket_parent_frame", "parent_frame")?;
    let (c, x_bm) = resolve("socket_child_frame", "child_frame")?;
    Ok((p, c, x_pf, x_bm))
}

/// The frame `path` names, resolved through the offset frames of `owner`'s `<frames>` (a
/// joint's or a constraint's) to a body and the frame's pose in it.
pub(super) fn offset_frame(
    src: &Src,
    owner: Node,
    path: &str,
) -> Result<(String, Pose), ImportError> {
    let frames: HashMap<&str, Node> = child(owner, "frames")
        .map(|f| {
            f.children()
                .filter(|c| c.is_element())
                .filter_map(|c| c.attribute("name").map(|n| (n, c)))
                .collect()
        })
        .unwrap_or_default();
    let mut cur = last(path).to_string();
    let mut acc = Pose::identity();
    for _ in 0..=frames.len() {
        match frames.get(cur.as_str()) {
            Some(f) => {
                let x = pose(
                    vec3(src, *f, "translation")?,
                    xyz_body(&vec3(src, *f, "orientation")?),
                );
                acc = x * acc;
                cur = last(text_of(*f, "socket_parent").unwrap_or("")).to_string();
            }
            None => break,
        }
    }
    Ok((cur, acc))
}

/// A joint's coordinates and their default values (a locked coordinate warned: imported free;
/// a default value that is not one finite number refused with its location).
fn joint_coords(src: &Src, b: &mut Builder, j: Node) -> Result<Vec<(String, f64)>, ImportError> {
    let cset = child(j, "CoordinateSet")
        .and_then(|c| child(c, "objects"))
        .or_else(|| child(j, "coordinates"));
    let mut coords = Vec::new();
    if let Some(cs) = cset {
        for c in children(cs, "Coordinate") {
            let v = match child(c, "default_value") {
                Some(d) => src.nums_text(d, 1).map_err(|e| {
                    e.with_help("a coordinate's default_value is one finite number")
                })?[0],
                None => 0.0,
            };
            coords.push((c.attribute("name").unwrap_or("").to_string(), v));
            if text_of(c, "locked") == Some("true") {
                let loc = src.loc(c);
                b.warn(format!(
                    "{loc}: coordinate `{}` is locked: imported as free",
                    c.attribute("name").unwrap_or("")
                ));
            }
        }
    }
    Ok(coords)
}

/// The tree at the default coordinates: each body's world pose, each joint's motion, and the
/// joint and stage of each independent coordinate.
pub(super) struct Tree {
    pub world: HashMap<String, Pose>,
    pub motion: Vec<Option<Motion>>,
    pub coord_joint: HashMap<String, (usize, usize)>,
}

/// World poses and joint motions, down the tree from the ground (a joint whose parent is not
/// reached keeps no motion).
pub(super) fn motions(
    src: &Src,
    b: &mut Builder,
    joints: &[OJoint],
    ground: &str,
) -> Result<Tree, ImportError> {
    let mut world: HashMap<String, Pose> = HashMap::new();
    world.insert(ground.to_string(), Pose::identity());
    let mut motion: Vec<Option<Motion>> = (0..joints.len()).map(|_| None).collect();
    let mut coord_joint: HashMap<String, (usize, usize)> = HashMap::new();
    let mut progress = true;
    while progress {
        progress = false;
        for (k, j) in joints.iter().enumerate() {
            if motion[k].is_some() {
                continue;
            }
            let Some(&xp) = world.get(&j.parent) else {
                continue;
            };
            let f = xp * j.x_pf;
            let mut m = joint_motion(src, b, j, f)?;
            world.insert(j.child.clone(), f * m.x_fm * j.x_bm.inverse());
            if m.independent.is_empty() {
                m.independent = j.coords.iter().map(|c| c.0.clone()).collect();
            }
            for c in &m.independent {
                coord_joint.insert(c.clone(), (k, m.stage_of(c)));
            }
            motion[k] = Some(m);
            progress = true;
        }
    }
    Ok(Tree {
        world,
        motion,
        coord_joint,
    })
}

/// A joint's motion by its tag, `f` its frame in the parent in the world.
fn joint_motion(src: &Src, b: &mut Builder, j: &OJoint, f: Pose) -> Result<Motion, ImportError> {
    let q: Vec<f64> = j.coords.iter().map(|c| c.1).collect();
    let qa = |i: usize| q.get(i).copied().unwrap_or(0.0);
    let g = |o: Vector3<f64>| Some(arr((f * Point3::from(o)).coords));
    let d = |v: Vector3<f64>| Some(arr(f.rotation * v));
    Ok(Motion::single(match j.tag.as_str() {
        "PinJoint" => (
            pose(
                [0.0; 3],
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), qa(0)),
            ),
            JointType::R,
            Geometry {
                origin: g(Vector3::zeros()),
                axis: d(Vector3::z()),
                ..Geometry::default()
            },
            vec![],
        ),
        "SliderJoint" => (
            Pose::from_parts(
                Translation3::from(Vector3::x() * qa(0)),
                UnitQuaternion::identity(),
            ),
            JointType::P,
            Geometry {
                origin: g(Vector3::zeros()),
                axis: d(Vector3::x()),
                ..Geometry::default()
            },
            vec![],
        ),
        "BallJoint" | "GimbalJoint" => (
            pose([0.0; 3], xyz_body(&[qa(0), qa(1), qa(2)])),
            JointType::S,
            Geometry {
                origin: g(Vector3::zeros()),
                ..Geometry::default()
            },
            vec![],
        ),
        "UniversalJoint" => universal_motion(f, qa(0), qa(1)),
        "FreeJoint" => (
            pose([qa(3), qa(4), qa(5)], xyz_body(&[qa(0), qa(1), qa(2)])),
            JointType::F,
            Geometry::default(),
            vec![],
        ),
        "PlanarJoint" => planar_motion(f, qa(0), qa(1), qa(2)),
        "WeldJoint" => (
            Pose::identity(),
            JointType::F,
            Geometry::default(),
            vec!["weld".into()],
        ),
        "CustomJoint" => return custom(src, b, j.n, &j.name, &j.coords, f),
        other => approximate_motion(src, b, j, f, other),
    }))
}

/// The joints into the builder (a WeldJoint welds its bodies; a chain of stages through
/// massless virtual bodies); every joint must be reached from the ground. Gives the builder's
/// joints of each joint, a stage each.
pub(super) fn add_joints(
    src: &Src,
    b: &mut Builder,
    joints: &[OJoint],
    motion: &[Option<Motion>],
) -> Result<HashMap<usize, Vec<usize>>, ImportError> {
    let mut jindex: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        let Some(m) = &motion[k] else {
            return Err(src
                .err(
                    j.n,
                    "not reached",
                    format!(
                        "joint `{}`: its parent `{}` is not connected to the ground",
                        j.name, j.parent
                    ),
                )
                .with_help("OpenSim models are trees rooted at the ground"));
        };
        let p = b.body(&j.parent, "");
        let c = b.body(&j.child, "");
        if m.independent.first().map(String::as_str) == Some("weld") {
            b.weld(p, c, &format!("WeldJoint `{}`", j.name));
            continue;
        }
        let here = format!("<{} name=\"{}\"> at {}", j.tag, j.name, src.loc(j.n));
        let n = m.stages.len();
        let mut prev = p;
        let mut ids = Vec::with_capacity(n);
        for (s, stage) in m.stages.iter().enumerate() {
            let next = if s + 1 == n {
                c
            } else {
                let v = b.fresh_name(&format!("{}~{}", j.child, s + 1));
                b.body(&v, "massless virtual body")
            };
            let (id, comments) = match &stage.coordinate {
                Some(coord) if n > 1 => (
                    format!("{}:{coord}", j.name),
                    vec![
                        here.clone(),
                        format!(
                            "coordinate `{coord}`, joint {} of {n}: chained through massless \
                             virtual bodies",
                            s + 1
                        ),
                    ],
                ),
                _ => (j.name.clone(), vec![here.clone()]),
            };
            ids.push(b.joint(JointRec {
                id,
                kind: stage.kind,
                bodies: vec![prev, next],
                driven: 0,
                geometry: stage.geometry.clone(),
                comments,
            }));
            prev = next;
        }
        jindex.insert(k, ids);
    }
    Ok(jindex)
}

/// A UniversalJoint at angles `q0` (about x) and `q1` (about the turned y).
fn universal_motion(f: Pose, q0: f64, q1: f64) -> Single {
    let g = |o: Vector3<f64>| Some(arr((f * Point3::from(o)).coords));
    let d = |v: Vector3<f64>| Some(arr(f.rotation * v));
    let r1 = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), q0);
    (
        pose(
            [0.0; 3],
            r1 * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), q1),
        ),
        JointType::U,
        Geometry {
            origin: g(Vector3::zeros()),
            axis: d(Vector3::x()),
            axis2: d(r1 * Vector3::y()),
            ..Geometry::default()
        },
        vec![],
    )
}

/// A PlanarJoint at rotation `q0` (about z) and translation (`q1`, `q2`).
fn planar_motion(f: Pose, q0: f64, q1: f64, q2: f64) -> Single {
    let g = |o: Vector3<f64>| Some(arr((f * Point3::from(o)).coords));
    let d = |v: Vector3<f64>| Some(arr(f.rotation * v));
    let t = Vector3::new(q1, q2, 0.0);
    (
        pose(
            [t.x, t.y, 0.0],
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q0),
        ),
        JointType::PL,
        Geometry {
            origin: g(t),
            normal: d(Vector3::z()),
            ..Geometry::default()
        },
        vec![],
    )
}

/// A joint type not representable exactly (`other`): R, U or S by its number of coordinates
/// (F beyond; a weld without coordinates: it allows no motion), warned.
fn approximate_motion(src: &Src, b: &mut Builder, j: &OJoint, f: Pose, other: &str) -> Single {
    let g = |o: Vector3<f64>| Some(arr((f * Point3::from(o)).coords));
    let d = |v: Vector3<f64>| Some(arr(f.rotation * v));
    let loc = src.loc(j.n);
    if j.coords.is_empty() {
        b.warn(format!(
            "{loc}: <{other}> `{}` is not a joint type the importer knows and has no \
             coordinates: imported as a weld (it allows no motion)",
            j.name
        ));
        return (
            Pose::identity(),
            JointType::F,
            Geometry::default(),
            vec!["weld".into()],
        );
    }
    let (kind, geom) = match j.coords.len() {
        1 => (
            JointType::R,
            Geometry {
                origin: g(Vector3::zeros()),
                axis: d(Vector3::z()),
                ..Geometry::default()
            },
        ),
        2 => (
            JointType::U,
            Geometry {
                origin: g(Vector3::zeros()),
                axis: d(Vector3::x()),
                axis2: d(Vector3::y()),
                ..Geometry::default()
            },
        ),
        3 => (
            JointType::S,
            Geometry {
                origin: g(Vector3::zeros()),
                ..Geometry::default()
            },
        ),
        _ => (JointType::F, Geometry::default()),
    };
    b.warn(format!(
        "{loc}: <{other}> `{}` is not representable exactly: imported as {} (its {} coordinate(s))",
        j.name,
        kind.code(),
        j.coords.len()
    ));
    (Pose::identity(), kind, geom, vec![])
}
