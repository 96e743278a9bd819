//! Tests of [`super`].

use crate::driver::footprint::Footprint;
use crate::driver::noise::NoiseParams;
use crate::eval::Evaluator;
use crate::eval::lod_surface::LOD_SETTLE;
use crate::material::{Driver, Heights, Material, Slopes};
use crate::math::random::splitmix;
use crate::microfacet::transfer::{Curve, TransferFunction};
use crate::scene::direction::direction;
use crate::scene::march::March;
use crate::scene::surface::{Surface, Trace};
use glam::{DVec2, DVec3};
use std::f64::consts::TAU;

/// Materials that stress the march: Gaussian heights in 3 and 6 octaves (grouped levels), a
/// transfer function with flat tops and steep pits (sponge), and one with a kinked floor (moss).
fn materials() -> Vec<Material> {
    let noise = |components, octaves, gain| {
        Driver::Noise(NoiseParams {
            components,
            octaves,
            gain,
            ..NoiseParams::default()
        })
    };
    let m = |driver, transfer, sigma_h, sigma_n| Material {
        driver,
        heights: Heights { sigma_h, transfer },
        slopes: Slopes {
            sigma_nx: sigma_n,
            sigma_ny: sigma_n * 0.7,
        },
        ..Material::default()
    };
    vec![
        m(noise(48, 3, 0.5), TransferFunction::Identity, 0.05, 0.35),
        m(noise(60, 6, 0.7), TransferFunction::Identity, 0.1, 0.8),
        m(
            noise(64, 3, 0.5),
            TransferFunction::Curve(Curve::sponge()),
            0.08,
            0.5,
        ),
        m(
            noise(64, 3, 0.55),
            TransferFunction::Curve(Curve::moss()),
            0.06,
            0.4,
        ),
    ]
}

/// Each material twice: without and with a bound grid.
fn gridded(ms: Vec<Material>) -> Vec<(Material, bool)> {
    ms.into_iter()
        .flat_map(|m| [(m.clone(), false), (m, true)])
        .collect()
}

/// A bound grid over [3, 27]²: part of the rays' range, so rays also cross its edge.
fn with_grid(s: Surface) -> Surface {
    let s = s.with_bound_grid(DVec2::splat(15.0), 12.0);
    assert!(s.grid.is_some());
    s
}

fn with_march(s: &Surface, march: March) -> Surface {
    Surface { march, ..s.clone() }
}

/// Primary rays from 20° to 89° and shadow rays from their hits toward random lights: the octave
/// march meets the surface where the reference march does (or both escape), on every material,
/// and no earlier crossing exists along the ray (dense scan at 1/20 of the finest wavelength's
/// minimum step).
#[test]
fn the_octave_march_finds_the_reference_crossing() {
    let mut rng = 5u64;
    for (m, grid) in gridded(materials()) {
        let fast = Surface::new(&m).unwrap();
        assert_eq!(fast.march, March::Fast);
        let fast = if grid { with_grid(fast) } else { fast };
        assert!(fast.octaves(None).is_some());
        let reference = with_march(&fast, March::Reference);
        let (mut hits, mut shadows, mut differ) = (0, 0, 0);
        for i in 0..400 {
            let theta = (20.0 + 69.0 * (i % 24) as f64 / 23.0).to_radians();
            let d = -direction(theta, TAU * splitmix(&mut rng));
            let o = DVec3::new(
                40.0 * splitmix(&mut rng),
                40.0 * splitmix(&mut rng),
                fast.h_max * 1.001 + 1e-6,
            );
            let (Trace::Hit(tf), Trace::Hit(tr)) = (fast.march(o, d), reference.march(o, d)) else {
                panic!("{}: a downward ray hits", m.name)
            };
            hits += 1;
            if (tf - tr).abs() > 1e-9 * tr.max(1.0) {
                differ += 1;
                continue;
            }
            let p = o + d * tf;
            let gap = p.z - fast.height(DVec2::new(p.x, p.y));
            assert!(gap.abs() < 1e-9, "{}: off the surface by {gap}", m.name);
            // A shadow ray from the hit.
            let l = direction(
                (5.0 + 80.0 * splitmix(&mut rng)).to_radians(),
                TAU * splitmix(&mut rng),
            );
            let (a, b) = (fast.march(p, l), reference.march(p, l));
            match (a, b) {
                (Trace::Escape, Trace::Escape) => {}
                (Trace::Hit(a), Trace::Hit(b)) if (a - b).abs() <= 1e-9 * b.max(1.0) => {}
                _ => differ += 1,
            }
            shadows += 1;
        }
        assert_eq!(hits, 400);
        // Both are rigorous up to min_step; at 89° a ray can skim a crest within min_step of
        // the surface, where either may take the sliver: allow one ray in 400.
        assert!(
            differ <= 1,
            "{} (grid {grid}): {differ} of {} rays differ",
            m.name,
            hits + shadows
        );
    }
}

