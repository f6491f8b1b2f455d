//! The validated mechanism model every analysis works from.
//!
//! Bodies are stored sorted by id (numbers first, numerically; then names) and joints sorted by
//! id in natural order, so analyses and reports do not depend on the order of declarations in
//! the file.

use crate::joint::JointType;
pub use crate::joint::Space;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::fmt;
use std::fmt::Write as _;

/// A body id as written in the file: an integer or a string.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(untagged)]
pub enum BodyId {
    /// An integer id (`1`, `13`).
    Int(i64),
    /// A string id (`"crank"`).
    Name(String),
}

impl Ord for BodyId {
    fn cmp(&self, other: &Self) -> Ordering {
        match (self, other) {
            (BodyId::Int(a), BodyId::Int(b)) => a.cmp(b),
            (BodyId::Int(_), BodyId::Name(_)) => Ordering::Less,
            (BodyId::Name(_), BodyId::Int(_)) => Ordering::Greater,
            (BodyId::Name(a), BodyId::Name(b)) => a.cmp(b),
        }
    }
}

impl PartialOrd for BodyId {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl fmt::Display for BodyId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BodyId::Int(i) => write!(f, "{i}"),
            BodyId::Name(s) => f.write_str(s),
        }
    }
}

impl BodyId {
    /// Parse a body reference written on the command line: an integer if it is one.
    pub fn from_text(text: &str) -> BodyId {
        match text.parse::<i64>() {
            Ok(i) => BodyId::Int(i),
            Err(_) => BodyId::Name(text.to_string()),
        }
    }
}

/// A body of the mechanism.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Body {
    /// Its id.
    pub id: BodyId,
    /// Optional display label.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
}

/// Optional joint geometry in the reference configuration. Planar points are stored with z = 0.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Geometry {
    /// A point of the joint.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// Joint axis (R, P, H, C, ER, first axis of U).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// Second axis of a universal joint.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis2: Option<[f64; 3]>,
    /// Second point: the centre on the second body of a sphere-sphere (SPSP) contact.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin2: Option<[f64; 3]>,
    /// Plane normal of a planar joint.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    /// Helical lead per radian.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch: Option<f64>,
    /// The joint as carried by the second body, when the file's configuration is not closed
    /// (`None`: the same as the first body's, closed). Boxed: rare, and `Geometry` is cloned
    /// per joint.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub second: Option<Box<Second>>,
}

/// The features of a joint as carried by its second body at a configuration that is not
/// closed (`docs/format.md`, "Open configurations"). A field left out is the same as the
/// joint's own (the first body's); which fields a kind accepts: [`Second::fields`].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Second {
    /// The joint point on the second body.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// The joint axis on the second body (R, P, H, C, ER, PC, CR; planar P; spherical R).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// The second axis of a universal joint (the one fixed in the second body).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis2: Option<[f64; 3]>,
    /// The plane normal on the second body (PL, FP in space).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
}

impl Second {
    /// The fields of `second` a binary joint of `kind` accepts in `space`: the features its
    /// second body carries (empty: `second` makes no sense for this kind).
    pub fn fields(kind: JointType, space: Space) -> &'static [&'static str] {
        use JointType::*;
        match space {
            Space::Spatial => match kind {
                R | P | H | C | ER | PC | CR => &["origin", "axis"],
                U => &["origin", "axis2"],
                S | SC | SP => &["origin"],
                PL | FP => &["origin", "normal"],
                _ => &[],
            },
            Space::Planar => match kind {
                R => &["origin"],
                P => &["origin", "axis"],
                _ => &[],
            },
            Space::Spherical => match kind {
                R => &["axis"],
                _ => &[],
            },
        }
    }

    /// Every vector set, with its field name.
    pub fn vectors(&self) -> [(&'static str, Option<[f64; 3]>); 4] {
        [
            ("origin", self.origin),
            ("axis", self.axis),
            ("axis2", self.axis2),
            ("normal", self.normal),
        ]
    }
}

impl Geometry {
    /// Whether no geometry field is set.
    pub fn is_empty(&self) -> bool {
        self == &Geometry::default()
    }
}

/// A joint (kinematic pair). `bodies` are indices into [`Mechanism::bodies`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Joint {
    /// Unique id (default `"<a>-<b>"`).
    pub id: String,
    /// Pair kind.
    pub kind: JointType,
    /// Indices of the joined bodies (>= 2; more = multiple joint, hub first). Read as a
    /// slice (`Deref<Target = [usize]>`).
    pub bodies: JointBodies,
    /// Driven DOF on this joint (0..=grade).
    pub driven: u32,
    /// Optional geometry (read through `Deref` as a [`Geometry`]; boxed only when set).
    pub geometry: JointGeometry,
}

/// The bodies of a joint: two held inline (no allocation for a binary joint), more in a
/// vector. Read as a slice through `Deref`; built from a `Vec<usize>` or an iterator.
#[derive(Clone)]
pub struct JointBodies(BodiesRepr);

#[derive(Clone)]
enum BodiesRepr {
    Two([usize; 2]),
    Many(Vec<usize>),
}

impl From<Vec<usize>> for JointBodies {
    fn from(v: Vec<usize>) -> JointBodies {
        match *v.as_slice() {
            [a, b] => JointBodies(BodiesRepr::Two([a, b])),
            _ => JointBodies(BodiesRepr::Many(v)),
        }
    }
}

impl From<&[usize]> for JointBodies {
    fn from(s: &[usize]) -> JointBodies {
        match *s {
            [a, b] => JointBodies(BodiesRepr::Two([a, b])),
            _ => JointBodies(BodiesRepr::Many(s.to_vec())),
        }
    }
}

