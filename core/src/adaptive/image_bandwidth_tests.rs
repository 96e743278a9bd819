//! Tests of [`crate::adaptive::image_bandwidth`]: the predicted spectrum against brute force, and
//! a view's map.

use crate::adaptive::image_bandwidth::{NYQUIST, Spectrum};
use crate::driver::field::DriverField;
use crate::driver::footprint::Footprint;
use crate::eval::Evaluator;
use crate::eval::query::FootprintQuery;
use crate::fixtures::preset;
use crate::material::colormap::LUMINANCE;
use crate::math::gaussian::eigenvalues;
use crate::math::quadrature::gauss_hermite_normal;
use crate::microfacet::slopes::normal_of;
use crate::scene::camera::{Camera, PIXEL_SIGMA};
use crate::scene::direction::direction;
use crate::scene::shape::Shape;
use glam::{DMat2, DMat3, DVec2};
use std::f64::consts::TAU;

/// Energy-weighted second moment of the spectrum of `img` (n × n, mean removed, Hann window),
/// in pixel axes, cycles per pixel: a direct DFT, row by row then column by column.
fn measured_moment(img: &[f64], n: usize) -> DMat2 {
    measured_spectrum(img, None, n).0
}

/// [`measured_moment`] and the spectrum's energy per pixel (the windowed variance), less the
/// expected power of white noise of per-pixel variance `noise` where given (each bin's power
/// floored at 0).
fn measured_spectrum(img: &[f64], noise: Option<&[f64]>, n: usize) -> (DMat2, f64) {
    let mean = img.iter().sum::<f64>() / img.len() as f64;
    let hann = |i: usize| 0.5 - 0.5 * (TAU * (i as f64 + 0.5) / n as f64).cos();
    let noise_power: f64 = noise.map_or(0.0, |v| {
        (0..n * n)
            .map(|i| (hann(i % n) * hann(i / n)).powi(2) * v[i])
            .sum()
    });
    let window_power: f64 = (0..n * n)
        .map(|i| (hann(i % n) * hann(i / n)).powi(2))
        .sum();
    let mut re = vec![0.0; n * n];
    let mut im = vec![0.0; n * n];
    // Rows: F(y, u).
    for y in 0..n {
        for u in 0..n {
            let (mut a, mut b) = (0.0, 0.0);
            for x in 0..n {
                let v = (img[y * n + x] - mean) * hann(x) * hann(y);
                let t = -TAU * (u * x) as f64 / n as f64;
                a += v * t.cos();
                b += v * t.sin();
            }
            re[y * n + u] = a;
            im[y * n + u] = b;
        }
    }
    let (mut e, mut m) = (0.0, DMat2::ZERO);
    for u in 0..n {
        for v in 0..n {
            let (mut a, mut b) = (0.0, 0.0);
            for y in 0..n {
                let t = -TAU * (v * y) as f64 / n as f64;
                let (c, s) = (t.cos(), t.sin());
                a += re[y * n + u] * c - im[y * n + u] * s;
                b += re[y * n + u] * s + im[y * n + u] * c;
            }
            let signed = |i: usize| {
                let f = i as f64 / n as f64;
                if f >= 0.5 { f - 1.0 } else { f }
            };
            let w = DVec2::new(signed(u), signed(v));
            let p = (a * a + b * b - noise_power).max(0.0);
            e += p;
            m += DMat2::from_cols(w * w.x, w * w.y) * p;
        }
    }
    let energy = e / (n * n) as f64 / window_power;
    (m * (1.0 / e), energy)
}

