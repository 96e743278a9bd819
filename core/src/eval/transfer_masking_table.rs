//! A transfer-curve material's table of masking conditioned on the driver's value and slope
//! ([`crate::microfacet::barrier_masking`], #17), and what the transfer mixture's bins take from it
//! ([`TransferRays`]).
//!
//! Entry: `ln G1(x_i, t_j)` at [`VALUE_NODES`] driver values `x_i` ([`value_node`], in the
//! driver's global σ) × [`SLOPE_NODES`] driver slopes along the ray `t_j` ([`slope_node`], in the
//! driver's global slope σ along the ray's azimuth), clamped to `[−MAX_LOG_G1, 0]`; back faces
//! hold the last front value (the clamped cosine and the projected area take them out).
//! Axes as [`crate::eval::slope_masking_table`]'s, without its footprint levels: the ray's
//! azimuth ([`TABLE_AZIMUTHS`] over [0, π)) and `ν = μ/(σ_h σ_t)` ([`TABLE_NUS`] nodes, linear in
//! ln ν). The process is the driver's whole (far field): the barrier is the curve at the
//! driver's absolute value, which a footprint's unresolved part alone does not know, so the
//! bins blend toward Smith's as the footprint resolves the driver ([`far_weight`]).
//!
//! **A CPU prototype.** [`crate::eval::Evaluator::new`] does not build the table and the views
//! keep Smith's bins; the measurements set [`crate::eval::Evaluator::transfer_masking`] to compare
//! (docs/design.md, "Transfer curves: masking that knows the driver's slope", has the full grid
//! and why it is not the default yet).

use crate::driver::noise::SumOfSines;
use crate::eval::slope_masking_table::{
    NU_MIN, NU_RATIO, TABLE_AZIMUTHS, TABLE_NUS, azimuth_coordinate, nu_coordinate,
};
use crate::material::transfer::TransferFunction;
use crate::math::gaussian::cholesky;
use crate::math::quadrature::gauss_hermite_normal;
use crate::microfacet::barrier_masking::{TransferBarrier, barrier_log_g1};
use crate::microfacet::slope_masking::{LineProcess, ProcessGrid};
use glam::DVec2;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::sync::{Arc, Mutex};

/// Driver values of an entry: `−4 + VALUE_STEP·i` (σ units).
pub const VALUE_NODES: usize = 32;
/// Step of the value nodes (σ units): 0.5 smeared a tread's masking across the riser next to
/// it (terraces, 16% off between nodes; docs/design.md).
pub const VALUE_STEP: f64 = 0.25;
/// Driver slopes of an entry: `−4 + SLOPE_STEP·j` (σ units).
pub const SLOPE_NODES: usize = 17;
/// Step of the slope nodes (σ units): over a tread `ln G1` falls ever faster as the driver rises
/// toward the ray, and a chord across 1σ came out several percent dark (terraces).
pub const SLOPE_STEP: f64 = 0.5;
/// f32 values per entry, value-major.
pub const TRANSFER_ENTRY: usize = VALUE_NODES * SLOPE_NODES;

/// Driver slope of node `j` (σ units along the ray).
pub fn slope_node(j: usize) -> f64 {
    -4.0 + SLOPE_STEP * j as f64
}

/// The slope nodes `j, j + 1` around `t` and the weight of `j + 1`, clamped (NaN reads 0).
pub fn slope_cell(t: f64) -> (usize, f64) {
    node_cell(t, slope_node(0), SLOPE_STEP, SLOPE_NODES)
}
/// Clamp of `−ln G1` (a start masked beyond e⁻³⁰ is as good as hidden).
pub const MAX_LOG_G1: f64 = 30.0;

/// Driver value of node `i` (global σ units).
pub fn value_node(i: usize) -> f64 {
    -4.0 + VALUE_STEP * i as f64
}

/// The value nodes `i, i + 1` around `x` and the weight of `i + 1`, clamped (NaN reads 0).
pub fn value_cell(x: f64) -> (usize, f64) {
    node_cell(x, value_node(0), VALUE_STEP, VALUE_NODES)
}

