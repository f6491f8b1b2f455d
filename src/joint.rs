//! The joint (kinematic pair) catalogue: the 24 pair kinds of the MBSSA3D paper's Table 3.
//!
//! Table 3 has 25 rows; the first one is "not connected", which is not a joint.

use serde::{Deserialize, Serialize};
use std::fmt;

/// The motion space: B = 6 (spatial) or 3 (planar, spherical).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Space {
    /// Spatial motion, B = 6.
    #[default]
    Spatial,
    /// Planar motion, B = 3.
    Planar,
    /// Spherical motion about a fixed point, B = 3.
    Spherical,
}

impl Space {
    /// DOF of a free body in this space.
    pub fn b(self) -> u32 {
        match self {
            Space::Spatial => 6,
            Space::Planar | Space::Spherical => 3,
        }
    }

    /// The SG type suffix: `3D` for spatial, `2D` otherwise.
    pub fn suffix(self) -> &'static str {
        match self {
            Space::Spatial => "3D",
            Space::Planar | Space::Spherical => "2D",
        }
    }

    /// Lower-case name as written in files.
    pub fn name(self) -> &'static str {
        match self {
            Space::Spatial => "spatial",
            Space::Planar => "planar",
            Space::Spherical => "spherical",
        }
    }
}

/// A kinematic pair kind. The declaration order is the catalogue order used in SG type strings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum JointType {
    /// Revolute (hinge, pin).
    R,
    /// Prismatic (slider).
    P,
    /// Helical (screw).
    H,
    /// Penta-point contact.
    CPEP,
    /// Cylindrical.
    C,
    /// Slotted spherical.
    ER,
    /// Universal (cardan, Hooke).
    U,
    /// Cam, point-curve, curve-curve.
    L,
    /// Ordinary gear.
    EO,
    /// Epicyclic gear.
    EPI,
    /// Tetra-point contact.
    CTEP,
    /// Pure rolling.
    RP,
    /// Sliding rolling.
    RD,
    /// Spherical (ball).
    S,
    /// Planar.
    PL,
    /// Slotted cylindrical.
    CR,
    /// Tri-point contact.
    CTRP,
    /// Free planar body (fictitious 3-DOF pair).
    FP,
    /// Sphere-cylinder.
    SC,
    /// Plane-cylinder.
    PC,
    /// Bi-point contact.
    CBIP,
    /// Sphere-plane.
    SP,
    /// Sphere-sphere.
    SPSP,
    /// Free spatial body (fictitious 6-DOF pair).
    F,
}

/// Static facts about one joint kind.
#[derive(Clone, Copy, Debug)]
pub struct JointInfo {
    /// The kind.
    pub kind: JointType,
    /// Short code as in the paper (`R`, `CPEP`, ...).
    pub code: &'static str,
    /// Accepted long names (lower case; matched case-insensitively).
    pub names: &'static [&'static str],
    /// Grade k: relative DOF the joint allows.
    pub grade: u8,
    /// Valid in a planar mechanism (B = 3).
    pub planar: bool,
    /// Valid in a spherical mechanism (B = 3).
    pub spherical: bool,
    /// Geometry fields the geometric analyses need (empty: count only).
    pub geometry: &'static [&'static str],
}

use JointType::*;

const fn info(
    kind: JointType,
    code: &'static str,
    names: &'static [&'static str],
    grade: u8,
    planar: bool,
    spherical: bool,
    geometry: &'static [&'static str],
) -> JointInfo {
    JointInfo {
        kind,
        code,
        names,
        grade,
        planar,
        spherical,
        geometry,
    }
}

/// The catalogue, in the paper's order. Planar validity: lower pairs that keep motion in the
/// plane (R, P), the planar higher pairs (cam, gears, rolling) and the free planar body. In a
/// spherical mechanism every revolute axis passes through the centre, so R, the higher pairs
/// of spherical motion (cam, bevel gears, rolling) and FP (the free body of B = 3) make sense.
#[rustfmt::skip]
pub const CATALOGUE: [JointInfo; 24] = [
    info(R, "R", &["revolute", "hinge", "pin"], 1, true, true, &["origin", "axis"]),
    info(P, "P", &["prismatic", "slider"], 1, true, false, &["axis"]),
    info(H, "H", &["helical", "screw"], 1, false, false, &["origin", "axis", "pitch"]),
    info(CPEP, "CPEP", &["penta-point contact", "penta punctual contact"], 1, false, false, &[]),
    info(C, "C", &["cylindrical"], 2, false, false, &["origin", "axis"]),
    info(ER, "ER", &["slotted spherical"], 2, false, false, &["origin", "axis"]),
    info(U, "U", &["universal", "cardan", "hooke"], 2, false, false, &["origin", "axis", "axis2"]),
    info(L, "L", &["cam", "point-curve", "curve-curve"], 2, true, true, &[]),
    info(EO, "EO", &["ordinary gear", "gear"], 2, true, true, &[]),
    info(EPI, "EPI", &["epicyclic gear"], 2, true, true, &[]),
    info(CTEP, "CTEP", &["tetra-point contact", "tetra punctual contact"], 2, false, false, &[]),
    info(RP, "RP", &["pure rolling", "rolling"], 2, true, true, &[]),
    info(RD, "RD", &["sliding rolling"], 2, true, true, &[]),
    info(S, "S", &["spherical", "ball"], 3, false, false, &["origin"]),
    info(PL, "PL", &["planar", "e"], 3, false, false, &["normal"]),
    info(CR, "CR", &["slotted cylindrical"], 3, false, false, &["origin", "axis", "normal"]),
    info(CTRP, "CTRP", &["tri-point contact", "tri punctual contact"], 3, false, false, &[]),
    info(FP, "FP", &["free planar", "free planar body", "free body plane"], 3, true, true, &[]),
    info(SC, "SC", &["sphere-cylinder"], 4, false, false, &["origin", "axis"]),
    info(PC, "PC", &["plane-cylinder"], 4, false, false, &["origin", "axis", "normal"]),
    info(CBIP, "CBIP", &["bi-point contact", "bi punctual contact"], 4, false, false, &[]),
    info(SP, "SP", &["sphere-plane"], 5, false, false, &["origin", "normal"]),
    info(SPSP, "SPSP", &["sphere-sphere"], 5, false, false, &["origin", "origin2"]),
    info(F, "F", &["free", "free spatial", "free body", "free spatial body"], 6, false, false, &[]),
];

