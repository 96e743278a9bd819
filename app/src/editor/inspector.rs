//! The material inspector: every parameter of the material, labelled, with a tooltip that names the
//! parameter and the equation it enters.

mod brdf;
mod filtering;
mod lighting;
use super::curve_editor::CurveEditor;
use super::gradient_editor::GradientEditor;
use egui::{Slider, Ui};
use filtering::{filtering, transfer_model_note};
use lighting::lighting;
use lodestone_core::driver::histogram::ImageHistogram;
use lodestone_core::driver::image::ImageDriver;
use lodestone_core::driver::noise::NoiseParams;
use lodestone_core::material::color_terms::{CombineMode, ConstantTerm, SlopeTerm};
use lodestone_core::material::colormap::Gradient;
use lodestone_core::material::environment::{Environment, EnvironmentSource, Lighting, Sky};
use lodestone_core::material::features::{Feature, FeatureSet};
use lodestone_core::material::merl_fit::MerlFit;
use lodestone_core::material::slope_color::SlopeColor;
use lodestone_core::material::{ColorModel, ColorSource, Driver, Filtering, Material};
use lodestone_core::microfacet::brdf::BaseBrdf;
use lodestone_core::microfacet::effective_height::HeightFilter;
use lodestone_core::microfacet::height_mixture::TransferSlopes;
use lodestone_core::microfacet::masking_shadowing::Correlation;
use lodestone_core::microfacet::slope_density::NoiseSlopes;
use lodestone_core::microfacet::slope_masking::SlopeMasking;
use lodestone_core::microfacet::transfer::{SurfaceShape, TransferFunction};
use std::sync::Arc;

/// UI state of the inspector.
#[derive(Debug, Default)]
pub struct Inspector {
    /// The colour map editor.
    pub gradient: GradientEditor,
    /// The transfer curve editor.
    pub curve: CurveEditor,
    /// The slope colour map's editor.
    pub slope_gradient: GradientEditor,
    /// σ_nx and σ_ny move together.
    pub isotropic_lock: bool,
    /// Skewness and excess kurtosis of the loaded image driver, if any (set by the editor).
    pub driver_shape: Option<(f64, f64)>,
    /// The measured BRDF's fit (set by the editor when the material's file has loaded).
    pub measured_fit: Option<MerlFit>,
    /// The loaded image driver, if any (set by the editor): the height histogram shows its texels.
    pub driver_image: Option<Arc<ImageDriver>>,
    /// The transfer curve's non-Gaussianity, cached with the curve it was computed for.
    transfer_shape: Option<(TransferFunction, SurfaceShape)>,
    /// The material's features at the last frame: a section collapses when the feature it
    /// edits goes unused (and opens again when it comes back).
    last_features: Option<FeatureSet>,
}

/// A section header that collapses when `used` turns false and opens when it turns true again,
/// or on the first frame of an inspector (otherwise it keeps whatever the user chose); its title
/// says why it does nothing.
fn section(
    title: &str,
    used: bool,
    unused_why: &str,
    was_used: Option<bool>,
) -> egui::CollapsingHeader {
    let text = if used {
        title.to_string()
    } else {
        format!("{title} (unused: {unused_why})")
    };
    let h = egui::CollapsingHeader::new(text)
        .id_salt(title)
        .default_open(used);
    // A new inspector (a material just loaded) starts from what the material uses.
    match was_used {
        Some(before) if before == used => h,
        _ => h.open(Some(used)),
    }
}

fn slider_f64(
    ui: &mut Ui,
    v: &mut f64,
    range: std::ops::RangeInclusive<f64>,
    text: &str,
    tip: &str,
    log: bool,
) -> bool {
    ui.add(
        Slider::new(v, range)
            .text(text)
            .logarithmic(log)
            .clamping(egui::SliderClamping::Always),
    )
    .on_hover_text(tip)
    .changed()
}

impl Inspector {
    /// A fresh inspector for `m`.
    pub fn new(m: &Material) -> Self {
        Self {
            isotropic_lock: m.slopes.sigma_nx == m.slopes.sigma_ny,
            ..Self::default()
        }
    }

