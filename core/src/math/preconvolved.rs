//! Pre-convolved 2D tables `T[m, σ] = (p ∗ N(0, σ²))(m)` indexed by the mean and standard deviation of
//! a Gaussian driver [HNPN14 Eq. 9, Sec. 4.2; Sec. 7 for transfer functions].
//!
//! Layout (shared with the GPU, which reads the same texels from the material's storage buffer and
//! interpolates them itself, `math/preconvolved.wgsl` `table_sample`):
//! * `size_m × size_sigma` texels of 4 f32 channels, row-major with σ as the row index;
//! * texel `(i, j)` holds the exact value at `m_i = m_min + i·(m_max − m_min)/(size_m − 1)` and
//!   `σ_j = j·σ_max/(size_sigma − 1)`: σ is indexed linearly, not σ² [HNPN14 footnote 3];
//! * [`PreconvolvedTable::sample`] interpolates bilinearly between texel values, clamped to the
//!   table's edges; the WGSL does the same arithmetic in f32 (an engine that prefers a texture
//!   gets the same result from a linear sampler with clamp-to-edge addressing and texel centres at
//!   `u = (i + ½)/size_m`).
//!
//! Border behaviour: lookups clamp to the table (clamp-to-edge). Builders choose `[m_min, m_max]`
//! as the map's support widened by [`MARGIN_SIGMAS`]·σ_max on both sides, where the exact value is
//! within `Q(4) ≈ 3.2e-5` (times the map's range) of the constant it clamps to; σ > σ_max clamps to σ_max.

use crate::math::piecewise::PiecewisePoly;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How far (in units of σ_max) tables extend beyond the support of the tabulated map.
pub const MARGIN_SIGMAS: f64 = 4.0;

/// Size and σ range of a pre-convolved table.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// Texels along the mean axis (≥ 2).
    pub size_m: usize,
    /// Texels along the σ axis (≥ 2).
    pub size_sigma: usize,
    /// Largest tabulated σ (in driver units); the driver's unfiltered std is 1.
    pub sigma_max: f64,
}

impl Default for TableSpec {
    /// 256×256 [HNPN14 Sec. 9], σ ∈ [0, 1]: the driver has unit variance, so no footprint of it is wider.
    fn default() -> Self {
        Self {
            size_m: 256,
            size_sigma: 256,
            sigma_max: 1.0,
        }
    }
}

impl TableSpec {
    /// Largest accepted size per axis: a 1024² RGBA32F table is 16 MiB, so the colour and transfer
    /// tables together stay far below the 128 MiB one storage binding holds on the software adapter
    /// (4096² was 256 MiB each: accepted, minutes to build, then refused by the GPU; issue #16).
    pub const MAX_SIZE: usize = 1024;

    /// Clamp to valid values (2..=MAX_SIZE texels, σ_max > 0 and finite).
    pub fn sanitized(self) -> Self {
        Self {
            size_m: self.size_m.clamp(2, Self::MAX_SIZE),
            size_sigma: self.size_sigma.clamp(2, Self::MAX_SIZE),
            sigma_max: if self.sigma_max.is_finite() && self.sigma_max > 0.0 {
                self.sigma_max
            } else {
                1.0
            },
        }
    }
}

/// A pre-convolved table: see the module docs for its layout.
#[derive(Clone, Debug, PartialEq)]
pub struct PreconvolvedTable {
    /// Mean at the first column.
    pub m_min: f64,
    /// Mean at the last column.
    pub m_max: f64,
    /// σ at the last row (the first row is σ = 0).
    pub sigma_max: f64,
    /// Columns.
    pub size_m: usize,
    /// Rows.
    pub size_sigma: usize,
    /// Row-major texels (row = σ index).
    pub texels: Vec<[f32; 4]>,
}

impl PreconvolvedTable {
    /// Tabulate `map(E[p(X)])`, `X ~ N(m_i, σ_j²)`, over the grid; `map` turns the channel
    /// expectations into the four stored channels. Rows are built in parallel (rayon).
    pub fn build(
        poly: &PiecewisePoly,
        spec: TableSpec,
        m_range: (f64, f64),
        map: impl Fn(&[f64]) -> [f32; 4] + Sync,
    ) -> Self {
        let spec = spec.sanitized();
        let (m_min, mut m_max) = m_range;
        if !(m_max > m_min) {
            m_max = m_min + 1e-6;
        }
        let (nm, ns) = (spec.size_m, spec.size_sigma);
        let degree = poly.degree();
        let mut texels = vec![[0.0f32; 4]; nm * ns];
        texels.par_chunks_mut(nm).enumerate().for_each(|(j, row)| {
            let sigma = spec.sigma_max * j as f64 / (ns - 1) as f64;
            let mut e = vec![0.0; poly.channels];
            for (i, texel) in row.iter_mut().enumerate() {
                let m = m_min + (m_max - m_min) * i as f64 / (nm - 1) as f64;
                poly.gaussian_expectation_fast(m, sigma, &mut e, degree);
                *texel = map(&e);
            }
        });
        Self {
            m_min,
            m_max,
            sigma_max: spec.sigma_max,
            size_m: nm,
            size_sigma: ns,
            texels,
        }
    }

    /// Bilinear lookup at (m, σ), clamped to the table's edges (what a linear sampler with
    /// clamp-to-edge addressing does).
    /// NaN coordinates are treated as the table's lower edge.
    pub fn sample(&self, m: f64, sigma: f64) -> [f64; 4] {
        let fu = (m - self.m_min) / (self.m_max - self.m_min) * (self.size_m - 1) as f64;
        let fv = sigma / self.sigma_max * (self.size_sigma - 1) as f64;
        let (i0, i1, a) = split(fu, self.size_m);
        let (j0, j1, b) = split(fv, self.size_sigma);
        let t = |i: usize, j: usize| self.texels[j * self.size_m + i];
        let mut out = [0.0; 4];
        for (c, o) in out.iter_mut().enumerate() {
            let top = f64::from(t(i0, j0)[c]) * (1.0 - a) + f64::from(t(i1, j0)[c]) * a;
            let bot = f64::from(t(i0, j1)[c]) * (1.0 - a) + f64::from(t(i1, j1)[c]) * a;
            *o = top * (1.0 - b) + bot * b;
        }
        out
    }

    /// The two rows [`PreconvolvedTable::sample`] blends at σ (equal past the last row).
    pub fn sigma_rows(&self, sigma: f64) -> (usize, usize) {
        let fv = sigma / self.sigma_max * (self.size_sigma - 1) as f64;
        let (j0, j1, _) = split(fv, self.size_sigma);
        (j0, j1)
    }

    /// Bytes the table occupies as RGBA32F.
    pub fn bytes(&self) -> usize {
        self.texels.len() * 16
    }
}

/// Split a continuous texel coordinate into the two neighbours and the blend weight, clamped.
fn split(f: f64, n: usize) -> (usize, usize, f64) {
    let f = if f.is_nan() {
        0.0
    } else {
        f.clamp(0.0, (n - 1) as f64)
    };
    let i0 = (f.floor() as usize).min(n - 2);
    (i0, i0 + 1, f - i0 as f64)
}
