use super::gram::*;
use super::model::*;
use super::realize::*;
use super::twists::*;
use super::*;
use crate::mechanism::{BodyId, Geometry, JointSpec, Mechanism};
use nalgebra::{DMatrix, DVector, Vector3};

/// The file's `precision` key is what the precision functions use, whatever the digits say.
#[test]
fn written_precision_takes_the_files_key() {
    use crate::format::{Format, load};
    let digits = "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\norigin = [0.1234, 0, 0]\n";
    let m = load("p.toml", digits, Format::Toml).unwrap();
    assert_eq!(written_precision(&m), 5e-5);
    let keyed = digits.replace("frame = 1\n", "frame = 1\nprecision = 1e-9\n");
    let m = load("p.toml", &keyed, Format::Toml).unwrap();
    assert_eq!(written_precision(&m), 1e-9);
    assert_eq!(written_direction_precision(&m), 1e-9);
}

/// [`complement`] in a motion space of runtime dimension `b` (3 or 6).
fn complement_in(cols: &[Vb], b: usize) -> Vecs {
    match b {
        6 => complement::<6>(cols),
        3 => complement::<3>(cols),
        _ => panic!("no motion space has dimension {b}"),
    }
}

/// [`contact_rows`] in `space`.
fn contact_rows_in(kind: JointType, g: &Geometry, space: Space) -> Vecs {
    match space {
        Space::Spatial => contact_rows::<6>(kind, g, space),
        _ => contact_rows::<3>(kind, g, space),
    }
}

fn check(m: &JointModel, b: usize, dim: usize) {
    assert_eq!(m.twists.nrows(), b);
    assert_eq!(m.rows.ncols(), b);
    assert_eq!(m.twists.ncols(), dim);
    assert_eq!(m.rows.nrows(), b - dim);
    let p = &m.rows * &m.twists;
    assert!(p.norm() < 1e-12, "rows · twists = {p}");
    let full = m.twists.clone().insert_columns(dim, 0, 0.0);
    let stacked = DMatrix::from_fn(b, b, |i, j| {
        if j < dim {
            full[(i, j)]
        } else {
            m.rows[(j - dim, i)]
        }
    });
    assert_eq!(stacked.rank(1e-9), b);
}

/// [`complement`] projects only the unit vectors that can have the largest residual; bit
/// for bit the same as projecting every one through [`project_out`] (its definition). Random columns, columns
/// with exact zeros and coordinate directions (ties between unit vectors), nearly
/// dependent columns, and the twists of every joint kind at random and axis-aligned
/// geometry.
#[test]
fn complement_equals_one_vector_at_a_time() {
    let mut rng = SplitMix64::new(7);
    for trial in 0..3000 {
        let b = [3, 6][trial % 2];
        let d = trial % b;
        let cols: Vec<Vb> = (0..d)
            .map(|_| {
                let mut v = [0.0; MAX_B];
                for x in v.iter_mut().take(b) {
                    // Some exact zeros, as joint twists have.
                    let r = rng.next_signed();
                    *x = if r.abs() < 0.2 { 0.0 } else { r };
                }
                v
            })
            .collect();
        check_complement(&cols, b, trial);
    }
    // Structured columns: small integers (many exact ties), nearly dependent pairs.
    for trial in 0..3000 {
        let b = [3, 6][trial % 2];
        let d = trial % b;
        let mut cols: Vec<Vb> = (0..d)
            .map(|_| {
                let mut v = [0.0; MAX_B];
                for x in v.iter_mut().take(b) {
                    *x = (rng.below(5) as f64 - 2.0) * [1.0, 0.5][rng.below(2) as usize];
                }
                v
            })
            .collect();
        if d >= 2 && trial % 3 == 0 {
            let k = rng.below(b as u64) as usize;
            cols[1] = cols[0];
            cols[1][k] += [1e-9, 1e-7, 1e-12][trial / 3 % 3];
        }
        check_complement(&cols, b, trial);
    }
    // The twists of every joint kind, random and axis-aligned geometry.
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        let b = space.b() as usize;
        for kind in JointType::all() {
            for trial in 0..40 {
                let mut g = random_geometry(kind, space, &mut rng);
                if trial % 2 == 0 {
                    let axis = |r: u64| {
                        let mut a = [0.0; 3];
                        a[r as usize % 3] = 1.0;
                        a
                    };
                    g.axis = g.axis.map(|_| axis(rng.below(3)));
                    g.axis2 = g.axis2.map(|_| axis(rng.below(3)));
                    g.normal = g.normal.map(|_| axis(rng.below(3)));
                    g.origin = g.origin.map(|o| o.map(|x| (x * 2.0).round()));
                }
                if kind.grade() as usize <= b {
                    check_complement(contact_rows_in(kind, &g, space).as_slice(), b, trial);
                }
                if let Ok(full) = full_twists(kind, &g, space) {
                    for driven in 0..=full.len() {
                        check_complement(&full.as_slice()[driven..], b, trial);
                    }
                }
            }
        }
    }
}

