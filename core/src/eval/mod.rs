//! CPU evaluation of one pixel footprint under every method: naive MIP, view-independent texture
//! filtering, filtered (the papers' model), and ground truth on the explicit micro-geometry.
//!
//! This is the reference the GPU renderer is tested against, so it is written to be obviously right
//! rather than fast.
//!
//! * **Footprint**: a Gaussian weight `w_P` over the mean plane z = 0 (where the pixel's eye rays cross
//!   it), centre `x0`, covariance Σ_p ([`crate::driver::footprint::Footprint`]).
//! * **Naive**: the colour map of the footprint-filtered driver, `C(f̄)` [HNPN14 Sec. 4, Sec. 9],
//!   shaded by the base BRDF at the filtered (mean-slope) normal; no masking, no shadowing.
//! * **View-independent**: the exact footprint average of the colour, `⟨C, N(f̄, σ_f²)⟩`
//!   [HNPN14 Eq. 9], shaded like naive: what a perfectly mip-mapped colour texture gives.
//! * **Filtered**: `I = V̄ · (C̄ · ρ̄_d + ρ̄_s)` [HNPN14 Eq. 10, 13]: C̄ is the colour map over the
//!   effective height distribution D_h [HNPN14 Eqs. 14–17] (exact table or fits), with masking L from
//!   the unresolved slopes (correlated or not) [HNPN14 Eq. 12]; the HN12 attribute model uses its closed
//!   form [HN12 Eq. 17]; ρ̄_d is the clamped cosine averaged over the visible slope distribution
//!   D_s ∝ p(s)·(ωo_z − s·ωo_xy)⁺ [HNPN14 Sec. 5.2] on n² polar nodes ([`crate::microfacet::visible_slopes::slope_rule`], n = 8 by
//!   default) jointly with the slope colour and environment irradiance, and ρ̄_s the Beckmann lobe
//!   widened by the unresolved slopes (σ_n² + σ_n0² [HN12 Sec. 5.5]). Transfer functions enter
//!   through their moment tables [HNPN14 Eqs. 21–26]; under a transfer curve the slopes are a
//!   mixture of Gaussians over bins of the driver's value with height-dependent masking
//!   ([`mixture_bins`]; the 241-node form it is checked against: [`mixture`]).
//! * **Ground truth**: eye rays through points drawn from `w_P`, marched onto the explicit surface
//!   ([`crate::scene::surface::Surface::march`]), shaded with the base BRDF at the true micro-normal, with a real shadow ray.
//!   No Smith, no Λ. Reported with its standard error.
//!
//! One file per method: [`naive`], [`view_independent`], [`filtered`], [`ground_truth`]; the
//! level-of-detail surface the analytic views march ([`lod_surface`]), one pixel of a view
//! ([`pixel`], [`cylinder`]); the material compiled once into closed enums ([`compiled`]), the
//! shading inputs every method shares ([`shading`]) and the footprint statistics ([`query`]).

pub mod compiled;
pub mod cylinder;
pub mod evaluator;
pub mod filtered;
pub mod ground_truth;
pub mod interception;
pub mod lod_surface;
pub mod masking;
pub mod mixture;
pub mod mixture_bins;
pub mod naive;
pub mod pixel;
pub mod query;
pub mod shading;
pub mod view_independent;

#[cfg(test)]
mod independent_tests;
#[cfg(test)]
mod tests;

pub use compiled::{CompiledColor, CompiledTransfer};
pub use evaluator::Evaluator;
pub use query::FootprintQuery;

/// A Monte Carlo estimate with its standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Mean linear RGB.
    pub mean: [f64; 3],
    /// Standard error of the mean, per channel.
    pub std_error: [f64; 3],
    /// Samples used.
    pub samples: usize,
}

/// The statistical methods, for [`Evaluator::pixel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// [`Evaluator::naive`].
    Naive,
    /// [`Evaluator::view_independent`].
    ViewIndependent,
    /// [`Evaluator::filtered`].
    Filtered,
}
