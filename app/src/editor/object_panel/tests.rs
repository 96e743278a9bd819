//! Tests of [`super`].

use super::*;

/// Quick frames get no preview; slower ones one whose k² fewer cones take at most the target
/// (while k is below its cap), never a factor below 2 or above 8, and never from a NaN.
#[test]
fn previews_shrink_with_the_last_frames_cost() {
    assert_eq!(preview_divisor(0.0), 1);
    assert_eq!(preview_divisor(PREVIEW_ABOVE_S), 1);
    assert_eq!(preview_divisor(f64::NAN), 1);
    for secs in [0.21, 0.5, 1.0, 2.1, 4.0] {
        let k = preview_divisor(secs);
        assert!((2..=8).contains(&k), "{secs}: {k}");
        assert!(secs / f64::from(k * k) <= PREVIEW_TARGET_S, "{secs}: {k}");
        assert!(
            k == 2 || secs / f64::from((k - 1) * (k - 1)) > PREVIEW_TARGET_S,
            "{secs}: {k} is not the smallest"
        );
    }
    assert_eq!(preview_divisor(1e9), 8);
}
