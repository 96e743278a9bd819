//! Measurements behind #17's transfer-curve masking (`#[ignore]`d: they print tables; run with
//! `cargo test --release -p lodestone-core -- --ignored --nocapture transfer_conditioned`): what
//! a visibility that knows the point's driver value alone leaves, against one that also knows the
//! driver's slope along the view's azimuth (docs/design.md, "Transfer curves").

use super::measurements::{FrontPoint, front_point};
use crate::eval::test_materials::preset;
use crate::eval::{Evaluator, FootprintQuery};
use crate::scene::direction::direction;
use glam::{DMat3, DVec3};

/// Under a transfer curve a flat tread hides the driver's slope from the shading but not from the
/// masking: a tread point where f rises toward the light meets the next riser up, one where it
/// falls toward the eye looks down a riser. Over points of the explicit surface (uniform on the
/// mean plane, weighted by their projected area toward the eye, front faces), with each point's
/// radiance lit and unlit from `shade_hit`:
/// - `truth`: the points the eye sees, lit where a shadow ray reaches the sun;
/// - `value only`: each point weighted by the empirical P(seen | f) and lit with P(lit | seen, f)
///   (the best model whose visibility depends on the height alone: what the views' bins do);
/// - `value and slope`: the same on bins of (f, t_f), t_f the driver's slope along the view's
///   azimuth (the best model that also knows that slope).
///
/// Printed per configuration, against the point truth, and P(seen | t_f)/G1, P(lit | seen,
/// t_f)/V̄ on five bins of t_f/σ.
#[test]
#[ignore = "a measurement, prints a table"]
fn transfer_conditioned_visibility() {
    use crate::microfacet::slopes::normal_of;
    const FB: usize = 24;
    const TB: usize = 8;
    let n_points = 400_000;
    for (name, view, light, az) in [
        ("terraces", 60.0, 60.0, 180.0),
        ("terraces", 60.0, 60.0, 0.0),
        ("terraces", 85.0, 60.0, 180.0),
        ("sponge", 60.0, 60.0, 180.0),
        ("sponge", 85.0, 60.0, 180.0),
        ("default", 60.0, 60.0, 180.0),
    ] {
        let mut m = preset(name);
        m.brdf.specular = 0.0;
        let p = Evaluator::new(&m).expect("prepared");
        let s = &p.surface;
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let d = glam::DVec2::new(wo.x, wo.y).normalize();
        // Per point: (u, f, t_f, seen, faces the sun, lit, L lit, L unlit).
        let mut pts = Vec::with_capacity(n_points);
        let mut rng = 11u64;
        let mut clears = Vec::with_capacity(n_points);
        for _ in 0..n_points {
            let Some(FrontPoint { x, f, h, grad, u }) = front_point(s, wo, &mut rng) else {
                continue;
            };
            let (_, gf) = s.driver.value_and_gradient(x);
            let n = normal_of(grad);
            let pt = DVec3::new(x.x, x.y, h);
            let seen = s.sees(pt, wo);
            // Self-shadowing is the clamped cosine's (L lit = L unlit there): `lit` asks only
            // whether other surface blocks the sun, for the points that face it.
            let faces = n.dot(wi) > 0.0;
            let clear = faces && s.sees(pt, wi);
            let lit = seen && clear;
            let l1 = p.shade_hit(f, n, wo, wi, &DMat3::IDENTITY, || true);
            let l0 = p.shade_hit(f, n, wo, wi, &DMat3::IDENTITY, || false);
            pts.push((u, f, gf.dot(d), seen, faces, lit, l1, l0));
            clears.push(clear);
        }
        let sd_f = (pts.iter().map(|p| p.1 * p.1).sum::<f64>() / pts.len() as f64).sqrt();
        let sd_t = (pts.iter().map(|p| p.2 * p.2).sum::<f64>() / pts.len() as f64).sqrt();
        let fbin = |f: f64| (((f / sd_f + 3.0) / 6.0 * FB as f64).max(0.0) as usize).min(FB - 1);
        let tbin = |t: f64| (((t / sd_t + 2.0) / 4.0 * TB as f64).max(0.0) as usize).min(TB - 1);
        // Empirical visibilities on a set of bins: (all, seen, seen and facing the sun, lit)
        // projected-area weighted.
        let model = |key: &dyn Fn(f64, f64) -> usize, bins: usize| {
            let mut acc = vec![[0.0f64; 4]; bins];
            for (u, f, t, seen, faces, lit, ..) in &pts {
                let a = &mut acc[key(*f, *t)];
                a[0] += u;
                if *seen {
                    a[1] += u;
                    if *faces {
                        a[2] += u;
                    }
                    if *lit {
                        a[3] += u;
                    }
                }
            }
            let (mut num, mut den) = ([0.0; 3], 0.0);
            for (u, f, t, _, _, _, l1, l0) in &pts {
                let a = acc[key(*f, *t)];
                let g = if a[0] > 0.0 { a[1] / a[0] } else { 0.0 };
                let v = if a[2] > 0.0 { a[3] / a[2] } else { 0.0 };
                for k in 0..3 {
                    num[k] += u * g * (v * l1[k] + (1.0 - v) * l0[k]);
                }
                den += u * g;
            }
            num.map(|x| x / den)
        };
        // Seen and lit independent given the bin: P(seen | bin)·P(clear | bin), P(clear) over
        // every point that faces the sun (seen or not).
        let independent = |key: &dyn Fn(f64, f64) -> usize, bins: usize| {
            let mut acc = vec![[0.0f64; 4]; bins];
            for ((u, f, t, seen, faces, ..), clear) in pts.iter().zip(&clears) {
                let a = &mut acc[key(*f, *t)];
                a[0] += u;
                if *seen {
                    a[1] += u;
                }
                if *faces {
                    a[2] += u;
                    if *clear {
                        a[3] += u;
                    }
                }
            }
            let (mut num, mut den) = ([0.0; 3], 0.0);
            for (u, f, t, _, _, _, l1, l0) in &pts {
                let a = acc[key(*f, *t)];
                let g = if a[0] > 0.0 { a[1] / a[0] } else { 0.0 };
                let v = if a[2] > 0.0 { a[3] / a[2] } else { 0.0 };
                for k in 0..3 {
                    num[k] += u * g * (v * l1[k] + (1.0 - v) * l0[k]);
                }
                den += u * g;
            }
            num.map(|x| x / den)
        };
        let independent_value = independent(&|f, _| fbin(f), FB);
        let independent_slope = independent(&|f, t| fbin(f) * TB + tbin(t), FB * TB);
        let (mut t, mut tw) = ([0.0; 3], 0.0);
        for (u, _, _, seen, _, lit, l1, l0) in &pts {
            if *seen {
                for k in 0..3 {
                    t[k] += u * if *lit { l1[k] } else { l0[k] };
                }
                tw += u;
            }
        }
        let t = t.map(|v| v / tw);
        let value_only = model(&|f, _| fbin(f), FB);
        let value_slope = model(&|f, t| fbin(f) * TB + tbin(t), FB * TB);
        let rel = |v: [f64; 3], r: [f64; 3]| {
            (0..3)
                .map(|k| 100.0 * (v[k] - r[k]) / r[k])
                .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
        };
        let cfg = FootprintQuery::far(&p, wo, wi);
        let gt = p.ground_truth(&cfg, 100_000, 5);
        eprintln!(
            "{name:9} view {view} light {light}/{az} (specular 0): value only {:+6.2}%, value and slope {:+6.2}%, \
             seen and lit independent given the value {:+6.2}%, given value and slope {:+6.2}% \
             (against the point truth); filtered {:+6.2}%, point truth {:+6.2}% (against the ray truth)",
            rel(value_only, t),
            rel(value_slope, t),
            rel(independent_value, t),
            rel(independent_slope, t),
            rel(p.filtered(&cfg), gt.mean),
            rel(t, gt.mean),
        );
        // The views' height-only visibility (Smith with slopes that depend on the value, view
        // and light combined as G2 combines them) on a fine grid of z = (f − f̄)/σ_f, against
        // the empirical one on eight bins of z.
        let loc = p.footprint_stats(&cfg);
        let dr = loc.driver;
        let g = &m.heights.transfer;
        const ZN: usize = 1201;
        let zk = |k: usize| -6.0 + 12.0 * k as f64 / (ZN - 1) as f64;
        let (mut log_g1, mut log_g2) = (vec![0.0f64; ZN], vec![0.0f64; ZN]);
        for k in (0..ZN - 1).rev() {
            let z = 0.5 * (zk(k) + zk(k + 1));
            let cov = dr
                .gradient_cov
                .scaled(s.sigma_h * g.derivative(dr.mean + dr.std * z));
            let ms = crate::microfacet::masking_shadowing::G2::from_directions(
                wo,
                wi,
                &cov,
                m.filtering.correlation,
            );
            let rate = crate::math::special::norm_pdf(z)
                / crate::math::special::norm_cdf(z).max(1e-300)
                * (zk(k + 1) - zk(k));
            log_g1[k] = log_g1[k + 1] - ms.lambda_o * rate;
            log_g2[k] = log_g2[k + 1] - ms.total * rate;
        }
        let zbin = |f: f64| {
            let z = (f - dr.mean) / dr.std.max(1e-12);
            (((z + 2.0) / 4.0 * 8.0).max(0.0) as usize).min(7)
        };
        let at = |f: f64| {
            let z = (f - dr.mean) / dr.std.max(1e-12);
            let k = (((z + 6.0) / 12.0 * (ZN - 1) as f64).round().max(0.0) as usize).min(ZN - 1);
            (log_g1[k].exp(), (log_g2[k] - log_g1[k]).exp())
        };
        let mut rows = [[0.0f64; 8]; 8];
        for ((u, f, _, seen, faces, lit, ..), clear) in pts.iter().zip(&clears) {
            let r = &mut rows[zbin(*f)];
            let (mg1, mv) = at(*f);
            r[0] += u;
            r[1] += u * mg1;
            if *faces {
                r[6] += u;
                if *clear {
                    r[7] += u;
                }
            }
            if *seen {
                r[2] += u;
                if *faces {
                    r[3] += u;
                    r[4] += u * mv;
                    if *lit {
                        r[5] += u;
                    }
                }
            }
        }
        let cells: Vec<String> = rows
            .iter()
            .map(|r| {
                format!(
                    "{:.2}/{:.2} {:.2} {:.2}/{:.2}",
                    r[2] / r[0].max(1e-300),
                    r[1] / r[0].max(1e-300),
                    r[7] / r[6].max(1e-300),
                    r[5] / r[3].max(1e-300),
                    r[4] / r[3].max(1e-300)
                )
            })
            .collect();
        eprintln!(
            "    by z = (f − f̄)/σ_f in (−∞,−1.5) … (1.5,∞), step 0.5: G1 truth/model, P(clear) truth, V truth/model: {}",
            cells.join(" | ")
        );
        let (mut w, mut ws, mut wf, mut wl) = ([0.0; 5], [0.0; 5], [0.0; 5], [0.0; 5]);
        for (u, _, tf, seen, faces, lit, ..) in &pts {
            let z = tf / sd_t;
            let b = [-1.5, -0.5, 0.5, 1.5].iter().filter(|e| z > **e).count();
            w[b] += u;
            if *seen {
                ws[b] += u;
                if *faces {
                    wf[b] += u;
                }
                if *lit {
                    wl[b] += u;
                }
            }
        }
        let g1 = ws.iter().sum::<f64>() / w.iter().sum::<f64>();
        let vbar = wl.iter().sum::<f64>() / wf.iter().sum::<f64>();
        let seen: Vec<String> = (0..5)
            .map(|b| format!("{:.2}", ws[b] / w[b].max(1e-300) / g1))
            .collect();
        let lit: Vec<String> = (0..5)
            .map(|b| format!("{:.2}", wl[b] / wf[b].max(1e-300) / vbar))
            .collect();
        eprintln!(
            "    t_f/σ in (−∞,−1.5) … (1.5,∞) (negative: f falls toward the eye): P(seen | t_f)/G1 {}; \
             P(lit | seen, faces the sun, t_f)/V̄ {} (G1 {g1:.3}, V̄ {vbar:.3})",
            seen.join(" "),
            lit.join(" ")
        );
    }
}

