//! Every WGSL file validates with naga, and the WGSL mirrors agree with lodestone-core on the GPU
//! adapter (llvmpipe on CI) over ≥ 10,000 inputs, extremes included.

use lodestone_core::features::FeatureSet;
use lodestone_core::{special, special_f32};
use lodestone_render::{GpuContext, compute::eval_unary, shaders};

/// Parse and validate a file together with the files it needs.
fn module_for(name: &str, file: &str) -> naga::Module {
    let mut parts = shaders::prelude_for(name);
    parts.push(file);
    let src = lodestone_render::specialize::specialize(&parts.join("\n"), FeatureSet::all())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let module = naga::front::wgsl::parse_str(&src)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {e:?}"));
    module
}

#[test]
fn every_wgsl_file_validates() {
    for (name, file) in shaders::ALL {
        let module = module_for(name, file);
        // The mirrored functions exist under core's names.
        if *name == "special.wgsl" {
            for f in shaders::SPECIAL_MIRRORED {
                assert!(
                    module
                        .functions
                        .iter()
                        .any(|(_, func)| func.name.as_deref() == Some(f)),
                    "{f} missing"
                );
            }
        }
    }
}

#[test]
fn gpu_params_match_the_wgsl_layout() {
    let module = module_for("material.wgsl", shaders::MATERIAL);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("Params"))
        .expect("struct Params");
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("Params is not a struct")
    };
    let rust = lodestone_render::gpu_types::gpu_params_offsets();
    assert_eq!(members.len(), rust.len(), "field count");
    for (m, (name, off)) in members.iter().zip(&rust) {
        assert_eq!(m.name.as_deref(), Some(*name), "field order");
        assert_eq!(m.offset as usize, *off, "offset of {name}");
    }
    assert_eq!(
        *span as usize,
        std::mem::size_of::<lodestone_render::gpu_types::GpuParams>(),
        "size"
    );
    let _ = layouter[handle].size;
}

fn inputs(lo: f32, hi: f32, n: usize, extremes: &[f32]) -> Vec<f32> {
    let mut v: Vec<f32> = (0..n)
        .map(|i| lo + (hi - lo) * (i as f32 + 0.37) / n as f32)
        .collect();
    v.extend_from_slice(extremes);
    v
}

#[test]
fn wgsl_special_functions_match_core_on_the_adapter() {
    let ctx = match GpuContext::new_headless() {
        Ok(c) => c,
        Err(e) => {
            // Never require a GPU: without any adapter (not even llvmpipe) this test has nothing to run on.
            eprintln!("skipping GPU mirror test: {e}");
            return;
        }
    };
    eprintln!("adapter: {}", ctx.describe());
    type Case = (&'static str, fn(f64) -> f64, fn(f32) -> f32, f32, f32);
    let cases: [Case; 7] = [
        ("erf", special::erf, special_f32::erf, -6.0, 6.0),
        ("erfc", special::erfc, special_f32::erfc, -6.0, 9.0),
        ("erfcx", special::erfcx, special_f32::erfcx, -9.0, 1e4),
        (
            "norm_pdf",
            special::norm_pdf,
            special_f32::norm_pdf,
            -13.0,
            13.0,
        ),
        (
            "norm_cdf",
            special::norm_cdf,
            special_f32::norm_cdf,
            -13.0,
            8.0,
        ),
        (
            "log_norm_cdf",
            special::log_norm_cdf,
            special_f32::log_norm_cdf,
            -1e3,
            8.0,
        ),
        (
            "smith_lambda",
            special::smith_lambda,
            special_f32::smith_lambda,
            0.0,
            10.0,
        ),
    ];
    let extremes = [
        0.0, -0.0, 1e-30, 1e-7, 0.999_999, 1.0, 1.000_001, 10.4, 10.6, -1e-7, 3.0e38,
    ];
    let mut total = 0;
    for (name, f64_fn, f32_fn, lo, hi) in cases {
        let xs = inputs(lo, hi, 12_000, &extremes);
        let gpu = eval_unary(&ctx, shaders::SPECIAL, name, &xs);
        let mut worst = 0.0f64;
        for (x, g) in xs.iter().zip(&gpu) {
            let want = f64_fn(f64::from(*x));
            let cpu32 = f64::from(f32_fn(*x));
            let g = f64::from(*g);
            assert!(
                g.is_finite() || !want.is_finite(),
                "{name}({x}): GPU gave {g}"
            );
            if !want.is_finite() || want.abs() > 3e38 || (want != 0.0 && want.abs() < 1e-35) {
                continue;
            }
            let err = (g - want).abs();
            let ok = err <= 1e-4 * want.abs() || err <= 1e-6;
            assert!(
                ok,
                "{name}({x}): GPU {g:e}, core {want:e} (core f32 {cpu32:e})"
            );
            if want.abs() > 1e-6 {
                worst = worst.max(err / want.abs());
            }
        }
        eprintln!(
            "{name}: {} inputs, worst relative error vs f64 core {worst:.2e}",
            xs.len()
        );
        total += xs.len();
    }
    assert!(total >= 10_000);
}
