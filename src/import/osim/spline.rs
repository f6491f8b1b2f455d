//! The functions of OpenSim's transform axes through knots: the cubic spline OpenSim evaluates
//! a `SimmSpline` and a `NaturalCubicSpline` with, and the piecewise-linear function.
//!
//! The spline is the interpolating cubic spline of Forsythe, Malcolm and Moler (*Computer
//! Methods for Mathematical Computations*, 1977, routines SPLINE and SEVAL): each end's third
//! derivative matches the third divided difference of its four nearest knots (a cubic through
//! the knots is reproduced exactly); two knots give the line through them, three a spline with
//! no end condition beyond that. Outside the knots both functions continue along the slope at
//! the nearest end, as OpenSim does.

/// Smallest knot spacing divided by (repeated abscissas are not divided by zero).
const TINY: f64 = 1e-20;

/// The knot interval `x` falls in: `k` with `xs[k] <= x <= xs[k + 1]` for ascending knots,
/// in `0..n-1` always (at least two knots).
fn interval(xs: &[f64], x: f64) -> usize {
    let n = xs.len();
    xs.partition_point(|&a| a <= x).clamp(1, n - 1) - 1
}

/// The piecewise-linear function through the knots (`xs` ascending, as long as `ys`, at least
/// two), extended along its end segments.
pub(super) fn linear(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let k = interval(xs, x);
    let slope = (ys[k + 1] - ys[k]) / (xs[k + 1] - xs[k]).max(TINY);
    ys[k] + (x - xs[k]) * slope
}

/// The cubic spline through the knots (`xs` ascending, as long as `ys`, at least two) at `x`,
/// extended linearly beyond the end knots.
pub(super) fn cubic(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let n = xs.len();
    if n == 2 {
        return linear(xs, ys, x);
    }
    let (b, c, d) = coefficients(xs, ys);
    if x < xs[0] {
        return ys[0] + (x - xs[0]) * b[0];
    }
    if x > xs[n - 1] {
        return ys[n - 1] + (x - xs[n - 1]) * b[n - 1];
    }
    let k = interval(xs, x);
    let t = x - xs[k];
    ys[k] + t * (b[k] + t * (c[k] + t * d[k]))
}

