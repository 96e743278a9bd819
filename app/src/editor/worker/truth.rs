//! The worker's ground truth: uniform accumulation, and the adaptive truth's progressive rounds
//! from the predicted deviation.

use super::*;

impl State {
    /// Adaptive ground truth (#18 §1): core predicts each pixel's ray deviation once (on a grid
    /// of at most [`PREDICT_SIDE`] pixels a side, nearest-upsampled: the allocation needs its
    /// shape, not its detail), then [`render_progressive`] traces rounds of doubling budgets up to
    /// `truth_spp` rays per pixel on average, each in steps of about one ray per pixel, so a newer
    /// request waits no longer than for a uniform frame.
    pub(super) fn accumulate_adaptive(
        &mut self,
        req: &Request,
        scale: f32,
        rx: &Receiver<Request>,
        send: &dyn Fn(Event),
    ) -> Result<Option<Request>, ()> {
        let size = Self::size_at(req, scale);
        let Some(mut target) = self.truth_target(size, send) else {
            return Ok(None);
        };
        let (Some(prepared), Some((_, gm))) = (&self.prepared, &self.material) else {
            self.truth = Some(target);
            return Ok(None);
        };
        let predicted = predicted_deviation(prepared, &req.scene, size);
        let predicted_f32 = Arc::new(predicted.iter().map(|v| *v as f32).collect::<Vec<_>>());
        let bandwidth = Arc::new(predicted_bandwidth(prepared, &req.scene, size));
        let spp = req.truth_spp.max(1);
        let plan = Progressive {
            predicted: &predicted,
            rays_per_pixel: f64::from(spp),
            max_rays: spp.saturating_mul(MAX_RAYS_FACTOR).max(16),
            // Measured in `lodestone report` (docs/design/adaptive-truth.md): on llvmpipe the cost-aware plan
            // lost to the plain one at equal error in time as well as in rays.
            cost_aware: false,
        };
        let renderer = &self.renderer;
        let mut outcome: Result<Option<Request>, ()> = Ok(None);
        let mut last_sent = Instant::now() - Duration::from_secs(1);
        let mut t0 = Instant::now();
        let traced = render_progressive(
            renderer,
            &mut target,
            gm,
            &req.scene,
            plan,
            |target, rays, round_end| {
                renderer.wait();
                let dt = t0.elapsed();
                let total: u64 = rays.iter().map(|r| u64::from(*r)).sum();
                let mean = (total as f64 / rays.len().max(1) as f64).round() as u32;
                if round_end || last_sent.elapsed() > Duration::from_millis(120) {
                    let image = target.read(renderer)?;
                    let moments = target.read_moments(renderer)?;
                    let cut_rays = target.cut_count(renderer)?;
                    let cost = costs_f32(&target.read_work(renderer)?, rays);
                    send(Event::Frame(Frame {
                        generation: req.generation,
                        mode: ViewMode::Truth,
                        image: Arc::new(image),
                        samples: mean,
                        rays: Some(Arc::new(rays.to_vec())),
                        predicted_sd: Some(predicted_f32.clone()),
                        predicted_bandwidth: Some(bandwidth.clone()),
                        cost: Some(Arc::new(cost)),
                        moments: Some(Arc::new(moments)),
                        pass_time: dt,
                        cut_rays,
                        scale,
                    }));
                    last_sent = Instant::now();
                }
                t0 = Instant::now();
                match Self::newest(rx) {
                    Err(()) => outcome = Err(()),
                    Ok(Some(newer)) => outcome = Ok(Some(newer)),
                    Ok(None) => return Ok(true),
                }
                Ok(false)
            },
        );
        if let Err(e) = traced {
            send(Event::RenderError(e.to_string()));
        }
        self.truth = Some(target);
        outcome
    }

    pub(super) fn accumulate_truth(
        &mut self,
        req: &Request,
        scale: f32,
        rx: &Receiver<Request>,
        send: &dyn Fn(Event),
    ) -> Result<Option<Request>, ()> {
        let size = Self::size_at(req, scale);
        let Some(mut target) = self.truth_target(size, send) else {
            return Ok(None);
        };
        target.reset();
        let mut last_sent = Instant::now() - Duration::from_secs(1);
        let result = loop {
            let Some((_, gm)) = &self.material else {
                break Ok(None);
            };
            let t0 = Instant::now();
            self.renderer
                .draw(&mut target, gm, &req.scene, ViewMode::Truth, 1);
            self.renderer.wait();
            let dt = t0.elapsed();
            let done = target.samples >= req.truth_spp;
            // Read back at most ~8 times a second (and always at the end): readback costs a copy.
            if done || last_sent.elapsed() > Duration::from_millis(120) || target.samples <= 4 {
                let read = target.read(&self.renderer).and_then(|image| {
                    Ok((
                        image,
                        target.read_moments(&self.renderer)?,
                        target.cut_count(&self.renderer)?,
                        target.read_work(&self.renderer)?,
                    ))
                });
                match read {
                    Ok((image, moments, cut_rays, work)) => send(Event::Frame(Frame {
                        generation: req.generation,
                        mode: ViewMode::Truth,
                        image: Arc::new(image),
                        samples: target.samples,
                        rays: None,
                        predicted_sd: None,
                        predicted_bandwidth: None,
                        cost: Some(Arc::new(costs_f32(
                            &work,
                            &vec![target.samples; work.len()],
                        ))),
                        moments: Some(Arc::new(moments)),
                        pass_time: dt,
                        cut_rays,
                        scale,
                    })),
                    Err(e) => {
                        send(Event::RenderError(e.to_string()));
                        break Ok(None);
                    }
                }
                last_sent = Instant::now();
            }
            match Self::newest(rx) {
                Err(()) => break Err(()),
                Ok(Some(newer)) => break Ok(Some(newer)),
                Ok(None) if done => break Ok(None),
                Ok(None) => {}
            }
        };
        self.truth = Some(target);
        result
    }
}