/// The nodes `i, i + 1` of an evenly spaced axis (`first + step·i`, n nodes) around `x` and the
/// weight of `i + 1`, clamped to the ends (NaN reads 0).
fn node_cell(x: f64, first: f64, step: f64, n: usize) -> (usize, f64) {
    let x = if x.is_nan() { 0.0 } else { x };
    let u = ((x - first) / step).clamp(0.0, (n - 1) as f64);
    let i = (u as usize).min(n - 2);
    (i, u - i as f64)
}

/// The table (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TransferMaskingTable {
    /// The driver's global standard deviation.
    pub sigma_f: f64,
    /// The driver's global gradient covariance `(xx, xy, yy)`.
    pub gradient: [f64; 3],
    /// `TRANSFER_ENTRY` values per (azimuth, ν), ν fastest.
    pub data: Vec<f32>,
}

static CACHE: Mutex<Vec<(Vec<u64>, Arc<TransferMaskingTable>)>> = Mutex::new(Vec::new());
const CACHE_SIZE: usize = 8;

impl TransferMaskingTable {
    /// [`TransferMaskingTable::new`] through a process-wide cache keyed by the waves and the
    /// curve, exactly (the tests' many evaluators of the same presets build it once).
    pub fn shared(noise: &SumOfSines, transfer: &TransferFunction) -> Option<Arc<Self>> {
        let mut key: Vec<u64> = noise
            .waves
            .iter()
            .flat_map(|w| [w.k.x.to_bits(), w.k.y.to_bits(), w.amplitude.to_bits()])
            .collect();
        if let TransferFunction::Curve(c) = transfer {
            key.extend(
                c.points
                    .iter()
                    .flat_map(|p| [p[0].to_bits(), p[1].to_bits()]),
            );
            key.push(c.interpolation as u64);
        }
        let lock = || {
            CACHE
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        };
        if let Some((_, t)) = lock().iter().find(|(k, _)| *k == key) {
            return Some(t.clone());
        }
        let table = Arc::new(Self::new(noise, transfer)?);
        let mut cache = lock();
        if cache.len() >= CACHE_SIZE {
            cache.remove(0);
        }
        cache.push((key, table.clone()));
        Some(table)
    }

    /// Tabulate (in parallel over azimuths). `None` without waves of any variance.
    pub fn new(noise: &SumOfSines, transfer: &TransferFunction) -> Option<Self> {
        let var: f64 = noise
            .waves
            .iter()
            .map(|w| 0.5 * w.amplitude * w.amplitude)
            .sum();
        if !(var > 0.0 && var.is_finite()) {
            return None;
        }
        let mut gradient = [0.0; 3];
        for w in &noise.waves {
            let (c, k) = (0.5 * w.amplitude * w.amplitude, TAU * w.k);
            gradient[0] += c * k.x * k.x;
            gradient[1] += c * k.x * k.y;
            gradient[2] += c * k.y * k.y;
        }
        let sigma_f = var.sqrt();
        let barrier = TransferBarrier::new(transfer, sigma_f);
        let rows: Vec<Vec<f32>> = (0..TABLE_AZIMUTHS)
            .into_par_iter()
            .map(|a| {
                let dir = DVec2::from_angle(PI * a as f64 / TABLE_AZIMUTHS as f64);
                let process = LineProcess::new(
                    noise
                        .waves
                        .iter()
                        .map(|w| (0.5 * w.amplitude * w.amplitude, TAU * w.k.dot(dir))),
                );
                let grid = process.as_ref().map(|p| ProcessGrid::new(p, NU_MIN));
                let mut out = Vec::with_capacity(TABLE_NUS * TRANSFER_ENTRY);
                for j in 0..TABLE_NUS {
                    let nu = NU_MIN * NU_RATIO.powi(j as i32);
                    for i in 0..VALUE_NODES {
                        let mut last = 0.0f64;
                        for s in 0..SLOPE_NODES {
                            let (x, t) = (value_node(i), slope_node(s));
                            let v = match &grid {
                                Some(_) if barrier.back_face(x, t, nu) && s > 0 => last,
                                Some(g) => barrier_log_g1(g, &barrier, x, t, nu).max(-MAX_LOG_G1),
                                None => 0.0,
                            };
                            last = v;
                            out.push(stored(v) as f32);
                        }
                    }
                }
                out
            })
            .collect();
        Some(Self {
            sigma_f,
            gradient,
            data: rows.concat(),
        })
    }

