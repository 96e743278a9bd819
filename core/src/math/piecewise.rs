//! Piecewise polynomials (degree ≤ 6, several channels on shared knots, constant outside the knots)
//! and their exact expectation under a Gaussian, `E[p(X)]`, `X ~ N(m, σ²)`.
//!
//! This is the convolution `(p ∗ N(0, σ²))(m)` of [HNPN14 Eq. 9] for colour maps and of
//! [HNPN14 Eqs. 21–28] for height transfer functions and their squares and derivatives. It is exact
//! up to rounding: no discretisation of the map, so step maps stay steps at σ = 0.
//!
//! Per segment `[a, b]`, `h = b − a`, with local variable `t = (x − a)/h ∈ [0, 1]`, we need the
//! moments `J_k = ∫_a^b t^k N(x; m, σ²) dx`, k ≤ 6:
//! * by the recurrence obtained from `N′ = −(x − m)/σ² N` and integration by parts:
//!   `J_{k+1} = −s(φ(β) − [k=0]φ(α)) + s²k J_{k−1} − ã J_k`, with `s = σ/h`, `ã = (a − m)/h`,
//!   `α = (a − m)/σ`, `β = (b − m)/σ`, `J_0 = Q(α) − Q(β)`; it amplifies rounding as s grows, and
//!   is used for s ≤ 4, where the measured worst error is 8e-12 at degree 6 (Φ and φ at a knot are
//!   shared by the two segments that meet there);
//! * otherwise (a Gaussian much wider than the segment), by 8-point Gauss–Legendre over the segment
//!   (the Gaussian then varies by a fraction of a standard deviation across it); measured error
//!   below 1e-13 (tests).
//!
//! Segments beyond 10σ from m are skipped (their mass is below 1e-23).

use crate::math::quadrature::gl8;
use crate::math::special::{erfc, norm_pdf};
use std::f64::consts::FRAC_1_SQRT_2;

/// Maximum polynomial degree per segment.
pub const MAX_DEGREE: usize = 6;
/// Number of coefficients per segment and channel.
pub const NCOEF: usize = MAX_DEGREE + 1;
/// Largest σ/h for which the moment recurrence is used (measured worst error 8e-12 for degree 6,
/// see the brute-force test); wider Gaussians use Gauss–Legendre.
const S_MAX: f64 = 4.0;

/// A multi-channel piecewise polynomial on shared knots `x_0 ≤ … ≤ x_n`, constant outside them.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewisePoly {
    /// Knots, non-decreasing. Zero-width segments are allowed (a jump) and contribute nothing.
    pub knots: Vec<f64>,
    /// Number of channels.
    pub channels: usize,
    /// `coeffs[seg * channels + ch][k]`: coefficient of `t^k` on segment `seg`, `t = (x − x_seg)/h`.
    pub coeffs: Vec<[f64; NCOEF]>,
    /// Value of each channel for `x < x_0`.
    pub left: Vec<f64>,
    /// Value of each channel for `x > x_n` (and at it).
    pub right: Vec<f64>,
}

/// `Q(z) = 1 − Φ(z)`.
fn upper(z: f64) -> f64 {
    0.5 * erfc(z * FRAC_1_SQRT_2)
}

impl PiecewisePoly {
    /// Number of segments.
    pub fn segments(&self) -> usize {
        self.knots.len().saturating_sub(1)
    }

    /// Evaluate every channel at x into `out` (length = channels). NaN evaluates as the left tail.
    pub fn eval(&self, x: f64, out: &mut [f64]) {
        let n = self.knots.len();
        if n == 0 || !(x >= self.knots[0]) {
            out.copy_from_slice(&self.left);
            return;
        }
        if x >= self.knots[n - 1] {
            out.copy_from_slice(&self.right);
            return;
        }
        // Last knot ≤ x (so a zero-width segment's right value wins, i.e. jumps are right-continuous).
        let seg = self.knots.partition_point(|k| *k <= x) - 1;
        let (a, b) = (self.knots[seg], self.knots[seg + 1]);
        let t = (x - a) / (b - a);
        for (ch, o) in out.iter_mut().enumerate() {
            let c = &self.coeffs[seg * self.channels + ch];
            *o = c.iter().rev().fold(0.0, |acc, ck| acc * t + ck);
        }
    }

    /// `E[p(X)]` for `X ~ N(m, σ²)`, every channel, into `out`. σ ≤ 0 evaluates at m.
    /// Finite for finite inputs; for σ = ∞ returns the average of the two tails (the limit).
    pub fn gaussian_expectation(&self, m: f64, sigma: f64, out: &mut [f64]) {
        self.expectation_with(m, sigma, out, upper, self.degree());
    }

