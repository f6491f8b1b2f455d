//! Bar-joint frameworks: points and bars, each bar a body, a joint where bars meet.

use super::bodies::undeclared;
use super::geometry::parse_vector;
use super::values::{as_id, as_map, as_seq, check_keys, err, get, label, nearest, required};
use super::{frame_not_in_joint, no_joints};
use crate::format::error::{ErrorKind, LoadError};
use crate::format::tree::{Entry, Node};
use crate::joint::JointType;
use crate::mechanism::{Body, BodyId, Geometry, JointSpec, Mechanism, Space};
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;

const POINT_KEYS: &[&str] = &["id", "at"];
const BAR_KEYS: &[&str] = &["id", "points"];

/// Points: id -> (position, id span), in file order.
struct Points {
    ids: Vec<BodyId>,
    info: BTreeMap<BodyId, (Option<[f64; 3]>, Range<usize>)>,
}

/// A bar: its explicit id (if given) and its two points.
type BarSpec = (Option<BodyId>, [BodyId; 2]);

/// The mechanism of a bar-joint framework: each bar a body, one joint (S, or R in the plane)
/// at each point where two or more bars meet.
#[allow(clippy::too_many_arguments)]
pub(super) fn build_framework(
    top: &[Entry],
    root: &Node,
    name: &str,
    space: Space,
    frame: BodyId,
    frame_node: &Node,
    points: Option<&Entry>,
    bars: Option<&Entry>,
) -> Result<Mechanism, LoadError> {
    let _ = top;
    let points = read_points(points, space)?;
    let Some(bars) = bars else {
        let at = root.span.start..root.span.start;
        return Err(no_joints(&at, "no `bar` list in this file"));
    };
    let list = as_seq(&bars.value, "the bar list")?;
    if list.is_empty() {
        return Err(no_joints(&bars.value.span, "empty list"));
    }
    let (bar_specs, explicit) = read_bars(list, &points)?;
    let bar_ids = bar_ids(&bar_specs, &explicit);
    if !bar_ids.contains(&frame) {
        return Err(undeclared(
            &frame,
            &frame_node.span,
            bar_ids.iter(),
            "frame bar",
            "bars",
        ));
    }
    let specs = joints_at_points(&points, &bar_specs, &bar_ids, space);
    if !specs.iter().any(|s| s.bodies.contains(&frame)) {
        return Err(frame_not_in_joint(&frame, frame_node));
    }
    let extra = bar_ids
        .into_iter()
        .map(|id| Body { id, label: None })
        .collect();
    Ok(Mechanism::from_parts(name, space, frame, extra, specs))
}

/// The `point` list: ids unique, positions optional.
fn read_points(points: Option<&Entry>, space: Space) -> Result<Points, LoadError> {
    let mut point_ids: Vec<BodyId> = Vec::new();
    let mut point_info: BTreeMap<BodyId, (Option<[f64; 3]>, Range<usize>)> = BTreeMap::new();
    if let Some(p) = points {
        for pt in as_seq(&p.value, "the point list")? {
            let es = as_map(pt, "a point")?;
            check_keys(es, POINT_KEYS, "point")?;
            let id_entry = required(es, "id", pt, "point")?;
            let id = as_id(&id_entry.value, "a point id")?;
            if let Some((_, first)) = point_info.get(&id) {
                return Err(LoadError::new(
                    ErrorKind::DuplicatePointId,
                    format!("point `{id}` is declared twice"),
                    vec![
                        label(&id_entry.value.span, "declared again here"),
                        label(first, "first declared here"),
                    ],
                    Some("point ids must be unique".into()),
                ));
            }
            let at = match get(es, "at") {
                Some(e) => Some(parse_vector(e, space, false)?),
                None => None,
            };
            point_ids.push(id.clone());
            point_info.insert(id, (at, id_entry.value.span.clone()));
        }
    }
    Ok(Points {
        ids: point_ids,
        info: point_info,
    })
}

/// The bars of a non-empty `bar` list, and where each explicit id is.
#[allow(clippy::type_complexity)]
fn read_bars(
    list: &[Node],
    points: &Points,
) -> Result<(Vec<BarSpec>, BTreeMap<BodyId, Range<usize>>), LoadError> {
    let mut bar_specs: Vec<BarSpec> = Vec::new();
    let mut explicit: BTreeMap<BodyId, Range<usize>> = BTreeMap::new();
    for b in list {
        let es = as_map(b, "a bar")?;
        check_keys(es, BAR_KEYS, "bar")?;
        let pe = required(es, "points", b, "bar")?;
        let [p, q] = bar_ends(pe, points)?;
        let id = match get(es, "id") {
            None => None,
            Some(e) => {
                let id = as_id(&e.value, "a bar id")?;
                if let Some(first) = explicit.get(&id) {
                    return Err(LoadError::new(
                        ErrorKind::DuplicateBodyId,
                        format!("two bars have the id `{id}`"),
                        vec![
                            label(&e.value.span, "again here"),
                            label(first, "first here"),
                        ],
                        Some("bar ids must be unique".into()),
                    ));
                }
                explicit.insert(id.clone(), e.value.span.clone());
                Some(id)
            }
        };
        bar_specs.push((id, [p, q]));
    }
    Ok((bar_specs, explicit))
}

