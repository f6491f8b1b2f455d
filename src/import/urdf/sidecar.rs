//! The Extended-URDF closure file (Batto, de Matteis, Mansard, "Extended URDF: Accounting for
//! parallel mechanism in robot description", 2025; the models of Gepetto's
//! `example-parallel-robots`, loaded into Pinocchio by its `completeRobotLoader`): a YAML file
//! beside `robot.urdf`, by default `robot.yaml`, with
//!
//! - `closed_loop`: pairs of frame names (a joint's frame, or a link's), each pair a loop cut;
//! - `type`: per pair, `3d` (the frames' origins coincide: a ball joint) or `6d` (the frames
//!   coincide: a weld); 6D when the key is absent;
//! - `name_mot`: the actuated joints (one driven DOF each);
//! - `joint_name`, `joint_type`: joints whose kind the URDF cannot say: `SPHERICAL`, `FIXED`,
//!   `UJOINT_XY` (a universal joint turning about the joint frame's x, then y; any two of X,
//!   Y, Z).
//!
//! The file is read with the importer's input limit (what is left of it after the URDF), every
//! error located in it (file:line:col).

use super::Frames;
use super::constraint::{Cut, Side, close};
use crate::import::{Builder, ImportError, ImportOptions, Src, arr, too_large};
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::Vector3;
use std::collections::{HashMap, HashSet};
use std::ops::Range;
use std::path::Path;

/// A YAML value with its byte span; every scalar is kept as its text.
#[derive(Debug)]
struct Y {
    span: Range<usize>,
    v: V,
}

#[derive(Debug)]
enum V {
    Map(Vec<(String, Range<usize>, Y)>),
    Seq(Vec<Y>),
    Str(String),
}

/// Names of a list of the file, each with its span.
type Names<'a> = Vec<(&'a str, Range<usize>)>;

/// Deepest nesting read (the file needs 3 levels).
const MAX_DEPTH: usize = 16;

/// A closure file, read and parsed.
pub(super) struct Closures {
    name: String,
    text: String,
    root: Y,
}

/// The closure file of a URDF: `options.closures` (empty: none), or `STEM.yaml` / `STEM.yml`
/// beside it when that file has a `closed_loop` key.
pub(super) fn load(
    src: &Src,
    base_dir: Option<&Path>,
    options: &ImportOptions,
) -> Result<Option<Closures>, ImportError> {
    let left = options.byte_limit().saturating_sub(src.text.len() as u64);
    if let Some(path) = &options.closures {
        if path.as_os_str().is_empty() {
            return Ok(None);
        }
        let text = read(path, left)?;
        let c = parse(&path.display().to_string(), text)?;
        if c.key("closed_loop").is_none() {
            return Err(c
                .err(
                    c.root.span.start..c.root.span.start,
                    "no `closed_loop`",
                    "the closure file has no `closed_loop` key",
                )
                .with_help(
                    "closed_loop: [[frame_a, frame_b], ...] names the frames each loop cut joins",
                ));
        }
        return Ok(Some(c));
    }
    let (Some(dir), Some(stem)) = (base_dir, Path::new(src.name).file_stem()) else {
        return Ok(None);
    };
    for ext in ["yaml", "yml"] {
        let mut file = stem.to_os_string();
        file.push(format!(".{ext}"));
        let path = dir.join(file);
        if !path.is_file() {
            continue;
        }
        let text = read(&path, left)?;
        let mentions = text.contains("closed_loop");
        match parse(&path.display().to_string(), text) {
            Ok(c) if c.key("closed_loop").is_some() => return Ok(Some(c)),
            Err(e) if mentions => return Err(e),
            _ => {}
        }
    }
    Ok(None)
}

