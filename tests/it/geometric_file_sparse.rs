//! The sparse floating-point path of the geometric analysis at the file's geometry (issue 16,
//! item 4): the same answers as the dense path where the dense path runs (every bundled
//! mechanism with geometry, generated N-four-bars), and the 1,000-window N-four-bar answered
//! with the right mobility (the dense path's rank decision fails there: the twists written
//! about the world origin make the Jacobian's conditioning grow with the square of the size).

use mbsa::JointType;
use mbsa::budget::Budget;
use mbsa::mechanism::{BodyId, Geometry, JointSpec, Mechanism, Space};
use mbsa::rigidity::geometric::{
    self, GeometricOptions, GeometricReport, GeometrySource, with_sparse_from,
};

/// The IFToMM N-four-bar with `n` windows (as the bundled `n-four-bar-40`): vertical V_k
/// pinned to the ground at (k, 0), its top at (k + dx, dy); horizontal H_k between the tops of
/// V_(k−1) and V_k. Generic: (0.6, 0.8); flat (singular, every bar on the x axis): (1, 0).
fn n_four_bar(n: i64, flat: bool) -> Mechanism {
    let (dx, dy) = if flat { (1.0, 0.0) } else { (0.6, 0.8) };
    n_four_bar_at(n, dx, dy)
}

/// The N-four-bar with the tops of the verticals at `(k + dx, dy)`.
fn n_four_bar_at(n: i64, dx: f64, dy: f64) -> Mechanism {
    let r = |id: String, a: i64, b: i64, x: f64, y: f64| JointSpec {
        id: Some(id),
        kind: JointType::R,
        bodies: vec![BodyId::Int(a), BodyId::Int(b)],
        driven: 0,
        geometry: Geometry {
            origin: Some([x, y, 0.0]),
            ..Geometry::default()
        },
    };
    let mut joints = vec![r("A0".into(), 1, 2, 0.0, 0.0)];
    for k in 1..=n {
        let x = k as f64;
        joints.push(r(
            format!("VB{}", k - 1),
            2 * k,
            2 * k + 1,
            x - 1.0 + dx,
            dy,
        ));
        joints.push(r(format!("B{k}"), 2 * k + 1, 2 * k + 2, x + dx, dy));
        joints.push(r(format!("P{k}"), 1, 2 * k + 2, x, 0.0));
    }
    Mechanism::from_parts("n-four-bar", Space::Planar, BodyId::Int(1), vec![], joints)
}

/// The file's geometry taken as exact (the generated numbers are not rounded).
fn exact_file() -> GeometricOptions {
    GeometricOptions {
        geometry: GeometrySource::File,
        precision: Some(0.0),
        check_finite: false,
    }
}

fn joints_of(r: &GeometricReport) -> Vec<String> {
    let mut v: Vec<String> = r.redundant_joints.iter().map(|w| w.joint.clone()).collect();
    v.sort();
    v
}

/// Every answer of the report but the numeric facts and the weights' values.
fn assert_same(name: &str, dense: &GeometricReport, sparse: &GeometricReport) {
    assert_eq!(
        (dense.rank, dense.mobility, dense.redundant),
        (sparse.rank, sparse.mobility, sparse.redundant),
        "{name}: rank, mobility, redundant"
    );
    assert_eq!(
        joints_of(dense),
        joints_of(sparse),
        "{name}: redundant joints"
    );
    assert_eq!(dense.locked_joints, sparse.locked_joints, "{name}: locked");
    assert_eq!(dense.rigid, sparse.rigid, "{name}: rigid clusters");
    assert_eq!(
        (
            dense.isolated,
            dense.fully_isolated,
            dense.structurally_isolated
        ),
        (
            sparse.isolated,
            sparse.fully_isolated,
            sparse.structurally_isolated
        ),
        "{name}: isolated"
    );
    assert_eq!(
        dense.isolated_motions, sparse.isolated_motions,
        "{name}: isolated motions"
    );
}

fn both(m: &Mechanism, opts: &GeometricOptions) -> (GeometricReport, GeometricReport) {
    let dense = with_sparse_from(usize::MAX, || geometric::analyze(m, opts)).unwrap();
    let sparse = with_sparse_from(0, || geometric::analyze(m, opts)).unwrap();
    (dense, sparse)
}

