//! Count the pixels where the GPU's naive view differs from core's evaluation of the same pixel, at a
//! grazing camera (the check that found llvmpipe's shared loop limit, see material.wgsl UNROLL).
//! Usage: `cargo run --release -p lodestone-render --example naive_vs_core [PRESET]`.
use glam::DVec2;
use lodestone_core::eval::{Evaluator, Method};
use lodestone_core::material::Material;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::{GpuContext, GpuMaterial, Renderer, Scene, ViewMode};

fn main() {
    let preset = std::env::args()
        .nth(1)
        .unwrap_or("presets/snow-under-sky.ron".into());
    let m = Material::from_ron(&std::fs::read_to_string(&preset).unwrap()).unwrap();
    let p = Evaluator::new(&m).unwrap();
    let r = Renderer::new(GpuContext::new_headless().unwrap());
    let camera = Camera {
        elevation_deg: 78.0,
        azimuth_deg: 0.0,
        distance: 5.0,
        target: [0.0, 0.0],
        fov_deg: 35.0,
    };
    let light = direction(45f64.to_radians(), 120f64.to_radians());
    let scene = Scene {
        camera,
        light,
        shape: Shape::Plane,
    };
    let gm =
        GpuMaterial::new(r.context(), &p, camera.target).expect("the material fits the adapter");
    let (w, h) = (400u32, 300u32);
    let img = r.render(&gm, &scene, ViewMode::Naive, (w, h), 1).unwrap();
    let mut bad = 0;
    for y in 0..h {
        for x in 0..w {
            let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
            let want = p.plane_pixel(Method::Naive, &camera, c, (w, h), light);
            let got = img.rgb(x, y);
            if (0..3).any(|k| (f64::from(got[k]) - want[k]).abs() > 0.05 * want[k].abs() + 0.01) {
                bad += 1;
            }
        }
    }
    println!("{preset}: {bad} of {} pixels differ by > 5% + 0.01", w * h);
}
