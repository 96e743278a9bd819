//! Measurements behind #17's slope-conditioned masking (all `#[ignore]`d: they print tables; run
//! with `cargo test --release -p lodestone-core --test measurements -- --ignored --nocapture NAME`): how much of the
//! grazing diffuse error a height-only visibility leaves, and a prototype of masking conditioned on
//! the facet's slope (docs/design/slope-masking.md, "The grazing diffuse error is slope-conditioned masking").

use crate::evaluation::{FrontPoint, front_point, worst_error};
use glam::{DVec2, DVec3};
use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::fixtures::preset;
use lodestone_core::scene::direction::direction;
use std::f64::consts::PI;

/// Is the grazing diffuse error slope-conditioned masking (#17: snake-skin at 75°, snow-under-sky
/// at 85°, default at 75–85° with specular 0)? Over points of the explicit surface (uniform on the
/// mean plane, each weighted by its projected area toward the eye `u = ωo_z − ∇h·ωo_xy`, front
/// faces only), with each point's radiance lit and unlit from `shade_hit`:
/// - `truth`: the points the eye sees, lit where a shadow ray reaches the sun;
/// - `height only`: each point weighted by the empirical probability that a point *of its height*
///   is seen, and lit with the empirical probability that a seen point of its height is lit: the
///   best any model gets whose visibility depends on height but not on slope (Smith's, height
///   correlated, exactly fitted to this surface);
/// - `none`: visibility independent of the point (one G1, one V̄).
///
/// `truth − height only` is what slope-conditioned masking and shadowing would add. The filtered
/// model's far patch and the truth's own rays (`ground_truth`) are printed beside it. Measurement
/// (`cargo test --release -p lodestone-core -- --ignored --nocapture slope_conditioned_visibility`).
#[test]
#[ignore = "a measurement, prints a table"]
fn slope_conditioned_visibility() {
    use glam::DMat3;
    use lodestone_core::microfacet::slopes::normal_of;
    const BINS: usize = 24;
    let n_points = 300_000;
    for (name, view, light, az, no_specular) in [
        ("default", 75.0, 75.0, 0.0, true),
        ("default", 85.0, 85.0, 0.0, true),
        ("snake-skin", 75.0, 30.0, 0.0, false),
        ("snake-skin", 75.0, 30.0, 0.0, true),
        ("snake-skin", 75.0, 30.0, 180.0, false),
        ("snow-under-sky", 85.0, 30.0, 0.0, false),
        ("snow-under-sky", 85.0, 0.0, 0.0, false),
    ] {
        let mut m = preset(name);
        if no_specular {
            m.brdf.specular = 0.0;
        }
        let p = Evaluator::new(&m).expect("prepared");
        let s = &p.surface;
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = if light == 0.0 {
            DVec3::Z
        } else {
            direction(f64::to_radians(light), f64::to_radians(az))
        };
        let h_max = s.h_max.max(1e-12);
        let bin = |h: f64| (((h / h_max + 1.0) * 0.5 * BINS as f64) as usize).min(BINS - 1);
        // Per point: (u, height bin, seen, lit given seen, L lit, L unlit); and the slope
        // along the view azimuth t = ∇h·ωo_xy/|ωo_xy| (negative: facing the eye) per point.
        let mut pts = Vec::with_capacity(n_points);
        let mut slopes = Vec::with_capacity(n_points);
        let mut rng = 7u64;
        for _ in 0..n_points {
            let Some(FrontPoint { x, f, h, grad, u }) = front_point(s, wo, &mut rng) else {
                continue;
            };
            let n = normal_of(grad);
            let pt = DVec3::new(x.x, x.y, h);
            let seen = s.sees(pt, wo);
            let lit = seen && n.dot(wi) > 0.0 && s.sees(pt, wi);
            let l1 = p.shade_hit(f, n, wo, wi, &DMat3::IDENTITY, || true);
            let l0 = p.shade_hit(f, n, wo, wi, &DMat3::IDENTITY, || false);
            pts.push((u, bin(h), seen, lit, l1, l0));
            slopes.push((grad.x * wo.x + grad.y * wo.y) / wo.x.hypot(wo.y).max(1e-12));
        }
        // Empirical P(seen | h) and P(lit | seen, h), projected-area weighted.
        let (mut all, mut seen_w, mut lit_w) = ([0.0; BINS], [0.0; BINS], [0.0; BINS]);
        for (u, b, seen, lit, ..) in &pts {
            all[*b] += u;
            if *seen {
                seen_w[*b] += u;
                if *lit {
                    lit_w[*b] += u;
                }
            }
        }
        let g1 = |b: usize| {
            if all[b] > 0.0 {
                seen_w[b] / all[b]
            } else {
                0.0
            }
        };
        let vb = |b: usize| {
            if seen_w[b] > 0.0 {
                lit_w[b] / seen_w[b]
            } else {
                0.0
            }
        };
        let g1_all = seen_w.iter().sum::<f64>() / all.iter().sum::<f64>();
        let v_all = lit_w.iter().sum::<f64>() / seen_w.iter().sum::<f64>();
        let (mut t, mut tw, mut hh, mut hw, mut nn, mut nw) =
            ([0.0; 3], 0.0, [0.0; 3], 0.0, [0.0; 3], 0.0);
        for (u, b, seen, lit, l1, l0) in &pts {
            let (g, v) = (g1(*b), vb(*b));
            for k in 0..3 {
                if *seen {
                    t[k] += u * if *lit { l1[k] } else { l0[k] };
                }
                hh[k] += u * g * (v * l1[k] + (1.0 - v) * l0[k]);
                nn[k] += u * g1_all * (v_all * l1[k] + (1.0 - v_all) * l0[k]);
            }
            if *seen {
                tw += u;
            }
            hw += u * g;
            nw += u * g1_all;
        }
        let t = t.map(|v| v / tw);
        let hh = hh.map(|v| v / hw);
        let nn = nn.map(|v| v / nw);
        let cfg = FootprintQuery::far(&p, wo, wi);
        let gt = p.ground_truth(&cfg, 100_000, 5);
        let rel = |v: [f64; 3], r: [f64; 3]| {
            (0..3)
                .map(|k| 100.0 * (v[k] - r[k]) / r[k])
                .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a })
        };
        eprintln!(
            "{name:15} view {view} light {light}/{az}: height-only model {:+6.2}%, no conditioning {:+6.2}% \
             (against the point truth); filtered {:+6.2}%, point truth {:+6.2}% (against the ray truth, s.e. {:.2}%); \
             G1 {g1_all:.3}, V̄ {v_all:.3}",
            rel(hh, t),
            rel(nn, t),
            rel(p.filtered(&cfg), gt.mean),
            rel(t, gt.mean),
            worst_error(gt.mean, &gt).1,
        );
        // P(seen | t) over P(seen), in five bins of t at ±0.5, 1.5 standard deviations
        // (projected-area weighted, front faces): Smith's G1 is 1 in every bin.
        let n = slopes.len() as f64;
        let sd = (slopes.iter().map(|t| t * t).sum::<f64>() / n)
            .sqrt()
            .max(1e-12);
        let (mut w, mut ws) = ([0.0f64; 5], [0.0f64; 5]);
        for ((u, _, seen, ..), t) in pts.iter().zip(&slopes) {
            let z = t / sd;
            let b = [-1.5, -0.5, 0.5, 1.5].iter().filter(|e| z > **e).count();
            w[b] += u;
            if *seen {
                ws[b] += u;
            }
        }
        let ratio: Vec<String> = (0..5)
            .map(|b| format!("{:.2}", ws[b] / w[b].max(1e-300) / g1_all))
            .collect();
        eprintln!(
            "    P(seen | t)/G1 for t/σ_t in (−∞,−1.5), (−1.5,−0.5), (−0.5,0.5), (0.5,1.5), (1.5,∞) \
             (negative t faces the eye; σ_t {sd:.3}): {}",
            ratio.join(" ")
        );
    }
}

