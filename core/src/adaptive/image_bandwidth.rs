//! The image's predicted local bandwidth (#18 §1, [BSSBH13 Secs. 2.1–2.2]): how fast the ground
//! truth's expected image varies around a pixel, in cycles per pixel, from what the scene knows and
//! before any ray is traced. BSSBH13 shade a pixel only where this bandwidth says the image cannot be
//! up-sampled from a coarser level [BSSBH13 Eq. 11]; Lodestone shows it beside the ray counts.
//!
//! BSSBH13 carry a 2-D bandwidth (space, angle) along each light path through the reflection
//! operator `R = P_x C_{−c} S B_{t,ρ} C_c P_i` [BSSBH13 Eq. 3] and free-space transport to the eye
//! [Eq. 4], then read the image-space rate off the eye's angular bandwidth [Eq. 6]. For a pixel of
//! Lodestone's plane or cylinder under a directional sun that chain reduces to three terms, each a
//! spatial spectrum on the tangent plane carried to the image by the pixel's Jacobian J (surface
//! offset per pixel offset; the footprint is `Σ_p = PIXEL_SIGMA²·J Jᵀ`):
//!
//! - **Texture** (`B_{t,ρ}`'s `+t`): the driver's resolved waves k_i (cycles per unit; a_i α_i
//!   their amplitudes under the pixel's footprint, of variance `v = Σ ½a_i²α_i²`) through the
//!   radiance.
//!   - *Value:* a pixel whose filtered driver is f̄ has the luminance `ℓ(f̄)`, averaged over the
//!     footprint's unresolved values and slopes. Its Hermite (Wiener chaos) expansion over
//!     `f̄ ~ N(m, v)`, `ℓ = Σ c_n He_n`, is exact for a Gaussian driver whatever the colour map:
//!     order n has the energy `n!·c_n²` and, by Mehler's formula, the n-fold self-convolution of
//!     the driver's spectrum, whose second moment is n times the driver's
//!     (`Σ ½a_i²α_i² k_i k_iᵀ / v`). A nonlinear colour map (sRGB stops, a smooth ramp) spreads
//!     the image's spectrum past the driver's this way.
//!   - *Slope:* wave i tilts the surface by `τ a_i α_i k_i` (`τ = 2π σ_h g′`), moving the
//!     luminance by `L_s·` that to first order (`L_s` its slope gradient, averaged as above): an
//!     energy `½(τ a_i α_i L_s·k_i)²` at k_i. Shading nonlinear in the slope (a slope colour ramp)
//!     has harmonics this misses (measured: the image 15–27% faster than predicted on
//!     snake-skin, 4–14% on default).
//!   - An image driver has no waves: its resolved value variance v and gradient covariance R (the
//!     whole image's minus what the footprint leaves unresolved) give the spectrum's second moment
//!     `R/(2π)²v` for both responses.
//! - **Curvature** (`C_{±c}`): on the cylinder (curvature c along the tangent's y) the normal turns
//!   by c per unit length, so the lobe, of angular width σ_θ (the base roughness widened by the
//!   unresolved slopes), sweeps across the surface at a spatial frequency `c/(2π σ_θ)` per unit,
//!   with the lobe's luminance as its energy. The diffuse cosine's angular bandwidth (about one
//!   cycle per 2π) adds `c/2π` with the diffuse luminance's.
//! - **The eye's angle** (`T_{d′}`'s unsheared part): the BRDF's angular bandwidth seen directly,
//!   one pixel's angle times `1/(2π σ_θ)`: below 10⁻² cycles per pixel in every view here, and
//!   left out.
//!
//! Each term's energy is attenuated by the pixel filter (the truth averages its rays over the
//! pixel, a Gaussian of [`PIXEL_SIGMA`] pixels), and the bandwidth is the energy-weighted root mean
//! square frequency along the image's fastest direction, `b = √(λ_max(Σ_c e_c κ_c M)/(Σ_c e_c + e₀))`
//! with `M = J Jᵀ` (so `κ M` has the eigenvalues of `Jᵀ κ J`, the spectrum in pixel axes). BSSBH13
//! take a 95th percentile of the energy; the root mean square is that of one sinusoid exactly, and
//! of a sum the energy's centre of mass. `e₀ = (L̄/256)²` is one display step of the pixel's own
//! value: variation below it does not need resolving, so a footprint that averages its texture
//! away reads as flat (BSSBH13 compare band energies to ε of their maximum [Eq. 7]). A pixel beside
//! the horizon or the cylinder's silhouette is a discontinuity: the largest bandwidth, Nyquist's
//! 0.5 cycles per pixel (values above it are clamped there too).