/// No crossing is stepped over: along grazing primary rays, a dense scan of `[0, t)` finds the
/// gap non-negative everywhere before the octave march's hit.
#[test]
fn the_octave_march_never_steps_over_a_crossing() {
    let mut rng = 9u64;
    for (m, grid) in gridded(materials()) {
        let s = Surface::new(&m).unwrap();
        let s = if grid { with_grid(s) } else { s };
        for i in 0..60 {
            let theta = (70.0 + 19.0 * (i % 10) as f64 / 9.0).to_radians();
            let d = -direction(theta, TAU * splitmix(&mut rng));
            let o = DVec3::new(20.0 * splitmix(&mut rng), 0.0, s.h_max * 1.001 + 1e-6);
            let Trace::Hit(t) = s.march(o, d) else {
                panic!("hits")
            };
            let n = 20_000;
            for j in 0..n {
                let q = o + d * (t * j as f64 / n as f64);
                let gap = q.z - s.height(DVec2::new(q.x, q.y));
                assert!(
                    gap > -1e-9,
                    "{}: crossing at {} skipped (hit at {t})",
                    m.name,
                    t * j as f64 / n as f64
                );
            }
        }
    }
}

/// The level-of-detail surface (attenuated waves, the transfer function's footprint mean) from
/// a point footprint to one that blurs two octaves, and the far field where every wave is gone
/// (the thin slab): the octave march meets h̄ where the reference march does, or (a camera
/// ray of the identity transfer) up to the settle width before it, never past it.
#[test]
fn the_octave_march_finds_the_reference_crossing_on_the_level_of_detail_surface() {
    let mut rng = 17u64;
    for (m, grid) in gridded(materials()) {
        let mut fast = Evaluator::new(&m).unwrap();
        let mut reference = fast.clone();
        reference.surface.march = March::Reference;
        if grid {
            fast.surface = with_grid(fast.surface.clone());
        }
        let scale = fast.surface.driver.finest_scale();
        let (mut differ, mut early) = (0, 0);
        for i in 0..240 {
            let fp = Footprint::isotropic(scale * [0.0, 0.05, 0.2, 0.5, 1.0, 3.0, 30.0][i % 7]);
            let theta = (30.0 + 58.0 * splitmix(&mut rng)).to_radians();
            let d = -direction(theta, TAU * splitmix(&mut rng));
            let o = DVec3::new(
                30.0 * splitmix(&mut rng),
                30.0 * splitmix(&mut rng),
                fast.surface.h_max * 1.001 + 1e-6,
            );
            let (a, b) = (fast.lod_march(o, d, fp), reference.lod_march(o, d, fp));
            let (Some(a), Some(b)) = (a, b) else {
                panic!("{}: downward rays hit h̄: {a:?} {b:?}", m.name)
            };
            // Never past the reference's crossing; before it by at most the settle width,
            // and only for camera rays of the identity transfer (the bracket's low end).
            let width = LOD_SETTLE * fp.min_std();
            assert!(a <= b + 1e-9 * b.max(1.0), "{}: {a} past {b}", m.name);
            if (a - b).abs() > 1e-9 * b.max(1.0) + width * (1.0 + 1e-9) {
                differ += 1;
            } else if a < b - 1e-9 * b.max(1.0) {
                early += 1;
            }
            let p = o + d * a;
            let gap = p.z - fast.lod_height(DVec2::new(p.x, p.y), fp);
            assert!(
                gap > -1e-9 && gap < 1e-9 + width * (d.z.abs() + fast.surface.slope_bound()),
                "{}: off h̄ by {gap}",
                m.name
            );
        }
        assert!(
            differ <= 1,
            "{} (grid {grid}): {differ} of 240 rays differ",
            m.name
        );
        // The bracket settles camera rays of the identity transfer (the new path is taken).
        let linear = matches!(m.heights.transfer, TransferFunction::Identity);
        assert!(
            !linear || early > 10,
            "{}: {early} rays settled early",
            m.name
        );
    }
}