/// A bar's `points`: two distinct declared points.
fn bar_ends(pe: &Entry, points: &Points) -> Result<[BodyId; 2], LoadError> {
    let items = as_seq(&pe.value, "a bar's `points`")?;
    if items.len() != 2 {
        return Err(err(
            ErrorKind::BarPoints,
            format!(
                "a bar joins exactly two points; this one names {}",
                items.len()
            ),
            &pe.value.span,
            format!("{} points", items.len()),
            Some("write its two end points, e.g. points = [1, 2]".into()),
        ));
    }
    let mut ends = Vec::with_capacity(2);
    for p in items {
        let id = as_id(p, "a point id")?;
        if !points.info.contains_key(&id) {
            let names: Vec<String> = points.ids.iter().map(|p| p.to_string()).collect();
            let text = id.to_string();
            let help = match nearest(&text, names.iter().map(String::as_str)) {
                Some(n) => format!("did you mean `{n}`? declared points: {}", names.join(", ")),
                None if names.is_empty() => "declare the points with [[point]] id = ...".into(),
                None => format!("declared points: {}", names.join(", ")),
            };
            return Err(err(
                ErrorKind::UnknownPoint,
                format!("point `{id}` is not declared"),
                &p.span,
                "unknown point",
                Some(help),
            ));
        }
        ends.push(id);
    }
    if ends[0] == ends[1] {
        return Err(err(
            ErrorKind::BarPoints,
            format!("a bar joins point `{}` to itself", ends[0]),
            &pe.value.span,
            "the same point twice",
            Some("a bar joins two distinct points".into()),
        ));
    }
    Ok(ends
        .try_into()
        .expect("exactly two ends were checked above"))
}

/// Each bar's id: the explicit one, else the default `p-q`, suffixed when taken.
fn bar_ids(bar_specs: &[BarSpec], explicit: &BTreeMap<BodyId, Range<usize>>) -> Vec<BodyId> {
    let mut taken: BTreeSet<BodyId> = explicit.keys().cloned().collect();
    let mut bar_ids: Vec<BodyId> = Vec::with_capacity(bar_specs.len());
    for (id, [p, q]) in bar_specs {
        let id = match id {
            Some(id) => id.clone(),
            None => {
                let base = format!("{p}-{q}");
                let mut id = BodyId::Name(base.clone());
                let mut n = 1;
                while taken.contains(&id) {
                    n += 1;
                    id = BodyId::Name(format!("{base}#{n}"));
                }
                taken.insert(id.clone());
                id
            }
        };
        bar_ids.push(id);
    }
    bar_ids
}

/// One joint per point where two or more bars meet, in point order.
fn joints_at_points(
    points: &Points,
    bar_specs: &[BarSpec],
    bar_ids: &[BodyId],
    space: Space,
) -> Vec<JointSpec> {
    let kind = if space == Space::Spatial {
        JointType::S
    } else {
        JointType::R
    };
    // The bars at each point, in bar order, in one pass over the bars (a scan of every bar
    // per point was quadratic: 58 s for a 10^5-point framework). A bar's ends are distinct.
    let mut at: BTreeMap<&BodyId, Vec<usize>> = BTreeMap::new();
    for (k, (_, ends)) in bar_specs.iter().enumerate() {
        for p in ends {
            at.entry(p).or_default().push(k);
        }
    }
    let mut specs = Vec::new();
    for pid in &points.ids {
        let meeting: Vec<BodyId> = at
            .get(pid)
            .map_or(&[][..], Vec::as_slice)
            .iter()
            .map(|&k| bar_ids[k].clone())
            .collect();
        if meeting.len() < 2 {
            continue;
        }
        let origin = points.info.get(pid).and_then(|(at, _)| *at);
        specs.push(JointSpec {
            id: Some(pid.to_string()),
            kind,
            bodies: meeting,
            driven: 0,
            geometry: Geometry {
                origin,
                axis: (space == Space::Planar).then_some([0.0, 0.0, 1.0]),
                ..Geometry::default()
            },
        });
    }
    specs
}
