//! MJCF `<equality>` constraints: `connect` closes a loop with a spherical joint, `weld` merges
//! two bodies; the couplings are warned.

use super::{Ctx, E, Fk, Site};
use crate::import::{Builder, ImportError, JointRec};
use crate::joint::JointType;
use nalgebra::Vector3;
use std::collections::HashMap;

impl<'d> Ctx<'d> {
    /// An element of `<equality>`: a connect (an S joint), a weld, or a coupling warned.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn equality(
        &self,
        e: E<'d>,
        b: &mut Builder,
        body_by_name: &HashMap<String, usize>,
        ids: &[usize],
        at0: &Fk,
        at: &Fk,
    ) -> Result<(), ImportError> {
        let s = self.src(e);
        let tag = e.n.tag_name().name();
        let name = e.n.attribute("name");
        let name_attr = name.map(|n| format!(" name=\"{n}\"")).unwrap_or_default();
        let loc = s.loc(e.n);
        if matches!(e.n.attribute("active"), Some("false")) {
            b.warn(format!(
                "{loc}: <{tag}{name_attr}> is inactive (active=\"false\"): left out"
            ));
            return Ok(());
        }
        match tag {
            "connect" => self.connect(e, b, body_by_name, ids, at0, at)?,
            "weld" => {
                let (b1, b2) = self.weld_bodies(e, body_by_name)?;
                b.weld(ids[b1], ids[b2], &format!("<weld{name_attr}> at {loc}"));
            }
            "joint" | "tendon" | "flex" | "distance" => {
                b.warn(format!(
                    "{loc}: <{tag}{name_attr}> equality coupling: not representable (left out)"
                ));
            }
            _ => {}
        }
        Ok(())
    }
    /// A `<connect>`: an S joint at a point of body1 (its anchor or site1) and of body2.
    #[allow(clippy::too_many_arguments)]
    fn connect(
        &self,
        e: E<'d>,
        b: &mut Builder,
        body_by_name: &HashMap<String, usize>,
        ids: &[usize],
        at0: &Fk,
        at: &Fk,
    ) -> Result<(), ImportError> {
        let s = self.src(e);
        let name = e.n.attribute("name");
        let name_attr = name.map(|n| format!(" name=\"{n}\"")).unwrap_or_default();
        let loc = s.loc(e.n);
        // (body1, point on it in its frame, body2, the same point in body2's frame).
        let (b1, b2, p1, p2) =
            if let (Some(s1), Some(s2)) = (self.eq_site(e, "site1")?, self.eq_site(e, "site2")?) {
                s.note(&s1.2, 1.0);
                s.note(&s2.2, 1.0);
                (s1.0, s2.0, s1.1, s2.1)
            } else {
                let Some(b1) = self.eq_body(e, "body1", false, body_by_name)? else {
                    return Err(s
                        .err(
                            e.n,
                            "no body1",
                            "<connect> needs body1 and anchor, or site1 and site2",
                        )
                        .with_help("write <connect body1=\"a\" body2=\"b\" anchor=\"x y z\"/>"));
                };
                let b2 = self.eq_body(e, "body2", true, body_by_name)?.unwrap_or(0);
                let Some(a) = s.nums_attr(e.n, "anchor", 3)? else {
                    return Err(s
                        .err(e.n, "no anchor", "<connect body1=...> without `anchor`")
                        .with_help("anchor is the point in body1's frame"));
                };
                let a = Vector3::new(a[0], a[1], a[2]);
                let world0 = at0.0[b1] * nalgebra::Point3::from(a);
                let local2 = at0.0[b2].inverse() * world0;
                (b1, b2, a, local2.coords)
            };
        let w1 = at.0[b1] * nalgebra::Point3::from(p1);
        let w2 = at.0[b2] * nalgebra::Point3::from(p2);
        let gap = (w1 - w2).norm();
        if gap > 1e-6 {
            b.warn(format!(
                "{loc}: <connect{name_attr}> between `{}` and `{}` is not closed at this configuration (gap {:.3e}): its joint carries body2's point in `second` (`mbsa assemble` closes the loop)",
                self.bodies[b1].name, self.bodies[b2].name, gap
            ));
        }
        let id = name.map(str::to_string).unwrap_or_else(|| {
            format!("connect:{}-{}", self.bodies[b1].name, self.bodies[b2].name)
        });
        b.joint(JointRec {
            id,
            kind: JointType::S,
            bodies: vec![ids[b1], ids[b2]],
            driven: 0,
            geometry: crate::import::point_closure(w1.coords, w2.coords),
            comments: vec![format!("<connect{name_attr}> (loop closure) at {loc}")],
        });
        Ok(())
    }

    /// The two bodies a `<weld>` names (by site1 and site2, or body1 and body2).
    fn weld_bodies(
        &self,
        e: E<'d>,
        body_by_name: &HashMap<String, usize>,
    ) -> Result<(usize, usize), ImportError> {
        let s = self.src(e);
        let (b1, b2) =
            if let (Some(s1), Some(s2)) = (self.eq_site(e, "site1")?, self.eq_site(e, "site2")?) {
                (s1.0, s2.0)
            } else {
                let Some(b1) = self.eq_body(e, "body1", false, body_by_name)? else {
                    return Err(s
                        .err(
                            e.n,
                            "no body1",
                            "<weld> needs body1 (and body2), or site1 and site2",
                        )
                        .with_help("write <weld body1=\"a\" body2=\"b\"/>"));
                };
                (
                    b1,
                    self.eq_body(e, "body2", true, body_by_name)?.unwrap_or(0),
                )
            };
        Ok((b1, b2))
    }

    /// The body an equality element's `attr` names (`world` by default when `default_world`).
    fn eq_body(
        &self,
        e: E<'d>,
        attr: &str,
        default_world: bool,
        body_by_name: &HashMap<String, usize>,
    ) -> Result<Option<usize>, ImportError> {
        let s = self.src(e);
        let tag = e.n.tag_name().name();
        match e.n.attribute(attr) {
            Some(n) => match body_by_name.get(n) {
                Some(&i) => Ok(Some(i)),
                None => Err(s
                    .err_attr(
                        e.n,
                        attr,
                        "no such body",
                        format!("<{tag}> names body `{n}`, which the model does not define"),
                    )
                    .with_help("body1 and body2 name <body> elements (or `world`)")),
            },
            None => Ok(default_world.then_some(0)),
        }
    }

    /// The site an equality element's `attr` names, if given.
    fn eq_site(&self, e: E<'d>, attr: &str) -> Result<Option<Site>, ImportError> {
        let s = self.src(e);
        let tag = e.n.tag_name().name();
        match e.n.attribute(attr) {
            Some(n) => match self.sites.get(n) {
                Some(&v) => Ok(Some(v)),
                None => Err(s
                    .err_attr(
                        e.n,
                        attr,
                        "no such site",
                        format!("<{tag}> names site `{n}`, which the model does not define"),
                    )
                    .with_help("site1 and site2 name <site> elements")),
            },
            None => Ok(None),
        }
    }
}
