//! The shared intermediate model the readers fill: bodies (welded ones merged by union-find),
//! joints, warnings and notes; written as format-v1 TOML and read back.

use super::balls::merge_balls;
use super::error::ImportError;
use super::pins::merge_pins;
use super::toml_text::{comment_text, num, precision_text, toml_str, written_rounding};
use super::{Import, ImportOptions, SourceFormat};
use super::{Pose, shift};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use crate::words::capped;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// Gaps below this (length, or angle in radians) between the two frames of a weld are closed.
const CLOSED: f64 = 1e-6;

/// A joint of the intermediate model.
#[derive(Clone, Debug)]
pub(crate) struct JointRec {
    pub id: String,
    pub kind: JointType,
    /// Body indices into [`Builder::names`].
    pub bodies: Vec<usize>,
    pub driven: u32,
    pub geometry: Geometry,
    /// Comment lines naming the source element(s).
    pub comments: Vec<String>,
}

/// The shared intermediate model the readers fill.
pub(crate) struct Builder {
    pub model_name: String,
    /// The configuration, in words (`qpos0`, `keyframe "home"`, ...).
    pub configuration: String,
    names: Vec<String>,
    comments: Vec<String>,
    index: HashMap<String, usize>,
    uf: Vec<usize>,
    /// Where each body sits relative to the file's placement of it: the identity, unless a
    /// loop cut welded it where the cut puts it ([`Builder::weld_moved`]).
    moved: Vec<Pose>,
    pub frame: usize,
    pub joints: Vec<JointRec>,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
    /// The coarsest rounding of the source numbers that enter the geometry ([`super::Src::note`]):
    /// the written model's `precision` (with at least the importer's own rounding).
    source_rounding: f64,
}

impl Builder {
    /// A new model whose fixed frame is the body `frame`.
    pub fn new(model_name: &str, frame: &str, frame_comment: &str) -> Builder {
        let mut b = Builder {
            model_name: model_name.to_string(),
            configuration: String::new(),
            names: Vec::new(),
            comments: Vec::new(),
            index: HashMap::new(),
            uf: Vec::new(),
            moved: Vec::new(),
            frame: 0,
            joints: Vec::new(),
            warnings: Vec::new(),
            notes: Vec::new(),
            source_rounding: 0.0,
        };
        b.frame = b.body(frame, frame_comment);
        b
    }

    /// The body named `name` (created if new).
    pub fn body(&mut self, name: &str, comment: &str) -> usize {
        if let Some(&i) = self.index.get(name) {
            return i;
        }
        let i = self.names.len();
        self.names.push(name.to_string());
        self.comments.push(comment.to_string());
        self.index.insert(name.to_string(), i);
        self.uf.push(i);
        self.moved.push(Pose::identity());
        i
    }

    /// A body name not used yet, from `base`.
    pub fn fresh_name(&self, base: &str) -> String {
        if !self.index.contains_key(base) {
            return base.to_string();
        }
        (2..)
            .map(|k| format!("{base}#{k}"))
            .find(|n| !self.index.contains_key(n))
            .unwrap_or_else(|| base.to_string())
    }

    /// The body named `name`, if it exists.
    pub fn find_body(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }

    fn root(&self, mut i: usize) -> usize {
        while self.uf[i] != i {
            i = self.uf[i];
        }
        i
    }

    /// Weld `other` to `keep` (they become one body, named as `keep`'s group unless `other`'s
    /// group holds the frame).
    pub fn weld(&mut self, keep: usize, other: usize, why: &str) {
        let (a, b) = (self.root(keep), self.root(other));
        if a == b {
            return;
        }
        let (keep_root, gone) = if b == self.root(self.frame) {
            (b, a)
        } else {
            (a, b)
        };
        self.uf[gone] = keep_root;
        self.notes.push(format!(
            "`{}` welded to `{}` ({why})",
            self.names[other], self.names[keep]
        ));
    }

    /// How body `i` was moved from the file's placement of it (the identity unless a weld
    /// moved it).
    pub fn moved(&self, i: usize) -> Pose {
        self.moved[i]
    }

