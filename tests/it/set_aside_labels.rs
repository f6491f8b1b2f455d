//! The equations set aside at the file's configuration do not depend on the body labels: a
//! random planar mechanism of R and P joints written in space (R axes along z, points in the
//! plane z = 0, P axes in the plane) has the planar file's structural groups and solve order,
//! and so has every renaming of its bodies.

use mbsa::format::{Format, load};
use mbsa::geometry::GeometrySource;
use mbsa::joint::JointType::{self, *};
use mbsa::mechanism::{BodyId, JointSpec, Mechanism, Space};
use mbsa::rng::SplitMix64;
use mbsa::structure::{Analysis, Library, Options, Status, analyze};

const KINDS: [JointType; 3] = [R, R, P];

fn count_only() -> Options {
    Options {
        count_only: true,
        ..Options::default()
    }
}

fn build(joints: &[JointSpec]) -> Mechanism {
    Mechanism::from_parts(
        "random",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        joints.to_vec(),
    )
}

fn count_status(joints: &[JointSpec]) -> (u64, u64, Status) {
    let a = analyze(&build(joints), &count_only(), &Library::empty()).expect("analyses");
    let d = a.diagnosis.as_ref();
    let missing = d
        .and_then(|d| d.underdetermined.as_ref())
        .map_or(0, |u| u.missing);
    let over = d
        .and_then(|d| d.overdetermined.as_ref())
        .map_or(0, |o| o.excess);
    (missing, over, a.status)
}

/// A joint of the random mechanism: kind, bodies (1 is the frame), driven DOF, point, and
/// the P axis (in the plane).
struct Pair {
    kind: JointType,
    bodies: [i64; 2],
    driven: u32,
    origin: [f64; 2],
    axis: [f64; 2],
}

/// A random connected planar mechanism of `n` bodies (frame 1) of R and P joints, determined
/// by counting (a spanning tree, extra joints that keep it free of over-determined parts,
/// inputs placed where they fix a missing DOF), at random geometry written with two decimals.
fn random_planar(n: usize, seed: u64) -> Option<Vec<Pair>> {
    let mut rng = SplitMix64::new(seed);
    let kind = |rng: &mut SplitMix64| KINDS[rng.below(KINDS.len() as u64) as usize];
    let mut joints: Vec<JointSpec> = Vec::new();
    for b in 2..=n as i64 {
        let a = 1 + rng.below(b as u64 - 1) as i64;
        joints.push(JointSpec::new(kind(&mut rng), a, b, 0));
    }
    for _ in 0..rng.below(2 * n as u64 + 1) {
        let a = 1 + rng.below(n as u64) as i64;
        let b = 1 + rng.below(n as u64) as i64;
        if a == b {
            continue;
        }
        joints.push(JointSpec::new(kind(&mut rng), a, b, 0));
        if count_status(&joints).1 > 0 {
            joints.pop();
        }
    }
    loop {
        let (miss, _, status) = count_status(&joints);
        if miss == 0 {
            if status != Status::Determined {
                return None;
            }
            break;
        }
        let start = rng.below(joints.len() as u64) as usize;
        let placed = (0..joints.len()).any(|i| {
            let j = (start + i) % joints.len();
            if joints[j].driven >= 1 {
                return false;
            }
            joints[j].driven = 1;
            let (m2, o2, _) = count_status(&joints);
            if o2 == 0 && m2 < miss {
                return true;
            }
            joints[j].driven = 0;
            false
        });
        if !placed {
            return None;
        }
    }
    let coord = |rng: &mut SplitMix64| (rng.below(2001) as f64 - 1000.0) / 100.0;
    Some(
        joints
            .into_iter()
            .map(|j| {
                let id = |b: &BodyId| match b {
                    BodyId::Int(i) => *i,
                    BodyId::Name(_) => unreachable!("integer bodies"),
                };
                let origin = [coord(&mut rng), coord(&mut rng)];
                let angle = rng.below(360) as f64 * std::f64::consts::PI / 180.0;
                let axis = [
                    (angle.cos() * 100.0).round() / 100.0,
                    (angle.sin() * 100.0).round() / 100.0,
                ];
                Pair {
                    kind: j.kind,
                    bodies: [id(&j.bodies[0]), id(&j.bodies[1])],
                    driven: j.driven,
                    origin,
                    axis,
                }
            })
            .collect(),
    )
}