/// Against brute force: the explicit surface's radiance averaged over each pixel's Gaussian
/// footprint (Gauss–Hermite, 4 × 4 nodes), on a 64 × 64 image whose pixels map to the plane by
/// a sheared, rotated J; the image's measured spectrum (its DFT) has the predicted second
/// moment, both axes, and energy within 15% (25% for the energy) where the shading is led by
/// the colour (default), and a known shortfall where it is nonlinear in the slope
/// (snake-skin). No masking on either side: this checks the spectrum's transport, the
/// radiance's responses and the pixel filter.
#[test]
fn the_predicted_spectrum_is_the_images() {
    for (name, wo, wi) in [
        ("default", direction(0.35, 3.5), direction(0.5, 0.7)),
        ("snake-skin", direction(0.2, 1.0), direction(0.9, 2.0)),
    ] {
        let mut ev = Evaluator::new(&preset(name)).unwrap();
        // The preset's finest octave at unit variance: its waves span a factor of 2, so that
        // the image holds many periods of every one (a longer wave's energy would be lost to
        // the image's mean and window).
        let DriverField::Noise(noise) = &ev.surface.driver else {
            panic!("a noise preset")
        };
        let k_max = noise.waves.iter().map(|w| w.k.length()).fold(0.0, f64::max);
        let mut noise = noise.clone();
        noise.waves.retain(|w| w.k.length() >= 0.5 * k_max);
        let var: f64 = noise
            .waves
            .iter()
            .map(|w| 0.5 * w.amplitude * w.amplitude)
            .sum();
        for w in &mut noise.waves {
            w.amplitude /= var.sqrt();
        }
        ev.surface.driver = DriverField::Noise(noise.clone());
        // J scaled so that the fastest wave is at 0.3 cycles per pixel (no aliasing).
        let j0 = DMat2::from_cols(DVec2::new(1.0, -0.3), DVec2::new(0.45, 1.6));
        let fastest = noise
            .waves
            .iter()
            .map(|w| (j0.transpose() * w.k).length())
            .fold(0.0, f64::max);
        let j = j0 * (0.3 / fastest);
        let fp = Footprint {
            cov: j * j.transpose() * (PIXEL_SIGMA * PIXEL_SIGMA),
        };
        let n = 64;
        let origin = DVec2::new(0.37, -1.2);
        let (z, wz) = gauss_hermite_normal(4);
        let frame = DMat3::IDENTITY;
        let mut img = vec![0.0; n * n];
        let mut predicted = Spectrum::default();
        for py in 0..n {
            for px in 0..n {
                let centre = origin + j * DVec2::new(px as f64, py as f64);
                let mut acc = 0.0;
                for (a, wa) in z.iter().zip(&wz) {
                    for (b, wb) in z.iter().zip(&wz) {
                        let x = centre + j * (DVec2::new(*a, *b) * PIXEL_SIGMA);
                        let (f, g) = ev.surface.driver.value_and_gradient(x);
                        let s = g * ev.transfer_slope(f);
                        let l = ev.shade_hit(f, normal_of(s), wo, wi, &frame, || true);
                        acc += wa * wb * (0..3).map(|k| LUMINANCE[k] * l[k]).sum::<f64>();
                    }
                }
                img[py * n + px] = acc;
                if px % 4 == 0 && py % 4 == 0 {
                    let cfg = FootprintQuery {
                        wo,
                        wi,
                        x0: centre,
                        footprint: fp,
                    };
                    let (s, _) = ev.radiance_spectrum(&cfg, &frame, 0.0);
                    predicted.energy += s.energy;
                    predicted.moment += s.moment;
                }
            }
        }
        let want = j.transpose() * predicted.moment * j * (1.0 / predicted.energy);
        let mean = img.iter().sum::<f64>() / img.len() as f64;
        let var = img.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / img.len() as f64;
        let e = predicted.energy / 256.0;
        let got = measured_moment(&img, n);
        let (w1, w2) = eigenvalues(want);
        let (g1, g2) = eigenvalues(got);
        let ratios = [w1.sqrt() / g1.sqrt(), w2.sqrt() / g2.sqrt(), e / var];
        eprintln!(
            "{name}: predicted/measured bandwidth {:.3} (fast axis) {:.3} (slow), energy {:.3}",
            ratios[0], ratios[1], ratios[2]
        );
        // Shading nonlinear in the slope (snake-skin's slope colour, a black-to-red ramp
        // across its facets) is taken to first order: its harmonics are missed, and its
        // energy, extrapolated past the ramp, overestimated (measured: bandwidth 0.86 and
        // 0.73, energy 2.2). Colour-led shading is within 15%.
        let (lo, hi) = if name == "default" {
            ([0.8, 0.8, 0.85], [1.15, 1.15, 1.25])
        } else {
            ([0.65, 0.65, 1.0], [1.0, 1.0, 3.0])
        };
        for k in 0..3 {
            assert!(
                ratios[k] > lo[k] && ratios[k] < hi[k],
                "{name}: {ratios:?}; {want:?} against {got:?}, energy {e} against {var}"
            );
        }
    }
}

