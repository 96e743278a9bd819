//! The ray march on the CPU (core f64): the reference march against the fast one, per preset and
//! view angle, one batch of primary rays each (issue #15); and the object's surface sampling (every
//! crossing of three line grids, what the voxel octree is built from, #19) with either march.
//! `cargo bench -p lodestone-core --bench march`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use lodestone_core::material::Material;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::march::March;
use lodestone_core::scene::surface::{Surface, Trace};
use std::hint::black_box;

/// 64 primary rays at `view_deg` from the normal, spread over azimuths and start points.
fn rays(s: &Surface, view_deg: f64) -> Vec<(DVec3, DVec3)> {
    (0..64)
        .map(|i| {
            let d = -direction(view_deg.to_radians(), 0.1 * i as f64);
            let o = DVec3::new(0.37 * i as f64, -0.23 * i as f64, s.h_max * 1.001 + 1e-6);
            (o, d)
        })
        .collect()
}

fn march(c: &mut Criterion) {
    let presets = [
        ("default", include_str!("../../presets/default.ron")),
        ("sponge", include_str!("../../presets/sponge.ron")),
    ];
    let mut g = c.benchmark_group("march 64 rays");
    g.sample_size(10);
    for (name, text) in presets {
        let m = Material::from_ron(text).expect("preset");
        let fast = Surface::new(&m).expect("noise driver");
        let reference = Surface {
            march: March::Reference,
            ..fast.clone()
        };
        for view in [60.0, 80.0] {
            let rs = rays(&fast, view);
            for (label, s) in [("reference", &reference), ("fast", &fast)] {
                g.bench_function(format!("{name} {view}° {label}"), |b| {
                    b.iter(|| {
                        rs.iter()
                            .filter(|(o, d)| matches!(s.march(*o, *d), Trace::Hit(_)))
                            .count()
                    })
                });
            }
            black_box(&rs);
        }
    }
    g.finish();
}

/// The default material on a unit sphere, its surface sampled by lines 0.04 apart (about 8 000
/// lines; the depth-7 octree's lines are 0.011 apart), with the reference and the fast march.
fn object_samples(c: &mut Criterion) {
    use lodestone_core::object::base_shape::BaseShape;
    use lodestone_core::object::displaced::DisplacedObject;
    let m = Material::default();
    let fast = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.0 }).expect("object");
    let reference = fast.clone().with_march(March::Reference);
    let mut g = c.benchmark_group("object surface samples");
    g.sample_size(10);
    for (label, o) in [("reference", &reference), ("fast", &fast)] {
        g.bench_function(format!("sphere, spacing 0.04, {label}"), |b| {
            b.iter(|| black_box(o.surface_samples(0.04, 1).len()))
        });
    }
    g.finish();
}

criterion_group!(benches, march, object_samples);
criterion_main!(benches);