    /// As [`Self::gaussian_expectation`] but with the tabulated upper tail [`fast_upper`]
    /// (absolute error ≤ 1e-13) and the degree given by the caller ([`Self::degree`], computed once):
    /// what table builders use.
    pub fn gaussian_expectation_fast(&self, m: f64, sigma: f64, out: &mut [f64], degree: usize) {
        self.expectation_with(m, sigma, out, fast_upper, degree);
    }

    /// The largest |p_ch(x)| over x ∈ [lo, hi], exact (up to rounding) for a channel of degree ≤ 2
    /// (both interval ends, the quadratic's vertex on each segment it crosses, the constant tails):
    /// what the march needs of g′, the derivative channel of [`crate::microfacet::transfer::Curve::moment_poly`]
    /// (a local Lipschitz constant of g). An empty or NaN interval (`!(lo <= hi)`) gives 0. Zero-width
    /// segments (jumps of p) contribute their neighbours' values only.
    pub fn max_abs_on(&self, ch: usize, lo: f64, hi: f64) -> f64 {
        let n = self.knots.len();
        if !(lo <= hi) {
            return 0.0;
        }
        if n == 0 {
            return self.left[ch].abs();
        }
        let mut best: f64 = 0.0;
        if lo < self.knots[0] {
            best = best.max(self.left[ch].abs());
        }
        if hi >= self.knots[n - 1] {
            best = best.max(self.right[ch].abs());
        }
        for seg in 0..n - 1 {
            let (a, b) = (self.knots[seg], self.knots[seg + 1]);
            if !(b > a) || hi < a || lo > b {
                continue;
            }
            let c = &self.coeffs[seg * self.channels + ch];
            debug_assert!(c[3..].iter().all(|v| *v == 0.0), "max_abs_on: degree > 2");
            let q = |t: f64| (c[2] * t + c[1]) * t + c[0];
            let t0 = ((lo - a) / (b - a)).clamp(0.0, 1.0);
            let t1 = ((hi - a) / (b - a)).clamp(0.0, 1.0);
            best = best.max(q(t0).abs()).max(q(t1).abs());
            if c[2] != 0.0 {
                let tv = -c[1] / (2.0 * c[2]);
                if tv > t0 && tv < t1 {
                    best = best.max(q(tv).abs());
                }
            }
        }
        best
    }

    /// The highest degree with a non-zero coefficient.
    pub fn degree(&self) -> usize {
        self.coeffs
            .iter()
            .map(|c| c.iter().rposition(|v| *v != 0.0).unwrap_or(0))
            .max()
            .unwrap_or(0)
    }

    /// `p(L(x))` for `L` the piecewise-linear interpolant of `(xs, ys)`, `ys` non-decreasing and
    /// `L` constant beyond the ends: exact, of p's degree, on the knots `xs` plus the preimages of
    /// p's knots inside each rising segment (a flat segment of L is p's constant value there, a
    /// jump of p stays a jump). What folds a histogram transfer `T⁻¹` into a colour map
    /// ([`crate::driver::histogram`]). Empty or mismatched `xs`/`ys` give p's left value.
    pub fn compose_linear(&self, xs: &[f64], ys: &[f64]) -> PiecewisePoly {
        let ch = self.channels;
        let mut value = vec![0.0; ch];
        let mut at = |y: f64| {
            self.eval(y, &mut value);
            value.clone()
        };
        if xs.is_empty() || xs.len() != ys.len() {
            let left = at(f64::NEG_INFINITY);
            return PiecewisePoly {
                knots: Vec::new(),
                channels: ch,
                coeffs: Vec::new(),
                left: left.clone(),
                right: left,
            };
        }
        let (left, right) = (at(ys[0]), at(ys[ys.len() - 1]));
        let mut knots = vec![xs[0]];
        let mut coeffs = Vec::new();
        for i in 0..xs.len() - 1 {
            let (xa, xb, ya, yb) = (xs[i], xs[i + 1], ys[i], ys[i + 1]);
            if !(xb > xa) {
                continue;
            }
            // Break points in y: the segment's ends and p's knots strictly inside.
            let mut ybreaks = vec![ya];
            if yb > ya {
                ybreaks.extend(self.knots.iter().copied().filter(|k| *k > ya && *k < yb));
                ybreaks.dedup();
            }
            ybreaks.push(yb);
            for w in ybreaks.windows(2) {
                let (y0, y1) = (w[0], w[1]);
                let x0 = if yb > ya {
                    xa + (y0 - ya) / (yb - ya) * (xb - xa)
                } else {
                    xa
                };
                let x1 = if yb > ya {
                    xa + (y1 - ya) / (yb - ya) * (xb - xa)
                } else {
                    xb
                };
                if !(x1 > x0) {
                    continue;
                }
                self.push_composed(y0, y1, &mut coeffs);
                knots.push(x1);
            }
        }
        PiecewisePoly {
            knots,
            channels: ch,
            coeffs,
            left,
            right,
        }
    }