    /// The driver's global slope deviation along the unit direction `dir`.
    pub fn slope_sigma(&self, dir: DVec2) -> f64 {
        let [xx, xy, yy] = self.gradient;
        (dir.x * dir.x * xx + 2.0 * dir.x * dir.y * xy + dir.y * dir.y * yy)
            .max(0.0)
            .sqrt()
    }

    /// The entry (`ln G1` at each node) of a ray of horizontal direction `dir` (unit) and slope
    /// `nu`: [`stored`] bilinear in the azimuth and ln ν (clamped; non-finite inputs read the
    /// first nodes).
    pub fn lookup(&self, dir: DVec2, nu: f64) -> [f64; TRANSFER_ENTRY] {
        let (a0, a1, fa) = azimuth_coordinate(dir);
        let (n0, fnu) = nu_coordinate(nu);
        let mut acc = [0.0f64; TRANSFER_ENTRY];
        for (a, wa) in [(a0, 1.0 - fa), (a1, fa)] {
            for (n, wn) in [(n0, 1.0 - fnu), (n0 + 1, fnu)] {
                let w = wa * wn;
                if w == 0.0 {
                    continue;
                }
                let base = (a * TABLE_NUS + n) * TRANSFER_ENTRY;
                for (o, v) in acc.iter_mut().zip(&self.data[base..base + TRANSFER_ENTRY]) {
                    *o += w * f64::from(*v);
                }
            }
        }
        acc.map(|q| -q.exp())
    }
}

/// Below this `−ln G1` counts as 0 in the stored logarithm ([`stored`]).
pub const MIN_EXPONENT: f64 = 1e-6;

/// What the table stores of `ln G1 ≤ 0`: `ln(max(−ln G1, MIN_EXPONENT))`, interpolated linearly
/// over the azimuth and ln ν. The exponent `−ln G1` follows Smith's Λ(ν), which is convex in ln ν
/// (exponential tails): interpolated as it is between nodes a ratio 1.5 apart it came out up to
/// 0.08 too dark in P(clear) on terraces; its logarithm is close to linear there.
pub fn stored(log_g1: f64) -> f64 {
    (-log_g1).max(MIN_EXPONENT).ln()
}

/// `ln G1` of an entry at driver value `x` and slope `t` (both in σ), bilinear, clamped.
pub fn entry_at(entry: &[f64; TRANSFER_ENTRY], x: f64, t: f64) -> f64 {
    let (i, fi) = value_cell(x);
    let (j, fj) = slope_cell(t);
    let v = |i: usize, j: usize| entry[i * SLOPE_NODES + j];
    (v(i, j) * (1.0 - fj) + v(i, j + 1) * fj) * (1.0 - fi)
        + (v(i + 1, j) * (1.0 - fj) + v(i + 1, j + 1) * fj) * fi
}

