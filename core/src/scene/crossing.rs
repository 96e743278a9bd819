//! The first crossing near a point of the octave march ([`crate::scene::octave_march`]) for a
//! linear G (the identity), where the gap's slope is known exactly: its bracket from the gap's
//! second-order bounds ([`OctaveSurface::bracket_width`], CPU and GPU), and safeguarded Newton
//! inside it ([`OctaveSurface::converge`], CPU only).

use crate::scene::march::FAST_WIDTH;
use crate::scene::octave_march::OctaveSurface;

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
        let (dp, dm) = (beta * beta + 4.0 * c * gap, beta * beta - 4.0 * c * gap);
        if !(beta > 0.0 && dm >= 0.0) {
            return None;
        }
        let (rp, rm) = (dp.sqrt(), dm.sqrt());
        let lo = 2.0 * gap / (beta + rp);
        let width = 16.0 * c * gap * gap / ((rp + rm) * (beta + rm) * (beta + rp));
        Some((lo, width))
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
