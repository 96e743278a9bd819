//! The render worker's side of the window: requests for what the views need, frames uploaded as
//! textures as they arrive, and error heat maps against the ground truth.

use super::truth_maps::truth_map;
use super::worker::{Event, Frame, MAX_RESTARTS, Request, Worker};
use super::{DeviceStatus, EditorApp, ErrorShown, Shown, TruthHeatShown};
use lodestone_render::error_map::{error_heat, error_stats, heat_gradient};
use lodestone_render::truth_noise::{BlockErrors, TruthEstimate};
use lodestone_render::{LinearImage, ViewMode};
use std::sync::Arc;

impl EditorApp {
    /// Take the worker's news and upload new images.
    pub(super) fn poll_worker(&mut self, ctx: &egui::Context) {
        for ev in self.worker.poll() {
            match ev {
                Event::Ready { adapter, software } => {
                    // A software rasterizer takes seconds per full-resolution frame: start at half
                    // resolution (the Resolution menu raises it).
                    if software && self.view.max_scale > 0.5 && !self.deterministic {
                        self.view.max_scale = 0.5;
                        self.notify(
                            ctx,
                            "Software GPU adapter: views render at 50% resolution (raise it under Resolution)",
                            false,
                        );
                    }
                    self.device = DeviceStatus::Ready(adapter);
                }
                Event::NoAdapter(e) => self.device = DeviceStatus::Failed(e),
                Event::Stopped(e) => self.restart_worker(ctx, &e),
                Event::MaterialError(e) => self.material_error = Some(e),
                Event::RenderError(e) => self.notify(ctx, e, true),
                Event::Frame(f) => {
                    self.material_error = None;
                    let img = f.image.to_srgb8();
                    let color = egui::ColorImage::from_rgba_unmultiplied(
                        [img.width() as usize, img.height() as usize],
                        img.as_raw(),
                    );
                    let opts = egui::TextureOptions::LINEAR;
                    match self.shown.get_mut(&f.mode) {
                        Some(s) => {
                            s.texture.set(color, opts);
                            s.frame = f;
                        }
                        None => {
                            let texture =
                                ctx.load_texture(format!("view-{:?}", f.mode), color, opts);
                            self.shown.insert(f.mode, Shown { frame: f, texture });
                        }
                    }
                }
            }
        }
    }

    /// The render thread stopped on a panic: start a new one and ask it for the views again (at
    /// most [`MAX_RESTARTS`] times), or say the renderer failed.
    pub(super) fn restart_worker(&mut self, ctx: &egui::Context, why: &str) {
        if self.restarts >= MAX_RESTARTS {
            self.device = DeviceStatus::Failed(format!(
                "the renderer stopped {} times (last: {why})",
                self.restarts + 1
            ));
            return;
        }
        self.restarts += 1;
        let repaint = ctx.clone();
        self.worker = Worker::spawn(self.device_source, move || repaint.request_repaint());
        self.device = DeviceStatus::Starting;
        // Nothing of the old thread's work survives: the next frame asks for everything again.
        self.last_request = None;
        self.notify(
            ctx,
            format!("The renderer stopped ({why}); restarted it"),
            true,
        );
    }

    /// Heat maps of each shown mode against the latest ground truth of the same size.
    pub(super) fn update_errors(&mut self, ctx: &egui::Context) {
        if !self.view.show_error {
            return;
        }
        let Some(truth) = self.shown.get(&ViewMode::Truth) else {
            return;
        };
        let tf = &truth.frame;
        let (block, scale) = (self.view.error_block.max(1), self.view.error_scale);
        for (mode, s) in &self.shown {
            if *mode == ViewMode::Truth {
                continue;
            }
            let f = &s.frame;
            if (f.image.width, f.image.height) != (tf.image.width, tf.image.height) {
                continue;
            }
            let from = (
                f.generation,
                tf.generation,
                tf.samples,
                block,
                scale.to_bits(),
            );
            if self.errors.get(mode).is_some_and(|e| e.from == from) {
                continue;
            }
            let map = error_map(&f.image, tf, block, f64::from(scale));
            let img = map.heat.to_srgb8();
            let color = egui::ColorImage::from_rgba_unmultiplied(
                [img.width() as usize, img.height() as usize],
                img.as_raw(),
            );
            match self.errors.get_mut(mode) {
                Some(e) => {
                    e.texture.set(color, egui::TextureOptions::LINEAR);
                    e.summary = map.summary;
                    e.from = from;
                }
                None => {
                    let texture = ctx.load_texture(
                        format!("error-{mode:?}"),
                        color,
                        egui::TextureOptions::LINEAR,
                    );
                    self.errors.insert(
                        *mode,
                        ErrorShown {
                            texture,
                            summary: map.summary,
                            from,
                        },
                    );
                }
            }
        }
    }

