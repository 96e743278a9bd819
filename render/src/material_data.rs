//! A compiled material packed for the GPU: the data words every table, polynomial, wave and
//! image level occupies, and the parameters ([`MaterialParams`]) that say where each one is.
//! Only what the feature set reads is packed. The material itself is compiled once in core
//! ([`Evaluator`]); this only lays it out.

use crate::gpu_codes::{
    ColorCode, CombineCode, CorrelationCode, DriverCode, HeightFilterCode, MarchCode, TransferCode,
};
use crate::gpu_types::MaterialParams;
use glam::DVec2;
use lodestone_core::driver::field::{DriverField, TiledImage};
use lodestone_core::driver::noise::SumOfSines;
use lodestone_core::eval::Evaluator;
use lodestone_core::eval::compiled::CompiledTransfer;
use lodestone_core::eval::interception::Interception;
use lodestone_core::eval::mixture_bins::conditioned_slope_rule;
use lodestone_core::material::color_terms::CombineMode;
use lodestone_core::material::features::{Feature, FeatureSet};
use lodestone_core::material::{ColorModel, ColorSource};
use lodestone_core::math::piecewise::PiecewisePoly;
use lodestone_core::math::preconvolved::PreconvolvedTable;
use lodestone_core::microfacet::effective_height::{EffectiveHeightTable, HeightFilter};
use lodestone_core::microfacet::height_mixture::bin_slope_points;
use lodestone_core::microfacet::masking_shadowing::Correlation;
use lodestone_core::microfacet::slope_density::NoiseSlopes;
use lodestone_core::microfacet::slope_rule::SlopeRule;
use lodestone_core::microfacet::transfer::TransferFunction;
use lodestone_core::scene::bound_grid::BoundGrid;
use lodestone_core::scene::field_grid::{FIELD_MARGIN_F32, FieldGrid};
use lodestone_core::scene::march::March;
use std::f64::consts::TAU;

/// Offsets (in f32 units) of each table in the material's data buffer.
#[derive(Clone, Copy, Debug, Default)]
struct Layout {
    waves: u32,
    color_table: u32,
    transfer_table: u32,
    dh: u32,
    slope_rule: u32,
    color_poly: u32,
    transfer_poly: u32,
}

fn push_table(data: &mut Vec<f32>, t: &PreconvolvedTable) -> u32 {
    let off = data.len() as u32;
    data.extend(t.texels.iter().flatten());
    off
}

/// Knots, then per segment and channel 4 coefficients (degree ≤ 3), then left and right tails.
fn push_poly(data: &mut Vec<f32>, p: &PiecewisePoly, channels: &[usize]) -> u32 {
    let off = data.len() as u32;
    data.extend(p.knots.iter().map(|k| *k as f32));
    for seg in 0..p.segments() {
        for &ch in channels {
            let c = &p.coeffs[seg * p.channels + ch];
            data.extend(c[..4].iter().map(|v| *v as f32));
        }
    }
    data.extend(channels.iter().map(|&ch| p.left[ch] as f32));
    data.extend(channels.iter().map(|&ch| p.right[ch] as f32));
    off
}

/// The image pyramid: per level the value grid (f̄, f²‾) and the cell grid (f_x, f_y, f_x², f_y²,
/// f_x·f_y), then a level table of [`IMAGE_LEVEL_SLOTS`] slots per level (value offset, grad
/// offset, width, height as u32 bits; mean variance, Lipschitz constants along x and y per level-0
/// texel as f32). The target is folded into the texel origin in f64.
/// Slots per level in the image's level table (WGSL `IMAGE_LEVEL_SLOTS`).
pub const IMAGE_LEVEL_SLOTS: usize = 7;

