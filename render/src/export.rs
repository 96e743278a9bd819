//! The engine bundle: everything another engine needs to evaluate a material's filtering without
//! Lodestone.
//!
//! | file | content |
//! |---|---|
//! | `lodestone_filtered.wgsl` | self-contained WGSL: the special functions and the material model (the renderer's own `special.wgsl` + `material.wgsl`, so it equals the renderer by construction) and an example compute entry point |
//! | `lodestone_filtered.glsl` | the same, translated to GLSL 4.50 (compute) by naga |
//! | `params.bin` | the material's WGSL `Params` struct (std430, little-endian) for binding 0 |
//! | `data.bin` | the material's f32 data buffer (waves, tables, D_h, quadrature rule) for binding 1 |
//! | `color_table.exr`, `transfer_table.exr`, `effective_height.exr` | the pre-convolved tables as images, for engines that prefer textures |
//! | `histogram_table.exr` | image drivers with a kept histogram: H(f̄, σ_f) = (μ_G, σ_G), the colour table is then indexed by it |
//! | `manifest.json` | sizes, ranges and indexing of every table, every `Params` field by name, the API |
//! | `material.ron` | the preset |
//!
//! API of the snippets: `eval_filtered(x0, fp, wo, wi, sun_visible) -> vec3` — linear RGB radiance of
//! the filtered material for a pixel footprint centred at surface point `x0` (world units) with
//! covariance `fp = (Σxx, Σyy, Σxy)`, unit view and light directions in the surface frame
//! (z = normal), `sun_visible` ∈ [0, 1] the engine's shadowing of the directional light at the point
//! (the environment term, if any, is unshadowed); `eval_naive` and `eval_view_independent` take the
//! same arguments.

use crate::gpu_types::{GpuStruct, MaterialParams};
use crate::material_data::material_data;
use crate::shaders;
use lodestone_core::eval::Evaluator;
use lodestone_core::material::features::FeatureSet;
use lodestone_core::math::preconvolved::PreconvolvedTable;
use lodestone_core::microfacet::effective_height::EffectiveHeightTable;
use serde_json::json;

/// Why a bundle could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The WGSL snippet does not parse or validate (a bug).
    #[error("the WGSL snippet is invalid: {0}")]
    Wgsl(String),
    /// naga could not translate the snippet to GLSL.
    #[error("translating the snippet to GLSL failed: {0}")]
    Glsl(String),
    /// A table could not be encoded as EXR.
    #[error("encoding {0} failed: {1}")]
    Image(String, String),
}

/// Name of the example entry point in both snippets.
pub const ENTRY_POINT: &str = "lodestone_filtered_main";

/// Floats per input record of the example entry point: x0 (2), fp (3), wo (3), wi (3), padding (1).
pub const INPUT_STRIDE: usize = 12;

const EXAMPLE: &str = r#"
// ---------------------------------------------------------------- example entry point
// One eval_filtered per input record of 12 floats: x0.xy, fp.(xx, yy, xy), wo.xyz, wi.xyz, padding.
// Writes linear RGB + 1 per record. Bind params.bin at binding 0 and data.bin at binding 1.
@group(0) @binding(2) var<storage, read> lodestone_inputs: array<f32>;
@group(0) @binding(3) var<storage, read_write> lodestone_outputs: array<f32>;

@compute @workgroup_size(64)
fn lodestone_filtered_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = arrayLength(&lodestone_inputs) / 12u;
    let i = id.x;
    if (i >= n) {
        return;
    }
    let b = i * 12u;
    let x0 = vec2<f32>(lodestone_inputs[b], lodestone_inputs[b + 1u]);
    let fp = vec3<f32>(lodestone_inputs[b + 2u], lodestone_inputs[b + 3u], lodestone_inputs[b + 4u]);
    let wo = vec3<f32>(lodestone_inputs[b + 5u], lodestone_inputs[b + 6u], lodestone_inputs[b + 7u]);
    let wi = vec3<f32>(lodestone_inputs[b + 8u], lodestone_inputs[b + 9u], lodestone_inputs[b + 10u]);
    let c = eval_filtered(x0, fp, wo, wi, 1.0);
    lodestone_outputs[i * 4u] = c.x;
    lodestone_outputs[i * 4u + 1u] = c.y;
    lodestone_outputs[i * 4u + 2u] = c.z;
    lodestone_outputs[i * 4u + 3u] = 1.0;
}
"#;

