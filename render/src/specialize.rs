//! Shader specialisation: the view shader compiled for exactly the features a scene uses.
//!
//! The WGSL sources mark feature-dependent code with line directives in comments:
//!
//! ```text
//! //#if relief              kept when the set has `relief`
//! //#if !relief             kept when it has not
//! //#if driver_color|height_color   kept when it has any of them
//! //#else
//! //#endif
//! ```
//!
//! (names are [`Feature::name`]; blocks nest). [`specialize`] removes the lines of every block whose
//! condition is false, replacing them with empty lines so that naga's error positions still point
//! into the source files, and whole files are left out when their feature is absent
//! ([`view_source_for`]).
//!
//! Why generated source and not WGSL `override` constants: an override is substituted when the
//! pipeline is created, but the branches it disables stay in the module handed to the backend
//! (naga does not prune them) and in everything it references (the wave cache, the image
//! pyramid's functions, the Smith terms): whether they cost registers or compile time is then up
//! to each driver, and we could neither measure nor guarantee that unused terms are absent.
//! Text specialisation removes them before naga sees the module, so the size reported by
//! [`ShaderSize`] is what every backend compiles, and the specialised source is plain WGSL that
//! can be read, validated and exported. The price is one pipeline per feature set, which the
//! renderer caches.

use lodestone_core::material::features::{Feature, FeatureSet};

/// A malformed directive in a shader source (a bug in the shipped WGSL; tests catch it).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SpecializeError {
    /// `//#if` names no feature this crate knows.
    #[error("line {line}: unknown feature `{name}` in a //#if directive")]
    UnknownFeature {
        /// 1-based line.
        line: usize,
        /// The name.
        name: String,
    },
    /// `//#else` or `//#endif` without an open `//#if`, or a second `//#else`.
    #[error("line {line}: `{directive}` has no matching //#if")]
    Unmatched {
        /// 1-based line.
        line: usize,
        /// The directive.
        directive: String,
    },
    /// An `//#if` never closed.
    #[error("line {line}: //#if is never closed by //#endif")]
    Unclosed {
        /// 1-based line of the `//#if`.
        line: usize,
    },
    /// A line starting with `//#` that is not a directive.
    #[error("line {line}: unknown directive `{text}`")]
    UnknownDirective {
        /// 1-based line.
        line: usize,
        /// The line.
        text: String,
    },
}

/// Evaluate `a|b|!c` against `set`.
fn condition(expr: &str, set: FeatureSet, line: usize) -> Result<bool, SpecializeError> {
    let mut any = false;
    for term in expr.split('|') {
        let term = term.trim();
        let (negated, name) = match term.strip_prefix('!') {
            Some(n) => (true, n.trim()),
            None => (false, term),
        };
        let f = Feature::from_name(name).ok_or_else(|| SpecializeError::UnknownFeature {
            line,
            name: name.to_string(),
        })?;
        any |= set.contains(f) != negated;
    }
    Ok(any)
}

/// `source` with every block whose condition is false for `features` blanked out (see the module
/// docs). Directive lines themselves are blanked too. Line count is preserved.
pub fn specialize(source: &str, features: FeatureSet) -> Result<String, SpecializeError> {
    struct Open {
        line: usize,
        parent_active: bool,
        taken: bool,
        seen_else: bool,
    }
    let mut stack: Vec<Open> = Vec::new();
    let mut active = true;
    let mut out = String::with_capacity(source.len());
    for (i, text) in source.lines().enumerate() {
        let line = i + 1;
        let trimmed = text.trim_start();
        if let Some(d) = trimmed.strip_prefix("//#") {
            let d = d.trim();
            if let Some(expr) = d.strip_prefix("if ") {
                let c = condition(expr, features, line)?;
                stack.push(Open {
                    line,
                    parent_active: active,
                    taken: c,
                    seen_else: false,
                });
                active = active && c;
            } else if d == "else" {
                let top = stack.last_mut().filter(|o| !o.seen_else).ok_or_else(|| {
                    SpecializeError::Unmatched {
                        line,
                        directive: "//#else".into(),
                    }
                })?;
                top.seen_else = true;
                active = top.parent_active && !top.taken;
            } else if d == "endif" {
                let top = stack.pop().ok_or_else(|| SpecializeError::Unmatched {
                    line,
                    directive: "//#endif".into(),
                })?;
                active = top.parent_active;
            } else {
                return Err(SpecializeError::UnknownDirective {
                    line,
                    text: text.to_string(),
                });
            }
        } else if active {
            out.push_str(text);
        }
        out.push('\n');
    }
    match stack.last() {
        Some(o) => Err(SpecializeError::Unclosed { line: o.line }),
        None => Ok(out),
    }
}