/// A prototype of slope-conditioned masking (#17), checked against the explicit surface: Smith's
/// crossing rate along the view ray, but with the surface along the ray conditioned on the start's
/// height h₀ *and slope* t (the slope along the view azimuth). Along a horizontal direction d the
/// height of a random-phase sum of sinusoids is a stationary process with autocovariance
/// `R(τ) = σ_h² Σ ½a_i² cos(ω_i τ)`, `ω_i = 2π k_i·d`; given (h(0), h′(0)) = (h₀, t), the pair
/// (h(τ), h′(τ)) is Gaussian with mean `(R h₀/R₀ − R′ t/λ₂, R′ h₀/R₀ − R″ t/λ₂)` (λ₂ = −R″(0)) and
/// the Schur complement as covariance. The ray r(τ) = h₀ + μτ (μ = cot θ) is crossed at the rate
/// `E[(h′ − μ)⁺ | h = r]·p(h = r)/P(h < r)` (Rice, with Smith's "below the ray so far"), so
/// `G1 = exp(−∫ rate dτ)`. Without the conditioning on t and on h₀ through R (independent
/// future) this is Smith's `P(h₀)^Λ`. Prints, per configuration, P(seen | t)/G1 in the bins of
/// `slope_conditioned_visibility` for the truth and the model, and the error left by weighting
/// the points with the model's G1 (against the point truth).
#[test]
#[ignore = "a measurement, prints a table"]
fn slope_conditioned_masking_prototype() {
    use glam::DMat3;
    use lodestone_core::math::special::{norm_cdf, norm_pdf};
    use lodestone_core::microfacet::slopes::normal_of;
    let n_points = 100_000;
    for (name, view, light, az) in [
        ("default", 75.0, 75.0, 0.0),
        ("default", 60.0, 60.0, 0.0),
        ("default", 85.0, 85.0, 0.0),
        ("snake-skin", 75.0, 30.0, 0.0),
        ("snow-under-sky", 85.0, 30.0, 0.0),
        ("gaussian", 75.0, 46.0, 180.0),
        ("gaussian", 60.0, 46.0, 180.0),
    ] {
        let mut m = if name == "gaussian" {
            lodestone_core::fixtures::gaussian_material()
        } else {
            preset(name)
        };
        m.brdf.specular = 0.0;
        let p = Evaluator::new(&m).expect("prepared");
        let s = &p.surface;
        let noise = m.noise().expect("noise");
        let sh = m.heights.sigma_h;
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let d = DVec2::new(wo.x, wo.y).normalize();
        let mu = wo.z / wo.x.hypot(wo.y);
        // R, R′, R″ on a τ grid.
        let waves: Vec<(f64, f64)> = noise
            .waves
            .iter()
            .map(|w| (0.5 * (sh * w.amplitude).powi(2), 2.0 * PI * w.k.dot(d)))
            .collect();
        let r0: f64 = waves.iter().map(|(c, _)| c).sum();
        let l2: f64 = waves.iter().map(|(c, w)| c * w * w).sum();
        let t_max = 4.0 * s.h_max / mu;
        let steps = 800;
        let dt = t_max / steps as f64;
        let grid: Vec<(f64, f64, f64)> = (1..=steps)
            .map(|i| {
                let tau = (i as f64 - 0.5) * dt;
                waves.iter().fold((0.0, 0.0, 0.0), |(a, b, c), (cw, w)| {
                    let (sn, cs) = (w * tau).sin_cos();
                    (a + cw * cs, b - cw * w * sn, c - cw * w * w * cs)
                })
            })
            .collect();
        // G1 of a start (h₀, t), conditioned on t or not.
        let g1 = |h0: f64, t: f64, conditioned: bool| -> f64 {
            if t >= mu {
                return 0.0;
            }
            let mut integral = 0.0;
            for (i, (r, r1, r2)) in grid.iter().enumerate() {
                let tau = (i as f64 + 0.5) * dt;
                let (mh, mp, vh, vp, c) = if conditioned {
                    (
                        r * h0 / r0 - r1 * t / l2,
                        r1 * h0 / r0 - r2 * t / l2,
                        r0 - r * r / r0 - r1 * r1 / l2,
                        l2 - r1 * r1 / r0 - r2 * r2 / l2,
                        -(r * r1) / r0 - r1 * r2 / l2,
                    )
                } else {
                    (0.0, 0.0, r0, l2, 0.0)
                };
                let vh = vh.max(1e-12 * r0);
                let ray = h0 + mu * tau;
                let z = (ray - mh) / vh.sqrt();
                let below = norm_cdf(z).max(1e-300);
                // h′ given h = ray.
                let m2 = mp + c / vh * (ray - mh);
                let s2 = (vp - c * c / vh).max(1e-12 * l2).sqrt();
                let q = (m2 - mu) / s2;
                let up = s2 * norm_pdf(q) + (m2 - mu) * norm_cdf(q);
                integral += up * norm_pdf(z) / vh.sqrt() / below * dt;
            }
            (-integral).exp()
        };
        let mut rng = 11u64;
        let (mut t_w, mut t_l, mut c_w, mut c_l, mut u_w, mut u_l) =
            (0.0, [0.0; 3], 0.0, [0.0; 3], 0.0, [0.0; 3]);
        let sd_t = l2.sqrt();
        let (mut bw, mut bt, mut bc, mut bu) = ([0.0; 5], [0.0; 5], [0.0; 5], [0.0; 5]);
        let (mut hh, mut tt, mut nn) = (0.0, 0.0, 0.0);
        for _ in 0..n_points {
            let Some(FrontPoint { x, f, h, grad, u }) = front_point(s, wo, &mut rng) else {
                continue;
            };
            let t = grad.dot(d);
            hh += h * h;
            tt += t * t;
            nn += 1.0;
            let n = normal_of(grad);
            let pt = DVec3::new(x.x, x.y, h);
            let seen = s.sees(pt, wo);
            let lit = n.dot(wi) > 0.0 && s.sees(pt, wi);
            let l = p.shade_hit(f, n, wo, wi, &DMat3::IDENTITY, || lit);
            let (gc, gu) = (g1(h, t, true), g1(h, t, false));
            let b = [-1.5, -0.5, 0.5, 1.5]
                .iter()
                .filter(|e| t / sd_t > **e)
                .count();
            bw[b] += u;
            bc[b] += u * gc;
            bu[b] += u * gu;
            if seen {
                bt[b] += u;
                t_w += u;
            }
            c_w += u * gc;
            u_w += u * gu;
            for k in 0..3 {
                if seen {
                    t_l[k] += u * l[k];
                }
                c_l[k] += u * gc * l[k];
                u_l[k] += u * gu * l[k];
            }
        }
        let rel = |a: [f64; 3], aw: f64| {
            (0..3)
                .map(|k| 100.0 * (a[k] / aw - t_l[k] / t_w) / (t_l[k] / t_w))
                .fold(0.0f64, |x, e| if e.abs() > x.abs() { e } else { x })
        };
        let tot: f64 = bw.iter().sum();
        let bins = |v: &[f64; 5], g: f64| {
            (0..5)
                .map(|b| format!("{:.2}", v[b] / bw[b].max(1e-300) / g))
                .collect::<Vec<_>>()
                .join(" ")
        };
        eprintln!(
            "{name:15} view {view} light {light}/{az}: G1 truth {:.3} conditioned {:.3} Smith {:.3}; \
             error left: conditioned {:+.2}%, Smith (height only) {:+.2}%",
            t_w / tot,
            c_w / tot,
            u_w / tot,
            rel(c_l, c_w),
            rel(u_l, u_w),
        );
        eprintln!(
            "    height sd: process {:.4}, front faces {:.4}; slope sd along d: process {:.4}, front faces {:.4}",
            r0.sqrt(),
            (hh / nn).sqrt(),
            l2.sqrt(),
            (tt / nn).sqrt()
        );
        eprintln!(
            "    P(seen|t)/G1 truth {} | conditioned {} | Smith {}",
            bins(&bt, t_w / tot),
            bins(&bc, c_w / tot),
            bins(&bu, u_w / tot)
        );
    }
}