/// The mechanism as a file: planar, or written in space; body `k` labelled `label[k - 1]`.
fn file(pairs: &[Pair], spatial: bool, label: &[i64]) -> String {
    let mut out = format!(
        "space = \"{}\"\nframe = {}\n",
        if spatial { "spatial" } else { "planar" },
        label[0]
    );
    let z = if spatial { ", 0" } else { "" };
    for p in pairs {
        let [a, b] = p.bodies.map(|x| label[x as usize - 1]);
        out.push_str(&format!(
            "\n[[joint]]\ntype = \"{}\"\nbodies = [{a}, {b}]\ndriven = {}\norigin = [{}, {}{z}]\n",
            p.kind.code(),
            p.driven,
            p.origin[0],
            p.origin[1]
        ));
        match (p.kind, spatial) {
            (R, true) => out.push_str("axis = [0, 0, 1]\n"),
            (P, _) => out.push_str(&format!("axis = [{}, {}{z}]\n", p.axis[0], p.axis[1])),
            _ => {}
        }
    }
    out
}

/// A group as the property compares it: its bodies (original labels, sorted), its level and
/// the bodies of the groups it depends on.
type Shape = (usize, Vec<i64>, Vec<Vec<i64>>);

/// The groups and their solve order, in original labels (`back[label]` is the body's
/// original number), independent of how the groups are numbered.
fn shape(a: &Analysis, back: &std::collections::HashMap<i64, i64>) -> Vec<Shape> {
    let bodies = |k: usize| -> Vec<i64> {
        let mut v: Vec<i64> = a.groups[k]
            .bodies
            .iter()
            .map(|s| back[&s.parse::<i64>().expect("integer body")])
            .collect();
        v.sort_unstable();
        v
    };
    let mut out: Vec<Shape> = (0..a.groups.len())
        .map(|k| {
            let mut deps: Vec<Vec<i64>> =
                a.groups[k].depends_on.iter().map(|&d| bodies(d)).collect();
            deps.sort();
            (a.groups[k].level, bodies(k), deps)
        })
        .collect();
    out.sort();
    out
}

fn analyze_file(text: &str) -> Analysis {
    let m = load("random.toml", text, Format::Toml).expect("loads");
    let opts = Options {
        geometry: GeometrySource::File,
        ..Options::default()
    };
    analyze(&m, &opts, &Library::empty()).expect("analyses")
}

/// A random permutation of the labels 1..=n.
fn permutation(n: usize, seed: u64) -> Vec<i64> {
    let mut rng = SplitMix64::new(seed);
    let mut p: Vec<i64> = (1..=n as i64).collect();
    for i in (1..n).rev() {
        p.swap(i, rng.below(i as u64 + 1) as usize);
    }
    p
}

/// One case: the planar file, the same in space, and the same in space with its bodies
/// renamed (two permutations), all with the same groups and solve order. `Ok(false)` when
/// there is no case: no mechanism, or a planar file at a special configuration (constraints
/// set aside in the plane too, as parallel P axes in a loop make), whose groups are not the
/// reference. `Err` names what differed.
fn case(n: usize, seed: u64) -> Result<bool, String> {
    case_with(n, seed, false)
}