impl From<[usize; 2]> for JointBodies {
    fn from(two: [usize; 2]) -> JointBodies {
        JointBodies(BodiesRepr::Two(two))
    }
}

impl FromIterator<usize> for JointBodies {
    fn from_iter<I: IntoIterator<Item = usize>>(iter: I) -> JointBodies {
        let mut it = iter.into_iter();
        match (it.next(), it.next(), it.next()) {
            (Some(a), Some(b), None) => JointBodies(BodiesRepr::Two([a, b])),
            (a, b, c) => {
                let mut v: Vec<usize> = a.into_iter().chain(b).chain(c).collect();
                v.extend(it);
                JointBodies(BodiesRepr::Many(v))
            }
        }
    }
}

impl std::ops::Deref for JointBodies {
    type Target = [usize];
    fn deref(&self) -> &[usize] {
        match &self.0 {
            BodiesRepr::Two(two) => two,
            BodiesRepr::Many(v) => v,
        }
    }
}

impl std::ops::DerefMut for JointBodies {
    fn deref_mut(&mut self) -> &mut [usize] {
        match &mut self.0 {
            BodiesRepr::Two(two) => two,
            BodiesRepr::Many(v) => v,
        }
    }
}

impl<'a> IntoIterator for &'a JointBodies {
    type Item = &'a usize;
    type IntoIter = std::slice::Iter<'a, usize>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl<'a> IntoIterator for &'a mut JointBodies {
    type Item = &'a mut usize;
    type IntoIter = std::slice::IterMut<'a, usize>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter_mut()
    }
}

impl IntoIterator for JointBodies {
    type Item = usize;
    type IntoIter = std::iter::Chain<
        std::iter::Take<std::array::IntoIter<usize, 2>>,
        std::vec::IntoIter<usize>,
    >;
    fn into_iter(self) -> Self::IntoIter {
        match self.0 {
            BodiesRepr::Two(two) => two.into_iter().take(2).chain(Vec::new()),
            BodiesRepr::Many(v) => [0, 0].into_iter().take(0).chain(v),
        }
    }
}

impl PartialEq for JointBodies {
    fn eq(&self, other: &JointBodies) -> bool {
        **self == **other
    }
}

impl PartialEq<Vec<usize>> for JointBodies {
    fn eq(&self, other: &Vec<usize>) -> bool {
        **self == **other
    }
}

impl fmt::Debug for JointBodies {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        <[usize]>::fmt(self, f)
    }
}

impl Serialize for JointBodies {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        <[usize]>::serialize(self, s)
    }
}

/// A joint's [`Geometry`], boxed only when some field is set: most large files give none, and
/// an inline `Geometry` (184 bytes) was three quarters of every `Joint`. Reads go through
/// `Deref` (`joint.geometry.origin`); a write through `DerefMut` boxes it first.
#[derive(Clone, Default)]
pub struct JointGeometry(Option<Box<Geometry>>);

/// The geometry of a joint that has none.
static NO_GEOMETRY: Geometry = Geometry {
    origin: None,
    axis: None,
    axis2: None,
    origin2: None,
    normal: None,
    pitch: None,
    second: None,
};

impl JointGeometry {
    /// The geometry as a plain value (a copy).
    pub fn to_geometry(&self) -> Geometry {
        Geometry::clone(self)
    }
}

impl From<Geometry> for JointGeometry {
    fn from(g: Geometry) -> JointGeometry {
        if g.is_empty() {
            JointGeometry(None)
        } else {
            JointGeometry(Some(Box::new(g)))
        }
    }
}

impl std::ops::Deref for JointGeometry {
    type Target = Geometry;
    fn deref(&self) -> &Geometry {
        self.0.as_deref().unwrap_or(&NO_GEOMETRY)
    }
}

impl std::ops::DerefMut for JointGeometry {
    fn deref_mut(&mut self) -> &mut Geometry {
        self.0.get_or_insert_with(Box::default)
    }
}

impl PartialEq for JointGeometry {
    fn eq(&self, other: &JointGeometry) -> bool {
        **self == **other
    }
}

impl PartialEq<Geometry> for JointGeometry {
    fn eq(&self, other: &Geometry) -> bool {
        **self == *other
    }
}

impl fmt::Debug for JointGeometry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Geometry::fmt(self, f)
    }
}

impl Serialize for JointGeometry {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        Geometry::serialize(self, s)
    }
}

impl Joint {
    /// Number of binary pairs this joint counts as (n - 1 for n bodies).
    pub fn pairs(&self) -> u32 {
        (self.bodies.len() as u32).saturating_sub(1)
    }

    /// Grade k of each binary pair.
    pub fn grade(&self) -> u32 {
        self.kind.grade() as u32
    }
}

/// Expectations written in the file's `[expect]` table, compared by `mbsa check`.
/// Every field is optional; only the ones present are checked.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Expect {
    /// Chebyshev-Gruebler-Kutzbach mobility count.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mobility: Option<i64>,
    /// Total driven inputs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inputs: Option<u64>,
    /// Number of structural groups.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<u64>,
    /// Number of solve levels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub levels: Option<u64>,
    /// Whether the mechanism is kinematically determined.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub determined: Option<bool>,
    /// Generic DOF by the pebble game (frame fixed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generic_dof: Option<i64>,
    /// True (instantaneous) mobility: frame fixed, driven inputs not counted (as `mbsa rigid`
    /// prints it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub true_mobility: Option<i64>,
    /// DOF the driven inputs leave free (as `mbsa analyze` reports it; 0 when determined).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncontrolled: Option<u64>,
    /// Isolated DOF.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub isolated: Option<u64>,
    /// Redundant constraints (overconstraint N).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub redundant: Option<u64>,
    /// Number of rigid parts (clusters with more than one body, or containing the frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid_parts: Option<u64>,
    /// Whether the file has an `[expect]` table at all (an empty one checks nothing, and
    /// `mbsa check` says so).
    #[serde(skip)]
    pub written: bool,
}