    /// Show every control; returns true when the material changed.
    pub fn ui(&mut self, ui: &mut Ui, m: &mut Material) -> bool {
        let mut changed = false;
        let features = FeatureSet::of_material(m);
        let last = self.last_features.replace(features);
        let relief = features.contains(Feature::Relief);
        let had_relief = last.map(|f| f.contains(Feature::Relief));
        ui.horizontal(|ui| {
            let l = ui.label("Name");
            changed |= ui
                .text_edit_singleline(&mut m.name)
                .labelled_by(l.id)
                .on_hover_text("Display name of the preset")
                .changed();
        });
        egui::CollapsingHeader::new("Driver f")
            .default_open(true)
            .show(ui, |ui| changed |= self.driver(ui, m));
        egui::CollapsingHeader::new("Heights")
            .default_open(true)
            .show(ui, |ui| {
                changed |= slider_f64(
                    ui,
                    &mut m.heights.sigma_h,
                    0.0..=1.0,
                    "σ_h",
                    "σ_h: height standard deviation of the microsurface, h = σ_h·g(f) [HNPN14 Sec. 5, Eq. 19]",
                    false,
                );
                ui.label("Height transfer function g [HNPN14 Sec. 7]");
                let image = self.driver_image.clone();
                changed |= self.curve.ui(ui, &mut m.heights.transfer, image.as_ref());
                if matches!(m.heights.transfer, TransferFunction::Curve(_)) {
                    // Cached per curve: 800-panel quadratures are cheap but not per-frame cheap.
                    if self.transfer_shape.as_ref().is_none_or(|(t, _)| *t != m.heights.transfer) {
                        self.transfer_shape = Some((m.heights.transfer.clone(), m.heights.transfer.shape()));
                    }
                    if let Some((_, sh)) = &self.transfer_shape {
                        ui.label(format!(
                            "Through g: heights skewness {:.2}, excess kurtosis {:.2}; slopes excess kurtosis {:.2} (0 for a Gaussian)",
                            sh.skewness, sh.excess_kurtosis, sh.slope_excess_kurtosis
                        ));
                        // The transfer mixture's masking conditioned on the driver's value and
                        // slope (#17): a noise driver with conditioned masking.
                        let conditioned = matches!(m.driver, Driver::Noise(_))
                            && m.transfer_mixture()
                            && m.filtering.slope_masking == SlopeMasking::Conditioned;
                        if sh.far_from_gaussian() && conditioned && !(m.terms.slope.is_some() || m.lighting.environment.is_some()) {
                            ui.label(
                                "Far from Gaussian: the filtered view's bins follow the curve and condition their masking \
                                 on the driver's value and slope; past 85° from the normal expect a few % \
                                 (Filtering, Slope masking: Smith is the faster path).",
                            );
                        } else if sh.far_from_gaussian() {
                            let slope_terms = m.terms.slope.is_some() || m.lighting.environment.is_some();
                            ui.colored_label(
                                ui.visuals().warn_fg_color,
                                if slope_terms {
                                    "Far from Gaussian: the slope colour and environment terms average over a Gaussian \
                                     visible slope distribution [HNPN14 Sec. 8, Fig. 14]; a colour map with fine detail \
                                     in slope will be off, most at grazing angles."
                                } else {
                                    "Far from Gaussian: the filtered view's masking and effective heights assume Gaussian \
                                     statistics [HNPN14 Sec. 8]; expect larger errors at grazing angles."
                                },
                            );
                        }
                    }
                }
            });
        section("Slopes", relief, "the surface is flat, sigma_h = 0", had_relief)
            .show(ui, |ui| {
                let from_image = matches!(m.driver, Driver::Image { .. });
                if from_image {
                    ui.label("An image driver's slopes come from the image (its gradients × σ_h); σ_n is not used.");
                }
                ui.add_enabled_ui(!from_image, |ui| {
                let before = m.slopes;
                changed |= slider_f64(
                    ui,
                    &mut m.slopes.sigma_nx,
                    0.0..=2.0,
                    "σ_nx",
                    "σ_nx: slope standard deviation along x; the sub-footprint slope variance widens the BRDF lobe, σ² = σ_n² + σ_n0² [HN12 Sec. 5.5]",
                    false,
                );
                changed |= slider_f64(
                    ui,
                    &mut m.slopes.sigma_ny,
                    0.0..=2.0,
                    "σ_ny",
                    "σ_ny: slope standard deviation along y (anisotropy when it differs from σ_nx) [HN12 Sec. 3]",
                    false,
                );
                ui.checkbox(&mut self.isotropic_lock, "Isotropic (σ_nx = σ_ny)")
                    .on_hover_text("Move σ_nx and σ_ny together");
                if self.isotropic_lock {
                    if m.slopes.sigma_nx != before.sigma_nx {
                        m.slopes.sigma_ny = m.slopes.sigma_nx;
                    } else if m.slopes.sigma_ny != before.sigma_ny {
                        m.slopes.sigma_nx = m.slopes.sigma_ny;
                    }
                }
                });
            });
        let colour_model = m.terms.uses_height_term();
        section(
            "Colour",
            colour_model,
            "the colour model is not one of the terms",
            last.map(|f| {
                f.contains(Feature::DriverColor)
                    || f.contains(Feature::HeightColor)
                    || f.contains(Feature::AttributeColor)
            }),
        )
        .show(ui, |ui| changed |= self.color(ui, m));
        // Colour terms and Lighting open by themselves when the material gains a slope term or an
        // environment (a preset that uses them was loaded, or the user added one), and close when
        // it loses them; otherwise they keep what the user chose.
        let follow = |name: &str, f: Feature| {
            let now = features.contains(f);
            let h = egui::CollapsingHeader::new(name).default_open(now);
            match last {
                Some(l) if l.contains(f) == now => h,
                _ => h.open(Some(now)),
            }
        };
        follow("Colour terms", Feature::SlopeColor).show(ui, |ui| changed |= self.terms(ui, m));
        follow("Lighting", Feature::Environment)
            .show(ui, |ui| changed |= lighting(ui, &mut m.lighting));
        egui::CollapsingHeader::new("Base BRDF")
            .default_open(true)
            .show(ui, |ui| {
                changed |= self.measured_brdf(ui, &mut m.brdf);
                let b = &mut m.brdf;
                ui.add_enabled_ui(b.measured.is_none(), |ui| {
                changed |= slider_f64(ui, &mut b.albedo, 0.0..=1.0, "Albedo",
                    "Lambertian albedo multiplying the colour map, ρ_d·C/π (unused with a measured BRDF)", false);
                changed |= slider_f64(ui, &mut b.specular, 0.0..=1.0, "Specular",
                    "Specular reflectance of the slope-space Beckmann lobe (unused with a measured BRDF)", false);
                ui.add_enabled_ui(b.specular > 0.0, |ui| {
                changed |= slider_f64(ui, &mut b.roughness, 0.001..=1.0, "Roughness σ_n0",
                    "σ_n0: base roughness (slope std of the BRDF lobe); filtered adds the footprint's slope variance, σ_n0² + σ_n² [HN12 Sec. 5.5]. Unused while Specular is 0", true);
                });
                });
            });
        egui::CollapsingHeader::new("Filtering")
            .default_open(false)
            .show(ui, |ui| {
                changed |= filtering(ui, &mut m.filtering);
                transfer_model_note(ui, m);
            });
        changed
    }

