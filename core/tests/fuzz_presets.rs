//! Fuzz-style robustness of the preset loader: 12,000 mutated preset files (character edits, swapped
//! numbers including NaN, infinities, negatives and huge values, duplicated, deleted and truncated
//! lines) go through `Material::from_ron`. Nothing may panic; every failure must be a proper error
//! (parse errors with a 1-based line and column inside the text); every success must be a valid
//! material whose tables build and whose far-patch evaluation is finite.

use lodestone_core::eval::{Evaluator, FootprintQuery};
use lodestone_core::material::{Material, MaterialError};
use lodestone_core::microfacet::slope_masking::SlopeMasking;
use lodestone_core::scene::direction::direction;

/// A small deterministic generator (SplitMix64), so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const NUMBERS: &[&str] = &[
    "NaN",
    "inf",
    "-inf",
    "-1.0",
    "0",
    "0.0",
    "1e308",
    "-1e308",
    "1e-320",
    "3",
    "1e9",
    "-0.0",
    "4294967296",
    "99999999999999999999",
    "256",
    "100000",
];
const JUNK: &[&str] = &[
    "(", ")", "[", "]", ",", ":", "\"", "Some(", "None", "Curve(", "Identity", "x", "\n", " ",
    "//", "/*", "r#\"", "'", "\\", "é", "\u{0}",
];

fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut t = text.to_string();
    for _ in 0..1 + rng.below(3) {
        let chars: Vec<char> = t.chars().collect();
        if chars.is_empty() {
            break;
        }
        let at = rng.below(chars.len());
        t = match rng.below(7) {
            // Replace a number by an extreme one.
            0 | 1 => {
                let starts: Vec<usize> = (0..chars.len())
                    .filter(|&i| {
                        (chars[i].is_ascii_digit() || chars[i] == '-')
                            && (i == 0 || !chars[i - 1].is_ascii_alphanumeric())
                    })
                    .collect();
                if starts.is_empty() {
                    continue;
                }
                let s = starts[rng.below(starts.len())];
                let mut e = s + 1;
                while e < chars.len()
                    && (chars[e].is_ascii_digit()
                        || matches!(chars[e], '.' | 'e' | 'E' | '-' | '+'))
                {
                    e += 1;
                }
                let n = NUMBERS[rng.below(NUMBERS.len())];
                chars[..s].iter().collect::<String>() + n + &chars[e..].iter().collect::<String>()
            }
            // Delete a character.
            2 => chars
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != at)
                .map(|(_, c)| c)
                .collect(),
            // Insert junk.
            3 => {
                let j = JUNK[rng.below(JUNK.len())];
                chars[..at].iter().collect::<String>() + j + &chars[at..].iter().collect::<String>()
            }
            // Duplicate or delete a line.
            4 => {
                let lines: Vec<&str> = t.lines().collect();
                let k = rng.below(lines.len());
                let mut out: Vec<&str> = lines.clone();
                if rng.below(2) == 0 {
                    out.insert(k, lines[k]);
                } else {
                    out.remove(k);
                }
                out.join("\n")
            }
            // Truncate.
            5 => chars[..at].iter().collect(),
            // Swap two characters.
            _ => {
                let b = rng.below(chars.len());
                let mut c = chars.clone();
                c.swap(at, b);
                c.into_iter().collect()
            }
        };
    }
    t
}

#[test]
fn twelve_thousand_mutated_presets_never_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets");
    let mut texts: Vec<String> = std::fs::read_dir(&dir)
        .expect("presets/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .map(|p| std::fs::read_to_string(p).expect("preset"))
        .collect();
    texts.sort();
    assert!(texts.len() >= 4);
    // `LODESTONE_FUZZ_SEED=N` explores other mutations (the default seed is the one CI runs).
    let seed = std::env::var("LODESTONE_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x0010_de57);
    let mut rng = Rng(seed);
    let (mut parse, mut invalid, mut too_new, mut ok) = (0, 0, 0, 0);
    for i in 0..12_000 {
        let base = &texts[i % texts.len()];
        let text = mutate(base, &mut rng);
        let result = std::panic::catch_unwind(|| Material::from_ron(&text));
        let Ok(result) = result else {
            panic!("the loader panicked on mutation {i}:\n{text}");
        };
        match result {
            Ok(mut m) => {
                ok += 1;
                assert!(
                    m.validate().is_ok(),
                    "accepted an invalid material (mutation {i})"
                );
                // The slope-conditioned masking's table costs about a second per wave set, and
                // most mutations of a noise preset make a new one: every 25th success keeps the
                // preset's masking, the others evaluate with Smith's.
                if ok % 25 != 0 {
                    m.filtering.slope_masking = SlopeMasking::Smith;
                }
                // Huge but valid values (e.g. 1e5 components of detail) may make preparation
                // slow; limit the check to what the editor would build.
                if let Ok(p) = Evaluator::new(&m) {
                    let cfg = FootprintQuery::far(&p, direction(1.0, 0.0), direction(0.5, 2.0));
                    for v in p.filtered(&cfg).into_iter().chain(p.naive(&cfg)) {
                        assert!(v.is_finite(), "non-finite result for mutation {i}:\n{text}");
                    }
                }
            }
            Err(MaterialError::Parse {
                line,
                column,
                message,
            }) => {
                parse += 1;
                let lines = text.lines().count().max(1);
                assert!(line >= 1 && column >= 1, "{line}:{column} {message}");
                assert!(
                    line <= lines + 1,
                    "line {line} beyond the text ({lines} lines)"
                );
                assert!(!message.is_empty());
            }
            Err(MaterialError::Invalid(problems)) => {
                invalid += 1;
                assert!(!problems.is_empty());
                for p in &problems {
                    assert!(!p.to_string().is_empty());
                }
            }
            Err(MaterialError::TooNew { .. }) => too_new += 1,
        }
    }
    eprintln!("parse errors {parse}, invalid {invalid}, too new {too_new}, accepted {ok}");
    // The mutations must exercise every path.
    assert!(
        parse > 1000 && invalid > 100 && ok > 100,
        "{parse} {invalid} {ok}"
    );
}
