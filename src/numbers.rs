//! Numbers as written in files: how precisely a decimal's digits pin its value.

/// The rounding uncertainty of one number as written (see [`crate::motion::written_precision`]).
pub fn rounding_of(x: f64) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return 0.0;
    }
    let text = format!("{:e}", x.abs());
    let (mantissa, exp) = text.split_once('e').unwrap_or((&text, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let digits = mantissa.chars().filter(|c| c.is_ascii_digit()).count() as i32;
    if !(4..15).contains(&digits) {
        // Short numbers are exact; 15-17 digits is full double precision.
        return 0.0;
    }
    // The last significant digit sits at 10^(exp − digits + 1).
    0.5 * 10f64.powi(exp - digits + 1)
}
