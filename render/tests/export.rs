//! The engine bundle: its snippets parse (naga reads the WGSL and the translated GLSL back), its
//! files are consistent with the manifest, and the WGSL snippet, run on the adapter with the bundle's
//! params.bin and data.bin, equals core's filtered evaluation on sample inputs.

use glam::{DMat2, DVec2};
use lodestone_core::driver::footprint::Footprint;
use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::material::Material;
use lodestone_core::scene::direction::direction;
use lodestone_render::export::{ENTRY_POINT, INPUT_STRIDE, bundle, snippet_glsl, snippet_wgsl};
use lodestone_tests::preset;

fn file<'a>(files: &'a [(String, Vec<u8>)], name: &str) -> &'a [u8] {
    &files
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("{name} missing"))
        .1
}

#[test]
fn snippets_parse_in_wgsl_and_glsl() {
    let wgsl = snippet_wgsl();
    let module = naga::front::wgsl::parse_str(&wgsl).expect("WGSL parses");
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .expect("WGSL validates");
    let glsl = snippet_glsl().expect("translates");
    assert!(glsl.contains("#version 450"));
    let mut frontend = naga::front::glsl::Frontend::default();
    let parsed = frontend
        .parse(
            &naga::front::glsl::Options::from(naga::ShaderStage::Compute),
            &glsl,
        )
        .unwrap_or_else(|e| panic!("GLSL does not parse: {e:?}"));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&parsed)
    .expect("GLSL validates");
    assert!(parsed.entry_points.iter().any(|e| e.name == "main"));
}

#[test]
fn bundle_files_match_the_manifest() {
    for name in ["default.ron", "moss.ron", "dirt-in-crevices.ron"] {
        let p = Evaluator::new(&preset(name)).unwrap();
        let files = bundle(&p).expect("bundle");
        let manifest: serde_json::Value =
            serde_json::from_slice(file(&files, "manifest.json")).expect("manifest is JSON");
        assert_eq!(
            manifest["params_size_bytes"].as_u64().unwrap() as usize,
            file(&files, "params.bin").len()
        );
        assert_eq!(
            manifest["data_floats"].as_u64().unwrap() as usize * 4,
            file(&files, "data.bin").len()
        );
        for (key, t) in manifest["tables"].as_object().unwrap() {
            let f = t["file"].as_str().unwrap();
            let img = image::load_from_memory(file(&files, f))
                .unwrap_or_else(|e| panic!("{name} {key}: {e}"))
                .to_rgba32f();
            let (w, h) = if key == "effective_height" {
                (t["size"].as_u64().unwrap() as u32, 1)
            } else {
                (
                    t["size_m"].as_u64().unwrap() as u32,
                    t["size_sigma"].as_u64().unwrap() as u32,
                )
            };
            assert_eq!((img.width(), img.height()), (w, h), "{name} {key}");
            // The EXR equals the data buffer from the offset on (first texel, all 4 channels).
            let off = t["data_offset_floats"].as_u64().unwrap() as usize * 4;
            let data = file(&files, "data.bin");
            let first: Vec<f32> = (0..4)
                .map(|k| f32::from_le_bytes(data[off + 4 * k..off + 4 * k + 4].try_into().unwrap()))
                .collect();
            let px = img.get_pixel(0, 0);
            let n = if key == "effective_height" { 2 } else { 4 };
            for k in 0..n {
                assert_eq!(px[k], first[k], "{name} {key} channel {k}");
            }
        }
        let ron = std::str::from_utf8(file(&files, "material.ron")).unwrap();
        assert_eq!(Material::from_ron(ron).unwrap(), p.material);
    }
}

