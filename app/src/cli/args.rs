//! Argument types and value parsers the subcommands share: angles, distances, sizes, shapes,
//! march and masking choices, each with its range in the message when a value is refused.

/// `eval --slope-masking`: [`lodestone_core::microfacet::slope_masking::SlopeMasking`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SlopeMaskingArg {
    /// Smith's: visibility depends on the height alone.
    Smith,
    /// Conditioned on the facet's height and slope along the ray jointly (the default).
    Conditioned,
}

impl From<SlopeMaskingArg> for lodestone_core::microfacet::slope_masking::SlopeMasking {
    fn from(a: SlopeMaskingArg) -> Self {
        match a {
            SlopeMaskingArg::Smith => Self::Smith,
            SlopeMaskingArg::Conditioned => Self::Conditioned,
        }
    }
}

/// What `render` draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RenderMode {
    /// Naive MIP.
    Naive,
    /// View-independent texture filtering.
    ViewIndependent,
    /// The filtered model.
    Filtered,
    /// Ray-traced ground truth.
    Truth,
    /// Heat map of |filtered − truth|.
    Error,
    /// Every mode and every error map, into a directory.
    All,
}

/// A view mode `bench` can time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchMode {
    /// The naive view.
    Naive,
    /// The view-independent filtered view.
    ViewIndependent,
    /// The filtered view.
    Filtered,
    /// Ground truth (one sample per pixel per frame).
    Truth,
}

impl BenchMode {
    /// Every mode, in the table's order.
    pub fn all() -> Vec<Self> {
        vec![
            Self::Naive,
            Self::ViewIndependent,
            Self::Filtered,
            Self::Truth,
        ]
    }

    /// The mode's name in the bench's JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Naive => "naive",
            Self::ViewIndependent => "view_independent",
            Self::Filtered => "filtered",
            Self::Truth => "truth",
        }
    }
}

/// How marches step and refine the crossing they find (`lodestone_core::scene::march::March`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MarchArg {
    /// Global Lipschitz steps and bisection, 48 halvings on the CPU and 24 on the GPU (the reference).
    Reference,
    /// The octave march (noise drivers) and the Illinois method to the same bracket width.
    Fast,
}

impl MarchArg {
    /// The core value.
    pub fn march(self) -> lodestone_core::scene::march::March {
        match self {
            Self::Reference => lodestone_core::scene::march::March::Reference,
            Self::Fast => lodestone_core::scene::march::March::Fast,
        }
    }
}

/// Whether the analytic views' camera rays can stop on the unresolved relief of a crest they pass
/// (`lodestone_core::eval::interception::Interception`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum InterceptionArg {
    /// Rays meet h̄ only (the reference: no crest stops them).
    Off,
    /// Rays can stop on crests (the views' default).
    Crests,
}

impl InterceptionArg {
    /// The core value.
    pub fn interception(self) -> lodestone_core::eval::interception::Interception {
        match self {
            Self::Off => lodestone_core::eval::interception::Interception::Off,
            Self::Crests => lodestone_core::eval::interception::Interception::Crests,
        }
    }
}

/// The base shape `object` displaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ObjectShapeArg {
    /// A sphere of `--radius`.
    Sphere,
    /// A ring torus of `--radius` and `--minor` around z.
    Torus,
    /// The closed OBJ mesh of `--mesh`.
    Mesh,
}

impl ObjectShapeArg {
    /// Its name for [`crate::object::shape`].
    pub fn name(self) -> &'static str {
        match self {
            Self::Sphere => "sphere",
            Self::Torus => "torus",
            Self::Mesh => "mesh",
        }
    }
}

/// The object `render` draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ShapeArg {
    /// The unbounded plane.
    Plane,
    /// A cylinder around an axis parallel to x.
    Cylinder,
}

impl ShapeArg {
    /// The object, with `radius` for the cylinder (which must be positive and finite).
    pub fn shape(self, radius: f64) -> Result<lodestone_core::scene::shape::Shape, String> {
        match self {
            ShapeArg::Plane => Ok(lodestone_core::scene::shape::Shape::Plane),
            ShapeArg::Cylinder if radius > 0.0 && radius.is_finite() => {
                Ok(lodestone_core::scene::shape::Shape::Cylinder { radius })
            }
            ShapeArg::Cylinder => Err(format!("--radius must be a positive number, got {radius}")),
        }
    }
}

