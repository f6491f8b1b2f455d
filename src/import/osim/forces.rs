//! OpenSim constraints (PointConstraint: a spherical joint; WeldConstraint: a weld) and
//! actuators (CoordinateActuator, TorqueActuator: driven DOF).

use super::joints::offset_frame;
use super::{last, text_of, vec3, xyz_body};
use crate::import::{Builder, ImportError, JointRec, Node, Pose, Src, pose};
use crate::joint::JointType;
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// One element of the ConstraintSet (`world`: the bodies' world poses); a disabled one and
/// the ones not representable are warned.
pub(super) fn constraint(
    src: &Src,
    b: &mut Builder,
    c: Node,
    world: &HashMap<String, Pose>,
) -> Result<(), ImportError> {
    let tag = c.tag_name().name();
    let cname = c.attribute("name").unwrap_or("");
    let loc = src.loc(c);
    if text_of(c, "isDisabled") == Some("true") || text_of(c, "isEnforced") == Some("false") {
        b.warn(format!("{loc}: <{tag}> `{cname}` is disabled: left out"));
        return Ok(());
    }
    let body_of_name = |name: &str| -> Result<(String, Pose), ImportError> {
        match world.get(name) {
            Some(p) => Ok((name.to_string(), *p)),
            None => Err(src
                .err(
                    c,
                    "no such body",
                    format!("<{tag}> `{cname}` names body `{name}`, which is not in the model"),
                )
                .with_help("name a Body of the BodySet, or the ground")),
        }
    };
    let body_of = |a: &str, bb: &str| -> Result<(String, Pose), ImportError> {
        let name = text_of(c, a).or_else(|| text_of(c, bb)).map(last);
        body_of_name(name.unwrap_or(""))
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
                geometry: crate::import::point_closure(p1.coords, p2.coords),
                comments: vec![format!(
                    "<PointConstraint name=\"{cname}\"> (loop closure) at {loc}"
                )],
            });
        }
        "WeldConstraint" => {
            // Each side: an OpenSim 4 frame (through the constraint's offset frames), or an
            // OpenSim 3 body with the frame's location and orientation in it.
            let side = |k: u8| -> Result<(String, Pose), ImportError> {
                let (name, x) = match text_of(c, &format!("socket_frame{k}")) {
                    Some(path) => offset_frame(src, c, path)?,
                    None => {
                        let name = text_of(c, &format!("body_{k}")).map(last).unwrap_or("");
                        let at = vec3(src, c, &format!("location_body_{k}"))?;
                        let turn = vec3(src, c, &format!("orientation_body_{k}"))?;
                        (name.to_string(), pose(at, xyz_body(&turn)))
                    }
                };
                let (name, w) = body_of_name(&name)?;
                Ok((name, w * x))
            };
            let ((n1, f1), (n2, f2)) = (side(1)?, side(2)?);
            let (i1, i2) = (b.body(&n1, ""), b.body(&n2, ""));
            b.weld_cut(i1, i2, &f1, &f2, &format!("WeldConstraint `{cname}`"), &loc);
        }
        "CoordinateCouplerConstraint" => {
            b.warn(format!("{loc}: CoordinateCouplerConstraint `{cname}` couples coordinates: not representable (left out)"));
        }
        other => b.warn(format!(
            "{loc}: <{other}> `{cname}` not representable (left out)"
        )),
    }
    Ok(())
}

/// One element of the ForceSet: an actuator drives one DOF of the joint of its coordinate or
/// between its bodies. `false` for a force element that is no actuator.
pub(super) fn actuator(
    src: &Src,
    b: &mut Builder,
    f: Node,
    coord_joint: &HashMap<String, (usize, usize)>,
    jindex: &HashMap<usize, Vec<usize>>,
) -> bool {
    let tag = f.tag_name().name();
    let fname = f.attribute("name").unwrap_or("");
    let loc = src.loc(f);
    let target = match tag {
        "CoordinateActuator" => {
            let cn = text_of(f, "coordinate").unwrap_or("");
            match coord_joint
                .get(cn)
                .and_then(|(k, s)| jindex.get(k).and_then(|v| v.get(*s)))
            {
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
        _ => return false,
    };
    if let Some(ji) = target {
        let j = &mut b.joints[ji];
        if j.driven < j.kind.grade() as u32 {
            j.driven += 1;
            j.comments
                .push(format!("driven by <{tag} name=\"{fname}\"> at {loc}"));
        }
    }
    true
}