/// Degenerate or awkward geometry for the models of `kind` (trial `trial % 6`): random,
/// axis-aligned with small integer points (exact zeros and ties), parallel or nearly parallel
/// directions and coincident centres, extreme or non-finite numbers, a field missing.
fn awkward_geometry(kind: JointType, space: Space, trial: usize, rng: &mut SplitMix64) -> Geometry {
    let mut g = random_geometry(kind, space, rng);
    let axis = |r: u64| {
        let mut a = [0.0; 3];
        a[r as usize % 3] = [1.0, -1.0][r as usize / 3 % 2];
        a
    };
    match trial % 6 {
        0 | 1 => {}
        2 => {
            g.axis = Some(axis(rng.below(6)));
            g.axis2 = Some(axis(rng.below(6)));
            g.normal = Some(axis(rng.below(6)));
            g.origin = g.origin.map(|o| o.map(|x| (x * 2.0).round()));
            g.origin2 = g.origin2.map(|o| o.map(|x| (x * 2.0).round()));
        }
        3 => {
            let eps = [0.0, 1e-12, 1e-9, 1e-4][rng.below(4) as usize];
            let a = g.axis.unwrap_or([0.0, 0.0, 1.0]);
            g.axis2 = Some([a[0] + eps, a[1], a[2]]);
            g.normal = Some([a[0], a[1] - eps, a[2]]);
            g.origin2 = g.origin.map(|o| [o[0] + eps, o[1], o[2]]);
        }
        4 => {
            let x = [1e200, 1e-200, f64::INFINITY, f64::NAN, 0.0, -0.0][rng.below(6) as usize];
            match rng.below(5) {
                0 => g.origin = g.origin.map(|o| [x, o[1], o[2]]),
                1 => g.axis = Some([x, 0.0, 0.0]),
                2 => g.normal = Some([0.0, x, 0.0]),
                3 => g.pitch = Some(x),
                _ => g.origin2 = g.origin2.map(|o| [o[0], o[1], x]),
            }
        }
        _ => match rng.below(5) {
            0 => g.origin = None,
            1 => g.axis = None,
            2 => g.axis2 = None,
            3 => g.normal = None,
            _ => g.origin2 = None,
        },
    }
    g
}

