//! OpenSim (.osim) reader, 3.x (joints inside bodies) and 4.x (JointSet with offset frames):
//! Pin, Slider, Ball, Gimbal, Universal, Free, Planar and Weld joints, CustomJoint when its
//! SpatialTransform maps to one of these; PointConstraint -> S, WeldConstraint -> merge;
//! CoordinateActuator / TorqueActuator -> driven; default coordinate values = configuration.

use super::{Builder, ImportError, JointRec, Node, Pose, Src, arr, child, children, pose, unit};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::{Point3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;

/// OpenSim's body-fixed X-Y-Z Euler angles.
fn xyz_body(a: &[f64]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a[0])
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), a[1])
        * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a[2])
}

fn text_of<'a>(n: Node<'a>, tag: &str) -> Option<&'a str> {
    child(n, tag).and_then(|c| c.text()).map(str::trim)
}

/// The last component of an OpenSim path (`/bodyset/r_humerus` -> `r_humerus`).
fn last(path: &str) -> &str {
    path.trim()
        .trim_end_matches('/')
        .rsplit('/')
        .next()
        .unwrap_or(path)
}

fn vec3(src: &Src, n: Node, tag: &str) -> Result<[f64; 3], ImportError> {
    match child(n, tag) {
        Some(c) => {
            let v = src.nums_text(c, 3)?;
            Ok([v[0], v[1], v[2]])
        }
        None => Ok([0.0; 3]),
    }
}

/// Evaluate a transform-axis function at `x` (`None`: not a function the importer knows).
fn eval(src: &Src, f: Node, x: f64) -> Result<Option<(f64, bool)>, ImportError> {
    // (value, linear in x)
    Ok(match f.tag_name().name() {
        "Constant" => {
            let v = text_of(f, "value")
                .and_then(|v| v.parse().ok())
                .unwrap_or(0.0);
            src.note(&[v], 1.0);
            Some((v, true))
        }
        "LinearFunction" => {
            let c = match child(f, "coefficients") {
                Some(c) => src.nums_text(c, 2)?,
                None => vec![1.0, 0.0],
            };
            Some((c[0] * x + c[1], true))
        }
        "SimmSpline" | "NaturalCubicSpline" | "GCVSpline" | "PiecewiseLinearFunction" => {
            let xs = child(f, "x")
                .map(|c| src.nums_text(c, 0))
                .transpose()?
                .unwrap_or_default();
            let ys = child(f, "y")
                .map(|c| src.nums_text(c, 0))
                .transpose()?
                .unwrap_or_default();
            if xs.is_empty() || xs.len() != ys.len() {
                return Ok(None);
            }
            // Piecewise-linear through the knots (enough for the configuration).
            let mut v = ys[0];
            if x >= xs[xs.len() - 1] {
                v = ys[ys.len() - 1];
            } else {
                for k in 1..xs.len() {
                    if x <= xs[k] {
                        let t = if xs[k] > xs[k - 1] {
                            (x - xs[k - 1]) / (xs[k] - xs[k - 1])
                        } else {
                            0.0
                        };
                        v = ys[k - 1] + t * (ys[k] - ys[k - 1]);
                        break;
                    }
                }
            }
            let linear = xs.len() == 2;
            Some((v, linear))
        }
        "MultiplierFunction" => {
            let scale = text_of(f, "scale")
                .and_then(|v| v.parse().ok())
                .unwrap_or(1.0);
            src.note(&[scale], 1.0);
            let inner = child(f, "function").and_then(|g| g.children().find(|c| c.is_element()));
            match inner {
                Some(g) => eval(src, g, x)?.map(|(v, l)| (scale * v, l)),
                None => None,
            }
        }
        _ => None,
    })
}

/// A joint's motion at the default coordinates, its kind and geometry, and its independent
/// coordinates (`["weld"]` for a weld).
type Motion = (Pose, JointType, Geometry, Vec<String>);

struct Axis<'a> {
    rotation: bool,
    coords: Vec<String>,
    axis: Vector3<f64>,
    function: Option<Node<'a>>,
    n: Node<'a>,
}

