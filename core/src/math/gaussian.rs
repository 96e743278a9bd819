//! Helpers for Gaussian distributions in the plane.

/// Lower-triangular Cholesky factor `(l11, l21, l22)` of the symmetric matrix `[[xx, xy], [xy, yy]]`,
/// so that `L Lᵀ` is the matrix and `s = μ + L z` with `z ~ N(0, I)` has that covariance.
///
/// Semi-definite safe: a zero or negative diagonal gives a zero column instead of NaN (`xx ≤ 0`
/// gives `l11 = l21 = 0`; a rank-one matrix gives `l22 = 0`).
pub fn cholesky(xx: f64, xy: f64, yy: f64) -> (f64, f64, f64) {
    let l11 = xx.max(0.0).sqrt();
    let l21 = if l11 > 0.0 { xy / l11 } else { 0.0 };
    (l11, l21, (yy - l21 * l21).max(0.0).sqrt())
}

/// Eigenvalues of a 2×2 matrix whose eigenvalues are real (a covariance, or the product of two),
/// larger first: `½(tr ± √(tr² − 4 det))`, the discriminant clamped at 0 against rounding.
pub fn eigenvalues(m: glam::DMat2) -> (f64, f64) {
    let (tr, det) = (m.x_axis.x + m.y_axis.y, m.determinant());
    let d = (tr * tr - 4.0 * det).max(0.0).sqrt();
    (0.5 * (tr + d), 0.5 * (tr - d))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric matrix's eigenvalues, and a repeated one whose discriminant rounds below 0.
    #[test]
    fn eigenvalues_of_known_matrices() {
        let m = glam::DMat2::from_cols(glam::DVec2::new(2.0, 1.0), glam::DVec2::new(1.0, 2.0));
        assert_eq!(eigenvalues(m), (3.0, 1.0));
        let (a, b) = eigenvalues(glam::DMat2::IDENTITY * 0.1);
        assert!((a - 0.1).abs() < 1e-15 && (b - 0.1).abs() < 1e-15);
    }

    /// `L Lᵀ` reproduces the matrix; singular and negative inputs stay finite.
    #[test]
    fn factor_reproduces_the_matrix() {
        for (xx, xy, yy) in [
            (4.0, 1.0, 2.0),
            (0.09, 0.02, 0.01),
            (1.0, 1.0, 1.0),
            (2.0, 0.0, 0.0),
        ] {
            let (a, b, c) = cholesky(xx, xy, yy);
            assert!((a * a - xx).abs() < 1e-12);
            assert!((a * b - xy).abs() < 1e-12);
            assert!((b * b + c * c - yy).abs() < 1e-12);
        }
        assert_eq!(cholesky(0.0, 0.0, 0.0), (0.0, 0.0, 0.0));
        let (a, b, c) = cholesky(-1.0, 0.5, -1.0);
        assert!(a == 0.0 && b == 0.0 && c == 0.0);
    }
}
