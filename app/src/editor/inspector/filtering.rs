//! The inspector's Filtering section: the filtered model's options, and what the transfer model
//! means for a curve.

use super::*;

/// Which slope model the filtered view runs for this material, and why (the reason `lodestone
/// inspect` gives).
pub(super) fn transfer_model_note(ui: &mut Ui, m: &Material) {
    let features = FeatureSet::of_material(m);
    let note = |feature: Feature, on: &str, off: &str| {
        if features.contains(feature) {
            on.to_owned()
        } else {
            let why = features
                .absent(m)
                .into_iter()
                .find(|(f, _)| *f == feature)
                .map_or("", |(_, why)| why);
            format!("{off} ({why})")
        }
    };
    ui.weak(note(
        Feature::TransferMixture,
        if m.image_slope_mixture() {
            "Slopes: mixture over the image's value (its slopes depend on its value)"
        } else {
            "Slopes: mixture over the driver's value (a transfer curve on relief)"
        },
        "Slopes: one Gaussian",
    ));
    if matches!(m.driver, Driver::Image { .. }) {
        ui.weak(note(
            Feature::ImageHistogram,
            "Image values: the image's own histogram, moment-matched per footprint",
            "Image values: one Gaussian",
        ));
    }
}

pub(super) fn filtering(ui: &mut Ui, f: &mut Filtering) -> bool {
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
    let mut t = f.transfer_slopes;
    egui::ComboBox::from_label("Transfer slopes")
        .selected_text(format!("{t:?}"))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut t, TransferSlopes::Mixture, "Mixture");
            ui.selectable_value(&mut t, TransferSlopes::Gaussian, "Gaussian");
        })
        .response
        .on_hover_text("Slopes under a transfer curve g, or of an image driver: a mixture of Gaussians over bins of the driver's value f (given f the slopes are Gaussian with std σ_h·g'(f) times the driver's gradient std; for an image, times the square root of its own conditional E[|grad f|² given f] / E[|grad f|²], so flat tops and steep flanks get their own slopes), with height-dependent masking (default), or one Gaussian of the same second moment [HNPN14 Eqs. 19–26]");
    if t != f.transfer_slopes {
        f.transfer_slopes = t;
        changed = true;
    }
    let mut d = f.noise_slopes;
    egui::ComboBox::from_label("Noise slope density")
        .selected_text(format!("{d:?}"))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut d, NoiseSlopes::Exact, "Exact");
            ui.selectable_value(&mut d, NoiseSlopes::Gaussian, "Gaussian");
        })
        .response
        .on_hover_text("Density of the noise's unresolved slopes under the specular lobe: the sum of sinusoids' own (saddlepoint of its cumulant generating function, Σ ln I0; lighter tails than a Gaussian; a few Newton steps over the waves per pixel, most of what the filtered view costs over naive) or the Gaussian of the same covariance [HN12 Sec. 5.5]");
    if d != f.noise_slopes {
        f.noise_slopes = d;
        changed = true;
    }
    let mut sm = f.slope_masking;
    egui::ComboBox::from_label("Slope masking")
        .selected_text(match sm {
            SlopeMasking::Smith => "Smith",
            SlopeMasking::Conditioned => "Conditioned on slope",
        })
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut sm, SlopeMasking::Smith, "Smith");
            ui.selectable_value(&mut sm, SlopeMasking::Conditioned, "Conditioned on slope");
        })
        .response
        .on_hover_text("Masking of the visible (height, slope) pairs: Smith's, where a facet's visibility depends on its height alone [HN12 Eqs. 4–6], or conditioned on the facet's height and slope along the view jointly (default; Smith's crossing rate with the surface conditioned on the start's height and slope through the noise's autocovariance; Rice, Smith 1967): facets facing the eye are seen more, those leaning to the silhouette less, high ones at every slope; each slope then sees its own heights, so colour and shading are summed together. Noise drivers (images keep Smith's); snake-skin at 75°: from −9% to +0.6% against the ray-traced truth (docs/design/slope-masking.md). A table of about a second per noise");
    if sm != f.slope_masking {
        f.slope_masking = sm;
        changed = true;
    }
    let mut ih = f.image_histogram;
    egui::ComboBox::from_label("Image histogram")
        .selected_text(format!("{ih:?}"))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut ih, ImageHistogram::Preserving, "Preserving");
            ui.selectable_value(&mut ih, ImageHistogram::Gaussian, "Gaussian");
        })
        .response
        .on_hover_text("An image driver's values inside a footprint: the image's own histogram: the inverse of its Gaussianizing transfer T applied to N(μ_G, σ_G²), moment-matched to the footprint's mean and std, with the colour map pre-convolved over G (default), or a Gaussian of the footprint's mean and std [HNPN14 Sec. 4.2; Heitz & Neyret 2018]");
    if ih != f.image_histogram {
        f.image_histogram = ih;
        changed = true;
    }
    changed |= ui
        .add(Slider::new(&mut f.slope_points, 1..=Filtering::MAX_SLOPE_POINTS).text("Slope points"))
        .on_hover_text("n: the radii of the polar rule for averages over the visible slope distribution D_s (diffuse cosine, slope colour C_s, environment), with n angles per ring, 2n with a slope colour (it turns with the facet's azimuth); n² or 2n² nodes per pixel [HNPN14 Sec. 5.2]")
        .changed();
    changed
}
