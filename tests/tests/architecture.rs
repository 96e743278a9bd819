//! The shape of the code, read from the sources so that a new module is covered without being
//! listed:
//!
//! - no import circle between files, nor between folders, in `core`, `render` or `app` (a module
//!   depends on another when its non-test code names it through `crate::` or `super::`);
//! - no source file (Rust or WGSL) longer than [`MAX_LINES`] lines, counted as lines, except the
//!   few in [`LONG_FILES`], each with its reason;
//! - the libraries (`core`, `render`) read no environment variable outside their tests, and every
//!   `LODESTONE_*` variable the binary reads is documented in `docs/testing.md`;
//! - the user and design documents, and the names of the repository's files, carry no issue
//!   numbers or work-log counters: they describe the project as it is (history is `git log`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest a source file may be.
const MAX_LINES: usize = 600;

/// Files allowed past [`MAX_LINES`], with the reason. Keep it short: split a file instead when it
/// holds more than one concept.
const LONG_FILES: &[(&str, &str)] = &[
    (
        "app/tests/cli.rs",
        "one integration test per subcommand's contract (exit codes, messages, outputs), \
         sharing the binary's harness",
    ),
    (
        "app/src/editor/tests.rs",
        "the editor's kittest scenarios share one harness and its snapshot helpers",
    ),
    (
        "render/tests/views.rs",
        "every view mode against core's pixels, sharing the scene fixtures",
    ),
];

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every file under `dir` whose name ends with one of `exts`.
fn files(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries {
        let p = entry.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            if name != "target" && !name.starts_with('.') {
                files(&p, exts, out);
            }
        } else if exts.iter().any(|e| name.ends_with(e)) {
            out.push(p);
        }
    }
}

/// The module path of a file (`microfacet/smith.rs` → `microfacet::smith`, `material/mod.rs` →
/// `material`, `lib.rs` and `main.rs` → the crate root `""`).
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    if parts
        .last()
        .is_some_and(|l| l == "mod" || l == "lib" || l == "main")
    {
        parts.pop();
    }
    parts.join("::")
}

/// The non-test code of a file: everything before its first `#[cfg(test)]`, without comments.
fn non_test_code(text: &str) -> String {
    let code = text.find("#[cfg(test)]").map_or(text, |i| &text[..i]);
    code.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Whether a file holds only tests (`tests.rs` or `NAME_tests.rs`, declared under `#[cfg(test)]`).
fn is_test_file(p: &Path) -> bool {
    let name = p.file_name().unwrap().to_string_lossy();
    name == "tests.rs" || name.ends_with("_tests.rs")
}

/// The files of one crate's `src/` that are not tests.
fn code_files(src: &Path) -> Vec<PathBuf> {
    let mut paths = Vec::new();
    files(src, &[".rs"], &mut paths);
    paths.retain(|p| !is_test_file(p));
    paths
}

/// The file-level dependency graph of one crate's `src/`: module → the modules its non-test code
/// names (the longest known module of each `crate::a::b::…` or `super::…` path). A module's own
/// children are not dependencies (a folder's `mod.rs` declares and re-exports them).
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let paths = code_files(src);
    let modules: BTreeMap<String, String> = paths
        .iter()
        .map(|f| (module_of(src, f), std::fs::read_to_string(f).unwrap()))
        .collect();
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, text) in &modules {
        let code = non_test_code(text);
        let deps = edges.entry(m.clone()).or_default();
        let own: Vec<&str> = if m.is_empty() {
            Vec::new()
        } else {
            m.split("::").collect()
        };
        for anchor in ["crate::", "super::"] {
            for (i, _) in code.match_indices(anchor) {
                // `foo_crate::` or `self.super::` are not paths of this crate.
                if i > 0 {
                    let before = code[..i].chars().next_back().unwrap();
                    if before.is_alphanumeric() || before == '_' {
                        continue;
                    }
                }
                let path: String = code[i..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                    .collect();
                let mut segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
                let mut base: Vec<&str> = Vec::new();
                if segs.first() == Some(&"crate") {
                    segs.remove(0);
                } else {
                    // `super` in a file module is its parent folder's module.
                    base = own.clone();
                    while segs.first() == Some(&"super") {
                        segs.remove(0);
                        base.pop();
                    }
                }
                base.extend(segs);
                for n in (1..=base.len()).rev() {
                    let cand = base[..n].join("::");
                    if modules.contains_key(&cand) {
                        if &cand != m && !cand.starts_with(&format!("{m}::")) && !m.is_empty() {
                            deps.insert(cand);
                        }
                        break;
                    }
                }
            }
        }
    }
    edges
}