use crate::driver::field::DriverField;
use crate::driver::footprint::Footprint;
use crate::eval::query::{FootprintQuery, FootprintStats};
use crate::eval::{Evaluator, shading::specular_tint};
use crate::material::colormap::LUMINANCE;
use crate::math::gaussian::{cholesky, eigenvalues};
use crate::math::quadrature::gauss_hermite_normal;
use crate::microfacet::slopes::normal_of;
use crate::microfacet::visible_slopes::slope_rule;
use crate::scene::camera::{Camera, PIXEL_SIGMA};
use crate::scene::shape::Shape;
use glam::{DMat2, DMat3, DVec2, DVec3};
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// Nyquist's bandwidth, cycles per pixel: the largest the map shows (a discontinuity).
pub const NYQUIST: f64 = 0.5;

/// n of the polar rule (n² nodes) over the unresolved slopes that the radiance's response is
/// averaged on.
const RESPONSE_POINTS: usize = 2;

/// Orders of the luminance's Hermite expansion in the driver's value (Wiener chaos).
pub const CHAOS_ORDERS: usize = 8;

/// Gauss–Hermite nodes its coefficients are projected on.
const CHAOS_NODES: usize = 16;

/// A local spatial spectrum on the tangent plane: total energy (luminance²) and its second moment
/// `Σ e·k kᵀ` (k in cycles per unit length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spectrum {
    /// Total energy.
    pub energy: f64,
    /// Energy-weighted second moment of the wave vectors.
    pub moment: DMat2,
}

impl Default for Spectrum {
    /// No energy (glam's `DMat2::default()` is the identity, not zero).
    fn default() -> Self {
        Self {
            energy: 0.0,
            moment: DMat2::ZERO,
        }
    }
}

impl Spectrum {
    /// Add energy `e` at wave vector `k`.
    fn add(&mut self, e: f64, k: DVec2) {
        if e > 0.0 && e.is_finite() && k.is_finite() {
            self.energy += e;
            self.moment += DMat2::from_cols(k * k.x, k * k.y) * e;
        }
    }

    /// The root mean square frequency along the image's fastest direction, in cycles per pixel,
    /// for a footprint `Σ_p = PIXEL_SIGMA²·J Jᵀ`, with `floor` energy counted at frequency 0;
    /// clamped to [0, [`NYQUIST`]]. 0 without energy.
    pub fn cycles_per_pixel(&self, footprint: &Footprint, floor: f64) -> f64 {
        let m = footprint.cov * (1.0 / (PIXEL_SIGMA * PIXEL_SIGMA));
        let total = self.energy + floor.max(0.0);
        if !(total > 0.0 && total.is_finite()) {
            return 0.0;
        }
        // λ_max of the 2×2 product (eigenvalues real and ≥ 0: similar to Jᵀ·moment·J).
        let lambda = eigenvalues(self.moment * m).0;
        let b = (lambda.max(0.0) / total).sqrt();
        if b.is_finite() {
            b.min(NYQUIST)
        } else {
            NYQUIST
        }
    }
}

/// The predicted bandwidth of a view: cycles per pixel, row-major (0 where the pixel sees the sky).
#[derive(Clone, Debug, PartialEq)]
pub struct BandwidthPrediction {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Cycles per pixel, in [0, [`NYQUIST`]].
    pub cycles: Vec<f64>,
}