/// [`case`], with `under`: the first input of the mechanism removed, so that part of it is
/// under-determined; a case whose spatial analysis sets a rigid part's own freedom aside
/// (parts on parallel P joints) is none, its groups being those of another rule.
fn case_with(n: usize, seed: u64, under: bool) -> Result<bool, String> {
    let Some(mut pairs) = random_planar(n, seed) else {
        return Ok(false);
    };
    if under {
        let Some(p) = pairs.iter_mut().find(|p| p.driven > 0) else {
            return Ok(false);
        };
        p.driven = 0;
    }
    let identity: Vec<i64> = (1..=n as i64).collect();
    let back_of = |label: &[i64]| -> std::collections::HashMap<i64, i64> {
        label
            .iter()
            .enumerate()
            .map(|(k, &l)| (l, k as i64 + 1))
            .collect()
    };
    let planar = analyze_file(&file(&pairs, false, &identity));
    if !planar.redundant.is_empty() {
        return Ok(false);
    }
    let planar = shape(&planar, &back_of(&identity));
    let mut labels = vec![identity.clone(), identity.iter().rev().copied().collect()];
    labels.push(permutation(n, seed ^ 0x1abe1));
    for label in &labels {
        let text = file(&pairs, true, label);
        let a = analyze_file(&text);
        if under && !(a.isolated.is_empty() && a.spins.is_empty()) {
            return Ok(false);
        }
        let spatial = shape(&a, &back_of(label));
        if spatial != planar {
            return Err(format!(
                "n = {n}, seed = {seed}, labels {label:?}: in space {spatial:?}, planar \
                 {planar:?}\n{text}"
            ));
        }
    }
    Ok(true)
}

/// Random planar mechanisms written in space, each under three labellings: `count` seeds
/// from `first` (at least half of them cases). The failures.
fn cases(first: u64, count: u64) -> Vec<String> {
    let mut failed = Vec::new();
    let mut checked = 0;
    for k in first..first + count {
        let n = 3 + (k % 8) as usize;
        match case(n, 0x5e7a_51de ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15)) {
            Ok(true) => checked += 1,
            Ok(false) => {}
            Err(e) => failed.push(e),
        }
    }
    assert!(
        checked >= count as usize / 2,
        "{checked} cases of {count} seeds"
    );
    failed
}

/// 200 cases (7 failed when the rows were chosen by frame distance alone: a pair of a later
/// group, first by its pair number, kept the out-of-plane rows of a one-body group or a dyad,
/// which merged into a coarser group).
#[test]
fn planar_in_space_has_the_planar_groups_under_any_labels() {
    let failed = cases(0, 200);
    assert!(
        failed.is_empty(),
        "{} failed:\n{}",
        failed.len(),
        failed.join("\n")
    );
}

/// 2,000 further cases (`--ignored`).
#[test]
#[ignore = "2,000 cases, about 30 s in a debug build"]
fn planar_in_space_has_the_planar_groups_under_any_labels_many() {
    let failed = cases(200, 2000);
    assert!(
        failed.is_empty(),
        "{} failed:\n{}",
        failed.len(),
        failed.join("\n")
    );
}

/// The seeds of the cases below, as the search that found them drew them.
fn found_seed(k: u64) -> u64 {
    0x1a4e ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15)
}

/// 47 bodies: the planar file has 18 groups. In space, the loop through a dyad joined to the
/// frame and to the 16-body group solved before it is nearer the frame than that group's own
/// loops: taken by frame distance, its rows kept the out-of-plane rows the group needed, and
/// the two merged (17 groups).
#[test]
fn a_47_body_mechanism_in_space_has_the_planar_groups() {
    assert_eq!(case(47, found_seed(207)), Ok(true));
}

/// 250 bodies: the planar file has 105 groups; in space, with the rows chosen by frame
/// distance and then again in the solve order of the best choice so far, it had 98 under its
/// own labels and 103 reversed or permuted.
#[test]
#[ignore = "250 bodies, about a minute in a debug build"]
fn a_250_body_mechanism_in_space_has_the_planar_groups() {
    assert_eq!(case(250, found_seed(4)), Ok(true));
}

/// Under-determined: the groups a first choice left in the under-determined part are found
/// too (28 bodies, its first input removed: the planar file has 13 groups; with only the
/// groups of the first choice split, 4 of its groups stayed in the under-determined part),
/// and 300 further seeds.
#[test]
fn under_determined_planar_in_space_has_the_planar_groups() {
    assert_eq!(case_with(28, found_seed(183), true), Ok(true));
    let mut failed = Vec::new();
    let mut checked = 0;
    for k in 0..300 {
        match case_with(5 + (k % 40) as usize, found_seed(k), true) {
            Ok(true) => checked += 1,
            Ok(false) => {}
            Err(e) => failed.push(e),
        }
    }
    assert!(checked >= 100, "{checked} cases");
    assert!(
        failed.is_empty(),
        "{} failed:\n{}",
        failed.len(),
        failed.join("\n")
    );
}
