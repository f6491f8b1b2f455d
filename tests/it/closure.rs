//! Issue 14 item 2, the closure check: a configuration written with `second` geometry (the
//! joint as carried by its second body) that misses closure is reported by every command that
//! uses the file's geometry (table and JSON), warned about, refused when grossly open, and
//! closed by `mbsa assemble`; the importers keep the gap of a real model's keyframe.

use assert_cmd::Command;
use mbsa::JointType;
use mbsa::mechanism::{BodyId, Geometry, JointSpec, Mechanism, Second, Space};
use mbsa::position::{ClosureStatus, Configuration, PositionModel, file_closure};
use mbsa::rng::SplitMix64;

const FIX: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures");

fn mbsa(args: &[&str]) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .output()
        .expect("mbsa runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn mbsa_stdin(args: &[&str], input: &str) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .write_stdin(input)
        .output()
        .expect("mbsa runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn snapshot(name: &str, value: &str) {
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!(name, value);
    });
}

fn gap() -> String {
    format!("{FIX}/closure/four-bar-gap.toml")
}

fn broken() -> String {
    format!("{FIX}/closure/four-bar-broken.toml")
}

fn json(args: &[&str]) -> serde_json::Value {
    let (code, out, err) = mbsa(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    serde_json::from_str(&out).expect("JSON")
}

#[test]
fn a_four_bar_with_a_gap_is_reported_in_analyze_and_rigid_with_a_warning() {
    let (code, out, err) = mbsa(&["analyze", &gap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.starts_with("warning: ")
            && err.contains("misses closure by 1.000e-2")
            && err.contains("joint(s) C (1.000e-2)"),
        "{err}"
    );
    assert!(
        out.contains("closure (warning)") && out.contains("  joint C: 1.000e-2"),
        "{out}"
    );
    snapshot("closure_analyze_four-bar-gap", &out);
    snapshot(
        "closure_warning_four-bar-gap",
        &err.replace(FIX, "tests/fixtures"),
    );
    let (code, out, err) = mbsa(&["rigid", &gap(), "--method", "geometric"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("misses closure by 1.000e-2"), "{err}");
    snapshot("closure_rigid_four-bar-gap", &out);
    // JSON: the closure section of the geometry used.
    let v = json(&["analyze", &gap(), "--format", "json"]);
    let c = &v["geometry"]["closure"];
    assert_eq!(c["status"], "open", "{c}");
    assert_eq!(c["max_residual"], 0.01, "{c}");
    assert_eq!(c["joints"][0]["joint"], "C", "{c}");
    assert_eq!(c["joints"].as_array().map(Vec::len), Some(1), "{c}");
    let v = json(&["rigid", &gap(), "--format", "json", "--method", "geometric"]);
    let c = &v["geometry_used"]["closure"];
    assert_eq!(c["status"], "open", "{c}");
    assert_eq!(c["joints"][0]["residual"], 0.01, "{c}");
    // The first-order results are the first body's geometry's: the closed four-bar's.
    assert_eq!(v["mobility"], 1, "{v}");
    assert_eq!(v["redundant"], 3, "{v}");
    // Every command that uses the file's geometry warns: dot, transform, check.
    for args in [
        vec!["dot", gap().leak() as &str],
        vec!["transform", gap().leak(), "--top", "1"],
        vec!["check", gap().leak()],
    ] {
        let (code, _, err) = mbsa(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(
            err.contains("misses closure by 1.000e-2"),
            "{args:?}: {err}"
        );
    }
    // Random geometry does not use the file's configuration: nothing to say.
    let (code, out, err) = mbsa(&["analyze", &gap(), "--geometry", "random"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty() && !out.contains("closure"), "{err}{out}");
    // Counting only: no geometry, no check.
    let (_, _, err) = mbsa(&["analyze", &gap(), "--count-only"]);
    assert!(err.is_empty(), "{err}");
}

/// `dot` carries the closure line under its title in every view when the configuration
/// misses closure (as `analyze`'s closure section); a closed file's pictures have none.
#[test]
fn dot_titles_carry_the_closure_line_of_an_open_file() {
    for view in ["diagram", "structure", "topology", "rigid"] {
        let (code, out, err) = mbsa(&["dot", &gap(), "--view", view]);
        assert_eq!(code, 0, "{view}: {err}");
        let label = out
            .lines()
            .find(|l| l.trim_start().starts_with("graph ["))
            .unwrap_or_default();
        assert!(
            label.contains("\\nclosure (warning): the configuration misses closure by up to 1.000e-2 at 1 joint(s)")
                && label.contains("\\n  joint C: 1.000e-2"),
            "{view}: {label}"
        );
        if view == "diagram" {
            snapshot("closure_dot_four-bar-gap", &out);
        }
    }
    // Closed: the title alone.
    let (code, out, err) = mbsa(&[
        "dot",
        "mechanisms/four-bar-3d-driven.toml",
        "--view",
        "structure",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("closure"), "{out}");
}

/// `rigid --finite` on an open file does not start from a configuration that is not one: it
/// assembles first (as `mbsa assemble`), says so in the first note (table and JSON), and
/// gives the same answer as on the assembled file.
#[test]
fn rigid_finite_on_an_open_file_assembles_first() {
    for method in ["geometric", "counting"] {
        let (code, out, err) = mbsa(&["rigid", &gap(), "--finite", "--method", method]);
        assert_eq!(code, 0, "{method}: {err}");
        assert!(
            err.contains("misses closure by 1.000e-2"),
            "{method}: {err}"
        );
        assert!(
            out.contains("- the file's configuration misses closure by up to 1.000e-2 at joint(s) C: analysed at the assembled configuration"),
            "{method}: {out}"
        );
    }
    let v = json(&["rigid", &gap(), "--finite", "--format", "json"]);
    let f = &v["finite"];
    assert_eq!(f["assembled"], true, "{f}");
    assert_eq!(
        (f["first_order"].as_u64(), f["finite"].as_u64()),
        (Some(1), Some(1)),
        "{f}"
    );
    assert_eq!(f["verdict"], "overconstrained_moving", "{f}");
    // The assembled file says the same, without the note.
    let (code, closed, err) = mbsa(&["assemble", &gap()]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = mbsa_stdin(&["rigid", "-", "--finite", "--format", "json"], &closed);
    assert_eq!(code, 0, "{err}");
    let w: serde_json::Value = serde_json::from_str(&out).unwrap();
    let g = &w["finite"];
    assert!(g.get("assembled").is_none(), "{g}");
    for k in ["count", "first_order", "finite", "verdict", "samples"] {
        assert_eq!(f[k], g[k], "{k}");
    }
    // A closed file: no note, no flag.
    let v = json(&[
        "rigid",
        "mechanisms/four-bar-3d-driven.toml",
        "--finite",
        "--format",
        "json",
    ]);
    assert!(v["finite"].get("assembled").is_none(), "{v}");
}

#[test]
fn a_gross_gap_is_an_error_naming_the_joint() {
    for cmd in ["analyze", "rigid", "dot", "transform", "check"] {
        let (code, out, err) = mbsa(&[cmd, &broken()]);
        assert_eq!(code, 2, "{cmd}: {out}{err}");
        assert!(
            err.contains("joint `C` is open by 1.000e-1")
                && err.contains("more than 2.3e-2")
                && err.contains("`mbsa assemble"),
            "{cmd}: {err}"
        );
    }
    // `--geometry file` and `auto` alike: no silent fall-back to a random realization.
    let (code, _, err) = mbsa(&["analyze", &broken(), "--geometry", "file"]);
    assert_eq!(code, 2, "{err}");
    snapshot(
        "closure_error_four-bar-broken",
        &err.replace(FIX, "tests/fixtures"),
    );
    // solve says it too (and `--assemble` closes first).
    let (code, _, err) = mbsa(&["solve", &broken(), "--set", "A=10"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("joint(s) C (1.000e-1)"), "{err}");
    let (code, _, err) = mbsa(&["solve", &broken(), "--set", "A=10", "--assemble"]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn assemble_closes_the_gap_and_the_result_analyzes_clean() {
    for file in [gap(), broken()] {
        let (code, toml, err) = mbsa(&["assemble", &file]);
        assert_eq!(code, 0, "{err}");
        assert!(toml.starts_with("# assembled by mbsa"), "{toml}");
        assert!(!toml.contains("second"), "{toml}");
        let (code, out, err) = mbsa_stdin(&["analyze", "-"], &toml);
        assert_eq!(code, 0, "{err}");
        assert!(err.is_empty(), "{err}");
        assert!(out.contains("closure: every joint closed"), "{out}");
        let (code, out, err) = mbsa_stdin(&["rigid", "-", "--format", "json"], &toml);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(
            v["geometric"]["geometry_used"]["closure"]["status"],
            "closed"
        );
        assert_eq!(v["geometric"]["mobility"], 1, "{out}");
        // The crank pivot and the rocker pivot stay; the loop now closes at C.
        assert!(toml.contains("origin = [1.93, -0.08, 0.0]"), "{toml}");
    }
}

#[test]
fn cassie_home_keyframe_shows_its_gap_from_the_real_model() {
    let cassie = format!("{FIX}/import/cassie.xml");
    let (code, toml, err) = mbsa(&["import", &cassie, "--keyframe", "home"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(toml.matches("second = { origin = [").count(), 4, "{toml}");
    // At qpos0 the loops close: no `second`.
    let (code, toml0, _) = mbsa(&["import", &cassie]);
    assert_eq!(code, 0);
    assert!(!toml0.contains("second"), "{toml0}");
    let v = json(&[
        "rigid",
        &cassie,
        "--keyframe",
        "home",
        "--format",
        "json",
        "--method",
        "geometric",
    ]);
    let c = &v["geometry_used"]["closure"];
    assert_eq!(c["status"], "open", "{c}");
    let worst = c["max_residual"].as_f64().unwrap();
    assert!((worst - 1.9495e-3).abs() < 1e-6, "{c}");
    let by: std::collections::BTreeMap<String, f64> = c["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| {
            (
                j["joint"].as_str().unwrap().to_string(),
                j["residual"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(by.len(), 4, "{c}");
    for side in ["left", "right"] {
        let foot = by[&format!("connect:{side}-plantar-rod-{side}-foot")];
        let heel = by[&format!("connect:{side}-achilles-rod-{side}-heel-spring")];
        assert!((foot - 1.9495e-3).abs() < 1e-6, "{side}: {foot}");
        assert!((heel - 5.9e-4).abs() < 1e-6, "{side}: {heel}");
    }
    // Same numbers as at the closed configuration (the first bodies' geometry).
    assert_eq!(v["mobility"], 22);
    assert_eq!(v["redundant"], 2);
    let (code, out, err) = mbsa(&["rigid", &cassie, "--keyframe", "home"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("misses closure by 1.949e-3")
            && out.contains("joint connect:left-plantar-rod-left-foot: 1.949e-3"),
        "{err}{out}"
    );
    // `mbsa assemble` closes the four loops.
    let (code, closed, err) = mbsa_stdin(&["assemble", "-"], &toml);
    assert_eq!(code, 0, "{err}");
    assert!(closed.starts_with("# assembled by mbsa: largest joint residual 1.949e-3 before"));
    let (code, out, err) = mbsa_stdin(&["rigid", "-", "--format", "json"], &closed);
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty(), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        v["geometric"]["geometry_used"]["closure"]["status"],
        "closed"
    );
    assert_eq!(v["geometric"]["mobility"], 22);
}

#[test]
fn second_where_it_makes_no_sense_is_a_located_error() {
    let base = "frame = 1\n[[joint]]\nbodies = [1, 2]\n";
    for (joint, name) in [
        (
            "type = \"S\"\norigin = [0, 0, 0]\nsecond = { origin = [0, 0, 1], axis = [0, 0, 1] }\n",
            "closure_format_second_axis_on_s",
        ),
        (
            "type = \"SPSP\"\norigin = [0, 0, 0]\norigin2 = [1, 0, 0]\nsecond = { origin = [0, 1, 0] }\n",
            "closure_format_second_on_spsp",
        ),
        (
            "type = \"R\"\norigin = [0, 0, 0]\naxis = [0, 0, 1]\nsecond = { centre = [0, 0, 1] }\n",
            "closure_format_second_unknown_key",
        ),
    ] {
        let text = format!("{base}{joint}");
        let (code, _, err) = mbsa_stdin(&["analyze", "-"], &text);
        assert_eq!(code, 2, "{text}\n{err}");
        snapshot(name, &err);
    }
    let multiple = "frame = 1\n[[joint]]\ntype = \"S\"\nbodies = [1, 2, 3]\norigin = [0, 0, 0]\nsecond = { origin = [0, 0, 1] }\n";
    let (code, _, err) = mbsa_stdin(&["analyze", "-"], multiple);
    assert_eq!(code, 2);
    assert!(
        err.contains("a multiple joint (3 bodies) has no `second`"),
        "{err}"
    );
}

fn one_joint(kind: JointType, space: Space, g: Geometry) -> Mechanism {
    Mechanism::from_parts(
        "one",
        space,
        BodyId::Int(1),
        vec![],
        vec![JointSpec {
            id: Some("J".into()),
            kind,
            bodies: vec![BodyId::Int(1), BodyId::Int(2)],
            driven: 0,
            geometry: g,
        }],
    )
}

fn v(r: &mut SplitMix64) -> [f64; 3] {
    [r.next_signed(), r.next_signed(), r.next_signed()]
}

/// Every kind that accepts `second`: the residual at the reference is the gap of the point
/// (or of the direction), the Jacobian matches finite differences with the offset, and a
/// `second` equal to the first geometry is closed.
#[test]
fn second_geometry_residuals_and_jacobians() {
    use JointType::*;
    let cases: &[(Space, &[JointType])] = &[
        (Space::Spatial, &[R, P, H, C, ER, U, S, PL, SP, SC, PC, CR]),
        (Space::Planar, &[R, P]),
        (Space::Spherical, &[R]),
    ];
    for &(space, kinds) in cases {
        let b = space.b() as usize;
        for &kind in kinds {
            let mut r = SplitMix64::new(kind as u64 + 100 * b as u64);
            let axis = [0.0, 0.0, 1.0];
            let mut g = Geometry {
                origin: Some(if space == Space::Spherical {
                    [0.0; 3]
                } else {
                    [0.3, -0.2, 0.0]
                }),
                axis: Some(if space == Space::Planar && kind == P {
                    [1.0, 0.0, 0.0]
                } else {
                    axis
                }),
                axis2: Some([1.0, 0.0, 0.0]),
                normal: Some(if matches!(kind, PC | CR) {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 0.0, 1.0]
                }),
                pitch: Some(0.1),
                ..Geometry::default()
            };
            // Closed: `second` equal to the first.
            let mut same = Second::default();
            for f in Second::fields(kind, space) {
                match *f {
                    "origin" => same.origin = g.origin,
                    "axis" => same.axis = g.axis,
                    "axis2" => same.axis2 = g.axis2,
                    _ => same.normal = g.normal,
                }
            }
            g.second = Some(Box::new(same));
            let m = one_joint(kind, space, g.clone());
            let c = file_closure(&m, None).unwrap();
            assert_eq!(c.status, ClosureStatus::Closed, "{kind:?} {space:?}: {c:?}");
            // Open: a moved point and a tilted axis.
            let mut open = Second::default();
            for f in Second::fields(kind, space) {
                let d = v(&mut r);
                match *f {
                    "origin" if space == Space::Planar => {
                        open.origin = Some([0.3 + 0.01 * d[0], -0.2 + 0.01 * d[1], 0.0])
                    }
                    "origin" => {
                        open.origin = Some([0.3 + 0.01 * d[0], -0.2 + 0.01 * d[1], 0.01 * d[2]])
                    }
                    "axis" if space == Space::Planar => open.axis = Some([1.0, 0.02, 0.0]),
                    "axis" if matches!(kind, PC | CR) => open.axis = Some([0.0, 0.02, 1.0]),
                    "axis" => open.axis = Some([0.02 * d[0], 0.02 * d[1], 1.0]),
                    "axis2" => open.axis2 = Some([1.0, 0.02 * d[1], 0.02 * d[2]]),
                    _ => open.normal = Some([0.02 * d[0], 0.02 * d[1], 1.0]),
                }
            }
            g.second = Some(Box::new(open));
            let m = one_joint(kind, space, g);
            let c = file_closure(&m, None).unwrap();
            assert_ne!(c.status, ClosureStatus::Closed, "{kind:?} {space:?}: {c:?}");
            let model = PositionModel::new(&m).unwrap();
            let pa = mbsa::position::Pose::identity().moved_by(
                space,
                &(0..b).map(|_| 0.2 * r.next_signed()).collect::<Vec<_>>(),
            );
            let pb = mbsa::position::Pose::identity().moved_by(
                space,
                &(0..b).map(|_| 0.2 * r.next_signed()).collect::<Vec<_>>(),
            );
            let e = model.pair_equations(0, &pa, &pb, &[]);
            let h = 1e-6;
            for side in 0..2 {
                for k in 0..b {
                    let mut t = vec![0.0; b];
                    t[k] = h;
                    let tm: Vec<f64> = t.iter().map(|x| -x).collect();
                    let (ap, am, bp, bm) = if side == 0 {
                        (pa.moved_by(space, &t), pa.moved_by(space, &tm), pb, pb)
                    } else {
                        (pa, pa, pb.moved_by(space, &t), pb.moved_by(space, &tm))
                    };
                    let ep = model.pair_equations(0, &ap, &bp, &[]);
                    let em = model.pair_equations(0, &am, &bm, &[]);
                    for i in 0..e.residual.len() {
                        let fd = (ep.residual[i] - em.residual[i]) / (2.0 * h);
                        let an = e.jacobian[(i, side * b + k)];
                        assert!(
                            (fd - an).abs() < 1e-5 * (1.0 + an.abs()),
                            "{kind:?} {space:?} row {i} col {side}/{k}: fd {fd} analytic {an}"
                        );
                    }
                }
            }
        }
    }
}

/// The gap of a point joint is the distance of its two points, exactly.
#[test]
fn a_point_gap_is_the_distance_of_the_points() {
    let g = Geometry {
        origin: Some([1.0, 2.0, 3.0]),
        second: Some(Box::new(Second {
            origin: Some([1.0, 2.03, 3.04]),
            ..Second::default()
        })),
        ..Geometry::default()
    };
    // A second joint so the model size is 10 (the gap stays below the gross limit 0.1).
    let mut m = one_joint(JointType::S, Space::Spatial, g);
    let mut far = m.joints[0].clone();
    far.id = "K".into();
    far.geometry = Geometry {
        origin: Some([1.0, 2.0, 13.0]),
        ..Geometry::default()
    }
    .into();
    m.joints.push(far);
    let c = file_closure(&m, None).unwrap();
    assert_eq!(c.status, ClosureStatus::Open);
    assert!((c.max_residual - 0.05).abs() < 1e-12, "{c:?}");
    // The check at the reference configuration of the full model agrees.
    let full =
        mbsa::position::check_closure(&m, &Configuration::reference(m.bodies.len()), None).unwrap();
    assert_eq!(full.max_residual, c.max_residual);
}

/// `second` survives writing and reading a mechanism file.
#[test]
fn second_round_trips_through_the_writer() {
    let text = std::fs::read_to_string(gap()).unwrap();
    let m = mbsa::format::load("gap.toml", &text, mbsa::format::Format::Toml).unwrap();
    let written = mbsa::generate::to_toml(&m);
    assert!(
        written.contains("second = { origin = [1.42, 1.22, 0.0] }"),
        "{written}"
    );
    let back = mbsa::format::load("back.toml", &written, mbsa::format::Format::Toml).unwrap();
    assert_eq!(back.joints, m.joints);
}