    /// Weld `other` to `keep` where `d` (a move of `other`) puts it: the links welded to
    /// `other` move with it (or, when those hold the fixed frame, the links welded to `keep`
    /// move by the inverse), and every joint between the moved links and the others carries
    /// the moved side in its `second` geometry ([`shift::move_side`]). Returns the names of
    /// the moved links; `Err` with the joints that cannot carry a moved side, nothing changed.
    pub fn weld_moved(
        &mut self,
        keep: usize,
        other: usize,
        d: &Pose,
        why: &str,
    ) -> Result<Vec<String>, Vec<String>> {
        // The second link's group moves; where its joints cannot carry the move (or it holds
        // the frame), the first link's group moves back instead.
        let frame = self.root(self.frame);
        let candidates = [(self.root(other), *d), (self.root(keep), d.inverse())];
        let mut first_blocked: Option<Vec<String>> = None;
        let mut chosen = None;
        for (group, d) in candidates.into_iter().filter(|c| c.0 != frame) {
            let inside: Vec<bool> = (0..self.names.len())
                .map(|i| self.root(i) == group)
                .collect();
            let blocked = self.blocked(&inside);
            if blocked.is_empty() {
                chosen = Some((inside, d));
                break;
            }
            first_blocked.get_or_insert(blocked);
        }
        let Some((inside, d)) = chosen else {
            return Err(first_blocked.unwrap_or_default());
        };
        let side = |j: &JointRec| -> Option<usize> {
            let ins: Vec<bool> = j.bodies.iter().map(|&x| inside[x]).collect();
            match ins.as_slice() {
                [a, b] if a != b => Some(usize::from(*b)),
                _ => None,
            }
        };
        for j in &mut self.joints {
            if let Some(k) = side(j) {
                shift::move_side(j.kind, &mut j.geometry, k, &d);
            } else if j.bodies.iter().all(|&x| inside[x]) {
                shift::move_joint(&mut j.geometry, &d);
            }
        }
        let mut names = Vec::new();
        for (i, &ins) in inside.iter().enumerate() {
            if ins {
                self.moved[i] = d * self.moved[i];
                names.push(self.names[i].clone());
            }
        }
        self.weld(keep, other, why);
        Ok(names)
    }

    /// Weld body `other` to body `keep` by a loop cut that makes frame `fc` of `other`
    /// coincide with frame `fk` of `keep` (both world poses as the file places the bodies).
    /// Closed: the bodies are welded. Open: `other` is welded where the cut puts it
    /// ([`Builder::weld_moved`]), or, where a joint cannot carry the move, as placed; a
    /// warning (at `loc`, naming the cut `what`) gives the gap and which it was.
    pub fn weld_cut(
        &mut self,
        keep: usize,
        other: usize,
        fk: &Pose,
        fc: &Pose,
        what: &str,
        loc: &str,
    ) {
        // A body a weld before this one moved sits where that weld put it.
        let (fk, fc) = (self.moved(keep) * fk, self.moved(other) * fc);
        let gap = (fk.translation.vector - fc.translation.vector).norm();
        let angle = (fk.rotation.inverse() * fc.rotation).angle();
        let why = format!("{what} at {loc}");
        let (a, c) = (self.names[keep].clone(), self.names[other].clone());
        if gap <= CLOSED && angle <= CLOSED {
            self.weld(keep, other, &why);
            return;
        }
        let open = format!(
            "{loc}: {what} between `{a}` and `{c}` is not closed at this configuration (gap {gap:.3e}, angle {angle:.3e} rad)"
        );
        match self.weld_moved(keep, other, &(fk * fc.inverse()), &why) {
            Ok(moved) => {
                let quoted: Vec<String> = moved.iter().map(|n| format!("`{n}`")).collect();
                let (who, it) = match quoted.len() {
                    1 => (format!("{} is", quoted[0]), "it"),
                    _ => (
                        format!("the bodies {} (one body) are", capped(&quoted)),
                        "them",
                    ),
                };
                self.warn(format!("{open}: {who} welded where the cut puts {it}, and the joints to {it} carry that side in `second` (`mbsa assemble` closes the loops)"));
            }
            Err(blocked) => {
                self.warn(format!("{open}: the bodies are welded as they are placed, which is not the assembled mechanism (the joints {} cannot carry a moved side)", capped(&blocked)));
                self.weld(keep, other, &why);
            }
        }
    }

    /// The joints between the bodies `inside` and the others that cannot carry a moved side.
    fn blocked(&self, inside: &[bool]) -> Vec<String> {
        self.joints
            .iter()
            .filter(|j| j.bodies.iter().any(|&x| inside[x]))
            .filter(|j| {
                let whole = j.bodies.iter().all(|&x| inside[x]);
                !whole && (j.bodies.len() != 2 || !shift::can_move_side(j.kind))
            })
            .map(|j| format!("{} ({})", j.id, j.kind.code()))
            .collect()
    }

    /// Add a joint; returns its index.
    pub fn joint(&mut self, j: JointRec) -> usize {
        self.joints.push(j);
        self.joints.len() - 1
    }

    /// Note the rounding of source numbers that enter the geometry (a [`super::Src::rounding`]).
    pub fn note_rounding(&mut self, rounding: f64) {
        self.source_rounding = self.source_rounding.max(rounding);
    }

