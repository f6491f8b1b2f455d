//! The importers (MJCF, SDFormat, URDF, OpenSim): any bytes read as one of them give a
//! mechanism or an error, never a panic; and a small tree of bodies on hinges, sliders and
//! balls, drawn from the bytes and written in MJCF, SDFormat, URDF and OpenSim, keeps its
//! mobility count and its numbers of bodies and joints when its names change and its elements
//! are reordered.
//!
//! The first byte chooses: bits 0-1 the format, bit 2 raw text or a generated tree.

use mbsa::import::{ImportOptions, SourceFormat, import_bytes, import_str};
use std::fmt::Write as _;

const FORMATS: [SourceFormat; 4] = [
    SourceFormat::Mjcf,
    SourceFormat::Sdf,
    SourceFormat::Urdf,
    SourceFormat::Osim,
];

/// Body `i + 1` hangs from `parent[i]` (0 is the root) on a joint of `kind[i]`.
struct Tree {
    parent: Vec<usize>,
    kind: Vec<u8>,
    axis: Vec<[i8; 3]>,
}

impl Tree {
    fn from(bytes: &[u8]) -> Tree {
        let mut t = Tree {
            parent: Vec::new(),
            kind: Vec::new(),
            axis: Vec::new(),
        };
        for (i, c) in bytes.chunks_exact(3).take(12).enumerate() {
            t.parent.push(c[0] as usize % (i + 1));
            t.kind.push(c[1] % 3);
            let a = [(c[2] & 3) as i8 - 1, ((c[2] >> 2) & 3) as i8 - 1, 1];
            t.axis.push(a);
        }
        t
    }

    /// The children of each body, reversed when `reverse` (another element order).
    fn children(&self, reverse: bool) -> Vec<Vec<usize>> {
        let mut ch = vec![Vec::new(); self.parent.len() + 1];
        for (i, &p) in self.parent.iter().enumerate() {
            ch[p].push(i + 1);
        }
        if reverse {
            ch.iter_mut().for_each(|c| c.reverse());
        }
        ch
    }

    fn axis(&self, body: usize) -> String {
        let a = self.axis[body - 1];
        format!("{} {} {}", a[0], a[1], a[2])
    }

    fn mjcf(&self, prefix: &str, reverse: bool) -> String {
        fn body(t: &Tree, ch: &[Vec<usize>], b: usize, prefix: &str, out: &mut String) {
            let kind = ["hinge", "slide", "ball"][t.kind[b - 1] as usize];
            let _ = write!(
                out,
                "<body name=\"{prefix}{b}\" pos=\"0 0 1\"><joint name=\"{prefix}j{b}\" \
                 type=\"{kind}\" axis=\"{}\"/><geom size=\"0.1\"/>",
                t.axis(b)
            );
            for &c in &ch[b] {
                body(t, ch, c, prefix, out);
            }
            out.push_str("</body>");
        }
        let ch = self.children(reverse);
        let mut out = String::from("<mujoco><worldbody>");
        for &c in &ch[0] {
            body(self, &ch, c, prefix, &mut out);
        }
        out.push_str("</worldbody></mujoco>");
        out
    }

    /// The joints in body order, or reversed.
    fn order(&self, reverse: bool) -> Vec<usize> {
        let mut v: Vec<usize> = (1..=self.parent.len()).collect();
        if reverse {
            v.reverse();
        }
        v
    }

    fn urdf(&self, prefix: &str, reverse: bool) -> String {
        let mut out = format!("<robot name=\"r\"><link name=\"{prefix}0\"/>");
        for b in self.order(reverse) {
            let _ = write!(out, "<link name=\"{prefix}{b}\"/>");
        }
        for b in self.order(reverse) {
            let kind = ["continuous", "prismatic", "floating"][self.kind[b - 1] as usize];
            let _ = write!(
                out,
                "<joint name=\"{prefix}j{b}\" type=\"{kind}\"><parent link=\"{prefix}{}\"/>\
                 <child link=\"{prefix}{b}\"/><origin xyz=\"0 0 1\"/><axis xyz=\"{}\"/>\
                 <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>",
                self.parent[b - 1],
                self.axis(b)
            );
        }
        out.push_str("</robot>");
        out
    }

    fn sdf(&self, prefix: &str, reverse: bool) -> String {
        let mut out = format!(
            "<sdf version=\"1.7\"><model name=\"m\"><link name=\"{prefix}0\"/>\
             <joint name=\"{prefix}fix\" type=\"fixed\"><parent>world</parent>\
             <child>{prefix}0</child></joint>"
        );
        for b in self.order(reverse) {
            let _ = write!(
                out,
                "<link name=\"{prefix}{b}\"><pose>0 0 {b} 0 0 0</pose></link>"
            );
        }
        for b in self.order(reverse) {
            let kind = ["revolute", "prismatic", "ball"][self.kind[b - 1] as usize];
            let _ = write!(
                out,
                "<joint name=\"{prefix}j{b}\" type=\"{kind}\"><parent>{prefix}{}</parent>\
                 <child>{prefix}{b}</child><axis><xyz>{}</xyz></axis></joint>",
                self.parent[b - 1],
                self.axis(b)
            );
        }
        out.push_str("</model></sdf>");
        out
    }

