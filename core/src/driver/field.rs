//! The driving function f over the plane, whichever kind the material has: the procedural noise
//! ([`SumOfSines`], analytic footprint statistics) or a tiled image ([`ImageDriver`], mip-mapped
//! moments). Everything downstream — the explicit surface, the level-of-detail surface, the filtered
//! statistics — asks this type, so both kinds go through the same code paths.

use crate::driver::footprint::{FilteredDriver, Footprint};
use crate::driver::image::{ImageDriver, lod_for_std};
use crate::driver::noise::SumOfSines;
use crate::microfacet::slopes::SlopeCov;
use glam::DVec2;
use std::f64::consts::TAU;
use std::sync::Arc;

/// An image driver tiling the plane: one tile is `size` world units wide (texels are square, so a
/// W×H image's tile is `size × size·H/W`).
#[derive(Clone, Debug)]
pub struct TiledImage {
    /// The image and its pyramid.
    pub image: Arc<ImageDriver>,
    /// World width of one tile.
    pub size: f64,
}

impl TiledImage {
    /// Level-0 texels per world unit.
    pub fn texels_per_unit(&self) -> f64 {
        self.image.size().0 as f64 / self.size
    }
}

/// The driver f.
#[derive(Clone, Debug)]
pub enum DriverField {
    /// Sum-of-sinusoids noise.
    Noise(SumOfSines),
    /// A tiled image.
    Image(TiledImage),
}

impl DriverField {
    /// An image driver tiled every `size` world units (a `size` that is not finite and positive
    /// reads as 1).
    pub fn tiled(image: Arc<ImageDriver>, size: f64) -> Self {
        Self::Image(TiledImage {
            image,
            size: if size.is_finite() && size > 0.0 {
                size
            } else {
                1.0
            },
        })
    }

    /// The image, for an image driver.
    pub fn image(&self) -> Option<&TiledImage> {
        match self {
            Self::Image(t) => Some(t),
            Self::Noise(_) => None,
        }
    }

    /// f(x).
    pub fn value(&self, x: DVec2) -> f64 {
        match self {
            Self::Noise(n) => n.value(x),
            Self::Image(t) => t.image.value_and_gradient(x * t.texels_per_unit()).0,
        }
    }

    /// f(x) and ∇f(x) (world units).
    pub fn value_and_gradient(&self, x: DVec2) -> (f64, DVec2) {
        match self {
            Self::Noise(n) => n.value_and_gradient(x),
            Self::Image(t) => {
                let s = t.texels_per_unit();
                let (f, g) = t.image.value_and_gradient(x * s);
                (f, g * s)
            }
        }
    }

    /// Footprint statistics at x: the noise's exact Gaussian attenuation, or the image's mip-mapped
    /// moments ([`ImageDriver::footprint_moments`]) converted to world units.
    pub fn filtered(&self, x: DVec2, fp: Footprint) -> FilteredDriver {
        match self {
            Self::Noise(n) => n.filtered(x, fp),
            Self::Image(t) => {
                let s = t.texels_per_unit();
                let m = t.image.footprint_moments(x * s, fp.cov * (s * s));
                FilteredDriver {
                    mean: m.mean,
                    std: m.std(),
                    mean_gradient: m.grad_mean * s,
                    gradient_cov: SlopeCov::from_mat(m.grad_cov() * (s * s)),
                }
            }
        }
    }

    /// The level-of-detail driver at footprint `fp`: `(f̄(x), σ_f)` with σ_f averaged over position
    /// (the noise's phase average; for the image the levels' mean variance at the area-equivalent
    /// isotropic footprint √(σ₁σ₂)), so the level-of-detail surface depends on x only through f̄.
    pub fn lod_moments(&self, x: DVec2, fp: Footprint) -> (f64, f64) {
        match self {
            Self::Noise(n) => {
                let d = n.filtered(x, fp);
                (d.mean, d.std)
            }
            Self::Image(t) => {
                let s = t.texels_per_unit();
                let cov = fp.cov * (s * s);
                let plan = t.image.plan(cov);
                let area = cov.determinant().max(0.0).sqrt().sqrt();
                (
                    t.image.footprint_mean(x * s, &plan),
                    t.image.mean_std(lod_for_std(area)),
                )
            }
        }
    }

    /// `Σ|a_i|` for the noise, max |texel| for the image: a bound on |f| and on every f̄.
    pub fn amplitude_bound(&self) -> f64 {
        match self {
            Self::Noise(n) => n.amplitude_bound(),
            Self::Image(t) => t.image.max_abs,
        }
    }

    /// A Lipschitz constant of f along the horizontal unit direction `dir`.
    pub fn lipschitz_along(&self, dir: DVec2) -> f64 {
        match self {
            Self::Noise(n) => n.lipschitz_along(dir),
            Self::Image(t) => {
                let l = t.image.lipschitz;
                t.texels_per_unit() * (l.x * dir.x.abs() + l.y * dir.y.abs())
            }
        }
    }

