//! The state every viewport shares: one orbit camera, one directional light, the display options,
//! and the zoom sweep animation.

use lodestone_core::scene::camera::Camera;
use lodestone_core::scene::direction::direction;
use lodestone_core::scene::shape::Shape;
use lodestone_render::{Scene, ViewMode};
use serde::{Deserialize, Serialize};

/// Closest and farthest camera distance the editor allows (world units; features are ~1/σ_n·σ_h).
pub const DISTANCE_RANGE: (f64, f64) = (0.02, 5000.0);

/// The A/B swipe: two modes in one viewport, split at `split` (0..1 of its width).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AbSwipe {
    /// Left of the split.
    pub left: Mode,
    /// Right of the split.
    pub right: Mode,
    /// Split position as a fraction of the width.
    pub split: f32,
}

/// A view mode as the editor names it (serialisable mirror of [`ViewMode`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Mode {
    /// Naive MIP.
    Naive,
    /// View-independent texture filtering.
    ViewIndependent,
    /// Ground truth.
    Truth,
    /// Filtered.
    Filtered,
}

impl Mode {
    /// The renderer's mode.
    pub fn render_mode(self) -> ViewMode {
        match self {
            Self::Naive => ViewMode::Naive,
            Self::ViewIndependent => ViewMode::ViewIndependent,
            Self::Truth => ViewMode::Truth,
            Self::Filtered => ViewMode::Filtered,
        }
    }

    /// Display name.
    pub fn label(self) -> &'static str {
        match self {
            Self::Naive => "Naive MIP",
            Self::ViewIndependent => "View-independent filtering",
            Self::Truth => "Ground truth",
            Self::Filtered => "Filtered",
        }
    }

    /// Every mode.
    pub const ALL: [Mode; 4] = [
        Self::Naive,
        Self::ViewIndependent,
        Self::Truth,
        Self::Filtered,
    ];
}

/// Camera, light and display options (persisted with the session).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ViewState {
    /// The shared camera.
    pub camera: Camera,
    /// Light angle from the normal, degrees.
    pub light_elevation_deg: f64,
    /// Light azimuth, degrees.
    pub light_azimuth_deg: f64,
    /// The baseline shown in the first viewport: naive MIP or view-independent filtering.
    pub baseline: Mode,
    /// Show |mode − ground truth| heat maps instead of the images.
    pub show_error: bool,
    /// Error that maps to the top of the heat scale (linear RGB units).
    pub error_scale: f32,
    /// Side of the pixel blocks whose means the error maps compare (1 = per pixel).
    pub error_block: u32,
    /// A/B swipe inside one viewport instead of three viewports.
    pub ab: Option<AbSwipe>,
    /// Ground-truth rays per pixel to accumulate.
    pub truth_spp: u32,
    /// Resolution cap as a fraction of the viewport's pixels.
    pub max_scale: f32,
    /// Widths of the first two viewports as fractions of the row (the third takes the rest).
    pub widths: [f32; 2],
    /// Show the plots panel.
    pub show_plots: bool,
    /// The object: the plane or a cylinder.
    pub shape: Shape,
    /// Ground truth gives each pixel its own ray count from its predicted and measured noise.
    pub adaptive_truth: bool,
    /// Every view marches with the reference march instead of the fast one (View → Debug; not
    /// kept across sessions), so both are one click apart.
    #[serde(skip)]
    pub reference_march: bool,
    /// What the ground-truth viewport shows: its image or one of its noise maps.
    pub truth_display: TruthDisplay,
}

/// What the ground-truth viewport shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TruthDisplay {
    /// The image.
    #[default]
    Image,
    /// The standard error of each pixel's mean luminance, from its own rays.
    StandardError,
    /// One ray's predicted luminance deviation (what adaptive sampling plans with).
    PredictedDeviation,
    /// The image's predicted local bandwidth, cycles per pixel [BSSBH13 Sec. 2.2].
    PredictedBandwidth,
    /// The rays each pixel has.
    Rays,
    /// What one more ray costs per pixel (march steps plus eights of waves summed).
    Cost,
    /// The image with each pixel pooled over the window around it that is flat within the
    /// truth's noise (intersection of confidence intervals, [BSSBH13 Sec. 3]).
    Reconstructed,
    /// The radius of that window per pixel: the scale below which the truth is flat, as
    /// measured by its rays.
    WindowRadius,
}

impl TruthDisplay {
    /// Every choice.
    pub const ALL: [Self; 8] = [
        Self::Image,
        Self::Reconstructed,
        Self::StandardError,
        Self::PredictedDeviation,
        Self::PredictedBandwidth,
        Self::Rays,
        Self::Cost,
        Self::WindowRadius,
    ];