/// The self-contained WGSL snippet.
pub fn snippet_wgsl() -> String {
    let material = [shaders::SPECIAL, shaders::material(), shaders::IMAGE_DRIVER].join("\n");
    // The bundle's data holds every table the material has, so the snippet is the all-features
    // shader (the engine then picks the material at run time, as Lodestone's own fallback does).
    let material = crate::specialize::specialize(&material, FeatureSet::all())
        .expect("the all-features material shader specialises");
    format!(
        "// Lodestone filtered material, self-contained WGSL (lodestone-core mirrored in f32).\n\
         // Bindings: 0 = Params (params.bin), 1 = data (data.bin); see manifest.json.\n\
         // API: eval_filtered / eval_naive / eval_view_independent(x0, fp, wo, wi, sun_visible) -> vec3<f32>.\n\n{}\n{}",
        material, EXAMPLE
    )
}

/// Parse and validate WGSL with naga.
fn validated(source: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), ExportError> {
    let module =
        naga::front::wgsl::parse_str(source).map_err(|e| ExportError::Wgsl(e.to_string()))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| ExportError::Wgsl(format!("{e:?}")))?;
    Ok((module, info))
}

/// The snippet translated to GLSL 4.50 (a compute shader with [`ENTRY_POINT`]).
pub fn snippet_glsl() -> Result<String, ExportError> {
    let (module, info) = validated(&snippet_wgsl())?;
    // Explicit layout(binding = N) for group 0's bindings 0..3, as desktop GLSL engines expect.
    let binding_map = (0..4u32)
        .map(|b| {
            (
                naga::ResourceBinding {
                    group: 0,
                    binding: b,
                },
                b as u8,
            )
        })
        .collect();
    let options = naga::back::glsl::Options {
        version: naga::back::glsl::Version::Desktop(450),
        binding_map,
        ..Default::default()
    };
    let pipeline = naga::back::glsl::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: ENTRY_POINT.into(),
        multiview: None,
    };
    let mut out = String::new();
    let mut writer = naga::back::glsl::Writer::new(
        &mut out,
        &module,
        &info,
        &options,
        &pipeline,
        naga::proc::BoundsCheckPolicies::default(),
    )
    .map_err(|e| ExportError::Glsl(e.to_string()))?;
    writer
        .write()
        .map_err(|e| ExportError::Glsl(e.to_string()))?;
    drop(writer);
    Ok(format!(
        "// Lodestone filtered material, GLSL 4.50 translated from lodestone_filtered.wgsl by naga.\n{out}"
    ))
}

/// A table as an RGBA32F EXR (width = m samples, height = σ samples).
fn table_exr(name: &str, t: &PreconvolvedTable) -> Result<Vec<u8>, ExportError> {
    let img = image::Rgba32FImage::from_fn(t.size_m as u32, t.size_sigma as u32, |x, y| {
        image::Rgba(t.texels[y as usize * t.size_m + x as usize])
    });
    encode_exr(name, img)
}

fn encode_exr(name: &str, img: image::Rgba32FImage) -> Result<Vec<u8>, ExportError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::DynamicImage::ImageRgba32F(img)
        .write_to(&mut bytes, image::ImageFormat::OpenExr)
        .map_err(|e| ExportError::Image(name.into(), e.to_string()))?;
    Ok(bytes.into_inner())
}

fn table_json(
    t: &PreconvolvedTable,
    file: &str,
    channels: [&str; 4],
    offset: u32,
) -> serde_json::Value {
    json!({
        "file": file,
        "size_m": t.size_m,
        "size_sigma": t.size_sigma,
        "m_min": t.m_min,
        "m_max": t.m_max,
        "sigma_max": t.sigma_max,
        "channels": channels,
        "data_offset_floats": offset,
        "indexing": "texel (i, j) holds the value at m = m_min + i·(m_max − m_min)/(size_m − 1), \
                     σ = j·sigma_max/(size_sigma − 1); bilinear between texels, clamp to edge",
    })
}

