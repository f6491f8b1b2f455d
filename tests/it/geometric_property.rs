//! Property: for random body-hinge mechanisms (revolute joints only, spatial) at a random
//! realization, the numeric mobility, redundancy and rigid clusters equal the generic answers
//! of the pebble game (Tay's body-hinge theorem: generic geometry realizes the generic count).

use mbsa::JointType;
use mbsa::mechanism::{BodyId, JointSpec, Mechanism, Space};
use mbsa::rigidity::geometric::{GeometricOptions, GeometrySource, analyze};
use mbsa::rigidity::pebble::{self, PebbleOptions};
use proptest::prelude::*;

fn mechanism(bodies: i64, extra: &[(i64, i64)]) -> Mechanism {
    // A spanning chain keeps it connected; extra hinges close loops.
    let mut joints: Vec<JointSpec> = (1..bodies)
        .map(|b| JointSpec::new(JointType::R, b, b + 1, 0))
        .collect();
    for &(a, b) in extra {
        let (a, b) = (1 + a % bodies, 1 + b % bodies);
        if a != b {
            joints.push(JointSpec::new(JointType::R, a, b, 0));
        }
    }
    Mechanism::from_parts(
        "random hinges",
        Space::Spatial,
        BodyId::Int(1),
        vec![],
        joints,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn numeric_equals_generic(
        bodies in 2i64..9,
        extra in proptest::collection::vec((0i64..9, 0i64..9), 0..12),
        seed in 0u64..1000,
    ) {
        let m = mechanism(bodies, &extra);
        let g = pebble::analyze(&m, &PebbleOptions::default());
        let r = analyze(&m, &GeometricOptions {
            geometry: GeometrySource::Random { seed },
            check_finite: false,
            precision: None,
        }).expect("random geometry always works");
        prop_assert_eq!(r.mobility as i64, g.dof);
        prop_assert_eq!(r.redundant as u64, g.redundant);
        // Clusters agree when no isolated motion is set aside (a dangling body's turn is a
        // fully isolated DOF, which the geometric clusters disregard and counting does not).
        if r.isolated == 0 {
            let clusters: Vec<Vec<String>> = r.rigid.iter().map(|c| c.bodies.clone()).collect();
            prop_assert_eq!(clusters, g.rigid);
        }
    }
}
