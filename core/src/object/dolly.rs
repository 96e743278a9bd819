//! Popping between octree levels (#19, [HN12 Sec. 5.3]): a cone's level follows its radius, so as
//! the camera dollies in every pixel crosses from one level to the next. Blending the two levels
//! around the cone's (quadrilinear lookups) should make that crossing smooth; nearest voxels at the
//! rounded level jump.
//!
//! On a real dolly the relief also slides under each pixel, which changes the image whatever the
//! filtering, so the level's own part is isolated by a **footprint sweep**: the camera held still
//! and only the cones' radius scaled in small geometric steps (the levels every pixel reads move
//! exactly as on a dolly, nothing else does). Per step, the image's change (mean absolute per-pixel
//! change of colour and coverage); the **jump ratio** is the largest step's change over the mean
//! step's: 1 when every step changes the image alike, about the number of steps when one step holds
//! all the change (a switch of levels). The dolly itself is measured the same way for the record.

use crate::object::cone_trace::{Compositing, ConeTracer};
use crate::object::object_truth::pixel_cone;
use crate::scene::camera::Camera;

/// One frame: `[r, g, b, coverage]` per pixel, row-major.
pub type Frame = Vec<[f64; 4]>;

/// One frame per `(camera, radius scale)`: each pixel's cone of `camera`, its spread times the
/// scale, traced with `mode`.
pub fn frames(
    tracer: &ConeTracer,
    shots: &[(Camera, f64)],
    (width, height): (u32, u32),
    mode: Compositing,
) -> Vec<Frame> {
    use rayon::prelude::*;
    shots
        .par_iter()
        .map(|(cam, scale)| {
            (0..width * height)
                .map(|i| {
                    let mut cone = pixel_cone(
                        cam,
                        f64::from(i % width) + 0.5,
                        f64::from(i / width) + 0.5,
                        width,
                        height,
                    );
                    cone.spread *= scale;
                    let p = tracer.trace(&cone, mode);
                    [p.color[0], p.color[1], p.color[2], p.coverage]
                })
                .collect()
        })
        .collect()
}

/// The frame-to-frame changes (module docs), one fewer than frames.
pub fn frame_changes(frames: &[Frame]) -> Vec<f64> {
    frames
        .windows(2)
        .map(|w| {
            let n = w[0].len().max(1) as f64;
            w[0].iter()
                .zip(&w[1])
                .map(|(a, b)| (0..4).map(|k| (a[k] - b[k]).abs()).sum::<f64>())
                .sum::<f64>()
                / n
        })
        .collect()
}

/// Per pixel covered in every frame, the [`jump_ratio`] of its own colour's changes; their mean
/// (1 when no pixel is covered throughout). A pixel whose colour moves smoothly reads near 1; one
/// whose colour holds and then jumps reads near the number of steps over its jumps.
pub fn pixel_jump_ratio(frames: &[Frame]) -> f64 {
    let Some(first) = frames.first() else {
        return 1.0;
    };
    let ratios: Vec<f64> = (0..first.len())
        .filter(|&i| frames.iter().all(|f| f[i][3] >= 0.999))
        .map(|i| {
            let c: Vec<f64> = frames
                .windows(2)
                .map(|w| (0..3).map(|k| (w[0][i][k] - w[1][i][k]).abs()).sum())
                .collect();
            jump_ratio(&c)
        })
        .collect();
    if ratios.is_empty() {
        return 1.0;
    }
    ratios.iter().sum::<f64>() / ratios.len() as f64
}

/// The jump ratio of a sequence of changes: the largest over the mean (1 for an empty, constant or
/// all-zero sequence; non-finite entries are left out).
pub fn jump_ratio(changes: &[f64]) -> f64 {
    let v: Vec<f64> = changes.iter().copied().filter(|c| c.is_finite()).collect();
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    let max = v.iter().copied().fold(0.0, f64::max);
    if mean > 0.0 { max / mean } else { 1.0 }
}

