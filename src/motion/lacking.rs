//! The joints that lack the geometry their kind's model needs.

use super::modelled;
use crate::joint::JointType;
use crate::mechanism::{Mechanism, Space};

/// A joint without the geometry its kind needs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Lacking {
    /// Joint id.
    pub joint: String,
    /// Its kind's code.
    pub kind: &'static str,
    /// The missing fields (empty when the kind has no geometric model at all).
    pub fields: Vec<&'static str>,
    /// The kind has no geometric model in this space (cams, gears, rolling, point contacts).
    pub no_model: bool,
}

impl Lacking {
    /// `A (S: origin)` or `G (EO: no geometric model)`.
    pub fn describe(&self) -> String {
        if self.no_model {
            format!("{} ({}: no geometric model)", self.joint, self.kind)
        } else {
            format!("{} ({}: {})", self.joint, self.kind, self.fields.join(", "))
        }
    }
}

/// The joints that lack geometry fields their kind needs, and those whose kind has no
/// geometric model: a mechanism has its geometry only when this is empty.
pub fn lacking(m: &Mechanism) -> Vec<Lacking> {
    m.joints.iter().filter_map(|j| lacking_of(m, j)).collect()
}

/// Whether joint `j` of `m` lacks the geometry field `f` (a name from its kind's list).
pub(super) fn field_missing(m: &Mechanism, j: &crate::mechanism::Joint, f: &str) -> bool {
    let g = &j.geometry;
    match f {
        "origin" => g.origin.is_none() && m.space != Space::Spherical,
        "origin2" => g.origin2.is_none(),
        "axis" => g.axis.is_none() && !(m.space == Space::Planar && j.kind == JointType::R),
        "axis2" => g.axis2.is_none(),
        "normal" => g.normal.is_none(),
        "pitch" => g.pitch.is_none(),
        _ => false,
    }
}

/// Whether joint `j` would be listed by [`lacking`] (without building its entry).
pub(crate) fn lacks(m: &Mechanism, j: &crate::mechanism::Joint) -> bool {
    (!modelled(j.kind, m.space) && j.kind != JointType::FP)
        || j.kind
            .info()
            .geometry
            .iter()
            .any(|f| field_missing(m, j, f))
}

/// Joint `j`'s entry of [`lacking`], if it has one.
pub(crate) fn lacking_of(m: &Mechanism, j: &crate::mechanism::Joint) -> Option<Lacking> {
    let fields: Vec<&'static str> = j
        .kind
        .info()
        .geometry
        .iter()
        .copied()
        .filter(|f| field_missing(m, j, f))
        .collect();
    let no_model = !modelled(j.kind, m.space) && j.kind != JointType::FP;
    (no_model || !fields.is_empty()).then(|| Lacking {
        joint: j.id.clone(),
        kind: j.kind.code(),
        fields,
        no_model,
    })
}

/// Whether every joint has the geometry fields its kind needs ([`lacking`] is empty).
pub fn has_geometry(m: &Mechanism) -> bool {
    // No list built: a mechanism without geometry lacks it at every joint.
    !m.joints.iter().any(|j| lacks(m, j))
}
