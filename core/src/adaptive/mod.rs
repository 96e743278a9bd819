//! Adaptive ground truth [BSSBH13]: the statistical model predicts, before any ray is traced, each
//! pixel's value and one ray's variance, and the image's bandwidth; a plan spends the rays where
//! they buy the most error, and a reconstruction pools rays where the image is flat within its noise.
//! The rays themselves are always the explicit surface's (`eval::ground_truth`): the model decides
//! where they go, never what they return.
//!
//! | concept | module | paper |
//! |---|---|---|
//! | one ray's predicted variance at a pixel | [`ray_variance`] | [BSSBH13 Sec. 2.4, Eqs. 8–9] |
//! | the image's predicted bandwidth | [`image_bandwidth`] | [BSSBH13 Eqs. 3–6] |
//! | the prediction over a camera image, and each pixel's own spread | [`truth_prediction`] | — |
//! | the sampling plan: lattice, counts, a posteriori refinement, progressive rounds | [`sampling_plan`] | [BSSBH13 Secs. 2.4, 3] |
//! | reconstruction over windows flat within the truth's noise (intersection of confidence intervals) | [`windows`] | [BSSBH13 Sec. 3] |
//!
//! `docs/design/adaptive-truth.md` has the measurements behind each choice.

pub mod image_bandwidth;
pub mod ray_variance;
pub mod sampling_plan;
pub mod truth_prediction;
pub mod windows;

#[cfg(test)]
mod image_bandwidth_tests;
