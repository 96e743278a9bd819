//! The object view's WGSL cone tracer against core's (#19, [HN12 Alg. 1]): the same octree, as the
//! GPU stores it (f16 descriptors decoded back for core), traced by both over every pixel of small
//! images of a displaced sphere, with masks, alpha blending and nearest voxels, shadow cones on, from
//! afar, at middle distance, filling the view, and through a lens (depth of field). f32 against f64: a sub-ray whose sample lies on an
//! element's edge can fall either side, so pixels are compared in bulk (the share within a tight
//! tolerance, the mean over the image) and no pixel may be off by more than a few sub-rays' worth.

use lodestone_core::eval::Evaluator;
use lodestone_core::material::Material;
use lodestone_core::object::base_shape::BaseShape;
use lodestone_core::object::cone_trace::{Compositing, ConeTracer};
use lodestone_core::object::coverage_mask::MaskTable;
use lodestone_core::object::displaced::DisplacedObject;
use lodestone_core::object::object_truth::{Lens, pixel_cone};
use lodestone_core::object::octree::VoxelOctree;
use lodestone_core::object::shading::ObjectLighting;
use lodestone_core::object::voxel_field::VoxelField;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_render::object::object_view::{ObjectShot, ObjectView};
use lodestone_render::object::voxel_store::GpuVoxels;

fn camera(distance: f64) -> Camera {
    Camera {
        elevation_deg: 60.0,
        azimuth_deg: 30.0,
        distance,
        target: [0.0, 0.0],
        fov_deg: 30.0,
    }
}

#[test]
fn cone_traced_pixels_match_core() {
    let Some(ctx) = lodestone_tests::gpu("the object view test") else {
        return;
    };
    let material = Material::default();
    let ev = Evaluator::new(&material).unwrap();
    let object = DisplacedObject::new(&material, BaseShape::Sphere { radius: 1.0 }).unwrap();
    let tree = VoxelOctree::of_object(&object, |f| ev.color_at(f), 5, 4.0, 1);
    let voxels = GpuVoxels::encode(&VoxelField::new(&tree));
    let field = voxels.decode();
    let table = MaskTable::new();
    let lighting = ObjectLighting::of_material(
        &material,
        direction(37f64.to_radians(), (-37f64).to_radians()),
    );
    let view = ObjectView::new(&ctx);
    let octree = view.upload(&ctx, &voxels).unwrap();
    let (w, h) = (32u32, 24u32);
    // The third distance through a lens (radius 0.2, focused in front of the sphere).
    for (distance, lens) in [
        (8.0, Lens::PINHOLE),
        (4.0, Lens::PINHOLE),
        (2.2, Lens::PINHOLE),
        (
            4.0,
            Lens {
                radius: 0.2,
                focus: 2.0,
            },
        ),
    ] {
        let cam = camera(distance);
        for mode in [
            Compositing::Masks,
            Compositing::AlphaBlend,
            Compositing::Nearest,
        ] {
            let tracer = ConeTracer {
                field: &field,
                table: &table,
                lighting: &lighting,
                shadows: true,
            };
            let shot = ObjectShot {
                camera: &cam,
                lighting: &lighting,
                mode,
                shadows: true,
                size: (w, h),
                lens,
            };
            let gpu = view.render(&ctx, &octree, &shot).unwrap();
            assert_eq!(gpu.cut, 0, "{mode:?} at {distance}: the adapter cut loops");
            let (mut close, mut worst, mut sum_gpu, mut sum_cpu, mut covered) =
                (0usize, 0.0f64, 0.0, 0.0, 0usize);
            let mut worst_cover = 0.0f64;
            for y in 0..h {
                for x in 0..w {
                    let c = tracer.trace(
                        &pixel_cone(&cam, f64::from(x) + 0.5, f64::from(y) + 0.5, w, h)
                            .with_lens(lens.radius, lens.focus),
                        mode,
                    );
                    let g = gpu.pixels[(y * w + x) as usize];
                    let d = (0..3)
                        .map(|k| (f64::from(g[k]) - c.color[k]).abs())
                        .fold(0.0, f64::max);
                    let dc = (f64::from(g[3]) - c.coverage).abs();
                    worst = worst.max(d);
                    worst_cover = worst_cover.max(dc);
                    if d <= 0.01 && dc <= 2.5 / 64.0 {
                        close += 1;
                    }
                    if c.coverage > 0.0 {
                        covered += 1;
                    }
                    sum_gpu += f64::from(g[0] + g[1] + g[2]);
                    sum_cpu += c.color.iter().sum::<f64>();
                }
            }
            let n = (w * h) as usize;
            let mean = (sum_gpu - sum_cpu).abs() / sum_cpu.max(1e-9);
            eprintln!(
                "{mode:?} d {distance}: {covered} covered, {close}/{n} close, worst colour {worst:.4}, worst coverage {worst_cover:.3}, image mean {:.3}%",
                100.0 * mean
            );
            assert!(
                covered > 30,
                "{mode:?} at {distance}: the sphere is in view"
            );
            assert!(
                close * 100 >= n * 97,
                "{mode:?} at {distance}: {close} of {n}"
            );
            assert!(mean < 0.005, "{mode:?} at {distance}: image mean {mean}");
            assert!(
                worst < 0.25 && worst_cover <= 0.2,
                "{mode:?} at {distance}: {worst} {worst_cover}"
            );
        }
    }
}

/// The adapter's loop budget (Mesa: 65535 iterations an invocation) holds on the longest cones: a
/// torus filling the view, cones passing through its hole and along its inner side, shadow cones
/// on. Every pixel finishes (no loop cut) in each mode.
#[test]
fn long_cones_fit_the_loop_budget() {
    let Some(ctx) = lodestone_tests::gpu("the object loop budget test") else {
        return;
    };
    let material = Material::default();
    let ev = Evaluator::new(&material).unwrap();
    let shape = BaseShape::Torus {
        major: 2.0,
        minor: 0.8,
    };
    let object = DisplacedObject::new(&material, shape).unwrap();
    let tree = VoxelOctree::of_object(&object, |f| ev.color_at(f), 7, 2.0, 1);
    let voxels = GpuVoxels::encode(&VoxelField::new(&tree));
    let lighting = ObjectLighting::of_material(
        &material,
        direction(37f64.to_radians(), (-37f64).to_radians()),
    );
    let view = ObjectView::new(&ctx);
    let octree = view.upload(&ctx, &voxels).unwrap();
    let cam = camera(3.0);
    for mode in [
        Compositing::Masks,
        Compositing::AlphaBlend,
        Compositing::Nearest,
    ] {
        let shot = ObjectShot {
            camera: &cam,
            lighting: &lighting,
            mode,
            shadows: true,
            size: (160, 120),
            lens: Lens::PINHOLE,
        };
        let img = view.render(&ctx, &octree, &shot).unwrap();
        eprintln!("{mode:?}: {} of {} pixels cut", img.cut, 160 * 120);
        assert_eq!(img.cut, 0, "{mode:?}");
    }
}