/// How far the footprint is, for the blend with Smith's: `(σ_f,footprint/σ_f,global)²`, in
/// [0, 1] (the share of the driver's variance the footprint leaves unresolved).
/// 0 when the driver has no global spread (nothing to condition on).
pub fn far_weight(footprint_std: f64, global_std: f64) -> f64 {
    if !(global_std > 0.0) {
        return 0.0;
    }
    let r = footprint_std / global_std;
    if r.is_finite() {
        (r * r).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Points per axis of the Gauss–Hermite rule over the driver's slopes at a value
/// ([`bin_visibility`]; the rule is their tensor product). 3 left the seen-and-lit share of a
/// value band up to 0.12 off the per-point model on terraces (G1 falls within 1σ of t over a
/// tread); 9 is within 0.04–0.07, as a 33 × 33 grid (docs/design.md).
pub const RULE_POINTS: usize = 9;

/// What one ray needs of the table: its entry and the projections of the driver's whitened
/// gradient on its azimuth in σ units.
#[derive(Clone, Debug, PartialEq)]
pub struct RayMasking {
    /// The looked-up entry.
    pub entry: [f64; TRANSFER_ENTRY],
    /// The ray's ν.
    pub nu: f64,
    /// `t = p·ξ` for the whitened gradient ξ of the footprint (σ units of the table).
    pub projection: DVec2,
}

/// One number per bin instead of the bins' node-by-node sums (what the measurements compare
/// with the per-point model, `transfer_conditioned_masking_prototype`): the bin visibility at
/// driver value `x` (global σ), `(V̂o, V̂2)`, the mean
/// of `G1o` and of the joint masking–shadowing over the driver's slopes at the value (the
/// footprint's Gaussian, [`RULE_POINTS`]² nodes), weighted by the projected area toward the eye
/// `max(0, 1 − G′(x)·t_o/ν_o)`, and the joint term also by the cosine toward the light
/// `max(0, 1 − G′(x)·t_i/ν_i)` (what it multiplies is lit). The joint term
/// combines the two conditioned `G1` as [`crate::microfacet::masking_shadowing::G2`] combines Λs
/// (the more masked one times the other to the azimuth factor `k`: 1 when uncorrelated, 0 for
/// a light along the view). `slope` is `G′(x)`. `None` when no node faces the eye.
pub fn bin_visibility(
    o: &RayMasking,
    i: Option<&RayMasking>,
    x: f64,
    slope: f64,
    k: f64,
) -> Option<(f64, f64)> {
    let (mut w_sum, mut w_lit, mut vo, mut v2) = (0.0, 0.0, 0.0, 0.0);
    let (nodes, weights) = gauss_hermite_normal(RULE_POINTS);
    let rule: Vec<(f64, f64)> = nodes.into_iter().zip(weights).collect();
    for &(a, wa) in &rule {
        for &(b, wb) in &rule {
            let xi = DVec2::new(a, b);
            let to = o.projection.dot(xi);
            let u = (1.0 - slope * to / o.nu.max(1e-300)).max(0.0);
            let w = wa * wb * u;
            if w == 0.0 {
                continue;
            }
            let go = entry_at(&o.entry, x, to).exp();
            w_sum += w;
            vo += w * go;
            if let Some(i) = i {
                // What the joint term multiplies is lit: weighted by the cosine toward the light.
                let ti = i.projection.dot(xi);
                let ui = (1.0 - slope * ti / i.nu.max(1e-300)).max(0.0);
                let gi = entry_at(&i.entry, x, ti).exp();
                let (lo, hi) = if go <= gi { (go, gi) } else { (gi, go) };
                w_lit += w * ui;
                v2 += w * ui * lo * hi.powf(k);
            }
        }
    }
    (w_sum > 0.0).then(|| (vo / w_sum, if w_lit > 0.0 { v2 / w_lit } else { 0.0 }))
}

/// A footprint's view and light against a [`TransferMaskingTable`]: what the transfer mixture's
/// bins need to replace Smith's height-only visibility ([`TransferRays::node_visibility`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TransferRays {
    /// The Cholesky factor of the footprint's unresolved driver-gradient covariance.
    chol: (f64, f64, f64),
    o: RayMasking,
    i: Option<RayMasking>,
    k: f64,
    /// The footprint's driver mean and deviation, in global σ.
    mean: f64,
    std: f64,
    far: f64,
}

/// Gauss–Hermite nodes (along the eye's projection, across it) of
/// [`TransferRays::visibility_moments`]: 6 × 3 is as good as the 64-node polar rule on #17's
/// grid (terraces 2.01% / 1.98%, sponge 0.23% / 12.67%, moss 0 / 0), 8 × 4 and 12 × 6 no better.
pub const MOMENT_NODES: (usize, usize) = (6, 3);

/// The moments of a visibility weight g over the footprint's whitened driver slopes
/// `z ~ N(0, I)`: `E[g]`, `E[z g]`, `E[z zᵀ g]` ([`TransferRays::visibility_moments`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityMoments {
    /// `E[g]`.
    pub mass: f64,
    /// `E[z g]`.
    pub first: DVec2,
    /// `E[z zᵀ g]`.
    pub second: glam::DMat2,
}

