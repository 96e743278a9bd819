//! The WGSL mirrors of #17's conditioned visibility (`math/gaussian_weight.wgsl`,
//! `eval/masking/transfer_masking_table.wgsl`) against lodestone-core's f64 on the GPU adapter: the
//! Gaussian weights' products, powers, expectations and tilts, and the table's rays and visibility
//! weights over views, lights and values.

use glam::{DMat2, DVec2};
use lodestone_core::eval::masking::transfer_masking_table::TransferMaskingTable;
use lodestone_core::material::Material;
use lodestone_core::material::features::FeatureSet;
use lodestone_core::math::gaussian_weight::GaussianWeight;
use lodestone_render::{compute::eval_unary, gpu_codes, shaders};

/// The mirrored files with what they need (the constants prelude, the special functions, the
/// Cholesky factor, Smith's masking for the azimuth factor, the footprint's driver, the slope
/// masking table's azimuth and ν coordinates), specialized
/// for every feature, and `extra` (the test's cases and entry function). The material's data is
/// the harness's input buffer (`datum`).
fn library(extra: &str) -> String {
    let files = [
        include_str!("../src/shaders/math/gaussian.wgsl"),
        include_str!("../src/shaders/math/gaussian_weight.wgsl"),
        include_str!("../src/shaders/microfacet/slopes.wgsl"),
        include_str!("../src/shaders/microfacet/smith.wgsl"),
        include_str!("../src/shaders/microfacet/masking_shadowing.wgsl"),
        include_str!("../src/shaders/driver/footprint.wgsl"),
        include_str!("../src/shaders/microfacet/slope_masking.wgsl"),
        include_str!("../src/shaders/eval/masking/slope_masking_table.wgsl"),
        include_str!("../src/shaders/eval/masking/transfer_masking_table.wgsl"),
    ];
    let data = "var<private> params: Params;\nconst PI: f32 = 3.14159265;\nconst SQRT_2: f32 = 1.4142135;\nfn datum(i: u32) -> f32 { return inputs[i]; }\n";
    let mut parts = vec![gpu_codes::wgsl_prelude(), shaders::SPECIAL, data];
    parts.extend(files);
    parts.push(extra);
    lodestone_render::specialize::specialize(&parts.join("\n"), FeatureSet::all())
        .expect("specialized")
}

