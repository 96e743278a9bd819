//! Reproducible random numbers for the Monte Carlo ground truth and the noise's realisation,
//! independent of any RNG crate's version.

/// SplitMix64 (Steele, Lea, Flood 2014): advances `state` and returns a uniform number in [0, 1)
/// with 53 random bits.
pub fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A standard normal draw by Box–Muller from two [`splitmix`] numbers (the first kept away from 0,
/// so the logarithm is finite).
pub fn standard_normal(state: &mut u64) -> f64 {
    let u1 = splitmix(state).max(1e-300);
    let u2 = splitmix(state);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean 0 and variance 1 within their standard errors over 200 000 draws; uniforms in [0, 1).
    #[test]
    fn normal_draws_have_unit_variance() {
        let mut s = 7u64;
        let n = 200_000;
        let (mut m, mut v) = (0.0, 0.0);
        for _ in 0..n {
            let z = standard_normal(&mut s);
            assert!(z.is_finite());
            m += z;
            v += z * z;
        }
        m /= n as f64;
        v = v / n as f64 - m * m;
        assert!(m.abs() < 4.0 / (n as f64).sqrt(), "mean {m}");
        assert!(
            (v - 1.0).abs() < 4.0 * (2.0 / n as f64).sqrt(),
            "variance {v}"
        );
        let mut s = 0u64;
        assert!(
            (0..10_000)
                .map(|_| splitmix(&mut s))
                .all(|u| (0.0..1.0).contains(&u))
        );
    }
}
