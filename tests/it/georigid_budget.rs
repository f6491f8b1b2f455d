//! Issue 16 item 1, the exact factorization's budget: a boundedness regression test.
//!
//! Before, the sparse GF(p) factorization behind the exact geometric analysis
//! (`exact::sparse::Factor`) charged nothing while it ran: its fill sat in pending fronts and
//! blocks that no check saw, so on the 10^5-body random file `rigid --method geometric` ran
//! over 200 s and 2.4 GB without answering or meeting a budget. Now every front charges its
//! real work (rows × width per pivot) and checks the memory then held (live blocks, the
//! front, the records kept) against the memory limit: a budget smaller than the
//! factorization's real needs stops it with the usual error.

use mbsa::budget::{Budget, Limit};
use mbsa::generate;
use mbsa::mechanism::Mechanism;
use mbsa::rigidity::geometric::{
    GeometricError, GeometricOptions, GeometricReport, analyze_within,
};

/// The geometric analysis of `m` (default options) under the default budget with its work
/// limit set to `max_work`.
fn under_work_limit(m: &Mechanism, max_work: u64) -> Result<GeometricReport, GeometricError> {
    let budget = Budget {
        max_work,
        ..Budget::DEFAULT
    };
    analyze_within(m, &GeometricOptions::default(), &budget)
}