fn push_image(
    data: &mut Vec<f32>,
    base: &mut MaterialParams,
    tiled: &TiledImage,
    target: [f64; 2],
) {
    let img = &tiled.image;
    let mut offsets = Vec::with_capacity(img.levels.len());
    for l in &img.levels {
        let v = data.len() as u32;
        data.extend(l.value.iter().flatten());
        let g = data.len() as u32;
        data.extend(l.grad.iter().flatten());
        offsets.push((v, g));
    }
    base.image_offset = data.len() as u32;
    for (l, (v, g)) in img.levels.iter().zip(offsets) {
        data.extend([
            f32::from_bits(v),
            f32::from_bits(g),
            f32::from_bits(l.width as u32),
            f32::from_bits(l.height as u32),
            l.mean_variance as f32,
            l.lipschitz.x as f32,
            l.lipschitz.y as f32,
        ]);
    }
    let scale = tiled.texels_per_unit();
    let (w, h) = img.size();
    base.driver_kind = DriverCode::Image.code();
    base.image_levels = img.levels.len() as u32;
    base.image_scale = scale as f32;
    base.image_u0 = (target[0] * scale).rem_euclid(w as f64) as f32;
    base.image_v0 = (target[1] * scale).rem_euclid(h as f64) as f32;
    base.image_lip_x = img.lipschitz.x as f32;
    base.image_lip_y = img.lipschitz.y as f32;
}

/// The material's data buffer and its parameters (WGSL `Params`), see [`material_data_for`]
/// (with every table the material has: what the all-features shader reads).
pub fn material_data(prepared: &Evaluator, target: [f64; 2]) -> (Vec<f32>, MaterialParams) {
    let d = material_data_for(prepared, target, FeatureSet::all());
    (d.data, d.params)
}