    /// Record a warning (an element not imported or not representable).
    pub fn warn(&mut self, message: impl Into<String>) {
        self.warnings.push(message.into());
    }

    /// Resolve welds, merge pins, write the TOML and read it back.
    pub fn finish(
        mut self,
        source_name: &str,
        format: SourceFormat,
        options: &ImportOptions,
    ) -> Result<Import, ImportError> {
        let mut joints = self.joints_through_welds();
        let frame = self.root(self.frame);
        let dropped = if options.merge_balls {
            merge_balls(&mut joints, frame)
        } else {
            Vec::new()
        };
        if !dropped.is_empty() {
            let names: Vec<String> = dropped.iter().map(|&b| self.names[b].clone()).collect();
            self.notes.push(format!(
                "--merge-balls: {} ball joint(s) written as three revolute joints merged into S \
                 joints; their intermediate bodies left out: {}",
                dropped.len() / 2,
                crate::words::capped(&names)
            ));
        }
        let merged_pins = if options.merge_pins {
            merge_pins(&mut joints)
        } else {
            0
        };
        if merged_pins > 0 {
            self.notes.push(format!(
                "--merge-pins: {merged_pins} coaxial revolute joint(s) merged into multiple joints"
            ));
        }
        unique_joint_ids(&mut joints);
        if joints.is_empty() {
            return Err(ImportError::new(format!(
                "`{source_name}`: no joints to analyse (every body is welded to the frame or \
                 the model has no joints)"
            ))
            .with_help("the analyses need at least one joint between two bodies"));
        }
        self.warn_unlinked(&joints, frame, &dropped);
        check_magnitudes(&joints)?;
        // A 10 MB name is quoted by its start only (the written joints keep it whole).
        for w in self.warnings.iter_mut().chain(self.notes.iter_mut()) {
            *w = super::names::cap_quoted(std::mem::take(w));
        }
        let toml = self.write_toml(source_name, format, &joints, frame);
        let mechanism = crate::format::load(source_name, &toml, crate::format::Format::Toml)
            .map_err(|e| {
                ImportError::new(format!(
                    "internal error: the imported model does not read back: {e}"
                ))
                .with_help("please report this with the source file")
            })?;
        Ok(Import {
            mechanism,
            toml,
            format,
            warnings: self.warnings,
            notes: self.notes,
            merged_pins,
            merged_balls: dropped.len() / 2,
        })
    }

