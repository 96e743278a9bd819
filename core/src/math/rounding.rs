//! Directed rounding from f64 to f32, for bounds the GPU reads (a bound rounded to nearest could
//! land on the wrong side of the value it bounds).

/// The largest f32 at or below `x` (NaN stays NaN).
pub fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x { f.next_down() } else { f }
}

/// The smallest f32 at or above `x` (NaN stays NaN).
pub fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x { f.next_up() } else { f }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each side of the value, never across it, and exact where f32 is exact.
    #[test]
    fn rounds_to_the_asked_side() {
        for x in [0.1, -0.1, 1.0 / 3.0, -1e-40, 3e38, 1e300, -1e300, 0.0, 2.5] {
            assert!(
                f64::from(f32_down(x)) <= x && f64::from(f32_up(x)) >= x,
                "{x}"
            );
        }
        assert_eq!(f32_up(2.5), 2.5);
        assert_eq!(f32_down(2.5), 2.5);
        assert_eq!(f32_up(1e300), f32::INFINITY);
        assert_eq!(f32_down(1e300), f32::MAX);
    }
}
