//! File geometry written in millimetres far from the world origin: the rank decisions must not
//! depend on where the model sits or on its length unit's size. A planar four-bar and a row of
//! ten windows, pins at about (1000, 500) mm with two decimals (known to ±0.005 mm): the
//! geometric analysis said mobility 9 and 63 (the rounding threshold multiplied every written
//! number by the largest coordinate), then 2 and 11 with the point/direction split alone
//! (twists about the world origin lose the decision); with the body-local twists of the
//! sparse path it says 1, as the same files written near the origin do. Since the geometry is
//! made dimensionless before every rank decision (points about their centre, lengths in link
//! lengths), a spatial and a planar four-bar get the same numbers from `rigid`, `analyze` and
//! `check` in m, mm and µm, near the origin or 10^4 units from it.

use assert_cmd::Command;
use std::fmt::Write;

/// An N-four-bar (IFToMM A02 layout, generic: vertical bars leaning by (0.6, 0.8)) scaled by
/// 100.3 mm and moved to (1000.17, 500.23) mm, rounded to 2 decimals.
fn n_four_bar_mm(n: usize) -> String {
    let (s, ox, oy) = (100.3, 1000.17, 500.23);
    let mut out = format!("name = \"N-four-bar in mm (N = {n})\"\nspace = \"planar\"\nframe = 1\n");
    let mut joint = |id: String, a: usize, b: usize, x: f64, y: f64| {
        let (x, y) = (
            ((ox + s * x) * 100.0).round() / 100.0,
            ((oy + s * y) * 100.0).round() / 100.0,
        );
        let _ = write!(
            out,
            "\n[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, {y}]\n"
        );
    };
    joint("A0".into(), 1, 2, 0.0, 0.0);
    for k in 1..=n {
        let kf = k as f64;
        joint(
            format!("VB{}", k - 1),
            2 * k,
            2 * k + 1,
            kf - 1.0 + 0.6,
            0.8,
        );
        joint(format!("B{k}"), 2 * k + 1, 2 * k + 2, kf + 0.6, 0.8);
        joint(format!("P{k}"), 1, 2 * k + 2, kf, 0.0);
    }
    out
}

fn true_mobility(text: &str) -> String {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(["rigid", "--method", "geometric", "-"])
        .write_stdin(text)
        .output()
        .expect("mbsa runs");
    assert_eq!(out.status.code(), Some(0));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    stdout
        .lines()
        .find(|l| l.contains("true mobility"))
        .unwrap_or("")
        .to_string()
}

#[test]
fn a_planar_four_bar_in_millimetres_far_from_the_origin_moves_with_one_dof() {
    for n in [1, 10] {
        let text = n_four_bar_mm(n);
        assert!(text.contains("origin = [1000.17, 500.23]"), "{text}");
        assert_eq!(
            true_mobility(&text),
            "count 1; true mobility 1",
            "{n} windows"
        );
    }
}

/// The four pins of a four-bar in millimetres (links of 100.3 mm, a parallelogram leaning by
/// (0.6, 0.8)), far from the origin; z = 250.5 is known to ±0.05 mm only.
const PINS_MM: [[f64; 3]; 4] = [
    [1000.17, 500.23, 250.5],
    [1060.35, 580.47, 250.5],
    [1160.65, 580.47, 250.5],
    [1100.47, 500.23, 250.5],
];

/// The same four-bar written in another unit and place: a point `p` (mm) is written
/// `(p + shift) · factor`, rounded to `decimals`.
#[derive(Clone, Copy, Debug)]
struct Units {
    label: &'static str,
    shift: [f64; 3],
    factor: f64,
    decimals: i32,
}

const VARIANTS: [Units; 5] = [
    // Metres near the origin: the reference (twists about the origin are well conditioned).
    Units {
        label: "m near the origin",
        shift: [-1080.0, -540.0, -250.0],
        factor: 1e-3,
        decimals: 5,
    },
    Units {
        label: "m",
        shift: [0.0; 3],
        factor: 1e-3,
        decimals: 5,
    },
    Units {
        label: "mm",
        shift: [0.0; 3],
        factor: 1.0,
        decimals: 2,
    },
    Units {
        label: "µm",
        shift: [0.0; 3],
        factor: 1e3,
        decimals: 0,
    },
    Units {
        label: "mm translated by 1e4",
        shift: [1e4; 3],
        factor: 1.0,
        decimals: 2,
    },
];