/// Compare joint ids in natural order (`1-2` < `1-10` < `13-9`, `A` < `B`): digit runs compare
/// as numbers, the rest as text.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    cmp_chunks(natural_chunks(a), natural_chunks(b)).then_with(|| a.cmp(b))
}

/// The digit runs and other runs of `s`, in order (`true` for digits).
fn natural_chunks(s: &str) -> impl Iterator<Item = (bool, &str)> {
    let mut rest = s;
    std::iter::from_fn(move || {
        let first = rest.chars().next()?;
        let digit = first.is_ascii_digit();
        let end = rest
            .find(|c: char| c.is_ascii_digit() != digit)
            .unwrap_or(rest.len());
        let (head, tail) = rest.split_at(end);
        rest = tail;
        Some((digit, head))
    })
}

/// [`natural_cmp`] on chunk sequences, before its tie-break on the whole text.
fn cmp_chunks<'a>(
    mut x: impl Iterator<Item = (bool, &'a str)>,
    mut y: impl Iterator<Item = (bool, &'a str)>,
) -> Ordering {
    loop {
        match (x.next(), y.next()) {
            (None, None) => return Ordering::Equal,
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some((dx, cx)), Some((dy, cy))) => {
                let o = if dx && dy {
                    let (tx, ty) = (cx.trim_start_matches('0'), cy.trim_start_matches('0'));
                    tx.len().cmp(&ty.len()).then_with(|| tx.cmp(ty))
                } else {
                    cx.cmp(cy)
                };
                if o != Ordering::Equal {
                    return o;
                }
            }
        }
    }
}

/// A validated mechanism.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Mechanism {
    /// Display name.
    pub name: String,
    /// Free text.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Motion space.
    pub space: Space,
    /// Index of the frame in `bodies`.
    pub frame: usize,
    /// Bodies sorted by id.
    pub bodies: Vec<Body>,
    /// Joints sorted by id in natural order ([`natural_cmp`]), so that no analysis or report
    /// depends on the order in which the file lists them.
    pub joints: Vec<Joint>,
    /// Expectations for `mbsa check`.
    pub expect: Expect,
    /// How precisely every geometry number of the file is known (±, file units): the file's
    /// `precision` key, which `mbsa import` writes from the source's digits. `None`: each
    /// number is judged by its written digits ([`crate::motion::written_precision`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub precision: Option<f64>,
}

impl Mechanism {
    /// B: DOF of a free body.
    pub fn b(&self) -> u32 {
        self.space.b()
    }

    /// Whether joint `j` is a free joint to the frame (a floating base): binary, the frame one
    /// of its bodies, removing no freedom (F in space; FP in a planar or spherical mechanism).
    pub fn free_to_frame(&self, j: usize) -> bool {
        let joint = &self.joints[j];
        joint.bodies.len() == 2 && joint.bodies.contains(&self.frame) && joint.grade() == self.b()
    }

    /// The id of body `i`.
    pub fn body_id(&self, i: usize) -> &BodyId {
        &self.bodies[i].id
    }

    /// Index of a body by id.
    pub fn body_index(&self, id: &BodyId) -> Option<usize> {
        self.bodies.binary_search_by(|b| b.id.cmp(id)).ok()
    }

    /// Number of movable bodies (all but the frame).
    pub fn movable(&self) -> usize {
        self.bodies.len().saturating_sub(1)
    }

    /// Total driven DOF.
    pub fn inputs(&self) -> u64 {
        self.joints.iter().map(|j| j.driven as u64).sum()
    }

    /// `a-b` label of a joint's bodies (all of them for a multiple joint).
    pub fn joint_bodies_label(&self, j: &Joint) -> String {
        j.bodies
            .iter()
            .map(|&b| self.body_id(b).to_string())
            .collect::<Vec<_>>()
            .join("-")
    }

    /// Replace every joint's driven DOF by the placement `spec`.
    pub fn apply_inputs(&mut self, spec: &InputSpec) -> Result<(), InputSpecError> {
        let resolved = spec.resolve(self)?;
        // Summed in 64 bits: `A:4294967295,A:2` must not wrap a u32 to 1.
        let mut driven = vec![0u64; self.joints.len()];
        for (j, n) in resolved {
            driven[j] = driven[j].saturating_add(u64::from(n));
        }
        for (j, &d) in self.joints.iter().zip(&driven) {
            let max = j.grade().saturating_mul(j.pairs());
            if d > u64::from(max) {
                return Err(InputSpecError::AboveGrade {
                    joint: j.id.clone(),
                    driven: d,
                    grade: max,
                });
            }
        }
        for (j, d) in self.joints.iter_mut().zip(driven) {
            // At most the grade times the pairs (checked above), so it fits.
            j.driven = u32::try_from(d).unwrap_or(u32::MAX);
        }
        Ok(())
    }
}

/// A joint described by body ids, for building mechanisms in code (tests, generators).
#[derive(Clone, Debug, PartialEq)]
pub struct JointSpec {
    /// Id; `None` gives the default `"<a>-<b>"` (suffixed `#2`, `#3`... if repeated).
    pub id: Option<String>,
    /// Pair kind.
    pub kind: JointType,
    /// Joined bodies.
    pub bodies: Vec<BodyId>,
    /// Driven DOF.
    pub driven: u32,
    /// Geometry.
    pub geometry: Geometry,
}