/// The WGSL snippet with the bundle's buffers, on the adapter, against core's f64 evaluation.
#[test]
fn wgsl_snippet_equals_core_filtered() {
    let Some(ctx) = lodestone_tests::gpu("the WGSL snippet test") else {
        return;
    };
    let p = Evaluator::new(&preset("default.ron")).unwrap();
    let files = bundle(&p).unwrap();
    // Sample inputs: positions, footprints from sub-feature to many features, view and light
    // from overhead to 80°.
    let mut inputs: Vec<f32> = vec![];
    let mut configs = vec![];
    let mut s = 1u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64) / ((1u64 << 53) as f64)
    };
    for _ in 0..256 {
        let x0 = DVec2::new(rnd() * 20.0 - 10.0, rnd() * 20.0 - 10.0);
        let r = 10f64.powf(-2.5 + 3.5 * rnd());
        let a = rnd() * 3.0;
        let cov = DMat2::from_cols(
            DVec2::new(r * r, 0.3 * r * r * a.cos()),
            DVec2::new(0.3 * r * r * a.cos(), r * r * (0.5 + rnd())),
        );
        let wo = direction((rnd() * 80.0).to_radians(), rnd() * std::f64::consts::TAU);
        let wi = direction((rnd() * 80.0).to_radians(), rnd() * std::f64::consts::TAU);
        inputs.extend([
            x0.x as f32,
            x0.y as f32,
            cov.x_axis.x as f32,
            cov.y_axis.y as f32,
            cov.x_axis.y as f32,
            wo.x as f32,
            wo.y as f32,
            wo.z as f32,
            wi.x as f32,
            wi.y as f32,
            wi.z as f32,
            0.0,
        ]);
        configs.push(FootprintQuery {
            wo,
            wi,
            x0,
            footprint: Footprint { cov },
        });
    }
    assert_eq!(inputs.len(), configs.len() * INPUT_STRIDE);
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("snippet"),
        source: wgpu::ShaderSource::Wgsl(snippet_wgsl().into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("snippet"),
        layout: None,
        module: &module,
        entry_point: Some(ENTRY_POINT),
        compilation_options: Default::default(),
        cache: None,
    });
    let storage = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
        let b = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.len().max(4) as u64,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue.write_buffer(&b, 0, bytes);
        b
    };
    let params = storage(
        "params",
        file(&files, "params.bin"),
        wgpu::BufferUsages::STORAGE,
    );
    let data = storage(
        "data",
        file(&files, "data.bin"),
        wgpu::BufferUsages::STORAGE,
    );
    let input = storage(
        "inputs",
        bytemuck::cast_slice(&inputs),
        wgpu::BufferUsages::STORAGE,
    );
    let out_size = (configs.len() * 16) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outputs"),
        size: out_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: out_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("snippet"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: data.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: output.as_entire_binding(),
            },
        ],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((configs.len() as u32).div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&output, 0, &readback, 0, out_size);
    ctx.queue.submit([enc.finish()]);
    readback.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let got: Vec<f32> =
        bytemuck::cast_slice(&readback.slice(..).get_mapped_range().unwrap()).to_vec();
    let mut off = 0;
    for (i, cfg) in configs.iter().enumerate() {
        let want = p.filtered(cfg);
        assert!(
            got[4 * i..4 * i + 3].iter().all(|v| v.is_finite()),
            "input {i}: {:?}",
            &got[4 * i..4 * i + 3]
        );
        let bad = (0..3)
            .any(|k| !((f64::from(got[4 * i + k]) - want[k]).abs() <= 5e-3 * want[k].abs() + 2e-4));
        if bad {
            off += 1;
            eprintln!(
                "input {i}: GPU {:?} vs core {want:?}",
                &got[4 * i..4 * i + 3]
            );
        }
    }
    assert!(
        off <= configs.len() / 100,
        "{off} of {} inputs differ",
        configs.len()
    );
}

/// An image-driven material's bundle describes the pyramid: the level table in data.bin matches
/// the image's levels.
#[test]
fn image_driver_bundle_describes_the_pyramid() {
    let mut m = preset("default.ron");
    m.driver = lodestone_core::material::Driver::Image {
        path: "x.png".into(),
        size: 2.0,
    };
    let values: Vec<f32> = (0..64 * 32).map(|i| ((i * 37) % 101) as f32).collect();
    let img = std::sync::Arc::new(
        lodestone_core::driver::image::ImageDriver::new(64, 32, &values).unwrap(),
    );
    let p = lodestone_core::eval::Evaluator::with_image(&m, Some(img.clone()), None).unwrap();
    let files = bundle(&p).expect("bundle");
    let manifest: serde_json::Value =
        serde_json::from_slice(file(&files, "manifest.json")).unwrap();
    let d = &manifest["tables"]["image_driver"];
    assert_eq!(d["levels"], img.levels.len());
    assert_eq!(d["size"][0], 64);
    let data: &[f32] = bytemuck::cast_slice(file(&files, "data.bin"));
    let table = d["level_table_offset_floats"].as_u64().unwrap() as usize;
    for (l, level) in img.levels.iter().enumerate() {
        let n = lodestone_render::material_data::IMAGE_LEVEL_SLOTS;
        let slot = &data[table + n * l..table + n * (l + 1)];
        assert_eq!(f64::from(slot[5]), level.lipschitz.x);
        assert_eq!(slot[2].to_bits() as usize, level.width);
        assert_eq!(slot[3].to_bits() as usize, level.height);
        let v = slot[0].to_bits() as usize;
        assert_eq!(data[v], level.value[0][0]);
    }
}
