//! Microfacet theory of a rough surface with Gaussian slopes: the slope statistics, Smith's Λ, the
//! height-correlated masking–shadowing G2, the effective height distribution D_h seen under masking,
//! the visible slope distribution D_s, the base BRDF of a facet (and its average over D_s), and the
//! HN12 attribute–height model.
//!
//! | concept | module | paper |
//! |---|---|---|
//! | slopes N(μ, Σ), σ_n | [`slopes`] | [HN12 Sec. 5.5] |
//! | Smith Λ, visibility `Φ(t)^Λ` | [`smith`] | [HN12 Eqs. 4–6] |
//! | G2, L = Λo ⊕ Λi, V̄ | [`masking_shadowing`] | [HNPN14 Eqs. 11–12] |
//! | D_h, its moments and fits | [`effective_height`] | [HNPN14 Eqs. 14–17] |
//! | D_s, the slope rule that runs | [`visible_slopes`] | [HNPN14 Sec. 5.2] |
//! | slopes under a transfer curve: bins, masking | [`height_mixture`] | #17, Smith 1967 |
//! | the noise's exact slope density (saddlepoint) | [`slope_density`] | #17, Daniels 1954 |
//! | masking conditioned on the facet's slope | [`slope_masking`] | #17, Smith 1967, Rice |
//! | base BRDF, filtered specular | [`brdf`] | [HN12 Sec. 5.5] |
//! | a(h) = ā + a_s·s(h) | [`attribute`] | [HN12 Eq. 17] |

pub mod attribute;
pub mod barrier_masking;
pub mod brdf;
pub mod effective_height;
pub mod height_mixture;
pub mod masking_shadowing;
pub mod slope_density;
pub mod slope_masking;
pub mod slope_rule;
pub mod slopes;
pub mod smith;
pub mod transfer;
pub mod visible_slopes;
