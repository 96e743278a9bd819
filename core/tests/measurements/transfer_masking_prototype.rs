//! A prototype of #17's transfer-curve masking conditioned on the driver's value and slope,
//! checked against the explicit surface (`#[ignore]`d measurements: `cargo test --release -p
//! lodestone-core -- --ignored --nocapture transfer_conditioned_masking_prototype`; the views'
//! form is [`lodestone_core::eval::masking::transfer_masking_table`]).

use crate::evaluation::traced_point;
use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::fixtures::preset;
use lodestone_core::scene::direction::direction;

/// Masking under a transfer curve, conditioned on the start's driver value f₀ and its slope t
/// along the ray's azimuth: the prototype of [`lodestone_core::microfacet::slope_masking`] with the ray
/// made a barrier in the driver's space. Along a horizontal direction the driver is a stationary
/// Gaussian process of autocovariance `R(τ) = Σ ½a_i² cos(ω_i τ)` (f, not h: the transfer is not
/// linear); the ray `h₀ + μs` (μ = cot θ) meets the surface `σ_h g(f)` where f crosses
/// `b(s) = g⁻¹((h₀ + μs)/σ_h)`, whose slope is `μ/(σ_h g′(b))` (steep over a tread, where the
/// ray climbs past a flat run of heights in no f at all). Rice's rate with Smith's "below so far",
/// `E[(f′ − b′)⁺ | f = b]·p(f = b)/P(f < b)`, the pair (f, f′) at s conditioned on (f₀, t).
/// Returns G1 on a grid of (f₀, t) for one direction; `t ≥ b′(0)` is a back face (0).
struct BarrierMasking {
    f0: Vec<f64>,
    t: Vec<f64>,
    g1: Vec<f64>,
}

impl BarrierMasking {
    fn new(m: &lodestone_core::material::Material, dir: glam::DVec2, mu: f64) -> Self {
        use lodestone_core::math::special::{norm_cdf, norm_pdf};
        use std::f64::consts::PI;
        let noise = m.noise().expect("a noise driver");
        let sh = m.heights.sigma_h;
        let g = &m.heights.transfer;
        let waves: Vec<(f64, f64)> = noise
            .waves
            .iter()
            .map(|w| (0.5 * w.amplitude * w.amplitude, 2.0 * PI * w.k.dot(dir)))
            .collect();
        let r0: f64 = waves.iter().map(|(c, _)| c).sum();
        let l2: f64 = waves.iter().map(|(c, w)| c * w * w).sum();
        // g on a fine grid of f for its inverse (non-decreasing).
        const GN: usize = 16001;
        let gf = |k: usize| -8.0 + 16.0 * k as f64 / (GN - 1) as f64;
        let gv: Vec<f64> = (0..GN).map(|k| g.eval(gf(k))).collect();
        let inverse = |y: f64| -> Option<f64> {
            if y > gv[GN - 1] {
                return None;
            }
            let k = gv.partition_point(|v| *v < y);
            if k == 0 {
                return Some(gf(0));
            }
            let (a, b) = (gv[k - 1], gv[k]);
            let w = if b > a { (y - a) / (b - a) } else { 1.0 };
            Some(gf(k - 1) + w * (gf(k) - gf(k - 1)))
        };
        let w_max = waves.iter().map(|(_, w)| w.abs()).fold(0.0, f64::max);
        let ds = (0.25 / w_max.max(1e-9)).min(0.05 * (r0 / l2).sqrt());
        let span = 2.5 * sh * (gv[GN - 1] - gv[0]) / mu.max(1e-6);
        let steps = ((span / ds).ceil() as usize).min(20_000);
        let ds = span / steps as f64;
        let grid: Vec<(f64, f64, f64)> = (0..steps)
            .map(|i| {
                let s = (i as f64 + 0.5) * ds;
                waves.iter().fold((0.0, 0.0, 0.0), |(a, b, c), (cw, w)| {
                    let (sn, cs) = (w * s).sin_cos();
                    (a + cw * cs, b - cw * w * sn, c - cw * w * w * cs)
                })
            })
            .collect();
        let (sf, st) = (r0.sqrt(), l2.sqrt());
        let f0: Vec<f64> = (0..141).map(|i| sf * (-3.5 + 0.05 * i as f64)).collect();
        let t: Vec<f64> = (0..41).map(|j| st * (-4.0 + 0.2 * j as f64)).collect();
        let mut g1 = Vec::with_capacity(f0.len() * t.len());
        for &x0 in &f0 {
            let h0 = g.eval(x0);
            let slope0 = mu / (sh * g.derivative(x0)).max(1e-300);
            for &t0 in &t {
                if t0 >= slope0 {
                    g1.push(0.0);
                    continue;
                }
                let mut integral = 0.0;
                for (i, &(r, r1, r2)) in grid.iter().enumerate() {
                    let s = (i as f64 + 0.5) * ds;
                    let Some(b) = inverse(h0 + mu * s / sh) else {
                        break;
                    };
                    let bd = mu / (sh * g.derivative(b)).max(1e-300);
                    let mh = r * x0 / r0 - r1 * t0 / l2;
                    let mp = r1 * x0 / r0 - r2 * t0 / l2;
                    let vh = (r0 - r * r / r0 - r1 * r1 / l2).max(1e-12 * r0);
                    let vp = l2 - r1 * r1 / r0 - r2 * r2 / l2;
                    let c = -(r * r1) / r0 - r1 * r2 / l2;
                    let z = (b - mh) / vh.sqrt();
                    let below = norm_cdf(z);
                    if below < 1e-300 {
                        integral = f64::INFINITY;
                        break;
                    }
                    let m2 = mp + c / vh * (b - mh);
                    let s2 = (vp - c * c / vh).max(1e-12 * l2).sqrt();
                    let q = (m2 - bd) / s2;
                    let up = s2 * norm_pdf(q) + (m2 - bd) * norm_cdf(q);
                    integral += up * norm_pdf(z) / vh.sqrt() / below * ds;
                    if integral > 700.0 {
                        break;
                    }
                }
                g1.push((-integral).exp());
            }
        }
        Self { f0, t, g1 }
    }

