//! The mechanism drawn from its joint geometry: every joint point (on each body it joins) and
//! a short segment of each joint axis, projected onto one plane, each body a polygon through
//! its joint points. The plane: a planar mechanism's own; else the best-fit plane of the joint
//! points (the two largest principal directions), turned so that the world's z (or y, when
//! the plane is nearly horizontal) points up. One frame per sweep step, as JSON numbers the
//! script reads.

use super::{Animation, Named, esc, px};
use crate::mechanism::{Mechanism, Space};
use crate::position::PoseReport;
use crate::structure::Analysis;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use std::fmt::Write;

const VIEW_W: f64 = 720.0;
const VIEW_H: f64 = 480.0;
const MARGIN: f64 = 24.0;

/// A point carried by a body: its body index and its position at the file's configuration.
struct Point {
    body: usize,
    at: Vector3<f64>,
}

/// A joint's marker: the joint's index, its point, its axis segment's two points.
type Marker = (usize, usize, Option<(usize, usize)>);

/// The points, each body's polygon (point indices) and each joint's marker.
struct Figure {
    points: Vec<Point>,
    links: Vec<(usize, Vec<usize>)>,
    joints: Vec<Marker>,
}

fn figure(m: &Mechanism, size: f64) -> Figure {
    let mut f = Figure {
        points: Vec::new(),
        links: Vec::new(),
        joints: Vec::new(),
    };
    let mut per_body: Vec<Vec<usize>> = vec![Vec::new(); m.bodies.len()];
    for (ji, j) in m.joints.iter().enumerate() {
        let Some(o) = j.geometry.origin else { continue };
        let o = Vector3::from(o);
        let first = f.points.len();
        for &b in j.bodies.iter() {
            per_body[b].push(f.points.len());
            f.points.push(Point { body: b, at: o });
        }
        let axis = j
            .geometry
            .axis
            .map(Vector3::from)
            .filter(|a| a.norm() > 1e-12);
        let seg = axis.map(|a| {
            let d = a.normalize() * size * 0.04;
            let k = f.points.len();
            f.points.push(Point {
                body: j.bodies[0],
                at: o - d,
            });
            f.points.push(Point {
                body: j.bodies[0],
                at: o + d,
            });
            (k, k + 1)
        });
        f.joints.push((ji, first, seg));
    }
    for (b, pts) in per_body.into_iter().enumerate() {
        if pts.len() >= 2 {
            f.links.push((b, pts));
        }
    }
    f
}

/// The projection plane: (right, up) unit vectors.
fn plane(m: &Mechanism, pts: &[Vector3<f64>]) -> (Vector3<f64>, Vector3<f64>) {
    if m.space == Space::Planar || pts.len() < 3 {
        return (Vector3::x(), Vector3::y());
    }
    let n = pts.len() as f64;
    let c = pts.iter().sum::<Vector3<f64>>() / n;
    let mut cov = Matrix3::zeros();
    for p in pts {
        let d = p - c;
        cov += d * d.transpose();
    }
    let e = cov.symmetric_eigen();
    let k = e.eigenvalues.imin();
    let normal: Vector3<f64> = e.eigenvectors.column(k).into_owned();
    if normal.norm() < 0.5 || !normal.iter().all(|x| x.is_finite()) {
        return (Vector3::x(), Vector3::y());
    }
    let normal = normal.normalize();
    let world_up = if normal.z.abs() < 0.9 {
        Vector3::z()
    } else {
        Vector3::y()
    };
    let up = (world_up - normal * normal.dot(&world_up)).normalize();
    // The viewer on the side of the normal with a positive largest component.
    let big = normal.iamax();
    let normal = if normal[big] < 0.0 { -normal } else { normal };
    let right = up.cross(&normal).normalize();
    (right, up)
}

fn pose_of(p: &PoseReport) -> (UnitQuaternion<f64>, Vector3<f64>) {
    let q = p.quaternion;
    (
        UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
        Vector3::from(p.translation),
    )
}