impl JointSpec {
    /// A binary joint between integer bodies, no geometry.
    pub fn new(kind: JointType, a: i64, b: i64, driven: u32) -> JointSpec {
        JointSpec {
            id: None,
            kind,
            bodies: vec![BodyId::Int(a), BodyId::Int(b)],
            driven,
            geometry: Geometry::default(),
        }
    }
}

impl Mechanism {
    /// Build a mechanism from joints given by body ids. Bodies are the frame, the declared
    /// `extra_bodies` and every body a joint names. No validation beyond that: callers that
    /// take user input validate first (the reader does).
    pub fn from_parts(
        name: impl Into<String>,
        space: Space,
        frame: BodyId,
        extra_bodies: Vec<Body>,
        joints: Vec<JointSpec>,
    ) -> Mechanism {
        // Every body once, sorted by id: the declared ones keep their labels.
        let mut extra_bodies = extra_bodies;
        extra_bodies.sort_by(|a, b| a.id.cmp(&b.id));
        extra_bodies.dedup_by(|b, a| a.id == b.id);
        let mut ids: Vec<&BodyId> = std::iter::once(&frame)
            .chain(joints.iter().flat_map(|j| j.bodies.iter()))
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let mut bodies: Vec<Body> = Vec::with_capacity(ids.len() + extra_bodies.len());
        let mut declared = extra_bodies.into_iter().peekable();
        for id in ids {
            while let Some(d) = declared.next_if(|d| d.id < *id) {
                bodies.push(d);
            }
            match declared.next_if(|d| d.id == *id) {
                Some(d) => bodies.push(d),
                None => bodies.push(Body {
                    id: id.clone(),
                    label: None,
                }),
            }
        }
        bodies.extend(declared);
        let index = |id: &BodyId| {
            bodies
                .binary_search_by(|b| b.id.cmp(id))
                .expect("every joint body was inserted above")
        };
        let frame = index(&frame);
        let joints: Vec<Joint> = joints
            .into_iter()
            .map(|j| Joint {
                id: j.id.unwrap_or_else(|| {
                    let mut id = String::new();
                    for (i, b) in j.bodies.iter().enumerate() {
                        let sep = if i == 0 { "" } else { "-" };
                        // Writing into a String cannot fail.
                        let _ = write!(id, "{sep}{b}");
                    }
                    id
                }),
                kind: j.kind,
                bodies: j.bodies.iter().map(index).collect(),
                driven: j.driven,
                geometry: j.geometry.into(),
            })
            .collect();
        Mechanism::from_indexed(name, space, frame, bodies, joints)
    }

    /// The last step of [`Mechanism::from_parts`], for callers that index the bodies
    /// themselves: `bodies` sorted by id, `frame` and the joints' bodies indices into it. The
    /// joints are put in natural order of their ids; the n-th joint (in given order) with an
    /// id already used gets `id#n`.
    pub(crate) fn from_indexed(
        name: impl Into<String>,
        space: Space,
        frame: usize,
        bodies: Vec<Body>,
        mut joints: Vec<Joint>,
    ) -> Mechanism {
        // Natural order by id; the n-th joint (in given order) with an id already used gets
        // `id#n`. Equal ids stay in given order next to each other.
        let order = natural_order(&joints);
        // A suffixed id may be another joint's own id (the second `[1, 2]` and a `[1, "2#2"]`
        // both give `1-2#2`): the suffix then skips to the next free number, so that ids stay
        // unique (the reader reports that case as an error before calling this).
        let mut renamed = false;
        let mut used: Option<std::collections::HashSet<String>> = None;
        let mut k = 0;
        while k < order.len() {
            let mut n = 1;
            let mut suffix = 1;
            while k + n < order.len() && joints[order[k + n]].id == joints[order[k]].id {
                let used =
                    used.get_or_insert_with(|| joints.iter().map(|j| j.id.clone()).collect());
                let j = &mut joints[order[k + n]];
                n += 1;
                suffix = suffix.max(n);
                let mut id = format!("{}#{suffix}", j.id);
                while used.contains(&id) {
                    suffix += 1;
                    id = format!("{}#{suffix}", j.id);
                }
                used.insert(id.clone());
                j.id = id;
                renamed = true;
            }
            k += n;
        }
        // In place (a second vector of joints would double the largest allocation).
        permute(&mut joints, order);
        if renamed {
            joints.sort_by(|a, b| natural_cmp(&a.id, &b.id));
        }
        Mechanism {
            name: name.into(),
            description: None,
            space,
            frame,
            bodies,
            joints,
            expect: Expect::default(),
            precision: None,
        }
    }
}

impl Mechanism {
    /// [`Mechanism::from_indexed`] for joints whose ids are distinct and whose natural order
    /// the caller knows already: `order[k]` is the position of the k-th joint in that order.
    pub(crate) fn from_indexed_in_order(
        name: impl Into<String>,
        space: Space,
        frame: usize,
        bodies: Vec<Body>,
        mut joints: Vec<Joint>,
        order: Vec<u32>,
    ) -> Mechanism {
        debug_assert_eq!(order.len(), joints.len());
        permute(&mut joints, order.into_iter().map(|k| k as usize).collect());
        Mechanism {
            name: name.into(),
            description: None,
            space,
            frame,
            bodies,
            joints,
            expect: Expect::default(),
            precision: None,
        }
    }
}