/// A finite number in `[lo, hi]` named `what`, or a message that gives the range and what was
/// typed (NaN and infinities are refused: they used to become black images or "0.00%" errors).
pub fn number_in(s: &str, lo: f64, hi: f64, what: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{what} must be a number, got {s:?}"))?;
    if !(lo..=hi).contains(&v) {
        return Err(format!("{what} must be between {lo} and {hi}, got {s}"));
    }
    Ok(v)
}

/// A reflectance or albedo: 0 to 1.
pub fn unit_fraction(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 1.0, "a reflectance")
}

/// A GGX roughness α: 0.01 to 1.
pub fn ggx_alpha(s: &str) -> Result<f64, String> {
    number_in(s, 0.01, 1.0, "the GGX roughness α")
}

/// A relative standard error to reach, 0.0001 to 0.5.
pub fn precision(s: &str) -> Result<f64, String> {
    number_in(s, 1e-4, 0.5, "relative standard error")
}

/// A camera angle from the normal: 0 to [`Camera::MAX_ELEVATION_DEG`] (89.5) degrees.
///
/// [`Camera::MAX_ELEVATION_DEG`]: lodestone_core::scene::camera::Camera::MAX_ELEVATION_DEG
pub fn view_angle(s: &str) -> Result<f64, String> {
    let max = lodestone_core::scene::camera::Camera::MAX_ELEVATION_DEG;
    number_in(s, 0.0, max, "the view angle (degrees from the normal)")
}

/// A light angle from the normal: 0 to 180 degrees (past 90 the sun is below the horizon).
pub fn light_angle(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 180.0, "the light angle (degrees from the normal)")
}

/// An azimuth: any finite angle up to ±3600 degrees.
pub fn azimuth(s: &str) -> Result<f64, String> {
    number_in(s, -3600.0, 3600.0, "the azimuth (degrees)")
}

/// A camera distance in the editor's range ([`DISTANCE_RANGE`]).
///
/// [`DISTANCE_RANGE`]: crate::editor::view_state::DISTANCE_RANGE
pub fn distance(s: &str) -> Result<f64, String> {
    let (lo, hi) = crate::editor::view_state::DISTANCE_RANGE;
    number_in(s, lo, hi, "the camera distance (world units)")
}

/// A target relative standard error in percent: 0 (none) to 100.
pub fn truth_se(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 100.0, "the truth's standard error target (percent)")
}

/// A thin lens's radius: 0 (a pinhole) to 10 world units.
pub fn lens_radius(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 10.0, "the lens radius (world units)")
}

/// An adaptive ground truth's budget: 0 (none) to 4096 rays per pixel on average.
pub fn ray_budget(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 4096.0, "the ray budget (rays per pixel)")
}

/// A cylinder radius: 0.01 to 10⁴ world units.
pub fn radius(s: &str) -> Result<f64, String> {
    number_in(s, 0.01, 1e4, "the cylinder radius (world units)")
}

/// `eval`'s ground-truth sample count: 2 (a standard error needs two) to 10⁸.
pub fn eval_samples(s: &str) -> Result<usize, String> {
    let v: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("the sample count must be a whole number, got {s:?}"))?;
    if !(2..=100_000_000).contains(&v) {
        return Err(format!(
            "the sample count must be between 2 and 100000000, got {s}"
        ));
    }
    Ok(v)
}

/// Parse "WxH".
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        return Err(format!("size must be between 1x1 and 8192x8192, got {s:?}"));
    }
    Ok((w, h))
}

/// Image formats `render --mode all` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Formats {
    /// 8-bit sRGB PNG only.
    Png,
    /// Linear EXR only (views as EXR; error maps as PNG heat maps and EXR |mode − truth|).
    Exr,
    /// Both (error maps as PNG heat maps and as linear EXR |mode − truth| per channel).
    Both,
}
