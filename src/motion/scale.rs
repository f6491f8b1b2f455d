//! The dimensionless geometry (centre and characteristic length) and how precisely the file's
//! numbers are known: what the rank threshold at the file's geometry is made of.

use crate::mechanism::{Geometry, Mechanism, Space};
use crate::numbers::rounding_of;

/// How many bodies (the first, in body order) [`scale_of`] measures for the characteristic
/// length: a median over 65,536 bodies is as good as over all, and the scratch memory stays
/// bounded (2.6 MB) on a 10^6-body file.
pub(super) const SIZED_BODIES: usize = 1 << 16;

/// The change of origin and length unit that makes the file's geometry dimensionless before
/// any rank decision: a point `p` becomes `(p − centre) / length`, a pitch `h` becomes
/// `h / length`, directions are unchanged. Twists and rows built at the scaled geometry are
/// those of the same model written in any length unit and placed anywhere; the rounding
/// threshold is scaled to match ([`file_threshold`]). Reports give points in file units
/// ([`Scale::world_twist`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// The centre of the bounding box of the joint points (file units).
    pub centre: [f64; 3],
    /// The characteristic length (file units, > 0).
    pub length: f64,
}

impl Scale {
    /// No change (random realizations, spherical mechanisms, files without points).
    pub const IDENTITY: Scale = Scale {
        centre: [0.0; 3],
        length: 1.0,
    };

    /// A point in characteristic lengths about the centre.
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|i| (p[i] - self.centre[i]) / self.length)
    }

    /// A joint's geometry made dimensionless (points and the pitch; directions unchanged).
    pub fn geometry(&self, g: &Geometry) -> Geometry {
        let mut out = g.clone();
        if *self == Scale::IDENTITY {
            return out;
        }
        out.origin = g.origin.map(|p| self.point(p));
        out.origin2 = g.origin2.map(|p| self.point(p));
        out.pitch = g.pitch.map(|h| h / self.length);
        if let Some(second) = out.second.as_mut() {
            second.origin = second.origin.map(|p| self.point(p));
        }
        out
    }

    /// A twist of the dimensionless geometry (about the centre, lengths in characteristic
    /// lengths) as the twist of the file's geometry about the world origin in file units:
    /// `v_O = Lc · v_c + c × ω` (spatial), `(Lc · v_c,x + ω c_y, Lc · v_c,y − ω c_x)`
    /// (planar); a spherical twist is unchanged.
    pub fn world_twist(&self, space: Space, t: &[f64]) -> Vec<f64> {
        let (c, l) = (self.centre, self.length);
        match (space, t) {
            (Space::Spatial, &[wx, wy, wz, vx, vy, vz]) => vec![
                wx,
                wy,
                wz,
                l * vx + c[1] * wz - c[2] * wy,
                l * vy + c[2] * wx - c[0] * wz,
                l * vz + c[0] * wy - c[1] * wx,
            ],
            (Space::Planar, &[w, vx, vy]) => vec![w, l * vx + w * c[1], l * vy - w * c[0]],
            _ => t.to_vec(),
        }
    }
}

