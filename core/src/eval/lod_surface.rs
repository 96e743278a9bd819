//! The level-of-detail surface the analytic views meet: the footprint-filtered height h̄ (the
//! noise's attenuated waves, or the image's pyramid, through the transfer function's mean), marched
//! with a rigorous rate bound.

use crate::driver::field::DriverField;
use crate::driver::footprint::Footprint;
use crate::eval::Evaluator;
use crate::eval::compiled::CompiledTransfer;
use crate::scene::bound_grid::GridView;
use crate::scene::local_slope::LocalSlope;
use crate::scene::march::{March, march_heightfield};
use glam::{DVec2, DVec3};

/// How closely a camera ray brackets its crossing of h̄ before it stops, as a fraction of the
/// footprint's smallest standard deviation ([`crate::scene::octave_march::OctaveSurface::settle_width`]).
pub const LOD_SETTLE: f64 = 1e-3;

impl Evaluator {
    /// h̄(x) for footprint `fp` (σ_f is phase-averaged, hence constant over x).
    pub fn lod_height(&self, x: DVec2, fp: Footprint) -> f64 {
        let (m, s) = self.surface.driver.lod_moments(x, fp);
        self.surface.sigma_h * self.transfer.moments(m, s).mean
    }

    /// Rate bound of the gap along d: `|d_z| + K|d_xy|`, with K = σ_h·max|g′|·L̄(d̂) and L̄ the
    /// Lipschitz constant of f̄ ([`DriverField::lod_lipschitz_along`]: for the noise the attenuated
    /// components `Σ|a_i| g_i 2π|k_i·d̂|`; for the image its levels' constants, or under
    /// [`March::Reference`] the explicit surface's, as before #15; ∂ḡ/∂m = E[g′] ≤ max|g′|).
    pub(super) fn lod_rate(&self, d: DVec3, fp: Footprint) -> f64 {
        let dxy = DVec2::new(d.x, d.y);
        let r = dxy.length();
        let mut k = 0.0;
        if r > 0.0 {
            let driver = &self.surface.driver;
            let lip = match (driver, self.surface.march) {
                (DriverField::Image(_), March::Reference) => driver.lipschitz_along(dxy / r),
                _ => driver.lod_lipschitz_along(dxy / r, fp),
            };
            k = lip * self.surface.sigma_h * self.surface.g_lip;
        }
        d.z.abs() + k * r
    }

