//! Tests of [`super`].

use super::*;
use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;

fn request(generation: u64, spp: u32) -> Request {
    Request {
        generation,
        material: Arc::new(Material::default()),
        image: None,
        environment: None,
        measured: None,
        scene: Scene {
            camera: Camera::default(),
            light: direction(0.5, 1.0),
            shape: Shape::Plane,
        },
        size: [32, 24],
        modes: vec![ViewMode::Naive, ViewMode::Filtered, ViewMode::Truth],
        truth_spp: spp,
        max_scale: 1.0,
        adaptive_truth: false,
        march: March::Fast,
    }
}

/// A headless worker whose device is up, or `None` (logged as skipped as `test`) without an
/// adapter.
fn ready_worker(test: &str) -> Option<Worker> {
    let w = Worker::spawn(DeviceSource::Headless, || {});
    match w.wait(Duration::from_secs(60)) {
        Some(Event::Ready { .. }) => Some(w),
        Some(Event::NoAdapter(e)) => {
            lodestone_tests::skip(test, e);
            None
        }
        other => panic!("unexpected {other:?}"),
    }
}

/// A panic while serving (as a driver's) ends the thread with `Stopped` and its message,
/// instead of leaving the window waiting; dropping the worker then joins it cleanly.
#[test]
fn a_panic_in_the_render_thread_is_reported() {
    let Some(w) = ready_worker("the worker panic test") else {
        return;
    };
    w.request(request(PANIC_GENERATION, 1));
    match w.wait(Duration::from_secs(60)) {
        Some(Event::Stopped(msg)) => assert!(msg.contains("injected"), "{msg}"),
        other => panic!("unexpected {other:?}"),
    }
    drop(w);
}

/// The worker renders every requested mode, refines to full size, and accumulates exactly
/// the requested truth samples.
#[test]
fn serves_every_mode_up_to_full_resolution() {
    let Some(w) = ready_worker("the worker test") else {
        return;
    };
    w.request(request(7, 3));
    let mut full = Vec::new();
    let mut truth_spp = 0;
    while let Some(ev) = w.wait(Duration::from_secs(120)) {
        let Event::Frame(f) = ev else {
            panic!("unexpected {ev:?}")
        };
        assert_eq!(f.generation, 7);
        assert!(f.image.pixels.iter().flatten().all(|v| v.is_finite()));
        if f.scale == 1.0 {
            assert_eq!((f.image.width, f.image.height), (32, 24));
            full.push(f.mode);
        }
        if f.mode == ViewMode::Truth {
            truth_spp = f.samples;
            if f.samples == 3 {
                break;
            }
        }
    }
    assert!(full.contains(&ViewMode::Naive) && full.contains(&ViewMode::Filtered));
    assert_eq!(truth_spp, 3);
}