    /// G1 at (f₀, t), bilinear on the grid (clamped).
    fn at(&self, f0: f64, t: f64) -> f64 {
        let cell = |v: &[f64], x: f64| {
            let x = (x - v[0]) / (v[1] - v[0]);
            let x = x.clamp(0.0, (v.len() - 1) as f64 - 1e-9);
            let i = x as usize;
            (i, x - i as f64)
        };
        let (i, fi) = cell(&self.f0, f0);
        let (j, fj) = cell(&self.t, t);
        let n = self.t.len();
        let v = |i: usize, j: usize| self.g1[i * n + j];
        (v(i, j) * (1.0 - fj) + v(i, j + 1) * fj) * (1.0 - fi)
            + (v(i + 1, j) * (1.0 - fj) + v(i + 1, j + 1) * fj) * fi
    }
}

/// The prototype above against the explicit surface: per point of the surface (as in
/// [`transfer_conditioned_visibility`]), P(seen) and P(clear toward the sun) from
/// [`BarrierMasking`] along the view's and the light's azimuths, taken independent given (f₀, t)
/// (the two rays leave the point on opposite sides when the light is opposite), against the traced
/// rays: on bins of the driver's value, and the radiance weighted by them (specular 0).
#[test]
#[ignore = "a measurement, prints a table"]
fn transfer_conditioned_masking_prototype() {
    let n_points = 200_000;
    for (name, view, light, az) in [
        ("terraces", 60.0, 60.0, 180.0),
        ("terraces", 85.0, 60.0, 180.0),
        ("terraces", 45.0, 60.0, 180.0),
        ("terraces", 1.0, 60.0, 180.0),
        ("sponge", 60.0, 60.0, 180.0),
    ] {
        let mut m = preset(name);
        m.brdf.specular = 0.0;
        let p = Evaluator::new(&m).expect("prepared");
        let wo = direction(f64::to_radians(view), 0.0);
        let wi = direction(f64::to_radians(light), f64::to_radians(az));
        let (d_o, d_i) = (
            glam::DVec2::new(wo.x, wo.y).normalize(),
            glam::DVec2::new(wi.x, wi.y).normalize(),
        );
        let masking = BarrierMasking::new(&m, d_o, wo.z / wo.x.hypot(wo.y));
        let shadowing = BarrierMasking::new(&m, d_i, wi.z / wi.x.hypot(wi.y));
        // The views' table at the same rays.
        let table =
            lodestone_core::eval::masking::transfer_masking_table::TransferMaskingTable::shared(
                &m.noise().expect("noise"),
                &m.heights.transfer,
            )
            .expect("table");
        let (st_o, st_i) = (table.slope_sigma(d_o), table.slope_sigma(d_i));
        let sh = m.heights.sigma_h;
        let entry_o = table.lookup(d_o, wo.z / wo.x.hypot(wo.y) / (sh * st_o));
        let entry_i = table.lookup(d_i, wi.z / wi.x.hypot(wi.y) / (sh * st_i));
        let sf = table.sigma_f;
        let from_table =
            |e: &[f64; lodestone_core::eval::masking::transfer_masking_table::TRANSFER_ENTRY],
             f: f64,
             t: f64| {
                lodestone_core::eval::masking::transfer_masking_table::entry_at(e, f / sf, t).exp()
            };
        // The views' bin formula at each point's value (the driver's slopes averaged out).
        let rays = lodestone_core::eval::masking::transfer_masking_table::TransferRays::new(
            &table,
            p.footprint_stats(&FootprintQuery::far(&p, wo, wi)).driver,
            (wo, wi),
            true,
            sh,
            m.filtering.correlation,
        );
        // Per bin: Σu·u_i, truth Σu·u_i·seen·clear, per-point model Σu·u_i·G1o·G1i, bin formula
        // Σu·u_i·V̂2 (the light's cosine weight u_i = ⟨n·ωi⟩⁺/n_z relative to flat).
        let mut joint = [[0.0f64; 4]; 8];
        let mut rng = 11u64;
        // Truth and model on 8 bins of f (step 0.5 from −2): Σu, Σu·seen, Σu·G1o, Σu (facing
        // the sun), Σu·clear, Σu·G1i; radiance sums: truth, model.
        let mut bins = [[0.0f64; 8]; 8];
        let (mut tl, mut tw, mut ml, mut mw) = ([0.0; 3], 0.0, [0.0; 3], 0.0);
        let (mut vl, mut vw) = ([0.0; 3], 0.0);
        let k_az = lodestone_core::microfacet::masking_shadowing::azimuth_factor(
            lodestone_core::microfacet::masking_shadowing::azimuth_difference(wo, wi),
        );
        for _ in 0..n_points {
            let Some(t) = traced_point(&p, wo, wi, &mut rng) else {
                continue;
            };
            let (f, gf, n, u) = (t.f, t.grad_f, t.normal, t.u);
            let (seen, faces, clear, l1, l0) = (t.seen, t.faces, t.clear, t.lit, t.unlit);
            let go = masking.at(f, gf.dot(d_o));
            let gi = if faces {
                shadowing.at(f, gf.dot(d_i))
            } else {
                0.0
            };
            let b = &mut bins[(((f + 2.0) / 0.5).max(0.0) as usize).min(7)];
            b[0] += u;
            b[1] += u * f64::from(u8::from(seen));
            b[2] += u * go;
            b[6] += u * from_table(&entry_o, f, gf.dot(d_o) / st_o);
            let ui = (n.dot(wi) / n.z / wi.z).max(0.0);
            let (_, v2) = rays
                .visibility_at(f / sf, m.heights.transfer.derivative(f))
                .unwrap_or((0.0, 0.0));
            let jb = &mut joint[(((f + 2.0) / 0.5).max(0.0) as usize).min(7)];
            jb[0] += u * ui;
            jb[1] += u * ui * f64::from(u8::from(seen && clear));
            jb[2] += u * ui * go * gi;
            jb[3] += u * ui * v2;
            if faces {
                b[3] += u;
                b[4] += u * f64::from(u8::from(clear));
                b[5] += u * gi;
                b[7] += u * from_table(&entry_i, f, gf.dot(d_i) / st_i);
            }
            // The views' form at the same point: the table's G1, combined as G2 combines Λs.
            let to = from_table(&entry_o, f, gf.dot(d_o) / st_o);
            let ti = if faces {
                from_table(&entry_i, f, gf.dot(d_i) / st_i)
            } else {
                0.0
            };
            let (lo, hi) = if to <= ti { (to, ti) } else { (ti, to) };
            let t2 = lo * hi.powf(k_az);
            for k in 0..3 {
                if seen {
                    tl[k] += u * if clear { l1[k] } else { l0[k] };
                }
                ml[k] += u * go * (gi * l1[k] + (1.0 - gi) * l0[k]);
                vl[k] += u * (t2 * l1[k] + (to - t2).max(0.0) * l0[k]);
            }
            vw += u * to;
            if seen {
                tw += u;
            }
            mw += u * go;
        }
        let err = (0..3)
            .map(|k| 100.0 * (ml[k] / mw - tl[k] / tw) / (tl[k] / tw))
            .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a });
        let err_table = (0..3)
            .map(|k| 100.0 * (vl[k] / vw - tl[k] / tw) / (tl[k] / tw))
            .fold(0.0f64, |a, e| if e.abs() > a.abs() { e } else { a });
        let cells: Vec<String> = bins
            .iter()
            .map(|b| {
                format!(
                    "{:.2}/{:.2}/{:.2} {:.2}/{:.2}/{:.2}",
                    b[1] / b[0].max(1e-300),
                    b[2] / b[0].max(1e-300),
                    b[6] / b[0].max(1e-300),
                    b[4] / b[3].max(1e-300),
                    b[5] / b[3].max(1e-300),
                    b[7] / b[3].max(1e-300)
                )
            })
            .collect();
        let jc: Vec<String> = joint
            .iter()
            .map(|j| {
                let n = j[0].max(1e-300);
                format!("{:.2}/{:.2}/{:.2}", j[1] / n, j[2] / n, j[3] / n)
            })
            .collect();
        eprintln!(
            "{name:9} view {view} light {light}/{az} (specular 0): conditioned model {err:+.2}% against the point truth\n    \
             by f in (−∞,−1.5) … (1.5,∞), step 0.5: P(seen) truth/model/table, P(clear | faces the sun) truth/model/table: {}",
            cells.join(" | ")
        );
        eprintln!(
            "    per point with the views' table and G2 combination: {err_table:+.2}% against the point truth"
        );
        eprintln!(
            "    seen and lit, cosine-weighted, truth/per point/bin formula: {}",
            jc.join(" | ")
        );
    }
}

