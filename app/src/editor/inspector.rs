//! The material inspector: every parameter of the material, labelled, with a tooltip that names the
//! parameter and the equation it enters.

use super::curve_editor::CurveEditor;
use super::gradient_editor::GradientEditor;
use egui::{Slider, Ui};
use lodestone_core::colormap::Gradient;
use lodestone_core::effective_height::HeightFilter;
use lodestone_core::features::{Feature, FeatureSet};
use lodestone_core::material::{ColorModel, ColorSource, Driver, Filtering, Material};
use lodestone_core::noise::NoiseParams;
use lodestone_core::shadowing::Correlation;

/// UI state of the inspector.
#[derive(Debug, Default)]
pub struct Inspector {
    /// The colour map editor.
    pub gradient: GradientEditor,
    /// The transfer curve editor.
    pub curve: CurveEditor,
    /// σ_nx and σ_ny move together.
    pub isotropic_lock: bool,
    /// Skewness and excess kurtosis of the loaded image driver, if any (set by the editor).
    pub driver_shape: Option<(f64, f64)>,
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
                changed |= self.curve.ui(ui, &mut m.heights.transfer);
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
        egui::CollapsingHeader::new("Colour")
            .default_open(true)
            .show(ui, |ui| changed |= self.color(ui, m));
        egui::CollapsingHeader::new("Base BRDF")
            .default_open(true)
            .show(ui, |ui| {
                let b = &mut m.brdf;
                changed |= slider_f64(ui, &mut b.albedo, 0.0..=1.0, "Albedo",
                    "Lambertian albedo multiplying the colour map, ρ_d·C/π", false);
                changed |= slider_f64(ui, &mut b.specular, 0.0..=1.0, "Specular",
                    "Specular reflectance of the slope-space Beckmann lobe", false);
                ui.add_enabled_ui(b.specular > 0.0, |ui| {
                changed |= slider_f64(ui, &mut b.roughness, 0.001..=1.0, "Roughness σ_n0",
                    "σ_n0: base roughness (slope std of the BRDF lobe); filtered adds the footprint's slope variance, σ_n0² + σ_n² [HN12 Sec. 5.5]. Unused while Specular is 0", true);
                });
            });
        egui::CollapsingHeader::new("Filtering")
            .default_open(false)
            .show(ui, |ui| changed |= filtering(ui, &mut m.filtering));
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

fn filtering(ui: &mut Ui, f: &mut Filtering) -> bool {
    let mut changed = false;
    let mut c = f.correlation;
    egui::ComboBox::from_label("Masking–shadowing")
        .selected_text(format!("{c:?}"))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut c, Correlation::HeightDirection, "HeightDirection");
            ui.selectable_value(&mut c, Correlation::Uncorrelated, "Uncorrelated");
        })
        .response
        .on_hover_text("Mean visibility V: height–direction correlated (default) or uncorrelated masking and shadowing [HNPN14 Eq. 12]");
    if c != f.correlation {
        f.correlation = c;
        changed = true;
    }
    let mut h = f.height_filter;
    egui::ComboBox::from_label("Effective height")
        .selected_text(format!("{h:?}"))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut h, HeightFilter::Exact, "Exact");
            ui.selectable_value(&mut h, HeightFilter::PaperFit, "PaperFit");
        })
        .response
        .on_hover_text("Moments of the visible height distribution D_h: exact table or the paper's fits [HNPN14 Sec. 5.1]");
    if h != f.height_filter {
        f.height_filter = h;
        changed = true;
    }
    changed |= ui
        .add(Slider::new(&mut f.slope_points, 1..=Filtering::MAX_SLOPE_POINTS).text("Slope points"))
        .on_hover_text("Gauss–Hermite points per axis for averages over the visible slope distribution D_s (n² per pixel)")
        .changed();
    changed
}
