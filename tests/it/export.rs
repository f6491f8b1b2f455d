//! `mbsa cut` and `mbsa export`: the cuts' closures against the geometric analysis of the
//! whole Jacobian, and the invariant of the export: reading the written MJCF or SDFormat back
//! (`mbsa import`) gives the same analyses as the mechanism (count, inputs, status, true
//! mobility, redundant constraints, isolated freedoms), on every bundled mechanism with
//! geometry and every import fixture.

use mbsa::budget::Budget;
use mbsa::cut::{self, CutOptions};
use mbsa::export::{ExportOptions, Target, export_within};
use mbsa::format::{Format, load};
use mbsa::geometry::GeometrySource;
use mbsa::import::{ImportOptions, import_file, import_str};
use mbsa::rigidity::geometric::{self, GeometricOptions};
use mbsa::structure::{self, Library};
use mbsa::{Mechanism, mobility};

const FIX: &str = "tests/fixtures/import";

/// The import fixtures that import (the others test include errors).
const FIXTURES: &[&str] = &[
    "cassie.xml",
    "include_main.xml",
    "robotiq_2f85.xml",
    "tilted_fourbar.xml",
    "xarm7_hand.xml",
    "four_bar.sdf",
    "stewart_upu.sdf",
    "triple_pin.sdf",
    "four_bar_split_fixed.urdf",
    "ur5.urdf",
    "double_pendulum.osim",
    "four_bar_point_constraint.osim",
];

/// Every bundled mechanism and import fixture, by name.
fn all() -> Vec<(String, Mechanism)> {
    let mut out: Vec<(String, Mechanism)> = mbsa::examples::names()
        .map(|n| {
            let (file, text) = mbsa::examples::find(n).expect("bundled");
            (
                format!("@{n}"),
                load(file, text, Format::Toml).expect("valid"),
            )
        })
        .collect();
    for f in FIXTURES {
        let path = std::path::Path::new(FIX).join(f);
        let m = import_file(&path, &ImportOptions::default()).expect("imports");
        out.push((f.to_string(), m.mechanism));
    }
    out
}

fn released(m: &Mechanism) -> Mechanism {
    let mut m = m.clone();
    for j in &mut m.joints {
        j.driven = 0;
    }
    m
}

#[test]
fn the_closures_redundant_rows_and_mobility_are_the_geometric_analysis_ones() {
    for (name, m) in all() {
        let c = cut::analyze(&m, &CutOptions::default()).expect("cuts");
        let g = geometric::analyze(&released(&m), &GeometricOptions::default()).expect("rigid");
        assert_eq!(
            (c.redundant, c.mobility),
            (g.redundant, g.mobility),
            "{name}: cut (redundant, mobility) vs the geometric analysis"
        );
        let counted = mobility::mobility(&m);
        assert_eq!(c.loops as u64, counted.loops as u64, "{name}: loops");
        assert_eq!(
            c.redundant,
            c.cuts.iter().map(|k| k.redundant).sum::<usize>()
        );
    }
}

/// What the invariant compares: the count, the inputs, the structural status, and the
/// geometric analysis of the chain (true mobility, redundant, isolated).
fn summary(m: &Mechanism, inputs: bool) -> String {
    let count = mobility::mobility(m).mobility.count;
    let opts = structure::Options {
        count_only: false,
        method: structure::Method::Flow,
        geometry: GeometrySource::default(),
        precision: None,
    };
    let g = geometric::analyze(&released(m), &GeometricOptions::default()).expect("rigid");
    let a = structure::analyze(m, &opts, &Library::builtin()).expect("analyze");
    let driven = if inputs {
        format!(
            " inputs {} status {:?} uncontrolled {}",
            m.inputs(),
            a.status,
            a.uncontrolled
        )
    } else {
        String::new()
    };
    format!(
        "count {count} mobility {} redundant {} isolated {}{driven}",
        g.mobility, g.redundant, g.isolated
    )
}

fn export(m: &Mechanism, target: Target, geometry: GeometrySource) -> mbsa::export::Export {
    let opts = ExportOptions {
        target,
        geometry,
        precision: None,
        source: "test".into(),
    };
    export_within(m, &opts, &Budget::DEFAULT).expect("exported")
}

fn read_back(text: &str, target: Target) -> Mechanism {
    let name = match target {
        Target::Mjcf => "exported.xml",
        Target::Sdf => "exported.sdf",
    };
    import_str(name, text, None, &ImportOptions::default())
        .unwrap_or_else(|e| panic!("{name} reads back: {e}\n{text}"))
        .mechanism
}

#[test]
fn reading_an_export_back_gives_the_same_analyses() {
    let mut checked = 0;
    for (name, m) in all() {
        if !mbsa::motion::lacking(&m).is_empty() {
            continue;
        }
        for target in [Target::Mjcf, Target::Sdf] {
            let e = export(&m, target, GeometrySource::File);
            let back = read_back(&e.text, target);
            // SDFormat has no actuators: the inputs are compared through MJCF only.
            let inputs = target == Target::Mjcf;
            assert_eq!(
                summary(&back, inputs),
                summary(&m, inputs),
                "{name} through {}",
                target.name()
            );
            checked += 1;
        }
    }
    assert!(checked >= 60, "{checked} exports checked");
}