/// A material's GPU data, by part.
#[derive(Clone, Debug)]
pub struct MaterialData {
    /// The data buffer (f32 words).
    pub data: Vec<f32>,
    /// The material's parameters.
    pub params: MaterialParams,
    /// Bytes of each part present (waves, image pyramid, colour table, …).
    pub segments: Vec<(&'static str, usize)>,
}

/// The material's data buffer (waves, image pyramid, tables, D_h, quadrature rule, curve
/// polynomials, as f32) and its parameters (WGSL `Params`), with coordinates relative to
/// `target`: each wave's phase absorbs 2π k·target in f64, so f32 phases stay accurate anywhere
/// on the plane. Parts the material has but `features` does not use are left out: the D_h table
/// and the slope quadrature rule need [`Feature::Relief`] (the colour and transfer tables, the
/// image and the waves exist only for the materials that use them). Shared by the renderer and
/// the engine bundle ([`crate::export`]).
pub fn material_data_for(
    prepared: &Evaluator,
    target: [f64; 2],
    features: FeatureSet,
) -> MaterialData {
    let mut segments: Vec<(&'static str, usize)> = Vec::new();
    let mut mark = |data: &Vec<f32>, start: usize, name: &'static str| {
        if data.len() > start {
            segments.push((name, (data.len() - start) * 4));
        }
    };
    let m = &prepared.material;
    let s = &prepared.surface;
    let mut data: Vec<f32> = Vec::new();
    let mut lay = Layout {
        waves: 0,
        ..Layout::default()
    };
    let mut base = MaterialParams::default();
    let start = data.len();
    match &s.driver {
        DriverField::Noise(noise) => {
            for w in &noise.waves {
                let phase =
                    (w.phase + TAU * (w.k.x * target[0] + w.k.y * target[1])).rem_euclid(TAU);
                data.extend([w.k.x as f32, w.k.y as f32, w.amplitude as f32, phase as f32]);
            }
            base.wave_count = noise.waves.len() as u32;
            let ends = &s.levels;
            base.level_count = ends.len() as u32;
            base.level_ends = ends
                .iter()
                .take(ends.len().saturating_sub(1))
                .enumerate()
                .map(|(l, &e)| (e.min(255) as u32) << (8 * l))
                .sum();
        }
        DriverField::Image(tiled) => push_image(&mut data, &mut base, tiled, target),
    }
    mark(
        &data,
        start,
        match s.driver {
            DriverField::Noise(_) => "noise waves",
            DriverField::Image(_) => "image pyramid",
        },
    );
    if let Some(t) = prepared.color.table() {
        let start = data.len();
        lay.color_table = push_table(&mut data, t);
        mark(&data, start, "colour table");
        base.ct_size_m = t.size_m as u32;
        base.ct_size_s = t.size_sigma as u32;
        base.ct_m_min = t.m_min as f32;
        base.ct_m_max = t.m_max as f32;
        base.ct_sigma_max = t.sigma_max as f32;
    }
    if let Some(t) = prepared.color.gaussianize_table() {
        // The colour table is over the image histogram's Gaussian space: H maps (f̄, σ_f) there.
        let start = data.len();
        base.ht_offset = push_table(&mut data, t);
        mark(&data, start, "histogram table H");
        base.ht_size_m = t.size_m as u32;
        base.ht_size_s = t.size_sigma as u32;
        base.ht_m_min = t.m_min as f32;
        base.ht_m_max = t.m_max as f32;
        base.ht_sigma_max = t.sigma_max as f32;
    }
    if let Some(t) = prepared
        .image_slopes
        .as_ref()
        .filter(|_| features.contains(Feature::TransferMixture))
    {
        let start = data.len();
        base.is_offset = data.len() as u32;
        base.is_on = 1;
        data.extend(t.scale.iter().chain(&t.inverse).map(|v| *v as f32));
        mark(&data, start, "image's value-conditioned slopes and T⁻¹");
    }
    if let Some(t) = prepared.transfer.table() {
        let start = data.len();
        lay.transfer_table = push_table(&mut data, t);
        mark(&data, start, "transfer table");
        base.tt_size_m = t.size_m as u32;
        base.tt_size_s = t.size_sigma as u32;
        base.tt_m_min = t.m_min as f32;
        base.tt_m_max = t.m_max as f32;
        base.tt_sigma_max = t.sigma_max as f32;
    }
    if let CompiledTransfer::Curve { slopes, .. } = &prepared.transfer
        && features.contains(Feature::Relief)
    {
        let start = data.len();
        base.ts_offset = data.len() as u32;
        base.ts_p = slopes.p as u32;
        data.extend(&slopes.entries);
        mark(&data, start, "transfer table's slope pyramids");
    }
    let rule = m.slope_rule();
    if features.contains(Feature::Relief) {
        // Built on first use (process-wide): a session of flat materials never builds it.
        let dh = EffectiveHeightTable::shared();
        base.dh_size = dh.mean.len() as u32;
        base.dh_ln_min = dh.ln_l_min as f32;
        base.dh_ln_max = dh.ln_l_max as f32;
        let start = data.len();
        lay.dh = data.len() as u32;
        for (a, b) in dh.mean.iter().zip(&dh.std) {
            data.extend([*a as f32, *b as f32]);
        }
        mark(&data, start, "visible-height table D_h");
        let start = data.len();
        lay.slope_rule = push_rule(&mut data, rule);
        mark(&data, start, "slope quadrature rule");
        if let Some(t) = &prepared.slope_masking {
            let start = data.len();
            base.cm_offset = data.len() as u32;
            base.cm_on = 1;
            data.extend([t.r0 as f32, t.level_step as f32]);
            data.extend(&t.data);
            mark(&data, start, "slope-conditioned masking table");
        }
        if m.transfer_mixture() {
            let n = bin_slope_points(rule, m.terms.slope.is_some());
            base.mix_nodes = n.len() as u32;
            base.mix_rule_offset = shared_or_pushed(
                &mut data,
                n,
                (rule, lay.slope_rule),
                &mut mark,
                "slope rule of the transfer mixture's bins",
            );
            if let Some(t) = &prepared.transfer_masking {
                let start = data.len();
                base.tm_offset = data.len() as u32;
                base.tm_on = 1;
                data.push(t.sigma_f as f32);
                data.extend(t.gradient.map(|g| g as f32));
                data.extend(&t.moments);
                mark(
                    &data,
                    start,
                    "transfer curve's value- and slope-conditioned masking moments",
                );
                let tn = conditioned_slope_rule(n);
                base.tm_nodes = tn.len() as u32;
                base.tm_rule_offset = shared_or_pushed(
                    &mut data,
                    tn,
                    (n, base.mix_rule_offset),
                    &mut mark,
                    "slope rule of the conditioned bins",
                );
            }
        }
    }
    match &m.color {
        ColorModel::Gradient { map, source } => {
            let p = map.to_piecewise();
            let start = data.len();
            lay.color_poly = push_poly(&mut data, &p, &[0, 1, 2]);
            mark(&data, start, "colour map polynomial");
            base.cp_knots = p.knots.len() as u32;
            base.color_kind = match source {
                ColorSource::Driver => ColorCode::Driver,
                ColorSource::Height => ColorCode::Height,
            }
            .code();
        }
        ColorModel::Attribute { mean, correlation } => {
            base.color_kind = ColorCode::Attribute.code();
            base.attr_mean = mean.map(|v| v as f32);
            base.attr_corr = correlation.map(|v| v as f32);
        }
    }
    // Colour terms: an absent term has weight 0 (see material.wgsl's `affine`).
    let terms = &m.terms;
    base.combine_mode = match terms.mode {
        CombineMode::Linear => CombineCode::Linear,
        CombineMode::Multiplicative => CombineCode::Multiplicative,
    }
    .code();
    if let Some(c) = &terms.constant {
        base.c0 = c.color.map(|v| v as f32);
        base.kappa0 = c.weight as f32;
    }
    base.kappa1 = terms.height.unwrap_or(0.0) as f32;
    if let (Some(t), Some(sc)) = (&terms.slope, &prepared.slope_color) {
        base.kappa2 = t.weight as f32;
        base.sc_dir = sc.direction.to_array().map(|v| v as f32);
        if features.contains(Feature::SlopeColor) {
            let start = data.len();
            base.sp_offset = push_poly(&mut data, &sc.poly, &[0, 1, 2]);
            base.sp_knots = sc.poly.knots.len() as u32;
            mark(&data, start, "slope colour polynomial");
        }
    }
    base.sun = m.lighting.sun as f32;
    if let Some(env) = &prepared.environment
        && features.contains(Feature::Environment)
    {
        let start = data.len();
        base.env_offset = data.len() as u32;
        base.has_env = 1;
        for c in env.irradiance_coefficients() {
            data.extend(c.map(|v| v as f32));
        }
        mark(&data, start, "environment SH9");
    }
    if let Some(measured) = &prepared.measured
        && features.contains(Feature::Measured)
    {
        let start = data.len();
        base.merl_offset = data.len() as u32;
        base.measured = 1;
        data.extend(measured.table.values());
        mark(&data, start, "measured BRDF table");
        let start = data.len();
        base.lobe_offset = data.len() as u32;
        base.lobe_count = measured.fit.lobes.len() as u32;
        for l in &measured.fit.lobes {
            data.push(l.sigma as f32);
            data.extend(l.weight.map(|v| v as f32));
            data.extend(l.fresnel.map(|v| v as f32));
        }
        mark(&data, start, "measured BRDF's fitted lobes");
    }
    if let TransferFunction::Curve(c) = &m.heights.transfer {
        let p = c.moment_poly();
        let start = data.len();
        lay.transfer_poly = push_poly(&mut data, &p, &[0, 2]);
        mark(&data, start, "transfer polynomial");
        base.tp_knots = p.knots.len() as u32;
        base.transfer_kind = TransferCode::Curve.code();
    }
    if data.is_empty() {
        data.push(0.0);
    }
    base.waves_offset = lay.waves;
    base.ct_offset = lay.color_table;
    base.tt_offset = lay.transfer_table;
    base.dh_offset = lay.dh;
    base.slope_rule_offset = lay.slope_rule;
    base.slope_nodes = rule.len() as u32;
    base.noise_slopes = u32::from(m.filtering.noise_slopes == NoiseSlopes::Exact);
    base.interception = u32::from(prepared.interception == Interception::Crests);
    let g = prepared.surface.driver.gradient_cov();
    (base.grad_cov_xx, base.grad_cov_yy, base.grad_cov_xy) =
        (g.xx as f32, g.yy as f32, g.xy as f32);
    base.cp_offset = lay.color_poly;
    base.tp_offset = lay.transfer_poly;
    base.sigma_h = s.sigma_h as f32;
    let weights = prepared.channel_weights();
    base.kd_rgb = weights.kd.map(|v| v as f32);
    base.albedo = m.brdf.albedo as f32;
    base.specular = m.brdf.specular as f32;
    base.roughness = m.brdf.roughness as f32;
    base.h_max = s.h_max as f32;
    base.g_lip = s.g_lip as f32;
    base.min_step = s.min_step as f32;
    base.slope_bound = s.slope_bound() as f32;
    base.correlation = match m.filtering.correlation {
        Correlation::Uncorrelated => CorrelationCode::Uncorrelated,
        Correlation::HeightDirection => CorrelationCode::HeightDirection,
    }
    .code();
    base.height_filter = match m.filtering.height_filter {
        HeightFilter::Exact => HeightFilterCode::Exact,
        HeightFilter::PaperFit => HeightFilterCode::PaperFit,
    }
    .code();
    base.march = match s.march {
        March::Reference => MarchCode::Reference,
        March::Fast => MarchCode::Fast,
    }
    .code();
    base.transfer_monotone = match &m.heights.transfer {
        TransferFunction::Identity => 1,
        TransferFunction::Curve(c) => match c.monotone() {
            Some(true) => 1,
            Some(false) => 2,
            None => 0,
        },
    };
    base.g_mean = prepared.global_height.0 as f32;
    base.g_std = prepared.global_height.1 as f32;
    MaterialData {
        data,
        params: base,
        segments,
    }
}

/// The offset of `rule`: the already uploaded `shared` rule's when it is the same rule, else
/// `rule` appended ([`push_rule`]) and marked as `name`.
fn shared_or_pushed(
    data: &mut Vec<f32>,
    rule: SlopeRule,
    (shared, offset): (SlopeRule, u32),
    mark: &mut impl FnMut(&Vec<f32>, usize, &'static str),
    name: &'static str,
) -> u32 {
    if rule == shared {
        return offset;
    }
    let start = data.len();
    let at = push_rule(data, rule);
    mark(data, start, name);
    at
}

/// Append a slope rule's nodes ([`SlopeRule::nodes`]: x, y, weight per node) and return its
/// offset.
fn push_rule(data: &mut Vec<f32>, rule: SlopeRule) -> u32 {
    let offset = data.len() as u32;
    for (z, w) in rule.nodes() {
        data.extend([z.x as f32, z.y as f32, *w as f32]);
    }
    offset
}

/// The noise driver the octave march sums, when the march is fast, the scene has relief and σ_h > 0:
/// what the bound grid and the field table are built from (`None` otherwise).
fn marched_noise(prepared: &Evaluator, features: FeatureSet) -> Option<&SumOfSines> {
    let s = &prepared.surface;
    let DriverField::Noise(noise) = &s.driver else {
        return None;
    };
    (s.march == March::Fast && features.contains(Feature::Relief) && s.sigma_h > 0.0)
        .then_some(noise)
}

/// Cells per side of the bound grid the GPU march reads (core's [`BoundGrid::around`]): 512² cells,
/// a pyramid of 2.8 MB, built in tens of milliseconds.
pub const GPU_GRID_CELLS: usize = 512;

/// Which of the octave march's tables the GPU gets. Both by default; leaving one out keeps the march
/// as rigorous and only changes its cost, so `lodestone bench --no-bound-grid` or `--no-field-table`
/// times the march without it on the same build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MarchTables {
    /// The min–max pyramid of the noise around the camera target that lets rays skip clear space
    /// ([`lodestone_core::scene::bound_grid`]).
    pub bound_grid: bool,
    /// The bicubic table of the noise that the march steps on near the surface
    /// ([`lodestone_core::scene::field_grid`]).
    pub field_table: bool,
}

impl Default for MarchTables {
    fn default() -> Self {
        Self {
            bound_grid: true,
            field_table: true,
        }
    }
}

/// Append the octave march's tables of a noise driver's explicit surface around `target` to `d`
/// when the march is fast and the scene has relief ([`push_bound_grid`], [`push_field_grid`]),
/// those `tables` asks for; nothing otherwise (`grid_n` and `field_n` stay 0: the march sums the
/// waves everywhere).
pub fn push_march_tables(
    prepared: &Evaluator,
    target: [f64; 2],
    features: FeatureSet,
    tables: MarchTables,
    d: &mut MaterialData,
) {
    let Some(noise) = marched_noise(prepared, features) else {
        return;
    };
    let centre = DVec2::from(target);
    if tables.bound_grid {
        push_bound_grid(noise, centre, d);
    }
    if tables.field_table {
        push_field_grid(noise, centre, d);
    }
}

/// Append the bound grid of `noise` around `centre` to `d` (the octave march's skips;
/// [`lodestone_core::scene::bound_grid`]): the pyramid's levels one after the other, `[lo, hi]` per
/// cell, in coordinates relative to `centre` like the waves.
fn push_bound_grid(noise: &SumOfSines, centre: DVec2, d: &mut MaterialData) {
    let Some(grid) = BoundGrid::around(noise, centre, GPU_GRID_CELLS) else {
        return;
    };
    let start = d.data.len();
    d.params.grid_offset = start as u32;
    for level in &grid.levels {
        for r in level {
            d.data.extend(r);
        }
    }
    d.segments.push(("bound grid", (d.data.len() - start) * 4));
    d.params.grid_n = grid.n as u32;
    d.params.grid_levels = grid.levels.len() as u32;
    d.params.grid_cell = grid.cell as f32;
    d.params.grid_x0 = (grid.origin.x - centre.x) as f32;
    d.params.grid_y0 = (grid.origin.y - centre.y) as f32;
    d.params.grid_amp = noise.waves.iter().map(|w| w.amplitude.abs()).sum::<f64>() as f32;
}

/// Cells per side of the field table the GPU march reads (core's [`FieldGrid::around`]): 512²
/// cells, 4.2 MB.
pub const GPU_FIELD_CELLS: usize = 512;

/// Append the field table of `noise` around `centre` to `d` (the octave march's steps near the
/// surface; [`lodestone_core::scene::field_grid`]), its origin relative to `centre` like the waves
/// and its error bounds widened by [`FIELD_MARGIN_F32`] for the f32 arithmetic.
fn push_field_grid(noise: &SumOfSines, centre: DVec2, d: &mut MaterialData) {
    let Some(field) = FieldGrid::around(noise, centre, GPU_FIELD_CELLS) else {
        return;
    };
    let start = d.data.len();
    d.params.field_offset = start as u32;
    for v in &field.vertices {
        d.data.extend(v);
    }
    d.segments.push(("field table", (d.data.len() - start) * 4));
    let amp = field.amplitude_sum;
    let fine = noise
        .waves
        .iter()
        .map(|w| std::f64::consts::TAU * w.k.abs())
        .fold(DVec2::ZERO, DVec2::max);
    let margin = FIELD_MARGIN_F32 * amp;
    d.params.field_n = field.n as u32;
    d.params.field_cell = field.cell as f32;
    d.params.field_x0 = (field.origin.x - centre.x) as f32;
    d.params.field_y0 = (field.origin.y - centre.y) as f32;
    d.params.field_error = (field.error + margin) as f32;
    d.params.field_slope_error_x = (field.slope_error.x + margin * fine.x) as f32;
    d.params.field_slope_error_y = (field.slope_error.y + margin * fine.y) as f32;
}