/// The view shader's source for `features`: the files it needs, specialised. Image drivers and
/// the cylinder live in their own files, left out whole when unused. The set is
/// [normalized](FeatureSet::normalized) first.
pub fn view_source_for(features: FeatureSet) -> Result<String, SpecializeError> {
    use crate::shaders;
    let features = features.normalized();
    let mut parts = vec![shaders::SPECIAL, shaders::view_material()];
    if features.contains(Feature::ImageDriver) {
        parts.push(shaders::IMAGE_DRIVER);
    }
    parts.push(shaders::view_bindings());
    if features.contains(Feature::Curved) {
        parts.push(shaders::CYLINDER);
    }
    parts.push(shaders::VIEW);
    specialize(&parts.join("\n"), features)
}

/// Size of a shader module after specialisation, counted by naga over what the entry point can
/// reach (functions called, transitively).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShaderSize {
    /// Functions reachable from the entry point (itself included).
    pub functions: usize,
    /// Statements in them, nested blocks included.
    pub statements: usize,
    /// Expressions in them.
    pub expressions: usize,
    /// Bytes of WGSL source (comments and blank lines included).
    pub source_bytes: usize,
}

impl ShaderSize {
    /// Parse and validate `source` with naga and measure what `entry` reaches.
    pub fn measure(source: &str, entry: &str) -> Result<ShaderSize, String> {
        let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .map_err(|e| e.emit_to_string(source))?;
        let ep = module
            .entry_points
            .iter()
            .find(|e| e.name == entry)
            .ok_or_else(|| format!("no entry point {entry}"))?;
        let mut size = ShaderSize {
            source_bytes: source.len(),
            ..ShaderSize::default()
        };
        let mut seen = std::collections::HashSet::new();
        let mut todo = Vec::new();
        let mut visit = |f: &naga::Function, todo: &mut Vec<naga::Handle<naga::Function>>| {
            size.functions += 1;
            size.expressions += f.expressions.len();
            size.statements += count_block(&f.body, todo);
        };
        visit(&ep.function, &mut todo);
        while let Some(h) = todo.pop() {
            if seen.insert(h) {
                visit(&module.functions[h], &mut todo);
            }
        }
        Ok(size)
    }
}