/// A cycle in `edges`, if any (depth-first search).
fn find_cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        m: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(m) {
            Some(2) => return None,
            Some(1) => {
                let at = stack.iter().position(|s| s == m).unwrap();
                let mut cycle = stack[at..].to_vec();
                cycle.push(m.to_string());
                return Some(cycle);
            }
            _ => {}
        }
        state.insert(m.to_string(), 1);
        stack.push(m.to_string());
        for d in edges.get(m).into_iter().flatten() {
            if let Some(c) = visit(d, edges, state, stack) {
                return Some(c);
            }
        }
        stack.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in edges.keys() {
        if let Some(c) = visit(m, edges, &mut state, &mut Vec::new()) {
            return Some(c);
        }
    }
    None
}

/// The folder a module lives in: its first path segment (a file at the crate root is a folder
/// of its own).
fn folder(m: &str) -> &str {
    m.split("::").next().unwrap_or("")
}

/// The folder-level graph: an edge between two folders when any file of one names any of the
/// other's.
fn folder_graph(edges: &BTreeMap<String, BTreeSet<String>>) -> BTreeMap<String, BTreeSet<String>> {
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, deps) in edges {
        let from = folder(m);
        let entry = out.entry(from.to_string()).or_default();
        for d in deps {
            if folder(d) != from {
                entry.insert(folder(d).to_string());
            }
        }
    }
    out
}

/// The files of one folder that name the other's, to say where a folder cycle comes from.
fn witnesses(edges: &BTreeMap<String, BTreeSet<String>>, cycle: &[String]) -> Vec<String> {
    cycle
        .windows(2)
        .flat_map(|w| {
            edges.iter().flat_map(move |(m, deps)| {
                deps.iter()
                    .filter(move |d| folder(m) == w[0] && folder(d) == w[1])
                    .map(move |d| format!("{m} → {d}"))
            })
        })
        .collect()
}

const CRATES: [&str; 3] = ["core", "render", "app"];

#[test]
fn no_import_circle_between_files_or_folders() {
    for krate in CRATES {
        let edges = module_graph(&root().join(krate).join("src"));
        assert!(
            edges.len() > 10,
            "{krate}: found only {} modules",
            edges.len()
        );
        if let Some(cycle) = find_cycle(&edges) {
            panic!("{krate}: file cycle {}", cycle.join(" → "));
        }
        let folders = folder_graph(&edges);
        if let Some(cycle) = find_cycle(&folders) {
            panic!(
                "{krate}: folder cycle {} ({})",
                cycle.join(" → "),
                witnesses(&edges, &cycle).join(", ")
            );
        }
    }
}

