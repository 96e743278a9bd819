//! The render worker's side of the window: requests for what the views need, frames uploaded as
//! textures as they arrive, and error heat maps against the ground truth.

use super::worker::{Event, Request};
use super::{DeviceStatus, EditorApp, ErrorShown, Shown};
use lodestone_render::ViewMode;
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

    /// Heat maps of each shown mode against the latest ground truth of the same size.
    pub(super) fn update_errors(&mut self, ctx: &egui::Context) {
        if !self.view.show_error {
            return;
        }
        let Some(truth) = self.shown.get(&ViewMode::Truth) else {
            return;
        };
        let tf = &truth.frame;
        for (mode, s) in &self.shown {
            if *mode == ViewMode::Truth {
                continue;
            }
            let f = &s.frame;
            if (f.image.width, f.image.height) != (tf.image.width, tf.image.height) {
                continue;
            }
            let from = (f.generation, tf.generation, tf.samples);
            if self.errors.get(mode).is_some_and(|e| e.from == from) {
                continue;
            }
            let heat = lodestone_render::error_map::error_heat(
                &f.image,
                &tf.image,
                f64::from(self.view.error_scale),
            );
            let stats = lodestone_render::error_map::error_stats(&f.image, &tf.image);
            let img = heat.to_srgb8();
            let color = egui::ColorImage::from_rgba_unmultiplied(
                [img.width() as usize, img.height() as usize],
                img.as_raw(),
            );
            match self.errors.get_mut(mode) {
                Some(e) => {
                    e.texture.set(color, egui::TextureOptions::LINEAR);
                    e.stats = stats;
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
                            stats,
                            from,
                        },
                    );
                }
            }
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
            scene,
            size: self.view_px,
            modes,
            truth_spp,
            max_scale: self.view.max_scale,
        };
        self.worker.request(req.clone());
        self.last_request = Some((self.doc.material.clone(), req));
    }
}
