//! `mbsa report`: the HTML page through the real binary (one SVG per view, every group drawn,
//! one animation frame per sweep step, byte-identical reruns) and in a real browser (headless
//! Chromium: the script runs without error, draws the first frame and sets `data-ready`).

use crate::common::mbsa;
use std::path::{Path, PathBuf};

const FOUR_BAR: &str = "tests/fixtures/import/four_bar.sdf";
const CASSIE: &str = "tests/fixtures/import/cassie.xml";

fn report(file: &str) -> String {
    let (code, out, err) = mbsa(&["report", file]);
    assert_eq!(code, 0, "{file}: {err}");
    out
}

/// The group names of `mbsa analyze --format json`.
fn groups(file: &str) -> Vec<String> {
    let (code, out, err) = mbsa(&["analyze", file, "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    v["groups"]
        .as_array()
        .expect("groups")
        .iter()
        .map(|g| g["name"].as_str().expect("name").to_string())
        .collect()
}

/// The frames the page embeds.
fn frames(html: &str) -> Vec<Vec<f64>> {
    let start = "<script type=\"application/json\" id=\"frames\">";
    let Some(at) = html.find(start) else {
        return Vec::new();
    };
    let rest = &html[at + start.len()..];
    let end = rest.find("</script>").expect("closed");
    serde_json::from_str(&rest[..end]).expect("frames are JSON numbers")
}

#[test]
fn one_svg_per_view_and_every_group_drawn_and_tabled() {
    let html = report("@rotor");
    // No geometry in @rotor: the diagram and the rigid parts, no drawing.
    assert_eq!(html.matches("<svg ").count(), 2, "{html}");
    assert!(html.contains("id=\"no-drawing\""));
    let names = groups("@rotor");
    assert_eq!(names.len(), 7);
    for (i, name) in names.iter().enumerate() {
        assert!(
            html.contains(&format!("<g id=\"g{i}\" class=\"group")),
            "g{i}"
        );
        assert!(
            html.contains(&format!("<tr id=\"row-g{i}\"><td>{name}</td>")),
            "{name}"
        );
        assert!(html.contains(&format!(">{name}</text>")), "{name}");
    }
    // Types not in the library are marked in the diagram.
    assert!(html.contains("uncovered"));
    // Self-contained: nothing fetched.
    for external in ["src=\"http", "href=\"http", "<link ", "@import"] {
        assert!(!html.contains(external), "{external}");
    }
    let four = report(FOUR_BAR);
    assert_eq!(four.matches("<svg ").count(), 3);
    // The diagnosis names the four joints as input candidates: drawn as such.
    assert_eq!(
        four.matches("class=\"joint under redundant\"").count(),
        4,
        "{four}"
    );
    assert!(four.contains("id=\"under-determined\" class=\"part under\""));
}

#[test]
fn the_frames_are_the_library_sweeps_steps() {
    // No driven input: the first joint the diagnosis offers (joint_A), swept both ways; each
    // way stops at a dead point. The steps are those `mbsa solve --sweep` gives.
    let steps = |range: &str| {
        let (_, out, err) = mbsa(&[
            "solve",
            FOUR_BAR,
            "--sweep",
            &format!("joint_A={range}"),
            "--format",
            "json",
        ]);
        let v: serde_json::Value = serde_json::from_str(&out).expect(&err);
        v["steps"].as_array().expect("steps").len()
    };
    let (fwd, back) = (steps("0..360:5"), steps("0..-360:5"));
    assert!(fwd > 5 && back > 5, "{fwd} {back}");
    let html = report(FOUR_BAR);
    let f = frames(&html);
    assert_eq!(f.len(), fwd + back - 1);
    assert!(html.contains(&format!("data-frames=\"{}\"", f.len())));
    // Every frame places the same points, and the mechanism moves.
    assert!(f.iter().all(|x| x.len() == f[0].len() && !x.is_empty()));
    assert_ne!(f[0], f[f.len() - 1]);
    // A stopped sweep says why.
    assert!(html.contains("The sweep stopped: dead point"));
}

#[test]
fn the_same_input_gives_the_same_bytes() {
    for file in ["@rig-double-banana", FOUR_BAR] {
        let a = report(file);
        assert_eq!(a, report(file), "{file}");
        let dir = fresh_dir(&format!("out-{}", file.replace(['/', '@', '.'], "_")));
        let path = dir.join("out.html");
        let p = path.to_str().expect("UTF-8 path");
        let (code, out, err) = mbsa(&["report", file, "-o", p]);
        assert_eq!((code, out.as_str()), (0, ""), "{err}");
        assert_eq!(std::fs::read_to_string(&path).expect("written"), a);
    }
}

/// An empty directory under the test binary's temporary directory (`target/tmp`).
fn fresh_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("report_html")
        .join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("directory made");
    dir
}

const CHROMIUM: &str = "/usr/bin/chromium";

/// Chromium's arguments: no network, no profile of the user's.
fn chromium(profile: &Path, extra: &[&str], url: &str) -> std::process::Output {
    std::process::Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--virtual-time-budget=3000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("chromium runs")
}

/// The value of attribute `name` on the rendered `<body>`.
fn body_attr(dom: &str, name: &str) -> Option<String> {
    let body = &dom[dom.find("<body")?..];
    let tag = &body[..body.find('>')?];
    let key = format!("{name}=\"");
    let at = tag.find(&key)? + key.len();
    Some(tag[at..at + tag[at..].find('"')?].to_string())
}

#[test]
fn the_page_renders_in_a_browser() {
    if !Path::new(CHROMIUM).exists() {
        assert!(
            std::env::var_os("CI").is_none(),
            "{CHROMIUM} is missing (install Debian's `chromium`)"
        );
        eprintln!("note: {CHROMIUM} not found: browser test skipped");
        return;
    }
    let out_dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report_html");
    std::fs::create_dir_all(&out_dir).expect("artifact dir");
    let cases = [
        ("rotor", "@rotor"),
        ("stewart", "@stewart"),
        ("rig-double-banana", "@rig-double-banana"),
        ("cassie", CASSIE),
        ("four_bar", FOUR_BAR),
    ];
    for (name, file) in cases {
        let html = report(file);
        let page = out_dir.join(format!("{name}.html"));
        std::fs::write(&page, &html).expect("page written");
        let url = format!("file://{}", page.canonicalize().expect("page").display());
        let dump = chromium(&fresh_dir("profile"), &["--dump-dom"], &url);
        let dom = String::from_utf8_lossy(&dump.stdout);
        assert_eq!(body_attr(&dom, "data-error"), None, "{name}: script error");
        assert_eq!(
            body_attr(&dom, "data-ready").as_deref(),
            Some("1"),
            "{name}: {dom}"
        );
        for i in 0..groups(file).len() {
            assert!(
                dom.contains(&format!("<g id=\"g{i}\" class=\"group")),
                "{name}: g{i}"
            );
        }
        let n = frames(&html).len();
        if html.contains("id=\"mechanism\"") {
            assert!(n >= 1, "{name}");
            assert_eq!(
                body_attr(&dom, "data-frames-drawn"),
                Some(n.to_string()),
                "{name}"
            );
            // The first frame drawn: the slider's label names it.
            assert!(dom.contains(&format!("frame 1 of {n}")), "{name}");
        }
        let shot = out_dir.join(format!("{name}.png"));
        let _ = std::fs::remove_file(&shot);
        let arg = format!("--screenshot={}", shot.display());
        chromium(
            &fresh_dir("profile"),
            &[&arg, "--window-size=1200,900"],
            &url,
        );
        let png = std::fs::read(&shot).expect("screenshot written");
        assert!(png.starts_with(b"\x89PNG"), "{name}");
    }
    // Cassie and the four-bar are drawn and animated.
    for name in ["cassie", "four_bar"] {
        let html = std::fs::read_to_string(out_dir.join(format!("{name}.html"))).expect("page");
        assert!(frames(&html).len() >= 2, "{name}");
    }
}