impl BandwidthPrediction {
    /// BSSBH13's level per pixel [BSSBH13 Eq. 11]: the coarsest lattice step `2^level` (capped at
    /// `max_level`) whose sampling rate, one sample per step, is at least twice the bandwidth.
    pub fn levels(&self, max_level: u32) -> Vec<u32> {
        self.cycles
            .iter()
            .map(|b| {
                if *b > 0.0 {
                    ((0.5 / b).log2().floor().max(0.0) as u32).min(max_level)
                } else {
                    max_level
                }
            })
            .collect()
    }
}

impl Evaluator {
    /// The response of the pixel's luminance to the driver (module docs): its mean, the energy
    /// of each order n = 1…[`CHAOS_ORDERS`] of `ℓ(f̄)` over the resolved driver `f̄ ~ N(m, v)`,
    /// and the gradient with respect to the slope, both averaged over the footprint's unresolved
    /// values and slopes (`loc`, the footprint's statistics); `frame` the tangent frame, as
    /// [`Evaluator::filtered`] takes it.
    fn radiance_response(
        &self,
        cfg: &FootprintQuery,
        loc: &FootprintStats,
        frame: &DMat3,
        (m, v): (f64, f64),
    ) -> (f64, [f64; CHAOS_ORDERS], DVec2) {
        let su = loc.driver.std;
        // The field's mean slope (the resolved slope at x0 is one realisation of what the
        // spectrum describes): the macro surface's.
        let s0 = DVec2::ZERO;
        let c = loc.stats.slope_cov;
        let (a11, a21, a22) = cholesky(c.xx, c.xy, c.yy);
        let lum = |f: f64, s: DVec2| -> f64 {
            let aff = self.material.terms.affine(self.color_at(f));
            let l = self.facet_radiance(aff, normal_of(s), cfg.wo, cfg.wi, 1.0, frame);
            (0..3).map(|k| LUMINANCE[k] * l[k]).sum::<f64>()
        };
        let slopes: Vec<(DVec2, f64)> = slope_rule(RESPONSE_POINTS)
            .iter()
            .map(|(z, w)| (s0 + DVec2::new(a11 * z.x, a21 * z.x + a22 * z.y), *w))
            .collect();
        let (uz, uw) = gauss_hermite_normal(3);
        // ℓ(f̄): the luminance at a pixel whose filtered driver is f̄, over the unresolved values
        // N(f̄, σ_u²) and slopes.
        let ell = |fbar: f64| -> f64 {
            let mut acc = 0.0;
            for (zu, wu) in uz.iter().zip(&uw) {
                for (s, w) in &slopes {
                    acc += wu * w * lum(fbar + su * zu, *s);
                }
            }
            acc
        };
        let (gz, gw) = gauss_hermite_normal(CHAOS_NODES);
        let sd = v.max(0.0).sqrt();
        let mut proj = [0.0; CHAOS_ORDERS];
        let mut mean = 0.0;
        for (z, w) in gz.iter().zip(&gw) {
            let l = ell(m + sd * z);
            mean += w * l;
            // He_n(z) by the recurrence He_{n+1} = z He_n − n He_{n−1}.
            let (mut h0, mut h1) = (1.0, *z);
            for (n, p) in proj.iter_mut().enumerate() {
                *p += w * l * h1;
                let h2 = z * h1 - (n + 1) as f64 * h0;
                (h0, h1) = (h1, h2);
            }
        }
        // E_n = n!·c_n² with c_n = E[ℓ He_n]/n!: (E[ℓ He_n])²/n!.
        let mut factorial = 1.0;
        let energies = std::array::from_fn(|n| {
            factorial *= (n + 1) as f64;
            proj[n] * proj[n] / factorial
        });
        let mut ls = DVec2::ZERO;
        for (s, w) in &slopes {
            let ds = 1e-3 * (1.0 + s.length());
            let d = |e: DVec2| (lum(m, *s + e * ds) - lum(m, *s - e * ds)) / (2.0 * ds);
            ls += *w * DVec2::new(d(DVec2::X), d(DVec2::Y));
        }
        if !(mean.is_finite() && ls.is_finite()) {
            return (0.0, [0.0; CHAOS_ORDERS], DVec2::ZERO);
        }
        (mean, energies, ls)
    }

    /// `σ_h·g′(f)`: how far a unit of the driver's gradient tilts the surface.
    pub(super) fn transfer_slope(&self, f: f64) -> f64 {
        self.surface.sigma_h * self.material.heights.transfer.derivative(f)
    }

