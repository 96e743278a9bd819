//! A transfer-curve material's table of masking conditioned on the driver's value and slope
//! ([`crate::microfacet::barrier_masking`], #17), and what the transfer mixture's bins take from it
//! ([`TransferRays`]).
//!
//! Entry: `ln G1(x_i, t_j)` at [`VALUE_NODES`] driver values `x_i` ([`value_node`], in the
//! driver's global σ) × [`SLOPE_NODES`] driver slopes along the ray `t_j` ([`slope_node`], in the
//! driver's global slope σ along the ray's azimuth), clamped to `[−MAX_LOG_G1, 0]`; back faces
//! hold the last front value (the clamped cosine and the projected area take them out).
//! Axes as [`crate::eval::masking::slope_masking_table`]'s, without its footprint levels: the ray's
//! azimuth ([`TABLE_AZIMUTHS`] over [0, π)) and `ν = μ/(σ_h σ_t)` ([`TABLE_NUS`] nodes, linear in
//! ln ν). The process is the driver's whole (far field): the barrier is the curve at the
//! driver's absolute value, which a footprint's unresolved part alone does not know, so the
//! bins blend toward Smith's as the footprint resolves the driver ([`far_weight`]).
//!
//! The bins read the entries' Gaussian moments ([`crate::eval::masking::transfer_moments`], built with the
//! table) rather than the entries: [`crate::eval::Evaluator::new`] builds both when the material
//! asks for conditioned masking under a transfer curve, and the views upload the moments
//! (docs/design/transfer-curves.md, "Masking that knows the driver's slope", has the grid).

use crate::driver::noise::SumOfSines;
use crate::eval::masking::slope_masking_table::{
    NU_MIN, NU_RATIO, TABLE_AZIMUTHS, TABLE_NUS, azimuth_coordinate, nu_coordinate,
};
use crate::eval::masking::transfer_moments;
use crate::math::gaussian::cholesky;
use crate::math::gaussian_weight::GaussianWeight;
use crate::math::quadrature::gauss_hermite_normal;
use crate::microfacet::barrier_masking::{TransferBarrier, barrier_log_g1};
use crate::microfacet::slope_masking::{LineProcess, ProcessGrid};
use crate::microfacet::transfer::TransferFunction;
use glam::DVec2;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::sync::{Arc, Mutex};

