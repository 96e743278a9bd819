//! The Object window's background thread: it builds the octree, traces the voxel views on the
//! adapter and the CPU, and the truth, and hands each image back as it finishes.

use super::*;

/// The background thread: builds, renders, compares; later jobs of a kind replace earlier ones.
/// A voxel frame that would be slow is drawn first at a fraction of the size, and the full frame
/// only when no newer camera or build is waiting by then: while the camera moves the view keeps
/// up at preview size and sharpens when it rests.
pub(super) fn run(
    jobs: Receiver<Job>,
    shared: Arc<Mutex<Shared>>,
    device: DeviceSource,
    repaint: impl Fn(),
) {
    crate::editor::priority::lower_current_thread();
    let mut scene: Option<(ObjectScene, Material, Option<GpuObject>)> = None;
    let table = MaskTable::new();
    let mut backlog: Vec<Job> = Vec::new();
    let mut last_full_s = 0.0;
    loop {
        let mut batch = std::mem::take(&mut backlog);
        if batch.is_empty() {
            match jobs.recv() {
                Ok(j) => batch.push(j),
                Err(_) => break,
            }
        }
        batch.extend(jobs.try_iter());
        let (mut build, mut render, mut compare) = (None, None, None);
        for job in batch {
            match job {
                Job::Build(b) => build = Some(b),
                Job::Render(s) => render = Some(s),
                Job::Compare(s, r) => compare = Some((s, r)),
            }
        }
        if let Some(b) = build {
            let (material, shape, depth) = *b;
            set(&shared, |s| {
                s.busy = true;
                s.status = format!("Voxelising to depth {depth}…");
            });
            repaint();
            scene = None;
            last_full_s = 0.0;
            match ObjectScene::build(&material, shape, depth) {
                Ok(sc) => {
                    let gpu = (device == DeviceSource::Headless)
                        .then(|| GpuObject::new(&sc.field))
                        .and_then(|g| {
                            g.inspect_err(|e| log::warn!("object view on the CPU: {e:#}"))
                                .ok()
                        });
                    let mib = sc.memory.iter().map(|l| l.gpu_bytes).sum::<usize>() as f64
                        / f64::from(1 << 20);
                    let status = format!(
                        "Octree: depth {depth}, {} voxels at the finest level, {mib:.2} MiB; built in {:.1} s; voxel view on {}",
                        sc.memory.last().map_or(0, |l| l.voxels),
                        sc.build_seconds,
                        gpu.as_ref()
                            .map_or("the CPU".to_string(), |g| g.ctx.describe())
                    );
                    set(&shared, |s| {
                        s.status = status;
                        s.voxel = None;
                        s.compare = None;
                    });
                    scene = Some((sc, material, gpu));
                }
                Err(e) => set(&shared, |s| s.status = format!("{e:#}")),
            }
        }
        let Some((sc, material, gpu)) = &scene else {
            set(&shared, |s| s.busy = false);
            repaint();
            continue;
        };
        if let Some(shot) = render {
            let light = ObjectLighting::of_material(material, shot.light);
            let draw = |shot: &Shot| {
                let started = std::time::Instant::now();
                let px = match gpu {
                    Some(g) => g
                        .render(
                            &masks_shot(&shot.camera, &light, shot.shadows, shot.size, shot.lens),
                            false,
                        )
                        .map(|(p, _)| p)
                        .map_err(|e| format!("{e:#}")),
                    None => Ok(cpu_masks(sc, &table, &light, shot)),
                };
                let secs = started.elapsed().as_secs_f64();
                set(&shared, |s| match px {
                    Ok(p) => s.voxel = Some((shot.size.0, shot.size.1, p, secs)),
                    Err(e) => s.status = e,
                });
                repaint();
                secs
            };
            let k = preview_divisor(last_full_s);
            if k > 1 {
                let (w, h) = shot.size;
                draw(&Shot {
                    size: ((w / k).max(1), (h / k).max(1)),
                    ..shot
                });
                backlog.extend(jobs.try_iter());
                if backlog
                    .iter()
                    .any(|j| matches!(j, Job::Render(_) | Job::Build(_)))
                {
                    // A newer camera or object: its frame replaces this one's full size.
                    if let Some((s, r)) = compare {
                        backlog.push(Job::Compare(s, r));
                    }
                    continue;
                }
            }
            last_full_s = draw(&shot);
        }
        if let Some((shot, rays)) = compare {
            set(&shared, |s| {
                s.status = format!("Ground truth at {rays} rays a pixel…")
            });
            repaint();
            let light = ObjectLighting::of_material(material, shot.light);
            let color = |f: f64| sc.color(f);
            let truth = ObjectTruth {
                object: &sc.object,
                lighting: &light,
                color: &color,
                shadows: shot.shadows,
            };
            let tracer = ConeTracer {
                field: &sc.field,
                table: &table,
                lighting: &light,
                shadows: shot.shadows,
            };
            let modes = [
                Compositing::Nearest,
                Compositing::AlphaBlend,
                Compositing::Masks,
            ];
            let mut images = ObjectImages::render(
                &truth,
                &tracer,
                &shot.camera,
                shot.size,
                rays as usize,
                &modes,
                shot.lens,
            );
            set(&shared, |s| {
                s.status = "Refining the ground truth to 0.5%…".into()
            });
            repaint();
            images.converge_truth(&truth, &shot.camera, shot.lens, 0.005, 4096);
            let errors = images.errors();
            let names = ["nearest voxels", "alpha blended", "ours (masks)"];
            let mut panels: Vec<(&'static str, Vec<ConePixel>)> = names
                .into_iter()
                .zip(images.views.into_iter().map(|v| v.1))
                .collect();
            panels.push(("ground truth", images.truth));
            set(&shared, |s| {
                s.compare = Some((shot.size.0, shot.size.1, panels, errors));
                s.status = "Comparison done".into();
            });
        }
        set(&shared, |s| s.busy = false);
        repaint();
    }
}

/// The masks image on the CPU (no adapter), rows in parallel.
pub(super) fn cpu_masks(
    sc: &ObjectScene,
    table: &MaskTable,
    light: &lodestone_core::object::shading::ObjectLighting,
    shot: &Shot,
) -> Vec<ConePixel> {
    use rayon::prelude::*;
    let tracer = ConeTracer {
        field: &sc.field,
        table,
        lighting: light,
        shadows: shot.shadows,
    };
    let (w, h) = shot.size;
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let cone = pixel_cone(
                &shot.camera,
                f64::from(i % w) + 0.5,
                f64::from(i / w) + 0.5,
                w,
                h,
            )
            .with_lens(shot.lens.radius, shot.lens.focus);
            tracer.trace(&cone, Compositing::Masks)
        })
        .collect()
}

pub(super) fn color_image(w: u32, h: u32, px: &[ConePixel]) -> egui::ColorImage {
    let bg = [40.0 / 255.0, 40.0 / 255.0, 48.0 / 255.0];
    let rgba: Vec<u8> = px
        .iter()
        .flat_map(|p| {
            let c: [u8; 3] = [0, 1, 2].map(|k| {
                let srgb = linear_to_srgb(p.color[k].clamp(0.0, 1.0));
                let v = srgb + (1.0 - p.coverage.clamp(0.0, 1.0)) * bg[k];
                (v.clamp(0.0, 1.0) * 255.0).round() as u8
            });
            [c[0], c[1], c[2], 255]
        })
        .collect();
    egui::ColorImage::from_rgba_unmultiplied([w as usize, h as usize], &rgba)
}
