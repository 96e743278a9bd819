//! The lighting a material is previewed under: the directional light (the "sun" whose direction the
//! scene sets) and an optional environment, either a built-in procedural sky or an equirectangular
//! EXR/HDR file, used as an irradiance environment map [HNPN14 Sec. 5.3] through its SH9 projection
//! ([`crate::math::sh`]).
//!
//! Conventions: directions in the tangent frame, z = macro normal = up. An equirectangular image's
//! column u ∈ [0, 1) is the azimuth φ = 2πu measured from +x toward +y, its row v ∈ [0, 1] the polar
//! angle θ = πv from the zenith (the top row is the sky's zenith).
//!
//! The environment is unshadowed, as in the paper: each micro-facet receives `E(n)` whatever the
//! surrounding relief. The ground truth does the same per micro-normal, so the comparison measures the
//! filtering; macroscale occlusion of the sky is out of the model's scope ([HNPN14 Sec. 5.3]: "this
//! assumption only holds if the macrosurface is planar").

use crate::material::validation::Problems;
use crate::math::sh::Sh9;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A procedural sky: a horizon-to-zenith gradient, a uniform ground, and a sun glow.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sky {
    /// Radiance at the zenith (linear RGB).
    pub zenith: [f64; 3],
    /// Radiance at the horizon.
    pub horizon: [f64; 3],
    /// Radiance below the horizon (light bounced off the ground).
    pub ground: [f64; 3],
    /// Peak radiance of the sun glow.
    pub sun: [f64; 3],
    /// Sun elevation above the horizon, degrees.
    pub sun_elevation_deg: f64,
    /// Sun azimuth, degrees from +x toward +y.
    pub sun_azimuth_deg: f64,
    /// Angular radius of the glow (standard deviation of its Gaussian falloff), degrees, ≥ 1.
    pub sun_size_deg: f64,
}

impl Default for Sky {
    /// A clear afternoon: blue zenith, pale horizon, brown ground, a bright low sun at azimuth 180°.
    fn default() -> Self {
        Self {
            zenith: [0.10, 0.22, 0.55],
            horizon: [0.55, 0.62, 0.70],
            ground: [0.12, 0.10, 0.08],
            sun: [40.0, 36.0, 30.0],
            sun_elevation_deg: 25.0,
            sun_azimuth_deg: 180.0,
            sun_size_deg: 5.0,
        }
    }
}

impl Sky {
    /// Unit direction toward the sun.
    pub fn sun_direction(&self) -> DVec3 {
        let (e, a) = (
            self.sun_elevation_deg.to_radians(),
            self.sun_azimuth_deg.to_radians(),
        );
        DVec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin())
    }

    /// Radiance toward unit direction d: `horizon + (zenith − horizon)·√d_z` above the horizon,
    /// `ground` below, plus `sun·exp((cos γ − 1)/s²)` (γ the angle to the sun, s its size in radians).
    pub fn radiance(&self, d: DVec3) -> [f64; 3] {
        let base = if d.z >= 0.0 {
            let t = d.z.sqrt();
            [0, 1, 2].map(|c| self.horizon[c] + (self.zenith[c] - self.horizon[c]) * t)
        } else {
            self.ground
        };
        let s = self.sun_size_deg.max(1.0).to_radians();
        let glow = ((d.dot(self.sun_direction()) - 1.0) / (s * s)).exp();
        [0, 1, 2].map(|c| base[c] + self.sun[c] * glow)
    }

    /// Its SH9 projection (256 rows: the glow's smallest size, 1°, is resolved).
    pub fn sh(&self) -> Sh9 {
        Sh9::project(256, |d| self.radiance(d))
    }

    fn validate(&self, field: &str, p: &mut Problems) {
        for (name, c) in [
            ("zenith", self.zenith),
            ("horizon", self.horizon),
            ("ground", self.ground),
            ("sun", self.sun),
        ] {
            for (i, v) in c.iter().enumerate() {
                p.in_range(&format!("{field}.{name}[{i}]"), *v, 0.0, 1e6);
            }
        }
        p.in_range(
            &format!("{field}.sun_elevation_deg"),
            self.sun_elevation_deg,
            -90.0,
            90.0,
        );
        p.in_range(
            &format!("{field}.sun_azimuth_deg"),
            self.sun_azimuth_deg,
            -360.0,
            360.0,
        );
        p.in_range(
            &format!("{field}.sun_size_deg"),
            self.sun_size_deg,
            1.0,
            90.0,
        );
    }
}