impl VisibilityMoments {
    /// The weight as a reweighting of the slopes' Gaussian: `(E[g], μ, C)` with the tilted
    /// Gaussian `N(μ, C)`, `μ = E[z g]/E[g]`, `C = E[z zᵀ g]/E[g] − μμᵀ` (clamped to be positive
    /// semi-definite). `None` where nothing is visible.
    pub fn tilted(&self) -> Option<(f64, DVec2, glam::DMat2)> {
        if !(self.mass > 1e-12) {
            return None;
        }
        let mu = self.first / self.mass;
        let c = self.second * (1.0 / self.mass) - glam::DMat2::from_cols(mu * mu.x, mu * mu.y);
        let (xx, yy) = (c.x_axis.x.max(0.0), c.y_axis.y.max(0.0));
        let xy = (0.5 * (c.x_axis.y + c.y_axis.x)).clamp(-(xx * yy).sqrt(), (xx * yy).sqrt());
        Some((
            self.mass,
            mu,
            glam::DMat2::from_cols(DVec2::new(xx, xy), DVec2::new(xy, yy)),
        ))
    }
}

impl TransferRays {
    /// For the footprint's driver `d`, `wo` and `wi` in the frame of its mean normal, the light
    /// up or not, σ_h and the material's correlation.
    pub fn new(
        table: &TransferMaskingTable,
        d: crate::driver::footprint::FilteredDriver,
        (wo, wi): (glam::DVec3, glam::DVec3),
        sun_lit: bool,
        sigma_h: f64,
        correlation: crate::microfacet::masking_shadowing::Correlation,
    ) -> Self {
        use crate::microfacet::masking_shadowing::{
            Correlation, azimuth_difference, azimuth_factor,
        };
        let c = d.gradient_cov;
        let (l11, l21, l22) = cholesky(c.xx, c.xy, c.yy);
        let ray = |w: glam::DVec3| {
            let r = w.x.hypot(w.y);
            let dir = if r > 0.0 {
                DVec2::new(w.x / r, w.y / r)
            } else {
                DVec2::X
            };
            let st = table.slope_sigma(dir).max(1e-300);
            let nu = if r > 0.0 {
                w.z.max(0.0) / r / (sigma_h.max(1e-300) * st)
            } else {
                f64::INFINITY
            };
            RayMasking {
                entry: table.lookup(dir, nu),
                nu,
                projection: DVec2::new(dir.x * l11 + dir.y * l21, dir.y * l22) / st,
            }
        };
        let k = match correlation {
            Correlation::Uncorrelated => 1.0,
            Correlation::HeightDirection => azimuth_factor(azimuth_difference(wo, wi)),
        };
        let sf = table.sigma_f.max(1e-300);
        Self {
            chol: (l11, l21, l22),
            o: ray(wo),
            i: sun_lit.then(|| ray(wi)),
            k,
            mean: d.mean / sf,
            std: d.std / sf,
            far: far_weight(d.std, table.sigma_f),
        }
    }

    /// `(G1o, G2)` of one start at driver value `x` (global σ) whose driver gradient is the
    /// footprint's Gaussian at the standard node `z` (`∇f = L z`, L the Cholesky factor of its
    /// unresolved gradient covariance): the conditioned masking along ωo, and the joint
    /// masking–shadowing combined as in [`bin_visibility`] (0 with the sun down).
    pub fn node_visibility(&self, x: f64, z: DVec2) -> (f64, f64) {
        let go = entry_at(&self.o.entry, x, self.o.projection.dot(z)).exp();
        let g2 = self.i.as_ref().map_or(0.0, |i| {
            let gi = entry_at(&i.entry, x, i.projection.dot(z)).exp();
            let (lo, hi) = if go <= gi { (go, gi) } else { (gi, go) };
            lo * hi.powf(self.k)
        });
        (go, g2)
    }

