//! Tests of [`super`].

use super::*;

/// The references are not the cases themselves, and they can fail: a 1% brighter diffuse
/// colour or the untransposed anisotropy is caught.
#[test]
fn references_catch_a_wrong_answer() {
    for case in material_cases() {
        if let Reference::Same { material, .. } = &case.reference {
            assert_ne!(**material, case.material, "{}", case.name);
        }
    }
    // The anisotropy case against its reference without the mirror: not the same.
    let r = 1e6f64;
    let p = procedural(&with_sigmas(0.05, 0.35 * r.sqrt(), 0.35 / r.sqrt()));
    let q = procedural(&with_sigmas(0.05, 0.35 / r.sqrt(), 0.35 * r.sqrt()));
    let (a, b) = (
        compared_statistics(&p, AZIMUTHS),
        compared_statistics(&q, AZIMUTHS),
    );
    let dev = a
        .iter()
        .zip(&b)
        .map(|(x, y)| deviation(*x, *y, 1e-3))
        .fold(0.0, f64::max);
    assert!(dev > 1e-2, "{dev}");
    // A 1% brighter attribute mean is off the clamped-attribute reference.
    let case = material_cases()
        .into_iter()
        .find(|c| matches!(c.reference, Reference::ClampedAttribute { .. }))
        .expect("the attribute case");
    let p = procedural(&case.material);
    let want = expected(&case, &p);
    let mut brighter = case.material.clone();
    if let ColorModel::Attribute { mean, .. } = &mut brighter.color {
        mean[1] *= 1.01;
    }
    let got = compared_statistics(&procedural(&brighter), AZIMUTHS);
    let dev = got
        .iter()
        .zip(&want)
        .map(|(x, y)| deviation(*x, *y, 1e-3))
        .fold(0.0, f64::max);
    assert!(dev > 1e-3, "{dev}");
}