/// A random spatial mechanism of 10^3 bodies: its one large block is analysed exactly. The
/// checks made before the factorization (its sampled motions: about 0.6 MB) fit in 700 KB;
/// the factorization itself holds more (its records alone are over a million bytes), so it
/// must stop on the memory limit. The old code, which checked only the motions, answered.
#[test]
fn the_factorization_stops_on_the_memory_limit() {
    let (m, _) = generate::random(1000, false, 1).expect("generates");
    let budget = Budget {
        max_memory_bytes: 700 * 1024,
        ..Budget::DEFAULT
    };
    match analyze_within(&m, &GeometricOptions::default(), &budget) {
        Err(GeometricError::Budget(e)) => {
            assert_eq!(e.limit, Limit::Memory, "{e}");
            let msg = e.to_string();
            assert!(msg.contains("exact"), "{msg}");
            assert!(msg.contains("memory limit"), "{msg}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("answered within 700 KB"),
    }
    // With the default budget it answers.
    assert!(analyze_within(&m, &GeometricOptions::default(), &Budget::DEFAULT).is_ok());
}

/// The work the factorization charges is its real work: a work limit just below what the
/// whole analysis needs stops it (exit 2 at the command line), and the count is
/// deterministic (the same mechanism charges the same units twice).
#[test]
fn the_factorization_charges_its_work() {
    let (m, _) = generate::random(1000, false, 1).expect("generates");
    assert!(under_work_limit(&m, Budget::DEFAULT.max_work).is_ok());
    match under_work_limit(&m, 100_000) {
        Err(GeometricError::Budget(e)) => assert_eq!(e.limit, Limit::Work, "{e}"),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("answered within 10^5 work units"),
    }
}

/// No cliffs: the floating-point self-stresses of a square random mechanism (its
/// driven DOF kept, as `rigid --with-inputs`) factor the transpose of their support, an
/// over-determined elimination whose fronts mix the rows of two bodies and fill in, and
/// re-run it while its float rank differs from the exact one. That elimination charges every
/// front's rows × columns per pivot and every compression as it goes (1.2·10^10 units here).
/// Under a work limit of 10^9 the old code stopped with the work limit's error (and on the
/// random spatial 10^4 file it did so under the default budget). The exact count does not
/// need them: they now run last, on what the rest left, and where they do not fit the
/// analysis answers with the exact count, the joints carrying the exact self-stresses listed
/// without weights (every joint the weights name among them) and a note naming the flag that
/// gets the weights.
#[test]
fn with_inputs_the_float_self_stresses_charge_their_elimination() {
    let (m, _) = generate::random(1000, false, 1).expect("generates");
    assert!(m.joints.iter().any(|j| j.driven > 0), "inputs kept");
    let full = under_work_limit(&m, Budget::DEFAULT.max_work).expect("answers");
    assert!(full.redundant > 0 && !full.redundant_joints.is_empty());
    assert!(full.redundant_joints_unweighted.is_empty());
    let cut = under_work_limit(&m, 1_000_000_000).expect("answers without weights");
    assert_eq!(
        (cut.rank, cut.redundant, cut.mobility),
        (full.rank, full.redundant, full.mobility)
    );
    assert!(cut.redundant_joints.is_empty());
    for j in &full.redundant_joints {
        assert!(
            cut.redundant_joints_unweighted.contains(&j.joint),
            "{} not listed",
            j.joint
        );
    }
    let note = cut.weights_note.clone().expect("a note");
    assert!(note.contains("were not computed"), "{note}");
    assert!(note.contains("--max-work"), "{note}");
    let listed = cut.redundant_joints_unweighted.len();
    assert!(note.contains(&format!("the {listed} joints")), "{note}");
    // Everything but the weights is the full report's.
    let mut same = cut.clone();
    same.redundant_joints = full.redundant_joints.clone();
    same.redundant_joints_unweighted.clear();
    same.weights_note = full.weights_note.clone();
    assert_eq!(same, full);
    // What the user reads: the text lists them with the note, the rigid DOT view draws them
    // as redundant without a weight.
    let text = mbsa::report::rigid_geometric::table(&cut);
    assert!(
        text.contains("joints involved, weights not computed: "),
        "{text}"
    );
    assert!(!text.contains("joints involved, by weight"), "{text}");
    assert!(text.contains("  Note: the weights of the "), "{text}");
    let dot = mbsa::report::dot::rigid(&m, &cut);
    let first = &cut.redundant_joints_unweighted[0];
    assert!(dot.contains(&format!("{first} ")), "{first} not drawn");
    assert!(
        dot.contains("\\nredundant\""),
        "no unweighted redundant label"
    );
    assert!(!dot.contains("\\nredundant "), "a weight drawn");
}

/// The float self-stresses re-run their transposed elimination while its rank differs from
/// the exact one; each re-run used to move the threshold past one decision (the smallest
/// pivot kept or the largest dropped), so a rank off by `d` cost at least `d` more runs. They
/// are now steered by the first run's pivot norms to the exact rank (the gap above the `d`
/// smallest kept pivots), one more run where the old way needed several. On this random
/// spatial 2·10^3 (driven DOF kept, first rank off by three) the analysis answers within
/// 6·10^9 units (about 4.5·10^9 charged); the old retries passed 10^10 and stopped there.
#[test]
fn steered_self_stress_retries_answer_within_fewer_runs() {
    let (m, _) = generate::random(2000, false, 1).expect("generates");
    assert!(m.joints.iter().any(|j| j.driven > 0), "inputs kept");
    let r = under_work_limit(&m, 6_000_000_000).expect("answers");
    assert!(r.redundant > 0, "self-stresses to weigh");
    assert!(!r.redundant_joints.is_empty());
    assert!(
        r.redundant_joints_unweighted.is_empty(),
        "every weight computed"
    );
}

/// The same through the binary, as a user meets it: `rigid --with-inputs --method geometric`
/// on that file under `--max-work 10^9` used to end with exit 2 and the work limit's message;
/// it now answers (exit 0) with the exact count, the joints without weights and the note, in
/// the text and in JSON (`redundant_joints_unweighted`, `weights_note`).
#[test]
fn the_command_answers_without_weights_under_a_tight_work_limit() {
    let (m, _) = generate::random(1000, false, 1).expect("generates");
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("georigid_budget");
    std::fs::create_dir_all(&dir).expect("the target directory is writable");
    let file = dir.join("random-spatial-1000.toml");
    std::fs::write(&file, generate::to_toml(&m)).expect("writable");
    let run = |json: bool| {
        let mut args = vec![
            "rigid".to_string(),
            file.display().to_string(),
            "--with-inputs".into(),
            "--method".into(),
            "geometric".into(),
            "--max-work".into(),
            "1000000000".into(),
        ];
        if json {
            args.extend(["--format".into(), "json".into()]);
        }
        let out = assert_cmd::Command::cargo_bin("mbsa")
            .expect("the binary is built")
            .env("NO_COLOR", "1")
            .args(&args)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(0), "{stderr}");
        String::from_utf8(out.stdout).expect("UTF-8")
    };
    let text = run(false);
    assert!(text.contains("redundant constraints (rows"), "{text}");
    assert!(
        text.contains("joints involved, weights not computed: "),
        "{text}"
    );
    assert!(
        text.contains("raise the limit with `--max-work N`"),
        "{text}"
    );
    let v: serde_json::Value = serde_json::from_str(&run(true)).expect("JSON");
    let listed = v["redundant_joints_unweighted"].as_array().expect("a list");
    assert!(!listed.is_empty());
    assert!(v["redundant"].as_u64().expect("a count") > 0);
    let note = v["weights_note"].as_str().expect("a note");
    assert!(note.contains("were not computed"), "{note}");
}
