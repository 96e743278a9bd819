//! Sample correlations: Pearson's and Spearman's (Pearson's of the ranks), for checking a
//! prediction against a measurement over many pixels.

/// Ranks 0, 1, … of `v` in ascending order (ties in order of appearance; NaN sorts last).
pub fn ranks(v: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|i, j| v[*i].total_cmp(&v[*j]));
    let mut r = vec![0.0; v.len()];
    for (k, i) in order.into_iter().enumerate() {
        r[i] = k as f64;
    }
    r
}

/// Pearson's correlation of the pairs `(a_i, b_i)` over the shorter length: in [−1, 1]; 0 with
/// fewer than two pairs or where either side is constant (no linear relation can be measured).
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    if n < 2 {
        return 0.0;
    }
    let (a, b) = (&a[..n], &b[..n]);
    let nf = n as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / nf, b.iter().sum::<f64>() / nf);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    let r = cov / (va * vb).sqrt();
    if r.is_finite() {
        r.clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// Spearman's rank correlation: Pearson's of the ranks (monotone relations give ±1).
pub fn spearman(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    pearson(&ranks(&a[..n]), &ranks(&b[..n]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_relations_give_plus_or_minus_one() {
        let a = [1.0, 2.0, 3.0, 4.0];
        assert!((pearson(&a, &[3.0, 5.0, 7.0, 9.0]) - 1.0).abs() < 1e-12);
        assert!((pearson(&a, &[-1.0, -2.0, -3.0, -4.0]) + 1.0).abs() < 1e-12);
        // Monotone but not linear: Spearman 1, Pearson below.
        let cubes = a.map(|x: f64| x.powi(3));
        assert!((spearman(&a, &cubes) - 1.0).abs() < 1e-12);
        assert!(pearson(&a, &cubes) < 0.99);
        assert_eq!(ranks(&[0.3, 0.1, 0.2]), vec![2.0, 0.0, 1.0]);
    }

    #[test]
    fn a_known_value_and_degenerate_input() {
        // x = 1..5, y = (2, 1, 4, 3, 5): deviations give Σdxdy = 8, Σdx² = Σdy² = 10, r = 0.8.
        let r = pearson(&[1.0, 2.0, 3.0, 4.0, 5.0], &[2.0, 1.0, 4.0, 3.0, 5.0]);
        assert!((r - 0.8).abs() < 1e-12, "{r}");
        assert_eq!(pearson(&[1.0], &[2.0]), 0.0);
        assert_eq!(pearson(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]), 0.0);
        assert_eq!(pearson(&[1.0, f64::NAN], &[1.0, 2.0]), 0.0);
        assert_eq!(spearman(&[], &[]), 0.0);
    }
}
