//! Numbers, strings and comments as the imported TOML writes them, and the rounding that
//! writing adds.

use super::JointRec;
use std::fmt::Write as _;

/// A number as written in the output: 10 decimals at most, trailing zeros trimmed (float noise
/// such as 6e-17 from cos 90° becomes 0).
pub(crate) fn num(x: f64) -> String {
    let s = format!("{x:.10}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" { "0".into() } else { s }
}

/// The rounding [`num`] adds to the numbers written: ±0.5·10^−10 when it rounds one, 0 when
/// every number is written exactly. Float noise of the composition (cos 90° = 6e-17 written
/// 0; below 1e-14 of the number) is not a rounding: what is written is the exact value.
pub(super) fn written_rounding(joints: &[JointRec]) -> f64 {
    let exact = |x: &f64| {
        num(*x)
            .parse::<f64>()
            .is_ok_and(|w| (w - x).abs() <= 1e-14 * x.abs().max(1.0))
    };
    let all_exact = joints.iter().all(|j| {
        let g = &j.geometry;
        let second = g.second.as_ref().map(|s| s.vectors()).unwrap_or_default();
        [g.origin, g.origin2, g.axis, g.axis2, g.normal]
            .into_iter()
            .chain(second.into_iter().map(|(_, v)| v))
            .flatten()
            .all(|v| v.iter().all(exact))
            && g.pitch.as_ref().is_none_or(exact)
    });
    if all_exact { 0.0 } else { 0.5e-10 }
}

/// A precision as written in the output: 3 significant digits at most (`5e-7`, `8.73e-5`).
pub(super) fn precision_text(p: f64) -> String {
    if p <= 0.0 || !p.is_finite() {
        return "0".into();
    }
    let s = format!("{p:.2e}");
    match s.split_once('e') {
        Some((mantissa, exp)) if mantissa.contains('.') => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{mantissa}e{exp}")
        }
        _ => s,
    }
}

/// A TOML basic string.
pub(super) fn toml_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Text safe inside a `#` comment (one line).
pub(super) fn comment_text(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}