/// With a table of f ([`crate::scene::field_grid`], over part of the rays' range so rays also
/// cross its edge) on the explicit surface (and, unchanged, the level-of-detail march beside
/// it, which does not use the table): camera rays stop within
/// `FIELD_SETTLE·top` above the surface, never past the reference's first crossing and with no
/// crossing before (dense scan); all but a few stop where the reference does (within the
/// settle band's width along the ray; the rest skim a crest within the band); shadow rays agree
/// with the reference's hit or escape.
#[test]
fn the_field_table_march_settles_on_the_first_crossing() {
    use crate::scene::field_grid::FIELD_SETTLE;
    let mut rng = 23u64;
    for m in materials() {
        let mut fast = Evaluator::new(&m).unwrap();
        fast.surface = fast
            .surface
            .clone()
            .with_field_grid(DVec2::splat(15.0), 256);
        let field = fast.surface.field.clone().expect("a table");
        let half = 0.5 * field.n as f64 * field.cell;
        let mut reference = fast.clone();
        reference.surface.march = March::Reference;
        let s = &fast.surface;
        let scale = s.driver.finest_scale();
        let (mut far, mut shadow_differ, mut n, mut settled) = (0, 0, 0, 0);
        for i in 0..300 {
            let lod = i % 3 == 2;
            let fp = Footprint::isotropic(scale * [0.05, 0.5][i % 2]);
            let theta = (20.0 + 68.0 * splitmix(&mut rng)).to_radians();
            let d = -direction(theta, TAU * splitmix(&mut rng));
            let o = DVec3::new(
                15.0 + 2.4 * half * (splitmix(&mut rng) - 0.5),
                15.0 + 2.4 * half * (splitmix(&mut rng) - 0.5),
                s.h_max * 1.001 + 1e-6,
            );
            let height = |p: DVec3| {
                let x = DVec2::new(p.x, p.y);
                if lod {
                    fast.lod_height(x, fp)
                } else {
                    s.height(x)
                }
            };
            let (tf, tr) = if lod {
                (fast.lod_march(o, d, fp), reference.lod_march(o, d, fp))
            } else {
                let t = |s: &Surface| match s.march(o, d) {
                    Trace::Hit(t) => Some(t),
                    Trace::Escape => None,
                };
                (t(s), t(&reference.surface))
            };
            let (Some(tf), Some(tr)) = (tf, tr) else {
                panic!("{}: a downward ray hits", m.name)
            };
            n += 1;
            let top = s
                .h_max
                .min(s.height_of(0.0).abs() + s.sigma_h * s.g_lip * field.amplitude_sum);
            let gap = o.z + d.z * tf - height(o + d * tf);
            assert!(
                gap > -1e-9 && gap <= FIELD_SETTLE * top * 1.001,
                "{} (lod {lod}): gap {gap} at the hit, settle {}",
                m.name,
                FIELD_SETTLE * top
            );
            assert!(
                tf <= tr * (1.0 + 1e-9) + 1e-12,
                "{}: {tf} past the first crossing {tr}",
                m.name
            );
            for j in 0..4000 {
                let q = o + d * (tf * f64::from(j) / 4000.0);
                assert!(
                    q.z - height(q) > -1e-9,
                    "{}: a crossing before the hit",
                    m.name
                );
            }
            if !lod {
                // Whether the table settled it (the point the march stopped at is one where it
                // may), rather than the waves' sum.
                let os = s.octaves(None).unwrap();
                let rw = os.ray(o, d);
                let last = os.ends.len().clamp(1, crate::driver::noise::MAX_LEVELS) - 1;
                let fv = os.field.unwrap();
                let at = os.field_step(
                    &fv,
                    o + d * tf,
                    d,
                    &rw.bounds(last),
                    &|f| s.height_of(f),
                    FIELD_SETTLE * top * (1.0 + 1e-12) + 1e-300,
                    true,
                );
                settled += usize::from(at == crate::scene::field_grid::FieldStep::Settle);
            }
            // Within the band's width along the ray (rate ≥ |d_z| where the gap shrinks).
            if tr - tf > 2.0 * FIELD_SETTLE * top / d.z.abs() {
                far += 1;
            }
            if !lod {
                let l = direction(
                    (5.0 + 80.0 * splitmix(&mut rng)).to_radians(),
                    TAU * splitmix(&mut rng),
                );
                let p = o + d * tr;
                let hit = |s: &Surface| matches!(s.march(p, l), Trace::Hit(_));
                if hit(s) != hit(&reference.surface) {
                    shadow_differ += 1;
                }
            }
        }
        eprintln!(
            "{}: {far} of {n} camera rays skim a crest, {settled} settled on the table, {shadow_differ} shadow rays differ",
            m.name
        );
        assert!(far <= n / 50, "{}: {far} of {n} rays stop early", m.name);
        assert!(
            settled * 5 >= n,
            "{}: the table settled {settled} of {n}",
            m.name
        );
        assert!(
            shadow_differ <= 1,
            "{}: {shadow_differ} shadow rays differ",
            m.name
        );
    }
}