/// Write the mechanism view.
pub(super) fn view(out: &mut String, m: &Mechanism, a: &Analysis, anim: &Animation) {
    let has_points = m.joints.iter().any(|j| j.geometry.origin.is_some());
    if matches!(anim, Animation::NoGeometry) || !has_points {
        out.push_str("<p id=\"no-drawing\" class=\"none\">No drawing: the file gives no joint geometry (joint origins and axes) to draw the mechanism from.</p>\n");
        return;
    }
    let size = crate::position::residual::model_size(m);
    let fig = figure(m, size);
    let refs: Vec<Vector3<f64>> = fig.points.iter().map(|p| p.at).collect();
    let (right, up) = plane(m, &refs);
    // Frames: body poses per step, or the file's configuration alone.
    let steps: Vec<&[PoseReport]> = match anim {
        Animation::Swept { sweep, .. } => sweep.steps.iter().map(|s| s.poses.as_slice()).collect(),
        _ => Vec::new(),
    };
    let mut frames: Vec<Vec<(f64, f64)>> = Vec::new();
    let project = |v: Vector3<f64>| (v.dot(&right), v.dot(&up));
    if steps.is_empty() {
        frames.push(refs.iter().map(|&v| project(v)).collect());
    }
    for poses in &steps {
        frames.push(
            fig.points
                .iter()
                .map(|p| match poses.get(p.body) {
                    Some(pr) => {
                        let (r, t) = pose_of(pr);
                        project(r * p.at + t)
                    }
                    None => project(p.at),
                })
                .collect(),
        );
    }
    // Bounds over every frame, one scale.
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for fr in &frames {
        for &(x, y) in fr {
            if x.is_finite() && y.is_finite() {
                lo = (lo.0.min(x), lo.1.min(y));
                hi = (hi.0.max(x), hi.1.max(y));
            }
        }
    }
    let span = ((hi.0 - lo.0).max(hi.1 - lo.1)).max(1e-9);
    let s = ((VIEW_W - 2.0 * MARGIN) / (hi.0 - lo.0).max(span * 0.05))
        .min((VIEW_H - 2.0 * MARGIN) / (hi.1 - lo.1).max(span * 0.05));
    let ox = (VIEW_W - s * (hi.0 - lo.0)) / 2.0 - s * lo.0;
    let oy = (VIEW_H + s * (hi.1 - lo.1)) / 2.0 + s * lo.1;
    let screen = |(x, y): (f64, f64)| (ox + s * x, oy - s * y);
    let scr: Vec<Vec<(f64, f64)>> = frames
        .iter()
        .map(|fr| fr.iter().map(|&p| screen(p)).collect())
        .collect();
    caption(out, m, anim, right, up, frames.len());
    shapes(out, m, a, &fig, &scr[0], frames.len());
    controls(out, anim, frames.len());
    // Frames: flat x, y lists.
    out.push_str("<script type=\"application/json\" id=\"frames\">[");
    for (k, fr) in scr.iter().enumerate() {
        if k > 0 {
            out.push(',');
        }
        out.push('[');
        for (i, &(x, y)) in fr.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            let _ = write!(out, "{},{}", px(x), px(y));
        }
        out.push(']');
    }
    out.push_str("]</script>\n");
}

fn caption(
    out: &mut String,
    m: &Mechanism,
    anim: &Animation,
    right: Vector3<f64>,
    up: Vector3<f64>,
    n: usize,
) {
    let v = |a: Vector3<f64>| format!("({:.2}, {:.2}, {:.2})", a.x + 0.0, a.y + 0.0, a.z + 0.0);
    let text = match anim {
        Animation::Swept { sweep, note } => {
            let mut t = format!("{note}: {n} step(s) of joint {}.", sweep.joint);
            if let Some(s) = &sweep.stopped {
                let _ = write!(t, " The sweep stopped: {s}.");
            }
            t
        }
        Animation::NoInput => "Not animated: the mechanism has no driven input and the diagnosis names no joint for one; drawn at the file's configuration.".into(),
        Animation::Failed { joint, reason } => format!("Not animated: the sweep of joint {joint} could not start: {reason}; drawn at the file's configuration."),
        Animation::NoGeometry => String::new(),
    };
    let _ = writeln!(out, "<p id=\"motion-note\">{}</p>", esc(&text));
    let plane = if m.space == Space::Planar {
        "the mechanism's plane".to_string()
    } else {
        format!(
            "projected onto the best-fit plane of the joint points: right {}, up {}",
            v(right),
            v(up)
        )
    };
    let _ = writeln!(
        out,
        "<p class=\"legend\">Bodies as polygons through their joint points, {plane}; joints named by the diagnosis in colour.</p>"
    );
}