impl JointType {
    /// All kinds in catalogue order.
    pub fn all() -> impl Iterator<Item = JointType> {
        CATALOGUE.iter().map(|i| i.kind)
    }

    /// The catalogue entry.
    pub fn info(self) -> &'static JointInfo {
        &CATALOGUE[self as usize]
    }

    /// Short code (`R`, `CPEP`, ...).
    pub fn code(self) -> &'static str {
        self.info().code
    }

    /// Grade k: the relative DOF the joint allows.
    pub fn grade(self) -> u8 {
        self.info().grade
    }

    /// The order of the DOF that `driven` and input values name, in words (docs/format.md,
    /// "Which DOF `driven` means"); `None` for a kind of one DOF or without named DOF (a driven
    /// DOF of those fixes a generic combination of its motions).
    pub fn dof_order(self) -> Option<&'static str> {
        Some(match self {
            C => "the slide, then the turn",
            PL => "the two slides in the plane, then the turn about the normal",
            U => "the turn about `axis`, then about `axis2`",
            S => "the turns about the world x, y, z axes through the centre",
            F => "the translations along x, y, z, then the turns about x, y, z",
            FP => "the translations along x, y, then the turn",
            SP => "the two slides in the plane, then the turns about x, y, z through the centre",
            SC => "the slide along the axis, then the turns about x, y, z",
            PC => "the two slides, the turn about `normal`, the turn about `axis`",
            CR => "the slide along `axis`, the slide across the slot, the turn about `axis`",
            _ => return None,
        })
    }

    /// Position in the catalogue order (used to sort type strings).
    pub fn order(self) -> usize {
        self as usize
    }

    /// Whether the kind is valid in a mechanism whose body DOF is `b` (`planar` selects
    /// between the two B = 3 spaces).
    pub fn valid_in(self, space: Space) -> bool {
        match space {
            Space::Spatial => true,
            Space::Planar => self.info().planar,
            Space::Spherical => self.info().spherical,
        }
    }

    /// Parse a code or long name, case-insensitively (`R`, `revolute`, `Hinge`).
    pub fn parse(text: &str) -> Option<JointType> {
        let t = text.trim();
        let lower = t.to_ascii_lowercase();
        let norm = lower.replace(['_', ' '], "-");
        CATALOGUE
            .iter()
            .find(|i| {
                i.code.eq_ignore_ascii_case(t)
                    || i.names
                        .iter()
                        .any(|n| *n == lower || n.replace(' ', "-") == norm)
            })
            .map(|i| i.kind)
    }

    /// The accepted spelling closest to `text` (for "did you mean" hints), if any is close.
    pub fn suggest(text: &str) -> Option<&'static str> {
        let lower = text.trim().to_ascii_lowercase();
        let mut best: Option<(f64, &'static str)> = None;
        for i in CATALOGUE.iter() {
            let code_score = strsim::jaro_winkler(&lower, &i.code.to_ascii_lowercase());
            let mut consider = |score: f64| {
                if best.is_none_or(|(s, _)| score > s) {
                    best = Some((score, i.code));
                }
            };
            consider(code_score);
            for n in i.names {
                consider(strsim::jaro_winkler(&lower, n));
            }
        }
        best.filter(|(s, _)| *s >= 0.7).map(|(_, c)| c)
    }
}

impl fmt::Display for JointType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.code())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_is_in_declaration_order() {
        for (i, info) in CATALOGUE.iter().enumerate() {
            assert_eq!(info.kind as usize, i, "{}", info.code);
            assert_eq!(format!("{:?}", info.kind), info.code);
        }
    }

    #[test]
    fn grades_match_table_3() {
        let grades: Vec<u8> = CATALOGUE.iter().map(|i| i.grade).collect();
        assert_eq!(
            grades,
            [
                1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3, 4, 4, 4, 5, 5, 6
            ]
        );
    }

    #[test]
    fn parses_codes_and_names() {
        assert_eq!(JointType::parse("r"), Some(R));
        assert_eq!(JointType::parse("Revolute"), Some(R));
        assert_eq!(JointType::parse("cpep"), Some(CPEP));
        assert_eq!(JointType::parse("Sphere-Plane"), Some(SP));
        assert_eq!(JointType::parse("slotted spherical"), Some(ER));
        assert_eq!(JointType::parse("slotted_spherical"), Some(ER));
        assert_eq!(JointType::parse("ball"), Some(S));
        assert_eq!(JointType::parse("xyz"), None);
    }

    #[test]
    fn suggests_nearest() {
        assert_eq!(JointType::suggest("revolut"), Some("R"));
        assert_eq!(JointType::suggest("sphercal"), Some("S"));
        assert_eq!(JointType::suggest("qqqqqqqq"), None);
    }
}