/// Read an OpenSim document.
#[allow(clippy::too_many_lines)]
pub(super) fn read(src: &Src, doc: &roxmltree::Document) -> Result<Builder, ImportError> {
    let root = doc.root_element();
    let Some(model) = child(root, "Model") else {
        return Err(src
            .err(root, "no <Model>", "no <Model> in the OpenSim document")
            .with_help("an .osim file holds <OpenSimDocument><Model>"));
    };
    let ground = child(model, "Ground")
        .and_then(|g| g.attribute("name"))
        .unwrap_or("ground")
        .to_string();
    let mut b = Builder::new(
        model.attribute("name").unwrap_or("model"),
        &ground,
        "the OpenSim ground",
    );
    b.configuration = "the coordinates' default values".into();
    let bodies: Vec<Node> = child(model, "BodySet")
        .and_then(|s| child(s, "objects"))
        .map(|o| children(o, "Body").collect())
        .unwrap_or_default();
    // Joints: (joint element, child body name (3.x: its owner)).
    let mut jnodes: Vec<(Node, Option<String>)> = Vec::new();
    for body in &bodies {
        if let Some(j) = child(*body, "Joint") {
            for k in j.children().filter(|c| c.is_element()) {
                jnodes.push((k, body.attribute("name").map(str::to_string)));
            }
        }
    }
    if let Some(o) = child(model, "JointSet").and_then(|s| child(s, "objects")) {
        for k in o.children().filter(|c| c.is_element()) {
            jnodes.push((k, None));
        }
    }
    for body in &bodies {
        if let Some(n) = body.attribute("name") {
            b.body(n, "");
        }
    }
    struct OJoint<'a> {
        n: Node<'a>,
        name: String,
        tag: String,
        parent: String,
        child: String,
        x_pf: Pose,
        x_bm: Pose,
        coords: Vec<(String, f64)>,
    }
    let mut joints: Vec<OJoint> = Vec::new();
    for (j, owner) in &jnodes {
        let name = j.attribute("name").unwrap_or("").to_string();
        let tag = j.tag_name().name().to_string();
        let (parent, child_b, x_pf, x_bm) = if let Some(owner) = owner {
            let Some(p) = text_of(*j, "parent_body") else {
                return Err(src
                    .err(
                        *j,
                        "no parent_body",
                        format!("joint `{name}` has no <parent_body>"),
                    )
                    .with_help("OpenSim 3 joints name their parent body"));
            };
            let x_pf = pose(
                vec3(src, *j, "location_in_parent")?,
                xyz_body(&vec3(src, *j, "orientation_in_parent")?),
            );
            let x_bm = pose(
                vec3(src, *j, "location")?,
                xyz_body(&vec3(src, *j, "orientation")?),
            );
            (p.to_string(), owner.clone(), x_pf, x_bm)
        } else {
            let frames: HashMap<&str, Node> = child(*j, "frames")
                .map(|f| {
                    f.children()
                        .filter(|c| c.is_element())
                        .filter_map(|c| c.attribute("name").map(|n| (n, c)))
                        .collect()
                })
                .unwrap_or_default();
            let resolve = |tag_a: &str, tag_b: &str| -> Result<(String, Pose), ImportError> {
                let Some(s) = text_of(*j, tag_a).or_else(|| text_of(*j, tag_b)) else {
                    return Err(src
                        .err(
                            *j,
                            format!("no <{tag_a}>"),
                            format!("joint `{name}` has no <{tag_a}>"),
                        )
                        .with_help("OpenSim 4 joints name their parent and child frames"));
                };
                let mut cur = last(s).to_string();
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
            };
            let (p, x_pf) = resolve("socket_parent_frame", "parent_frame")?;
            let (c, x_bm) = resolve("socket_child_frame", "child_frame")?;
            (p, c, x_pf, x_bm)
        };
        for (who, bn) in [("parent", &parent), ("child", &child_b)] {
            if *bn != ground
                && !bodies
                    .iter()
                    .any(|x| x.attribute("name") == Some(bn.as_str()))
            {
                return Err(src
                    .err(
                        *j,
                        format!("no body `{bn}`"),
                        format!("joint `{name}`: its {who} `{bn}` is not a body of the model"),
                    )
                    .with_help("name a Body of the BodySet, or the ground"));
            }
        }
        let cset = child(*j, "CoordinateSet")
            .and_then(|c| child(c, "objects"))
            .or_else(|| child(*j, "coordinates"));
        let mut coords = Vec::new();
        if let Some(cs) = cset {
            for c in children(cs, "Coordinate") {
                let v = text_of(c, "default_value")
                    .and_then(|v| v.parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .unwrap_or(0.0);
                src.note(&[v], 1.0);
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
        if text_of(*j, "reverse") == Some("true") {
            let loc = src.loc(*j);
            b.warn(format!(
                "{loc}: joint `{name}` is reversed (child to parent): imported as written"
            ));
        }
        joints.push(OJoint {
            n: *j,
            name,
            tag,
            parent,
            child: child_b,
            x_pf,
            x_bm,
            coords,
        });
    }
    // World poses, down the tree.
    let mut world: HashMap<String, Pose> = HashMap::new();
    world.insert(ground.clone(), Pose::identity());
    let mut motion: Vec<Option<Motion>> = (0..joints.len()).map(|_| None).collect();
    let mut coord_joint: HashMap<String, usize> = HashMap::new();
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
            let q: Vec<f64> = j.coords.iter().map(|c| c.1).collect();
            let qa = |i: usize| q.get(i).copied().unwrap_or(0.0);
            let g = |o: Vector3<f64>| Some(arr((f * Point3::from(o)).coords));
            let d = |v: Vector3<f64>| Some(arr(f.rotation * v));
            let (x_fm, kind, geom, independent): (Pose, JointType, Geometry, Vec<String>) = match j
                .tag
                .as_str()
            {
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
                "UniversalJoint" => {
                    let r1 = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), qa(0));
                    (
                        pose(
                            [0.0; 3],
                            r1 * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), qa(1)),
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
                "FreeJoint" => (
                    pose([qa(3), qa(4), qa(5)], xyz_body(&[qa(0), qa(1), qa(2)])),
                    JointType::F,
                    Geometry::default(),
                    vec![],
                ),
                "PlanarJoint" => {
                    let t = Vector3::new(qa(1), qa(2), 0.0);
                    (
                        pose(
                            [t.x, t.y, 0.0],
                            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), qa(0)),
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
                "WeldJoint" => (
                    Pose::identity(),
                    JointType::F,
                    Geometry::default(),
                    vec!["weld".into()],
                ),
                "CustomJoint" => custom(src, &mut b, j.n, &j.name, &j.coords, f)?,
                other => {
                    let loc = src.loc(j.n);
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
                    b.warn(format!("{loc}: <{other}> `{}` is not representable exactly: imported as {} (its {} coordinate(s))", j.name, kind.code(), j.coords.len()));
                    (Pose::identity(), kind, geom, vec![])
                }
            };
            world.insert(j.child.clone(), f * x_fm * j.x_bm.inverse());
            let independent = if independent.is_empty() {
                j.coords.iter().map(|c| c.0.clone()).collect()
            } else {
                independent
            };
            for c in &independent {
                coord_joint.insert(c.clone(), k);
            }
            motion[k] = Some((x_fm, kind, geom, independent));
            progress = true;
        }
    }
    let mut jindex: HashMap<usize, usize> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        let Some((_, kind, geom, ind)) = &motion[k] else {
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
        if ind.first().map(String::as_str) == Some("weld") {
            b.weld(p, c, &format!("WeldJoint `{}`", j.name));
            continue;
        }
        let ji = b.joint(JointRec {
            id: j.name.clone(),
            kind: *kind,
            bodies: vec![p, c],
            driven: 0,
            geometry: geom.clone(),
            comments: vec![format!(
                "<{} name=\"{}\"> at {}",
                j.tag,
                j.name,
                src.loc(j.n)
            )],
        });
        jindex.insert(k, ji);
    }
    // Constraints.
    if let Some(o) = child(model, "ConstraintSet").and_then(|s| child(s, "objects")) {
        for c in o.children().filter(|c| c.is_element()) {
            let tag = c.tag_name().name();
            let cname = c.attribute("name").unwrap_or("");
            let loc = src.loc(c);
            if text_of(c, "isDisabled") == Some("true") || text_of(c, "isEnforced") == Some("false")
            {
                b.warn(format!("{loc}: <{tag}> `{cname}` is disabled: left out"));
                continue;
            }
            let body_of = |a: &str, bb: &str| -> Result<(String, Pose), ImportError> {
                let name = text_of(c, a)
                    .or_else(|| text_of(c, bb))
                    .map(last)
                    .unwrap_or("")
                    .to_string();
                match world.get(&name) {
                    Some(p) => Ok((name, *p)),
                    None => Err(src
                        .err(
                            c,
                            "no such body",
                            format!(
                                "<{tag}> `{cname}` names body `{name}`, which is not in the model"
                            ),
                        )
                        .with_help("name a Body of the BodySet, or the ground")),
                }
            };
            match tag {
                "PointConstraint" => {
                    let (n1, w1) = body_of("socket_body_1", "body_1")?;
                    let (n2, w2) = body_of("socket_body_2", "body_2")?;
                    let p1 = w1 * Point3::from(Vector3::from(vec3(src, c, "location_body_1")?));
                    let p2 = w2 * Point3::from(Vector3::from(vec3(src, c, "location_body_2")?));
                    if (p1 - p2).norm() > 1e-6 {
                        b.warn(format!("{loc}: PointConstraint `{cname}` between `{n1}` and `{n2}` is not closed at the default coordinates (gap {:.3e}): its joint carries body 2's point in `second` (`mbsa assemble` closes the loop)", (p1 - p2).norm()));
                    }
                    let (i1, i2) = (b.body(&n1, ""), b.body(&n2, ""));
                    b.joint(JointRec {
                        id: if cname.is_empty() {
                            format!("point:{n1}-{n2}")
                        } else {
                            cname.to_string()
                        },
                        kind: JointType::S,
                        bodies: vec![i1, i2],
                        driven: 0,
                        geometry: super::point_closure(p1.coords, p2.coords),
                        comments: vec![format!(
                            "<PointConstraint name=\"{cname}\"> (loop closure) at {loc}"
                        )],
                    });
                }
                "WeldConstraint" => {
                    let (n1, _) = body_of("socket_frame1", "body_1")?;
                    let (n2, _) = body_of("socket_frame2", "body_2")?;
                    let (i1, i2) = (b.body(&n1, ""), b.body(&n2, ""));
                    b.weld(i1, i2, &format!("WeldConstraint `{cname}`"));
                }
                "CoordinateCouplerConstraint" => {
                    b.warn(format!("{loc}: CoordinateCouplerConstraint `{cname}` couples coordinates: not representable (left out)"));
                }
                other => b.warn(format!(
                    "{loc}: <{other}> `{cname}` not representable (left out)"
                )),
            }
        }
    }
    // Actuators.
    let mut other_forces = 0usize;
    if let Some(o) = child(model, "ForceSet").and_then(|s| child(s, "objects")) {
        for f in o.children().filter(|c| c.is_element()) {
            let tag = f.tag_name().name();
            let fname = f.attribute("name").unwrap_or("");
            let loc = src.loc(f);
            let target = match tag {
                "CoordinateActuator" => {
                    let cn = text_of(f, "coordinate").unwrap_or("");
                    match coord_joint.get(cn).and_then(|k| jindex.get(k)) {
                        Some(&ji) => Some(ji),
                        None => {
                            b.warn(format!("{loc}: CoordinateActuator `{fname}` drives `{cn}`, not an independent coordinate of an imported joint: not counted"));
                            None
                        }
                    }
                }
                "TorqueActuator" => {
                    let ba = text_of(f, "socket_bodyA")
                        .or_else(|| text_of(f, "bodyA"))
                        .or_else(|| text_of(f, "body_A"))
                        .map(last)
                        .unwrap_or("");
                    let bb = text_of(f, "socket_bodyB")
                        .or_else(|| text_of(f, "bodyB"))
                        .or_else(|| text_of(f, "body_B"))
                        .map(last)
                        .unwrap_or("");
                    let (ia, ib) = (b.find_body(ba), b.find_body(bb));
                    let found = b.joints.iter().position(|j| {
                        Some(j.bodies[0]) == ia && Some(j.bodies[1]) == ib
                            || Some(j.bodies[0]) == ib && Some(j.bodies[1]) == ia
                    });
                    if found.is_none() {
                        b.warn(format!("{loc}: TorqueActuator `{fname}` between `{ba}` and `{bb}`: no joint joins them: not counted"));
                    }
                    found
                }
                _ => {
                    other_forces += 1;
                    None
                }
            };
            if let Some(ji) = target {
                let j = &mut b.joints[ji];
                if j.driven < j.kind.grade() as u32 {
                    j.driven += 1;
                    j.comments
                        .push(format!("driven by <{tag} name=\"{fname}\"> at {loc}"));
                }
            }
        }
    }
    if other_forces > 0 {
        b.warn(format!("{other_forces} force element(s) (muscles, springs, contacts, ...) not imported: they are not kinematic"));
    }
    Ok(b)
}

