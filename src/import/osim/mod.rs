//! OpenSim (.osim) reader, 3.x (joints inside bodies) and 4.x (JointSet with offset frames):
//! Pin, Slider, Ball, Gimbal, Universal, Free, Planar and Weld joints; a CustomJoint as the one
//! of these its SpatialTransform makes, else as a chain of one-axis joints through massless
//! virtual bodies (one per coordinate); PointConstraint -> S, WeldConstraint -> merge;
//! CoordinateActuator / TorqueActuator -> driven; default coordinate values = configuration.

mod custom;
mod forces;
mod joints;
mod spline;

use super::{Builder, ImportError, Node, Pose, Src, Unique, child, children};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::{UnitQuaternion, Vector3};

/// OpenSim's body-fixed X-Y-Z Euler angles.
fn xyz_body(a: &[f64]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a[0])
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), a[1])
        * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a[2])
}

/// The trimmed text of `n`'s child `tag`.
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

/// Three numbers, the text of `n`'s child `tag` (zeros when absent).
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
            if xs.is_empty() || xs.len() != ys.len() || xs.windows(2).any(|w| w[0] >= w[1]) {
                return Ok(None);
            }
            if xs.len() == 1 {
                return Ok(Some((ys[0], true)));
            }
            // As OpenSim evaluates them; a GCVSpline (a smoothing spline, in no joint of the
            // public models) between its knots as the piecewise-linear function.
            let v = match f.tag_name().name() {
                "SimmSpline" | "NaturalCubicSpline" => spline::cubic(&xs, &ys, x),
                _ => spline::linear(&xs, &ys, x),
            };
            if !v.is_finite() {
                return Ok(None);
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

/// A joint imported as one mbsa joint: its motion at the default coordinates, its kind and
/// geometry, and its independent coordinates (empty: all of the joint's; `["weld"]` for a weld).
type Single = (Pose, JointType, Geometry, Vec<String>);

/// A joint's motion at the default coordinates (`x_fm`, the child's joint frame in the
/// parent's), the mbsa joints it is imported as, from the parent to the child, and its
/// independent coordinates (empty: all of the joint's; `["weld"]` for a weld).
struct Motion {
    x_fm: Pose,
    stages: Vec<Stage>,
    independent: Vec<String>,
}

/// One mbsa joint of an imported joint: its kind, its geometry and, in a chain of one-axis
/// joints (a CustomJoint no single mbsa joint matches), the coordinate it carries.
struct Stage {
    kind: JointType,
    geometry: Geometry,
    coordinate: Option<String>,
}

impl Motion {
    /// A joint imported as one mbsa joint.
    fn single((x_fm, kind, geometry, independent): Single) -> Motion {
        Motion {
            x_fm,
            stages: vec![Stage {
                kind,
                geometry,
                coordinate: None,
            }],
            independent,
        }
    }

    /// The stage that carries coordinate `c` (the only one of a single joint).
    fn stage_of(&self, c: &str) -> usize {
        self.stages
            .iter()
            .position(|s| s.coordinate.as_deref() == Some(c))
            .unwrap_or(0)
    }
}

/// A joint of the model: its element, name and tag, the bodies it joins, its frames in the
/// parent (`x_pf`) and child (`x_bm`) bodies, and its coordinates with their default values.
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

/// Read an OpenSim document.
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
    let mut body_names = Unique::new("body");
    for body in &bodies {
        if let Some(n) = body.attribute("name") {
            if n.is_empty() {
                return Err(src
                    .err_attr(*body, "name", "empty", "<Body> with an empty `name`")
                    .with_help("every body has a unique, non-empty name"));
            }
            body_names.add(src, *body, "name", n)?;
            b.body(n, "");
        }
    }
    let mut joints: Vec<OJoint> = Vec::new();
    let mut joint_names = Unique::new("joint");
    for (j, owner) in &jnodes {
        if let Some(n) = j.attribute("name").filter(|n| !n.is_empty()) {
            joint_names.add(src, *j, "name", n)?;
        }
        joints.push(joints::read_joint(
            src, &mut b, *j, owner, &bodies, &ground,
        )?);
    }
    let tree = joints::motions(src, &mut b, &joints, &ground)?;
    let jindex = joints::add_joints(src, &mut b, &joints, &tree.motion)?;
    if let Some(o) = child(model, "ConstraintSet").and_then(|s| child(s, "objects")) {
        for c in o.children().filter(|c| c.is_element()) {
            forces::constraint(src, &mut b, c, &tree.world)?;
        }
    }
    let mut other_forces = 0usize;
    if let Some(o) = child(model, "ForceSet").and_then(|s| child(s, "objects")) {
        for f in o.children().filter(|c| c.is_element()) {
            if !forces::actuator(src, &mut b, f, &tree.coord_joint, &jindex) {
                other_forces += 1;
            }
        }
    }
    if other_forces > 0 {
        b.warn(format!("{other_forces} force element(s) (muscles, springs, contacts, ...) not imported: they are not kinematic"));
    }
    Ok(b)
}