/// Every model that builds, at random and awkward geometry, every kind, space and number of
/// driven DOF, is a model: `B − k + driven` orthonormal rows annihilating its `k − driven`
/// twists; and the rows of many models built at once ([`batch`], kinds and driven DOF mixed
/// in the lanes) are those of one model at a time, bit for bit (a joint no model fits: the
/// fallback model's).
#[test]
fn models_in_lanes_are_the_one_joint_models() {
    let bits = |v: &Vecs| -> Vec<[u64; MAX_B]> {
        v.as_slice().iter().map(|x| x.map(f64::to_bits)).collect()
    };
    let mut rng = SplitMix64::new(1611);
    #[allow(clippy::type_complexity)]
    let mut many: [Vec<(JointType, Geometry, u32, u64, Vecs, String)>; 3] = Default::default();
    let mut built = 0;
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        let b = space.b() as usize;
        for kind in JointType::all() {
            for trial in 0..300 {
                let g = awkward_geometry(kind, space, trial, &mut rng);
                for driven in 0..=kind.grade() as u32 + 1 {
                    let what = format!("{kind:?} {space:?} driven {driven} trial {trial}");
                    let seed = rng.next_u64();
                    let want = match stack_model(kind, &g, space, driven) {
                        Ok(m) => {
                            let k = kind.grade() as usize - driven as usize;
                            if trial % 6 < 3 {
                                check(&m.matrices(), b, k);
                            }
                            // Orthonormal rows, as many as the kind and driven DOF give
                            // (coordinates of 1e200 overflow the Gram-Schmidt: not checked).
                            let r = m.matrices().rows;
                            if trial % 6 != 4 {
                                assert_eq!((r.nrows(), m.twists.len()), (b - k, k), "{what}");
                                let gram = &r * r.transpose() - DMatrix::identity(b - k, b - k);
                                assert!(gram.norm() < 1e-9, "{what}: rows orthonormal");
                            }
                            built += 1;
                            m.rows
                        }
                        Err(_) => fallback_model(kind, space, driven, seed).rows,
                    };
                    many[space as usize].push((kind, g.clone(), driven, seed, want, what));
                }
            }
        }
    }
    assert!(built > 15_000, "{built}");
    batch::RUNS.with(|c| c.set([0; 2]));
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        let cases = &mut many[space as usize];
        for i in (1..cases.len()).rev() {
            cases.swap(i, rng.below(i as u64 + 1) as usize);
        }
        let requests = |i: usize| {
            let (k, g, d, s, _, _) = &cases[i];
            (*k, g, *d, *s)
        };
        let mut scratch = batch::Scratch::default();
        let rows = match space {
            Space::Spatial => batch::rows_many::<6, _>(space, cases.len(), requests, &mut scratch),
            _ => batch::rows_many::<3, _>(space, cases.len(), requests, &mut scratch),
        };
        for (j, (_, _, _, _, want, what)) in cases.iter().enumerate() {
            let got = Vecs::of(rows.get(j));
            assert_eq!(bits(&got), bits(want), "{what}: rows of many");
        }
    }
    // Lanes as well as one at a time (errors, count-only kinds, a length's last few).
    let [lanes, single] = batch::RUNS.with(|c| c.get());
    assert!(
        lanes > 10_000 && single > 1_000,
        "{lanes} in lanes, {single} alone"
    );
}