    /// A Lipschitz constant of f̄ at footprint `fp` along `dir`: the noise's attenuated components;
    /// for the image the constants of the levels the footprint's probe plan blends
    /// ([`ImageDriver::lod_lipschitz`]: coarse levels are smooth, so the far field marches in long
    /// steps).
    pub fn lod_lipschitz_along(&self, dir: DVec2, fp: Footprint) -> f64 {
        match self {
            Self::Noise(n) => n
                .waves
                .iter()
                .map(|w| w.amplitude.abs() * n.attenuation(w, fp) * TAU * w.k.dot(dir).abs())
                .sum(),
            Self::Image(t) => {
                let s = t.texels_per_unit();
                let l = t.image.lod_lipschitz(&t.image.plan(fp.cov * (s * s)));
                s * (l.x * dir.x.abs() + l.y * dir.y.abs())
            }
        }
    }

    /// A bound on |∇f| in every direction.
    pub fn gradient_bound(&self) -> f64 {
        match self {
            Self::Noise(n) => n
                .waves
                .iter()
                .map(|w| w.amplitude.abs() * TAU * w.k.length())
                .sum(),
            Self::Image(t) => t.texels_per_unit() * t.image.lipschitz.length(),
        }
    }

    /// The finest scale of the driver (shortest wavelength; the texel size for an image).
    pub fn finest_scale(&self) -> f64 {
        match self {
            Self::Noise(n) => {
                let k = n.waves.iter().map(|w| w.k.length()).fold(0.0, f64::max);
                if k > 0.0 { 1.0 / k } else { 1e-2 }
            }
            Self::Image(t) => 1.0 / t.texels_per_unit(),
        }
    }

    /// The coarsest scale of the driver (longest wavelength; the tile for an image).
    pub fn coarsest_scale(&self) -> f64 {
        match self {
            Self::Noise(n) => {
                let k = n
                    .waves
                    .iter()
                    .map(|w| w.k.length())
                    .fold(f64::INFINITY, f64::min);
                if k.is_finite() && k > 0.0 {
                    1.0 / k
                } else {
                    1.0 / 20.0
                }
            }
            Self::Image(t) => t.size,
        }
    }

