//! Water filling: integer counts in proportion to weights under per-item floors and caps, the
//! allocation behind an adaptive ground truth's rays (Neyman's `n_p ∝ σ_p` [BSSBH13 Sec. 2.4]
//! with every pixel's least and most rays).

/// `v` where it is finite and positive, else 0.
fn clean(v: f64) -> f64 {
    if v.is_finite() && v > 0.0 { v } else { 0.0 }
}

/// Integer counts in proportion to `weight`, each within `[floor[p], cap[p]]` (a cap below its
/// floor counts as the floor), summing to `total` rounded, or to what the floors force beyond it,
/// or to what the caps allow below it; what the caps leave over goes to the others (water
/// filling: `n_p = clamp(λ·w_p, floor_p, cap_p)` with λ bisected). Non-finite or negative weights,
/// floors and caps count as 0, a non-finite `total` as 0; the rounding error is carried along the
/// pixels, so the sum stays within one of its goal.
pub fn water_fill(weight: &[f64], floor: &[f64], cap: &[f64], total: f64) -> Vec<u32> {
    let n = weight.len();
    let at = |v: &[f64], p: usize| clean(v.get(p).copied().unwrap_or(0.0));
    let w: Vec<f64> = (0..n).map(|p| at(weight, p)).collect();
    let lo_b: Vec<f64> = (0..n).map(|p| at(floor, p).min(u32::MAX as f64)).collect();
    let hi_b: Vec<f64> = (0..n)
        .map(|p| at(cap, p).min(u32::MAX as f64).max(lo_b[p]))
        .collect();
    let total = clean(total).round();
    let spent = |lambda: f64| -> f64 {
        (0..n)
            .map(|p| (lambda * w[p]).clamp(lo_b[p], hi_b[p]))
            .sum()
    };
    // Σ clamp(λ w_p) is non-decreasing in λ: bisect for the λ that spends the total.
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    while spent(hi) < total && hi < 1e300 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if spent(mid) < total {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut carry = 0.0;
    (0..n)
        .map(|p| {
            let want = (hi * w[p]).clamp(lo_b[p], hi_b[p]) + carry;
            let r = want.round().clamp(lo_b[p], hi_b[p]);
            carry = want - r;
            r as u32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Water filling spends the total in proportion to the weights, lifts floors, and gives what
    /// a cap cuts to the others; what no one can take is not spent.
    #[test]
    fn water_filling_respects_floors_and_caps() {
        assert_eq!(water_fill(&[1.0, 3.0], &[0.0; 2], &[100.0; 2], 8.0), [2, 6]);
        // The second is capped at 4: the first takes the rest.
        assert_eq!(
            water_fill(&[1.0, 3.0], &[0.0; 2], &[100.0, 4.0], 8.0),
            [4, 4]
        );
        // A floor above the proportional share.
        assert_eq!(
            water_fill(&[1.0, 3.0], &[5.0, 0.0], &[100.0; 2], 8.0),
            [5, 3]
        );
        // Caps of 2 cannot hold 8: 4 are spent.
        assert_eq!(water_fill(&[1.0, 3.0], &[0.0; 2], &[2.0; 2], 8.0), [2, 2]);
        // Hostile inputs count as 0.
        let c = water_fill(
            &[f64::NAN, -1.0, 2.0],
            &[f64::INFINITY, 1.0, f64::NAN],
            &[f64::NAN, 3.0, 1e9],
            f64::NAN,
        );
        assert_eq!(c, [0, 1, 0]);
        assert!(water_fill(&[], &[], &[], 4.0).is_empty());
    }
}
