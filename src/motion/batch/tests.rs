//! The rows of many joints in lanes against the one-joint code, bit for bit.

use super::*;
use crate::rng::SplitMix64;

/// Work regression: the models of a random spatial mechanism (every kind of its mix,
/// some driven) are built in lanes, nearly all of them; before, one joint at a time (the
/// Gram-Schmidt's chain of dependent products waited on itself). Their rows are the
/// one-joint code's, bit for bit.
#[test]
fn a_random_mechanism_is_built_in_lanes() {
    for (planar, seed) in [(false, 3), (true, 4)] {
        let (m, _) = crate::generate::random(3000, planar, seed).expect("valid");
        let jobs: Vec<(usize, u32)> = (0..m.joints.len())
            .map(|i| (i, m.joints[i].driven))
            .collect();
        RUNS.with(|c| c.set([0; 2]));
        WIDE_STEPS.with(|c| c.set(0));
        let mut scratch = Scratch::default();
        let geometry = |i| super::super::random_pair_geometry(&m, 9, i);
        let rows = pair_rows_many(&m, &jobs, geometry, &mut scratch);
        let [lanes, single] = RUNS.with(|c| c.get());
        // (Planar: the count-only kinds of its mix, two thirds of the joints, are built
        // one at a time.)
        let ratio = if planar { 0 } else { 10 };
        assert!(
            lanes > ratio * single && lanes > 1000,
            "{lanes} in lanes, {single} alone"
        );
        // Most of them eight at a time (before: four).
        let wide = WIDE_STEPS.with(|c| c.get()) * LANES;
        assert!(2 * wide > lanes, "{wide} of {lanes} eight at a time");
        for (j, &(i, driven)) in jobs.iter().enumerate() {
            let want = super::super::pair_stack_model(&m, i, &geometry(i), driven).rows;
            let bits = |v: &[Vb]| v.iter().map(|x| x.map(f64::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(rows.get(j)), bits(want.as_slice()), "joint {i}");
        }
    }
}

/// The candidates of the lanes' complement (chosen without a branch per unit vector) are
/// the one-joint code's: bases with exact ties between unit vectors (axis-aligned,
/// permuted, signed, a rotation in one plane), nearly tied ones (within the gap or just
/// outside it), and lanes with infinite or NaN entries (all candidates, or the lane left
/// to the one-joint code); every lane's complement bit for bit.
#[test]
fn lane_candidates_are_the_one_joint_choice() {
    fn case<const N: usize, const L: usize>(rng: &mut SplitMix64, seen: &mut [usize; 3]) {
        let bits = |v: &Vecs| -> Vec<[u64; MAX_B]> {
            v.as_slice().iter().map(|x| x.map(f64::to_bits)).collect()
        };
        let k = 1 + rng.below(N as u64 - 1) as usize;
        let bases: Vec<Vecs> = (0..L)
            .map(|_| {
                // Unit vectors along distinct axes, signed.
                let mut axes: Vec<usize> = (0..N).collect();
                for i in (1..N).rev() {
                    axes.swap(i, rng.below(i as u64 + 1) as usize);
                }
                let mut vs: Vec<Vb> = axes[..k]
                    .iter()
                    .map(|&a| {
                        let mut v = [0.0; MAX_B];
                        v[a] = if rng.below(2) == 0 { 1.0 } else { -1.0 };
                        v
                    })
                    .collect();
                match rng.below(6) {
                    // A rotation in the plane of the first two axes (k ≥ 2).
                    0 | 1 if k >= 2 => {
                        let t = rng.next_signed() * [1.0, 1e-3, 1e-5, 1e-9][rng.below(4) as usize];
                        let (c, s) = (t.cos(), t.sin());
                        let (a, b) = (vs[0], vs[1]);
                        for x in 0..N {
                            vs[0][x] = c * a[x] - s * b[x];
                            vs[1][x] = s * a[x] + c * b[x];
                        }
                    }
                    2 => {
                        let x = rng.below(N as u64) as usize;
                        vs[0][x] = [f64::NAN, f64::INFINITY, 1e300][rng.below(3) as usize];
                    }
                    _ => {}
                }
                Vecs::of(&vs)
            })
            .collect();
        let refs: [&[Vb]; L] = std::array::from_fn(|l| bases[l].as_slice());
        let mut wide = [wide_zero::<L>(); MAX_B];
        widen(refs, &mut wide);
        let regular = complement_wide::<N, L>(&mut wide, k);
        for l in 0..L {
            if regular[l] {
                let got = lane_of::<N, L>(&wide[k..N], l);
                assert_eq!(bits(&got), bits(&complement_of::<N>(bases[l])));
                let tied = bases[l]
                    .as_slice()
                    .iter()
                    .all(|v| v.iter().all(|x| *x == 0.0 || x.abs() == 1.0));
                seen[usize::from(tied)] += 1;
            } else {
                seen[2] += 1;
            }
        }
    }
    let mut rng = SplitMix64::new(5);
    let mut seen = [0; 3];
    for t in 0..20_000 {
        match t % 4 {
            0 => case::<6, HALF>(&mut rng, &mut seen),
            1 => case::<3, HALF>(&mut rng, &mut seen),
            2 => case::<6, LANES>(&mut rng, &mut seen),
            _ => case::<3, LANES>(&mut rng, &mut seen),
        }
    }
    assert!(seen.iter().all(|&c| c > 100), "{seen:?}");
}

/// The lane kernels on random lists, with exact zeros, ties and dependent vectors, are bit
/// for bit the one-joint functions.
#[test]
fn lanes_are_the_one_joint_code() {
    lanes_case::<HALF>(99);
    lanes_case::<LANES>(98);
}

fn lanes_case<const L: usize>(seed: u64) {
    let mut rng = SplitMix64::new(seed);
    let bits = |v: &Vecs| -> Vec<[u64; MAX_B]> {
        v.as_slice().iter().map(|x| x.map(f64::to_bits)).collect()
    };
    let mut irregular = 0;
    for trial in 0..20_000 {
        let n = [3, 6][trial % 2];
        let k = 1 + (trial / 2) % (n - 1);
        let lists: Vec<Vec<Vb>> = (0..L)
            .map(|_| {
                (0..k)
                    .map(|_| {
                        let mut v = [0.0; MAX_B];
                        for x in v.iter_mut().take(n) {
                            let r = rng.next_signed();
                            *x = match rng.below(8) {
                                0 => 0.0,
                                1 => (r * 3.0).round(),
                                2 => r * 1e-12,
                                3 if trial % 97 == 0 => f64::NAN,
                                4 if trial % 89 == 0 => 1e300,
                                _ => r,
                            };
                        }
                        v
                    })
                    .collect()
            })
            .collect();
        let refs: [&[Vb]; L] = std::array::from_fn(|l| lists[l].as_slice());
        let want_o: Vec<Vecs> = refs
            .iter()
            .map(|r| {
                if n == 6 {
                    orthonormal::<6>(r)
                } else {
                    orthonormal::<3>(r)
                }
            })
            .collect();
        let (mut cols, mut out) = ([wide_zero::<L>(); MAX_B], [wide_zero::<L>(); MAX_B]);
        widen(refs, &mut cols);
        let kept = if n == 6 {
            orthonormal_wide::<6, L>(&cols, k, &mut out)
        } else {
            orthonormal_wide::<3, L>(&cols, k, &mut out)
        };
        for l in 0..L {
            if kept[l] {
                let got = if n == 6 {
                    lane_of::<6, L>(&out[..k], l)
                } else {
                    lane_of::<3, L>(&out[..k], l)
                };
                assert_eq!(bits(&got), bits(&want_o[l]), "trial {trial}");
            } else {
                assert!(
                    want_o[l].len() < k,
                    "trial {trial}: a lane dropped a vector"
                );
                irregular += 1;
            }
        }
        // Complements of the bases that kept every vector.
        if want_o.iter().all(|b| b.len() == k) {
            let refs: [&[Vb]; L] = std::array::from_fn(|l| want_o[l].as_slice());
            let mut basis = [wide_zero::<L>(); MAX_B];
            widen(refs, &mut basis);
            let regular = if n == 6 {
                complement_wide::<6, L>(&mut basis, k)
            } else {
                complement_wide::<3, L>(&mut basis, k)
            };
            for l in 0..L {
                let want = if n == 6 {
                    complement_of::<6>(want_o[l])
                } else {
                    complement_of::<3>(want_o[l])
                };
                if regular[l] {
                    let got = if n == 6 {
                        lane_of::<6, L>(&basis[k..n], l)
                    } else {
                        lane_of::<3, L>(&basis[k..n], l)
                    };
                    assert_eq!(bits(&got), bits(&want), "trial {trial}");
                } else {
                    irregular += 1;
                }
            }
        }
    }
    assert!(irregular > 0, "the irregular lanes are exercised");
}