/// Driver values of an entry: `−4 + VALUE_STEP·i` (σ units).
pub const VALUE_NODES: usize = 32;
/// Step of the value nodes (σ units): 0.5 smeared a tread's masking across the riser next to
/// it (terraces, 16% off between nodes; docs/design/transfer-curves.md).
pub const VALUE_STEP: f64 = 0.25;
/// Driver slopes of an entry: `−4 + SLOPE_STEP·j` (σ units).
pub const SLOPE_NODES: usize = 17;
/// Step of the slope nodes (σ units): over a tread `ln G1` falls ever faster as the driver rises
/// toward the ray, and a chord across 1σ came out several percent dark (terraces).
pub const SLOPE_STEP: f64 = 0.5;
/// f32 values per entry, value-major.
pub const TRANSFER_ENTRY: usize = VALUE_NODES * SLOPE_NODES;
/// f32 values per entry of the moments ([`transfer_moments`]): value-major, then the projection
/// length, then the three moments.
pub const MOMENT_ENTRY: usize = VALUE_NODES * transfer_moments::LENGTH_NODES * 3;

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
    /// The entries' Gaussian moments ([`crate::eval::masking::transfer_moments`]): [`MOMENT_ENTRY`]
    /// values per (azimuth, ν), ν fastest.
    pub moments: Vec<f32>,
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
        let data = rows.concat();
        let moments = data
            .par_chunks(TRANSFER_ENTRY)
            .flat_map_iter(|e| {
                let entry: Vec<f64> = e.iter().map(|q| -f64::from(*q).exp()).collect();
                let knots: Vec<f64> = (0..SLOPE_NODES).map(slope_node).collect();
                transfer_moments::entry_moments(&entry, &knots)
            })
            .collect();
        Some(Self {
            sigma_f,
            gradient,
            data,
            moments,
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

    /// The moment block ([`MOMENT_ENTRY`] values) of a ray of horizontal
    /// direction `dir` and slope `nu`: the entries' moments, linear in the azimuth and ln ν
    /// with [`TransferMaskingTable::lookup`]'s weights.
    pub fn moment_lookup(&self, dir: DVec2, nu: f64) -> Vec<f64> {
        let (a0, a1, fa) = azimuth_coordinate(dir);
        let (n0, fnu) = nu_coordinate(nu);
        let size = MOMENT_ENTRY;
        let mut acc = vec![0.0f64; size];
        for (a, wa) in [(a0, 1.0 - fa), (a1, fa)] {
            for (n, wn) in [(n0, 1.0 - fnu), (n0 + 1, fnu)] {
                let w = wa * wn;
                if w == 0.0 {
                    continue;
                }
                let base = (a * TABLE_NUS + n) * size;
                for (o, v) in acc.iter_mut().zip(&self.moments[base..base + size]) {
                    *o += w * f64::from(*v);
                }
            }
        }
        acc
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
/// tread); 9 is within 0.04–0.07, as a 33 × 33 grid (docs/design/transfer-curves.md).
pub const RULE_POINTS: usize = 9;

/// What one ray needs of the table: its entry and the projections of the driver's whitened
/// gradient on its azimuth in σ units.
#[derive(Clone, Debug, PartialEq)]
pub struct RayMasking {
    /// The looked-up entry.
    pub entry: [f64; TRANSFER_ENTRY],
    /// The ray's moment block ([`TransferMaskingTable::moment_lookup`]; empty where only
    /// the entry is used).
    pub moments: Vec<f64>,
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
    /// The driver's global σ (the table's unit).
    sigma_f: f64,
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
                moments: table.moment_lookup(dir, nu),
                nu,
                projection: DVec2::new(dir.x * l11 + dir.y * l21, dir.y * l22) / st,
            }
        };
        let k = match correlation {
            Correlation::Uncorrelated => 1.0,
            Correlation::HeightDirection => azimuth_factor(azimuth_difference(wo, wi)),
        };
        let sf = table.sigma_f.max(1e-300);
        let (o, i) = (ray(wo), sun_lit.then(|| ray(wi)));
        // A ray flatter than the table's first ν node is outside it (clamped there, the bins
        // came out 24% dark at 89° on moss): Smith's bins take it.
        let inside = o.nu >= NU_MIN && i.as_ref().is_none_or(|i| i.nu >= NU_MIN);
        Self {
            chol: (l11, l21, l22),
            o,
            i,
            k,
            mean: d.mean / sf,
            std: d.std / sf,
            far: if inside {
                far_weight(d.std, table.sigma_f)
            } else {
                0.0
            },
            sigma_f: sf,
        }
    }

    /// The conditioned `G1` of one ray (the light's when `light`) at driver value `x` (global σ)
    /// over the footprint's whitened driver slopes `z ~ N(0, I)`, as a Gaussian function of z
    /// ([`GaussianWeight::along`]). It depends on z only through its projection `t = len·a`, so
    /// its moments are 1-D: the table's ([`crate::eval::masking::transfer_moments`], exact at its nodes,
    /// bilinear in the value and the projection's length between them). `None` with the sun down
    /// or nothing visible.
    pub fn ray_weight(&self, x: f64, light: bool) -> Option<GaussianWeight> {
        let r = if light { self.i.as_ref()? } else { &self.o };
        let len = r.projection.length();
        let e = if len > 1e-12 {
            r.projection / len
        } else {
            DVec2::X
        };
        let [m0, m1, m2] = transfer_moments::moments_at(&r.moments, value_cell(x), len);
        GaussianWeight::along(e, m0, m1, m2)
    }

    /// The conditioned visibility of a start at driver value `x` (global σ) over the footprint's
    /// driver slopes, `[G1 along ωo, joint masking–shadowing]`, each a Gaussian function of the
    /// whitened slopes z: a reweighting of the slopes' Gaussian that the bins shade as any
    /// Gaussian (docs/design/transfer-curves.md, "The visibility as a Gaussian reweighting"). The joint term
    /// combines the two rays' own weights as [`bin_visibility`] combines their `G1`: the more
    /// masked one (the smaller mass) times the other to the power `k`, multiplied in closed form
    /// (on #17's grid within 0.15% of a 6 × 3 rule over both projections). Where that product has no Gaussian (it rises faster than the
    /// slopes' Gaussian falls) the two are taken as independent: the masses multiplied, the
    /// more masked one's tilt.
    pub fn visibility_weights(&self, x: f64) -> [Option<GaussianWeight>; 2] {
        let o = self.ray_weight(x, false);
        let joint = o.zip(self.ray_weight(x, true)).map(|(o, i)| {
            let mass = |w: &GaussianWeight| w.tilted().map_or(0.0, |t| t.0);
            let (lo, hi) = if mass(&o) <= mass(&i) { (o, i) } else { (i, o) };
            let joint = lo * hi.powf(self.k);
            if joint.tilted().is_some() {
                joint
            } else {
                GaussianWeight {
                    log_scale: lo.log_scale + self.k * mass(&hi).max(1e-300).ln(),
                    ..lo
                }
            }
        });
        [o, joint]
    }

    /// The footprint's unresolved driver-gradient Cholesky factor as a matrix (`z ↦ L z`).
    pub fn gradient_factor(&self) -> glam::DMat2 {
        let (l11, l21, l22) = self.chol;
        glam::DMat2::from_cols(DVec2::new(l11, l21), DVec2::new(0.0, l22))
    }

    /// `L⁻¹`, the whitening of a driver gradient (`z = L⁻¹ ∇f`), `None` where the footprint's
    /// gradient has no spread in some direction.
    pub fn whitening(&self) -> Option<glam::DMat2> {
        let (l11, _, l22) = self.chol;
        (l11 > 1e-12 && l22 > 1e-12).then(|| self.gradient_factor().inverse())
    }

    /// The share of the footprint's driver variance it leaves unresolved ([`far_weight`]).
    pub fn far(&self) -> f64 {
        self.far
    }

    /// The driver value (global σ) at quantile `u` of the footprint.
    pub fn value_at(&self, u: f64) -> f64 {
        self.mean + self.std * crate::math::special::norm_quantile(u)
    }

    /// The driver value (driver units, what the transfer curve takes) of `x` in global σ.
    pub fn driver_value(&self, x: f64) -> f64 {
        x * self.sigma_f
    }

    /// `(V̂o, V̂2)` of [`bin_visibility`] at driver value `x` (global σ) with `G′ = slope`.
    pub fn visibility_at(&self, x: f64, slope: f64) -> Option<(f64, f64)> {
        bin_visibility(&self.o, self.i.as_ref(), x, slope, self.k)
    }
}

#[cfg(test)]
mod tests;
