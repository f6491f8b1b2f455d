//! OpenSim CustomJoint: its SpatialTransform's six axes composed at the default coordinates,
//! and the mbsa joint its driving axes make.

use super::{Motion, Stage, eval, text_of};
use crate::import::{Builder, ImportError, Node, Pose, Src, arr, child, children, unit};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::{Point3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;

/// A TransformAxis: rotation or translation, its coordinates, its axis and function.
struct Axis<'a> {
    rotation: bool,
    coords: Vec<String>,
    axis: Vector3<f64>,
    function: Option<Node<'a>>,
    n: Node<'a>,
}

/// A CustomJoint: its motion at the default coordinates, the joint kind and geometry of its
/// independent coordinates, and the names of those coordinates.
pub(super) fn custom(
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
    let axes = transform_axes(src, st)?;
    let Composed {
        rot,
        t,
        coupled,
        driving,
    } = compose(src, b, name, coords, f, &axes)?;
    let x_fm = Pose::from_parts(Translation3::from(t), rot);
    let origin = Some(arr((f * Point3::from(t)).coords));
    let rots: Vec<&(bool, Vector3<f64>, String)> = driving.iter().filter(|d| d.0).collect();
    let trans: Vec<&(bool, Vector3<f64>, String)> = driving.iter().filter(|d| !d.0).collect();
    let (kind, geom, exact) = custom_kind(origin, &rots, &trans);
    if driving.is_empty() {
        // No coordinate moves anything: a weld.
        return Ok(Motion::single((
            x_fm,
            JointType::F,
            Geometry::default(),
            vec!["weld".into()],
        )));
    }
    let names: Vec<String> = driving.iter().map(|d| d.2.clone()).collect();
    if coupled {
        b.warn(format!("{loc}: CustomJoint `{name}`: coupled coordinates ({}) drive several axes or non-linear functions: not representable; imported as {} about its independent coordinates at the default values", names.join(", "), kind.code()));
    } else if !exact {
        return Ok(chain(x_fm, origin, &rots, &trans, names));
    }
    let geom = if matches!(kind, JointType::F) {
        Geometry::default()
    } else {
        geom
    };
    Ok(Motion::single((x_fm, kind, geom, names)))
}

/// A CustomJoint of independent linear coordinates that no single mbsa joint makes (one
/// rotation and three translations, two translations, ...), as the chain of one-axis joints
/// OpenSim composes: a slider along each translation, fixed in the parent, then a hinge about
/// each rotation axis (each turned by the rotations before it) through the child's joint
/// origin. Exact to first order and in finite motion.
fn chain(
    x_fm: Pose,
    origin: Option<[f64; 3]>,
    rots: &[&(bool, Vector3<f64>, String)],
    trans: &[&(bool, Vector3<f64>, String)],
    independent: Vec<String>,
) -> Motion {
    let stage = |kind, d: &(bool, Vector3<f64>, String)| Stage {
        kind,
        geometry: Geometry {
            origin,
            axis: Some(arr(d.1)),
            ..Geometry::default()
        },
        coordinate: Some(d.2.clone()),
    };
    let stages = (trans.iter().map(|d| stage(JointType::P, d)))
        .chain(rots.iter().map(|d| stage(JointType::R, d)))
        .collect();
    Motion {
        x_fm,
        stages,
        independent,
    }
}

/// The TransformAxis elements of a SpatialTransform.
fn transform_axes<'a>(src: &Src, st: Node<'a>) -> Result<Vec<Axis<'a>>, ImportError> {
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
    Ok(axes)
}

/// The six axes composed at the default coordinates.
struct Composed {
    rot: UnitQuaternion<f64>,
    t: Vector3<f64>,
    /// Whether a coordinate drives several axes or a non-linear function.
    coupled: bool,
    /// (is rotation, world direction, coordinate) of each coordinate's driving axis.
    driving: Vec<(bool, Vector3<f64>, String)>,
}

/// Compose the axes at the coordinates' default values (`f`: the joint's frame in the parent
/// in the world); a function not evaluated is warned (taken as 0).
fn compose(
    src: &Src,
    b: &mut Builder,
    name: &str,
    coords: &[(String, f64)],
    f: Pose,
    axes: &[Axis],
) -> Result<Composed, ImportError> {
    let value_of = |c: &str| coords.iter().find(|x| x.0 == c).map(|x| x.1).unwrap_or(0.0);
    let mut rot = UnitQuaternion::identity();
    let mut t = Vector3::zeros();
    let mut coupled = false;
    let mut use_count: HashMap<&str, usize> = HashMap::new();
    for a in axes {
        for c in &a.coords {
            *use_count.entry(c.as_str()).or_default() += 1;
        }
    }
    // (is rotation, world direction, coordinate) of each coordinate's driving axis.
    let mut driving: Vec<(bool, Vector3<f64>, String)> = Vec::new();
    for a in axes {
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
    Ok(Composed {
        rot,
        t,
        coupled,
        driving,
    })
}

/// The mbsa joint that the driving rotations and translations make, and whether it is exact.
/// Over 80 lines: one flat table, a row per combination of axes.
fn custom_kind(
    origin: Option<[f64; 3]>,
    rots: &[&(bool, Vector3<f64>, String)],
    trans: &[&(bool, Vector3<f64>, String)],
) -> (JointType, Geometry, bool) {
    let par = |a: Vector3<f64>, b: Vector3<f64>| a.cross(&b).norm() < 1e-9;
    match (rots.len(), trans.len()) {
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
    }
}