/// The graph itself finds what it should: a cycle through `super::` and one through folders.
#[test]
fn the_graph_sees_super_paths_and_folder_cycles() {
    let dir = std::env::temp_dir().join(format!("lodestone-arch-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).unwrap();
    std::fs::create_dir_all(src.join("b")).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod a;\npub mod b;\n").unwrap();
    std::fs::write(src.join("a/mod.rs"), "pub mod x;\npub mod y;\n").unwrap();
    std::fs::write(
        src.join("a/x.rs"),
        "use super::y::Y;\nuse crate::b::z::Z;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("a/y.rs"),
        "pub struct Y;\n#[cfg(test)]\nuse crate::a::x::X;\n",
    )
    .unwrap();
    std::fs::write(src.join("b/mod.rs"), "pub mod z;\n").unwrap();
    std::fs::write(src.join("b/z.rs"), "// crate::a::x\nuse crate::a::y::Y;\n").unwrap();
    std::fs::write(src.join("b/tests.rs"), "use crate::a::x::X;\n").unwrap();
    let edges = module_graph(&src);
    assert!(edges["a::x"].contains("a::y"), "{edges:?}");
    assert_eq!(
        edges["b::z"],
        BTreeSet::from(["a::y".to_string()]),
        "comments are no dependency"
    );
    assert!(
        !edges.contains_key("b::tests"),
        "test files are no dependency"
    );
    assert!(
        !edges["a::y"].contains("a::x"),
        "test code is no dependency"
    );
    assert_eq!(find_cycle(&edges), None, "{edges:?}");
    let folders = folder_graph(&edges);
    let cycle = find_cycle(&folders).expect("a → b → a");
    assert_eq!(cycle.len(), 3, "{cycle:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn no_file_is_longer_than_the_limit_without_a_reason() {
    let mut long = Vec::new();
    let mut seen_allowed = BTreeSet::new();
    for krate in CRATES {
        let mut paths = Vec::new();
        files(&root().join(krate), &[".rs", ".wgsl"], &mut paths);
        for p in paths {
            let rel = p
                .strip_prefix(root())
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let lines = std::fs::read_to_string(&p).unwrap().lines().count();
            if LONG_FILES.iter().any(|(f, _)| *f == rel) {
                seen_allowed.insert(rel.clone());
                continue;
            }
            if lines > MAX_LINES {
                long.push(format!("{rel}: {lines} lines"));
            }
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines (split them, or say why in LONG_FILES): {long:#?}"
    );
    for (f, why) in LONG_FILES {
        assert!(
            seen_allowed.contains(*f),
            "LONG_FILES names {f}, which does not exist"
        );
        assert!(why.len() > 20, "{f}: say why it is long");
    }
}

/// `LODESTONE_…` names in a text, each with what follows it up to the end of the name.
fn variables(text: &str) -> BTreeSet<String> {
    text.match_indices("LODESTONE_")
        .map(|(i, _)| {
            text[i..]
                .chars()
                .take_while(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || *c == '_')
                .collect()
        })
        .collect()
}

#[test]
fn libraries_read_no_environment_and_the_binary_documents_what_it_reads() {
    for krate in ["core", "render"] {
        for p in code_files(&root().join(krate).join("src")) {
            let code = non_test_code(&std::fs::read_to_string(&p).unwrap());
            for needle in ["env::var", "var_os("] {
                assert!(
                    !code.contains(needle),
                    "{}: a library reads the environment; make it an option the binary sets",
                    p.display()
                );
            }
        }
    }
    let documented = std::fs::read_to_string(root().join("docs/testing.md")).unwrap();
    for p in code_files(&root().join("app/src")) {
        let code = non_test_code(&std::fs::read_to_string(&p).unwrap());
        for v in variables(&code) {
            assert!(
                documented.contains(&format!("`{v}")),
                "{} reads {v}, which docs/testing.md does not document",
                p.display()
            );
        }
    }
}

/// Whether `text` names an issue (`#12`) or a work-log counter (`session 12`, `session-12`).
fn history_markers(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for word in ["session", "Session"] {
        for (i, _) in text.match_indices(word) {
            let rest = text[i + word.len()..].trim_start_matches([' ', '-', '_']);
            if rest.starts_with(|c: char| c.is_ascii_digit()) {
                found.push(text[i..].chars().take(word.len() + 3).collect());
            }
        }
    }
    for (i, _) in text.match_indices('#') {
        let after = &text[i + 1..];
        let before = text[..i].chars().next_back();
        let digits = after.chars().take_while(|c| c.is_ascii_digit()).count();
        // `#` as a Markdown heading or a colour (`#ff0000`) is not an issue.
        let word_follows = after[digits..].starts_with(|c: char| c.is_alphanumeric());
        if digits > 0 && !word_follows && !before.is_some_and(|c| c == '&' || c.is_alphanumeric()) {
            found.push(text[i..i + 1 + digits].to_string());
        }
    }
    found
}

#[test]
fn documents_and_file_names_describe_the_project_as_it_is() {
    let mut docs = vec![
        root().join("README.md"),
        root().join("presets/README.md"),
        root().join("screenshots/README.md"),
    ];
    files(&root().join("docs"), &[".md"], &mut docs);
    let mut problems = Vec::new();
    for p in &docs {
        let text = std::fs::read_to_string(p).unwrap();
        for (n, line) in text.lines().enumerate() {
            for m in history_markers(line) {
                problems.push(format!("{}:{}: {m}", p.display(), n + 1));
            }
        }
    }
    let mut all = Vec::new();
    for dir in [
        "core",
        "render",
        "app",
        "tests",
        "docs",
        "presets",
        "screenshots",
        "scripts",
    ] {
        files(&root().join(dir), &[""], &mut all);
    }
    for p in all {
        let name = p
            .strip_prefix(root())
            .unwrap()
            .to_string_lossy()
            .into_owned();
        for m in history_markers(&name) {
            problems.push(format!("file name {name}: {m}"));
        }
    }
    assert!(
        problems.is_empty(),
        "issue numbers or work-log counters: {problems:#?}"
    );
    assert_eq!(
        history_markers("see #18 and session 31."),
        ["session 31", "#18"]
    );
    assert!(history_markers("# Heading, `#[cfg(test)]`, #ff0000, &#8212;").is_empty());
}