/// Masking under a transfer curve, conditioned on the start's driver value f₀ and its slope t
/// along the ray's azimuth: the prototype of [`crate::microfacet::slope_masking`] with the ray
/// made a barrier in the driver's space. Along a horizontal direction the driver is a stationary
/// Gaussian process of autocovariance `R(τ) = Σ ½a_i² cos(ω_i τ)` (f, not h: the transfer is not
/// linear); the ray `h₀ + μs` (μ = cot θ) meets the surface `σ_h g(f)` where f crosses
/// `b(s) = g⁻¹((h₀ + μs)/σ_h)`, whose slope is `μ/(σ_h g′(b))` (steep over a tread, where the
/// ray climbs past a flat run of heights in no f at all). Rice's rate with Smith's "below so far",
/// `E[(f′ − b′)⁺ | f = b]·p(f = b)/P(f < b)`, the pair (f, f′) at s conditioned on (f₀, t).
/// Returns G1 on a grid of (f₀, t) for one direction; `t ≥ b′(0)` is a back face (0).
struct BarrierMasking {
    f0: Vec<f64>,
    t: Vec<f64>,
    g1: Vec<f64>,
}

impl BarrierMasking {
    fn new(m: &crate::material::Material, dir: glam::DVec2, mu: f64) -> Self {
        use crate::math::special::{norm_cdf, norm_pdf};
        use std::f64::consts::PI;
        let noise = m.noise().expect("a noise driver");
        let sh = m.heights.sigma_h;
        let g = &m.heights.transfer;
        let waves: Vec<(f64, f64)> = noise
            .waves
            .iter()
            .map(|w| (0.5 * w.amplitude * w.amplitude, 2.0 * PI * w.k.dot(dir)))
            .collect();
        let r0: f64 = waves.iter().map(|(c, _)| c).sum();
        let l2: f64 = waves.iter().map(|(c, w)| c * w * w).sum();
        // g on a fine grid of f for its inverse (non-decreasing).
        const GN: usize = 16001;
        let gf = |k: usize| -8.0 + 16.0 * k as f64 / (GN - 1) as f64;
        let gv: Vec<f64> = (0..GN).map(|k| g.eval(gf(k))).collect();
        let inverse = |y: f64| -> Option<f64> {
            if y > gv[GN - 1] {
                return None;
            }
            let k = gv.partition_point(|v| *v < y);
            if k == 0 {
                return Some(gf(0));
            }
            let (a, b) = (gv[k - 1], gv[k]);
            let w = if b > a { (y - a) / (b - a) } else { 1.0 };
            Some(gf(k - 1) + w * (gf(k) - gf(k - 1)))
        };
        let w_max = waves.iter().map(|(_, w)| w.abs()).fold(0.0, f64::max);
        let ds = (0.25 / w_max.max(1e-9)).min(0.05 * (r0 / l2).sqrt());
        let span = 2.5 * sh * (gv[GN - 1] - gv[0]) / mu.max(1e-6);
        let steps = ((span / ds).ceil() as usize).min(20_000);
        let ds = span / steps as f64;
        let grid: Vec<(f64, f64, f64)> = (0..steps)
            .map(|i| {
                let s = (i as f64 + 0.5) * ds;
                waves.iter().fold((0.0, 0.0, 0.0), |(a, b, c), (cw, w)| {
                    let (sn, cs) = (w * s).sin_cos();
                    (a + cw * cs, b - cw * w * sn, c - cw * w * w * cs)
                })
            })
            .collect();
        let (sf, st) = (r0.sqrt(), l2.sqrt());
        let f0: Vec<f64> = (0..141).map(|i| sf * (-3.5 + 0.05 * i as f64)).collect();
        let t: Vec<f64> = (0..41).map(|j| st * (-4.0 + 0.2 * j as f64)).collect();
        let mut g1 = Vec::with_capacity(f0.len() * t.len());
        for &x0 in &f0 {
            let h0 = g.eval(x0);
            let slope0 = mu / (sh * g.derivative(x0)).max(1e-300);
            for &t0 in &t {
                if t0 >= slope0 {
                    g1.push(0.0);
                    continue;
                }
                let mut integral = 0.0;
                for (i, &(r, r1, r2)) in grid.iter().enumerate() {
                    let s = (i as f64 + 0.5) * ds;
                    let Some(b) = inverse(h0 + mu * s / sh) else {
                        break;
                    };
                    let bd = mu / (sh * g.derivative(b)).max(1e-300);
                    let mh = r * x0 / r0 - r1 * t0 / l2;
                    let mp = r1 * x0 / r0 - r2 * t0 / l2;
                    let vh = (r0 - r * r / r0 - r1 * r1 / l2).max(1e-12 * r0);
                    let vp = l2 - r1 * r1 / r0 - r2 * r2 / l2;
                    let c = -(r * r1) / r0 - r1 * r2 / l2;
                    let z = (b - mh) / vh.sqrt();
                    let below = norm_cdf(z);
                    if below < 1e-300 {
                        integral = f64::INFINITY;
                        break;
                    }
                    let m2 = mp + c / vh * (b - mh);
                    let s2 = (vp - c * c / vh).max(1e-12 * l2).sqrt();
                    let q = (m2 - bd) / s2;
                    let up = s2 * norm_pdf(q) + (m2 - bd) * norm_cdf(q);
                    integral += up * norm_pdf(z) / vh.sqrt() / below * ds;
                    if integral > 700.0 {
                        break;
                    }
                }
                g1.push((-integral).exp());
            }
        }
        Self { f0, t, g1 }
    }