    /// Menu and title text.
    pub fn label(self) -> &'static str {
        match self {
            Self::Image => "image",
            Self::StandardError => "standard error of the mean",
            Self::PredictedDeviation => "predicted ray deviation",
            Self::PredictedBandwidth => "predicted bandwidth",
            Self::Rays => "rays per pixel",
            Self::Cost => "cost per ray",
            Self::Reconstructed => "image, reconstructed",
            Self::WindowRadius => "reconstruction window radius",
        }
    }

    /// What it shows, for a tooltip.
    pub fn help(self) -> &'static str {
        match self {
            Self::Image => "The ground-truth image",
            Self::StandardError => {
                "√(s²/n) of each pixel's mean luminance, s² the sample variance of its n rays: how far the truth itself may be off"
            }
            Self::PredictedDeviation => {
                "σ̂, one truth ray's luminance deviation predicted from the filtered model (Evaluator::predict_truth: visible colour, slopes, sun visibility, specular second moment); adaptive ground truth plans its rays with it [BSSBH13 Sec. 2.4]"
            }
            Self::PredictedBandwidth => {
                "b, how fast the truth's image varies around each pixel, in cycles per pixel, predicted before any ray from the driver's waves through the colour map (its Hermite orders) and the shading's slope response, the cylinder's curvature through the lobe's width, and the pixel filter (Evaluator::predict_bandwidth, BSSBH13 Sec. 2.2). A lattice of step 2^floor(log2(1/2b)) samples it at Nyquist's rate [BSSBH13 Eq. 11]; 0.5 marks an edge (horizon, silhouette). Visibility is left out: where masking and shadow edges cut the relief the truth varies about twice as fast"
            }
            Self::Rays => {
                "Rays each pixel has: uniform truth gives every pixel the same; adaptive truth gives them in proportion to σ̂ + ½·mean σ̂, pooled with each pixel's measured deviation"
            }
            Self::Cost => {
                "What one more ground-truth ray costs in each pixel: march steps plus eights of waves summed, averaged over its rays (rays that skim the relief toward the horizon march longest)"
            }
            Self::Reconstructed => {
                "The ground truth with each pixel pooled over the least noisy square window around it whose mean stays within the truth's own noise (intersection of confidence intervals, Γ = 2, radius ≤ 8; BSSBH13 Sec. 3): far less noise where the image is flat, edges kept. Chosen from the rays alone, never from the filtered model; error maps still use the unpooled truth"
            }
            Self::WindowRadius => {
                "The radius of each pixel's reconstruction window: the scale, in pixels, over which the truth is flat within its noise (its measured bandwidth is about 1/(2r + 1) cycles per pixel); 0 keeps the pixel's own rays"
            }
        }
    }
}

impl Default for ViewState {
    fn default() -> Self {
        Self {
            camera: Camera {
                elevation_deg: 77.0,
                azimuth_deg: 0.0,
                distance: 3.0,
                target: [0.0, 0.0],
                fov_deg: 35.0,
            },
            light_elevation_deg: 45.0,
            light_azimuth_deg: 120.0,
            baseline: Mode::Naive,
            show_error: false,
            error_scale: 0.1,
            error_block: 8,
            ab: None,
            truth_spp: 64,
            max_scale: 1.0,
            widths: [1.0 / 3.0, 1.0 / 3.0],
            show_plots: true,
            shape: Shape::Plane,
            adaptive_truth: false,
            reference_march: false,
            truth_display: TruthDisplay::Image,
        }
    }
}

impl ViewState {
    /// Unit vector toward the light.
    pub fn light(&self) -> glam::DVec3 {
        direction(
            self.light_elevation_deg.clamp(0.0, 90.0).to_radians(),
            self.light_azimuth_deg.to_radians(),
        )
    }

    /// The renderer's scene.
    pub fn scene(&self) -> Scene {
        Scene {
            camera: self.camera,
            light: self.light(),
            shape: self.shape,
        }
    }

    /// The modes the viewports show, in order.
    pub fn shown(&self) -> Vec<Mode> {
        match self.ab {
            Some(ab) => vec![ab.left, ab.right],
            None => vec![self.baseline, Mode::Truth, Mode::Filtered],
        }
    }

    /// The modes to render: the shown ones, plus ground truth when errors are shown.
    pub fn needed(&self) -> Vec<ViewMode> {
        let mut modes: Vec<ViewMode> = Vec::new();
        for m in self.shown() {
            if !modes.contains(&m.render_mode()) {
                modes.push(m.render_mode());
            }
        }
        if self.show_error && !modes.contains(&ViewMode::Truth) {
            modes.push(ViewMode::Truth);
        }
        modes
    }

