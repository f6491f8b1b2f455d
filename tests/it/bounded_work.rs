//! Analyses whose work the input sets stop at the work budget (`--max-work`) with exit code 2
//! and the budget's message, instead of running for minutes or exhausting memory.

use assert_cmd::Command;
use std::time::Instant;

fn mbsa(args: &[&str], stdin: &str) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .write_stdin(stdin)
        .output()
        .expect("mbsa runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn generated(args: &[&str]) -> String {
    let mut all = vec!["generate"];
    all.extend_from_slice(args);
    let (code, text, err) = mbsa(&all, "");
    assert_eq!(code, 0, "{err}");
    text
}

/// The exhaustive search is charged to the work budget: a small budget stops it with the
/// budget's message; the default budget still answers, as the flow method does.
#[test]
fn exhaustive_search_stops_at_the_work_limit() {
    let file = generated(&["assur", "--class", "2", "--groups", "8"]);
    let args = [
        "--max-work",
        "1000",
        "analyze",
        "--method",
        "exhaustive",
        "--count-only",
        "-",
    ];
    let (code, out, err) = mbsa(&args, &file);
    assert_eq!(code, 2, "{out}{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("the exhaustive search needs more than 1000 work units"),
        "{err}"
    );
    assert!(err.contains("--max-work"), "{err}");
    let (code, dot, err) = mbsa(
        &["--max-work", "1000", "dot", "--method", "exhaustive", "-"],
        &file,
    );
    assert_eq!(code, 2, "{dot}{err}");
    // Within the default budget it answers, with the groups the flow method finds.
    let (code, exh, err) = mbsa(
        &["analyze", "--method", "exhaustive", "--count-only", "-"],
        &file,
    );
    assert_eq!(code, 0, "{err}");
    let (code, flow, err) = mbsa(&["analyze", "--count-only", "-"], &file);
    assert_eq!(code, 0, "{err}");
    let groups = |t: &str| t.lines().filter(|l| l.contains("SG-")).count();
    assert!(
        groups(&exh) > 0 && groups(&exh) == groups(&flow),
        "{exh}\n{flow}"
    );
}

/// `transform` on one S joint shared by n bodies: the table's expansion column lists a few
/// pairs and counts the rest, so the output grows linearly (it was n^2: 435 MB at 5,000
/// bodies, an abort at 10,000); `--limit 1` answers at once at 20,000. The JSON still lists
/// every pair.
#[test]
fn a_shared_joint_transform_writes_linear_output() {
    let mut sizes = Vec::new();
    for n in ["2500", "5000"] {
        let file = generated(&["star", "--bodies", n, "--joint", "S", "--shared"]);
        let start = Instant::now();
        let (code, table, err) = mbsa(&["transform", "-"], &file);
        eprintln!(
            "transform of a {n}-body shared joint: {} bytes in {:?}",
            table.len(),
            start.elapsed()
        );
        assert_eq!(code, 0, "{err}");
        assert!(
            table.contains("hub: 1-2, 1-3, 1-4, 1-5, 1-6, 1-7, 1-8, 1-9 (+"),
            "{}",
            &table[..2000]
        );
        sizes.push(table.len());
    }
    // Twice the bodies, about twice the bytes (n^2 gave four times); the table shows three
    // placements of the family, 15,000 inputs each (n^2 gave 435 MB).
    assert!(sizes[1] < 3 * sizes[0], "{sizes:?}");
    assert!(sizes[1] < 4_000_000, "{sizes:?}");
    let file = generated(&["star", "--bodies", "20000", "--joint", "S", "--shared"]);
    let start = Instant::now();
    let (code, table, err) = mbsa(&["transform", "--limit", "1", "-"], &file);
    let took = start.elapsed();
    eprintln!(
        "transform --limit 1 of a 20000-body shared joint: {} bytes in {took:?}",
        table.len()
    );
    assert_eq!(code, 0, "{err}");
    assert!(table.contains("(+19991 more pairs)"), "{}", &table[..2000]);
    assert!(table.len() < 10_000_000, "{}", table.len());
    let (code, json, err) = mbsa(
        &["transform", "--limit", "1", "--format", "json", "-"],
        &file,
    );
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    let expansion = v["placements"][0]["expansion"]
        .as_str()
        .expect("an expansion");
    assert_eq!(expansion.matches(", ").count(), 19998, "every pair in JSON");
}

/// A single loop of `n` spatial R joints (parallel axes, on a circle) with its geometry:
/// bodies 1..=n, joint k between body k and body k + 1 (the last back to 1).
fn loop_of(n: usize) -> String {
    let mut s = String::from("name = \"loop\"\nspace = \"spatial\"\nframe = 1\n");
    for k in 0..n {
        let t = std::f64::consts::TAU * k as f64 / n as f64;
        let r = n as f64 / 6.0;
        s.push_str(&format!(
            "\n[[joint]]\nid = \"j{k}\"\ntype = \"R\"\nbodies = [{}, {}]\norigin = [{:?}, {:?}, 0]\naxis = [0, 0, 1]\n",
            k + 1,
            (k + 1) % n + 1,
            r * t.cos(),
            r * t.sin()
        ));
    }
    s
}

/// `rigid --finite` on a 400-joint loop (2,394 unknowns): refused at once from its sizes
/// with the budget's message (it ran past 120 s in its first dense SVD, whose work was
/// charged at a twentieth of its time); a 10-joint loop still answers.
#[test]
fn the_finite_test_is_refused_up_front_when_its_sizes_exceed_the_budget() {
    let start = Instant::now();
    let (code, out, err) = mbsa(&["rigid", "--finite", "-"], &loop_of(400));
    let took = start.elapsed();
    eprintln!("rigid --finite on a 400-joint loop: exit {code} in {took:?}");
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("the finite-mobility test on 2394 unknowns and 2000 constraint rows needs"),
        "{err}"
    );
    assert!(err.contains("--max-work"), "{err}");
    assert!(took.as_secs() < 30, "{took:?}");
    let (code, out, err) = mbsa(&["rigid", "--finite", "-"], &loop_of(10));
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("Finite mobility: 7 (first order 7, count 4"),
        "{out}"
    );
}

/// `rigid --finite` on loops of 60 and 80 joints: the levels of curve tests the count makes
/// certain are estimated before they run. At 80 from the sizes, at 60 projected from the
/// first levels; both ran 10-17 s before the meter stopped them at the budget's end.
#[test]
fn the_finite_test_projects_its_levels_before_running_them() {
    let (code, out, err) = mbsa(&["rigid", "--finite", "-"], &loop_of(80));
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("at least 74 level(s) of curve tests, needs"),
        "{err}"
    );
    let (code, out, err) = mbsa(&["rigid", "--finite", "-"], &loop_of(60));
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("the finite-mobility test (projected from its first 2 of at least 54 levels"),
        "{err}"
    );
    assert!(err.contains("--max-work"), "{err}");
}