    /// March `o + t·d` against h̄ with the explicit surface's march: the octave march for a noise
    /// driver under [`March::Fast`], else [`march_heightfield`] with the level-of-detail rate. The
    /// octave march may stop a camera ray up to [`LOD_SETTLE`] footprint deviations before the
    /// crossing (never past it) where the transfer is the identity.
    pub fn lod_march(&self, o: DVec3, d: DVec3, fp: Footprint) -> Option<f64> {
        let s = &self.surface;
        if let (DriverField::Noise(n), March::Fast) = (&s.driver, s.march) {
            let att: Vec<f64> = n.waves.iter().map(|w| n.attenuation(w, fp)).collect();
            if let Some(mut os) = s.octaves(Some(&att)) {
                // σ_f is the phase average, the same at every x.
                let sf = s.driver.lod_moments(DVec2::new(o.x, o.y), fp).1;
                if let CompiledTransfer::Curve { table, slopes } = &self.transfer {
                    // G is the table's row at σ_f: its own slopes bound the march, locally and
                    // globally (the curve's max |g′| is the riser's, several times steeper).
                    let rows = slopes.at(table, sf);
                    os.g_lip = os.g_lip.min(rows.max());
                    os.g_slope = Some(LocalSlope::Table(rows));
                }
                let total = n.waves.iter().map(|w| w.amplitude.abs()).sum();
                let shift = n
                    .waves
                    .iter()
                    .zip(&att)
                    .map(|(w, g)| w.amplitude.abs() * (1.0 - g))
                    .sum();
                os.grid = s
                    .grid
                    .as_ref()
                    .map(|g| GridView::level_of_detail(g, fp, total, shift));
                // No table here: its band would be the shift D = Σ|a_i|(1 − g_i) on top of its own
                // error, which at the footprints of a frame (D ≈ 0.04 at 96×64, 60°, distance 1.5,
                // default preset) is ten times the band a camera ray may settle in, so the table
                // saved nothing (measured: naive 134 against 132 ms) and the hits stay exact.
                os.field = None;
                // A camera ray stops once the crossing is bracketed to a thousandth of the
                // footprint: the filtered colour moves by about that fraction of its variation over
                // a footprint (invisible), and the last two or three full sums of the waves go.
                os.settle_width = LOD_SETTLE * fp.min_std();
                let height_of = |m| s.sigma_h * self.transfer.moments(m, sf).mean;
                return os.march(o, d, height_of, s.march);
            }
        }
        march_heightfield(
            o,
            d,
            self.lod_rate(d, fp),
            s.h_max,
            s.min_step,
            s.march,
            |x| self.lod_height(x, fp),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::image::ImageDriver;
    use crate::driver::test_images;
    use crate::fixtures::gaussian_material;
    use crate::material::Driver;
    use crate::math::random::splitmix;
    use std::sync::Arc;

    /// The image's level-of-detail march, whose rate now comes from the levels the footprint
    /// blends (coarse levels march in long steps), never steps over a crossing of h̄: along
    /// grazing and steep rays, from a point footprint to one of 64 texels, a dense scan of
    /// `[0, t)` finds the gap non-negative, and at `t` the ray is on h̄.
    #[test]
    fn the_image_level_of_detail_march_never_steps_over_a_crossing() {
        let side = test_images::SIDE;
        let image = Arc::new(ImageDriver::new(side, side, &test_images::bricks()).unwrap());
        let mut m = gaussian_material();
        m.driver = Driver::Image {
            path: "bricks.png".into(),
            size: 1.0,
        };
        m.heights.sigma_h = 0.01;
        let e = Evaluator::with_image(&m, Some(image), None).unwrap();
        assert_eq!(e.surface.march, March::Fast);
        let mut reference = e.clone();
        reference.surface.march = March::Reference;
        let texel = 1.0 / side as f64;
        let mut rng = 5u64;
        let mut hits = 0;
        for i in 0..84 {
            let sigma = texel * [0.0, 0.3, 1.0, 2.5, 6.0, 16.0, 64.0][i % 7];
            let fp = Footprint::isotropic(sigma);
            let theta = (55.0 + 34.0 * splitmix(&mut rng)).to_radians();
            let phi = std::f64::consts::TAU * splitmix(&mut rng);
            let d = -DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            let o = DVec3::new(
                splitmix(&mut rng),
                splitmix(&mut rng),
                e.surface.h_max * 1.001 + 1e-6,
            );
            let Some(t) = e.lod_march(o, d, fp) else {
                continue;
            };
            hits += 1;
            let gap = |t: f64| {
                let q = o + d * t;
                q.z - e.lod_height(DVec2::new(q.x, q.y), fp)
            };
            let n = 3000;
            for j in 0..n {
                let s = t * j as f64 / n as f64;
                assert!(
                    gap(s) > -1e-9,
                    "σ {sigma}: crossing at {s} skipped (hit at {t})"
                );
            }
            assert!(gap(t).abs() < 1e-7, "σ {sigma}: off h̄ by {}", gap(t));
            // The reference march (the explicit surface's global constant) meets the same crossing.
            let b = reference
                .lod_march(o, d, fp)
                .expect("the reference meets h̄ too");
            assert!(
                (t - b).abs() <= 1e-6 * t.max(1.0),
                "σ {sigma}: {t} against {b}"
            );
        }
        assert!(hits > 70, "downward rays meet h̄: {hits}");
    }
}