    fn driver(&mut self, ui: &mut Ui, m: &mut Material) -> bool {
        let mut changed = false;
        let is_noise = matches!(m.driver, Driver::Noise(_));
        let mut want_noise = is_noise;
        egui::ComboBox::from_label("Driver kind")
            .selected_text(if is_noise { "Sum-of-sines noise" } else { "Image" })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut want_noise, true, "Sum-of-sines noise");
                ui.selectable_value(&mut want_noise, false, "Image");
            })
            .response
            .on_hover_text("The driving function f: procedural noise with analytic footprint statistics, or a grayscale image");
        if want_noise != is_noise {
            m.driver = if want_noise {
                Driver::Noise(NoiseParams::default())
            } else {
                Driver::Image {
                    path: String::new(),
                    size: 1.0,
                }
            };
            changed = true;
        }
        match &mut m.driver {
            Driver::Noise(n) => {
                ui.horizontal(|ui| {
                    let l = ui.label("Seed");
                    changed |= ui
                        .add(egui::DragValue::new(&mut n.seed))
                        .labelled_by(l.id)
                        .on_hover_text("Random seed of the sinusoids' directions and phases")
                        .changed();
                });
                changed |= ui
                    .add(
                        Slider::new(&mut n.components, 1..=NoiseParams::MAX_COMPONENTS)
                            .text("Components"),
                    )
                    .on_hover_text(
                        "Number of sinusoids; more is more Gaussian (excess kurtosis about −3/(2N))",
                    )
                    .changed();
                changed |= ui
                    .add(Slider::new(&mut n.octaves, 1..=12).text("Octaves"))
                    .on_hover_text("Frequency bands, each an octave above the last")
                    .changed();
                changed |= slider_f64(
                    ui,
                    &mut n.gain,
                    0.0..=1.0,
                    "Gain",
                    "Amplitude ratio between successive octaves",
                    false,
                );
                changed |= slider_f64(
                    ui,
                    &mut n.bandwidth,
                    0.0..=1.5,
                    "Bandwidth",
                    "Relative spread of |k| within an octave (0 = one ring)",
                    false,
                );
                changed |= slider_f64(
                    ui,
                    &mut n.frequency,
                    0.01..=100.0,
                    "Frequency",
                    "Base frequency (cycles per unit), used when σ_h or σ_n is 0; otherwise the frequencies follow from σ_n/σ_h",
                    true,
                );
            }
            Driver::Image { path, size } => {
                ui.horizontal(|ui| {
                    let l = ui.label("Image");
                    changed |= ui
                        .text_edit_singleline(path)
                        .labelled_by(l.id)
                        .on_hover_text("Grayscale image driving f (path relative to the preset)")
                        .changed();
                    if ui.button("Browse…").clicked()
                        && let Some(p) = rfd::FileDialog::new()
                            .add_filter("Images", &["png", "exr", "jpg", "jpeg"])
                            .pick_file()
                    {
                        *path = p.display().to_string();
                        changed = true;
                    }
                });
                if let Some((skew, kurt)) = self.driver_shape {
                    ui.label(format!(
                        "Histogram: skewness {skew:.2}, excess kurtosis {kurt:.2} (0 and 0 for a Gaussian)"
                    ));
                    if skew.abs() > 0.5 || kurt.abs() > 1.0 {
                        ui.colored_label(
                            ui.visuals().warn_fg_color,
                            "Far from Gaussian: the filtered views approximate the driver by a Gaussian \
                             [HNPN14 Sec. 4.2, Fig. 14]; expect larger errors, most at grazing angles.",
                        );
                    }
                }
                changed |= slider_f64(
                    ui,
                    size,
                    0.01..=100.0,
                    "Tile size",
                    "World size of one tile of the image",
                    true,
                );
            }
        }
        changed
    }

    /// The colour terms C0, C_h, C_s, their weights and how they combine [HNPN14 Sec. 6].
    fn terms(&mut self, ui: &mut Ui, m: &mut Material) -> bool {
        let mut changed = false;
        let t = &mut m.terms;
        let mut mode = t.mode;
        egui::ComboBox::from_label("Combination")
            .selected_text(match mode {
                CombineMode::Linear => "Linear",
                CombineMode::Multiplicative => "Multiplicative",
            })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut mode, CombineMode::Linear, "Linear");
                ui.selectable_value(&mut mode, CombineMode::Multiplicative, "Multiplicative");
            })
            .response
            .on_hover_text("Linear: C = κ0·C0 + κ1·C_h + κ2·C_s; multiplicative: C = Π(1 − κ + κ·C) over the terms [HNPN14 Sec. 6]");
        if mode != t.mode {
            t.mode = mode;
            changed = true;
        }
        // Constant C0.
        let mut on = t.constant.is_some();
        if ui
            .checkbox(&mut on, "Constant term C0")
            .on_hover_text("Add or remove κ0·C0, a constant colour [HNPN14 Sec. 6]")
            .changed()
        {
            t.constant = on.then_some(ConstantTerm {
                color: [0.5; 3],
                weight: 1.0,
            });
            changed = true;
        }
        if let Some(c) = &mut t.constant {
            ui.horizontal(|ui| {
                let l = ui.label("C0");
                let mut rgb = c.color.map(|v| v.clamp(0.0, 1.0) as f32);
                if ui
                    .color_edit_button_rgb(&mut rgb)
                    .labelled_by(l.id)
                    .on_hover_text("C0: the constant colour (linear RGB)")
                    .changed()
                {
                    c.color = rgb.map(f64::from);
                    changed = true;
                }
            });
            changed |= slider_f64(
                ui,
                &mut c.weight,
                0.0..=1.0,
                "κ0",
                "κ0: weight of C0 [HNPN14 Sec. 6]",
                false,
            );
        }
        // Height / driver colour model C_h.
        let mut on = t.height.is_some();
        if ui
            .checkbox(&mut on, "Colour model term C_h")
            .on_hover_text("Add or remove κ1·C_h, the colour model of the Colour section (driver-, height- or attribute-correlated)")
            .changed()
        {
            t.height = on.then_some(1.0);
            changed = true;
        }
        if let Some(w) = &mut t.height {
            changed |= slider_f64(
                ui,
                w,
                0.0..=1.0,
                "κ1",
                "κ1: weight of the colour model C_h [HNPN14 Sec. 6]",
                false,
            );
        }
        // Slope colour C_s.
        let mut on = t.slope.is_some();
        if ui
            .checkbox(&mut on, "Slope colour term C_s")
            .on_hover_text("Add or remove κ2·C_s(n): a colour map of n·d, filtered over the visible slope distribution D_s [HNPN14 Sec. 5.2]")
            .changed()
        {
            t.slope = on.then(|| SlopeTerm {
                color: SlopeColor::snow(),
                weight: 1.0,
            });
            changed = true;
        }
        if let Some(st) = &mut t.slope {
            changed |= slider_f64(
                ui,
                &mut st.weight,
                0.0..=1.0,
                "κ2",
                "κ2: weight of the slope colour C_s [HNPN14 Sec. 6]",
                false,
            );
            changed |= slider_f64(
                ui,
                &mut st.color.elevation_deg,
                -90.0..=90.0,
                "Direction elevation",
                "Elevation of d (degrees above the mean plane): the map's input is t = n·d; 90 = 'how level is the facet'",
                false,
            );
            changed |= slider_f64(
                ui,
                &mut st.color.azimuth_deg,
                -180.0..=180.0,
                "Direction azimuth",
                "Azimuth of d (degrees from +x toward +y): e.g. the side facets face for 'moss on north faces' [HNPN14 Fig. 9]",
                false,
            );
            ui.label("C_s against t = n·d (−1 … 1)");
            ui.push_id("slope colour map", |ui| {
                changed |= self.slope_gradient.ui(ui, &mut st.color.map);
            });
        }
        changed
    }

    fn color(&mut self, ui: &mut Ui, m: &mut Material) -> bool {
        let mut changed = false;
        let is_gradient = matches!(m.color, ColorModel::Gradient { .. });
        let mut want_gradient = is_gradient;
        egui::ComboBox::from_label("Colour model")
            .selected_text(if is_gradient { "Colour map" } else { "Height attribute (HN12)" })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut want_gradient, true, "Colour map");
                ui.selectable_value(&mut want_gradient, false, "Height attribute (HN12)");
            })
            .response
            .on_hover_text("Colour map C(f) pre-convolved over the footprint [HNPN14 Sec. 4], or a(h) = ā + a_s·(2P(h) − 1) [HN12 Eq. 17]");
        if want_gradient != is_gradient {
            m.color = if want_gradient {
                ColorModel::Gradient {
                    map: Gradient::viridis(-2.0, 2.0),
                    source: ColorSource::Driver,
                }
            } else {
                ColorModel::Attribute {
                    mean: [0.4, 0.3, 0.2],
                    correlation: [0.2, 0.15, 0.1],
                }
            };
            changed = true;
        }
        match &mut m.color {
            ColorModel::Gradient { map, source } => {
                let mut s = *source;
                egui::ComboBox::from_label("Indexed by")
                    .selected_text(match s {
                        ColorSource::Driver => "Driver f",
                        ColorSource::Height => "Height",
                    })
                    .show_ui(ui, |ui| {
                        ui.selectable_value(&mut s, ColorSource::Driver, "Driver f");
                        ui.selectable_value(&mut s, ColorSource::Height, "Height");
                    })
                    .response
                    .on_hover_text("Index the map by f [HNPN14 Sec. 4] or by the standardized height (h − mean h)/σ [HNPN14 Secs. 5.1, 7]");
                if s != *source {
                    *source = s;
                    changed = true;
                }
                changed |= self.gradient.ui(ui, map);
            }
            ColorModel::Attribute { mean, correlation } => {
                for (c, name) in ["red", "green", "blue"].iter().enumerate() {
                    changed |= slider_f64(
                        ui,
                        &mut mean[c],
                        0.0..=1.0,
                        &format!("ā {name}"),
                        "ā: mean attribute (linear RGB) of the channel [HN12 Eq. 17]",
                        false,
                    );
                    changed |= slider_f64(
                        ui,
                        &mut correlation[c],
                        -1.0..=1.0,
                        &format!("a_s {name}"),
                        "a_s: attribute–height correlation; a(h) = ā + a_s·(2P(h) − 1), filtered as 1 − 2/(L+2) with masking L [HN12 Eq. 17]",
                        false,
                    );
                }
            }
        }
        changed
    }
}
