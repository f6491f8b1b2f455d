//! From the spanned tree to a validated [`Mechanism`]: every check of format v1, each error
//! located at the key or value it is about.

mod bodies;
mod expect;
mod framework;
mod geometry;
mod joint_ids;
mod joints;
mod values;

use super::error::{ErrorKind, LoadError};
use super::read::Lazy;
use super::tree::{Entry, Node, Value};
use crate::mechanism::{BodyId, Mechanism, Space};
use expect::parse_expect;
use framework::build_framework;
pub(crate) use joint_ids::push_int;
use joints::build_joints;
use std::ops::Range;
use values::{as_id, as_map, as_number, as_str, check_keys, err, get, get_alias, label, nearest};

const TOP_KEYS: &[&str] = &[
    "name",
    "description",
    "space",
    "frame",
    "body",
    "bodies",
    "joint",
    "joints",
    "point",
    "points",
    "bar",
    "bars",
    "expect",
    "precision",
    "$schema",
];

/// Read the whole document.
pub(crate) fn build<'a>(
    mut root: Node<'a>,
    default_name: &str,
    lazy: Lazy<'a>,
) -> Result<Mechanism, LoadError> {
    let mut lists = take_joint_lists(&mut root);
    let root = &root;
    let top = as_map(root, "the top level")?;
    if top.is_empty() {
        return Err(empty(root));
    }
    check_keys(top, TOP_KEYS, "top-level")?;
    let name = match get(top, "name") {
        Some(e) => as_str(&e.value, "`name`")?.to_string(),
        None => default_name.to_string(),
    };
    let description = match get(top, "description") {
        Some(e) => Some(as_str(&e.value, "`description`")?.to_string()),
        None => None,
    };
    if let Some(e) = get(top, "$schema") {
        as_str(&e.value, "`$schema`")?;
    }
    let space = match get(top, "space") {
        Some(e) => parse_space(&e.value)?,
        None => Space::Spatial,
    };
    let joints = get_alias(top, "joint", "joints")?;
    let bodies = get_alias(top, "body", "bodies")?;
    let points = get_alias(top, "point", "points")?;
    let bars = get_alias(top, "bar", "bars")?;
    let classic = joints.or(bodies);
    let framework = points.or(bars);
    if let (Some(c), Some(f)) = (classic, framework) {
        return Err(LoadError::new(
            ErrorKind::MixedFramework,
            "joints and a bar-joint framework in one file",
            vec![
                label(&f.key_span, "framework"),
                label(&c.key_span, "joint-and-body description"),
            ],
            Some("describe the mechanism either with `joint`/`body` or with `point`/`bar`".into()),
        ));
    }
    let frame_entry = get(top, "frame").ok_or_else(|| missing_frame(top))?;
    let frame = as_id(&frame_entry.value, "`frame`")?;

    let mut m = if framework.is_some() {
        build_framework(
            top,
            root,
            &name,
            space,
            frame,
            &frame_entry.value,
            points,
            bars,
        )?
    } else {
        let list = joints.and_then(|j| lists[usize::from(j.key != "joint")].take());
        build_joints(
            root,
            &name,
            space,
            frame,
            &frame_entry.value,
            joints.map(|j| (j, list, lazy)),
            bodies,
        )?
    };
    m.description = description;
    if let Some(e) = get(top, "expect") {
        m.expect = parse_expect(&e.value)?;
    }
    if let Some(e) = get(top, "precision") {
        m.precision = Some(parse_precision(&e.value)?);
    }
    Ok(m)
}

/// The joint lists taken out of the tree (a placeholder stays), to be read and freed one
/// joint at a time: the largest part of a large file. `[joint, joints]`.
fn take_joint_lists<'a>(root: &mut Node<'a>) -> [Option<Value<'a>>; 2] {
    let mut lists: [Option<Value<'a>>; 2] = [None, None];
    if let Value::Map(es) = &mut root.value {
        for e in es.iter_mut() {
            let slot = match e.key.as_ref() {
                "joint" => 0,
                "joints" => 1,
                _ => continue,
            };
            if matches!(e.value.value, Value::Seq(_) | Value::Deferred) {
                lists[slot] = Some(std::mem::replace(&mut e.value.value, Value::Deferred));
            }
        }
    }
    lists
}

/// No `frame` at the top level (`top`, not empty).
fn missing_frame(top: &[Entry]) -> LoadError {
    let at = top[0].key_span.clone();
    err(
        ErrorKind::MissingFrame,
        "no `frame`: the fixed body is required",
        &at,
        "the top level has no `frame`",
        Some("add `frame = <body id>` (TOML) or `frame: <body id>` (YAML), e.g. frame = 1".into()),
    )
}

/// The `precision` key: how precisely every geometry number is known (±, file units), a
/// geometry number ([`as_number`]: finite, at most [`values::MAX_GEOMETRY_NUMBER`]) that is >= 0.
fn parse_precision(node: &Node) -> Result<f64, LoadError> {
    let x = as_number(node, "`precision`")?;
    if x < 0.0 {
        return Err(err(
            ErrorKind::NumberOutOfRange,
            format!("`precision` must be a number >= 0, not {x:e}"),
            &node.span,
            "negative",
            Some(
                "`precision` is how precisely the geometry numbers are known (±, in file units), \
                 e.g. precision = 5e-7; leave it out to judge the numbers by their written digits"
                    .into(),
            ),
        ));
    }
    Ok(x)
}

fn empty(root: &Node) -> LoadError {
    err(
        ErrorKind::Empty,
        "the file is empty",
        &(root.span.start..root.span.start),
        "nothing here",
        Some("a mechanism needs at least `frame` and one joint; see docs/format.md".into()),
    )
}

/// A root that is absent (YAML stream without a document).
pub(crate) fn empty_document() -> LoadError {
    empty(&Node {
        span: 0..0,
        value: Value::Null,
    })
}

fn parse_space(node: &Node) -> Result<Space, LoadError> {
    let s = as_str(node, "`space`")?;
    match s.trim().to_ascii_lowercase().as_str() {
        "spatial" => Ok(Space::Spatial),
        "planar" => Ok(Space::Planar),
        "spherical" => Ok(Space::Spherical),
        _ => {
            let names = ["spatial", "planar", "spherical"];
            let help = match nearest(s, names) {
                Some(n) => {
                    format!("did you mean `{n}`? space is one of spatial, planar, spherical")
                }
                None => "space is one of spatial (B = 6), planar (B = 3), spherical (B = 3)".into(),
            };
            Err(err(
                ErrorKind::InvalidSpace,
                format!("invalid space `{s}`"),
                &node.span,
                "not a space",
                Some(help),
            ))
        }
    }
}

pub(super) fn no_joints(at: &Range<usize>, label_text: &str) -> LoadError {
    err(
        ErrorKind::NoJoints,
        "the mechanism has no joints",
        at,
        label_text,
        Some(
            "add at least one joint: [[joint]] with `type` and `bodies` (or points and bars)"
                .into(),
        ),
    )
}

pub(super) fn frame_not_in_joint(frame: &BodyId, frame_node: &Node) -> LoadError {
    err(
        ErrorKind::FrameNotInJoint,
        format!("the frame `{frame}` is not joined to anything"),
        &frame_node.span,
        "no joint names this body",
        Some("the frame must appear in the `bodies` of at least one joint".into()),
    )
}
