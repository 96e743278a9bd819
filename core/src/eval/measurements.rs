//! Measurements behind #17's notes (all `#[ignore]`d: they print tables; run with
//! `cargo test --release -p lodestone-core -- --ignored --nocapture NAME`): the noise's slope
//! density in its tails, the transfer-curve and specular presets against the ray-traced truth, and
//! where the grazing specular error lives on the explicit surface.

use crate::eval::test_materials::preset;
use crate::eval::{Evaluator, FootprintQuery};
use crate::scene::direction::direction;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// The signed relative error (%) of the channel farthest from `truth`, and the truth's largest
/// relative standard error (%).
fn worst_error(v: [f64; 3], truth: &crate::eval::Estimate) -> (f64, f64) {
    let rel = (0..3)
        .map(|k| 100.0 * (v[k] - truth.mean[k]) / truth.mean[k])
        .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a });
    let se = (0..3)
        .map(|k| 100.0 * truth.std_error[k] / truth.mean[k])
        .fold(0.0f64, f64::max);
    (rel, se)
}

/// A point of the explicit surface drawn uniformly on the mean plane's square [−100, 100]²,
/// kept when it faces the eye: its position, driver value, height, gradient and projected area
/// toward ωo per unit of mean-plane area, `u = ωo_z − ∇h·ωo_xy > 0`.
struct FrontPoint {
    x: DVec2,
    f: f64,
    h: f64,
    grad: DVec2,
    u: f64,
}

fn front_point(s: &crate::scene::surface::Surface, wo: DVec3, rng: &mut u64) -> Option<FrontPoint> {
    use crate::math::random::splitmix;
    let x = DVec2::new(200.0 * splitmix(rng) - 100.0, 200.0 * splitmix(rng) - 100.0);
    let (f, h, grad) = s.sample(x);
    let u = wo.z - grad.x * wo.x - grad.y * wo.y;
    (u > 0.0).then_some(FrontPoint { x, f, h, grad, u })
}

/// Why the specular lobe is off in the slope distribution's tails (#17, bumpy-specular): the
/// density of the noise's slopes (σ_h ∇f of a sum of sinusoids, phases uniform: the footprint's
/// statistics far away) at the half vectors of the failing configurations, by Monte Carlo over the
/// phases, against the Gaussian of the same covariance that the filtered lobe uses. Measurement
/// (`cargo test -- --ignored`), printed.
#[test]
#[ignore = "a measurement for the closing note, prints a table"]
fn slope_density_of_the_noise_in_its_tails() {
    use crate::microfacet::slopes::slope_of;
    let m = preset("bumpy-specular");
    let noise = m.noise().expect("a noise driver");
    let sh = m.heights.sigma_h;
    // Slope contributions c_i k̂_i sin ψ_i, c_i = σ_h 2π a_i |k_i|.
    let terms: Vec<(f64, DVec2)> = noise
        .waves
        .iter()
        .map(|w| {
            (
                sh * 2.0 * PI * w.amplitude * w.k.length(),
                w.k.normalize_or_zero(),
            )
        })
        .collect();
    let (mut xx, mut yy, mut xy) = (0.0, 0.0, 0.0);
    for (c, d) in &terms {
        xx += 0.5 * c * c * d.x * d.x;
        yy += 0.5 * c * c * d.y * d.y;
        xy += 0.5 * c * c * d.x * d.y;
    }
    let det = xx * yy - xy * xy;
    let gauss = |s: DVec2| {
        let q = (yy * s.x * s.x - 2.0 * xy * s.x * s.y + xx * s.y * s.y) / det;
        (-0.5 * q).exp() / (2.0 * PI * det.sqrt())
    };
    let max_slope: f64 = terms.iter().map(|(c, _)| c.abs()).sum();
    eprintln!(
        "σ_n {:.3} {:.3}, slopes bounded by Σ c_i = {max_slope:.2}",
        xx.sqrt(),
        yy.sqrt()
    );
    let configs = [
        ("45° / 30° same side", 45.0, 30.0, 0.0),
        ("75° / 30° same side", 75.0, 30.0, 0.0),
        ("85° / 30° opposite", 85.0, 30.0, 180.0),
        ("45° / 60° opposite", 45.0, 60.0, 180.0),
        ("60° / 0°", 60.0, 0.0, 0.0),
    ];
    let samples = 20_000_000u64;
    let r = 0.03;
    let mut counts = vec![0u64; configs.len()];
    let centres: Vec<DVec2> = configs
        .iter()
        .map(|(_, v, l, az)| {
            let wo = direction(f64::to_radians(*v), 0.0);
            let wi = direction(f64::to_radians(*l), f64::to_radians(*az));
            slope_of((wo + wi).normalize())
        })
        .collect();
    let mut rng = 0x1234_5678_u64;
    for _ in 0..samples {
        let mut s = DVec2::ZERO;
        for (c, d) in &terms {
            let psi = 2.0 * PI * crate::math::random::splitmix(&mut rng);
            s += *d * (c * psi.sin());
        }
        for (i, c) in centres.iter().enumerate() {
            if (s - *c).length_squared() < r * r {
                counts[i] += 1;
            }
        }
    }
    for (i, (name, ..)) in configs.iter().enumerate() {
        let exact = counts[i] as f64 / (samples as f64 * PI * r * r);
        let g = gauss(centres[i]);
        let sigmas = (centres[i].length_squared() / xx).sqrt();
        let v: Vec<DVec2> = terms.iter().map(|(c, d)| *d * *c).collect();
        let sp = crate::microfacet::slope_density::sinusoid_density_ratio(&v, 0.0, centres[i]);
        eprintln!(
            "{name:22} half-vector slope {:.3} ({sigmas:.1}σ): noise density {exact:.4e} ({} hits), Gaussian {g:.4e}, ratio {:.3}, saddlepoint ratio {sp:.3}",
            centres[i].length(),
            counts[i],
            exact / g
        );
    }
}

