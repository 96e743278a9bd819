//! The filtered model's masking beyond Smith's, tabulated per material: masking conditioned on the
//! facet's slope for noise drivers ([`slope_masking_table`], used by [`slope_weights`]), and masking
//! that knows the driver's slope under a transfer curve ([`transfer_masking_table`], its Gaussian
//! moments in [`transfer_moments`]). The functions they tabulate are `microfacet::slope_masking` and
//! `microfacet::barrier_masking`; these tables are what the views read (WGSL mirrors under
//! `shaders/eval/masking/`). `docs/design/slope-masking.md` and `docs/design/transfer-curves.md` have
//! the measurements.

pub mod slope_masking_table;
pub mod slope_weights;
pub mod transfer_masking_table;
pub mod transfer_moments;