/// The closed form of the motions a joint of `kind` at geometry `g` allows, written with
/// nalgebra from the geometry's fields (`None` for count-only kinds: a generic contact).
fn closed_form(kind: JointType, space: Space, g: &Geometry) -> Option<Vec<Vec<f64>>> {
    let turn = |u: Vector3<f64>, p: Vector3<f64>| {
        let m = p.cross(&u);
        vec![u.x, u.y, u.z, m.x, m.y, m.z]
    };
    let slide = |u: Vector3<f64>| vec![0.0, 0.0, 0.0, u.x, u.y, u.z];
    let xyz = [Vector3::x(), Vector3::y(), Vector3::z()];
    let v = |a: Option<[f64; 3]>| Vector3::from(a.expect("drawn"));
    let (p, u, n) = (v(g.origin), v(g.axis).normalize(), v(g.normal).normalize());
    let across = |a: Vector3<f64>, n: Vector3<f64>| (a - n * n.dot(&a)).normalize();
    let (e1, e2) = (across(u, n), n.cross(&across(u, n)));
    Some(match (space, kind) {
        (Space::Spatial, JointType::R) => vec![turn(u, p)],
        (Space::Spatial, JointType::P) => vec![slide(u)],
        (Space::Spatial, JointType::H) => {
            let h = g.pitch.expect("drawn");
            let mut t = turn(u, p);
            (3..6).for_each(|i| t[i] += h * u[i - 3]);
            vec![t]
        }
        (Space::Spatial, JointType::C) => vec![slide(u), turn(u, p)],
        (Space::Spatial, JointType::ER) => {
            let a = across(Vector3::new(0.3, -0.8, 0.5), u);
            vec![turn(a, p), turn(u.cross(&a), p)]
        }
        (Space::Spatial, JointType::U) => vec![turn(u, p), turn(v(g.axis2), p)],
        (Space::Spatial, JointType::S) => xyz.map(|e| turn(e, p)).to_vec(),
        (Space::Spatial, JointType::PL | JointType::FP) => {
            vec![slide(e1), slide(e2), turn(n, p)]
        }
        (Space::Spatial, JointType::F) => xyz
            .iter()
            .map(|&e| slide(e))
            .chain(xyz.map(|e| turn(e, p)))
            .collect(),
        (Space::Spatial, JointType::SP) => [slide(e1), slide(e2)]
            .into_iter()
            .chain(xyz.map(|e| turn(e, p)))
            .collect(),
        (Space::Spatial, JointType::SC) => [slide(u)]
            .into_iter()
            .chain(xyz.map(|e| turn(e, p)))
            .collect(),
        (Space::Spatial, JointType::PC) => {
            vec![slide(e1), slide(e2), turn(n, p), turn(e1, p)]
        }
        (Space::Spatial, JointType::CR) => {
            // The slot's face normal is `normal` across the axis; the slides are
            // along the axis and along the slot (across both).
            let w = across(n, u);
            vec![slide(u), slide(w.cross(&u)), turn(u, p)]
        }
        (Space::Spatial, JointType::SPSP) => {
            // Every motion but the stretch of the line of centres: the turns about
            // the first centre, and the slides across the line.
            let d = (v(g.origin2) - p).normalize();
            let (a, c) = (across(Vector3::x(), d), d.cross(&across(Vector3::x(), d)));
            let mut t = xyz.map(|e| turn(e, p)).to_vec();
            t.extend([slide(a), slide(c)]);
            t
        }
        (Space::Planar, JointType::R) => vec![vec![1.0, p.y, -p.x]],
        (Space::Planar, JointType::P) => {
            let a = Vector3::new(u.x, u.y, 0.0).normalize();
            vec![vec![0.0, a.x, a.y]]
        }
        (Space::Planar, JointType::FP) => {
            vec![
                vec![0.0, 1.0, 0.0],
                vec![0.0, 0.0, 1.0],
                vec![1.0, p.y, -p.x],
            ]
        }
        (Space::Spherical, JointType::R) => vec![vec![u.x, u.y, u.z]],
        (Space::Spherical, JointType::FP) => xyz.iter().map(|e| vec![e.x, e.y, e.z]).collect(),
        // Count-only kinds: a generic contact, no closed form.
        _ => return None,
    })
}

/// The twists of every spatial kind with a model span the closed form of its motions, written
/// here with nalgebra from the geometry's fields: a revolute about `u` through `p` allows
/// `(u; p × u)`, a slide `(0; u)`, a helix `(u; p × u + h u)`, a ball every `(ω; p × ω)`, a
/// plane contact the slides across `n` and the turn about `n` through `p`, and so on; the
/// planar and spherical ones likewise. Rows annihilate the closed forms.
#[test]
fn twists_are_the_closed_forms() {
    let mut rng = SplitMix64::new(77);
    let mut checked = 0;
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        let b = space.b() as usize;
        for kind in JointType::all() {
            for _ in 0..20 {
                let g = random_geometry(kind, space, &mut rng);
                let Ok(m) = joint_model(kind, &g, space, 0) else {
                    assert!(
                        space != Space::Spatial || !modelled(kind, space),
                        "{kind:?}"
                    );
                    continue;
                };
                let Some(closed) = closed_form(kind, space, &g) else {
                    continue;
                };
                let c = DMatrix::from_fn(b, closed.len(), |i, j| closed[j][i]);
                let what = format!("{kind:?} {space:?}");
                assert_eq!(m.twists.ncols(), closed.len(), "{what}");
                assert_eq!(c.rank(1e-9), closed.len(), "{what}: closed form");
                let both = DMatrix::from_fn(b, 2 * c.ncols(), |i, j| {
                    if j < c.ncols() {
                        c[(i, j)]
                    } else {
                        m.twists[(i, j - c.ncols())]
                    }
                });
                assert_eq!(both.rank(1e-9), closed.len(), "{what}: the same span");
                assert!((&m.rows * &c).norm() < 1e-9, "{what}: rows · closed form");
                checked += 1;
            }
        }
    }
    // Every kind with a model: 15 spatial, 3 planar, 2 spherical.
    assert_eq!(checked, 20 * 20);
}