/// Read a closure file of at most `left` bytes, as UTF-8.
fn read(path: &Path, left: u64) -> Result<String, ImportError> {
    let name = path.display().to_string();
    let budget = crate::budget::Budget {
        max_input_bytes: left,
        ..crate::budget::Budget::UNLIMITED
    };
    let bytes = budget.read_file(path).map_err(|e| match e {
        crate::budget::ReadError::Io(e) => {
            ImportError::new(format!("cannot read the closure file `{name}`: {e}"))
                .with_help("--closures names the Extended-URDF YAML file of the loop closures")
        }
        crate::budget::ReadError::TooLarge(e) => too_large(e.what, e.needed, e.at_least, e.allowed),
    })?;
    String::from_utf8(bytes).map_err(|e| {
        ImportError::new(format!(
            "the closure file `{name}` is not UTF-8 text: invalid byte at offset {}",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// Parse YAML text into [`Y`] (one document, a mapping; aliases refused).
fn parse(name: &str, text: String) -> Result<Closures, ImportError> {
    let root = {
        let mut p = Parser::new(&text);
        p.document().map_err(|(span, m)| {
            ImportError::at(name, &text, span, "here", format!("malformed YAML: {m}")).with_help(
                "the closure file is YAML: closed_loop, type, name_mot, joint_name, joint_type",
            )
        })?
    };
    let c = Closures {
        name: name.to_string(),
        text,
        root,
    };
    if !matches!(c.root.v, V::Map(_)) {
        return Err(c
            .err(
                c.root.span.clone(),
                "not a mapping",
                "the closure file is not a YAML mapping",
            )
            .with_help("write closed_loop: [[frame_a, frame_b]] and type: [3d] at the top level"));
    }
    Ok(c)
}

/// A reader of saphyr events into [`Y`], spans in bytes.
struct Parser<'a> {
    p: saphyr_parser::Parser<'a, saphyr_parser::StrInput<'a>>,
    text: &'a str,
    /// Byte offset of each char when the text is not ASCII.
    chars: Option<Vec<usize>>,
}

type Failed = (Range<usize>, String);

impl<'a> Parser<'a> {
    fn new(text: &'a str) -> Parser<'a> {
        let chars = (!text.is_ascii()).then(|| {
            text.char_indices()
                .map(|(b, _)| b)
                .chain([text.len()])
                .collect()
        });
        Parser {
            p: saphyr_parser::Parser::new_from_str(text),
            text,
            chars,
        }
    }

    fn byte(&self, char_index: usize) -> usize {
        match &self.chars {
            None => char_index.min(self.text.len()),
            Some(c) => c.get(char_index).copied().unwrap_or(self.text.len()),
        }
    }

    fn next(&mut self) -> Result<(saphyr_parser::Event<'a>, Range<usize>), Failed> {
        match self.p.next_event() {
            Some(Ok((ev, s))) => {
                let a = self.byte(s.start.index());
                Ok((ev, a..self.byte(s.end.index()).max(a)))
            }
            Some(Err(e)) => {
                let at = self.byte(e.marker().index());
                Err((at..at, e.info().to_string()))
            }
            None => Err((
                self.text.len()..self.text.len(),
                "unexpected end of input".into(),
            )),
        }
    }

    /// The first document's root (an empty stream: an empty mapping).
    fn document(&mut self) -> Result<Y, Failed> {
        use saphyr_parser::Event;
        loop {
            let (ev, span) = self.next()?;
            match ev {
                Event::StreamStart | Event::DocumentStart(_) | Event::Nothing => {}
                Event::StreamEnd => {
                    return Ok(Y {
                        span: 0..0,
                        v: V::Map(Vec::new()),
                    });
                }
                _ => return self.node(ev, span, 0),
            }
        }
    }

    fn node(
        &mut self,
        ev: saphyr_parser::Event<'a>,
        span: Range<usize>,
        depth: usize,
    ) -> Result<Y, Failed> {
        use saphyr_parser::Event;
        if depth > MAX_DEPTH {
            return Err((span, format!("nested deeper than {MAX_DEPTH} levels")));
        }
        let v = match ev {
            Event::Scalar(t, ..) => V::Str(t.into_owned()),
            Event::SequenceStart(..) => {
                let mut items = Vec::new();
                loop {
                    let (ev, s) = self.next()?;
                    if matches!(ev, Event::SequenceEnd) {
                        break;
                    }
                    items.push(self.node(ev, s, depth + 1)?);
                }
                V::Seq(items)
            }
            Event::MappingStart(..) => V::Map(self.entries(depth)?),
            Event::Alias(_) => return Err((span, "aliases are not read".into())),
            _ => return Err((span, "unexpected YAML event".into())),
        };
        Ok(Y { span, v })
    }

    fn entries(&mut self, depth: usize) -> Result<Vec<(String, Range<usize>, Y)>, Failed> {
        use saphyr_parser::Event;
        let mut entries = Vec::new();
        loop {
            let (ev, ks) = self.next()?;
            let key = match ev {
                Event::MappingEnd => return Ok(entries),
                Event::Scalar(k, ..) => k.into_owned(),
                _ => return Err((ks, "a key must be a plain text".into())),
            };
            let (ev, vs) = self.next()?;
            let value = self.node(ev, vs, depth + 1)?;
            entries.push((key, ks, value));
        }
    }
}

/// A closure frame: a joint's frame (the one Pinocchio finds first) or a link's.
fn frame_of(frames: &Frames, name: &str) -> Option<Side> {
    if let Some((child, pose)) = frames.joints.get(name) {
        return Some(Side {
            link: child.clone(),
            frame: *pose,
        });
    }
    frames.link(name).map(|frame| Side {
        link: name.to_string(),
        frame,
    })
}

impl Closures {
    fn err(&self, span: Range<usize>, label: &str, message: impl Into<String>) -> ImportError {
        ImportError::at(&self.name, &self.text, span, label, message)
    }

    /// `file:line:col` of a byte offset.
    fn loc(&self, at: usize) -> String {
        let before = &self.text[..at.min(self.text.len())];
        let line = before.matches('\n').count() + 1;
        let col = before[before.rfind('\n').map_or(0, |i| i + 1)..]
            .chars()
            .count()
            + 1;
        let file = Path::new(&self.name)
            .file_name()
            .and_then(|f| f.to_str())
            .unwrap_or(&self.name);
        format!("{file}:{line}:{col}")
    }

    fn key(&self, key: &str) -> Option<(&Range<usize>, &Y)> {
        let V::Map(entries) = &self.root.v else {
            return None;
        };
        entries
            .iter()
            .find(|(k, ..)| k == key)
            .map(|(_, s, y)| (s, y))
    }

    /// The strings of a sequence key (`None` when the key is absent).
    fn strings(&self, key: &str) -> Result<Option<Names<'_>>, ImportError> {
        let Some((_, y)) = self.key(key) else {
            return Ok(None);
        };
        let V::Seq(items) = &y.v else {
            return Err(self.err(
                y.span.clone(),
                "not a list",
                format!("`{key}` is not a list"),
            ));
        };
        items
            .iter()
            .map(|i| match &i.v {
                V::Str(s) => Ok((s.as_str(), i.span.clone())),
                _ => Err(self.err(
                    i.span.clone(),
                    "not a name",
                    format!("an item of `{key}` is not a name"),
                )),
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    /// Apply the file to the model: joint kinds, actuated joints, loop cuts. `index` gives the
    /// builder's joint of each tree joint that is not fixed.
    pub(super) fn apply(
        &self,
        b: &mut Builder,
        frames: &Frames,
        index: &HashMap<String, usize>,
    ) -> Result<(), ImportError> {
        b.notes.push(format!(
            "loop closures, actuated joints and joint kinds read from `{}` (Extended URDF)",
            self.name
        ));
        if let V::Map(entries) = &self.root.v {
            for (k, s, _) in entries {
                if !matches!(
                    k.as_str(),
                    "closed_loop" | "type" | "name_mot" | "joint_name" | "joint_type"
                ) {
                    b.warn(format!(
                        "{}: key `{k}` of the closure file not read",
                        self.loc(s.start)
                    ));
                }
            }
        }
        let removed = self.joint_kinds(b, frames, index)?;
        self.actuated(b, index, &removed)?;
        self.loops(b, frames)?;
        let mut i = 0;
        b.joints.retain(|_| {
            i += 1;
            !removed.contains(&(i - 1))
        });
        Ok(())
    }

    /// The tree joint a name of the file names (not fixed), or a located error.
    fn tree_joint(
        &self,
        index: &HashMap<String, usize>,
        name: &str,
        span: &Range<usize>,
        key: &str,
    ) -> Result<usize, ImportError> {
        index.get(name).copied().ok_or_else(|| {
            self.err(span.clone(), "no such joint", format!("`{key}` names joint `{name}`, which the URDF does not define (or defines fixed)"))
                .with_help("name a revolute, continuous, prismatic, planar or floating <joint> of the URDF")
        })
    }

    /// `joint_name` / `joint_type`: the joints the URDF cannot type. Returns the builder
    /// indices of the joints made FIXED (their links welded).
    fn joint_kinds(
        &self,
        b: &mut Builder,
        frames: &Frames,
        index: &HashMap<String, usize>,
    ) -> Result<HashSet<usize>, ImportError> {
        let names = self.strings("joint_name")?.unwrap_or_default();
        let kinds = self.strings("joint_type")?.unwrap_or_default();
        self.same_length("joint_name", names.len(), "joint_type", kinds.len())?;
        let mut removed = HashSet::new();
        for ((name, ns), (kind, ks)) in names.iter().zip(&kinds) {
            let Some(&ji) = index.get(*name) else {
                // Pinocchio's loader skips the names its model lacks.
                b.warn(format!("{}: `joint_name` names joint `{name}`, which the URDF does not define (or defines fixed): skipped", self.loc(ns.start)));
                continue;
            };
            let pose = frames.joints[*name].1;
            let loc = self.loc(ks.start);
            let j = &mut b.joints[ji];
            let origin = j.geometry.origin;
            let unit_axis = |c: char| {
                let v = match c {
                    'X' => Vector3::x(),
                    'Y' => Vector3::y(),
                    _ => Vector3::z(),
                };
                arr(pose.rotation * v)
            };
            match *kind {
                "SPHERICAL" => {
                    j.kind = JointType::S;
                    j.geometry = Geometry {
                        origin,
                        ..Geometry::default()
                    };
                }
                "FIXED" => {
                    let (p, c) = (j.bodies[0], j.bodies[1]);
                    removed.insert(ji);
                    b.weld(
                        p,
                        c,
                        &format!("joint `{name}` FIXED in the closure file at {loc}"),
                    );
                    continue;
                }
                k if universal(k) => {
                    let mut axes = k[7..].chars();
                    let (a, c) = (axes.next().unwrap_or('X'), axes.next().unwrap_or('Y'));
                    j.kind = JointType::U;
                    j.geometry = Geometry {
                        origin,
                        axis: Some(unit_axis(a)),
                        axis2: Some(unit_axis(c)),
                        ..Geometry::default()
                    };
                }
                other => {
                    return Err(self.err(ks.clone(), "unknown joint type", format!("`joint_type` `{other}` is not a joint type of the Extended URDF"))
                        .with_help("joint types: SPHERICAL, FIXED, UJOINT_XY (two of X, Y, Z: the joint frame's axes, in turn order)"));
                }
            }
            j.driven = j.driven.min(j.kind.grade() as u32);
            j.comments
                .push(format!("{kind} in the closure file at {loc}"));
        }
        Ok(removed)
    }

    /// `name_mot`: one driven DOF on each joint named.
    fn actuated(
        &self,
        b: &mut Builder,
        index: &HashMap<String, usize>,
        removed: &HashSet<usize>,
    ) -> Result<(), ImportError> {
        for (name, span) in self.strings("name_mot")?.unwrap_or_default() {
            let ji = self.tree_joint(index, name, &span, "name_mot")?;
            let loc = self.loc(span.start);
            if removed.contains(&ji) {
                b.warn(format!(
                    "{loc}: `name_mot` actuates joint `{name}`, made FIXED: not counted"
                ));
                continue;
            }
            let j = &mut b.joints[ji];
            if j.driven < j.kind.grade() as u32 {
                j.driven += 1;
                j.comments.push(format!("actuated (`name_mot` at {loc})"));
            }
        }
        Ok(())
    }

    /// `closed_loop` and `type`: each pair of frames joined by a ball joint (3D) or welded (6D).
    fn loops(&self, b: &mut Builder, frames: &Frames) -> Result<(), ImportError> {
        let Some((ks, y)) = self.key("closed_loop") else {
            return Ok(());
        };
        let V::Seq(pairs) = &y.v else {
            return Err(self.err(
                y.span.clone(),
                "not a list",
                "`closed_loop` is not a list of frame pairs",
            ));
        };
        let types = self.strings("type")?;
        if let Some(t) = &types {
            self.same_length("closed_loop", pairs.len(), "type", t.len())?;
        } else if !pairs.is_empty() {
            b.notes.push(format!(
                "{}: no `type`: every loop cut is 6D (a weld), as Pinocchio's loader takes it",
                self.loc(ks.start)
            ));
        }
        for (i, pair) in pairs.iter().enumerate() {
            let sides = self.pair(pair, frames)?;
            let (kind, kspan) = match &types {
                Some(t) => (t[i].0, t[i].1.clone()),
                None => ("6d", pair.span.clone()),
            };
            let cut = match kind {
                "3d" | "3D" => Cut::Joint(JointType::S, None, None),
                "6d" | "6D" => Cut::Weld,
                other => {
                    return Err(self.err(kspan, "unknown type", format!("loop type `{other}` is neither 3d nor 6d"))
                        .with_help("3d: the frames' origins coincide (a ball joint); 6d: the frames coincide (a weld)"));
                }
            };
            let (a, c) = (&sides[0].0, &sides[1].0);
            let what = format!("closed_loop [{a}, {c}] ({kind})");
            close(
                b,
                &format!("{a}-{c}"),
                &cut,
                &sides[0].1,
                &sides[1].1,
                &what,
                &self.loc(pair.span.start),
            );
        }
        Ok(())
    }

    /// A pair of frame names, each found in the URDF.
    fn pair(&self, pair: &Y, frames: &Frames) -> Result<Vec<(String, Side)>, ImportError> {
        let bad = || {
            self.err(
                pair.span.clone(),
                "not a pair",
                "an item of `closed_loop` is not a pair of frame names",
            )
            .with_help("write [frame_a, frame_b]: the frames the loop cut joins")
        };
        let V::Seq(items) = &pair.v else {
            return Err(bad());
        };
        if items.len() != 2 {
            return Err(bad());
        }
        items
            .iter()
            .map(|i| {
                let V::Str(name) = &i.v else {
                    return Err(bad());
                };
                let side = frame_of(frames, name).ok_or_else(|| {
                    self.err(
                        i.span.clone(),
                        "no such frame",
                        format!("frame `{name}` is neither a joint nor a link of the URDF"),
                    )
                    .with_help(
                        "closed_loop names the frames of joints or links (Pinocchio's frame names)",
                    )
                })?;
                Ok((name.clone(), side))
            })
            .collect()
    }

    fn same_length(&self, a: &str, na: usize, b: &str, nb: usize) -> Result<(), ImportError> {
        if na == nb {
            return Ok(());
        }
        let span = self.key(b).or(self.key(a)).map_or(0..0, |(s, _)| s.clone());
        Err(self
            .err(
                span,
                "length differs",
                format!("`{b}` has {nb} item(s) but `{a}` has {na}"),
            )
            .with_help(format!("`{b}` gives one item for each item of `{a}`")))
    }
}

/// `UJOINT_AB` with A and B two different axes among X, Y, Z.
fn universal(k: &str) -> bool {
    let Some(axes) = k.strip_prefix("UJOINT_") else {
        return false;
    };
    let a: Vec<char> = axes.chars().collect();
    a.len() == 2 && a[0] != a[1] && a.iter().all(|c| matches!(c, 'X' | 'Y' | 'Z'))
}