/// The dimensionless geometry of `m`'s file geometry ([`Scale`]). The centre is the centre
/// of the bounding box of the joint points (`origin`, `origin2`). The characteristic length
/// is the median body size, a body's size being the largest distance from its first joint's
/// origin to its other joints' origins (bodies whose joints' origins coincide left out): the
/// length of a typical link, which does not grow with the number of links. (A length that
/// grew with the model's extent, such as the RMS distance of the points from the centre,
/// would shrink a long row's bars to 1/N and its smallest singular values with them, below
/// the relative threshold.) Without such a body, half the bounding box's diagonal; without
/// points (or in a spherical mechanism, whose points are the fixed centre), no change.
pub fn scale_of(m: &Mechanism) -> Scale {
    if m.space == Space::Spherical {
        return Scale::IDENTITY;
    }
    let finite = |p: &[f64; 3]| p.iter().all(|x| x.is_finite());
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in m
        .joints
        .iter()
        .flat_map(|j| [j.geometry.origin, j.geometry.origin2])
        .flatten()
        .filter(finite)
    {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    if lo[0] > hi[0] {
        return Scale::IDENTITY;
    }
    let centre = [0, 1, 2].map(|i| lo[i] + (hi[i] - lo[i]) / 2.0);
    let nb = m.bodies.len().min(SIZED_BODIES);
    let mut anchor: Vec<Option<[f64; 3]>> = vec![None; nb];
    let mut size = vec![0.0f64; nb];
    for j in &m.joints {
        let Some(o) = j.geometry.origin.filter(finite) else {
            continue;
        };
        for &b in j.bodies.iter().filter(|&&b| b < nb) {
            match anchor[b] {
                None => anchor[b] = Some(o),
                Some(a) => {
                    let d = (0..3).map(|i| (o[i] - a[i]).powi(2)).sum::<f64>().sqrt();
                    size[b] = size[b].max(d);
                }
            }
        }
    }
    let mut sizes: Vec<f64> = size
        .into_iter()
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    let length = if sizes.is_empty() {
        (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt() / 2.0
    } else {
        let mid = sizes.len() / 2;
        *sizes.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    if !(length.is_finite() && length > 0.0 && finite(&centre)) {
        return Scale::IDENTITY;
    }
    Scale { centre, length }
}

/// How precisely the file's geometry numbers are known: its `precision` key
/// ([`Mechanism::precision`]) when it has one, else the largest rounding uncertainty of a
/// written number. A number shown with 4 or more significant digits and d decimals is known
/// to ±0.5·10^−d (CAD exports round so); a shorter one (`2.5`, `0`, `1`) is taken as exact.
/// Numbers are judged by their shortest round-trip decimal form ([`rounding_of`]).
pub fn written_precision(m: &Mechanism) -> f64 {
    m.precision.unwrap_or_else(|| written(m, false))
}

/// [`written_precision`] of the direction numbers alone (axes, normals): a rounded direction
/// moves a joint's constraint rows by its error times the lever arm, a rounded point only by
/// its error, so the threshold weighs the two apart ([`file_threshold`]). The `precision`
/// key, like `--tolerance`, sets both.
pub fn written_direction_precision(m: &Mechanism) -> f64 {
    m.precision.unwrap_or_else(|| written(m, true))
}

pub(super) fn written(m: &Mechanism, directions_only: bool) -> f64 {
    // A number's digits are judged against the size of what it belongs to, not its own
    // magnitude: a coordinate against the model's largest coordinate, a direction's component
    // against the direction's largest. Float noise written where 0 is meant (`1.2246e-17` in
    // a model of size 1) carries digits far below double precision at that size: exact, not
    // a model "known to ±5e-22".
    let size = largest_coordinate(m);
    let mut worst: f64 = 0.0;
    let mut judge = |x: f64, reference: f64| {
        let r = rounding_of(x);
        if r > EXACT_BELOW * reference {
            worst = worst.max(r);
        }
    };
    for j in &m.joints {
        let g = &j.geometry;
        let second = g.second.iter().flat_map(|s| s.vectors());
        let fields = [
            ("origin", g.origin),
            ("origin2", g.origin2),
            ("axis", g.axis),
            ("axis2", g.axis2),
            ("normal", g.normal),
        ];
        for (name, v) in fields.into_iter().chain(second) {
            let Some(v) = v else { continue };
            let point = name.starts_with("origin");
            if directions_only && point {
                continue;
            }
            let reference = if point {
                size
            } else {
                v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
            };
            for x in v {
                judge(x, reference);
            }
        }
        if let Some(h) = g.pitch.filter(|_| !directions_only) {
            judge(h, size);
        }
    }
    worst
}

/// A number whose rounding is below this fraction of its reference size is exact: 15
/// significant digits at that size, as [`rounding_of`] takes a number of 15 digits or more.
const EXACT_BELOW: f64 = 5e-15;

/// The largest absolute coordinate of a joint point (and pitch), in file units: the size a
/// point's written digits are judged against.
fn largest_coordinate(m: &Mechanism) -> f64 {
    m.joints
        .iter()
        .flat_map(|j| {
            let g = &j.geometry;
            let second = g.second.as_ref().and_then(|s| s.origin);
            [g.origin, g.origin2, second]
                .into_iter()
                .flatten()
                .flatten()
                .chain(g.pitch)
        })
        .filter(|x| x.is_finite())
        .fold(0.0f64, |a, x| a.max(x.abs()))
}

/// The lever arm of the constraint rows at the dimensionless geometry `scale` gives: the
/// largest coordinate of a joint point about the centre, in characteristic lengths (the rows'
/// moments are taken about the centre).
pub(crate) fn lever(m: &Mechanism, scale: &Scale) -> f64 {
    m.joints
        .iter()
        .flat_map(|j| [j.geometry.origin, j.geometry.origin2])
        .flatten()
        .flat_map(|p| scale.point(p).into_iter())
        .filter(|x| x.is_finite())
        .fold(0.0f64, |a, x| a.max(x.abs()))
}

/// Factor of the precision-derived threshold: rounding a point by δ moves a joint's unit rows
/// by about δ, rounding a direction by δ_d with lever arms up to L by about δ_d·(1 + L), and an
/// exact zero singular value by about as much (the Bennett linkage rounded to 4 decimals:
/// 1.3e-5 for δ = 5e-5); twice that is the threshold, and a decision within a factor 100 of it
/// is flagged.
pub const FILE_TOL_FACTOR: f64 = 2.0;