/// Adaptive ground truth spends the requested rays per pixel on average, gives pixels
/// different counts, traces exactly those (each pixel's weight is its count), and gives the
/// pixels the prediction calls noisier more rays.
#[test]
fn adaptive_truth_gives_each_pixel_its_planned_rays() {
    let w = Worker::spawn(DeviceSource::Headless, || {});
    match w.wait(Duration::from_secs(60)) {
        Some(Event::Ready { adapter, .. }) => {
            lodestone_tests::ran("adaptive_truth_gives_each_pixel_its_planned_rays", &adapter)
        }
        Some(Event::NoAdapter(e)) => {
            lodestone_tests::skip("the adaptive worker test", e);
            return;
        }
        other => panic!("unexpected {other:?}"),
    }
    let mut req = request(9, 8);
    req.adaptive_truth = true;
    req.modes = vec![ViewMode::Truth];
    // Grazing, the sun low on the far side: glints and shadows make the noise uneven.
    req.scene.camera.elevation_deg = 75.0;
    req.scene.camera.distance = 3.0;
    req.scene.light = direction(1.2, 0.0);
    w.request(req);
    let mut last = None;
    while let Some(ev) = w.wait(Duration::from_secs(300)) {
        let Event::Frame(f) = ev else {
            panic!("unexpected {ev:?}")
        };
        if f.mode != ViewMode::Truth {
            continue;
        }
        assert!(f.image.pixels.iter().flatten().all(|v| v.is_finite()));
        let done = f.samples >= 8;
        last = Some(f);
        if done {
            break;
        }
    }
    let f = last.expect("a truth frame");
    let rays = f.rays.as_deref().expect("an adaptive truth's ray counts");
    let sd = f.predicted_sd.as_deref().expect("its prediction");
    let n = 32 * 24;
    assert_eq!((rays.len(), sd.len()), (n, n));
    // The predicted bandwidth came with it: the sky 0, the horizon Nyquist's, the rest between.
    let b = f.predicted_bandwidth.as_deref().expect("its bandwidth");
    assert_eq!(b.len(), n);
    assert!(b.iter().all(|v| (0.0..=0.5).contains(v)), "{b:?}");
    assert!(b.contains(&0.0) && b.contains(&0.5) && b.iter().any(|v| *v > 0.0 && *v < 0.5));
    let total: u32 = rays.iter().sum();
    assert!(total.abs_diff(8 * n as u32) <= 1, "{total} rays");
    // Traced as planned: each pixel's weight is its ray count.
    for (p, r) in f.image.pixels.iter().zip(rays) {
        assert_eq!(p[3], *r as f32);
    }
    let (lo, hi) = (rays.iter().min().unwrap(), rays.iter().max().unwrap());
    assert!(*lo >= 1 && hi > lo, "rays {lo}..{hi}");
    // Noisier predicted pixels got more rays on average.
    let cost = f.cost.as_deref().expect("its costs");
    assert!(cost.iter().all(|c| *c >= 1.0));
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|a, b| sd[*a].total_cmp(&sd[*b]));
    let mean = |ix: &[usize]| ix.iter().map(|&p| f64::from(rays[p])).sum::<f64>() / ix.len() as f64;
    let (quiet, noisy) = (mean(&order[..n / 4]), mean(&order[3 * n / 4..]));
    eprintln!("rays {lo}..{hi}: quietest quarter {quiet}, noisiest {noisy}");
    assert!(
        noisy > 1.5 * quiet,
        "rays: quietest quarter {quiet}, noisiest {noisy}"
    );
}

#[test]
fn reports_a_missing_adapter() {
    let w = Worker::spawn(DeviceSource::Unavailable, || {});
    assert!(matches!(
        w.wait(Duration::from_secs(10)),
        Some(Event::NoAdapter(_))
    ));
}

/// Switch the worker through `presets` of the library (all of them when empty), each with the
/// light on either side of the normal (each scene's pipeline and the other shadow variant's), and
/// wait for each request's frames; panics on any other event (a stopped render thread).
fn switch_through(test: &str, presets: &[&str]) {
    let Some(w) = ready_worker(test) else {
        return;
    };
    let mut generation = 100;
    for (path, text) in lodestone_tests::presets() {
        if !presets.is_empty() && !presets.iter().any(|p| path.ends_with(&format!("/{p}.ron"))) {
            continue;
        }
        let m = Material::from_ron(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
        let image = lodestone_tests::prepare(&path, &m)
            .surface
            .driver
            .image()
            .map(|t| t.image.clone());
        for light in [direction(0.8, 1.0), direction(0.0, 0.0)] {
            generation += 1;
            let mut r = request(generation, 1);
            r.material = Arc::new(m.clone());
            r.image = image.clone();
            r.scene.light = light;
            r.size = [24, 16];
            w.request(r);
            // Served when the truth's ray has come back at full size.
            loop {
                match w.wait(Duration::from_secs(600)) {
                    Some(Event::Frame(f))
                        if f.generation == generation
                            && f.mode == ViewMode::Truth
                            && f.scale == 1.0
                            && f.samples == 1 =>
                    {
                        break;
                    }
                    Some(Event::Frame(_)) => {}
                    other => panic!("{path}: unexpected {other:?}"),
                }
            }
        }
    }
    drop(w);
}

/// Switching between presets whose pipelines are the largest (transfer curves, an image driver)
/// never stops the render thread. On OpenGL the device is this thread's alone: a pipeline
/// compiled on another thread beside a frame held the context lock past wgpu's one-second wait,
/// and the thread stopped on a panic (with Mesa's shader cache cold or disabled,
/// `MESA_SHADER_CACHE_DISABLE=true`: switching from cobblestones to moss stopped it).
#[test]
fn switching_presets_never_stops_the_render_thread() {
    switch_through("the preset switching test", &["cobblestones", "moss"]);
}

/// The same through every preset of the library (about 15 minutes on llvmpipe with Mesa's shader
/// cache disabled).
#[test]
#[ignore = "long: every preset's pipelines"]
fn switching_every_preset_never_stops_the_render_thread() {
    switch_through("the every-preset switching test", &[]);
}