    /// G1 at (f₀, t), bilinear on the grid (clamped).
    fn at(&self, f0: f64, t: f64) -> f64 {
        let cell = |v: &[f64], x: f64| {
            let x = (x - v[0]) / (v[1] - v[0]);
            let x = x.clamp(0.0, (v.len() - 1) as f64 - 1e-9);
            let i = x as usize;
            (i, x - i as f64)
        };
        let (i, fi) = cell(&self.f0, f0);
        let (j, fj) = cell(&self.t, t);
        let n = self.t.len();
        let v = |i: usize, j: usize| self.g1[i * n + j];
        (v(i, j) * (1.0 - fj) + v(i, j + 1) * fj) * (1.0 - fi)
            + (v(i + 1, j) * (1.0 - fj) + v(i + 1, j + 1) * fj) * fi
    }
}

/// The prototype above against the explicit surface: per point of the surface (as in
/// [`transfer_conditioned_visibility`]), P(seen) and P(clear toward the sun) from
/// [`BarrierMasking`] along the view's and the light's azimuths, taken independent given (f₀, t)
/// (the two rays leave the point on opposite sides when the light is opposite), against the traced
/// rays: on bins of the driver's value, and the radiance weighted by them (specular 0).
#[test]
#[ignore = "a measurement, prints a table"]
fn transfer_conditioned_masking_prototype() {
    use crate::microfacet::slopes::normal_of;
    let n_points = 200_000;
    for (name, view, light, az) in [
        ("terraces", 60.0, 60.0, 180.0),
        ("terraces", 85.0, 60.0, 180.0),
        ("terraces", 45.0, 60.0, 180.0),
        ("sponge", 60.0, 60.0, 180.0),
    ] {
        let mut m = preset(name);
        m.brdf.specular = 0.0;
        let p = Evaluator::new(&m).expect("prepared");
        let s = &p.surface;
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let (d_o, d_i) = (
            glam::DVec2::new(wo.x, wo.y).normalize(),
            glam::DVec2::new(wi.x, wi.y).normalize(),
        );
        let masking = BarrierMasking::new(&m, d_o, wo.z / wo.x.hypot(wo.y));
        let shadowing = BarrierMasking::new(&m, d_i, wi.z / wi.x.hypot(wi.y));
        let mut rng = 11u64;
        // Truth and model on 8 bins of f (step 0.5 from −2): Σu, Σu·seen, Σu·G1o, Σu (facing
        // the sun), Σu·clear, Σu·G1i; radiance sums: truth, model.
        let mut bins = [[0.0f64; 6]; 8];
        let (mut tl, mut tw, mut ml, mut mw) = ([0.0; 3], 0.0, [0.0; 3], 0.0);
        for _ in 0..n_points {
            let Some(FrontPoint { x, f, h, grad, u }) = front_point(s, wo, &mut rng) else {
                continue;
            };
            let (_, gf) = s.driver.value_and_gradient(x);
            let n = normal_of(grad);
            let pt = DVec3::new(x.x, x.y, h);
            let seen = s.sees(pt, wo);
            let faces = n.dot(wi) > 0.0;
            let clear = faces && s.sees(pt, wi);
            let l1 = p.shade_hit(f, n, wo, wi, &DMat3::IDENTITY, || true);
            let l0 = p.shade_hit(f, n, wo, wi, &DMat3::IDENTITY, || false);
            let go = masking.at(f, gf.dot(d_o));
            let gi = if faces {
                shadowing.at(f, gf.dot(d_i))
            } else {
                0.0
            };
            let b = &mut bins[(((f + 2.0) / 0.5).max(0.0) as usize).min(7)];
            b[0] += u;
            b[1] += u * f64::from(u8::from(seen));
            b[2] += u * go;
            if faces {
                b[3] += u;
                b[4] += u * f64::from(u8::from(clear));
                b[5] += u * gi;
            }
            for k in 0..3 {
                if seen {
                    tl[k] += u * if clear { l1[k] } else { l0[k] };
                }
                ml[k] += u * go * (gi * l1[k] + (1.0 - gi) * l0[k]);
            }
            if seen {
                tw += u;
            }
            mw += u * go;
        }
        let err = (0..3)
            .map(|k| 100.0 * (ml[k] / mw - tl[k] / tw) / (tl[k] / tw))
            .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a });
        let cells: Vec<String> = bins
            .iter()
            .map(|b| {
                format!(
                    "{:.2}/{:.2} {:.2}/{:.2}",
                    b[1] / b[0].max(1e-300),
                    b[2] / b[0].max(1e-300),
                    b[4] / b[3].max(1e-300),
                    b[5] / b[3].max(1e-300)
                )
            })
            .collect();
        eprintln!(
            "{name:9} view {view} light {light}/{az} (specular 0): conditioned model {err:+.2}% against the point truth\n    \
             by f in (−∞,−1.5) … (1.5,∞), step 0.5: P(seen) truth/model, P(clear | faces the sun) truth/model: {}",
            cells.join(" | ")
        );
    }
}
