//! The first crossing near a point of the octave march ([`crate::scene::octave_march`]) for a
//! linear G (the identity), where the gap's slope is known exactly: its bracket from the gap's
//! second-order bounds ([`OctaveSurface::bracket_width`], CPU and GPU), and safeguarded Newton
//! inside it ([`OctaveSurface::converge`], CPU only).

use crate::scene::march::FAST_WIDTH;
use crate::scene::octave_march::OctaveSurface;

/// The first positive root of `γ − βs − cs²` (γ ≥ 0, c of either sign), or infinity when it stays
/// positive: `2γ/(β + √(β² + 4cγ))` wherever that denominator is positive (written without the
/// difference of roots, so f32 keeps it).
pub(crate) fn first_root(gap: f64, beta: f64, c: f64) -> f64 {
    let disc = beta * beta + 4.0 * c * gap;
    if !(disc >= 0.0) {
        return f64::INFINITY;
    }
    let den = beta + disc.sqrt();
    if den > 0.0 {
        2.0 * gap / den
    } else if gap == 0.0 && c > 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// The bracket `(s_lo, s_hi, s_hi − s_lo)` of the first zero of a gap with
/// `γ − βs − c₊s² ≤ γ(t + s) ≤ γ − βs − c₋s²`, `c± = c ± spread` (spread ≥ 0, γ > 0): `s_lo` and
/// `s_hi` the two bounds' first roots ([`first_root`]), the width written without their
/// difference, `16·spread·γ²/((√D₊ + √D₋)(β + √D₋)(β + √D₊))` with `D± = β² + 4c±γ`, so f32
/// keeps it to relative rounding. `None` when the upper bound never reaches 0.
fn quadratic_bracket(gap: f64, beta: f64, c: f64, spread: f64) -> Option<(f64, f64, f64)> {
    let (cp, cm) = (c + spread, c - spread);
    let (dp, dm) = (beta * beta + 4.0 * cp * gap, beta * beta + 4.0 * cm * gap);
    if !(dp >= 0.0 && dm >= 0.0) {
        return None;
    }
    let (rp, rm) = (dp.sqrt(), dm.sqrt());
    if !(beta + rm > 0.0) {
        return None;
    }
    let (lo, hi) = (2.0 * gap / (beta + rp), 2.0 * gap / (beta + rm));
    let width = 16.0 * spread * gap * gap / ((rp + rm) * (beta + rm) * (beta + rp));
    Some((lo, hi, width))
}

/// How many times [`OctaveSurface::cubic_step`] re-solves with the window it last found.
const CUBIC_TRIES: usize = 3;

/// The octave march's endgame near a transversal crossing ([`crate::scene::octave_march`]).
impl OctaveSurface<'_> {
    /// The first crossing's bracket ahead of a point at exact gap `γ = gap > 0` of a linear G (the
    /// identity): `(s_lo, s_hi − s_lo)`. With the gap's descent rate `β = σ_h f′ − d_z > 0` and
    /// `|γ″| ≤ 2c` (`c = σ_h M/2`, M the ray's curvature bound `curv`), `γ − βs − cs² ≤ γ(t + s) ≤
    /// γ − βs + cs²`: the lower bound stays positive up to `s_lo = 2γ/(β + √(β² + 4cγ))` (the safe
    /// step), and when `β² ≥ 4cγ` the upper bound reaches 0 at `s_hi = 2γ/(β + √(β² − 4cγ))`, so
    /// the first crossing lies in `(t + s_lo, t + s_hi]`. The width is written without the
    /// difference of the roots, `8cγ²·2/((√D₊ + √D₋)(β + √D₋)(β + √D₊))`, so f32 keeps it to
    /// relative rounding. `None` when G is not linear or the conditions do not hold.
    pub(crate) fn bracket_width(
        &self,
        gap: f64,
        fd: f64,
        curv: f64,
        dz: f64,
    ) -> Option<(f64, f64)> {
        if !self.linear || !(gap > 0.0) {
            return None;
        }
        let beta = self.sigma_h * fd - dz;
        let c = 0.5 * self.sigma_h * curv;
        quadratic_bracket(gap, beta, 0.0, c).map(|(lo, _, width)| (lo, width))
    }

    /// The third-order bound's `(β, q, r)` ([`OctaveSurface::cubic_step`]): from σ_h and the signed
    /// derivatives for the identity, from `sg` and their magnitudes under a transfer curve.
    fn cubic_terms(&self, fd: f64, fdd: f64, jerk: f64, dz: f64, sg: f64) -> (f64, f64, f64) {
        if self.linear {
            let s = self.sigma_h;
            (s * fd - dz, 0.5 * s * fdd, s * jerk / 6.0)
        } else {
            (sg * fd.abs() - dz, 0.5 * sg * fdd.abs(), sg * jerk / 6.0)
        }
    }

    /// The safe step from the gap's third-order bound: with the level's exact `f′ = fd` and
    /// `f″ = fdd` at the point and `|f‴| ≤ J = jerk` (`Σ|a_i||ω_i|³`),
    /// `γ(t + s) ≥ γ − βs − q s² − r s³` where, for the identity, `β = σ_h f′ − d_z`,
    /// `q = σ_h f″/2`, `r = σ_h J/6` (Taylor), and for a transfer curve with `|G′| ≤ g` over the
    /// range f reaches (`sg = σ_h g`), `β = sg|f′| − d_z`, `q = sg|f″|/2`, `r = sg J/6`
    /// (`|G(f(t+s)) − G(f(t))| ≤ g|f(t+s) − f(t)|` and Taylor on f). On a window `s ≤ S` the cubic
    /// is at least the quadratic with `c = q + rS`, whose first root ([`first_root`]) capped at S is
    /// safe. Unlike [`OctaveSurface::step`]'s global curvature `M = Σ|a_i|ω_i²` (every wave at its
    /// crest), this uses the curvature the ray has, so near a crossing it steps much closer.
    /// Windows: `2·from` (from: a step already proven safe), then each step found. 0 when the gap
    /// is not positive.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn cubic_step(
        &self,
        gap: f64,
        fd: f64,
        fdd: f64,
        jerk: f64,
        dz: f64,
        from: f64,
        sg: f64,
    ) -> f64 {
        if !(gap > 0.0) {
            return 0.0;
        }
        let (beta, q, r) = self.cubic_terms(fd, fdd, jerk, dz, sg);
        let mut window = 2.0 * from.max(self.min_step);
        let mut best = 0.0f64;
        for _ in 0..CUBIC_TRIES {
            let s = first_root(gap, beta, q + r * window);
            best = best.max(s.min(window));
            if !(s.is_finite() && s > 0.0) {
                break;
            }
            window = s;
        }
        best
    }

    /// [`OctaveSurface::bracket_width`] from the gap's third-order bounds (see
    /// [`OctaveSurface::cubic_step`]): on a window `s ≤ S`, `γ − βs − c₊s² ≤ γ(t + s) ≤ γ − βs − c₋s²`
    /// with `c± = q ± rS`, so when the upper bound's first root `s_hi` is within the window the
    /// first crossing lies in `(t + s_lo, t + s_hi]`, `s_lo` the lower bound's first root. The
    /// window is 1.25× the crossing the quadratic `γ − βs − qs²` predicts, then 1.25× the s_hi
    /// found. `(s_lo, s_hi − s_lo)`, the width written without the difference of the roots.
    pub(crate) fn cubic_bracket(
        &self,
        gap: f64,
        fd: f64,
        fdd: f64,
        jerk: f64,
        dz: f64,
    ) -> Option<(f64, f64)> {
        if !self.linear || !(gap > 0.0) {
            return None;
        }
        let (beta, q, r) = self.cubic_terms(fd, fdd, jerk, dz, self.sigma_h);
        let mut window = 1.25 * first_root(gap, beta, q);
        for _ in 0..2 {
            if !window.is_finite() {
                return None;
            }
            let (lo, hi, width) = quadratic_bracket(gap, beta, q, r * window)?;
            if hi <= window {
                return Some((lo, width));
            }
            window = 1.25 * hi;
        }
        None
    }

    /// Near a transversal crossing of a linear G (the identity), the first crossing directly: with
    /// the exact gap `γ = gap > 0`, its descent rate `β = σ_h f′ − d_z` and `|γ″| ≤ 2c`
    /// (`c = σ_h M/2`, M the ray's curvature bound `curv`), `γ(t + s) ≤ γ − βs + cs²`, which
    /// reaches 0 at `s_hi = 2γ/(β + √(β² − 4cγ))` when `β² ≥ 4cγ`, and `γ′ ≤ −β + 2cs < 0` up to
    /// there. So the first crossing is the only one in `(t, t + s_hi]`, where γ decreases
    /// strictly: safeguarded Newton (bisection when it leaves the bracket, half a width inside it
    /// so a converged step closes it) finds it to [`FAST_WIDTH`] in two or three evaluations of
    /// `exact` (gap and f′ at a t), instead of more safe steps, a crossing and [`refine`]. `None`
    /// when the conditions do not hold (then the march goes on as before). CPU only: on llvmpipe
    /// the Newton loop's divergence across SIMD lanes cost more than it saved (default preset, 96×64,
    /// 60°: naive 70.8 → 60.9 ms and ground truth 9055 → 7432 ns/ray without it), and both find
    /// the same crossing.
    pub(crate) fn converge(
        &self,
        exact: &impl Fn(f64) -> (f64, f64),
        t: f64,
        gap: f64,
        fd: f64,
        curv: f64,
        dz: f64,
    ) -> Option<f64> {
        if !self.linear || !(gap > 0.0) {
            return None;
        }
        let beta = self.sigma_h * fd - dz;
        let c = 0.5 * self.sigma_h * curv;
        let disc = beta * beta - 4.0 * c * gap;
        if !(beta > 0.0 && disc >= 0.0) {
            return None;
        }
        let mut b = t + 2.0 * gap / (beta + disc.sqrt());
        let width = FAST_WIDTH * b.abs().max(1.0);
        let (mut a, mut x, mut gx, mut rx) = (t, t, gap, beta);
        for _ in 0..64 {
            if b - a <= width {
                break;
            }
            let mut m = x + gx / rx;
            if !(m > a && m < b) {
                m = 0.5 * (a + b);
            }
            m = m.clamp(a + 0.5 * width, b - 0.5 * width);
            let (gm, fm) = exact(m);
            if gm >= 0.0 {
                a = m;
            } else {
                b = m;
            }
            // γ decreases strictly here: a rate that rounding makes non-positive bisects next.
            (x, gx, rx) = (m, gm, (self.sigma_h * fm - dz).max(f64::MIN_POSITIVE));
        }
        Some(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::random::splitmix;

    fn surface(sigma_h: f64) -> OctaveSurface<'static> {
        OctaveSurface {
            waves: &[],
            attenuation: None,
            ends: &[0],
            sigma_h,
            g_lip: 1.0,
            linear: true,
            monotone: Some(true),
            h_max: 1.0,
            min_step: 1e-12,
            g_slope: None,
            grid: None,
            field: None,
            settle_width: 0.0,
        }
    }

    /// The third-order step and bracket on random sums of cosines along a ray (the identity, and a
    /// transfer curve for the step), checked by a dense scan of the exact gap: no crossing within
    /// the step, and the first crossing inside the bracket. They must also do better than the global-curvature bounds somewhere (not vacuous).
    #[test]
    fn cubic_bounds_hold_on_random_waves() {
        let mut rng = 5u64;
        let (mut longer, mut longer_curve, mut narrower, mut brackets) = (0, 0, 0, 0);
        for case in 0..400 {
            let n = 1 + case % 24;
            let waves: Vec<(f64, f64, f64)> = (0..n)
                .map(|_| {
                    let a = (0.05 + splitmix(&mut rng)) / n as f64;
                    let om = (splitmix(&mut rng) - 0.5) * 40.0 * (1.0 + splitmix(&mut rng) * 4.0);
                    (a, om, std::f64::consts::TAU * splitmix(&mut rng))
                })
                .collect();
            // A quarter of the cases under a transfer curve G(f) = f + 0.3 sin 3f, |G′| ≤ 1.9.
            let curve = case % 4 >= 2;
            let mut s = surface(0.05 + splitmix(&mut rng));
            s.linear = !curve;
            let g = |x: f64| if curve { x + 0.3 * (3.0 * x).sin() } else { x };
            let sg = s.sigma_h * if curve { 1.9 } else { 1.0 };
            let dz = -(0.02 + splitmix(&mut rng));
            let f = |t: f64| {
                waves
                    .iter()
                    .map(|&(a, om, p)| a * (p + om * t).cos())
                    .sum::<f64>()
            };
            let total: f64 = waves.iter().map(|w| w.0).sum();
            // Half the rays start high in the slab, half just above the surface.
            let z0 = if case % 2 == 0 {
                s.sigma_h * (total + 0.3) * (0.2 + 0.8 * splitmix(&mut rng))
            } else {
                s.sigma_h * (g(f(0.0)) + total * 1e-3 * splitmix(&mut rng))
            };
            let gap = |t: f64| z0 + dz * t - s.sigma_h * g(f(t));
            let g0 = gap(0.0);
            if !(g0 > 0.0) {
                continue;
            }
            let fd = -waves
                .iter()
                .map(|&(a, om, p)| a * om * p.sin())
                .sum::<f64>();
            let fdd = -waves
                .iter()
                .map(|&(a, om, p)| a * om * om * p.cos())
                .sum::<f64>();
            let jerk: f64 = waves.iter().map(|&(a, om, _)| a * om.abs().powi(3)).sum();
            let curv: f64 = waves.iter().map(|&(a, om, _)| a * om * om).sum();
            let lip: f64 = waves.iter().map(|&(a, om, _)| a * om.abs()).sum();
            let global = s.step(g0, fd, lip, curv, dz, sg);
            let step = s.cubic_step(g0, fd, fdd, jerk, dz, global, sg);
            // The first crossing by a dense scan (to the end of the longer of the two windows).
            let end = 4.0 * global.max(step).min(1e3) + 1.0;
            let scan = 40_000;
            let first = (1..=scan)
                .map(|k| end * k as f64 / scan as f64)
                .find(|&t| gap(t) < 0.0);
            if step.is_finite() {
                let checks = 500;
                for k in 1..=checks {
                    let t = step * k as f64 / checks as f64;
                    assert!(
                        gap(t) >= -1e-12,
                        "case {case}: crossing at {t} within step {step}"
                    );
                }
            }
            if step > global * (1.0 + 1e-9) {
                longer += 1;
                longer_curve += usize::from(curve);
            }
            if let Some((lo, width)) = s.cubic_bracket(g0, fd, fdd, jerk, dz) {
                brackets += 1;
                let hit = first.expect("a bracket implies a crossing");
                let h = end / scan as f64;
                assert!(
                    hit > lo - h && hit <= lo + width + h,
                    "case {case}: crossing {hit} outside ({lo}, {})",
                    lo + width
                );
                if s.bracket_width(g0, fd, curv, dz)
                    .is_none_or(|(_, w)| width < w)
                {
                    narrower += 1;
                }
            }
        }
        assert!(
            longer > 100 && longer_curve > 30,
            "{longer} longer steps, {longer_curve} on a curve"
        );
        assert!(
            brackets > 50 && narrower > brackets / 2,
            "{narrower} of {brackets}"
        );
    }

    #[test]
    fn first_root_covers_every_sign() {
        // c > 0: 1 − s − s² = 0 at s = (√5 − 1)/2.
        assert!((first_root(1.0, 1.0, 1.0) - (5f64.sqrt() - 1.0) / 2.0).abs() < 1e-15);
        // c < 0 with a real root: 1 − 3s + s² = 0 at (3 − √5)/2.
        assert!((first_root(1.0, 3.0, -1.0) - (3.0 - 5f64.sqrt()) / 2.0).abs() < 1e-15);
        // c < 0 without one, and a rising line.
        assert_eq!(first_root(1.0, 1.0, -1.0), f64::INFINITY);
        assert_eq!(first_root(1.0, -1.0, 0.0), f64::INFINITY);
        assert_eq!(first_root(1.0, 2.0, 0.0), 0.5);
        assert_eq!(first_root(0.0, 1.0, 1.0), 0.0);
    }
}
