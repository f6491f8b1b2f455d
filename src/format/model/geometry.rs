//! Joint geometry: coordinate arrays, the geometry keys of a joint and its `second` table.

use super::joints::c_name;
use super::values::{as_map, as_number, as_seq, check_keys, err};
use crate::format::error::{ErrorKind, LoadError};
use crate::format::tree::Entry;
use crate::joint::JointType;
use crate::mechanism::{Geometry, Second, Space};
use std::ops::Range;

const SECOND_KEYS: &[&str] = &["origin", "axis", "axis2", "normal"];

/// A coordinate array: 3 numbers, or 2 in a planar mechanism when `planar2` (z = 0).
pub(super) fn parse_vector(e: &Entry, space: Space, axis: bool) -> Result<[f64; 3], LoadError> {
    let items = as_seq(&e.value, &format!("`{}`", e.key))?;
    let planar = space == Space::Planar;
    if !(items.len() == 3 || (planar && items.len() == 2)) {
        let want = if planar {
            "[x, y] or [x, y, z]"
        } else {
            "[x, y, z]"
        };
        return Err(err(
            ErrorKind::GeometryLength,
            format!(
                "`{}` must have {} coordinates, not {}",
                e.key,
                if planar { "2 or 3" } else { "3" },
                items.len()
            ),
            &e.value.span,
            format!("{} numbers", items.len()),
            Some(format!("write `{}` as {want}", e.key)),
        ));
    }
    let mut v = [0.0; 3];
    for (i, x) in items.iter().enumerate() {
        v[i] = as_number(x, &format!("a coordinate of `{}`", e.key))?;
    }
    if axis && v.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-12 {
        return Err(err(
            ErrorKind::ZeroAxis,
            format!("`{}` is the zero vector", e.key),
            &e.value.span,
            "zero length",
            Some("an axis or normal needs a direction, e.g. [0, 0, 1]".into()),
        ));
    }
    Ok(v)
}

pub(super) fn parse_geometry(es: &[Entry], space: Space) -> Result<Geometry, LoadError> {
    let mut g = Geometry::default();
    for e in es {
        match e.key.as_ref() {
            "origin" => g.origin = Some(parse_vector(e, space, false)?),
            "origin2" => g.origin2 = Some(parse_vector(e, space, false)?),
            "axis" => g.axis = Some(parse_vector(e, space, true)?),
            "axis2" => g.axis2 = Some(parse_vector(e, space, true)?),
            "normal" => g.normal = Some(parse_vector(e, space, true)?),
            "pitch" => g.pitch = Some(as_number(&e.value, "`pitch`")?),
            _ => {}
        }
    }
    Ok(g)
}

/// `second = { origin = [...], axis = [...] }`: the joint as carried by its second body at a
/// configuration that is not closed. Only the features the kind's second body carries
/// ([`Second::fields`]); not on a multiple joint.
pub(super) fn parse_second(
    e: &Entry,
    kind: JointType,
    space: Space,
    bodies: usize,
) -> Result<Box<Second>, LoadError> {
    let es = as_map(&e.value, "`second`")?;
    check_keys(es, SECOND_KEYS, "`second`")?;
    let fields = Second::fields(kind, space);
    let not_here = |span: &Range<usize>, message: String, text: &str, help: String| {
        err(
            ErrorKind::SecondNotApplicable,
            message,
            span,
            text,
            Some(help),
        )
    };
    if bodies > 2 {
        return Err(not_here(
            &e.key_span,
            format!("a multiple joint ({bodies} bodies) has no `second` geometry"),
            "not on a multiple joint",
            "split it into binary joints to give each its second body's geometry".into(),
        ));
    }
    if fields.is_empty() {
        return Err(not_here(
            &e.key_span,
            format!(
                "joint type {} ({}) has no `second` geometry in a {} mechanism",
                kind.code(),
                c_name(kind.code()),
                space.name()
            ),
            "not for this joint type",
            match kind {
                JointType::SPSP => {
                    "SPSP carries its second body's centre in `origin2` already".into()
                }
                _ => "its second body carries no point or axis the constraints compare; remove `second`"
                    .into(),
            },
        ));
    }
    let mut s = Second::default();
    for x in es {
        let key = x.key.as_ref();
        if !fields.contains(&key) {
            return Err(not_here(
                &x.key_span,
                format!(
                    "joint type {}: its second body carries no `{key}`",
                    kind.code()
                ),
                "not carried by the second body",
                format!(
                    "`second` of joint type {} in a {} mechanism takes {}",
                    kind.code(),
                    space.name(),
                    fields
                        .iter()
                        .map(|f| format!("`{f}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        let v = Some(parse_vector(x, space, key != "origin")?);
        match key {
            "origin" => s.origin = v,
            "axis" => s.axis = v,
            "axis2" => s.axis2 = v,
            _ => s.normal = v,
        }
    }
    Ok(Box::new(s))
}