/// `n` geometric steps from `a` to `b` (`a` alone when n < 2).
pub fn geometric(a: f64, b: f64, n: usize) -> Vec<f64> {
    if n < 2 {
        return vec![a];
    }
    (0..n)
        .map(|i| a * (b / a).powf(i as f64 / (n - 1) as f64))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::object::base_shape::BaseShape;
    use crate::object::coverage_mask::MaskTable;
    use crate::object::displaced::DisplacedObject;
    use crate::object::octree::VoxelOctree;
    use crate::object::shading::ObjectLighting;
    use crate::object::voxel_field::VoxelField;

    use crate::object::test_camera as camera;

    fn with_tracer<R>(depth: u32, body: impl FnOnce(&ConeTracer) -> R) -> R {
        let m = Material::default();
        let obj = DisplacedObject::new(&m, BaseShape::Sphere { radius: 1.0 }).unwrap();
        let ev = crate::eval::Evaluator::new(&m).unwrap();
        let tree = VoxelOctree::of_object(&obj, |f| ev.color_at(f), depth, 4.0, 1);
        let field = VoxelField::new(&tree);
        let table = MaskTable::new();
        let lighting =
            ObjectLighting::of_material(&m, glam::DVec3::new(0.4, -0.3, 0.8).normalize());
        body(&ConeTracer {
            field: &field,
            table: &table,
            lighting: &lighting,
            shadows: true,
        })
    }

    /// The footprint sweep of `mode`: distance 4, the radius scaled over one octave in `steps`.
    fn sweep(tracer: &ConeTracer, mode: Compositing, steps: usize, size: (u32, u32)) -> Vec<Frame> {
        let shots: Vec<_> = geometric(1.0, 2.0, steps)
            .into_iter()
            .map(|s| (camera(4.0), s))
            .collect();
        frames(tracer, &shots, size, mode)
    }

    #[test]
    fn the_ratio_flags_a_jump() {
        assert_eq!(jump_ratio(&[]), 1.0);
        assert_eq!(jump_ratio(&[1.0, 1.0, 1.0]), 1.0);
        assert_eq!(jump_ratio(&[0.0, 0.0, 4.0, 0.0]), 4.0);
        assert_eq!(jump_ratio(&[0.0, 0.0]), 1.0);
        assert_eq!(jump_ratio(&[f64::NAN, 2.0]), 1.0);
        assert_eq!(geometric(1.0, 4.0, 3), vec![1.0, 2.0, 4.0]);
        assert_eq!(geometric(3.0, 4.0, 1), vec![3.0]);
    }

    /// Over one octave of cone radius in 24 steps (every pixel crosses one level boundary), each
    /// covered pixel's colour under the masks changes evenly (mean jump ratio 2.94, bound 4; a
    /// level switch in one step would read up to 24), nearest voxels' in jumps (6.70, more than
    /// twice). With the levels rounded instead of blended the masks read 4.71 and the bound fails.
    #[test]
    fn masks_blend_levels_without_popping() {
        with_tracer(5, |tracer| {
            let fm = sweep(tracer, Compositing::Masks, 24, (32, 24));
            let fnear = sweep(tracer, Compositing::Nearest, 24, (32, 24));
            let (masks, nearest) = (pixel_jump_ratio(&fm), pixel_jump_ratio(&fnear));
            eprintln!(
                "pixel jump ratio: masks {masks:.2}, nearest {nearest:.2}; image: masks {:.2}, nearest {:.2}",
                jump_ratio(&frame_changes(&fm)),
                jump_ratio(&frame_changes(&fnear))
            );
            assert!(masks < 4.0, "masks {masks}");
            assert!(nearest > 2.0 * masks, "nearest {nearest} masks {masks}");
        });
    }

    /// The tables (#19): `cargo test --release -p lodestone-core --lib -- --ignored --nocapture
    /// popping_sweeps`: the footprint sweep (two octaves in 96 steps, depth 7) and a slow dolly
    /// (distance 8 to 2 in 140 frames) per mode.
    #[test]
    #[ignore = "a measurement: prints each mode's jump ratios"]
    fn popping_sweeps() {
        with_tracer(7, |tracer| {
            let dolly: Vec<_> = geometric(8.0, 2.0, 140)
                .into_iter()
                .map(|d| (camera(d), 1.0))
                .collect();
            for mode in [
                Compositing::Nearest,
                Compositing::AlphaBlend,
                Compositing::Masks,
            ] {
                let shots: Vec<_> = geometric(1.0, 4.0, 96)
                    .into_iter()
                    .map(|s| (camera(4.0), s))
                    .collect();
                let ff = frames(tracer, &shots, (64, 48), mode);
                let fd = frames(tracer, &dolly, (64, 48), mode);
                let (f, d) = (frame_changes(&ff), frame_changes(&fd));
                eprintln!(
                    "{mode:?}: footprint sweep per pixel {:.2}, image {:.2} (mean step {:.5}); dolly per pixel {:.2}, image {:.2} (mean step {:.5})",
                    pixel_jump_ratio(&ff),
                    jump_ratio(&f),
                    f.iter().sum::<f64>() / f.len() as f64,
                    pixel_jump_ratio(&fd),
                    jump_ratio(&d),
                    d.iter().sum::<f64>() / d.len() as f64,
                );
            }
        });
    }
}