    /// The texture's and the curvature's spectrum of the pixel-filtered radiance at `cfg` (module
    /// docs), with the pixel's mean luminance; `curvature` the macro curvature along the tangent's
    /// y (0 on the plane), `frame` the tangent frame.
    pub fn radiance_spectrum(
        &self,
        cfg: &FootprintQuery,
        frame: &DMat3,
        curvature: f64,
    ) -> (Spectrum, f64) {
        let mut out = Spectrum::default();
        if cfg.wo.z <= 0.0 {
            return (out, 0.0);
        }
        let fp = cfg.footprint;
        let d = &self.surface.driver;
        let loc = self.footprint_stats(cfg);
        // The resolved driver's spectrum: per wave for the noise (amplitudes under the pixel's
        // footprint); for an image its second moment `R/(2π)²` from the resolved gradient
        // covariance, about the whole image's mean.
        let mut resolved = Spectrum::default();
        let mut global_mean = 0.0;
        let amplitudes: Vec<(DVec2, f64)> = match d {
            DriverField::Noise(n) => n
                .waves
                .iter()
                .map(|w| (w.k, w.amplitude * n.attenuation(w, fp)))
                .collect(),
            DriverField::Image(_) => Vec::new(),
        };
        for (k, a) in &amplitudes {
            resolved.add(0.5 * a * a, *k);
        }
        if let DriverField::Image(_) = d {
            let here = &loc.driver;
            let whole = d.filtered(cfg.x0, Footprint::isotropic(1e3 * d.coarsest_scale()));
            let r = d.gradient_cov().to_mat() - here.gradient_cov.to_mat();
            resolved.energy = (whole.std * whole.std - here.std * here.std).max(0.0);
            resolved.moment = DMat2::from_cols(
                DVec2::new(r.x_axis.x.max(0.0), r.x_axis.y),
                DVec2::new(r.y_axis.x, r.y_axis.y.max(0.0)),
            ) * (1.0 / (TAU * TAU));
            global_mean = whole.mean;
        }
        let v = resolved.energy;
        let (mean, chaos, ls) = self.radiance_response(cfg, &loc, frame, (global_mean, v));
        if v > 0.0 {
            // Order n's spectrum is the n-fold convolution of the driver's (normalised): its
            // second moment is n times the driver's.
            let k2 = resolved.moment * (1.0 / v);
            for (n, e) in chaos.iter().enumerate() {
                if *e > 0.0 && e.is_finite() {
                    out.energy += e;
                    out.moment += k2 * (e * (n + 1) as f64);
                }
            }
        }
        // The slope's first order: wave k tilts the surface by τ·k (τ = 2π σ_h g′).
        let tau = TAU * self.transfer_slope(global_mean);
        for (k, a) in &amplitudes {
            let t = tau * a * ls.dot(*k);
            out.add(0.5 * t * t, *k);
        }
        if amplitudes.is_empty() && v > 0.0 {
            let e = tau * tau * ls.dot(resolved.moment * ls);
            if e > 0.0 {
                out.energy += e;
                out.moment += resolved.moment * (e / v);
            }
        }
        if curvature != 0.0 && curvature.is_finite() {
            let (diffuse, specular) = self.lobe_luminances(cfg, &loc, frame);
            let b = &self.material.brdf;
            let width = (b.roughness * b.roughness + loc.stats.slope_cov.yy)
                .sqrt()
                .max(1e-3);
            let sweep = |e: f64, cycles_per_radian: f64| {
                let k = DVec2::Y * (curvature.abs() * cycles_per_radian);
                let att = (-2.0 * PI * PI * k.dot(fp.cov * k)).exp();
                (e * att * att, k)
            };
            for (e, k) in [
                sweep(specular * specular, 1.0 / (TAU * width)),
                sweep(diffuse * diffuse, 1.0 / TAU),
            ] {
                out.add(e, k);
            }
        }
        (out, mean)
    }