/// The library's transfer-curve presets against the ray-traced truth: the binned mixture the
/// views run, one Gaussian and the 241-node mixture (measurement for #17's closing note, far
/// patch, 200k rays; `cargo test --release -- --ignored --nocapture transfer_presets`).
#[test]
#[ignore = "a measurement, prints a table"]
fn transfer_presets_against_ground_truth() {
    use crate::microfacet::height_mixture::TransferSlopes;
    for name in ["moss", "sponge", "terraces"] {
        let m = preset(name);
        let p = Evaluator::new(&m).expect("prepared");
        let mut g = m.clone();
        g.filtering.transfer_slopes = TransferSlopes::Gaussian;
        let pg = Evaluator::new(&g).expect("prepared");
        for (view, light, az) in [
            (0.0, 0.0, 0.0),
            (30.0, 30.0, 180.0),
            (45.0, 60.0, 0.0),
            (60.0, 30.0, 0.0),
            (75.0, 30.0, 180.0),
            (85.0, 0.0, 0.0),
        ] {
            let wi = if light == 0.0 {
                DVec3::Z
            } else {
                direction(f64::to_radians(light), f64::to_radians(az))
            };
            let cfg = FootprintQuery::far(&p, direction(f64::to_radians(view), 0.0), wi);
            let gt = p.ground_truth(&cfg, 200_000, 41);
            let rel = |v: [f64; 3]| worst_error(v, &gt).0;
            let se = worst_error(gt.mean, &gt).1;
            eprintln!(
                "{name:9} view {view:2} light {light:2}/{az:3}: bins {:+6.2}%  gaussian {:+6.2}%  fine {:+6.2}%  (truth s.e. {se:.2}%)",
                rel(p.filtered(&cfg)),
                rel(pg.filtered(&cfg)),
                rel(p.filtered_mixture(&cfg).expect("applies")),
            );
        }
    }
}

/// Where the grazing specular error of bumpy-specular lives (#17): over points of the explicit
/// surface (uniform on the mean plane, so area-weighted), the unmasked specular per unit visible
/// area against the Gaussian lobe the model integrates, the mean visibility (view, view and light)
/// over visible area against Smith's, and the same visibility weighted by the specular lobe: if the
/// lobe's facets are masked unlike the average facet, the last two differ. Measurement
/// (`cargo test --release -- --ignored --nocapture grazing_specular_decomposition`).
#[test]
#[ignore = "a measurement, prints a table"]
fn grazing_specular_decomposition() {
    use crate::math::random::splitmix;
    use crate::microfacet::brdf::filtered_specular;
    use crate::microfacet::masking_shadowing::G2;
    use crate::microfacet::slopes::{SlopeCov, normal_of};
    let m = preset("bumpy-specular");
    let p = Evaluator::new(&m).expect("prepared");
    let s = &p.surface;
    let n_points = 400_000;
    for (view, light, az) in [
        (45.0, 30.0, 0.0),
        (60.0, 0.0, 0.0),
        (75.0, 30.0, 0.0),
        (85.0, 30.0, 180.0),
    ] {
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let cfg = FootprintQuery::far(&p, wo, wi);
        let loc = p.footprint_stats(&cfg);
        let (mut u_sum, mut spec_u, mut u_vo, mut u_vovi, mut spec_u_vovi, mut spec_u_vo) =
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut rng = 99u64;
        for _ in 0..n_points {
            let x = DVec2::new(
                200.0 * splitmix(&mut rng) - 100.0,
                200.0 * splitmix(&mut rng) - 100.0,
            );
            let (_f, h, grad) = s.sample(x);
            let n = normal_of(grad);
            let u = wo.z - grad.x * wo.x - grad.y * wo.y;
            if u <= 0.0 {
                continue;
            }
            let spec = m.brdf.specular_with(n, wo, wi, SlopeCov::default());
            let pt = DVec3::new(x.x, x.y, h);
            let vo = if s.sees(pt, wo) { 1.0 } else { 0.0 };
            let vi = if vo > 0.0 && s.sees(pt, wi) { 1.0 } else { 0.0 };
            u_sum += u;
            spec_u += spec * u;
            u_vo += u * vo;
            u_vovi += u * vo * vi;
            spec_u_vovi += spec * u * vo * vi;
            spec_u_vo += spec * u * vo;
        }
        let b = &m.brdf;
        let lobe = filtered_specular(
            b.specular,
            b.roughness,
            loc.stats.slope_mean,
            &loc.stats.slope_cov,
            wo,
            wi,
        );
        let ms = G2::from_directions(wo, wi, &loc.stats.slope_cov, m.filtering.correlation);
        eprintln!(
            "view {view} light {light}/{az}: unmasked lobe truth {:.4e} model {lobe:.4e} ({:+.1}%); \
             G1 truth {:.4} Smith {:.4}; shadowing|visible truth {:.4} model {:.4}; \
             lobe-weighted: G1 {:.4}, shadowing|visible {:.4}; spec/visible area truth {:.4e} model {:.4e} ({:+.1}%)",
            spec_u / u_sum,
            100.0 * (lobe / (spec_u / u_sum) - 1.0),
            u_vo / u_sum,
            1.0 / (1.0 + ms.lambda_o),
            u_vovi / u_vo,
            ms.mean_shadowing(),
            spec_u_vo / spec_u,
            spec_u_vovi / spec_u_vo,
            spec_u_vovi / u_vo,
            lobe * ms.mean_shadowing(),
            100.0 * (lobe * ms.mean_shadowing() / (spec_u_vovi / u_vo) - 1.0),
        );
    }
}