    /// The unfiltered gradient covariance of f (world units): the noise's construction target, the
    /// image's global cell averages.
    pub fn gradient_cov(&self) -> SlopeCov {
        match self {
            Self::Noise(n) => n.gradient_cov(),
            Self::Image(t) => {
                let s = t.texels_per_unit();
                let top = t.image.moments_at(DVec2::ZERO, 99.0);
                SlopeCov::from_mat(top.grad_cov() * (s * s))
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::driver::DriverError;
    use crate::driver::noise::Wave;
    use crate::eval::{Evaluator, FootprintQuery};
    use crate::material::Driver;
    use crate::scene::direction::direction;
    use glam::DVec3;

    /// Sinusoids with whole numbers of cycles per tile (so an image of them tiles exactly), unit
    /// variance, wavelengths from 1/4 to 1/10 of the tile.
    pub(crate) fn tiling_waves(tile: f64) -> SumOfSines {
        let mut waves = Vec::new();
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..24 {
            let a = std::f64::consts::PI * (i as f64 + next()) / 24.0;
            let r = 4.0 + 6.0 * next();
            let k = (DVec2::from_angle(a) * r).round();
            if k == DVec2::ZERO {
                continue;
            }
            waves.push(Wave {
                k: k / tile,
                amplitude: 1.0,
                phase: TAU * next(),
            });
        }
        let norm = (waves.len() as f64 / 2.0).sqrt();
        for w in &mut waves {
            w.amplitude /= norm;
        }
        SumOfSines { waves, octaves: 1 }
    }

    /// The same field sampled into a `n`×`n` image over one tile.
    pub(crate) fn image_of(noise: &SumOfSines, tile: f64, n: usize) -> Arc<ImageDriver> {
        let values: Vec<f32> = (0..n * n)
            .map(|i| {
                let x = DVec2::new((i % n) as f64 + 0.5, (i / n) as f64 + 0.5) * (tile / n as f64);
                noise.value(x) as f32
            })
            .collect();
        Arc::new(ImageDriver::new(n, n, &values).unwrap())
    }

    /// The image of a noise has the noise's statistics at every scale: footprint mean, σ_f and
    /// the unresolved gradient covariance agree with the noise's exact Gaussian filtering (within
    /// the box-versus-Gaussian kernel difference and the image's own standardization).
    #[test]
    fn image_statistics_match_the_analytic_noise_they_sample() {
        let tile = 2.0;
        let noise = tiling_waves(tile);
        let img = DriverField::Image(TiledImage {
            image: image_of(&noise, tile, 256),
            size: tile,
        });
        let nf = DriverField::Noise(noise);
        // Global gradient covariance.
        let (a, b) = (nf.gradient_cov(), img.gradient_cov());
        assert!(
            (a.xx - b.xx).abs() < 0.03 * a.xx && (a.yy - b.yy).abs() < 0.03 * a.yy,
            "{a:?} {b:?}"
        );
        // Filtered statistics, averaged over positions.
        for r in [0.01, 0.03, 0.1, 1.0] {
            let fp = Footprint::isotropic(r);
            let (mut e_mean, mut var_n, mut var_i, mut gx_n, mut gx_i) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for j in 0..64 {
                let x = DVec2::new(0.37 * j as f64, 0.61 * j as f64 + 0.1);
                let (dn, di) = (nf.filtered(x, fp), img.filtered(x, fp));
                e_mean += (dn.mean - di.mean).abs() / 64.0;
                var_n += dn.std.powi(2) / 64.0;
                var_i += di.std.powi(2) / 64.0;
                gx_n += (dn.gradient_cov.xx + dn.mean_gradient.x.powi(2)) / 64.0;
                gx_i += (di.gradient_cov.xx + di.mean_gradient.x.powi(2)) / 64.0;
            }
            eprintln!(
                "r {r}: |Δmean| {e_mean:.4}, σ_f² {var_n:.4} vs {var_i:.4}, E f_x² {gx_n:.3} vs {gx_i:.3}"
            );
            // At r = 0.1 (σ ≈ λ/3 of the longest waves) the box kernels ring where the Gaussian
            // decays: the largest difference of the two filters.
            assert!(e_mean < 0.1, "r {r}: mean differs by {e_mean}");
            assert!(
                (var_n - var_i).abs() < 0.12 * var_n + 0.01,
                "r {r}: σ_f² {var_n} vs {var_i}"
            );
            assert!(
                (gx_n - gx_i).abs() < 0.12 * gx_n + 0.01 * a.xx,
                "r {r}: E f_x² {gx_n} vs {gx_i}"
            );
        }
        // Bounds hold for the image.
        let d = DVec2::new(0.6, 0.8);
        for j in 0..500 {
            let x = DVec2::new(0.013 * j as f64, -0.029 * j as f64);
            let e = 1e-7;
            let slope = (img.value(x + d * e) - img.value(x)) / e;
            assert!(slope.abs() <= img.lipschitz_along(d) * (1.0 + 1e-6));
            assert!(img.value(x).abs() <= img.amplitude_bound() + 1e-12);
        }
    }

    /// An image-driven material: the filtered model matches ground truth on the explicit bilinear
    /// micro-geometry at a far footprint, and naive does not.
    #[test]
    fn image_driven_material_filtered_matches_ground_truth() {
        let tile = 2.0;
        let noise = tiling_waves(tile);
        let mut m = crate::fixtures::gaussian_material();
        m.driver = Driver::Image {
            path: "test.png".into(),
            size: tile,
        };
        m.heights.sigma_h = 0.03;
        assert_eq!(
            Evaluator::new(&m).err(),
            Some(DriverError::ImageDriver),
            "an image driver needs its image"
        );
        let p = Evaluator::with_image(&m, Some(image_of(&noise, tile, 256)), None).unwrap();
        let sigma_n = p.surface.driver.gradient_cov().scaled(m.heights.sigma_h);
        eprintln!("image slopes σ_n² = {sigma_n:?}");
        for deg in [0.0_f64, 30.0, 60.0] {
            let cfg = FootprintQuery::far(&p, direction(deg.to_radians(), 0.3), DVec3::Z);
            let gt = p.ground_truth(&cfg, 60_000, 3);
            let fi = p.filtered(&cfg);
            let na = p.naive(&cfg);
            let err = |v: [f64; 3]| {
                (0..3)
                    .map(|k| (v[k] - gt.mean[k]).abs() / gt.mean[k])
                    .fold(0.0, f64::max)
            };
            eprintln!(
                "view {deg}°: filtered err {:.2}%, naive err {:.2}% (truth ± {:.2}%)",
                100.0 * err(fi),
                100.0 * err(na),
                100.0 * gt.std_error[0] / gt.mean[0]
            );
            assert!(
                err(fi) < 0.02,
                "view {deg}°: filtered {fi:?} vs truth {:?}",
                gt.mean
            );
            assert!(err(na) > 0.1, "naive should be visibly wrong");
        }
        // Reuse keeps the image when the driver is unchanged.
        let mut m2 = m.clone();
        m2.heights.sigma_h = 0.07;
        let p2 = Evaluator::reusing(&m2, Some(&p)).unwrap();
        assert!(p2.surface.driver.image().is_some());
        m2.driver = Driver::Image {
            path: "other.png".into(),
            size: tile,
        };
        assert!(Evaluator::reusing(&m2, Some(&p)).is_err());
    }
}
