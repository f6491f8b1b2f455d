//! `mbsa completions SHELL` and `mbsa man [COMMAND]`: scripts that the shells accept and
//! manual pages that `man` renders (each tool checked only where it is installed).

use assert_cmd::Command;
use std::path::PathBuf;

fn mbsa(args: &[&str]) -> (i32, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the binary is built")
        .args(args)
        .output()
        .expect("the binary runs");
    let code = out.status.code().expect("exited normally");
    (code, String::from_utf8(out.stdout).expect("UTF-8"))
}

/// Whether `tool` runs here.
fn installed(tool: &str) -> bool {
    std::process::Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn every_shell_gets_a_script_naming_the_commands() {
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let (code, script) = mbsa(&["completions", shell]);
        assert_eq!(code, 0, "{shell}");
        for word in ["mbsa", "analyze", "check", "files-from", "completions"] {
            assert!(script.contains(word), "{shell} script lacks `{word}`");
        }
    }
    assert_ne!(
        mbsa(&["completions", "tcsh"]).0,
        0,
        "an unknown shell is a usage error"
    );
}

#[test]
fn bash_accepts_the_script_and_completes_mbsa() {
    let (_, script) = mbsa(&["completions", "bash"]);
    assert!(script.contains("complete -F _mbsa") || script.contains("-F _mbsa"));
    if !installed("bash") {
        eprintln!("bash not installed: only the script's text was checked");
        return;
    }
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_completions");
    std::fs::create_dir_all(&dir).expect("writable");
    let path = dir.join("mbsa.bash");
    std::fs::write(&path, script).expect("writable");
    let out = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!("source '{}' && complete -p mbsa", path.display()))
        .output()
        .expect("bash runs");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        said.contains("-F _mbsa") && said.trim_end().ends_with(" mbsa"),
        "{said}"
    );
}

#[test]
fn man_pages_are_roff_that_man_renders() {
    let (code, page) = mbsa(&["man"]);
    assert_eq!(code, 0);
    assert!(
        page.contains("\n.TH mbsa 1 "),
        "roff title line: {page:.200}"
    );
    assert!(page.contains(".SH SYNOPSIS") && page.contains(".SH OPTIONS"));
    let (code, check) = mbsa(&["man", "check"]);
    assert_eq!(code, 0);
    assert!(check.contains("\n.TH mbsa-check 1 "), "{check:.200}");
    assert!(
        check.contains("files\\-from"),
        "the page lists check's options"
    );
    assert_eq!(mbsa(&["man", "no-such-command"]).0, 2);
    if !installed("man") {
        eprintln!("man not installed: only the roff header was checked");
        return;
    }
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_completions");
    std::fs::create_dir_all(&dir).expect("writable");
    let path = dir.join("mbsa-check.1");
    std::fs::write(&path, check).expect("writable");
    let out = std::process::Command::new("man")
        .arg("-l")
        .arg(&path)
        .env("MANWIDTH", "80")
        .env("MANPAGER", "cat")
        .env("PAGER", "cat")
        .output()
        .expect("man runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("mbsa-check") && text.contains("SYNOPSIS"),
        "{text:.400}"
    );
}