/// Rearrange `v` so that its k-th item is the `order[k]`-th before (`order` a permutation),
/// by following the cycles of `order` with swaps: no second vector.
fn permute<T>(v: &mut [T], mut order: Vec<usize>) {
    const DONE: usize = usize::MAX;
    for i in 0..order.len() {
        let mut j = i;
        while order[j] != DONE {
            let next = order[j];
            order[j] = DONE;
            if next == i {
                break;
            }
            v.swap(j, next);
            j = next;
        }
    }
}

/// The joints' positions sorted by [`natural_cmp`] of their ids, equal ids in given order.
fn natural_order(joints: &[Joint]) -> Vec<usize> {
    // Fast path: ids made of numbers without leading zeros joined by `-` or `#` (`12-5`,
    // `3-4#2`), the default ids of integer bodies. Their natural order is the order of the
    // token sequences (numbers by value, separators by character, a prefix first), and equal
    // sequences are equal texts. At most five tokens (`a-b#n`): a packed key sorted in place,
    // the first number, then each separator with the number after it (the separator's rank
    // above the number: 0 none, 1 `#`, 2 `-`, as `#` < `-`; so a shorter sequence padded with
    // zeros still sorts first).
    let mut buf: Vec<u64> = Vec::with_capacity(8);
    let mut keyed: Vec<([u64; 3], u32)> = Vec::with_capacity(joints.len());
    let short = joints.len() <= u32::MAX as usize
        && joints
            .iter()
            .enumerate()
            .all(|(k, j)| match short_natural_key(&j.id, &mut buf) {
                Some(key) => {
                    keyed.push((key, k as u32));
                    true
                }
                None => false,
            });
    if short {
        keyed.sort_unstable();
        return keyed.into_iter().map(|(_, k)| k as usize).collect();
    }
    drop(keyed);
    let mut order: Vec<usize> = (0..joints.len()).collect();
    // Longer sequences: compared as slices of one flat array, no allocation per joint.
    let mut tokens: Vec<u64> = Vec::with_capacity(3 * joints.len());
    let mut ranges: Vec<(u32, u32)> = Vec::with_capacity(joints.len());
    let simple = joints.iter().all(|j| {
        let start = tokens.len();
        let ok = numeric_tokens(&j.id, &mut tokens);
        ranges.push((start as u32, tokens.len() as u32));
        ok && tokens.len() <= u32::MAX as usize
    });
    if simple {
        let key = |i: usize| &tokens[ranges[i].0 as usize..ranges[i].1 as usize];
        order.sort_unstable_by(|&a, &b| key(a).cmp(key(b)).then(a.cmp(&b)));
        return order;
    }
    drop(tokens);
    // Each id split into chunks once, not at every comparison.
    let keys: Vec<Vec<(bool, &str)>> = joints
        .iter()
        .map(|j| natural_chunks(&j.id).collect())
        .collect();
    order.sort_by(|&a, &b| {
        cmp_chunks(keys[a].iter().copied(), keys[b].iter().copied())
            .then_with(|| joints[a].id.cmp(&joints[b].id))
    });
    order
}

/// The packed natural-order key of an id of at most five numeric tokens (`a`, `a-b`,
/// `a-b#n`, ...: see [`natural_order`]): the first number, then each separator's rank (0 none,
/// 1 `#`, 2 `-`) above the number after it. Keys compare as the ids' natural order; `None`
/// for other ids (and numbers from 2^56 after a separator). `buf` is scratch.
pub(crate) fn short_natural_key(id: &str, buf: &mut Vec<u64>) -> Option<[u64; 3]> {
    buf.clear();
    if !numeric_tokens(id, buf) || buf.len() > 5 {
        return None;
    }
    let mut key = [buf[0], 0, 0];
    for (slot, pair) in key[1..].iter_mut().zip(buf[1..].chunks_exact(2)) {
        let rank = if pair[0] == u64::from(b'#') { 1 } else { 2 };
        if pair[1] >= 1 << 56 {
            return None;
        }
        *slot = (rank << 56) | pair[1];
    }
    Some(key)
}

/// Append the tokens of `id` (numbers, separators as their byte) when it is numbers without
/// leading zeros (at most 18 digits) joined by single `-` or `#`; `false` otherwise.
fn numeric_tokens(id: &str, out: &mut Vec<u64>) -> bool {
    let bytes = id.as_bytes();
    let mut i = 0;
    loop {
        let start = i;
        let mut n: u64 = 0;
        while let Some(&b) = bytes.get(i)
            && b.is_ascii_digit()
        {
            n = n.wrapping_mul(10).wrapping_add(u64::from(b - b'0')); // more than 18 digits is refused below
            i += 1;
        }
        let len = i - start;
        if len == 0 || len > 18 || (len > 1 && bytes[start] == b'0') {
            return false;
        }
        out.push(n);
        match bytes.get(i) {
            None => return true,
            Some(&c @ (b'-' | b'#')) => {
                out.push(u64::from(c));
                i += 1;
            }
            Some(_) => return false,
        }
    }
}

/// One entry of an `--inputs` spec: a joint id or a body pair `a-b`, with a DOF count.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputRef {
    /// The reference as written (`A`, `1-13`).
    pub text: String,
    /// Driven DOF (`:n`, default 1).
    pub count: u32,
}

/// A placement of driven inputs: `1-2,1-13,13-15` or `A,K:2`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct InputSpec {
    /// The entries in order.
    pub refs: Vec<InputRef>,
}