    /// The luminance of the footprint's diffuse (with the environment) and specular parts, at its
    /// mean slope.
    fn lobe_luminances(
        &self,
        cfg: &FootprintQuery,
        loc: &FootprintStats,
        frame: &DMat3,
    ) -> (f64, f64) {
        let n = normal_of(loc.stats.slope_mean);
        let aff = self.material.terms.affine(self.color_at(loc.driver.mean));
        let s = self.point_shading(n, cfg.wi, frame);
        let spec = self.specular_lobes(loc.stats.slope_mean, &loc.stats.slope_cov, cfg.wo, cfg.wi);
        let tint = specular_tint(&self.channel_weights(), &aff, &s);
        let sun = self.material.lighting.sun;
        let all = self.radiance(aff, aff, &s, 1.0, spec);
        let lum = |v: [f64; 3]| (0..3).map(|k| LUMINANCE[k] * v[k]).sum::<f64>();
        let specular = lum([0, 1, 2].map(|k| sun * spec[k] * tint[k]));
        ((lum(all) - specular).max(0.0), specular.max(0.0))
    }

    /// The predicted bandwidth of one pixel at `cfg` (module docs), cycles per pixel.
    pub fn pixel_bandwidth(&self, cfg: &FootprintQuery, frame: &DMat3, curvature: f64) -> f64 {
        let (spectrum, mean) = self.radiance_spectrum(cfg, frame, curvature);
        let floor = (mean.abs() / 256.0).powi(2);
        spectrum.cycles_per_pixel(&cfg.footprint, floor)
    }

    /// The predicted bandwidth of a `width × height` view of `shape` by `camera` under the sun
    /// direction `wi`, at the pixels [`Evaluator::predict_truth_of`] predicts, each pixel's own
    /// footprint; with `step` > 1 only the centre pixel of each `step × step` block is evaluated
    /// and the block takes its value (still in cycles per pixel of the full image). Blocks beside
    /// the sky (the horizon, the cylinder's silhouette) get [`NYQUIST`]. Rows run in parallel;
    /// finite for every input.
    pub fn predict_bandwidth(
        &self,
        shape: Shape,
        camera: &Camera,
        (width, height): (u32, u32),
        wi: DVec3,
        step: u32,
    ) -> BandwidthPrediction {
        let plane_camera = self.surface.clear_camera(camera);
        let step = step.max(1);
        let (bw, bh) = (
            width.div_ceil(step) as usize,
            height.div_ceil(step) as usize,
        );
        let blocks: Vec<Option<f64>> = (0..bw * bh)
            .into_par_iter()
            .map(|p| {
                let centre = |i: usize, n: u32| {
                    ((i as u32 * step + step / 2).min(n.saturating_sub(1))) as f64 + 0.5
                };
                let px = DVec2::new(centre(p % bw, width), centre(p / bw, height));
                let (cfg, _, frame) =
                    self.view_pixel_query(shape, &plane_camera, camera, px, (width, height), wi)?;
                let curvature = match shape {
                    Shape::Plane => 0.0,
                    Shape::Cylinder { radius } => 1.0 / radius,
                };
                let b = self.pixel_bandwidth(&cfg, &frame, curvature);
                Some(if b.is_finite() { b } else { NYQUIST })
            })
            .collect();
        let (w, h) = (bw, bh);
        let pixels = blocks;
        let at = |x: isize, y: isize| -> bool {
            x < 0
                || y < 0
                || x >= w as isize
                || y >= h as isize
                || pixels[y as usize * w + x as usize].is_some()
        };
        let block: Vec<f64> = (0..w * h)
            .map(|p| {
                let Some(b) = pixels[p] else { return 0.0 };
                let (x, y) = ((p % w) as isize, (p / w) as isize);
                let edge = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                    .iter()
                    .any(|(dx, dy)| !at(x + dx, y + dy));
                if edge { NYQUIST } else { b }
            })
            .collect();
        let (fw, fh) = (width as usize, height as usize);
        let s = step as usize;
        let cycles = (0..fw * fh)
            .map(|p| block[(p / fw / s) * w + (p % fw) / s])
            .collect();
        BandwidthPrediction {
            width: fw,
            height: fh,
            cycles,
        }
    }
}