    /// The coefficients (in the local variable u ∈ [0, 1]) of `p(y0 + (y1 − y0)·u)` on a span of y
    /// inside one of p's segments or tails, pushed channel by channel.
    fn push_composed(&self, y0: f64, y1: f64, coeffs: &mut Vec<[f64; NCOEF]>) {
        let n = self.knots.len();
        let mid = 0.5 * (y0 + y1);
        if n < 2 || !(mid >= self.knots[0]) || mid >= self.knots[n - 1] {
            let tail = if n > 0 && mid >= self.knots[n - 1] {
                &self.right
            } else {
                &self.left
            };
            for v in tail {
                let mut c = [0.0; NCOEF];
                c[0] = *v;
                coeffs.push(c);
            }
            return;
        }
        let seg = (self.knots.partition_point(|k| *k <= mid) - 1).min(n - 2);
        let (a, h) = (self.knots[seg], self.knots[seg + 1] - self.knots[seg]);
        // t = (y − a)/h = α + β·u.
        let (alpha, beta) = ((y0 - a) / h, (y1 - y0) / h);
        for chn in 0..self.channels {
            let src = &self.coeffs[seg * self.channels + chn];
            let mut c = [0.0; NCOEF];
            // Σ_k src_k (α + βu)^k by Horner in polynomials of u.
            for &sk in src.iter().rev() {
                let mut next = [0.0; NCOEF];
                for j in 0..NCOEF {
                    next[j] += c[j] * alpha;
                    if j + 1 < NCOEF {
                        next[j + 1] += c[j] * beta;
                    }
                }
                next[0] += sk;
                c = next;
            }
            coeffs.push(c);
        }
    }

    fn expectation_with(
        &self,
        m: f64,
        sigma: f64,
        out: &mut [f64],
        q: fn(f64) -> f64,
        degree: usize,
    ) {
        let nj = degree.min(MAX_DEGREE) + 1;
        let nk = self.knots.len();
        if !(sigma > 0.0) || nk == 0 {
            self.eval(m, out);
            return;
        }
        if !sigma.is_finite() {
            for (ch, o) in out.iter_mut().enumerate() {
                *o = 0.5 * (self.left[ch] + self.right[ch]);
            }
            return;
        }
        let alpha0 = (self.knots[0] - m) / sigma;
        let beta_n = (self.knots[nk - 1] - m) / sigma;
        let (wl, wr) = (1.0 - q(alpha0), q(beta_n));
        for (ch, o) in out.iter_mut().enumerate() {
            *o = wl * self.left[ch] + wr * self.right[ch];
        }
        let mut j = [0.0; NCOEF];
        // Φ-tail and φ at the left knot of the current segment, shared with the previous segment.
        let mut left: Option<(f64, f64, f64)> = None; // (z, Q(z), φ(z))
        for seg in 0..self.segments() {
            let (a, b) = (self.knots[seg], self.knots[seg + 1]);
            let h = b - a;
            let (alpha, beta) = ((a - m) / sigma, (b - m) / sigma);
            if !(h > 0.0) || alpha > 10.0 || beta < -10.0 {
                left = None;
                continue;
            }
            let s = sigma / h;
            if s > S_MAX {
                gl_moments(a, h, m, sigma, &mut j);
                left = None;
            } else {
                let (qa, pa) = match left {
                    Some((z, qz, pz)) if z == alpha => (qz, pz),
                    _ => (q(alpha), norm_pdf(alpha)),
                };
                let (qb, pb) = (q(beta), norm_pdf(beta));
                left = Some((beta, qb, pb));
                recurrence_moments(s, (a - m) / h, qa - qb, pa, pb, &mut j, nj);
            }
            for (ch, o) in out.iter_mut().enumerate() {
                let c = &self.coeffs[seg * self.channels + ch];
                *o += c[..nj]
                    .iter()
                    .zip(&j[..nj])
                    .map(|(c, j)| c * j)
                    .sum::<f64>();
            }
        }
    }
}