/// A CustomJoint: its motion at the default coordinates, the joint kind and geometry of its
/// independent coordinates, and the names of those coordinates.
fn custom(
    src: &Src,
    b: &mut Builder,
    j: Node,
    name: &str,
    coords: &[(String, f64)],
    f: Pose,
) -> Result<Motion, ImportError> {
    let loc = src.loc(j);
    let Some(st) = child(j, "SpatialTransform") else {
        return Err(src
            .err(
                j,
                "no SpatialTransform",
                format!("CustomJoint `{name}` has no <SpatialTransform>"),
            )
            .with_help("a CustomJoint lists its six TransformAxis elements"));
    };
    let mut axes: Vec<Axis> = Vec::new();
    for (k, ta) in children(st, "TransformAxis").enumerate() {
        let rotation = ta
            .attribute("name")
            .map(|n| n.starts_with("rotation"))
            .unwrap_or(k < 3);
        let cs: Vec<String> = text_of(ta, "coordinates")
            .unwrap_or("")
            .split_whitespace()
            .map(str::to_string)
            .collect();
        let av = match child(ta, "axis") {
            Some(a) => src.nums_text(a, 3)?,
            None => vec![0.0, 0.0, 1.0],
        };
        let axis = unit(&av).unwrap_or_else(Vector3::z);
        let function = match child(ta, "function") {
            Some(fun) => fun.children().find(|c| c.is_element()),
            None => ta
                .children()
                .find(|c| c.is_element() && !matches!(c.tag_name().name(), "coordinates" | "axis")),
        };
        axes.push(Axis {
            rotation,
            coords: cs,
            axis,
            function,
            n: ta,
        });
    }
    let value_of = |c: &str| coords.iter().find(|x| x.0 == c).map(|x| x.1).unwrap_or(0.0);
    let mut rot = UnitQuaternion::identity();
    let mut t = Vector3::zeros();
    let mut coupled = false;
    let mut use_count: HashMap<&str, usize> = HashMap::new();
    for a in &axes {
        for c in &a.coords {
            *use_count.entry(c.as_str()).or_default() += 1;
        }
    }
    // (is rotation, world direction, coordinate) of each coordinate's driving axis.
    let mut driving: Vec<(bool, Vector3<f64>, String)> = Vec::new();
    for a in &axes {
        let x = a.coords.first().map(|c| value_of(c)).unwrap_or(0.0);
        let (v, linear) = match a.function {
            Some(fun) => match eval(src, fun, x)? {
                Some(v) => v,
                None => {
                    b.warn(format!(
                        "{}: function <{}> of CustomJoint `{name}` not evaluated (taken as 0)",
                        src.loc(a.n),
                        fun.tag_name().name()
                    ));
                    (0.0, false)
                }
            },
            None => (if a.coords.is_empty() { 0.0 } else { x }, true),
        };
        if let Some(c) = a.coords.first() {
            if !linear || use_count.get(c.as_str()).copied().unwrap_or(0) > 1 || a.coords.len() > 1
            {
                coupled = true;
            }
            if !driving.iter().any(|d| d.2 == *c)
                || (a.rotation && !driving.iter().any(|d| d.2 == *c && d.0))
            {
                let dir = if a.rotation {
                    f.rotation * (rot * a.axis)
                } else {
                    f.rotation * a.axis
                };
                driving.retain(|d| !(d.2 == *c && !d.0 && a.rotation));
                driving.push((a.rotation, dir, c.clone()));
            }
        }
        if a.rotation {
            rot *= UnitQuaternion::from_axis_angle(&Unit::new_normalize(a.axis), v);
        } else {
            t += a.axis * v;
        }
    }
    let x_fm = Pose::from_parts(Translation3::from(t), rot);
    let origin = Some(arr((f * Point3::from(t)).coords));
    let rots: Vec<&(bool, Vector3<f64>, String)> = driving.iter().filter(|d| d.0).collect();
    let trans: Vec<&(bool, Vector3<f64>, String)> = driving.iter().filter(|d| !d.0).collect();
    let par = |a: Vector3<f64>, b: Vector3<f64>| a.cross(&b).norm() < 1e-9;
    let (kind, geom, exact) = match (rots.len(), trans.len()) {
        (1, 0) => (
            JointType::R,
            Geometry {
                origin,
                axis: Some(arr(rots[0].1)),
                ..Geometry::default()
            },
            true,
        ),
        (0, 1) => (
            JointType::P,
            Geometry {
                origin,
                axis: Some(arr(trans[0].1)),
                ..Geometry::default()
            },
            true,
        ),
        (2, 0) => (
            JointType::U,
            Geometry {
                origin,
                axis: Some(arr(rots[0].1)),
                axis2: Some(arr(rots[1].1)),
                ..Geometry::default()
            },
            true,
        ),
        (3, 0) => (
            JointType::S,
            Geometry {
                origin,
                ..Geometry::default()
            },
            true,
        ),
        (1, 1) if par(rots[0].1, trans[0].1) => (
            JointType::C,
            Geometry {
                origin,
                axis: Some(arr(rots[0].1)),
                ..Geometry::default()
            },
            true,
        ),
        (1, 2)
            if rots[0].1.dot(&trans[0].1).abs() < 1e-9
                && rots[0].1.dot(&trans[1].1).abs() < 1e-9 =>
        {
            (
                JointType::PL,
                Geometry {
                    origin,
                    normal: Some(arr(rots[0].1)),
                    ..Geometry::default()
                },
                true,
            )
        }
        (3, 3) => (JointType::F, Geometry::default(), true),
        (0, 0) => (JointType::F, Geometry::default(), false),
        (r, tt) => {
            let kind = match r + tt {
                1 => JointType::R,
                2 => JointType::U,
                3 => JointType::S,
                _ => JointType::F,
            };
            (
                kind,
                Geometry {
                    origin,
                    ..Geometry::default()
                },
                false,
            )
        }
    };
    if driving.is_empty() {
        // No coordinate moves anything: a weld.
        return Ok((x_fm, JointType::F, Geometry::default(), vec!["weld".into()]));
    }
    let names: Vec<String> = driving.iter().map(|d| d.2.clone()).collect();
    if coupled {
        b.warn(format!("{loc}: CustomJoint `{name}`: coupled coordinates ({}) drive several axes or non-linear functions: not representable; imported as {} about its independent coordinates at the default values", names.join(", "), kind.code()));
    } else if !exact {
        b.warn(format!("{loc}: CustomJoint `{name}`: its spatial transform ({} rotation(s), {} translation(s)) maps to no mbsa joint: imported as {}", rots.len(), trans.len(), kind.code()));
    }
    let geom = if matches!(kind, JointType::F) {
        Geometry::default()
    } else {
        geom
    };
    Ok((x_fm, kind, geom, names))
}