/// [`random_pair_geometry`] draws only the fields a model reads: its models are bit
/// for bit those at the whole [`random_geometry`] (a field the model reads but not drawn
/// would be an error, then the fallback model), and the fields drawn are the same.
#[test]
fn partial_random_geometry_gives_the_same_models() {
    let bits = |v: &Vecs| -> Vec<[u64; MAX_B]> {
        v.as_slice().iter().map(|x| x.map(f64::to_bits)).collect()
    };
    let mut partial = 0;
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        for kind in JointType::all() {
            let reads = model_reads(kind, space);
            partial += usize::from(reads != Drawn::All);
            for seed in 0..200u64 {
                let whole = random_geometry(kind, space, &mut SplitMix64::new(seed));
                let g = random_geometry_to(kind, space, &mut SplitMix64::new(seed), reads);
                let fields = |g: &Geometry| {
                    [g.origin, g.axis, g.axis2, g.normal, g.origin2]
                        .map(|f| f.map(|a| a.map(f64::to_bits)))
                };
                for (a, b) in fields(&g).iter().zip(fields(&whole)) {
                    assert!(a.is_none() || *a == b, "{kind:?} {space:?}");
                }
                assert!(g.pitch.is_none() || g.pitch == whole.pitch);
                for driven in 0..=kind.grade() as u32 {
                    let what = format!("{kind:?} {space:?} driven {driven} seed {seed}");
                    match (
                        stack_model(kind, &g, space, driven),
                        stack_model(kind, &whole, space, driven),
                    ) {
                        (Ok(a), Ok(b)) => {
                            assert_eq!(bits(&a.rows), bits(&b.rows), "{what}");
                            assert_eq!(bits(&a.twists), bits(&b.twists), "{what}");
                        }
                        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "{what}"),
                        (a, b) => panic!("{what}: {a:?} against {b:?}"),
                    }
                }
            }
        }
    }
    assert!(partial >= 15, "{partial}");
}

/// Work regression: [`complement`] projected every unit vector for every new vector
/// (`B` per row of the model, 30 for a spatial revolute joint); at random geometry only
/// the one with the largest residual is projected.
#[test]
fn complement_projects_one_unit_vector_per_new_vector() {
    let mut rng = SplitMix64::new(3);
    for kind in [JointType::R, JointType::U, JointType::H] {
        let g = random_geometry(kind, Space::Spatial, &mut rng);
        let twists = full_twists(kind, &g, Space::Spatial).expect("modelled");
        PROJECTED.with(|c| c.set(0));
        let rows = complement::<6>(twists.as_slice());
        assert_eq!(rows.len(), 6 - twists.len());
        assert_eq!(PROJECTED.with(|c| c.get()), rows.len(), "{kind:?}");
    }
}

/// The complement by its definition: every unit vector projected ([`project_out`]) for every
/// new vector, the one with the largest residual taken.
fn naive_complement<const N: usize>(cols: &[Vb]) -> Vec<Vb> {
    let mut basis: Vec<Vb> = orthonormal::<N>(cols).as_slice().to_vec();
    let first_new = basis.len();
    while basis.len() < N {
        let mut best: Option<(Vb, f64)> = None;
        for i in 0..N {
            let mut v = [0.0; MAX_B];
            v[i] = 1.0;
            project_out::<N>(&mut v, &basis);
            let n = norm::<N>(&v);
            if best.is_none_or(|(_, w)| n > w) {
                best = Some((v, n));
            }
        }
        let (v, n) = best.expect("N > 0");
        basis.push(normalized::<N>(&v, n));
    }
    basis[first_new..].to_vec()
}