/// Statements of `block` (recursively); pushes called functions onto `calls`.
fn count_block(block: &naga::Block, calls: &mut Vec<naga::Handle<naga::Function>>) -> usize {
    use naga::Statement as S;
    let mut n = 0;
    for s in block.iter() {
        // Emit only marks expressions as evaluated; it is not code of its own.
        if matches!(s, S::Emit(_)) {
            continue;
        }
        n += 1;
        match s {
            S::Block(b) => n += count_block(b, calls),
            S::If { accept, reject, .. } => {
                n += count_block(accept, calls) + count_block(reject, calls);
            }
            S::Switch { cases, .. } => {
                n += cases
                    .iter()
                    .map(|c| count_block(&c.body, calls))
                    .sum::<usize>()
            }
            S::Loop {
                body, continuing, ..
            } => n += count_block(body, calls) + count_block(continuing, calls),
            S::Call { function, .. } => calls.push(*function),
            _ => {}
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(names: &[&str]) -> FeatureSet {
        names
            .iter()
            .map(|n| Feature::from_name(n).expect("feature"))
            .collect()
    }

    #[test]
    fn blocks_nest_and_else_inverts() {
        let src = "a\n//#if relief\nb\n//#if !specular\nc\n//#else\nd\n//#endif\n//#endif\ne\n";
        let keep = |s: &str| -> Vec<String> {
            s.lines()
                .filter(|l| !l.is_empty())
                .map(str::to_string)
                .collect()
        };
        assert_eq!(
            keep(&specialize(src, set(&["relief"])).unwrap()),
            ["a", "b", "c", "e"]
        );
        assert_eq!(
            keep(&specialize(src, set(&["relief", "specular"])).unwrap()),
            ["a", "b", "d", "e"]
        );
        // An inactive parent hides both branches of its child.
        assert_eq!(
            keep(&specialize(src, set(&["specular"])).unwrap()),
            ["a", "e"]
        );
        // Line count is preserved.
        let out = specialize(src, FeatureSet::EMPTY).unwrap();
        assert_eq!(out.lines().count(), src.lines().count());
    }

    #[test]
    fn alternatives_and_negation() {
        let src = "//#if image|!noise\nx\n//#endif\n";
        assert!(specialize(src, set(&["image"])).unwrap().contains('x'));
        assert!(specialize(src, FeatureSet::EMPTY).unwrap().contains('x'));
        assert!(!specialize(src, set(&["noise"])).unwrap().contains('x'));
    }

    #[test]
    fn malformed_directives_are_errors() {
        let e = |s: &str| specialize(s, FeatureSet::all()).unwrap_err();
        assert_eq!(
            e("//#if relief\nx\n"),
            SpecializeError::Unclosed { line: 1 }
        );
        assert!(matches!(
            e("x\n//#endif\n"),
            SpecializeError::Unmatched { line: 2, .. }
        ));
        assert!(matches!(
            e("//#if relief\n//#else\n//#else\n//#endif\n"),
            SpecializeError::Unmatched { line: 3, .. }
        ));
        assert!(matches!(
            e("//#if voxels\n//#endif\n"),
            SpecializeError::UnknownFeature { line: 1, .. }
        ));
        assert!(matches!(
            e("//#ifdef relief\n"),
            SpecializeError::UnknownDirective { line: 1, .. }
        ));
    }

    #[test]
    fn every_directive_in_the_shipped_shaders_is_well_formed_and_fewer_features_mean_less_code() {
        let all = view_source_for(FeatureSet::all()).expect("all features");
        let full = ShaderSize::measure(&all, "view_main").expect("valid");
        let flat: FeatureSet = [Feature::NoiseDriver, Feature::DriverColor]
            .into_iter()
            .collect();
        let small =
            ShaderSize::measure(&view_source_for(flat).expect("flat"), "view_main").expect("valid");
        assert!(
            small.statements * 2 < full.statements,
            "{small:?} vs {full:?}"
        );
        assert!(small.functions < full.functions);
        // Removing any one feature never adds code.
        for f in Feature::ALL {
            let s = FeatureSet::all().with(f, false);
            let size = ShaderSize::measure(&view_source_for(s).expect("source"), "view_main")
                .unwrap_or_else(|e| panic!("without {}: {e}", f.name()));
            assert!(size.statements <= full.statements, "without {}", f.name());
        }
        // Every combination a pipeline can be built for (the normalized sets of the 2^14 without a
        // measured BRDF) is valid WGSL; the measured BRDF's lookup (material/measured.wgsl, and
        // facet_radiance) reads only the data buffer and the tangent basis, so it is checked with
        // every combination of the features that touch the shading around it (2^8 more, not 2^14:
        // this test is a tenth of CI's time).
        let subsets = |features: &[Feature], with: FeatureSet| {
            (0u32..1 << features.len())
                .map(|bits| {
                    features
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| bits >> i & 1 == 1)
                        .fold(with, |s, (_, f)| s.with(*f, true))
                        .normalized()
                })
                .collect::<Vec<_>>()
        };
        let others: Vec<Feature> = Feature::ALL
            .into_iter()
            .filter(|f| *f != Feature::Measured)
            .collect();
        let around_measured = [
            Feature::NoiseDriver,
            Feature::ImageDriver,
            Feature::Relief,
            Feature::Shadows,
            Feature::Specular,
            Feature::Curved,
            Feature::SlopeColor,
            Feature::Environment,
        ];
        let sets: std::collections::HashSet<FeatureSet> = subsets(&others, FeatureSet::EMPTY)
            .into_iter()
            .chain(subsets(
                &around_measured,
                FeatureSet::EMPTY.with(Feature::Measured, true),
            ))
            .collect();
        use rayon::prelude::*;
        sets.into_par_iter().for_each(|s| {
            ShaderSize::measure(&view_source_for(s).expect("source"), "view_main")
                .unwrap_or_else(|e| panic!("{s}: {e}"));
        });
    }
}