/// Errors in an `--inputs` spec.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum InputSpecError {
    /// Bad syntax.
    #[error("invalid input spec `{text}`: {reason}")]
    Syntax {
        /// The offending entry.
        text: String,
        /// Why.
        reason: String,
    },
    /// The reference matches no joint.
    #[error("input `{text}` matches no joint{}", hint.as_ref().map(|h| format!(" (did you mean `{h}`?)")).unwrap_or_default())]
    NoMatch {
        /// The reference.
        text: String,
        /// Nearest joint id or pair.
        hint: Option<String>,
    },
    /// A body pair matches several joints.
    #[error("input `{text}` matches several joints: {}; name one by its id", joints.join(", "))]
    Ambiguous {
        /// The reference.
        text: String,
        /// Ids of the matching joints.
        joints: Vec<String>,
    },
    /// More driven DOF than the joint allows.
    #[error("joint `{joint}` would have {driven} driven DOF but allows at most {grade}")]
    AboveGrade {
        /// Joint id.
        joint: String,
        /// Requested driven DOF (the sum of the spec's entries for this joint).
        driven: u64,
        /// Its grade.
        grade: u32,
    },
}

impl InputSpec {
    /// Parse `ref[:n],ref[:n],...`. An empty string is the empty placement.
    pub fn parse(text: &str) -> Result<InputSpec, InputSpecError> {
        Self::parse_with(text, |_| false)
    }

    /// [`InputSpec::parse`] against the mechanism the spec is for: an entry whose text after
    /// its last `:` is not a number but which as a whole names a joint (an id or a body pair)
    /// is that joint with 1 DOF. Imported models have such ids (`connect:a-b`, `point:a-b`,
    /// `base:free`), and the reports print them as they are; `connect:a-b:2` still reads as
    /// 2 DOF.
    pub fn parse_in(text: &str, m: &Mechanism) -> Result<InputSpec, InputSpecError> {
        Self::parse_with(text, |whole| {
            !matches!(resolve_ref(m, whole), Err(InputSpecError::NoMatch { .. }))
        })
    }

    /// The parser; `names_joint(entry)` says whether a whole entry names a joint.
    fn parse_with(
        text: &str,
        names_joint: impl Fn(&str) -> bool,
    ) -> Result<InputSpec, InputSpecError> {
        let mut refs = Vec::new();
        for part in text.split(',').map(str::trim) {
            if part.is_empty() {
                if text.trim().is_empty() {
                    continue;
                }
                return Err(InputSpecError::Syntax {
                    text: text.to_string(),
                    reason: "empty entry between commas".into(),
                });
            }
            let (name, count) = match part.rsplit_once(':') {
                Some((name, n)) => match n.trim().parse::<u32>() {
                    Ok(count) => (name.trim(), count),
                    Err(_) if names_joint(part) => (part, 1),
                    Err(_) => {
                        return Err(InputSpecError::Syntax {
                            text: part.to_string(),
                            reason: format!("`{n}` is not a non-negative whole number of DOF"),
                        });
                    }
                },
                None => (part, 1),
            };
            if name.is_empty() {
                return Err(InputSpecError::Syntax {
                    text: part.to_string(),
                    reason: "missing joint id or body pair before `:`".into(),
                });
            }
            refs.push(InputRef {
                text: name.to_string(),
                count,
            });
        }
        Ok(InputSpec { refs })
    }

    /// Resolve every entry to a joint index. A joint id wins over a body pair.
    pub fn resolve(&self, m: &Mechanism) -> Result<Vec<(usize, u32)>, InputSpecError> {
        self.refs
            .iter()
            .map(|r| resolve_ref(m, &r.text).map(|j| (j, r.count)))
            .collect()
    }
}

/// Find the joint a reference names: its id, or the body pair `a-b` (either order).
pub fn resolve_ref(m: &Mechanism, text: &str) -> Result<usize, InputSpecError> {
    if let Some(j) = m.joints.iter().position(|j| j.id == text) {
        return Ok(j);
    }
    let mut matches = Vec::new();
    if let Some(pair) = split_pair(m, text) {
        for (ji, j) in m.joints.iter().enumerate() {
            if j.bodies.contains(&pair.0) && j.bodies.contains(&pair.1) {
                matches.push(ji);
            }
        }
    }
    match matches.len() {
        1 => Ok(matches[0]),
        0 => Err(InputSpecError::NoMatch {
            text: text.to_string(),
            hint: colon_hint(m, text).or_else(|| nearest_id(m, text)),
        }),
        _ => Err(InputSpecError::Ambiguous {
            text: text.to_string(),
            joints: matches.iter().map(|&j| m.joints[j].id.clone()).collect(),
        }),
    }
}

/// The joints an imported id names in part: `text` before the `:` of several (an OpenSim
/// CustomJoint imported as a chain: `ground_pelvis` for `ground_pelvis:pelvis_tx`, ...; the
/// first 8) or after the `:` of one (its coordinate, `pelvis_tilt`), as a hint quoted apart.
fn colon_hint(m: &Mechanism, text: &str) -> Option<String> {
    let named = |f: &dyn Fn(&str, &str) -> bool| -> Vec<&str> {
        m.joints
            .iter()
            .filter(|j| j.id.rsplit_once(':').is_some_and(|(a, b)| f(a, b)))
            .map(|j| j.id.as_str())
            .collect()
    };
    let after = named(&|_, b| b == text);
    if after.len() == 1 {
        return Some(after[0].to_string());
    }
    let before = named(&|a, _| a == text);
    if before.is_empty() {
        return None;
    }
    let shown: Vec<&str> = before.iter().take(8).copied().collect();
    Some(shown.join("`, `"))
}