fn check_complement(cols: &[Vb], b: usize, trial: usize) {
    let got = complement_in(cols, b);
    let want = match b {
        6 => naive_complement::<6>(cols),
        _ => naive_complement::<3>(cols),
    };
    assert_eq!(got.len(), want.len(), "trial {trial}: {cols:?}");
    for (g, w) in got.as_slice().iter().zip(&want) {
        let bits = |v: &Vb| v.map(f64::to_bits);
        assert_eq!(bits(g), bits(w), "trial {trial}: {cols:?}");
    }
}

#[test]
fn splitmix_vector() {
    let mut r = SplitMix64::new(0);
    assert_eq!(r.next_u64(), 0xe220a8397b1dcdaf);
    assert_eq!(r.next_u64(), 0x6e789e6aa1b965f4);
}

#[test]
fn every_kind_has_consistent_rows_and_twists() {
    for space in [Space::Spatial, Space::Planar, Space::Spherical] {
        let b = space.b() as usize;
        for kind in JointType::all() {
            let mut rng = SplitMix64::new(kind as u64 + 11);
            let g = random_geometry(kind, space, &mut rng);
            for driven in 0..=kind.grade() as u32 {
                match joint_model(kind, &g, space, driven) {
                    Ok(m) => check(&m, b, kind.grade() as usize - driven as usize),
                    Err(MotionError::InvalidInSpace { .. }) => {
                        assert!(space != Space::Spatial, "{kind:?} spatial");
                    }
                    Err(e) => panic!("{kind:?} {space:?}: {e}"),
                }
            }
        }
    }
}

/// A driven DOF of a kind without named DOF keeps a generic direction. Formerly
/// a planar contact joint (one line, two allowed twists) dropped the first twist of its
/// pivoted basis, and whenever the pivot was the rotation the twist kept was `r × e_ω`, a
/// pure translation: a fixed fraction of draws gave an input that cannot turn the body.
/// Nothing driven gives the twists as before, and the same geometry the same model.
#[test]
fn driven_dof_without_a_name_is_generic() {
    let mut rng = SplitMix64::new(16);
    for (kind, space) in [
        (JointType::EO, Space::Planar),
        (JointType::RP, Space::Planar),
        (JointType::L, Space::Spherical),
        (JointType::SPSP, Space::Spatial),
        (JointType::CTEP, Space::Spatial),
    ] {
        let b = space.b() as usize;
        let k = kind.grade() as usize;
        for _ in 0..200 {
            let g = random_geometry(kind, space, &mut rng);
            let all = if modelled(kind, space) {
                full_twists(kind, &g, space).expect("a model")
            } else {
                complement_in(contact_rows_in(kind, &g, space).as_slice(), b)
            };
            let undriven = stack_model(kind, &g, space, 0).expect("a model");
            assert_eq!(undriven.twists, all, "{kind:?}: nothing driven, as before");
            for driven in 1..=k as u32 {
                let m = stack_model(kind, &g, space, driven).expect("a model");
                check(&m.matrices(), b, k - driven as usize);
                assert_eq!(m, stack_model(kind, &g, space, driven).expect("a model"));
                // Inside the allowed motions: annihilated by the undriven rows.
                for t in m.twists.as_slice() {
                    for r in undriven.rows.as_slice() {
                        let d: f64 = r.iter().zip(t).take(b).map(|(x, y)| x * y).sum();
                        assert!(d.abs() < 1e-12, "{kind:?}");
                    }
                }
            }
            if space == Space::Planar {
                // One twist kept: it turns the body (ω ≠ 0) and moves the origin.
                let t = stack_model(kind, &g, space, 1).expect("a model").twists;
                assert!(
                    t.as_slice()[0][0].abs() > 1e-6,
                    "{kind:?}: a pure translation"
                );
            }
        }
    }
    // The fallback model too: nothing driven as before, driven generic.
    for seed in 0..50 {
        let m = fallback_model(JointType::EO, Space::Planar, 1, seed);
        check(&m.matrices(), 3, 1);
        assert!(m.twists.as_slice()[0][0].abs() > 1e-6, "a pure translation");
    }
}

