//! File geometry written in millimetres far from the world origin: the rank decisions must not
//! depend on where the model sits or on its length unit's size. A planar four-bar and a row of
//! ten windows, pins at about (1000, 500) mm with two decimals (known to ±0.005 mm): the
//! geometric analysis said mobility 9 and 63 (the rounding threshold multiplied every written
//! number by the largest coordinate), then 2 and 11 with the point/direction split alone
//! (twists about the world origin lose the decision); with the body-local twists of the
//! sparse path it says 1, as the same files written near the origin do.

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