    /// OpenSim 4: the bodies in the BodySet, each joint in the JointSet from an offset frame
    /// on its parent (the ground for body 0) to the child body.
    fn osim(&self, prefix: &str, reverse: bool) -> String {
        let mut out = String::from(
            "<OpenSimDocument Version=\"40000\"><Model name=\"m\"><Ground name=\"ground\"/>\
             <BodySet><objects>",
        );
        for b in self.order(reverse) {
            let _ = write!(out, "<Body name=\"{prefix}{b}\"/>");
        }
        out.push_str("</objects></BodySet><JointSet><objects>");
        for b in self.order(reverse) {
            let (kind, coords) =
                [("PinJoint", 1), ("SliderJoint", 1), ("BallJoint", 3)][self.kind[b - 1] as usize];
            let parent = match self.parent[b - 1] {
                0 => "/ground".to_string(),
                p => format!("/bodyset/{prefix}{p}"),
            };
            let _ = write!(
                out,
                "<{kind} name=\"{prefix}j{b}\"><socket_parent_frame>{prefix}f{b}\
                 </socket_parent_frame><socket_child_frame>/bodyset/{prefix}{b}\
                 </socket_child_frame><coordinates>"
            );
            for c in 0..coords {
                let _ = write!(out, "<Coordinate name=\"{prefix}q{b}_{c}\"/>");
            }
            let _ = write!(
                out,
                "</coordinates><frames><PhysicalOffsetFrame name=\"{prefix}f{b}\">\
                 <socket_parent>{parent}</socket_parent><translation>0 0 1</translation>\
                 <orientation>0 0 0</orientation></PhysicalOffsetFrame></frames></{kind}>"
            );
        }
        out.push_str("</objects></JointSet></Model></OpenSimDocument>");
        out
    }
}

/// Mobility count, bodies and joints of an import, or the error's text.
fn summary(text: &str, format: SourceFormat) -> Result<(i64, usize, usize), String> {
    let opts = ImportOptions {
        format: Some(format),
        ..ImportOptions::default()
    };
    match import_str("fuzz.xml", text, None, &opts) {
        Ok(i) => {
            let m = &i.mechanism;
            let mob = mbsa::mobility::mobility(m);
            Ok((mob.mobility.count, m.bodies.len(), m.joints.len()))
        }
        Err(e) => Err(e.to_string()),
    }
}

/// The mobility count of the tree drawn from `bytes`, written in each format (MJCF, SDFormat,
/// URDF, OpenSim), or the import's error. For `tests/it/fuzz_corpus.rs`; the fuzz binary
/// does not call it.
#[allow(dead_code)]
pub fn tree_mobility(bytes: &[u8]) -> Vec<Result<i64, String>> {
    let t = Tree::from(bytes);
    [
        t.mjcf("b", false),
        t.sdf("b", false),
        t.urdf("b", false),
        t.osim("b", false),
    ]
    .iter()
    .zip(FORMATS)
    .map(|(text, format)| summary(text, format).map(|s| s.0))
    .collect()
}

/// One input through the checks; a panic is a finding.
pub fn run(data: &[u8]) {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let format = FORMATS[(sel & 3) as usize];
    if sel & 4 == 0 {
        // The optional merges rewrite the joints: bits 3 and 4 turn them on.
        let opts = ImportOptions {
            format: Some(format),
            merge_pins: sel & 8 != 0,
            merge_balls: sel & 16 != 0,
            ..ImportOptions::default()
        };
        if let Ok(i) = import_bytes("fuzz.xml", rest, None, &opts) {
            let _ = mbsa::mobility::mobility(&i.mechanism);
            let _ = i.warning_block();
        }
        return;
    }
    let t = Tree::from(rest);
    let write = |prefix: &str, reverse: bool| match format {
        SourceFormat::Mjcf => t.mjcf(prefix, reverse),
        SourceFormat::Sdf => t.sdf(prefix, reverse),
        SourceFormat::Osim => t.osim(prefix, reverse),
        _ => t.urdf(prefix, reverse),
    };
    let a = summary(&write("b", false), format);
    let b = summary(&write("link_", true), format);
    match (&a, &b) {
        (Ok(x), Ok(y)) => assert_eq!(x, y, "renamed and reordered: {a:?} vs {b:?}"),
        (Err(_), Err(_)) => {}
        _ => panic!("one spelling imports, the other not: {a:?} vs {b:?}"),
    }
}