    /// The moments of G1 along ωo and of the joint G2 of a start at driver value `x` over the
    /// footprint's driver slopes: the visibility as a reweighting of the slopes' Gaussian, which
    /// the bins then shade as any Gaussian (docs/design.md, "The visibility as a Gaussian
    /// reweighting"). On a Gauss–Hermite product rule aligned with the eye's projection
    /// ([`MOMENT_NODES`]): G1 along ωo depends on the slope only through it, so it is read at the
    /// along-nodes alone (6 reads of the table instead of 64 on the polar rule, the light's 18;
    /// #17's grid moves by at most 1% against the 64-node polar rule).
    pub fn visibility_moments(&self, x: f64) -> [VisibilityMoments; 2] {
        let zero = VisibilityMoments {
            mass: 0.0,
            first: DVec2::ZERO,
            second: glam::DMat2::ZERO,
        };
        let mut out = [zero; 2];
        let p = self.o.projection;
        let (e1, e2) = if p.length() > 1e-12 {
            let e = p.normalize();
            (e, e.perp())
        } else {
            (DVec2::X, DVec2::Y)
        };
        let (az, aw) = gauss_hermite_normal(MOMENT_NODES.0);
        let (bz, bw) = gauss_hermite_normal(MOMENT_NODES.1);
        for (a, wa) in az.iter().zip(&aw) {
            let go = entry_at(&self.o.entry, x, p.length() * a).exp();
            for (b, wb) in bz.iter().zip(&bw) {
                let z = e1 * *a + e2 * *b;
                let g2 = self.i.as_ref().map_or(0.0, |i| {
                    let gi = entry_at(&i.entry, x, i.projection.dot(z)).exp();
                    let (lo, hi) = if go <= gi { (go, gi) } else { (gi, go) };
                    lo * hi.powf(self.k)
                });
                for (m, g) in out.iter_mut().zip([go, g2]) {
                    let wg = wa * wb * g;
                    m.mass += wg;
                    m.first += z * wg;
                    m.second += glam::DMat2::from_cols(z * z.x, z * z.y) * wg;
                }
            }
        }
        out
    }

    /// The footprint's unresolved driver-gradient Cholesky factor as a matrix (`z ↦ L z`,
    /// [`TransferRays::gradient_at`]).
    pub fn gradient_factor(&self) -> glam::DMat2 {
        glam::DMat2::from_cols(self.gradient_at(DVec2::X), self.gradient_at(DVec2::Y))
    }

    /// The driver gradient `L z` of the standard node `z` (L the Cholesky factor of the
    /// footprint's unresolved driver-gradient covariance).
    pub fn gradient_at(&self, z: DVec2) -> DVec2 {
        let (l11, l21, l22) = self.chol;
        DVec2::new(l11 * z.x, l21 * z.x + l22 * z.y)
    }

    /// [`TransferRays::node_visibility`] of a start whose driver gradient is `grad` (driver
    /// units; a direction the footprint's gradient has no spread in reads its mean, 0).
    pub fn gradient_visibility(&self, x: f64, grad: DVec2) -> (f64, f64) {
        let (l11, l21, l22) = self.chol;
        let z1 = if l11 > 0.0 { grad.x / l11 } else { 0.0 };
        let z2 = if l22 > 0.0 {
            (grad.y - l21 * z1) / l22
        } else {
            0.0
        };
        self.node_visibility(x, DVec2::new(z1, z2))
    }

    /// The share of the footprint's driver variance it leaves unresolved ([`far_weight`]).
    pub fn far(&self) -> f64 {
        self.far
    }

    /// The driver value (global σ) at quantile `u` of the footprint.
    pub fn value_at(&self, u: f64) -> f64 {
        self.mean + self.std * crate::math::special::norm_quantile(u)
    }