/// Every file of the bundle, as (name, bytes).
pub fn bundle(prepared: &Evaluator) -> Result<Vec<(String, Vec<u8>)>, ExportError> {
    let (data, params) = material_data(prepared, [0.0, 0.0]);
    let m = &prepared.material;
    let mut files: Vec<(String, Vec<u8>)> = vec![
        (
            "lodestone_filtered.wgsl".into(),
            snippet_wgsl().into_bytes(),
        ),
        (
            "lodestone_filtered.glsl".into(),
            snippet_glsl()?.into_bytes(),
        ),
        ("params.bin".into(), bytemuck::bytes_of(&params).to_vec()),
        ("data.bin".into(), bytemuck::cast_slice(&data).to_vec()),
        ("material.ron".into(), m.to_ron().into_bytes()),
    ];
    let mut tables = serde_json::Map::new();
    if let Some(t) = prepared.color.table() {
        files.push(("color_table.exr".into(), table_exr("color_table.exr", t)?));
        tables.insert(
            "color".into(),
            table_json(
                t,
                "color_table.exr",
                ["R", "G", "B", "unused"],
                params.ct_offset,
            ),
        );
    }
    if let Some(t) = prepared.color.gaussianize_table() {
        // The colour table is then indexed by the image histogram's Gaussian space (μ_G, σ_G).
        files.push((
            "histogram_table.exr".into(),
            table_exr("histogram_table.exr", t)?,
        ));
        tables.insert(
            "histogram".into(),
            table_json(
                t,
                "histogram_table.exr",
                ["mean G", "std G", "unused", "unused"],
                params.ht_offset,
            ),
        );
    }
    if let Some(t) = prepared.transfer.table() {
        files.push((
            "transfer_table.exr".into(),
            table_exr("transfer_table.exr", t)?,
        ));
        tables.insert(
            "transfer".into(),
            table_json(
                t,
                "transfer_table.exr",
                ["mean g", "std g", "mean g'", "std g'"],
                params.tt_offset,
            ),
        );
    }
    let dh = EffectiveHeightTable::shared();
    let img = image::Rgba32FImage::from_fn(dh.mean.len() as u32, 1, |x, _| {
        image::Rgba([
            dh.mean[x as usize] as f32,
            dh.std[x as usize] as f32,
            0.0,
            1.0,
        ])
    });
    files.push((
        "effective_height.exr".into(),
        encode_exr("effective_height.exr", img)?,
    ));
    tables.insert(
        "effective_height".into(),
        json!({
            "file": "effective_height.exr",
            "size": dh.mean.len(),
            "ln_l_min": dh.ln_l_min,
            "ln_l_max": dh.ln_l_max,
            "channels": ["mean of D_h / σ_h", "std of D_h / σ_h", "unused", "unused"],
            "data_offset_floats": params.dh_offset,
            "indexing": "texel i holds the moments at ln L = ln_l_min + i·(ln_l_max − ln_l_min)/(size − 1) [HNPN14 Sec. 5.1]",
        }),
    );
    if let Some(t) = prepared.surface.driver.image() {
        let (w, h) = t.image.size();
        tables.insert(
            "image_driver".into(),
            json!({
                "size": [w, h],
                "levels": t.image.levels.len(),
                "tile_world_width": t.size,
                "level_table_offset_floats": params.image_offset,
                "layout": "at level_table_offset, per level 7 slots: value offset, grad offset, width, height \
                           (u32 bits), mean variance, Lipschitz constants of f̄ along x and y per level-0 texel \
                           (f32); the value grid holds (f̄, f²‾) per texel, the cell grid \
                           (f_x, f_y, f_x², f_y², f_x·f_y) per texel, half a texel after the value grid [HNPN14 Sec. 4.2]",
                "coordinates": "texel = (image_u0, image_v0) + x·image_scale for x relative to the target the \
                                bundle was made for (the origin); tiles wrap",
            }),
        );
    }
    let bytes = bytemuck::bytes_of(&params);
    let fields: serde_json::Map<String, serde_json::Value> = MaterialParams::offsets()
        .into_iter()
        .map(|(name, off)| {
            let word =
                u32::from_le_bytes([bytes[off], bytes[off + 1], bytes[off + 2], bytes[off + 3]]);
            (
                name.to_string(),
                json!({ "offset_bytes": off, "bits": word, "as_f32": f32::from_bits(word) }),
            )
        })
        .collect();
    let manifest = json!({
        "format": "lodestone-engine-bundle",
        "version": 1,
        "material": m.name,
        "api": {
            "wgsl": "lodestone_filtered.wgsl",
            "glsl": "lodestone_filtered.glsl",
            "functions": ["eval_filtered", "eval_naive", "eval_view_independent"],
            "signature": "(x0: vec2 surface point in world units, fp: vec3 footprint covariance (xx, yy, xy), wo: vec3 unit view direction, wi: vec3 unit light direction; z = surface normal) -> vec3 linear RGB",
            "bindings": { "0": "params.bin (Params, std430)", "1": "data.bin (array<f32>)" },
            "example_entry_point": ENTRY_POINT,
            "example_input_stride_floats": INPUT_STRIDE,
        },
        "params_size_bytes": std::mem::size_of::<MaterialParams>(),
        "params": fields,
        "data_floats": data.len(),
        "tables": tables,
    });
    files.push((
        "manifest.json".into(),
        serde_json::to_string_pretty(&manifest)
            .unwrap_or_default()
            .into_bytes(),
    ));
    Ok(files)
}