/// An equirectangular radiance map (linear RGB, row-major, top row = zenith).
#[derive(Clone, Debug, PartialEq)]
pub struct EquirectMap {
    /// Width in pixels (azimuth).
    pub width: usize,
    /// Height in pixels (polar angle).
    pub height: usize,
    /// `width × height` linear-RGB texels.
    pub texels: Vec<[f32; 3]>,
}

/// Why an equirectangular map cannot be used.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum EquirectError {
    /// Size and texel count disagree, or the map is empty.
    #[error("an environment map needs at least 2×1 texels and width·height of them")]
    Size,
    /// A texel is negative, NaN, infinite or above [`EquirectMap::MAX_RADIANCE`].
    #[error("texel ({x}, {y}) is not a radiance between 0 and 1e9")]
    NotFinite {
        /// Column.
        x: usize,
        /// Row.
        y: usize,
    },
}

impl EquirectMap {
    /// Largest texel radiance accepted: far above a captured sun (~1e5 in HDR maps), far below
    /// where f32 sums on the GPU overflow (#16: texels of 3e38 turned the filtered view black and
    /// the error report into "RMSE NaN, max 0").
    pub const MAX_RADIANCE: f32 = 1e9;

    /// Check and wrap texels: each finite, non-negative and at most [`Self::MAX_RADIANCE`].
    pub fn new(width: usize, height: usize, texels: Vec<[f32; 3]>) -> Result<Self, EquirectError> {
        if width < 2 || height < 1 || texels.len() != width * height {
            return Err(EquirectError::Size);
        }
        if let Some(i) = texels
            .iter()
            .position(|t| t.iter().any(|v| !(0.0..=Self::MAX_RADIANCE).contains(v)))
        {
            return Err(EquirectError::NotFinite {
                x: i % width,
                y: i / width,
            });
        }
        Ok(Self {
            width,
            height,
            texels,
        })
    }

    /// Its SH9 projection: every texel weighted by its exact solid angle.
    pub fn sh(&self) -> Sh9 {
        let mut sh = Sh9::default();
        crate::math::sh::sphere_grid(self.height, self.width, |y, x, d, d_omega| {
            let t = self.texels[y * self.width + x];
            sh.add(t.map(f64::from), d, d_omega);
        });
        sh
    }
}

/// Where the environment's radiance comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum EnvironmentSource {
    /// The built-in procedural sky (no file needed).
    Sky(Sky),
    /// An equirectangular `.exr` or `.hdr` file, relative to the preset; loaded by the application.
    File {
        /// Path of the file.
        path: String,
    },
}

/// Environment lighting: a source and an intensity scale.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Environment {
    /// The radiance.
    pub source: EnvironmentSource,
    /// Multiplies the radiance, ≥ 0.
    #[serde(default = "one")]
    pub intensity: f64,
}

fn one() -> f64 {
    1.0
}

/// The preview lighting saved with a material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Lighting {
    /// Radiance scale of the directional light (1 = unit irradiance at normal incidence; 0 turns
    /// it off and leaves the environment alone).
    pub sun: f64,
    /// Environment lighting, if any.
    pub environment: Option<Environment>,
}

impl Default for Lighting {
    fn default() -> Self {
        Self {
            sun: 1.0,
            environment: None,
        }
    }
}