#[test]
fn planar_revolute_twist() {
    let g = Geometry {
        origin: Some([2.0, 3.0, 0.0]),
        ..Geometry::default()
    };
    let m = joint_model(JointType::R, &g, Space::Planar, 0).unwrap();
    assert_eq!(m.twists.column(0).as_slice(), &[1.0, 3.0, -2.0]);
    // The velocity of the pin point itself is zero: v_p = v_O + ω ẑ × p.
    let (w, vx, vy) = (1.0, 3.0, -2.0);
    assert_eq!((vx - w * 3.0, vy + w * 2.0), (0.0, 0.0));
}

#[test]
fn spatial_revolute_and_driven_order() {
    let g = Geometry {
        origin: Some([1.0, 0.0, 0.0]),
        axis: Some([0.0, 0.0, 2.0]),
        ..Geometry::default()
    };
    let r = joint_model(JointType::R, &g, Space::Spatial, 0).unwrap();
    assert_eq!(
        r.twists.column(0).as_slice(),
        &[0.0, 0.0, 1.0, 0.0, -1.0, 0.0]
    );
    // C with the slide driven keeps only the turn.
    let c = joint_model(JointType::C, &g, Space::Spatial, 1).unwrap();
    assert_eq!(c.twists.column(0).as_slice(), r.twists.column(0).as_slice());
    check(&c, 6, 1);
}

#[test]
fn missing_fields_are_named() {
    let e = joint_model(JointType::U, &Geometry::default(), Space::Spatial, 0).unwrap_err();
    assert!(matches!(e, MotionError::MissingField { field: "axis", .. }));
    let g = Geometry {
        origin: Some([0.0; 3]),
        axis: Some([1.0, 0.0, 0.0]),
        ..Geometry::default()
    };
    let e = joint_model(JointType::U, &g, Space::Spatial, 0).unwrap_err();
    assert!(matches!(
        e,
        MotionError::MissingField { field: "axis2", .. }
    ));
    let m = Mechanism::from_parts(
        "t",
        Space::Spatial,
        BodyId::Int(1),
        vec![],
        vec![JointSpec::new(JointType::S, 1, 2, 0)],
    );
    let e = configure(&m).unwrap_err();
    assert_eq!(
        e.to_string(),
        "joint `1-2`: a S joint needs `origin` for geometric analysis"
    );
}

#[test]
fn ss_bar_has_one_isolated_spin() {
    let s = |p: [f64; 3]| {
        let g = Geometry {
            origin: Some(p),
            ..Geometry::default()
        };
        joint_model(JointType::S, &g, Space::Spatial, 0).unwrap()
    };
    let (a, b) = (s([0.1, 0.2, 0.3]), s([1.0, -0.5, 0.7]));
    let stacked = DMatrix::from_fn(6, 6, |i, j| {
        if i < 3 {
            a.rows[(i, j)]
        } else {
            b.rows[(i - 3, j)]
        }
    });
    let nullity = 6 - stacked.rank(1e-9);
    assert_eq!(nullity, 1);
    // The spin: rotation about the line through both centres.
    let u = Vector3::new(0.9, -0.7, 0.4).normalize();
    let t = DVector::from_vec(super::kinds::turn(&u.into(), &[0.1, 0.2, 0.3]).to_vec());
    assert!((&stacked * t).norm() < 1e-12);
}

#[test]
fn realize_is_per_joint() {
    let j = |a, b| JointSpec::new(JointType::R, a, b, 0);
    let m1 = Mechanism::from_parts(
        "a",
        Space::Spatial,
        BodyId::Int(1),
        vec![],
        vec![j(1, 2), j(2, 3)],
    );
    let m2 = Mechanism::from_parts(
        "b",
        Space::Spatial,
        BodyId::Int(1),
        vec![],
        vec![j(1, 2), j(2, 3), j(3, 1)],
    );
    let (r1, r2) = (realize(&m1, 5), realize(&m2, 5));
    assert_eq!(r1[..], r2[..2]);
    assert_ne!(r1[0], r1[1]);
}
