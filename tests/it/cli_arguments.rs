//! Arguments that cannot mean what they say are refused with exit code 2 and a message that
//! names the problem, instead of being silently reinterpreted.

use assert_cmd::Command;

fn mbsa(args: &[&str]) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the mbsa binary is built")
        .args(args)
        .output()
        .expect("mbsa runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Two `--set` values for one joint: refused (the last one was silently kept), whether the
/// joint is named twice by id or once by id and once by its body pair.
#[test]
fn a_joint_set_twice_is_refused() {
    let (code, out, err) = mbsa(&["solve", "@rig-bennett", "--set", "A=20", "--set", "A=30"]);
    assert_eq!(code, 2, "{out}{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("joint `A` is given twice (`A=20` and `A=30`)"),
        "{err}"
    );
    let (code, _, err) = mbsa(&[
        "solve",
        "@slider-crank-geometry",
        "--set",
        "O=10",
        "--set",
        "ground-crank=20",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("joint `O` is given twice"), "{err}");
    // One value per joint still solves.
    let (code, _, err) = mbsa(&["solve", "@rig-bennett", "--set", "A=20"]);
    assert_eq!(code, 0, "{err}");
}

/// A joint both swept and set: the sweep would drop the `--set` without a word (exit 0, the
/// output of the sweep alone); refused instead.
#[test]
fn a_joint_swept_and_set_is_refused() {
    let (code, out, err) = mbsa(&[
        "solve",
        "@slider-crank-geometry",
        "--sweep",
        "O=0..90:30",
        "--set",
        "O=20",
    ]);
    assert_eq!(code, 2, "{out}{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("joint `O` is given by both `--sweep` and `--set` (`O=20`)"),
        "{err}"
    );
    let (code, _, err) = mbsa(&["solve", "@slider-crank-geometry", "--sweep", "O=0..90:30"]);
    assert_eq!(code, 0, "{err}");
}

/// A library type with a zero, zero-padded or overflowing pair count is refused with the
/// count and the range in the message; a plain one is read.
#[test]
fn library_counts_out_of_range_are_refused() {
    let dir = std::env::temp_dir().join(format!("mbsa-library-counts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("mkdir");
    for (t, count) in [
        ("0R3D", "0"),
        ("99999999999999999999999R3D", "99999999999999999999999"),
    ] {
        let path = dir.join("lib.toml");
        std::fs::write(&path, format!("types = [\"1R3D\", \"{t}\"]\n")).expect("write");
        let p = path.to_str().expect("UTF-8 path");
        let (code, out, err) = mbsa(&["analyze", "@rotor", "--library", p]);
        assert_eq!(code, 2, "{t}: {out}{err}");
        assert!(
            err.contains(&format!("`{t}` has the pair count `{count}`")),
            "{err}"
        );
        assert!(err.contains("from 1 to 4294967295"), "{err}");
        assert!(err.contains("line 1, column 18"), "{err}");
    }
    let path = dir.join("ok.toml");
    std::fs::write(&path, "types = [\"1R3D\", \"12R2D\"]\n").expect("write");
    let (code, _, err) = mbsa(&[
        "analyze",
        "@rotor",
        "--library",
        path.to_str().expect("UTF-8"),
    ]);
    assert_eq!(code, 0, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