/// A view at 75°: the sky is 0, the pixels beside it Nyquist's, every pixel finite within
/// [0, 0.5]. Near the camera the relief spans many pixels (low cycles per pixel); toward the
/// horizon foreshortening packs its waves toward Nyquist; just below it the footprints
/// average them away and the image is flat again.
#[test]
fn a_view_is_flat_far_away_and_sharp_at_the_horizon() {
    let ev = Evaluator::new(&preset("default")).unwrap();
    let camera = Camera {
        elevation_deg: 75.0,
        distance: 3.0,
        ..Default::default()
    };
    let wi = direction(0.6, 1.0);
    let (w, h) = (24u32, 18u32);
    let t0 = std::time::Instant::now();
    let b = ev.predict_bandwidth(Shape::Plane, &camera, (w, h), wi, 1);
    eprintln!(
        "{:.0} µs a pixel",
        t0.elapsed().as_secs_f64() * 1e6 / f64::from(w * h)
    );
    for row in b.cycles.chunks(w as usize) {
        eprintln!(
            "{}",
            row.iter()
                .map(|v| format!("{v:.2}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    assert!(
        b.cycles
            .iter()
            .all(|v| v.is_finite() && (0.0..=NYQUIST).contains(v))
    );
    let lifted = ev.surface.clear_camera(&camera);
    let sky = |x: u32, y: u32| {
        lifted
            .plane_footprint(DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5), w, h)
            .is_none()
    };
    let mut horizon = 0;
    for y in 0..h {
        for x in 0..w {
            let v = b.cycles[(y * w + x) as usize];
            if sky(x, y) {
                assert_eq!(v, 0.0);
            } else if y > 0 && sky(x, y - 1) {
                assert_eq!(v, NYQUIST);
                horizon += 1;
            }
        }
    }
    assert_eq!(horizon, w as usize, "one row of horizon");
    let row_mean = |y: u32| {
        b.cycles[(y * w) as usize..((y + 1) * w) as usize]
            .iter()
            .sum::<f64>()
            / f64::from(w)
    };
    assert!(
        row_mean(h - 1) < 0.6 * row_mean(4),
        "{} {}",
        row_mean(h - 1),
        row_mean(4)
    );
    assert!(
        b.cycles[(2 * w) as usize..(3 * w) as usize]
            .iter()
            .any(|v| *v < 0.05)
    );
    // BSSBH13's Eq. 11 levels: a step of 2^level samples at twice the bandwidth or more.
    let eq11 = crate::adaptive::image_bandwidth::BandwidthPrediction {
        width: 5,
        height: 1,
        cycles: vec![0.5, 0.25, 0.1, 0.01, 0.0],
    };
    assert_eq!(eq11.levels(4), vec![0, 1, 2, 4, 4]);
    // Blocks of 3: each takes its centre pixel's value.
    let coarse = ev.predict_bandwidth(Shape::Plane, &camera, (w, h), wi, 3);
    assert_eq!((coarse.width, coarse.height), (24, 18));
    assert_eq!(
        coarse.cycles[(10 * w + 7) as usize],
        b.cycles[(10 * w + 7) as usize]
    );
    assert_eq!(
        coarse.cycles[(11 * w + 8) as usize],
        b.cycles[(10 * w + 7) as usize]
    );
    // A cylinder: finite, within range, 0 beside it.
    let c = ev.predict_bandwidth(Shape::Cylinder { radius: 1.0 }, &camera, (w, h), wi, 2);
    assert!(
        c.cycles
            .iter()
            .all(|v| v.is_finite() && (0.0..=NYQUIST).contains(v))
    );
    assert!(c.cycles.contains(&0.0) && c.cycles.iter().any(|v| *v > 0.0 && *v < NYQUIST));
}

/// BSSBH13's Fig. 12 for Lodestone (a measurement, ignored): per 32 × 32 window of a 128 × 96
/// view (BSSBH13 used 32 × 32 windows), the predicted bandwidth (energy-weighted over its pixels,
/// no display floor) against the ground truth's (CPU truth, 64 rays a pixel, masking and
/// shadowing included; its DFT's power less the truth's own noise). Prints each window, and per
/// preset and over all windows the correlation and the median ratios of bandwidth and energy.
#[test]
#[ignore = "a measurement: predicted against measured bandwidth over views (about a minute)"]
fn predicted_bandwidth_against_the_truths() {
    use crate::math::correlation::{pearson, spearman};
    let (w, h, win, rays) = (128u32, 96u32, 32usize, 64);
    let (mut xs, mut ys, mut resolvable) = (vec![], vec![], vec![]);
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        if v.is_empty() {
            f64::NAN
        } else {
            v[v.len() / 2]
        }
    };
    for name in ["default", "dirt-in-crevices", "snake-skin"] {
        let (mut bw, mut en) = (vec![], vec![]);
        let ev = Evaluator::new(&preset(name)).unwrap();
        for (elevation, distance) in [(60.0, 3.0), (75.0, 3.0), (45.0, 1.5)] {
            let camera = Camera {
                elevation_deg: elevation,
                distance,
                ..Default::default()
            };
            let wi = direction(0.6, 1.0);
            let lifted = ev.surface.clear_camera(&camera);
            let pixels: Vec<Option<(f64, f64, f64, f64)>> = (0..w * h)
                .map(|p| {
                    let px = DVec2::new(f64::from(p % w) + 0.5, f64::from(p / w) + 0.5);
                    let (_, cov) = lifted.plane_footprint(px, w, h)?;
                    let ray = lifted.ray(px, w, h);
                    let (cfg, _) = ev.pixel_query(ray.origin, ray.dir, wi, Footprint { cov })?;
                    let (s, _) = ev.radiance_spectrum(&cfg, &DMat3::IDENTITY, 0.0);
                    let b = s.cycles_per_pixel(&cfg.footprint, 0.0);
                    let e = ev.ground_truth(&cfg, rays, u64::from(p) + 1);
                    let lum = |v: [f64; 3]| (0..3).map(|k| LUMINANCE[k] * v[k]).sum::<f64>();
                    Some((s.energy, b, lum(e.mean), lum(e.std_error).powi(2)))
                })
                .collect();
            for wy in 0..(h as usize / win) {
                for wx in 0..(w as usize / win) {
                    let ids: Vec<usize> = (0..win * win)
                        .map(|i| (wy * win + i / win) * w as usize + wx * win + i % win)
                        .collect();
                    let Some(px): Option<Vec<_>> = ids.iter().map(|i| pixels[*i]).collect() else {
                        continue;
                    };
                    let energy: f64 = px.iter().map(|p| p.0).sum();
                    let predicted =
                        (px.iter().map(|p| p.0 * p.1 * p.1).sum::<f64>() / energy).sqrt();
                    let img: Vec<f64> = px.iter().map(|p| p.2).collect();
                    let noise: Vec<f64> = px.iter().map(|p| p.3).collect();
                    let (m, e) = measured_spectrum(&img, Some(&noise), win);
                    let measured = eigenvalues(m).0.sqrt();
                    eprintln!(
                        "{name} {elevation}° d {distance} window ({wx}, {wy}): predicted {predicted:.3} measured {measured:.3} cycles/px; energy predicted {:.2e} measured {e:.2e}",
                        energy / px.len() as f64
                    );
                    if measured.is_finite() && measured > 0.0 && predicted > 0.0 {
                        xs.push(predicted.ln());
                        ys.push(measured.ln());
                        bw.push(predicted / measured);
                        en.push(energy / px.len() as f64 / e);
                        // A window holds two periods or more of what it is to measure.
                        if predicted.max(measured) >= 2.0 / win as f64 {
                            resolvable.push(predicted / measured);
                        }
                    }
                }
            }
        }
        eprintln!(
            "{name}: {} windows, predicted/measured median bandwidth {:.2}, energy {:.2}",
            bw.len(),
            median(bw.clone()),
            median(en.clone())
        );
    }
    let mut sorted: Vec<f64> = xs.iter().zip(&ys).map(|(x, y)| (x - y).exp()).collect();
    sorted.sort_by(f64::total_cmp);
    eprintln!(
        "{} windows: log correlation {:.2}, rank {:.2}, predicted/measured median {:.2} (quartiles {:.2}–{:.2})",
        xs.len(),
        pearson(&xs, &ys),
        spearman(&xs, &ys),
        sorted[sorted.len() / 2],
        sorted[sorted.len() / 4],
        sorted[3 * sorted.len() / 4]
    );
    eprintln!(
        "{} windows holding two periods: predicted/measured median {:.2}",
        resolvable.len(),
        median(resolvable.clone())
    );
}
