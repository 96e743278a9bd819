//! Hostile sizes (issue #16): a view target or material data beyond what the adapter can bind is a
//! clear error before anything is created, never a wgpu validation panic.

use lodestone_render::view_target::max_pixels;
use lodestone_render::{RenderError, ViewTarget};

#[test]
fn targets_beyond_the_adapter_limit_are_refused_and_smaller_ones_render() {
    let Some(r) = lodestone_tests::renderer("the limits test") else {
        return;
    };
    let max = max_pixels(r.context());
    assert!(max >= 1 << 20, "{max}");
    // One row more than fits, at the CLI's widest image.
    let w = 8192u32;
    let h = u32::try_from(max / u64::from(w) + 1).expect("height");
    match ViewTarget::new(&r, w, h) {
        Err(RenderError::TooLarge { bytes, limit, .. }) => assert!(bytes > limit),
        other => panic!(
            "{w}×{h} ({} px, max {max}): {other:?}",
            u64::from(w) * u64::from(h)
        ),
    }
    let msg = ViewTarget::new(&r, w, h).unwrap_err().to_string();
    assert!(
        msg.contains("more than this adapter can bind") && msg.contains("at most"),
        "{msg}"
    );
    // A size within the limit is accepted.
    assert!(ViewTarget::new(&r, 1024, 1024).is_ok());
}