    /// `(V̂o, V̂2)` of [`bin_visibility`] at driver value `x` (global σ) with `G′ = slope`.
    pub fn visibility_at(&self, x: f64, slope: f64) -> Option<(f64, f64)> {
        bin_visibility(&self.o, self.i.as_ref(), x, slope, self.k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::test_materials::preset;

    fn terraces_table() -> (crate::material::Material, Arc<TransferMaskingTable>) {
        let m = preset("terraces");
        let t = TransferMaskingTable::shared(&m.noise().expect("noise"), &m.heights.transfer)
            .expect("a table");
        (m, t)
    }

    /// At an azimuth node and a ν node the lookup is the direct conditioned masking at every
    /// (value, slope) node (the layout, the stored logarithm and its f32 round trip), back faces
    /// hold the last front value, and nothing is NaN between or beyond the nodes.
    #[test]
    fn the_lookup_at_nodes_is_the_direct_masking() {
        let (m, table) = terraces_table();
        let noise = m.noise().expect("noise");
        let barrier = TransferBarrier::new(&m.heights.transfer, table.sigma_f);
        for (a, j) in [(0usize, 3usize), (3, 8), (6, 11)] {
            let dir = DVec2::from_angle(PI * a as f64 / TABLE_AZIMUTHS as f64);
            let nu = NU_MIN * NU_RATIO.powi(j as i32);
            let process = LineProcess::new(
                noise
                    .waves
                    .iter()
                    .map(|w| (0.5 * w.amplitude * w.amplitude, TAU * w.k.dot(dir))),
            )
            .expect("a process");
            let grid = ProcessGrid::new(&process, NU_MIN);
            let entry = table.lookup(dir, nu);
            let mut checked = 0;
            for i in (0..VALUE_NODES).step_by(3) {
                for s in 0..SLOPE_NODES {
                    let (x, t) = (value_node(i), slope_node(s));
                    let got = entry[i * SLOPE_NODES + s];
                    if barrier.back_face(x, t, nu) {
                        assert_eq!(got, entry[i * SLOPE_NODES + s - 1], "({x}, {t})");
                        continue;
                    }
                    let want = barrier_log_g1(&grid, &barrier, x, t, nu).max(-MAX_LOG_G1);
                    let tol = 1e-4 * (1.0 + want.abs()) + MIN_EXPONENT;
                    assert!(
                        (got - want).abs() <= tol,
                        "({x}, {t}), ν {nu}: {got} vs {want}"
                    );
                    checked += 1;
                }
            }
            assert!(checked > 50, "{checked}");
        }
        for dir in [DVec2::new(f64::NAN, 0.0), DVec2::new(0.3, -0.95)] {
            for nu in [f64::NAN, -1.0, 0.0, 1e-9, 0.77, 1e9, f64::INFINITY] {
                let e = table.lookup(dir, nu);
                assert!(e.iter().all(|v| v.is_finite() && *v <= 0.0), "{dir} {nu}");
                assert!(entry_at(&e, f64::NAN, 0.3).is_finite());
            }
        }
    }

    /// With no masking (ln G1 ≡ 0) every value is seen and lit; with G1 falling as the driver
    /// rises toward the ray, the joint term of a light opposite the eye is below the product of
    /// the two means (one slope makes a start hard to see and easy to light: Chebyshev's
    /// inequality for a decreasing and an increasing function of t), and along the eye it is
    /// above it; a sun below the horizon lights nothing.
    #[test]
    fn the_bin_visibility_follows_the_hidden_slope() {
        let ray = |entry: [f64; TRANSFER_ENTRY], p: DVec2| RayMasking {
            entry,
            nu: 1.0,
            projection: p,
        };
        let flat = ray([0.0; TRANSFER_ENTRY], DVec2::X);
        assert_eq!(
            bin_visibility(&flat, Some(&flat), 0.3, 0.0, 1.0),
            Some((1.0, 1.0))
        );
        let mut falling = [0.0; TRANSFER_ENTRY];
        for i in 0..VALUE_NODES {
            for s in 0..SLOPE_NODES {
                falling[i * SLOPE_NODES + s] = -0.4 * (slope_node(s) + 4.0);
            }
        }
        let o = ray(falling, DVec2::X);
        let (vo, _) = bin_visibility(&o, None, 0.0, 0.0, 1.0).expect("front faces");
        assert!(vo > 0.0 && vo < 1.0, "{vo}");
        let opposite = ray(falling, -DVec2::X);
        let (_, v_opp) = bin_visibility(&o, Some(&opposite), 0.0, 0.0, 1.0).expect("lit");
        let (_, v_same) = bin_visibility(&o, Some(&o), 0.0, 0.0, 1.0).expect("lit");
        assert!(v_opp < 0.95 * vo * vo, "{v_opp} vs {}", vo * vo);
        assert!(v_same > 1.05 * vo * vo, "{v_same} vs {}", vo * vo);
        // A flat tread (G′ = 0) weighs every slope alike; no node faces the eye → None.
        assert!(bin_visibility(&o, None, 0.0, 1e6, 1.0).is_some());
        let steep = RayMasking {
            projection: DVec2::ZERO,
            nu: 1e-9,
            ..o.clone()
        };
        assert!(bin_visibility(&steep, None, 0.0, 1.0, 1.0).is_some());
        assert_eq!(far_weight(1.0, 1.0), 1.0);
        assert_eq!(far_weight(0.5, 1.0), 0.25);
        assert_eq!(far_weight(f64::NAN, 1.0), 0.0);
        assert_eq!(far_weight(3.0, 0.0), 0.0);
    }

    /// A reweighting's tilted Gaussian: `E[g] = 2`, `E[z g] = (2, 0)`, `E[z zᵀ g] = diag(4, 2)`
    /// is twice N((1, 0), I); an impossible second moment is clamped to a degenerate Gaussian;
    /// nothing visible is `None`.
    #[test]
    fn visibility_moments_tilt_the_gaussian() {
        let m = VisibilityMoments {
            mass: 2.0,
            first: DVec2::new(2.0, 0.0),
            second: glam::DMat2::from_cols(DVec2::new(4.0, 0.0), DVec2::new(0.0, 2.0)),
        };
        let (m0, mu, c) = m.tilted().expect("visible");
        assert_eq!(m0, 2.0);
        assert!((mu - DVec2::new(1.0, 0.0)).length() < 1e-12);
        assert!((c - glam::DMat2::IDENTITY).abs_diff_eq(glam::DMat2::ZERO, 1e-12));
        let bad = VisibilityMoments {
            second: glam::DMat2::ZERO,
            ..m
        };
        let (_, _, c) = bad.tilted().expect("visible");
        assert!(c.x_axis.x >= 0.0 && c.y_axis.y >= 0.0 && c.determinant() >= -1e-12);
        let none = VisibilityMoments { mass: 0.0, ..m };
        assert!(none.tilted().is_none());
    }

    /// The filtered view with the conditioned bins: at the normal, where nothing is masked or
    /// shadowed, it is the per-value mixture (each sub-value's g′), at least as close to it as
    /// Smith's bins; everywhere else finite and non-negative, grazing and below the horizon
    /// included.
    #[test]
    fn the_conditioned_bins_are_smiths_where_nothing_is_masked() {
        use crate::eval::{Evaluator, FootprintQuery};
        use crate::scene::direction::direction;
        for name in ["terraces", "sponge"] {
            let m = preset(name);
            let smith = Evaluator::new(&m).expect("prepared");
            let mut own = smith.clone();
            own.transfer_masking =
                TransferMaskingTable::shared(&m.noise().expect("noise"), &m.heights.transfer);
            let at = |e: &Evaluator, v: f64, l: f64, az: f64| {
                let cfg = FootprintQuery::far(
                    e,
                    direction(v.to_radians(), 0.0),
                    direction(l.to_radians(), az.to_radians()),
                );
                e.filtered(&cfg)
            };
            let (a, b) = (at(&smith, 0.0, 0.0, 0.0), at(&own, 0.0, 0.0, 0.0));
            // At the normal nothing is masked: what differs is the slope scale, each sub-value's
            // own g′ instead of the bin's root mean square, which the 241-node mixture (every
            // value its own g′) evaluates exactly; measured 0.55% from it on terraces, Smith's
            // bins 1.2%.
            let cfg = FootprintQuery::far(&own, glam::DVec3::Z, glam::DVec3::Z);
            let x = own.filtered_mixture(&cfg).expect("mixture");
            for k in 0..3 {
                assert!((b[k] - x[k]).abs() <= 8e-3 * x[k], "{name}: {b:?} vs {x:?}");
                assert!(
                    (b[k] - x[k]).abs() <= (a[k] - x[k]).abs() + 1e-3 * x[k],
                    "{name}: {b:?} vs {x:?}, Smith's bins {a:?}"
                );
            }
            // Shadowing moves it: the light at 60° opposite the eye at 60°.
            let (a, b) = (at(&smith, 60.0, 60.0, 180.0), at(&own, 60.0, 60.0, 180.0));
            if name == "terraces" {
                assert!(b[0] < 0.95 * a[0], "{a:?} vs {b:?}");
            }
            for v in [0.0, 45.0, 85.0, 89.5] {
                for (l, az) in [(0.0, 0.0), (60.0, 180.0), (89.9, 0.0), (120.0, 90.0)] {
                    let r = at(&own, v, l, az);
                    assert!(
                        r.iter().all(|c| c.is_finite() && *c >= 0.0),
                        "{v} {l} {az}: {r:?}"
                    );
                }
            }
        }
    }
}