/// Upper tail `Q(z) = 1 − Φ(z)` from a quintic Hermite table (Φ, φ, φ′ at steps of 1/32 over
/// [−9, 9]; constant beyond): absolute error ≤ 1e-13 (tested), about 10× faster than `erfc`.
pub fn fast_upper(z: f64) -> f64 {
    use std::sync::OnceLock;
    const STEP: f64 = 1.0 / 32.0;
    const LO: f64 = -9.0;
    const N: usize = 577;
    static TABLE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..N)
            .map(|i| {
                let x = LO + STEP * i as f64;
                (upper(x), norm_pdf(x))
            })
            .collect()
    });
    if !(z > LO) {
        return if z.is_nan() { 0.5 } else { 1.0 };
    }
    let u = (z - LO) / STEP;
    let i = u as usize;
    if i >= N - 1 {
        return 0.0;
    }
    let t = u - i as f64;
    let (x0, x1) = (LO + STEP * i as f64, LO + STEP * (i + 1) as f64);
    let ((q0, p0), (q1, p1)) = (table[i], table[i + 1]);
    // Q′ = −φ, Q″ = zφ; scaled by the step.
    let (d0, d1) = (-p0 * STEP, -p1 * STEP);
    let (e0, e1) = (x0 * p0 * STEP * STEP, x1 * p1 * STEP * STEP);
    let t2 = t * t;
    let t3 = t2 * t;
    let t4 = t3 * t;
    let t5 = t4 * t;
    let h0 = 1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5;
    let h1 = t - 6.0 * t3 + 8.0 * t4 - 3.0 * t5;
    let h2 = 0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5;
    let h3 = 0.5 * t3 - t4 + 0.5 * t5;
    let h4 = -4.0 * t3 + 7.0 * t4 - 3.0 * t5;
    let h5 = 10.0 * t3 - 15.0 * t4 + 6.0 * t5;
    h0 * q0 + h1 * d0 + h2 * e0 + h3 * e1 + h4 * d1 + h5 * q1
}

/// Moments by the integration-by-parts recurrence (σ < h·s_max), from the segment mass
/// `J_0 = Q(α) − Q(β)` and φ at both ends.
fn recurrence_moments(s: f64, at: f64, j0: f64, pa: f64, pb: f64, j: &mut [f64; NCOEF], nj: usize) {
    j[0] = j0;
    j[1] = -s * (pb - pa) - at * j[0];
    for k in 1..nj.saturating_sub(1) {
        j[k + 1] = -s * pb + s * s * k as f64 * j[k - 1] - at * j[k];
    }
}

