//! The octave march's use of the bound grid ([`crate::scene::bound_grid`]): skip the part of a ray
//! the grid's ranges prove clear of the surface, in a few lookups instead of many steps.

use crate::scene::bound_grid::GridView;
use crate::scene::octave_march::{GRID_TRIES, OctaveSurface};
use glam::{DVec2, DVec3};

/// The octave march's use of the grid: skip what it proves clear ([`crate::scene::octave_march`]).
impl OctaveSurface<'_> {
    /// The furthest `t1 > t` to which [`GridView`] proves the ray clear of the surface, with the
    /// gap's lower bound there, or `None`. Segments from the last clear point double while they are
    /// clear and halve when not, down to one cell (`len` carries the length between calls).
    pub(crate) fn grid_skip(
        &self,
        gv: &GridView,
        o: DVec3,
        d: DVec3,
        t: f64,
        len: &mut f64,
        height_of: &impl Fn(f64) -> f64,
    ) -> Option<(f64, f64)> {
        let cell = gv.grid.cell;
        let mut best: Option<(f64, f64)> = None;
        let mut l = len.max(2.0 * cell);
        for _ in 0..GRID_TRIES {
            let t0 = best.map_or(t, |b| b.0);
            let t1 = t0 + l;
            match self.grid_gap(gv, o + d * t0, o + d * t1, height_of) {
                Some(g) if g > 0.0 => {
                    best = Some((t1, g));
                    l *= 2.0;
                }
                _ => {
                    if l <= cell {
                        break;
                    }
                    l *= 0.5;
                }
            }
        }
        *len = l;
        best
    }

    /// A lower bound of the gap along the segment from `a` to `b` from the grid's range of f over
    /// its box: the segment's lowest z minus the highest surface that range allows (`σ_h·G(hi)`
    /// for the identity and rising curves; `σ_h·(G(mid) + L·(hi − lo)/2)` with the local Lipschitz constant L of a
    /// curve; G at one end of the range when G is monotone). `None` where the box leaves the grid.
    fn grid_gap(
        &self,
        gv: &GridView,
        a: DVec3,
        b: DVec3,
        height_of: &impl Fn(f64) -> f64,
    ) -> Option<f64> {
        let (lo, hi) = gv.range(DVec2::new(a.x, a.y), DVec2::new(b.x, b.y))?;
        let h = if let Some(rising) = self.monotone {
            height_of(if rising { hi } else { lo })
        } else {
            let l = self
                .g_slope
                .map_or(self.g_lip, |gs| gs.lipschitz_on(lo, hi).min(self.g_lip));
            height_of(0.5 * (lo + hi)) + self.sigma_h * l * 0.5 * (hi - lo)
        };
        Some(a.z.min(b.z) - h)
    }
}
