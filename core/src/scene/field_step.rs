//! The octave march's use of the table of f ([`crate::scene::field_grid`]): step near the surface on
//! the table's bounds instead of the waves' sum, and let a camera ray settle where they prove it on
//! the surface.

use crate::scene::field_grid::{FieldProbe, FieldStep, FieldView};
use crate::scene::octave_march::OctaveSurface;
use glam::{DVec2, DVec3};

/// The octave march's use of the table.
impl OctaveSurface<'_> {
    /// At `p` on a ray along `d`, with the exact surface's first-order and curvature bounds along
    /// the ray (`(_, K, M)` of the last level): the gap lies within `z − σ_h G(F) ± σ_h L e` (F the
    /// table's value, e its error bound, L the Lipschitz constant of G over `F ± e`), and the slope
    /// of f along the ray within `F′ ± e′`. From the lower bound the octave march's steps are safe
    /// with the slope's upper bound in place of the exact one. A step is taken while the lower
    /// bound is at least twice the band (further in, the waves are summed), or, for a camera ray
    /// (`crawl`) whose band is at most a quarter of `settle`, until the upper bound is below
    /// `settle` ([`FieldStep::Settle`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn field_step(
        &self,
        fv: &FieldView,
        p: DVec3,
        d: DVec3,
        &(_, lip, curv): &(f64, f64, f64),
        height_of: &impl Fn(f64) -> f64,
        settle: f64,
        crawl: bool,
    ) -> FieldStep {
        let Some(pr) = fv.probe(DVec2::new(p.x, p.y), DVec2::new(d.x, d.y)) else {
            return FieldStep::Unsure;
        };
        let e = pr.error;
        let g = self.g_slope.map_or(self.g_lip, |gs| {
            gs.lipschitz_on(pr.value - e, pr.value + e).min(self.g_lip)
        });
        let above = p.z - height_of(pr.value);
        let band = self.sigma_h * g * e;
        let (lo, hi) = (above - band, above + band);
        if !(lo >= 0.0) {
            return FieldStep::Unsure;
        }
        if hi <= settle {
            return self.field_crossing_ahead(fv, p, d, pr, hi + 2.0 * band, height_of);
        }
        if !(lo >= 2.0 * band || crawl && 4.0 * band <= settle) {
            return FieldStep::Unsure;
        }
        let fd = if self.linear {
            pr.slope + pr.slope_error
        } else {
            pr.slope.abs() + pr.slope_error
        };
        let sg = self.sigma_h * self.g_lip;
        let found = Some((self.step(lo, fd, lip, curv, d.z, sg), lo));
        match self.local_step(found, above, pr.value, fd, (e, lip, curv), d.z, None) {
            Some((s, gap)) if s.is_finite() && s >= self.min_step => FieldStep::Clear(s, gap),
            _ => FieldStep::Unsure,
        }
    }

    /// Where the table puts the gap within `[0, settle]`: [`FieldStep::Settle`] only when it also
    /// proves a crossing just ahead, so a camera ray that skims a crest within the band goes on
    /// (with the waves' sum) instead of stopping on it. From the table's rate of descent of the gap
    /// (`σ_h G′(F)·F′ − d_z`, by a difference over the table's error), the point `δ = 2·reach/rate`
    /// ahead (`reach` = the gap's upper bound plus the band) must be certainly below the surface.
    fn field_crossing_ahead(
        &self,
        fv: &FieldView,
        p: DVec3,
        d: DVec3,
        pr: FieldProbe,
        reach: f64,
        height_of: &impl Fn(f64) -> f64,
    ) -> FieldStep {
        let eps = pr.error / pr.slope.abs().max(1e-300);
        let rate = (height_of(pr.value + pr.slope * eps) - height_of(pr.value)) / eps - d.z;
        if !(rate > 0.0 && eps.is_finite()) {
            return FieldStep::Unsure;
        }
        let q = p + d * (2.0 * reach / rate);
        let Some(pq) = fv.probe(DVec2::new(q.x, q.y), DVec2::new(d.x, d.y)) else {
            return FieldStep::Unsure;
        };
        let e = pq.error;
        let g = self.g_slope.map_or(self.g_lip, |gs| {
            gs.lipschitz_on(pq.value - e, pq.value + e).min(self.g_lip)
        });
        if q.z - height_of(pq.value) + self.sigma_h * g * e < 0.0 {
            FieldStep::Settle
        } else {
            FieldStep::Unsure
        }
    }
}
