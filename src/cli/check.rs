//! `mbsa check`: validate files and compare their `[expect]` tables.

use super::{Failure, emit, input};
use std::fmt::Write;

/// Check every file; exit 2 if any cannot be read, else 1 if any expectation fails.
pub fn run(
    files: &[String],
    input_format: Option<input::InputFormat>,
    geometry: &super::analysis::GeometryArgs,
) -> Result<(), Failure> {
    let opts = mbsa::rigidity::geometric::GeometricOptions {
        geometry: geometry.source(),
        precision: geometry.precision()?,
        check_finite: false,
    };
    let mut names: Vec<String> = Vec::new();
    for f in files {
        if f == "@all" {
            names.extend(mbsa::examples::names().map(|n| format!("@{n}")));
        } else {
            names.push(f.clone());
        }
    }
    let (mut failed, mut broken) = (0usize, Vec::new());
    for name in &names {
        let m = match input::load_path(name, input_format) {
            Ok(m) => m,
            Err(Failure::Input(msg)) => {
                broken.push(msg);
                continue;
            }
            Err(Failure::Check) => unreachable!("loading never fails a check"),
        };
        if let Err(Failure::Input(msg)) = geometry.closure_check(name, &m) {
            broken.push(msg);
            continue;
        }
        let outcomes = mbsa::expect::evaluate(&m, &opts);
        let mut text = String::new();
        let bad = outcomes.iter().filter(|o| !o.ok).count();
        if bad == 0 {
            let summary: Vec<String> = outcomes
                .iter()
                .map(|o| format!("{} {}", o.key, o.actual))
                .collect();
            let summary = if summary.is_empty() && m.expect.written {
                "valid (empty [expect] table: nothing checked)".to_string()
            } else if summary.is_empty() {
                "valid (no [expect] table)".to_string()
            } else {
                summary.join(", ")
            };
            let _ = writeln!(text, "ok      {name}: {summary}");
            for o in &outcomes {
                if let Some(n) = &o.note {
                    let _ = writeln!(text, "        note: {}: {n}", o.key);
                }
            }
        } else {
            failed += 1;
            let _ = writeln!(text, "FAILED  {name}:");
            for o in &outcomes {
                let mark = if o.ok { "ok" } else { "MISMATCH" };
                let _ = writeln!(
                    text,
                    "        {mark:<8} {}: expected {}, got {}",
                    o.key, o.expected, o.actual
                );
                if let Some(n) = &o.note {
                    let _ = writeln!(text, "                 note: {n}");
                }
            }
        }
        emit(&text)?;
    }
    if !broken.is_empty() {
        return Err(Failure::Input(broken.join("\n")));
    }
    if failed > 0 {
        emit(&format!(
            "{failed} of {} file(s) failed their expectations\n",
            names.len()
        ))?;
        return Err(Failure::Check);
    }
    Ok(())
}