impl Lighting {
    /// Every invalid field.
    pub fn validate(&self, p: &mut Problems) {
        p.in_range("lighting.sun", self.sun, 0.0, 1e6);
        if let Some(env) = &self.environment {
            p.in_range("lighting.environment.intensity", env.intensity, 0.0, 1e6);
            match &env.source {
                EnvironmentSource::Sky(sky) => sky.validate("lighting.environment.source", p),
                EnvironmentSource::File { path } => {
                    if path.trim().is_empty() {
                        p.push(
                            "lighting.environment.source.path",
                            "an environment file needs a path",
                        );
                    }
                }
            }
        }
    }

    /// The environment's SH9 radiance (intensity applied) when it needs no file; `None` without an
    /// environment or for a file (the application projects the file with [`EquirectMap::sh`]).
    pub fn builtin_sh(&self) -> Option<Sh9> {
        let env = self.environment.as_ref()?;
        match &env.source {
            EnvironmentSource::Sky(sky) => Some(sky.sh().scaled(env.intensity)),
            EnvironmentSource::File { .. } => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equirect_of_the_sky_projects_like_the_sky() {
        let sky = Sky::default();
        let (w, h) = (512, 256);
        let mut texels = Vec::with_capacity(w * h);
        for y in 0..h {
            let theta = std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
            for x in 0..w {
                let phi = std::f64::consts::TAU * (x as f64 + 0.5) / w as f64;
                let d = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                texels.push(sky.radiance(d).map(|v| v as f32));
            }
        }
        let map = EquirectMap::new(w, h, texels).unwrap();
        let (a, b) = (map.sh(), sky.sh());
        for k in 0..9 {
            for ch in 0..3 {
                assert!(
                    (a.coeffs[k][ch] - b.coeffs[k][ch]).abs() < 1e-3 * b.coeffs[0][ch],
                    "coefficient {k}, channel {ch}"
                );
            }
        }
        // The sun is where it says: irradiance is largest facing it.
        let e_sun = b.irradiance(sky.sun_direction())[0];
        let e_away = b.irradiance(-sky.sun_direction())[0];
        assert!(e_sun > 2.5 * e_away, "{e_sun} vs {e_away}");
    }

    #[test]
    fn bad_maps_are_refused() {
        assert_eq!(
            EquirectMap::new(1, 1, vec![[0.0; 3]]),
            Err(EquirectError::Size)
        );
        assert_eq!(
            EquirectMap::new(2, 2, vec![[0.0; 3]; 3]),
            Err(EquirectError::Size)
        );
        let mut t = vec![[0.5; 3]; 8];
        t[5][1] = f32::NAN;
        assert_eq!(
            EquirectMap::new(4, 2, t),
            Err(EquirectError::NotFinite { x: 1, y: 1 })
        );
        // Finite but beyond what f32 sums survive (3e38), and negative.
        for v in [3e38, EquirectMap::MAX_RADIANCE * 1.01, -1e-3] {
            let mut t = vec![[0.5; 3]; 8];
            t[6][2] = v;
            assert_eq!(
                EquirectMap::new(4, 2, t),
                Err(EquirectError::NotFinite { x: 2, y: 1 }),
                "{v}"
            );
        }
        let mut t = vec![[0.5; 3]; 8];
        t[6][2] = EquirectMap::MAX_RADIANCE;
        assert!(EquirectMap::new(4, 2, t).is_ok());
    }

    #[test]
    fn lighting_validation_names_fields() {
        let mut l = Lighting {
            sun: -1.0,
            environment: Some(Environment {
                source: EnvironmentSource::Sky(Sky {
                    sun_size_deg: 0.0,
                    ..Sky::default()
                }),
                intensity: f64::NAN,
            }),
        };
        let mut p = Problems::default();
        l.validate(&mut p);
        let fields: Vec<_> = p.0.iter().map(|p| p.field.as_str()).collect();
        assert_eq!(
            fields,
            [
                "lighting.sun",
                "lighting.environment.intensity",
                "lighting.environment.source.sun_size_deg"
            ]
        );
        l = Lighting::default();
        let mut p = Problems::default();
        l.validate(&mut p);
        assert!(p.0.is_empty());
        assert!(l.builtin_sh().is_none());
    }
}