/// The presets with a specular lobe against the ray-traced truth, the lobe over the noise's own
/// slope density and over the Gaussian (measurement for #17, far patch, up to 400k rays;
/// `cargo test --release -- --ignored --nocapture specular_presets_against`).
#[test]
#[ignore = "a measurement, prints a table"]
fn specular_presets_against_ground_truth() {
    use crate::microfacet::slope_density::NoiseSlopes;
    for name in ["bumpy-specular", "default", "snake-skin"] {
        let m = preset(name);
        if m.brdf.specular <= 0.0 {
            eprintln!("{name}: no specular");
            continue;
        }
        let p = Evaluator::new(&m).expect("prepared");
        let mut g = m.clone();
        g.filtering.noise_slopes = NoiseSlopes::Gaussian;
        let pg = Evaluator::new(&g).expect("prepared");
        for (view, light, az) in [
            (0.0, 30.0, 0.0),
            (45.0, 30.0, 0.0),
            (45.0, 60.0, 180.0),
            (60.0, 0.0, 0.0),
            (60.0, 30.0, 180.0),
            (75.0, 30.0, 0.0),
            (75.0, 60.0, 180.0),
            (85.0, 30.0, 180.0),
            (85.0, 0.0, 0.0),
        ] {
            let wi = if light == 0.0 {
                DVec3::Z
            } else {
                direction(f64::to_radians(light), f64::to_radians(az))
            };
            let cfg = FootprintQuery::far(&p, direction(f64::to_radians(view), 0.0), wi);
            let gt = p.ground_truth(&cfg, 400_000, 47);
            let rel = |v: [f64; 3]| worst_error(v, &gt).0;
            let se = worst_error(gt.mean, &gt).1;
            eprintln!(
                "{name:15} view {view:2} light {light:2}/{az:3}: exact {:+7.2}%  gaussian {:+7.2}%  (truth s.e. {se:.2}%)",
                rel(p.filtered(&cfg)),
                rel(pg.filtered(&cfg)),
            );
        }
    }
}

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
    use crate::microfacet::slopes::normal_of;
    use glam::DMat3;
    const BINS: usize = 24;
    let n_points = 300_000;
    for (name, view, light, az, no_specular) in [
        ("default", 75.0, 75.0, 0.0, true),
        ("default", 85.0, 85.0, 0.0, true),
        ("snake-skin", 75.0, 30.0, 0.0, false),
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
        let (mut w, mut ws) = ([0.0; 5], [0.0; 5]);
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
    use crate::math::special::{norm_cdf, norm_pdf};
    use crate::microfacet::slopes::normal_of;
    use glam::DMat3;
    let n_points = 100_000;
    for (name, view, light, az) in [
        ("default", 75.0, 75.0, 0.0),
        ("default", 60.0, 60.0, 0.0),
        ("default", 85.0, 85.0, 0.0),
        ("snake-skin", 75.0, 30.0, 0.0),
        ("snow-under-sky", 85.0, 30.0, 0.0),
    ] {
        let mut m = preset(name);
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