#[test]
fn a_random_realization_exports_a_file_without_geometry() {
    let (file, text) = mbsa::examples::find("stewart").expect("bundled");
    let m = load(file, text, Format::Toml).expect("valid");
    let e = export(&m, Target::Mjcf, GeometrySource::Random { seed: 1 });
    let back = read_back(&e.text, Target::Mjcf);
    let g = geometric::analyze(&released(&back), &GeometricOptions::default()).expect("rigid");
    assert_eq!((g.mobility, g.redundant), (6, 0));
    assert_eq!(back.inputs(), 6);
}

#[test]
fn a_planar_mechanism_is_exported_without_redundant_rows() {
    let (file, text) = mbsa::examples::find("n-four-bar-40").expect("bundled");
    let m = load(file, text, Format::Toml).expect("valid");
    for target in [Target::Mjcf, Target::Sdf] {
        let e = export(&m, target, GeometrySource::File);
        assert!(e.warnings.is_empty(), "{:?}", e.warnings);
        let back = read_back(&e.text, target);
        assert_eq!(back.space, mbsa::Space::Spatial);
        let g = geometric::analyze(&back, &GeometricOptions::default()).expect("rigid");
        assert_eq!((g.count, g.mobility, g.redundant), (1, 1, 0));
    }
}

#[test]
fn the_same_input_gives_the_same_bytes() {
    for (name, m) in all().into_iter().filter(|(n, _)| {
        [
            "@bricard",
            "@rig-seven-roof",
            "cassie.xml",
            "stewart_upu.sdf",
        ]
        .contains(&n.as_str())
    }) {
        for target in [Target::Mjcf, Target::Sdf] {
            let a = export(&m, target, GeometrySource::File).text;
            let b = export(&m.clone(), target, GeometrySource::File).text;
            assert_eq!(a, b, "{name}");
        }
    }
}

use super::common::mbsa;

#[test]
fn the_command_line_warns_of_redundant_rows_and_refuses_missing_geometry() {
    let (code, out, err) = mbsa(&["export", "@bricard", "--to", "mjcf"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("<!-- Bricard linkage: written by mbsa export"));
    assert!(
        err.contains("warning: the MJCF export carries 1 redundant constraint row(s), in the closure(s) of `Pin_6` (1)"),
        "{err}"
    );
    assert!(out.contains("<!-- warning: the MJCF export carries 1 redundant constraint row(s)"));
    let (code, _, err) = mbsa(&["export", "@four-bar", "--to", "sdf"]);
    assert_eq!(code, 2);
    assert!(
        err.starts_with("error: @four-bar: 4 joint(s) lack the geometry an export writes: A (R: origin), B (R: origin)"),
        "{err}"
    );
    assert!(err.contains("--geometry random"), "{err}");
}

#[test]
fn cut_json_names_the_tree_and_each_closure() {
    let (code, out, err) = mbsa(&["cut", "@stewart", "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(v["format_version"], 1);
    assert_eq!(v["loops"], 6);
    let cuts = v["cuts"].as_array().expect("cuts");
    assert!(
        cuts.iter()
            .all(|c| c["why"] == "spherical" && c["rows"] == 3)
    );
    assert_eq!(v["tree"].as_array().expect("tree").len(), 13);
    assert_eq!(v["geometry_used"]["mode"], "random");
}

#[test]
fn a_work_limit_stops_the_cuts_with_the_flag_named() {
    let (code, _, err) = mbsa(&["cut", "@n-four-bar-40", "--max-work", "1000"]);
    assert_eq!(code, 2);
    assert!(err.contains("--max-work"), "{err}");
}

#[test]
fn a_tree_deeper_than_mujoco_reads_continues_at_the_top_level() {
    let m = mbsa::generate::serial_chain(1000, mbsa::JointType::C, false, true).expect("chain");
    let e = export(&m, Target::Mjcf, GeometrySource::Random { seed: 3 });
    // Every 400th level continues in a top-level body with a free joint.
    assert_eq!(e.text.matches("<freejoint").count(), 2);
    assert!(e.text.contains("The tree is deeper than 400 bodies"));
    let depth = e
        .text
        .lines()
        .map(|l| l.len() - l.trim_start().len())
        .max()
        .unwrap_or(0);
    assert!(depth <= 2 * 25, "indentation {depth}");
    let back = read_back(&e.text, Target::Mjcf);
    assert_eq!(back.inputs(), m.inputs());
    let g = geometric::analyze(&released(&back), &GeometricOptions::default()).expect("rigid");
    assert_eq!((g.mobility, g.redundant), (2 * 999, 0));
}
