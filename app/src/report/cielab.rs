//! CIELAB colour differences for error reports: linear sRGB (D65) → CIE XYZ → L*a*b* with the D65
//! white, and ΔE*ab (CIE 1976), the Euclidean distance in L*a*b* (≈ 2.3 is a just-noticeable
//! difference). Negative and non-finite inputs are treated as 0 (a renderer's error maps never need
//! more).

/// Linear sRGB (D65, Rec. 709 primaries) to CIE XYZ (Y = 1 for white).
pub fn linear_srgb_to_xyz(c: [f64; 3]) -> [f64; 3] {
    let c = c.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
    [
        0.412_456_4 * c[0] + 0.357_576_1 * c[1] + 0.180_437_5 * c[2],
        0.212_672_9 * c[0] + 0.715_152_2 * c[1] + 0.072_175_0 * c[2],
        0.019_333_9 * c[0] + 0.119_192_0 * c[1] + 0.950_304_1 * c[2],
    ]
}

/// The D65 reference white in XYZ (Y = 1).
pub const D65: [f64; 3] = [0.950_47, 1.0, 1.088_83];

fn lab_f(t: f64) -> f64 {
    const E: f64 = 216.0 / 24389.0;
    const K: f64 = 24389.0 / 27.0;
    if t > E {
        t.cbrt()
    } else {
        (K * t + 16.0) / 116.0
    }
}

/// Linear sRGB to CIE L*a*b* (D65 white; L* = 100 for linear (1, 1, 1)).
pub fn linear_srgb_to_lab(c: [f64; 3]) -> [f64; 3] {
    let xyz = linear_srgb_to_xyz(c);
    let f = [0, 1, 2].map(|k| lab_f(xyz[k] / D65[k]));
    [
        116.0 * f[1] - 16.0,
        500.0 * (f[0] - f[1]),
        200.0 * (f[1] - f[2]),
    ]
}

/// ΔE*ab between two linear sRGB colours.
pub fn delta_e76(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (p, q) = (linear_srgb_to_lab(a), linear_srgb_to_lab(b));
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_colours() {
        // White and black.
        let w = linear_srgb_to_lab([1.0; 3]);
        assert!(
            (w[0] - 100.0).abs() < 1e-3 && w[1].abs() < 1e-2 && w[2].abs() < 1e-2,
            "{w:?}"
        );
        assert_eq!(linear_srgb_to_lab([0.0; 3]), [0.0, 0.0, 0.0]);
        // sRGB primaries (published L*a*b* of pure sRGB red and green, D65).
        let r = linear_srgb_to_lab([1.0, 0.0, 0.0]);
        assert!(
            (r[0] - 53.24).abs() < 0.02
                && (r[1] - 80.09).abs() < 0.05
                && (r[2] - 67.20).abs() < 0.05,
            "{r:?}"
        );
        let g = linear_srgb_to_lab([0.0, 1.0, 0.0]);
        assert!(
            (g[0] - 87.73).abs() < 0.02
                && (g[1] + 86.18).abs() < 0.05
                && (g[2] - 83.18).abs() < 0.05,
            "{g:?}"
        );
        // Middle grey: linear 0.18 is L* ≈ 49.5.
        assert!((linear_srgb_to_lab([0.18; 3])[0] - 49.5).abs() < 0.05);
    }

    #[test]
    fn delta_e_is_a_distance() {
        let (a, b) = ([0.2, 0.3, 0.1], [0.25, 0.28, 0.12]);
        assert_eq!(delta_e76(a, a), 0.0);
        assert!((delta_e76(a, b) - delta_e76(b, a)).abs() < 1e-12);
        assert!(delta_e76(a, b) > 0.5);
        assert!(delta_e76([f64::NAN, -1.0, 0.0], [0.0; 3]) == 0.0);
    }
}
