//! Numerical integration: Gauss–Legendre and Gauss–Hermite rules and composite Gauss–Legendre.
//!
//! Used to build tables (effective height moments, pre-convolutions) and, in tests, as the
//! independent reference that closed forms are checked against.

use std::sync::OnceLock;

/// Nodes and weights of the `n`-point Gauss–Legendre rule on [−1, 1], computed by Newton's method
/// on the Legendre recurrence (accurate to ~1e-15 for n ≤ 64). Exact for polynomials of degree 2n−1.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "a quadrature rule needs at least one node");
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    let nf = n as f64;
    for i in 0..n.div_ceil(2) {
        // Tricomi's initial guess for the i-th root.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let kf = k as f64;
                let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
                p0 = p1;
                p1 = p2;
            }
            let p = if n == 1 { x } else { p1 };
            let pm1 = if n == 1 { 1.0 } else { p0 };
            dp = nf * (x * p - pm1) / (x * x - 1.0);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        nodes[i] = -x;
        nodes[n - 1 - i] = x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    if n % 2 == 1 {
        nodes[n / 2] = 0.0;
    }
    (nodes, weights)
}

/// The 8-point Gauss–Legendre rule on [−1, 1], computed once.
pub fn gl8() -> &'static (Vec<f64>, Vec<f64>) {
    static RULE: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    RULE.get_or_init(|| gauss_legendre(8))
}

/// Composite Gauss–Legendre: `∫_a^b f` with `panels` equal panels of the 8-point rule.
pub fn integrate(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
    let (x, w) = gl8();
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let c = a + (p as f64 + 0.5) * h;
        for (xi, wi) in x.iter().zip(w) {
            sum += wi * f(c + 0.5 * h * xi);
        }
    }
    0.5 * h * sum
}

/// Nodes and weights for `E[f(Z)]`, `Z ~ N(0, 1)` (probabilists' Gauss–Hermite), `n` points,
/// obtained from the Golub–Welsch-free recurrence with Newton refinement. Exact for polynomials of
/// degree 2n−1; weights sum to 1.
pub fn gauss_hermite_normal(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(
        (1..=64).contains(&n),
        "Gauss–Hermite supports 1..=64 points"
    );
    // Physicists' Hermite roots by Newton from the asymptotic guesses (Numerical Recipes' scheme),
    // then scaled: x_prob = √2 x_phys, w_prob = w_phys/√π.
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    let nf = n as f64;
    let pim4 = std::f64::consts::PI.powf(-0.25);
    let m = n.div_ceil(2);
    let mut z = 0.0;
    for i in 0..m {
        z = match i {
            0 => (2.0 * nf + 1.0).sqrt() - 1.85575 * (2.0 * nf + 1.0).powf(-1.0 / 6.0),
            1 => z - 1.14 * nf.powf(0.426) / z,
            2 => 1.86 * z - 0.86 * nodes[0] / -std::f64::consts::SQRT_2,
            3 => 1.91 * z - 0.91 * nodes[1] / -std::f64::consts::SQRT_2,
            _ => 2.0 * z - nodes[i - 2] / -std::f64::consts::SQRT_2,
        };
        let mut pp = 0.0;
        for _ in 0..100 {
            let mut p1 = pim4;
            let mut p2 = 0.0;
            for j in 0..n {
                let p3 = p2;
                p2 = p1;
                let jf = j as f64;
                p1 = z * (2.0 / (jf + 1.0)).sqrt() * p2 - (jf / (jf + 1.0)).sqrt() * p3;
            }
            pp = (2.0 * nf).sqrt() * p2;
            let dz = p1 / pp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / (pp * pp);
        // Store probabilists' nodes (negative first).
        nodes[i] = -z * std::f64::consts::SQRT_2;
        nodes[n - 1 - i] = z * std::f64::consts::SQRT_2;
        weights[i] = w / std::f64::consts::PI.sqrt();
        weights[n - 1 - i] = w / std::f64::consts::PI.sqrt();
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legendre_integrates_polynomials_exactly() {
        for n in [1, 2, 5, 8, 16, 33] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13);
            for deg in 0..(2 * n) {
                let got: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let want = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!(
                    (got - want).abs() < 1e-13,
                    "n={n} deg={deg}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn composite_rule_integrates_exp() {
        let got = integrate(f64::exp, -1.0, 2.0, 4);
        assert!((got - (2f64.exp() - (-1f64).exp())).abs() < 1e-13);
    }

    #[test]
    fn hermite_reproduces_normal_moments() {
        for n in [1, 2, 3, 6, 10, 20, 32] {
            let (x, w) = gauss_hermite_normal(n);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "n={n}");
            // E[Z^2k] = (2k−1)!!
            let mut dfact = 1.0;
            for k in 0..n {
                if k > 0 {
                    dfact *= (2 * k - 1) as f64;
                }
                let got: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(x, w)| w * x.powi(2 * k as i32))
                    .sum();
                assert!(
                    ((got - dfact) / dfact).abs() < 1e-10,
                    "n={n} k={k}: {got} vs {dfact}"
                );
            }
        }
    }
}
