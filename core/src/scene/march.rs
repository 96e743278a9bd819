//! Marching a ray against a heightfield: the rigorous sphere tracing every surface shares
//! ([`march_heightfield`], [`sphere_trace`]), the refinement of a bracketed crossing ([`refine`]),
//! and the choice between the reference and the fast march ([`March`]).
//!
//! Step rule (sphere tracing for heightfields, docs/design/marches.md): along a ray `p(t) = o + t·d`, the gap
//! `z(t) − h(x(t))` changes at most at rate `|d_z| + K_d |d_xy|`, where `K_d` bounds the slope of h
//! along the ray's horizontal direction ([`crate::scene::surface::Surface::lipschitz_along`]). So the
//! step `Δt = gap/(|d_z| + K_d|d_xy|)` can never cross the surface. To bound the work where a ray
//! skims the surface, steps are at least `Δ_min` (1e-4 of the finest wavelength or texel); a sign
//! change of the gap is then refined. A feature can be missed only if it pokes through the ray over
//! less than Δ_min, i.e. never in practice. Rays stop once outside the slab `|h| ≤ h_max`.

use glam::{DVec2, DVec3};

/// How a march steps and refines the crossing it brackets: the selectable reference, and the fast
/// path that replaces it (issue #15 measures one against the other; both are rigorous).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum March {
    /// Over-relaxed sphere tracing with the global Lipschitz bound ([`march_heightfield`]), and
    /// bisection of the bracket: 48 halvings in f64 (24 in the f32 WGSL).
    Reference,
    /// For a noise driver, the octave march ([`crate::scene::octave_march`]: nested octave levels,
    /// first- and second-order steps); for an image the reference's steps. The crossing is refined
    /// by the Illinois method (a bracketed secant whose stale end is halved) until the bracket is
    /// as narrow as the reference's (or at the precision of t), typically in 5–8 evaluations
    /// instead of 48 (24 on the GPU). It keeps the bracket, so it returns a point above the surface
    /// within the same crossing interval as the reference.
    #[default]
    Fast,
}

/// Over-relaxation factor of the march (after Keinert et al. 2014, "Enhanced Sphere Tracing").
pub const RELAXATION: f64 = 1.6;

/// Sphere tracing on any heightfield `height` bounded by |h| ≤ `h_max`, along `p(t) = o + t·d`,
/// with `rate` a bound on how fast the gap `z − h` can change per unit t (see the module docs).
///
/// At a point with gap g ≥ 0 no crossing lies within `g/rate` on either side. Steps are over-relaxed
/// (`RELAXATION·g/rate`); before anything else is concluded at the new point (a hit, or leaving the
/// slab), the safe intervals of the two points must cover everything between them, otherwise the march
/// backs off to the end of the previous safe interval and steps unrelaxed — so relaxation never skips
/// a crossing. Steps are at least `min_step`; a sign change is refined by 48 bisections, returning the
/// last point above the surface. A negative gap at t = 0 is rounding (the origin is on the surface by
/// contract). `None` when the ray leaves the slab. Shared by the explicit and the level-of-detail surface.
/// `march` chooses how the crossing is refined ([`March`]).
pub fn march_heightfield(
    o: DVec3,
    d: DVec3,
    rate: f64,
    h_max: f64,
    min_step: f64,
    march: March,
    height: impl Fn(DVec2) -> f64,
) -> Option<f64> {
    let top = h_max * (1.0 + 1e-12) + 1e-300;
    sphere_trace(
        |t| {
            let p = o + d * t;
            p.z - height(DVec2::new(p.x, p.y))
        },
        rate,
        min_step,
        |t| {
            let z = o.z + d.z * t;
            (d.z >= 0.0 && z > top) || (d.z < 0.0 && z < -top - 1.0)
        },
        march,
    )
}