    /// Orbit by a drag of (dx, dy) points.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        let c = &mut self.camera;
        c.azimuth_deg = (c.azimuth_deg - f64::from(dx) * 0.4).rem_euclid(360.0);
        c.elevation_deg =
            (c.elevation_deg + f64::from(dy) * 0.3).clamp(0.0, Camera::MAX_ELEVATION_DEG);
    }

    /// Zoom by `steps` (positive: closer), multiplicatively so it spans scales evenly.
    pub fn zoom(&mut self, steps: f64) {
        if !steps.is_finite() {
            return;
        }
        let d = self.camera.distance * (-steps * 0.1).exp();
        self.camera.distance = d.clamp(DISTANCE_RANGE.0, DISTANCE_RANGE.1);
    }

    /// Point the light from a position in the unit disc (the hemisphere seen from above).
    pub fn set_light_from_disc(&mut self, x: f64, y: f64) {
        let r = (x * x + y * y).sqrt().min(1.0);
        self.light_elevation_deg = r.asin().to_degrees().clamp(0.0, 90.0);
        if r > 1e-9 {
            self.light_azimuth_deg = y.atan2(x).to_degrees().rem_euclid(360.0);
        }
    }

    /// The light's position in the unit disc.
    pub fn light_disc(&self) -> (f64, f64) {
        let r = self.light_elevation_deg.to_radians().sin();
        let a = self.light_azimuth_deg.to_radians();
        (r * a.cos(), r * a.sin())
    }
}

/// The zoom sweep: close → far → close on a log scale over `period` seconds, then back where it
/// started.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sweep {
    /// Distance when the sweep started (it returns there).
    pub start_distance: f64,
    /// Time the sweep started.
    pub start_time: f64,
    /// Seconds for the whole cycle.
    pub period: f64,
}

impl Sweep {
    /// Closest and farthest distance of a sweep.
    pub const RANGE: (f64, f64) = (0.15, 400.0);

    /// Distance at `time`, or `None` when the sweep is over.
    pub fn distance(&self, time: f64) -> Option<f64> {
        let t = (time - self.start_time) / self.period;
        if !(0.0..1.0).contains(&t) {
            return None;
        }
        let (lo, hi) = (Self::RANGE.0.ln(), Self::RANGE.1.ln());
        let s = self.start_distance.clamp(Self::RANGE.0, Self::RANGE.1).ln();
        // Start → closest → farthest → start, piecewise linear in log distance.
        let total = (s - lo) + (hi - lo) + (hi - s);
        let mut u = t * total;
        let ln = if u < s - lo {
            s - u
        } else {
            u -= s - lo;
            if u < hi - lo {
                lo + u
            } else {
                hi - (u - (hi - lo))
            }
        };
        Some(ln.exp())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_disc_round_trips() {
        let mut v = ViewState::default();
        for (e, a) in [(10.0, 20.0), (60.0, 200.0), (89.0, 359.0)] {
            v.light_elevation_deg = e;
            v.light_azimuth_deg = a;
            let (x, y) = v.light_disc();
            v.set_light_from_disc(x, y);
            assert!((v.light_elevation_deg - e).abs() < 1e-9);
            assert!((v.light_azimuth_deg - a).abs() < 1e-9);
        }
    }

    #[test]
    fn sweep_spans_the_range_and_returns() {
        let s = Sweep {
            start_distance: 3.0,
            start_time: 10.0,
            period: 8.0,
        };
        let ds: Vec<f64> = (0..800)
            .filter_map(|i| s.distance(10.0 + f64::from(i) * 0.01))
            .collect();
        let min = ds.iter().cloned().fold(f64::INFINITY, f64::min);
        let max = ds.iter().cloned().fold(0.0, f64::max);
        assert!((min - Sweep::RANGE.0).abs() < 0.01 && (max / Sweep::RANGE.1 - 1.0).abs() < 0.01);
        assert!((ds[0] - 3.0).abs() < 0.05 && (ds[ds.len() - 1] / 3.0 - 1.0).abs() < 0.02);
        assert!(s.distance(18.5).is_none());
    }

    #[test]
    fn orbit_and_zoom_stay_in_range() {
        let mut v = ViewState::default();
        v.orbit(0.0, 1e6);
        assert_eq!(v.camera.elevation_deg, Camera::MAX_ELEVATION_DEG);
        v.orbit(0.0, -1e6);
        assert_eq!(v.camera.elevation_deg, 0.0);
        v.zoom(1e6);
        assert_eq!(v.camera.distance, DISTANCE_RANGE.0);
        v.zoom(-1e6);
        assert_eq!(v.camera.distance, DISTANCE_RANGE.1);
        v.zoom(f64::NAN);
        assert!(v.camera.distance.is_finite());
    }
}