/// A four-bar (bodies 1-4, frame 1, R joints A-D) at [`PINS_MM`] written in `u`: spatial
/// (axes z) or planar.
fn four_bar(u: Units, spatial: bool) -> String {
    let space = if spatial { "spatial" } else { "planar" };
    let mut out = format!("name = \"four-bar\"\nspace = \"{space}\"\nframe = 1\n");
    let scale = 10f64.powi(u.decimals);
    for (k, (p, (a, b))) in PINS_MM
        .iter()
        .zip([(1, 2), (2, 3), (3, 4), (4, 1)])
        .enumerate()
    {
        let q: Vec<String> = (0..if spatial { 3 } else { 2 })
            .map(|i| {
                format!(
                    "{}",
                    ((p[i] + u.shift[i]) * u.factor * scale).round() / scale
                )
            })
            .collect();
        let _ = write!(
            out,
            "\n[[joint]]\nid = \"{}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{}]\n{}",
            ["A", "B", "C", "D"][k],
            q.join(", "),
            if spatial { "axis = [0, 0, 1]\n" } else { "" }
        );
    }
    out
}

fn run(args: &[&str], text: &str) -> (Option<i32>, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .write_stdin(text)
        .output()
        .expect("mbsa runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

/// The numbers of `rigid --method geometric`: count, true mobility, redundant constraints,
/// rows, rank, unknowns, isolated DOF (from the JSON report).
fn rigid_numbers(text: &str) -> Vec<i64> {
    let (code, out) = run(
        &["rigid", "--method", "geometric", "--format", "json", "-"],
        text,
    );
    assert_eq!(code, Some(0), "{out}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("a JSON report");
    let r = v.get("geometric").unwrap_or(&v);
    [
        "count",
        "mobility",
        "redundant",
        "rows",
        "rank",
        "columns",
        "isolated",
    ]
    .iter()
    .map(|k| r[*k].as_i64().unwrap_or_else(|| panic!("`{k}` in {out}")))
    .collect()
}

/// `analyze`'s verdict: every line but the geometry's (its precision is in the unit written)
/// and the closure's.
fn analyze_verdict(text: &str) -> String {
    let (code, out) = run(&["analyze", "-"], text);
    assert_eq!(code, Some(0), "{out}");
    out.lines()
        .filter(|l| !l.starts_with("geometry:") && !l.starts_with("closure:"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// `check` with the expectations of the four-bar as analysed in metres near the origin.
fn check_passes(text: &str, expect: &str) -> (Option<i32>, String) {
    run(&["check", "-"], &format!("{text}\n[expect]\n{expect}"))
}

#[test]
fn four_bars_in_any_unit_and_place_get_the_same_verdicts() {
    // (spatial, rigid numbers, analyze's summary, expectations for `check`), the numbers
    // being those of the metres file near the origin: a spatial four-bar counts -2 (6·3 −
    // 4·5) but moves with 1 DOF, its 3 redundant constraints set aside at the file's
    // configuration; a planar one counts and moves 1.
    let cases = [
        (
            true,
            [-2, 1, 3, 20, 17, 18, 0],
            "count -2, true mobility 1, inputs 0; under-determined",
            "mobility = -2\ntrue_mobility = 1\nredundant = 3\nisolated = 0\ngroups = 0\n\
             determined = false\nuncontrolled = 1\n",
        ),
        (
            false,
            [1, 1, 0, 8, 8, 9, 0],
            "mobility 1, inputs 0; under-determined",
            "mobility = 1\ntrue_mobility = 1\nredundant = 0\nisolated = 0\ngroups = 0\n\
             determined = false\nuncontrolled = 1\n",
        ),
    ];
    for (spatial, numbers, summary, expect) in cases {
        let reference = four_bar(VARIANTS[0], spatial);
        let verdict = analyze_verdict(&reference);
        assert!(verdict.contains(summary), "{verdict}");
        for u in VARIANTS {
            let text = four_bar(u, spatial);
            let what = format!(
                "{} ({})",
                u.label,
                if spatial { "spatial" } else { "planar" }
            );
            assert_eq!(rigid_numbers(&text), numbers, "{what}:\n{text}");
            assert_eq!(analyze_verdict(&text), verdict, "{what}:\n{text}");
            let (code, out) = check_passes(&text, expect);
            assert_eq!(code, Some(0), "{what}: {out}");
        }
    }
}

/// A bar between two balls spins about the line of their centres: its axis is reported in
/// the file's units and place, though the rank decisions ran on the dimensionless geometry.
#[test]
fn an_isolated_spin_in_millimetres_is_reported_in_millimetres() {
    let text = "name = \"SS bar\"\nspace = \"spatial\"\nframe = 1\n\
        \n[[joint]]\nid = \"A\"\ntype = \"S\"\nbodies = [1, 2]\norigin = [1000.17, 500.23, 250.5]\n\
        \n[[joint]]\nid = \"B\"\ntype = \"S\"\nbodies = [2, 1]\norigin = [1100.47, 580.47, 250.5]\n";
    let (code, out) = run(
        &["rigid", "--method", "geometric", "--format", "json", "-"],
        text,
    );
    assert_eq!(code, Some(0), "{out}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("a JSON report");
    let r = v.get("geometric").unwrap_or(&v);
    assert_eq!(r["mobility"], 1, "{out}");
    let axis = &r["isolated_motions"][0]["axis"];
    assert_eq!(axis["kind"], "rotation", "{out}");
    let get = |k: &str| -> [f64; 3] {
        let a = axis[k].as_array().unwrap_or_else(|| panic!("{k} in {out}"));
        [0, 1, 2].map(|i| a[i].as_f64().unwrap_or(f64::NAN))
    };
    let (p, d) = (get("point"), get("direction"));
    // The point lies on the line through both centres, the direction along it.
    let (a, b) = (PINS_MM[0], [1100.47, 580.47, 250.5]);
    let ab: Vec<f64> = (0..3).map(|i| b[i] - a[i]).collect();
    let len = ab.iter().map(|x| x * x).sum::<f64>().sqrt();
    let ap: Vec<f64> = (0..3).map(|i| p[i] - a[i]).collect();
    let cross = [
        ap[1] * ab[2] - ap[2] * ab[1],
        ap[2] * ab[0] - ap[0] * ab[2],
        ap[0] * ab[1] - ap[1] * ab[0],
    ];
    let off = cross.iter().map(|x| x * x).sum::<f64>().sqrt() / len;
    assert!(
        off < 1e-6,
        "the axis point {p:?} is {off} mm off the line: {out}"
    );
    let along = (0..3).map(|i| d[i] * ab[i] / len).sum::<f64>().abs();
    assert!((along - 1.0).abs() < 1e-9, "direction {d:?}: {out}");
}

/// The N-four-bar of [`n_four_bar_mm`] written in metres (5 decimals: the same ±0.005 mm).
fn n_four_bar_m(n: usize) -> String {
    let mm = n_four_bar_mm(n);
    mm.lines()
        .map(|l| match l.strip_prefix("origin = [") {
            Some(rest) => {
                let nums: Vec<String> = rest
                    .trim_end_matches(']')
                    .split(", ")
                    .map(|x| {
                        let v: f64 = x.parse().expect("a number");
                        format!("{}", (v * 1e-3 * 1e5).round() / 1e5)
                    })
                    .collect();
                format!("origin = [{}]", nums.join(", "))
            }
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// `analyze` on a long row of windows agrees with `rigid`: mobility 1, under-determined, no
/// isolated freedom and no equation too many, in metres and in millimetres, from 10 to 1,000
/// windows. With the earlier rank check the 1,000-window files got about 1,000 isolated freedoms and
/// "over-determined" (twists about the centre, 500 link lengths away).
#[test]
fn analyze_agrees_with_rigid_on_long_rows_of_windows() {
    for n in [10, 100, 1000] {
        for (unit, text) in [("mm", n_four_bar_mm(n)), ("m", n_four_bar_m(n))] {
            let what = format!("{n} windows in {unit}");
            assert_eq!(true_mobility(&text), "count 1; true mobility 1", "{what}");
            let verdict = analyze_verdict(&text);
            assert!(
                verdict.contains("mobility 1, inputs 0; under-determined"),
                "{what}: {verdict}"
            );
            assert!(!verdict.contains("isolated"), "{what}: {verdict}");
            assert!(!verdict.contains("too many"), "{what}: {verdict}");
            // `dot` draws the same verdict: no body in the over-determined colour.
            let (code, out) = run(&["dot", "--view", "structure", "-"], &text);
            assert_eq!(code, Some(0), "{what}: {out}");
            assert!(out.contains("#f9d68a"), "{what}: under-determined bodies");
            assert!(!out.contains("#f4a6a6"), "{what}: over-determined bodies");
        }
    }
}

/// The N-four-bar of [`n_four_bar_mm`] written in space: R joints with parallel axes (z), the
/// pins at z = 250.5 mm.
fn n_four_bar_mm_in_space(n: usize) -> String {
    n_four_bar_mm(n)
        .replace("space = \"planar\"", "space = \"spatial\"")
        .lines()
        .map(|l| match l.strip_prefix("origin = [") {
            Some(rest) => format!(
                "origin = [{}, 250.5]\naxis = [0, 0, 1]",
                rest.trim_end_matches(']')
            ),
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// A long row of windows written in space: `analyze` sets aside the constraints its
/// configuration satisfies (three per window) and answers as `rigid` does, one DOF no input
/// fixes, at 100 and 1,000 windows too. The earlier set-aside was dense only (blocks
/// of at most 1,200 unknowns): from 100 windows (1,206 unknowns) `analyze` said "299
/// equation(s) too many" and over-determined, and the block after the set-aside was left to
/// the count unchecked.
#[test]
fn analyze_sets_aside_the_redundant_constraints_of_long_rows_of_windows_in_space() {
    for n in [10, 100, 1000] {
        let text = n_four_bar_mm_in_space(n);
        assert!(text.contains("axis = [0, 0, 1]"), "{text}");
        let what = format!("{n} windows in space");
        let count = 1 - 3 * n as i64;
        assert_eq!(
            true_mobility(&text),
            format!("count {count}; true mobility 1"),
            "{what}"
        );
        let verdict = analyze_verdict(&text);
        assert!(
            verdict.contains("- 1 DOF not fixed by any input"),
            "{what}: {verdict}"
        );
        assert!(
            verdict.contains(&format!("{} redundant constraint(s) set aside", 3 * n)),
            "{what}: {verdict}"
        );
        assert!(!verdict.contains("too many"), "{what}: {verdict}");
        assert!(!verdict.contains("isolated"), "{what}: {verdict}");
        assert!(
            !verdict.contains("left"),
            "{what}: unchecked blocks: {verdict}"
        );
    }
}

#[test]
fn redundancy_that_fights_nothing_leaves_the_verdict_under_determined() {
    // (bundled mechanism, geometry, verdict): redundant constraints set aside at the file's
    // configuration, or found with no input driven, are consistent and fight nothing, so a
    // mechanism with a free DOF is under-determined, as it is determined once inputs fix that
    // DOF; the micro-manipulator's platform between two centres its inputs move apart is a
    // real fight beside its free spin: mixed.
    let cases = [
        ("bricard", "file", "under-determined"),
        ("rig-planar-four-bar-3d", "file", "under-determined"),
        (
            "micro-manipulator",
            "random",
            "not determined (over- and under-determined parts)",
        ),
    ];
    for (name, geometry, verdict) in cases {
        let path = format!("{}/mechanisms/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).expect("a bundled mechanism");
        let (code, out) = run(&["analyze", "--geometry", geometry, "-"], &text);
        assert_eq!(code, Some(0), "{name}: {out}");
        let head = out.lines().next().unwrap_or_default();
        assert!(
            head.ends_with(&format!("; {verdict}")),
            "{name} at {geometry} geometry: {head}"
        );
        // Not determined either way: `check`'s `determined` means the same.
        assert!(!head.ends_with("; determined"), "{name}: {head}");
    }
}

/// The IFToMM N-four-bar as written near the origin (verticals pinned at `(k, 0)`, their tops
/// at `(k + 0.6, 0.8)`), its first crank driven: from 100 windows on its numbers have four
/// digits and are known to ±0.05 only.
fn n_four_bar_driven(n: usize) -> String {
    // The tops' x written to one decimal, as a file would (`1.6`, not `1.5999999999999999`).
    let top = |x: f64| (x * 10.0).round() / 10.0;
    crate::common::n_four_bar_with(n, "space = \"planar\"\nframe = 1", |x, y| {
        let x = if y == 0.0 { x } else { top(x) };
        format!("origin = [{x}, {y}]")
    })
}

/// A driven row of windows far from its centre is determined, one group a window, as `rigid`
/// finds it (no redundant constraint). Each pair's rows were orthonormal about the centre:
/// moved to the bodies' own reference points 100 link lengths away they shrank and leaned on
/// each other, and at the threshold of numbers known to ±0.05 the 200-window row had 525
/// equations set aside ("not determined", the crank's own pair "redundant").
#[test]
fn a_driven_row_of_windows_at_one_decimal_is_determined() {
    for n in [99, 199, 499] {
        let text = n_four_bar_driven(n);
        assert_eq!(true_mobility(&text), "count 1; true mobility 1", "N = {n}");
        let verdict = analyze_verdict(&text);
        let head = format!(
            "{} structural group(s) on {} level(s); mobility 1, inputs 1; determined",
            n + 1,
            n + 1
        );
        assert!(verdict.contains(&head), "N = {n}: {verdict}");
        assert!(!verdict.contains("redundant"), "N = {n}: {verdict}");
    }
}
