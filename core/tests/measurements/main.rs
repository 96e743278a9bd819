//! Measurements: the experiments behind the design documents (`docs/design/`), kept runnable so a
//! figure can be measured again on the current build. Most are `#[ignore]`d because they print
//! tables and take minutes:
//! `cargo test --release -p lodestone-core --test measurements -- --ignored --nocapture NAME`.
//! The few that are not ignored hold a measured property as a test.

mod evaluation;
mod slope_masking;
mod slope_weights;
mod transfer_masking;
mod transfer_masking_prototype;