/// Moments by 8-point Gauss–Legendre over the segment split into panels at most one σ wide
/// (Gaussians wide compared with the segment).
fn gl_moments(a: f64, h: f64, m: f64, sigma: f64, j: &mut [f64; NCOEF]) {
    let (x, w) = gl8();
    let panels = (h / sigma).ceil().clamp(1.0, 64.0) as usize;
    let pw = 1.0 / panels as f64;
    j.fill(0.0);
    for p in 0..panels {
        for (xi, wi) in x.iter().zip(w) {
            let t = pw * (p as f64 + 0.5 * (xi + 1.0));
            let z = (a + h * t - m) / sigma;
            let weight = 0.5 * pw * wi * norm_pdf(z) * h / sigma;
            let mut tk = 1.0;
            for jk in j.iter_mut() {
                *jk += weight * tk;
                tk *= t;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::quadrature::integrate;

    /// `max_abs_on` against a dense scan of the interval, on a quadratic channel with a vertex inside
    /// a segment, a zero-width segment and non-zero tails, over random intervals (including ones
    /// beyond the knots and single points).
    #[test]
    fn max_abs_on_matches_a_dense_scan() {
        let p = PiecewisePoly {
            knots: vec![-1.0, 0.5, 0.5, 2.0],
            channels: 1,
            coeffs: vec![
                [0.3, 2.0, -2.5, 0.0, 0.0, 0.0, 0.0],
                [0.0; NCOEF],
                [-1.0, 0.5, 0.8, 0.0, 0.0, 0.0, 0.0],
            ],
            left: vec![0.2],
            right: vec![-0.4],
        };
        let mut rng = 7u64;
        let mut out = [0.0];
        for _ in 0..2000 {
            let a = -3.0 + 6.0 * crate::math::random::splitmix(&mut rng);
            let b = a + 3.0 * crate::math::random::splitmix(&mut rng).powi(3);
            let mut scan: f64 = 0.0;
            for i in 0..=4000 {
                p.eval(a + (b - a) * f64::from(i) / 4000.0, &mut out);
                scan = scan.max(out[0].abs());
            }
            let m = p.max_abs_on(0, a, b);
            assert!(m >= scan - 1e-12, "[{a}, {b}]: {m} below the scan's {scan}");
            assert!(
                m <= scan + 2e-3 * (b - a) + 1e-12,
                "[{a}, {b}]: {m} above the scan's {scan}"
            );
        }
        assert_eq!(p.max_abs_on(0, 1.0, 0.0), 0.0);
        assert_eq!(p.max_abs_on(0, f64::NAN, 1.0), 0.0);
    }

    fn sample_poly() -> PiecewisePoly {
        // Two channels: a degree-6 wiggle and a step-like cubic, with a zero-width segment (a jump).
        PiecewisePoly {
            knots: vec![-1.0, -0.2, -0.2, 0.7, 2.5],
            channels: 2,
            coeffs: vec![
                [0.1, 0.5, -0.3, 0.2, 0.1, -0.4, 0.3],
                [1.0, 0.0, 3.0, -2.0, 0.0, 0.0, 0.0],
                [9.0; NCOEF],
                [9.0; NCOEF],
                [0.5, -1.0, 2.0, 0.5, -0.7, 0.2, 0.1],
                [0.2, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.4, 0.0, 0.0, -0.3, 0.0, 0.0, 0.2],
                [-0.5, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            left: vec![0.1, 1.0],
            right: vec![0.3, 0.5],
        }
    }

    /// Brute force: adaptive-enough composite quadrature of p(x) N(x) split at the knots.
    fn brute(p: &PiecewisePoly, m: f64, s: f64, ch: usize) -> f64 {
        let mut out = vec![0.0; p.channels];
        let f = |x: f64| {
            let mut o = vec![0.0; p.channels];
            p.eval(x, &mut o);
            o[ch] * norm_pdf((x - m) / s) / s
        };
        let mut pts = vec![m - 14.0 * s];
        pts.extend(
            p.knots
                .iter()
                .copied()
                .filter(|k| (*k - m).abs() < 14.0 * s),
        );
        pts.push(m + 14.0 * s);
        pts.sort_by(f64::total_cmp);
        let mut total = 0.0;
        for w in pts.windows(2) {
            if w[1] > w[0] {
                total += integrate(f, w[0], w[1], 200);
            }
        }
        out[ch] = total;
        out[ch]
    }

    #[test]
    fn matches_brute_force_quadrature() {
        let p = sample_poly();
        let mut worst: f64 = 0.0;
        for &m in &[-3.0, -1.0, -0.5, -0.2, 0.0, 0.3, 0.7, 1.5, 2.5, 4.0] {
            for &s in &[1e-4, 0.01, 0.1, 0.5, 0.9, 1.0, 2.0, 5.0, 30.0] {
                let mut got = [0.0; 2];
                p.gaussian_expectation(m, s, &mut got);
                for ch in 0..2 {
                    let want = brute(&p, m, s, ch);
                    worst = worst.max((got[ch] - want).abs());
                    assert!(
                        (got[ch] - want).abs() < 1e-11,
                        "m={m} σ={s} ch={ch}: {} vs {want}",
                        got[ch]
                    );
                }
            }
        }
        eprintln!("piecewise Gaussian expectation worst abs error {worst:e}");
    }

    #[test]
    fn fast_upper_tail_is_accurate() {
        let mut worst: f64 = 0.0;
        for i in 0..200_001 {
            let z = -10.0 + 20.0 * f64::from(i) / 200_000.0;
            worst = worst.max((fast_upper(z) - upper(z)).abs());
        }
        assert!(worst < 1e-13, "fast Q error {worst:e}");
        let p = sample_poly();
        for &(m, s) in &[(0.1, 0.3), (2.0, 1.5), (-0.7, 0.05)] {
            let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
            p.gaussian_expectation(m, s, &mut a);
            p.gaussian_expectation_fast(m, s, &mut b, p.degree());
            assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
        }
    }

    #[test]
    fn sigma_zero_and_infinite() {
        let p = sample_poly();
        let mut a = [0.0; 2];
        let mut b = [0.0; 2];
        p.gaussian_expectation(0.1, 0.0, &mut a);
        p.eval(0.1, &mut b);
        assert_eq!(a, b);
        p.gaussian_expectation(0.1, f64::INFINITY, &mut a);
        assert_eq!(a, [0.2, 0.75]);
        // Continuity as σ → 0⁺ away from knots.
        p.gaussian_expectation(0.1, 1e-9, &mut a);
        assert!((a[0] - b[0]).abs() < 1e-8 && (a[1] - b[1]).abs() < 1e-8);
    }
}