/// The over-relaxed sphere tracing shared by every surface: `gap(t)` is the signed distance-like
/// gap along the ray (≥ 0 outside), `rate` a bound on |d gap/dt|, `left(t)` says the ray has left
/// the region where the surface can be. Rules as in [`march_heightfield`]: relaxed steps back off
/// when the safe intervals do not cover them, steps are at least `min_step`, a sign change is refined
/// ([`refine`], by `march`) returning the last point above, a negative gap at t = 0 is rounding.
pub fn sphere_trace(
    gap: impl Fn(f64) -> f64,
    rate: f64,
    min_step: f64,
    left: impl Fn(f64) -> bool,
    march: March,
) -> Option<f64> {
    if !(rate > 0.0) {
        return None;
    }
    let (mut t, mut prev_t, mut prev_r, mut prev_g) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    let mut relaxed = false;
    for _ in 0..1_000_000 {
        let mut g = gap(t);
        if g < 0.0 && t == 0.0 {
            g = 0.0;
        }
        let r = g.max(0.0) / rate;
        if relaxed && t - prev_t > prev_r + r {
            // The relaxed step left a stretch no safe interval covers: back off and step safely.
            t = prev_t + prev_r.max(min_step);
            relaxed = false;
            continue;
        }
        if left(t) {
            return None;
        }
        if g < 0.0 {
            return Some(refine(&gap, (prev_t, prev_g), (t, g), march));
        }
        prev_t = t;
        prev_r = r;
        prev_g = g;
        let safe = r.max(min_step);
        let step = (RELAXATION * r).max(min_step);
        relaxed = step > safe;
        t += step;
    }
    None
}

/// The crossing in the bracket `a` (gap ≥ 0) to `b` (gap < 0): the last point found with gap ≥ 0,
/// at most the reference's final bracket width (`(b − a)/2⁴⁸`, or the precision of t) before the
/// crossing. [`March::Reference`] bisects 48 times; [`March::Fast`] runs the Illinois method
/// (regula falsi whose end that stays put twice has its gap halved), which keeps the bracket, falls
/// back to the midpoint when the secant leaves it, and stops at the same width.
/// [`March::Fast`]'s refinement stops at this fraction of max(|t|, 1), about 4500 f64 ulps of t:
/// below it the gap itself is rounding (a sum of unit-scale terms), so further halvings only
/// shuffle which side rounding puts a point on. Far below any shading precision.
pub const FAST_WIDTH: f64 = 1.0 / (1u64 << 40) as f64;

/// [`FAST_WIDTH`] for the f32 WGSL: 8 f32 ulps of max(|t|, 1).
pub const FAST_WIDTH_F32: f64 = 1.0 / (1u64 << 20) as f64;

pub fn refine(
    gap: &impl Fn(f64) -> f64,
    (mut a, mut ga): (f64, f64),
    (mut b, mut gb): (f64, f64),
    march: March,
) -> f64 {
    const HALVINGS: i32 = 48;
    match march {
        March::Reference => {
            for _ in 0..HALVINGS {
                let m = 0.5 * (a + b);
                if gap(m) >= 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            a
        }
        March::Fast => {
            let width = ((b - a) * 0.5f64.powi(HALVINGS)).max(FAST_WIDTH * b.abs().max(1.0));
            let mut side = 0;
            for _ in 0..2 * HALVINGS {
                if b - a <= width {
                    break;
                }
                let mut c = (a * gb - b * ga) / (gb - ga);
                if !(c > a && c < b) {
                    c = 0.5 * (a + b);
                }
                // Half a width inside the bracket: once the secant is that close to the crossing,
                // the next point lands across it and closes the bracket.
                c = c.clamp(a + 0.5 * width, b - 0.5 * width);
                let gc = gap(c);
                if gc >= 0.0 {
                    (a, ga) = (c, gc);
                    if side == 1 {
                        gb *= 0.5;
                    }
                    side = 1;
                } else {
                    (b, gb) = (c, gc);
                    if side == -1 {
                        ga *= 0.5;
                    }
                    side = -1;
                }
            }
            a
        }
    }
}