/// The grid does its job: from the slab's top, the first skip of a primary ray (20°–80°) covers
/// most of the way to the hit on the Gaussian materials (the part of the slab above the local
/// relief), and never reaches past it.
#[test]
fn the_grid_skips_most_of_the_empty_slab() {
    let mut rng = 3u64;
    for m in materials().into_iter().take(2) {
        let s = with_grid(Surface::new(&m).unwrap());
        let os = s.octaves(None).unwrap();
        let gv = os.grid.unwrap();
        let height_of = |f| s.height_of(f);
        let (mut covered, mut n) = (0.0, 0);
        for i in 0..100 {
            let theta = (20.0 + 60.0 * (i % 7) as f64 / 6.0).to_radians();
            let d = -direction(theta, TAU * splitmix(&mut rng));
            let o = DVec3::new(
                10.0 + 10.0 * splitmix(&mut rng),
                10.0 + 10.0 * splitmix(&mut rng),
                s.h_max * 1.001 + 1e-6,
            );
            let Trace::Hit(t) = s.march(o, d) else {
                panic!("hits")
            };
            let mut len = 0.0;
            let skipped = os
                .grid_skip(&gv, o, d, 0.0, &mut len, &height_of)
                .map_or(0.0, |(t1, _)| t1);
            assert!(
                skipped <= t,
                "{}: skipped to {skipped} past the hit at {t}",
                m.name
            );
            covered += skipped / t;
            n += 1;
        }
        let mean = covered / f64::from(n);
        assert!(
            mean > 0.5,
            "{}: the first skip covers {mean:.2} of the way",
            m.name
        );
    }
}

/// Hostile inputs: σ_h = 0, a vertical ray, a horizontal ray, a ray starting below the slab,
/// huge coordinates: a hit, an escape or None, never a hang or a panic.
#[test]
fn extreme_rays_end() {
    for m in materials() {
        let s = Surface::new(&m).unwrap();
        let top = s.h_max * 1.001 + 1e-6;
        assert!(matches!(
            s.march(DVec3::new(0.3, 0.2, top), DVec3::NEG_Z),
            Trace::Hit(_)
        ));
        assert!(matches!(
            s.march(DVec3::new(0.3, 0.2, top), DVec3::Z),
            Trace::Escape
        ));
        let _ = s.march(DVec3::new(0.3, 0.2, 0.0), DVec3::X);
        let _ = s.march(DVec3::new(1e7, -1e7, top), DVec3::new(0.6, 0.0, -0.8));
        let flat = Surface::new(&Material {
            heights: Heights {
                sigma_h: 0.0,
                ..m.heights.clone()
            },
            ..m.clone()
        })
        .unwrap();
        assert!(
            matches!(flat.march(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.6, 0.0, -0.8)), Trace::Hit(t) if (t - 1.25).abs() < 1e-9)
        );
    }
}