    /// The truth viewport's noise map, when it shows one, from the latest truth frame.
    pub(super) fn update_truth_heat(&mut self, ctx: &egui::Context) {
        let display = self.view.truth_display;
        let Some(truth) = self.shown.get(&ViewMode::Truth) else {
            return;
        };
        let f = &truth.frame;
        let from = (f.generation, f.samples, display);
        if self.truth_heat.as_ref().is_some_and(|h| h.from == from) {
            return;
        }
        let Some(heat) = truth_map(f, display) else {
            self.truth_heat = None;
            return;
        };
        let img = heat.image.to_srgb8();
        let color = egui::ColorImage::from_rgba_unmultiplied(
            [img.width() as usize, img.height() as usize],
            img.as_raw(),
        );
        // Nearest: a ray count is a pixel's own, not a blend of its neighbours'.
        let opts = egui::TextureOptions::NEAREST;
        match &mut self.truth_heat {
            Some(h) => {
                h.texture.set(color, opts);
                h.max = heat.max;
                h.from = from;
            }
            None => {
                self.truth_heat = Some(TruthHeatShown {
                    texture: ctx.load_texture("truth-heat", color, opts),
                    max: heat.max,
                    from,
                });
            }
        }
    }

    /// The march the views use: the fast one, or the reference (View → Debug).
    fn march(&self) -> lodestone_core::scene::march::March {
        if self.view.reference_march {
            lodestone_core::scene::march::March::Reference
        } else {
            lodestone_core::scene::march::March::Fast
        }
    }

    /// Send the worker what the views need now, if it changed.
    pub(super) fn request_views(&mut self, ctx: &egui::Context) {
        if self.view_px[0] == 0 || self.view_px[1] == 0 {
            return;
        }
        let scene = self.view.scene();
        let modes = self.view.needed();
        let truth_spp = self.view.truth_spp.max(1);
        let same = self.last_request.as_ref().is_some_and(|(m, r)| {
            *m == self.doc.material
                && r.scene == scene
                && r.size == self.view_px
                && r.modes == modes
                && r.truth_spp == truth_spp
                && r.max_scale == self.view.max_scale
                && r.adaptive_truth == self.view.adaptive_truth
                && r.march == self.march()
        });
        if same {
            return;
        }
        // Until the material's files have loaded there is nothing to render (no request: the
        // next frame asks again).
        let Some(resolved) = self.resolved(ctx) else {
            return;
        };
        self.generation += 1;
        let req = Request {
            generation: self.generation,
            material: Arc::new(self.doc.material.clone()),
            image: resolved.image,
            environment: resolved.environment,
            measured: resolved.measured,
            scene,
            size: self.view_px,
            modes,
            truth_spp,
            max_scale: self.view.max_scale,
            adaptive_truth: self.view.adaptive_truth,
            march: self.march(),
        };
        self.worker.request(req.clone());
        self.last_request = Some((self.doc.material.clone(), req));
    }
}

/// One mode's difference from the ground truth as the editor shows it.
pub(super) struct ErrorMap {
    /// The heat map (linear RGB, the view's size).
    pub heat: LinearImage,
    /// Its numbers.
    pub summary: ErrorSummary,
}

/// The numbers beside an error map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct ErrorSummary {
    /// RMSE per pixel as measured, the truth's own noise included.
    pub rmse_raw: f64,
    /// Largest per-pixel error (max over channels).
    pub max: f64,
    /// Block side of the noise-aware numbers, in view pixels.
    pub block: u32,
    /// RMSE of the block means beyond the truth's noise, with its range for ±2 standard errors
    /// ([`BlockErrors::rmse`]); `None` while the truth has fewer than two rays per pixel.
    pub beyond_noise: Option<(f64, (f64, f64))>,
    /// Fraction of the view in blocks whose difference is significant
    /// ([`BlockErrors::significant_fraction`]).
    pub significant: Option<f64>,
}

/// `image` against the ground-truth frame `truth` (same size): heat of the `block × block` means'
/// difference (`scale` at the top), blocks within the truth's noise in grey
/// ([`BlockErrors::heat`]); while the truth's noise is unknown (one ray per pixel, or no
/// moments), the per-pixel |image − truth| map.
pub(super) fn error_map(image: &LinearImage, truth: &Frame, block: u32, scale: f64) -> ErrorMap {
    let raw = error_stats(image, &truth.image);
    let blocks = truth
        .moments
        .as_deref()
        .and_then(|m| TruthEstimate::new(&truth.image, m))
        .and_then(|t| BlockErrors::new(image, &t, block));
    let summary = ErrorSummary {
        rmse_raw: raw.rmse,
        max: raw.max,
        block,
        beyond_noise: blocks.as_ref().map(|b| (b.rmse(), b.rmse_range(2.0))),
        significant: blocks.as_ref().map(BlockErrors::significant_fraction),
    };
    let heat = match &blocks {
        Some(b) => b.heat(image.width, image.height, &heat_gradient(), scale),
        None => error_heat(image, &truth.image, scale),
    };
    ErrorMap { heat, summary }
}