/// The coefficients `b`, `c`, `d` of each interval's cubic
/// `y_k + b_k t + c_k t^2 + d_k t^3`, `t = x - x_k` (at least three knots): the second
/// derivatives solve a tridiagonal system, with the ends' third derivatives from divided
/// differences when there are four knots or more.
fn coefficients(xs: &[f64], ys: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = xs.len();
    let h: Vec<f64> = xs.windows(2).map(|w| (w[1] - w[0]).max(TINY)).collect();
    let slope: Vec<f64> = (0..n - 1).map(|i| (ys[i + 1] - ys[i]) / h[i]).collect();
    // The system for σ (a third of the second derivative): diagonal `diag`, off-diagonal `h`,
    // right-hand side `rhs`.
    let mut diag = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    for i in 1..n - 1 {
        diag[i] = 2.0 * (h[i - 1] + h[i]);
        rhs[i] = slope[i] - slope[i - 1];
    }
    diag[0] = -h[0];
    diag[n - 1] = -h[n - 2];
    if n > 3 {
        let dd = |a: usize, b: usize| (xs[b] - xs[a]).max(TINY);
        let third_start = rhs[2] / dd(1, 3) - rhs[1] / dd(0, 2);
        let third_end = rhs[n - 2] / dd(n - 3, n - 1) - rhs[n - 3] / dd(n - 4, n - 2);
        rhs[0] = third_start * h[0] * h[0] / dd(0, 3);
        rhs[n - 1] = -third_end * h[n - 2] * h[n - 2] / dd(n - 4, n - 1);
    }
    // Forward elimination and back substitution.
    for i in 1..n {
        let t = h[i - 1] / diag[i - 1];
        diag[i] -= t * h[i - 1];
        rhs[i] -= t * rhs[i - 1];
    }
    let mut sigma = rhs;
    sigma[n - 1] /= diag[n - 1];
    for i in (0..n - 1).rev() {
        sigma[i] = (sigma[i] - h[i] * sigma[i + 1]) / diag[i];
    }
    let mut b = vec![0.0; n];
    let mut d = vec![0.0; n];
    for i in 0..n - 1 {
        b[i] = slope[i] - h[i] * (sigma[i + 1] + 2.0 * sigma[i]);
        d[i] = (sigma[i + 1] - sigma[i]) / h[i];
    }
    b[n - 1] = slope[n - 2] + h[n - 2] * (sigma[n - 2] + 2.0 * sigma[n - 1]);
    d[n - 1] = d[n - 2];
    let c = sigma.iter().map(|s| 3.0 * s).collect();
    (b, c, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + b.abs())
    }

    #[test]
    fn the_spline_passes_through_its_knots() {
        let xs = [-2.0, -1.2, 0.0, 0.5, 1.7, 3.0];
        let ys = [0.3, -0.1, 0.4, 0.45, -0.2, 0.0];
        for (x, y) in xs.iter().zip(&ys) {
            assert!(
                close(cubic(&xs, &ys, *x), *y),
                "{x}: {}",
                cubic(&xs, &ys, *x)
            );
        }
    }

    /// The end conditions match the third divided differences, so a cubic is reproduced
    /// exactly between and at the knots (a natural spline would bend it at the ends).
    #[test]
    fn a_cubic_through_the_knots_is_reproduced() {
        let f = |x: f64| 0.5 - 1.5 * x + 0.25 * x * x + 0.125 * x * x * x;
        let xs = [-2.0, -1.0, 0.0, 1.5, 2.0, 4.0];
        let ys: Vec<f64> = xs.iter().map(|&x| f(x)).collect();
        for x in [-1.9, -0.5, 0.3, 1.7, 3.9] {
            assert!(
                close(cubic(&xs, &ys, x), f(x)),
                "{x}: {} vs {}",
                cubic(&xs, &ys, x),
                f(x)
            );
        }
    }

    /// Beyond the end knots the spline goes on along its end slope (OpenSim's extrapolation),
    /// and two knots make the line through them.
    #[test]
    fn ends_and_two_knots_are_lines() {
        let f = |x: f64| 1.0 + 2.0 * x - x * x * x;
        let xs = [0.0, 1.0, 2.0, 3.0];
        let ys: Vec<f64> = xs.iter().map(|&x| f(x)).collect();
        let slope_end = 2.0 - 3.0 * 9.0;
        assert!(close(cubic(&xs, &ys, 4.0), f(3.0) + slope_end));
        let slope_start = 2.0;
        assert!(close(cubic(&xs, &ys, -1.0), f(0.0) - slope_start));
        assert!(close(cubic(&[0.0, 2.0], &[1.0, 5.0], 0.5), 2.0));
        assert!(close(cubic(&[0.0, 2.0], &[1.0, 5.0], -1.0), -1.0));
        assert!(close(linear(&xs, &ys, 1.5), 0.5 * (f(1.0) + f(2.0))));
        assert!(close(
            linear(&xs, &ys, 5.0),
            f(3.0) + 2.0 * (f(3.0) - f(2.0))
        ));
    }

    /// Repeated or descending abscissas give finite numbers, never a panic or a loop.
    #[test]
    fn degenerate_knots_stay_finite() {
        for xs in [
            [0.0, 0.0, 1.0, 1.0],
            [3.0, 2.0, 1.0, 0.0],
            [0.0, 1.0, 1.0, 2.0],
        ] {
            let ys = [1.0, 2.0, 0.5, 3.0];
            for x in [-1.0, 0.0, 0.5, 1.0, 2.5] {
                let _ = cubic(&xs, &ys, x);
                let _ = linear(&xs, &ys, x);
            }
        }
    }
}
