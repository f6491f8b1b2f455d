//! The configuration of an MJCF model: the keyframe chosen (or qpos0), and forward kinematics
//! at it.

use super::{Ctx, E, Fk, Kind};
use crate::import::{ImportError, ImportOptions, Pose, Unique, pose, unit_quat};
use nalgebra::{Translation3, UnitQuaternion};

impl<'d> Ctx<'d> {
    /// Two keyframes with one name are refused (MuJoCo refuses them; `--keyframe` would pick
    /// one of them silently).
    pub(super) fn check_keyframe_names(
        &self,
        top: &[E<'d>],
        docs: &'d [roxmltree::Document<'d>],
    ) -> Result<(), ImportError> {
        let mut names = Unique::new("keyframe");
        for sec in top.iter().filter(|e| e.n.has_tag_name("keyframe")) {
            for k in self.kids(*sec, docs) {
                if let Some(n) = k.n.attribute("name").filter(|n| !n.is_empty())
                    && k.n.has_tag_name("key")
                {
                    names.add(self.src(k), k.n, "name", n)?;
                }
            }
        }
        Ok(())
    }

    /// The keyframe's qpos (`None` = qpos0) and the configuration in words.
    pub(super) fn keyframe(
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
    pub(super) fn fk(&self, qpos: Option<&[f64]>) -> Fk {
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
                        if let (Some(w), Some(x), Some(y), Some(z)) = (q(0), q(1), q(2), q(3))
                            && let Some(r) = unit_quat(w, x, y, z)
                        {
                            p = about(p, r);
                        }
                    }
                    Kind::Free => {
                        if let Some(v) = qpos {
                            let a = &v[j.qposadr..j.qposadr + 7];
                            let r = unit_quat(a[3], a[4], a[5], a[6])
                                .unwrap_or_else(UnitQuaternion::identity);
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
}