/// The joint id or body pair nearest `text`, by Jaro-Winkler (a shared start weighs most) and
/// by shared letter pairs (a shared end counts too): for OpenSim's coordinate `elbow_flex_r`,
/// the joint `elbow_r`, not `elbow_l`.
fn nearest_id(m: &Mechanism, text: &str) -> Option<String> {
    m.joints
        .iter()
        .flat_map(|j| [j.id.clone(), m.joint_bodies_label(j)])
        .map(|cand| {
            let jw = strsim::jaro_winkler(text, &cand);
            (jw, jw + strsim::sorensen_dice(text, &cand), cand)
        })
        .filter(|(jw, _, _)| *jw >= 0.75)
        .max_by(|a, b| a.1.total_cmp(&b.1).then_with(|| b.2.cmp(&a.2)))
        .map(|(_, _, c)| c)
}

/// Split `a-b` into two known body indices, trying every `-` (ids may contain dashes).
fn split_pair(m: &Mechanism, text: &str) -> Option<(usize, usize)> {
    text.match_indices('-').find_map(|(i, _)| {
        let a = m.body_index(&BodyId::from_text(&text[..i]))?;
        let b = m.body_index(&BodyId::from_text(&text[i + 1..]))?;
        Some((a, b))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_joint_name_not_found_suggests_the_nearest_one() {
        let j = |id: &str, a: i64, b: i64| JointSpec {
            id: Some(id.into()),
            ..JointSpec::new(JointType::R, a, b, 0)
        };
        let m = Mechanism::from_parts(
            "arms",
            Space::Spatial,
            BodyId::Int(1),
            vec![],
            vec![j("elbow_l", 1, 2), j("elbow_r", 1, 3)],
        );
        let hint = |text: &str| match resolve_ref(&m, text) {
            Err(InputSpecError::NoMatch { hint, .. }) => hint,
            other => panic!("{other:?}"),
        };
        assert_eq!(hint("elbow_flex_r").as_deref(), Some("elbow_r"));
        assert_eq!(hint("elbow_flex_l").as_deref(), Some("elbow_l"));
        assert_eq!(hint("wrist"), None);
    }

    /// An OpenSim CustomJoint imported as a chain has ids `joint:coordinate`: its coordinate
    /// names the one joint, its name the chain (the nearest id by spelling was another joint:
    /// `pelvis_tilt` gave `pelvis-femur_r`).
    #[test]
    fn a_part_of_an_imported_id_suggests_the_joints_it_names() {
        let j = |id: &str, a: i64, b: i64| JointSpec {
            id: Some(id.into()),
            ..JointSpec::new(JointType::R, a, b, 0)
        };
        let m = Mechanism::from_parts(
            "leg",
            Space::Spatial,
            BodyId::Int(1),
            vec![],
            vec![
                j("ground_pelvis:pelvis_tx", 1, 2),
                j("ground_pelvis:pelvis_tilt", 2, 3),
                j("pelvis-femur_r", 3, 4),
            ],
        );
        let hint = |text: &str| match resolve_ref(&m, text) {
            Err(InputSpecError::NoMatch { hint, .. }) => hint,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            hint("pelvis_tilt").as_deref(),
            Some("ground_pelvis:pelvis_tilt")
        );
        assert_eq!(
            hint("ground_pelvis").as_deref(),
            Some("ground_pelvis:pelvis_tilt`, `ground_pelvis:pelvis_tx")
        );
        let e = resolve_ref(&m, "ground_pelvis").expect_err("no joint of that id");
        assert!(
            e.to_string()
                .contains("(did you mean `ground_pelvis:pelvis_tilt`, `ground_pelvis:pelvis_tx`?)"),
            "{e}"
        );
    }

    #[test]
    fn a_joint_stays_small_and_reads_as_before() {
        // 240 bytes with the inline geometry and a body vector: 10^6 joints touched 360 MB.
        assert!(
            std::mem::size_of::<Joint>() <= 64,
            "{}",
            std::mem::size_of::<Joint>()
        );
        let mut j = Joint {
            id: "1-2".into(),
            kind: JointType::R,
            bodies: vec![3, 4].into(),
            driven: 0,
            geometry: Geometry::default().into(),
        };
        assert!(j.geometry.is_empty() && j.geometry.origin.is_none());
        assert_eq!(j.bodies[..], [3, 4]);
        j.geometry.origin = Some([1.0, 2.0, 3.0]);
        assert_eq!(j.geometry.origin, Some([1.0, 2.0, 3.0]));
        assert_ne!(j.geometry, Geometry::default());
        let many: JointBodies = (0..5).collect();
        assert_eq!(many[..], [0, 1, 2, 3, 4]);
        assert_eq!(
            many.clone().into_iter().collect::<Vec<_>>(),
            vec![0, 1, 2, 3, 4]
        );
        assert_eq!(j.bodies.clone().into_iter().collect::<Vec<_>>(), vec![3, 4]);
        assert_eq!(
            serde_json::to_string(&j).ok(),
            Some(r#"{"id":"1-2","kind":"R","bodies":[3,4],"driven":0,"geometry":{"origin":[1.0,2.0,3.0]}}"#.to_string())
        );
    }

    /// The packed-key and flat-token fast paths of `natural_order` agree with `natural_cmp`.
    #[test]
    fn natural_order_fast_paths_agree_with_natural_cmp() {
        let sets: [&[&str]; 5] = [
            &[
                "12-5", "3-4", "0-1", "10-2", "3-4", "1", "1-0", "2-10", "2-9", "0",
            ],
            // Up to five tokens packed (separator above number), numbers below 2^56.
            &[
                "1-2#2",
                "1#2",
                "1-2",
                "1",
                "2-1#10",
                "2-1#9",
                "1-2-3",
                "1#2#3",
                "1#2-3",
                "1-72057594037927935",
                "1-72057594037927935#2",
                "72057594037927936-1",
            ],
            // A number from 2^56 after a separator: the flat tokens instead.
            &["1-72057594037927936", "1-2#2", "1-2", "1-72057594037927935"],
            &[
                "3-4#2", "3-4", "1-2-3", "1-2#2", "1-2", "12-5", "3-4#10", "3-4#9", "1-2-3",
            ],
            &[
                "a-1", "3-4", "03-4", "1-2", "x", "-1-2", "1--2", "10-2", "1-2",
            ],
        ];
        for ids in sets {
            let joints: Vec<Joint> = ids
                .iter()
                .map(|id| Joint {
                    id: id.to_string(),
                    kind: JointType::R,
                    bodies: vec![0, 1].into(),
                    driven: 0,
                    geometry: Default::default(),
                })
                .collect();
            let mut expected: Vec<usize> = (0..ids.len()).collect();
            expected.sort_by(|&a, &b| natural_cmp(ids[a], ids[b]));
            assert_eq!(natural_order(&joints), expected, "{ids:?}");
        }
    }

    #[test]
    fn permute_follows_the_order() {
        for n in 0..9usize {
            // A few permutations of n items: rotations and reversals of rotations.
            for shift in 0..n.max(1) {
                for rev in [false, true] {
                    let mut order: Vec<usize> = (0..n).map(|k| (k + shift) % n.max(1)).collect();
                    if rev {
                        order.reverse();
                    }
                    let mut v: Vec<usize> = (0..n).map(|k| 10 * k).collect();
                    let expected: Vec<usize> = order.iter().map(|&k| 10 * k).collect();
                    permute(&mut v, order);
                    assert_eq!(v, expected);
                }
            }
        }
    }

    #[test]
    fn body_ids_sort_numbers_first() {
        let mut ids = [
            BodyId::Name("b".into()),
            BodyId::Int(10),
            BodyId::Int(2),
            BodyId::Name("a".into()),
        ];
        ids.sort();
        let shown: Vec<String> = ids.iter().map(|i| i.to_string()).collect();
        assert_eq!(shown, ["2", "10", "a", "b"]);
    }

    #[test]
    fn natural_order_of_joint_ids() {
        let mut ids = ["13-9", "1-10", "1-2", "B", "A", "1-2#2", "x07", "x7a"];
        ids.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            ids,
            ["1-2", "1-2#2", "1-10", "13-9", "A", "B", "x07", "x7a"]
        );
    }

    #[test]
    fn parses_input_specs() {
        let s = InputSpec::parse("1-2, A:2 ,13-15").unwrap();
        assert_eq!(s.refs.len(), 3);
        assert_eq!(s.refs[1].text, "A");
        assert_eq!(s.refs[1].count, 2);
        assert!(InputSpec::parse("").unwrap().refs.is_empty());
        assert!(InputSpec::parse("A,,B").is_err());
        assert!(InputSpec::parse("A:x").is_err());
        assert!(InputSpec::parse(":2").is_err());
    }

    #[test]
    fn input_specs_take_imported_ids_with_colons() {
        // Ids as the importers write them: an MJCF `connect` closing a loop, a free base.
        let joint = |id: &str, kind, a: &str, b: &str| JointSpec {
            id: Some(id.into()),
            kind,
            bodies: vec![BodyId::from_text(a), BodyId::from_text(b)],
            driven: 0,
            geometry: Geometry::default(),
        };
        let m = Mechanism::from_parts(
            "ids",
            Space::Spatial,
            BodyId::from_text("world"),
            vec![],
            vec![
                joint("drive", JointType::R, "world", "crank"),
                joint("connect:crank-rod", JointType::S, "crank", "rod"),
                joint("rod:free", JointType::F, "world", "rod"),
            ],
        );
        // (joint id, driven DOF) of each entry.
        let resolved = |text: &str| {
            InputSpec::parse_in(text, &m)
                .and_then(|s| s.resolve(&m))
                .map(|r| {
                    r.into_iter()
                        .map(|(j, n)| (m.joints[j].id.clone(), n))
                        .collect::<Vec<_>>()
                })
                .map_err(|e| e.to_string())
        };
        let ids = |pairs: &[(&str, u32)]| -> Result<Vec<(String, u32)>, String> {
            Ok(pairs.iter().map(|&(id, n)| (id.to_string(), n)).collect())
        };
        assert_eq!(
            resolved("connect:crank-rod,rod:free,drive"),
            ids(&[("connect:crank-rod", 1), ("rod:free", 1), ("drive", 1)])
        );
        // `:n` after such an id still counts DOF.
        assert_eq!(
            resolved("connect:crank-rod:2,rod:free:6"),
            ids(&[("connect:crank-rod", 2), ("rod:free", 6)])
        );
        // Without the mechanism the same text is a syntax error, and so is a typo with it.
        assert!(InputSpec::parse("connect:crank-rod").is_err());
        assert_eq!(
            resolved("drive:x"),
            Err(
                "invalid input spec `drive:x`: `x` is not a non-negative whole number of DOF"
                    .into()
            )
        );
    }

    #[test]
    fn long_numeric_ids_are_not_numbers_and_do_not_overflow() {
        // 20 digits overflowed `n * 10` (a debug-build panic found by reliability_smoke).
        let mut out = Vec::new();
        assert!(!numeric_tokens("99999999999999999999", &mut out));
        out.clear();
        assert!(numeric_tokens("999999999999999999-2", &mut out));
        assert_eq!(out, vec![999_999_999_999_999_999, u64::from(b'-'), 2]);
    }
}
