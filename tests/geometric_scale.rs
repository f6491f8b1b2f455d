//! Scale and timing of the geometric rigidity analysis (timings printed, not asserted).

use mbsa::JointType;
use mbsa::mechanism::{BodyId, Geometry, JointSpec, Mechanism, Space};
use mbsa::motion::SplitMix64;
use mbsa::rigidity::geometric::{GeometricOptions, GeometrySource, analyze};
use std::time::Instant;

/// A random 3D framework built by Henneberg steps: each new point is joined by bars to three
/// earlier points (three of the six nearest). Generically rigid: true mobility = bars − 1 spins +
/// 1 frame-bar spin, no redundancy. Bars are bodies, points are multiple S joints.
pub fn framework(points: usize, seed: u64) -> Mechanism {
    let mut rng = SplitMix64::new(seed);
    let mut p: Vec<[f64; 3]> = Vec::new();
    let mut bars: Vec<(usize, usize)> = vec![(0, 1), (0, 2), (1, 2)];
    for i in 0..points {
        let s = (i as f64).cbrt();
        p.push([
            s * rng.next_signed(),
            s * rng.next_signed(),
            s * rng.next_signed(),
        ]);
        if i >= 3 {
            let mut near: Vec<(f64, usize)> = (0..i)
                .map(|j| {
                    let d: f64 = (0..3).map(|k| (p[i][k] - p[j][k]).powi(2)).sum();
                    (d, j)
                })
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            // Three of the six nearest, at random: local, and not too flat.
            let mut pick: Vec<usize> = near.iter().take(6).map(|x| x.1).collect();
            for _ in 0..3 {
                let k = rng.below(pick.len() as u64) as usize;
                bars.push((pick.swap_remove(k), i));
            }
        }
    }
    let name = |k: usize| BodyId::Name(format!("b{k:05}"));
    let joints = (0..points)
        .map(|i| JointSpec {
            id: Some(format!("p{i}")),
            kind: JointType::S,
            bodies: bars
                .iter()
                .enumerate()
                .filter(|(_, (a, b))| *a == i || *b == i)
                .map(|(k, _)| name(k))
                .collect(),
            driven: 0,
            geometry: Geometry {
                origin: Some(p[i]),
                ..Geometry::default()
            },
        })
        .collect();
    Mechanism::from_parts("framework", Space::Spatial, name(0), vec![], joints)
}

#[test]
fn random_framework_is_rigid_with_spins() {
    for points in [20, 120] {
        let m = framework(points, 3);
        let bars = m.bodies.len();
        let t = Instant::now();
        let r = analyze(
            &m,
            &GeometricOptions {
                geometry: GeometrySource::File,
                check_finite: false,
            },
        )
        .expect("geometry given");
        let dt = t.elapsed();
        assert_eq!(r.redundant, 0);
        assert_eq!(r.mobility, bars, "{bars} bars: spins (frame's included)");
        assert_eq!(r.isolated, bars);
        assert_eq!(r.rigid.len(), 1);
        assert_eq!(r.rigid[0].bodies.len(), bars);
        eprintln!("{bars} bars: {dt:?}");
    }
}

/// `cargo test --release --test geometric_scale -- --ignored --nocapture`
#[test]
#[ignore]
fn timing_thousand_bars() {
    let m = framework(334, 3);
    let t = Instant::now();
    let r = analyze(
        &m,
        &GeometricOptions {
            geometry: GeometrySource::File,
            check_finite: false,
        },
    )
    .expect("geometry given");
    eprintln!(
        "{} bars: {:?} (mobility {}, redundant {}, rigid clusters {})",
        m.bodies.len(),
        t.elapsed(),
        r.mobility,
        r.redundant,
        r.rigid.len()
    );
    eprintln!("{:?}", r.numeric);
}