fn f32s(v: impl IntoIterator<Item = f64>) -> String {
    v.into_iter()
        .map(|x| format!("{:?}", x as f32))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Products of two weights from moments (one a power), their expectations under a full, a
/// rank-one and a zero covariance, and their tilted Gaussians: the GPU against core.
#[test]
fn wgsl_gaussian_weights_match_core_on_the_adapter() {
    let Some(ctx) = lodestone_tests::gpu("the GPU mirror test") else {
        return;
    };
    // (e_a, moments a, e_b, moments b, power of b, mean, covariance root)
    type Case = (DVec2, [f64; 3], DVec2, [f64; 3], f64, DVec2, DMat2);
    let mut cases: Vec<Case> = vec![];
    let roots = [
        DMat2::from_cols(DVec2::new(0.7, 0.2), DVec2::new(0.0, 0.4)),
        DMat2::from_cols(DVec2::new(0.5, -0.3), DVec2::ZERO),
        DMat2::ZERO,
        DMat2::IDENTITY,
    ];
    for (j, (ma, mb)) in [
        ([0.7, -0.2, 0.5], [0.5, 0.15, 0.3]),
        ([0.14, -0.13, 0.13], [0.88, 0.02, 0.9]),
        ([0.999, 0.0, 0.999], [0.3, 0.25, 0.22]),
        ([0.05, 0.045, 0.0406], [0.6, -0.3, 0.35]),
    ]
    .into_iter()
    .enumerate()
    {
        let ea = DVec2::from_angle(0.4 + j as f64);
        let eb = DVec2::from_angle(2.9 - 0.7 * j as f64);
        for (k, root) in roots.iter().enumerate() {
            for power in [1.0, 0.6, 0.0] {
                let mean = DVec2::new(0.3 - 0.2 * k as f64, -0.5 + 0.3 * j as f64);
                cases.push((ea, ma, eb, mb, power, mean, *root));
            }
        }
    }
    // Core on the f32 inputs the GPU reads.
    let r = |x: f64| f64::from(x as f32);
    let cases: Vec<Case> = cases
        .into_iter()
        .map(|(ea, ma, eb, mb, p, mu, l)| {
            let v = |v: DVec2| DVec2::new(r(v.x), r(v.y));
            (
                v(ea),
                ma.map(r),
                v(eb),
                mb.map(r),
                r(p),
                v(mu),
                DMat2::from_cols(v(l.x_axis), v(l.y_axis)),
            )
        })
        .collect();
    let n = cases.len();
    let list = |f: &dyn Fn(&Case) -> String| cases.iter().map(f).collect::<Vec<_>>().join(", ");
    let v2 = |v: DVec2| format!("vec2<f32>({:?}, {:?})", v.x as f32, v.y as f32);
    let v3 = |v: [f64; 3]| format!("vec3<f32>({})", f32s(v));
    let extra = format!(
        "var<private> EA: array<vec2<f32>, {n}> = array({});\n\
         var<private> MA: array<vec3<f32>, {n}> = array({});\n\
         var<private> EB: array<vec2<f32>, {n}> = array({});\n\
         var<private> MB: array<vec3<f32>, {n}> = array({});\n\
         var<private> PW: array<f32, {n}> = array({});\n\
         var<private> MU: array<vec2<f32>, {n}> = array({});\n\
         var<private> L0: array<vec2<f32>, {n}> = array({});\n\
         var<private> L1: array<vec2<f32>, {n}> = array({});\n\
         fn run(x: f32) -> f32 {{\n\
             let i = u32(x) / 6u;\n\
             let a = gaussian_weight_along(EA[i], MA[i].x, MA[i].y, MA[i].z);\n\
             let b = gaussian_weight_along(EB[i], MB[i].x, MB[i].y, MB[i].z);\n\
             let w = gaussian_weight_mul(a, gaussian_weight_powf(b, PW[i]));\n\
             let e = gaussian_weight_expect_under(w, MU[i], mat2x2<f32>(L0[i], L1[i]));\n\
             let t = gaussian_weight_tilted(w);\n\
             switch (u32(x) % 6u) {{\n\
                 case 0u: {{ return select(-1.0, e.x, e.y > 0.0); }}\n\
                 case 1u: {{ return select(-1.0, t.mass, t.ok); }}\n\
                 case 2u: {{ return t.mean.x; }}\n\
                 case 3u: {{ return t.mean.y; }}\n\
                 case 4u: {{ return t.cov.x; }}\n\
                 default: {{ return t.cov.y; }}\n\
             }}\n\
         }}\n",
        list(&|c| v2(c.0)),
        list(&|c| v3(c.1)),
        list(&|c| v2(c.2)),
        list(&|c| v3(c.3)),
        list(&|c| format!("{:?}", c.4 as f32)),
        list(&|c| v2(c.5)),
        list(&|c| v2(c.6.x_axis)),
        list(&|c| v2(c.6.y_axis)),
    );
    let xs: Vec<f32> = (0..6 * n).map(|i| i as f32).collect();
    let gpu = eval_unary(&ctx, &library(&extra), "run", &xs);
    let mut worst = 0.0f64;
    for (i, (ea, ma, eb, mb, p, mu, l)) in cases.iter().enumerate() {
        let a = GaussianWeight::along(*ea, ma[0], ma[1], ma[2]).expect("a");
        let b = GaussianWeight::along(*eb, mb[0], mb[1], mb[2]).expect("b");
        let w = a * b.powf(*p);
        let g = |k: usize| f64::from(gpu[6 * i + k]);
        let mut check = |k: usize, want: f64, scale: f64| {
            let err = (g(k) - want).abs() / scale.max(1e-30);
            assert!(
                err <= 1e-4,
                "case {i} output {k}: GPU {:e}, core {want:e}, error {err:.2e}",
                g(k)
            );
            worst = worst.max(err);
        };
        match w.expect_under(*mu, *l) {
            Some(e) => check(0, e, e),
            None => assert_eq!(g(0), -1.0, "case {i}: core has no expectation"),
        }
        let Some((mass, mean, cov)) = w.tilted() else {
            assert_eq!(g(1), -1.0, "case {i}: core has no tilt");
            continue;
        };
        let spread = cov.x_axis.x.max(cov.y_axis.y).sqrt();
        check(1, mass, mass);
        check(2, mean.x, spread);
        check(3, mean.y, spread);
        check(4, cov.x_axis.x, spread * spread);
        check(5, cov.x_axis.y, spread * spread);
    }
    eprintln!("gaussian weights: {n} cases, worst relative error {worst:.2e}");
}

/// The terraces table in the harness's input buffer (σ_f, the gradient covariance, the moments),
/// then the table's rays for views 0–85° and lights along, across and opposite (one below the
/// horizon) on a far and a nearer footprint, and each ray's weights at nine driver values: the
/// GPU's masses and tilts against core's `TransferRays::visibility_weights`.
#[test]
fn wgsl_transfer_rays_match_core_on_the_adapter() {
    use lodestone_core::driver::footprint::FilteredDriver;
    use lodestone_core::eval::masking::transfer_masking_table::TransferRays;
    use lodestone_core::microfacet::masking_shadowing::Correlation;
    use lodestone_core::microfacet::slopes::SlopeCov;
    use lodestone_core::scene::direction::direction;
    let Some(ctx) = lodestone_tests::gpu("the GPU mirror test") else {
        return;
    };
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../presets/terraces.ron"
    ))
    .expect("terraces preset");
    let m = Material::from_ron(&text).expect("terraces");
    let table = TransferMaskingTable::shared(&m.noise().expect("noise"), &m.heights.transfer)
        .expect("a table");
    let r = |x: f64| f64::from(x as f32);
    let mut data: Vec<f32> = vec![table.sigma_f as f32];
    data.extend(table.gradient.map(|g| g as f32));
    data.extend(&table.moments);
    // Core on the f32 header the GPU reads.
    let mut t32 = (*table).clone();
    t32.sigma_f = r(t32.sigma_f);
    t32.gradient = t32.gradient.map(r);
    let [xx, xy, yy] = t32.gradient;
    let sigma_h = r(m.heights.sigma_h);
    // (driver, wo, wi, x)
    type RayCase = (FilteredDriver, glam::DVec3, glam::DVec3, f64);
    let mut cases: Vec<RayCase> = vec![];
    for (scale, mean) in [(1.0, 0.0), (0.6, 0.4)] {
        let d = FilteredDriver {
            mean: r(mean * t32.sigma_f),
            std: r(scale * t32.sigma_f),
            mean_gradient: DVec2::ZERO,
            gradient_cov: SlopeCov {
                xx: r(xx * scale * scale),
                xy: r(xy * scale * scale),
                yy: r(yy * scale * scale),
            },
        };
        for view in [0.0f64, 30.0, 60.0, 75.0, 85.0] {
            for (light, az) in [(60.0f64, 0.0f64), (30.0, 90.0), (60.0, 180.0), (100.0, 0.0)] {
                let v = |w: glam::DVec3| glam::DVec3::new(r(w.x), r(w.y), r(w.z));
                let wo = v(direction(view.to_radians(), 0.3));
                let wi = v(direction(light.to_radians(), 0.3 + az.to_radians()));
                for x in [-2.5, -1.5, -0.9, -0.3, 0.0, 0.4, 1.1, 1.9, 3.0] {
                    cases.push((d, wo, wi, x));
                }
            }
        }
    }
    let n = cases.len();
    let list = |f: &dyn Fn(&RayCase) -> String| cases.iter().map(f).collect::<Vec<_>>().join(", ");
    let v3 = |v: [f64; 3]| format!("vec3<f32>({})", f32s(v));
    // Per case: the driver (mean, std, cov xx yy xy), wo, wi, x, read from private arrays.
    let extra = format!(
        "var<private> DRV: array<vec2<f32>, {n}> = array({});\n\
         var<private> COV: array<vec3<f32>, {n}> = array({});\n\
         var<private> WO: array<vec3<f32>, {n}> = array({});\n\
         var<private> WI: array<vec3<f32>, {n}> = array({});\n\
         var<private> XS: array<f32, {n}> = array({});\n\
         fn run(x: f32) -> f32 {{\n\
             if (x > -1.0e6 + 0.5) {{ return 0.0; }}\n\
             let c = u32(-x - 1.0e6);\n\
             let i = c / 6u;\n\
             let d = FilteredDriver(DRV[i].x, DRV[i].y, vec2<f32>(0.0), COV[i]);\n\
             let lit = WI[i].z > 0.0;\n\
             let rays = transfer_rays_new(0u, d, WO[i], WI[i], lit, {sigma_h:?}, CORRELATION_HEIGHT_DIRECTION);\n\
             let w = visibility_weights(rays, XS[i]);\n\
             let te = gaussian_weight_tilted(w.eye);\n\
             let tj = gaussian_weight_tilted(w.joint);\n\
             switch (c % 6u) {{\n\
                 case 0u: {{ return select(-1.0, te.mass, w.eye.ok && te.ok); }}\n\
                 case 1u: {{ return te.mean.y; }}\n\
                 case 2u: {{ return te.cov.x; }}\n\
                 case 3u: {{ return select(-1.0, tj.mass, w.joint.ok && tj.ok); }}\n\
                 case 4u: {{ return tj.mean.y; }}\n\
                 default: {{ return rays.far; }}\n\
             }}\n\
         }}\n",
        list(&|c| format!("vec2<f32>({:?}, {:?})", c.0.mean as f32, c.0.std as f32)),
        list(&|c| v3([
            c.0.gradient_cov.xx,
            c.0.gradient_cov.yy,
            c.0.gradient_cov.xy
        ])),
        list(&|c| v3(c.1.to_array())),
        list(&|c| v3(c.2.to_array())),
        list(&|c| format!("{:?}", c.3 as f32)),
        sigma_h = sigma_h as f32,
    );
    // The data occupy the front of the buffer (`run` leaves them); case output k is the input
    // −10⁶ − k.
    let mut xs: Vec<f32> = data;
    let first = xs.len();
    xs.extend((0..6 * n).map(|k| -1.0e6 - k as f32));
    let gpu = eval_unary(&ctx, &library(&extra), "run", &xs);
    let gpu = &gpu[first..];
    let mut worst = 0.0f64;
    let mut visible = 0;
    for (i, (d, wo, wi, x)) in cases.iter().enumerate() {
        let rays = TransferRays::new(
            &t32,
            *d,
            (*wo, *wi),
            wi.z > 0.0,
            sigma_h,
            Correlation::HeightDirection,
        );
        let [eye, joint] = rays.visibility_weights(*x);
        let g = |k: usize| f64::from(gpu[6 * i + k]);
        let mut check = |k: usize, want: f64, scale: f64, what: &str| {
            let what = format!(
                "{what}, light azimuth {:.0}°",
                wo.truncate().angle_to(wi.truncate()).to_degrees()
            );
            let err = (g(k) - want).abs() / scale.max(1e-30);
            assert!(
                err <= 1e-3,
                "case {i} ({what}; view {:.1}°, light {:.1}°, x {x}): GPU {:e}, core {want:e}, error {err:.2e}",
                wo.z.acos().to_degrees(),
                wi.z.acos().to_degrees(),
                g(k)
            );
            worst = worst.max(err);
        };
        check(5, rays.far(), 1.0, "far weight");
        match eye.and_then(|e| e.tilted()) {
            Some((mass, mean, cov)) => {
                check(0, mass, mass, "eye mass");
                check(1, mean.y, 1.0, "eye tilt");
                check(2, cov.x_axis.x, 1.0, "eye spread");
                visible += usize::from(mass < 0.9);
            }
            None => assert_eq!(g(0), -1.0, "case {i}: core sees nothing"),
        }
        match joint.and_then(|j| j.tilted()) {
            Some((mass, mean, _)) => {
                check(3, mass, mass, "joint mass");
                // Where the two rays' masses tie within f32 (a light opposite the eye at the
                // same angle) the GPU may take the other as the more masked one: lo·hi^k and
                // hi·lo^k differ by (1 − k) of their tilts, 0.07 × 0.035 on terraces.
                check(4, mean.y, 10.0, "joint tilt");
            }
            None => assert_eq!(g(3), -1.0, "case {i}: core lights nothing"),
        }
    }
    eprintln!("transfer rays: {n} cases ({visible} masked), worst error {worst:.2e}");
    assert!(visible >= 50, "{visible}");
}