    /// The joints with their bodies through the welds; a joint whose bodies were welded
    /// together is left out (warned).
    fn joints_through_welds(&mut self) -> Vec<JointRec> {
        let mut joints = std::mem::take(&mut self.joints);
        let mut kept = Vec::with_capacity(joints.len());
        for mut j in joints.drain(..) {
            let named = j.bodies.clone();
            for b in &mut j.bodies {
                *b = self.root(*b);
            }
            let mut seen = j.bodies.clone();
            seen.sort_unstable();
            seen.dedup();
            if seen.len() < j.bodies.len() {
                // Named as the file names them, and the body the welds make them part of.
                let quoted = |bs: &[usize]| {
                    bs.iter()
                        .map(|&b| format!("`{}`", self.names[b]))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                self.warnings.push(format!(
                    "joint `{}` joins bodies welded together ({}, welded into {}): left out",
                    j.id,
                    quoted(&named),
                    quoted(&seen)
                ));
                continue;
            }
            kept.push(j);
        }
        kept
    }

    /// Warnings for a frame no joint touches and for bodies no joint names (left out).
    fn warn_unlinked(&mut self, joints: &[JointRec], frame: usize, merged: &[usize]) {
        if !joints.iter().any(|j| j.bodies.contains(&frame)) {
            self.warnings.push(format!(
                "no joint touches the frame `{}`: the bodies are not linked to it",
                self.names[frame]
            ));
        }
        let mut used_bodies = vec![false; self.names.len()];
        for j in joints {
            for &b in &j.bodies {
                used_bodies[b] = true;
            }
        }
        used_bodies[frame] = true;
        for &b in merged {
            used_bodies[b] = true;
        }
        for (i, &u) in used_bodies.iter().enumerate() {
            if !u && self.root(i) == i {
                self.warnings.push(format!(
                    "body `{}` is joined to nothing: left out",
                    self.names[i]
                ));
            }
        }
    }

    /// The format-v1 TOML text: a header of comments (source, configuration, notes, warnings),
    /// the top-level keys, then each joint.
    fn write_toml(
        &self,
        source_name: &str,
        format: SourceFormat,
        joints: &[JointRec],
        frame: usize,
    ) -> String {
        let mut t = String::new();
        let file = Path::new(source_name)
            .file_name()
            .and_then(|f| f.to_str())
            .unwrap_or(source_name);
        let _ = writeln!(
            t,
            "# Imported by `mbsa import` from {} ({}).",
            comment_text(file),
            format.name()
        );
        if !self.configuration.is_empty() {
            let _ = writeln!(
                t,
                "# Configuration: {}. Joint origins and axes are in the world frame there.",
                comment_text(&self.configuration)
            );
        }
        for n in &self.notes {
            let _ = writeln!(t, "# note: {}", comment_text(n));
        }
        for w in &self.warnings {
            let _ = writeln!(t, "# warning: {}", comment_text(w));
        }
        let _ = writeln!(t, "name = {}", toml_str(&self.model_name));
        let _ = writeln!(t, "space = \"spatial\"");
        let _ = writeln!(t, "frame = {}", toml_str(&self.names[frame]));
        let _ = writeln!(
            t,
            "# How precisely the numbers are known (±): the coarsest rounding of the source's \
             numbers."
        );
        let _ = writeln!(
            t,
            "precision = {}",
            precision_text(self.source_rounding.max(written_rounding(joints)))
        );
        for j in joints {
            self.write_joint(&mut t, j);
        }
        t
    }

    /// One `[[joint]]` table of the TOML text.
    fn write_joint(&self, t: &mut String, j: &JointRec) {
        t.push('\n');
        let _ = writeln!(t, "[[joint]]");
        for c in &j.comments {
            let _ = writeln!(t, "# {}", comment_text(c));
        }
        let _ = writeln!(t, "id = {}", toml_str(&j.id));
        let _ = writeln!(t, "type = \"{}\"", j.kind.code());
        let bodies: Vec<String> = j.bodies.iter().map(|&b| toml_str(&self.names[b])).collect();
        let _ = writeln!(t, "bodies = [{}]", bodies.join(", "));
        if j.driven > 0 {
            let _ = writeln!(t, "driven = {}", j.driven);
        }
        let g = &j.geometry;
        for (key, v) in [
            ("origin", g.origin),
            ("origin2", g.origin2),
            ("axis", g.axis),
            ("axis2", g.axis2),
            ("normal", g.normal),
        ] {
            if let Some(v) = v {
                let _ = writeln!(t, "{key} = [{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]));
            }
        }
        if let Some(p) = g.pitch {
            let _ = writeln!(t, "pitch = {}", num(p));
        }
        if let Some(s) = &g.second {
            let fields: Vec<String> = s
                .vectors()
                .into_iter()
                .filter_map(|(key, v)| {
                    v.map(|v| format!("{key} = [{}, {}, {}]", num(v[0]), num(v[1]), num(v[2])))
                })
                .collect();
            let _ = writeln!(t, "second = {{ {} }}", fields.join(", "));
        }
    }
}

/// Every geometry number below [`super::xml::MAX_MAGNITUDE`] in magnitude: poses composed of
/// numbers each in range can still sum past it, and the written file could not be read back.
fn check_magnitudes(joints: &[JointRec]) -> Result<(), ImportError> {
    for j in joints {
        let g = &j.geometry;
        let second = g.second.as_ref().map(|s| s.vectors()).unwrap_or_default();
        let vectors = [g.origin, g.origin2, g.axis, g.axis2, g.normal]
            .into_iter()
            .chain(second.into_iter().map(|(_, v)| v))
            .flatten()
            .flatten()
            .chain(g.pitch);
        if let Some(x) = vectors
            .into_iter()
            .find(|x| x.is_nan() || x.abs() >= super::xml::MAX_MAGNITUDE)
        {
            let at = j.comments.first().map(String::as_str).unwrap_or("");
            return Err(ImportError::new(format!(
                "joint `{}` ({at}): its geometry has the number {x:e}, beyond 1e18 in magnitude",
                j.id
            ))
            .with_help(
                "the poses in the file place this joint too far away: check their numbers",
            ));
        }
    }
    Ok(())
}

/// Unique joint ids: an empty id becomes `joint`, a repeated one is suffixed `#2`, `#3`...
fn unique_joint_ids(joints: &mut [JointRec]) {
    let mut used: HashMap<String, usize> = HashMap::new();
    for j in joints {
        if j.id.is_empty() {
            j.id = "joint".into();
        }
        let n = used.entry(j.id.clone()).or_insert(0);
        *n += 1;
        if *n > 1 {
            let mut k = *n;
            let mut id = format!("{}#{k}", j.id);
            while used.contains_key(&id) {
                k += 1;
                id = format!("{}#{k}", j.id);
            }
            used.insert(id.clone(), 1);
            j.id = id;
        }
    }
}
