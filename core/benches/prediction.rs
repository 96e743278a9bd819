//! What an adaptive ground truth's prediction costs on the CPU (#18 §1): per pixel, the filtered
//! view (the truth's expected value) and one ray's predicted moments, over a 64 × 40 view of the
//! default preset as `lodestone report` plans it. `cargo bench -p lodestone-core --bench prediction`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use lodestone_core::eval::{Evaluator, Method};
use lodestone_core::material::Material;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use std::hint::black_box;

fn prediction(c: &mut Criterion) {
    let m = Material::from_ron(include_str!("../../presets/default.ron")).expect("preset");
    let e = Evaluator::new(&m).expect("evaluator");
    let wi = direction(0.0, 0.0);
    let size = (64u32, 40u32);
    let mut g = c.benchmark_group("prediction 64x40");
    g.sample_size(10);
    for view in [60.0, 80.0] {
        let camera = Camera {
            elevation_deg: view,
            distance: 6.0,
            ..Default::default()
        };
        let lifted = e.surface.clear_camera(&camera);
        let queries: Vec<_> = (0..size.0 * size.1)
            .filter_map(|p| {
                let px = DVec2::new(f64::from(p % size.0) + 0.5, f64::from(p / size.0) + 0.5);
                e.view_pixel_query(Shape::Plane, &lifted, &camera, px, size, wi)
            })
            .collect();
        g.bench_function(format!("{view}° whole (predict_truth)"), |b| {
            b.iter(|| black_box(e.predict_truth(&camera, size, wi)))
        });
        g.bench_function(format!("{view}° queries only"), |b| {
            b.iter(|| {
                (0..size.0 * size.1)
                    .filter_map(|p| {
                        let px =
                            DVec2::new(f64::from(p % size.0) + 0.5, f64::from(p / size.0) + 0.5);
                        e.view_pixel_query(Shape::Plane, &lifted, &camera, px, size, wi)
                    })
                    .count()
            })
        });
        g.bench_function(
            format!("{view}° filtered view (query included), one thread"),
            |b| {
                b.iter(|| {
                    for p in 0..size.0 * size.1 {
                        let px =
                            DVec2::new(f64::from(p % size.0) + 0.5, f64::from(p / size.0) + 0.5);
                        black_box(e.plane_pixel(Method::Filtered, &camera, px, size, wi));
                    }
                })
            },
        );
        g.bench_function(format!("{view}° ray moments, one thread"), |b| {
            b.iter(|| {
                for (cfg, _, _) in &queries {
                    black_box(e.predicted_ray_moments(cfg));
                }
            })
        });
    }
    g.finish();
}

criterion_group!(benches, prediction);
criterion_main!(benches);