#[test]
fn sparse_agrees_with_dense_on_every_bundled_mechanism_with_geometry() {
    let mut checked = 0;
    for name in mbsa::examples::names() {
        let (file, text) = mbsa::examples::find(name).unwrap();
        let Ok(m) = mbsa::format::load(file, text, mbsa::format::Format::Toml) else {
            continue;
        };
        if !mbsa::motion::has_geometry(&m) {
            continue;
        }
        let opts = GeometricOptions {
            geometry: GeometrySource::File,
            ..GeometricOptions::default()
        };
        let Ok(dense) = with_sparse_from(usize::MAX, || geometric::analyze(&m, &opts)) else {
            continue;
        };
        let sparse = with_sparse_from(0, || geometric::analyze(&m, &opts)).unwrap();
        assert_same(name, &dense, &sparse);
        checked += 1;
    }
    assert!(
        checked >= 20,
        "only {checked} bundled mechanisms with geometry"
    );
}

#[test]
fn sparse_agrees_with_dense_on_generated_n_four_bars() {
    for n in [1, 2, 5, 20, 100] {
        for flat in [false, true] {
            let m = n_four_bar(n, flat);
            let (dense, sparse) = both(&m, &exact_file());
            assert_same(&format!("{n} windows, flat {flat}"), &dense, &sparse);
            // Generic: one DOF; flat: every window has its own first-order freedom.
            let want = if flat { n as usize + 1 } else { 1 };
            assert_eq!(sparse.mobility, want, "{n} windows, flat {flat}");
        }
    }
}

#[test]
fn thousand_window_n_four_bar_is_answered_with_the_right_mobility() {
    for (flat, mobility, redundant) in [(false, 1, 0), (true, 1001, 1000)] {
        let m = n_four_bar(1000, flat);
        let r = geometric::analyze(&m, &exact_file()).unwrap();
        assert_eq!(
            (r.mobility, r.redundant, r.count),
            (mobility, redundant, 1),
            "flat {flat}: {:?}",
            r.numeric
        );
        // Every joint turns in some motion.
        assert!(r.locked_joints.is_empty(), "flat {flat}");
    }
}

/// Scale regression: 10^4 windows (60,003 unknowns in one biconnected block) within a work
/// cap the sparse path fits in; the dense path needs more than 10^11 units on the flat layout
/// (10^4 motions over 6·10^4 unknowns) and decides the generic layout's rank wrongly.
#[test]
fn ten_thousand_window_n_four_bar_within_a_small_work_cap() {
    let budget = Budget {
        max_work: 2_000_000_000,
        ..Budget::DEFAULT
    };
    for (flat, mobility) in [(false, 1), (true, 10_001)] {
        let m = n_four_bar(10_000, flat);
        let r = geometric::analyze_within(&m, &exact_file(), &budget).unwrap();
        assert_eq!(r.mobility, mobility, "flat {flat}: {:?}", r.numeric);
        assert_eq!(r.redundant, mobility - 1, "flat {flat}");
    }
    // The dense path on the flat layout is refused by the same cap.
    let m = n_four_bar(10_000, true);
    let e = with_sparse_from(usize::MAX, || {
        geometric::analyze_within(&m, &exact_file(), &budget)
    });
    assert!(matches!(e, Err(geometric::GeometricError::Budget(_))));
}

/// The sparse path's self-stresses carry the residual check the dense path's have:
/// an N-four-bar 10^-7 off its flat pose, taken as exact, is decided flat by the rank
/// threshold (its 40 near-redundant rows dropped), so the self-stresses its weights come from
/// leave |yᵀA| of about 10^-8 σ_max, over the 10^-9 accepted: both paths say the weights are
/// approximate (the sparse path said nothing before). Flat, or 10^-9 off, neither does.
#[test]
fn sparse_self_stresses_carry_the_residual_check() {
    for (dy, approximate) in [(0.0, false), (1e-9, false), (1e-8, true), (1e-7, true)] {
        let m = n_four_bar_at(40, 1.0, dy);
        let (dense, sparse) = both(&m, &exact_file());
        assert_eq!(
            (dense.mobility, dense.redundant),
            (41, 40),
            "{dy}: {:?}",
            dense.numeric
        );
        assert_same(&format!("40 windows {dy} off flat"), &dense, &sparse);
        for (path, r) in [("dense", &dense), ("sparse", &sparse)] {
            assert_eq!(
                r.weights_note.is_some(),
                approximate,
                "{path}, {dy} off flat: {:?}",
                r.weights_note
            );
        }
    }
}
