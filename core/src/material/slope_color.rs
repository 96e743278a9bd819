//! Slope-correlated colour `C_s(n)` [HNPN14 Sec. 5.2]: a gradient colour map indexed by how much a
//! micro-facet faces a chosen direction, `t = n·d`, t ∈ [−1, 1].
//!
//! With d at the zenith, `t = n_z = cos θ_n`: flats are t = 1, cliffs t → 0 ("snow on the flats"); with
//! d tilted toward +y, facets facing +y are t ≈ 1 ("moss on the north faces", [HNPN14 Fig. 9]); an
//! elevation of 0 colours by orientation alone. The map is a [`Gradient`], so smooth, linear or
//! stepped transitions are all available, and it is filtered over the visible slope distribution D_s
//! ([`crate::microfacet::visible_slopes`], `footprint::visible_slope_nodes`).

use crate::material::colormap::Gradient;
use crate::material::validation::Problems;
use crate::math::piecewise::PiecewisePoly;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A colour map of the facet normal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlopeColor {
    /// Colour against `t = n·d` (positions in [−1, 1]).
    pub map: Gradient,
    /// Elevation of d above the mean plane, degrees (90 = the macro normal).
    pub elevation_deg: f64,
    /// Azimuth of d, degrees from +x toward +y.
    pub azimuth_deg: f64,
}

impl SlopeColor {
    /// Snow on the flats: rock below `t = cos 25°`, snow above `cos 15°` (smooth in between).
    pub fn snow() -> Self {
        use crate::material::colormap::{ColorStop, Interpolation};
        let rock = [0.16, 0.13, 0.11];
        let snow = [0.85, 0.88, 0.92];
        Self {
            map: Gradient {
                stops: vec![
                    ColorStop {
                        position: 25f64.to_radians().cos(),
                        color: rock,
                    },
                    ColorStop {
                        position: 15f64.to_radians().cos(),
                        color: snow,
                    },
                ],
                interpolation: Interpolation::Smooth,
            },
            elevation_deg: 90.0,
            azimuth_deg: 0.0,
        }
    }

    /// Unit direction d.
    pub fn direction(&self) -> DVec3 {
        let (e, a) = (
            self.elevation_deg.to_radians(),
            self.azimuth_deg.to_radians(),
        );
        DVec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin())
    }

    /// The map's input for unit facet normal n.
    pub fn index(&self, n: DVec3) -> f64 {
        n.dot(self.direction())
    }

    /// `C_s(n)` (builds the map's polynomial: use [`SlopeColor::compiled`] in loops).
    pub fn sample(&self, n: DVec3) -> [f64; 3] {
        self.compiled().sample(n)
    }

    /// The map as a polynomial with the direction resolved, for repeated evaluation.
    pub fn compiled(&self) -> CompiledSlopeColor {
        CompiledSlopeColor {
            poly: self.map.to_piecewise(),
            direction: self.direction(),
        }
    }

    /// Every invalid field.
    pub fn validate(&self, field: &str, p: &mut Problems) {
        self.map.validate(&format!("{field}.map"), p);
        p.in_range(
            &format!("{field}.elevation_deg"),
            self.elevation_deg,
            -90.0,
            90.0,
        );
        p.in_range(
            &format!("{field}.azimuth_deg"),
            self.azimuth_deg,
            -360.0,
            360.0,
        );
    }
}

/// A [`SlopeColor`] ready to evaluate: its piecewise polynomial (what the GPU uploads) and d.
#[derive(Clone, Debug, PartialEq)]
pub struct CompiledSlopeColor {
    /// The gradient as a polynomial of t.
    pub poly: PiecewisePoly,
    /// Unit d.
    pub direction: DVec3,
}

impl CompiledSlopeColor {
    /// `C_s(n)`.
    pub fn sample(&self, n: DVec3) -> [f64; 3] {
        let mut out = [0.0; 3];
        if !self.poly.knots.is_empty() {
            self.poly.eval(n.dot(self.direction), &mut out);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snow_lies_on_the_flats() {
        let s = SlopeColor::snow();
        let flat = s.sample(DVec3::Z);
        let cliff = s.sample(DVec3::new(0.8, 0.0, 0.6));
        assert!(flat[0] > 0.8 && cliff[0] < 0.2, "{flat:?} {cliff:?}");
        // Through the gradient's own sampling.
        assert_eq!(s.sample(DVec3::Z), s.map.sample(1.0));
    }

    #[test]
    fn direction_follows_elevation_and_azimuth() {
        let mut s = SlopeColor::snow();
        s.elevation_deg = 0.0;
        s.azimuth_deg = 90.0;
        let d = s.direction();
        assert!((d - DVec3::Y).length() < 1e-12);
        assert!((s.index(DVec3::Y) - 1.0).abs() < 1e-12);
        assert!(s.index(DVec3::Z).abs() < 1e-12);
    }
}