/// The table's entries against [`BarrierMasking`] (the prototype, in the driver's own units) at a
/// few starts: the table's normalization and lookup.
#[test]
#[ignore = "a measurement, prints a table"]
fn transfer_table_against_the_prototype() {
    use lodestone_core::eval::masking::transfer_masking_table::{TransferMaskingTable, entry_at};
    let m = preset("terraces");
    let noise = m.noise().expect("noise");
    let table = TransferMaskingTable::new(&noise, &m.heights.transfer).expect("table");
    let sh = m.heights.sigma_h;
    for (view, az) in [(60.0, 0.0), (60.0, 180.0), (30.0, 180.0)] {
        let w = direction(f64::to_radians(view), f64::to_radians(az));
        let dir = glam::DVec2::new(w.x, w.y).normalize();
        let mu = w.z / w.x.hypot(w.y);
        let proto = BarrierMasking::new(&m, dir, mu);
        let st = table.slope_sigma(dir);
        let nu = mu / (sh * st);
        let entry = table.lookup(dir, nu);
        let sf = table.sigma_f;
        let mut row = vec![];
        for x in [-2.0, -1.25, -0.5, 0.0, 0.5, 1.25] {
            for t in [-2.0, 0.0, 1.0, 2.0] {
                row.push(format!(
                    "({x},{t}) {:.3}/{:.3}",
                    proto.at(sf * x, st * t),
                    entry_at(&entry, x, t).exp()
                ));
            }
        }
        eprintln!("{view}°/{az}° ν {nu:.3}: prototype/table {}", row.join(" "));
    }
}