fn shapes(
    out: &mut String,
    m: &Mechanism,
    a: &Analysis,
    fig: &Figure,
    at: &[(f64, f64)],
    n: usize,
) {
    let named = Named::of(a);
    let _ = writeln!(
        out,
        "<svg id=\"mechanism\" class=\"view\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {VIEW_W} {VIEW_H}\" width=\"{VIEW_W}\" data-frames=\"{n}\">"
    );
    for (b, pts) in &fig.links {
        // A polygon around the points' centre at the file's configuration, in angle order.
        let (cx, cy) = pts
            .iter()
            .fold((0.0, 0.0), |s, &i| (s.0 + at[i].0, s.1 + at[i].1));
        let (cx, cy) = (cx / pts.len() as f64, cy / pts.len() as f64);
        let mut order = pts.clone();
        order.sort_by(|&i, &j| {
            let ai = (at[i].1 - cy).atan2(at[i].0 - cx);
            let aj = (at[j].1 - cy).atan2(at[j].0 - cx);
            ai.total_cmp(&aj).then(i.cmp(&j))
        });
        let idx: Vec<String> = order.iter().map(|i| i.to_string()).collect();
        let coords: Vec<String> = order
            .iter()
            .map(|&i| format!("{},{}", px(at[i].0), px(at[i].1)))
            .collect();
        let class = if *b == m.frame { "link frame" } else { "link" };
        let _ = writeln!(
            out,
            "<polygon class=\"{class}\" data-p=\"{}\" points=\"{}\"><title>body {}</title></polygon>",
            idx.join(" "),
            coords.join(" "),
            esc(&m.body_id(*b).to_string())
        );
    }
    for &(ji, p, seg) in &fig.joints {
        let j = &m.joints[ji];
        if let Some((p1, p2)) = seg {
            let _ = writeln!(
                out,
                "<line class=\"axis\" data-p=\"{p1} {p2}\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
                px(at[p1].0),
                px(at[p1].1),
                px(at[p2].0),
                px(at[p2].1)
            );
        }
        let mut class = vec!["joint"];
        if j.driven > 0 {
            class.push("driven");
        }
        for (set, c) in [
            (&named.over_joints, "over"),
            (&named.under_joints, "under"),
            (&named.redundant_joints, "redundant"),
        ] {
            if set.contains(&j.id) {
                class.push(c);
            }
        }
        let _ = writeln!(
            out,
            "<circle class=\"{}\" data-joint=\"{}\" data-p=\"{p}\" cx=\"{}\" cy=\"{}\" r=\"5\"><title>joint {} ({})</title></circle>",
            class.join(" "),
            esc(&j.id),
            px(at[p].0),
            px(at[p].1),
            esc(&j.id),
            j.kind.code()
        );
    }
    out.push_str("</svg>\n");
}

fn controls(out: &mut String, anim: &Animation, n: usize) {
    let label = match anim {
        Animation::Swept { sweep, .. } => {
            let vals: Vec<String> = sweep.steps.iter().map(|s| format!("{}", s.value)).collect();
            format!(" data-values=\"{}\"", vals.join(" "))
        }
        _ => String::new(),
    };
    let disabled = if n < 2 { " disabled" } else { "" };
    let _ = writeln!(
        out,
        "<div class=\"controls\"><button id=\"play\" type=\"button\"{disabled}>play</button> <input id=\"step\" type=\"range\" min=\"0\" max=\"{}\" value=\"0\"{disabled}{label}> <span id=\"step-label\"></span></div>",
        n.saturating_sub(1)
    );
}
