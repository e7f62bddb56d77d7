//! Imports run one way (issue 11): reads the sources under `src/` and checks
//! which top-level modules each part of the library names through `crate::`
//! (or `super::` up to the crate root), and that only the binary's files
//! mention the command-line and terminal crates. A broken rule is reported
//! with its file and line.
//!
//! Test code is left out of the import rules: `tests.rs` files, files
//! declared by `#[cfg(test)] mod x;`, and the rest of a file from a
//! `#[cfg(test)]` that opens an inline `mod x {`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Who may not name whom: (the rule, the modules it covers, the modules they must not name).
const RULES: &[(&str, &[&str], &[&str])] = &[
    (
        "scene describes the world",
        &["scene"],
        &["integrator", "photon", "state_file", "viewer"],
    ),
    (
        "the basic types import nothing above them",
        &[
            "geometry", "material", "medium", "light", "camera", "sampling", "bsdf", "bssrdf", "texture",
        ],
        &["scene", "integrator", "photon", "state_file", "viewer", "settings"],
    ),
    (
        "settings are plain data",
        &["settings"],
        &["scene", "integrator", "photon", "viewer"],
    ),
];

/// The crates of the binary's command line and terminal.
const BINARY_CRATES: &[&str] = &["clap", "indicatif", "ctrlc"];
/// The files that may mention them.
const BINARY_FILES: &[&str] = &["src/main.rs", "src/cli.rs"];

struct Source {
    /// Relative to the crate root, with `/` separators: `src/scene/mod.rs`.
    name: String,
    /// The module path: `["scene"]` for `src/scene/mod.rs` or `src/scene.rs`.
    module: Vec<String>,
    text: String,
}

fn sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![];
    collect(&root.join("src"), &mut files);
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let name = p.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
            let mut module: Vec<String> = name
                .trim_start_matches("src/")
                .trim_end_matches(".rs")
                .split('/')
                .map(str::to_string)
                .collect();
            if matches!(module.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                module.pop();
            }
            let text = std::fs::read_to_string(&p).unwrap();
            Source { name, module, text }
        })
        .collect()
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            collect(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The code of `text`: comments and the contents of string and character
/// literals blanked, line breaks kept (so line numbers stay).
fn code_only(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let keep_lines = |out: &mut String, from: &[char]| out.extend(from.iter().filter(|&&x| x == '\n'));
    let mut i = 0;
    while i < c.len() {
        let at = |k: usize| c.get(i + k).copied();
        let word_start = i == 0 || !is_ident(c[i - 1]);
        if at(0) == Some('/') && at(1) == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if at(0) == Some('/') && at(1) == Some('*') {
            let (start, mut depth) = (i, 0);
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            keep_lines(&mut out, &c[start..i.min(c.len())]);
        } else if word_start && (at(0) == Some('r') || (at(0) == Some('b') && at(1) == Some('r'))) && {
            let k = if at(0) == Some('b') { 1 } else { 0 };
            let hashes = c[i + k + 1..].iter().take_while(|&&x| x == '#').count();
            c.get(i + k + 1 + hashes) == Some(&'"')
        } {
            // A raw string: r"..." or r#"..."#.
            let k = if at(0) == Some('b') { 1 } else { 0 };
            let hashes = c[i + k + 1..].iter().take_while(|&&x| x == '#').count();
            let start = i;
            i += k + 2 + hashes;
            while i < c.len()
                && !(c[i] == '"' && c[i + 1..].iter().take(hashes).filter(|&&x| x == '#').count() == hashes)
            {
                i += 1;
            }
            i = (i + 1 + hashes).min(c.len());
            out.push_str("\"\"");
            keep_lines(&mut out, &c[start..i]);
        } else if at(0) == Some('"') {
            let start = i;
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i = (i + 1).min(c.len());
            out.push_str("\"\"");
            keep_lines(&mut out, &c[start..i]);
        } else if at(0) == Some('\'') && (at(1) == Some('\\') || at(2) == Some('\'')) {
            // A character literal ('x', '\n', '\'', '\u{..}'), not a lifetime.
            i += if at(1) == Some('\\') { 3 } else { 2 };
            while i < c.len() && c[i] != '\'' {
                i += 1;
            }
            i += 1;
            out.push_str("' '");
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The next item's first line after an attribute at line `i`: skips blank
/// lines and further attributes.
fn item_after(lines: &[&str], i: usize) -> Option<String> {
    lines[i + 1..]
        .iter()
        .map(|l| l.trim())
        .find(|l| !l.is_empty() && !l.starts_with("#["))
        .map(str::to_string)
}

/// `mod x;` or `pub(crate) mod x {`: the module's name and whether it is inline.
fn mod_item(line: &str) -> Option<(String, bool)> {
    let rest = line.split_once("mod ")?;
    if !rest.0.trim().is_empty() && !rest.0.trim().starts_with("pub") {
        return None;
    }
    let name: String = rest.1.chars().take_while(|&c| is_ident(c)).collect();
    let after = rest.1[name.len()..].trim_start();
    match after.chars().next() {
        Some(';') => Some((name, false)),
        Some('{') => Some((name, true)),
        _ => None,
    }
}

/// The code of `text` the import rules look at (see the file's doc; an
/// inline test module is blanked up to its closing brace, lines kept), and
/// the names of the file modules it declares under `#[cfg(test)]`.
fn non_test_part(text: &str) -> (String, Vec<String>) {
    let code = code_only(text);
    let mut lines: Vec<String> = code.lines().map(str::to_string).collect();
    let mut test_files = vec![];
    let mut i = 0;
    while i < lines.len() {
        if lines[i].trim() != "#[cfg(test)]" {
            i += 1;
            continue;
        }
        let refs: Vec<&str> = lines.iter().map(String::as_str).collect();
        match item_after(&refs, i).as_deref().and_then(mod_item) {
            Some((_, true)) => {
                // Blank from the attribute to the brace that closes the module.
                let mut depth = 0;
                let mut opened = false;
                let mut j = i;
                while j < lines.len() {
                    for c in lines[j].chars() {
                        match c {
                            '{' => {
                                depth += 1;
                                opened = true;
                            }
                            '}' => depth -= 1,
                            _ => {}
                        }
                    }
                    lines[j].clear();
                    j += 1;
                    if opened && depth == 0 {
                        break;
                    }
                }
                i = j;
            }
            Some((name, false)) => {
                test_files.push(name);
                i += 1;
            }
            None => i += 1,
        }
    }
    (lines.join("\n"), test_files)
}

/// Top-level modules named in `text` by a file of module path `module`:
/// (line from 1, module, the text that names it).
fn crate_references(text: &str, module: &[String]) -> Vec<(usize, String, String)> {
    let text = code_only(text);
    let mut out = vec![];
    let bytes: Vec<char> = text.chars().collect();
    let line_of = |at: usize| bytes[..at].iter().filter(|&&c| c == '\n').count() + 1;
    let starts_word = |at: usize| at == 0 || !is_ident(bytes[at - 1]);
    let word_at =
        |at: usize, w: &str| w.chars().enumerate().all(|(k, c)| bytes.get(at + k) == Some(&c)) && starts_word(at);
    let mut at = 0;
    while at < bytes.len() {
        // `crate::`, or as many `super::` as lead from this file to the crate root.
        let start = at;
        let mut rest = if word_at(at, "crate::") {
            Some(at + "crate::".len())
        } else if word_at(at, "super::") && !module.is_empty() {
            let mut p = at;
            let mut n = 0;
            while word_at(p, "super::") {
                p += "super::".len();
                n += 1;
            }
            at = p;
            (n == module.len()).then_some(p)
        } else {
            None
        };
        let Some(p) = rest.take() else {
            at = at.max(start + 1);
            continue;
        };
        let mut names = vec![];
        if bytes.get(p) == Some(&'{') {
            // `crate::{a, b::c, d::{e, f}}`: the names at the first level.
            let (mut depth, mut q, mut item_start) = (0, p, true);
            while q < bytes.len() {
                match bytes[q] {
                    '{' => {
                        depth += 1;
                        item_start = depth == 1;
                    }
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    ',' if depth == 1 => item_start = true,
                    c if item_start && depth == 1 && is_ident(c) => {
                        names.push(bytes[q..].iter().take_while(|&&c| is_ident(c)).collect::<String>());
                        item_start = false;
                    }
                    _ => {}
                }
                q += 1;
            }
            at = (q + 1).min(bytes.len());
        } else {
            let name: String = bytes[p..].iter().take_while(|&&c| is_ident(c)).collect();
            at = p + name.len();
            names.push(name);
        }
        let said: String = bytes[start..at.min(bytes.len())]
            .iter()
            .collect::<String>()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        for n in names.into_iter().filter(|n| !n.is_empty()) {
            out.push((line_of(start), n, said.clone()));
        }
    }
    out
}

/// Lines of `text` that name `word` as a whole word, any case: (line from 1, line).
fn mentions(text: &str, word: &str) -> Vec<(usize, String)> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| {
            let l = l.to_ascii_lowercase();
            l.match_indices(word)
                .any(|(i, _)| !l[..i].ends_with(is_ident) && !l[i + word.len()..].starts_with(is_ident))
        })
        .map(|(i, l)| (i + 1, l.trim().to_string()))
        .collect()
}

#[test]
fn imports_run_one_way_and_the_library_knows_no_command_line() {
    let sources = sources();
    let mut test_files: BTreeSet<String> = BTreeSet::new();
    for s in &sources {
        let dir = Path::new(&s.name).parent().unwrap().to_string_lossy().into_owned();
        // `mod x;` in `a/mod.rs` or `lib.rs` is `a/x.rs`; in `a/b.rs` it is `a/b/x.rs`.
        let base = match Path::new(&s.name).file_stem().unwrap().to_str().unwrap() {
            "mod" | "lib" | "main" => dir,
            stem => format!("{dir}/{stem}"),
        };
        for m in non_test_part(&s.text).1 {
            test_files.insert(format!("{base}/{m}.rs"));
            test_files.insert(format!("{base}/{m}/mod.rs"));
        }
    }
    let mut broken = vec![];
    let mut covered = vec![0; RULES.len()];
    for s in &sources {
        let test_only = s.name.ends_with("/tests.rs") || test_files.contains(&s.name);
        for (k, (rule, modules, forbidden)) in RULES.iter().enumerate() {
            if test_only || !s.module.first().is_some_and(|m| modules.contains(&m.as_str())) {
                continue;
            }
            covered[k] += 1;
            let (code, _) = non_test_part(&s.text);
            for (line, name, said) in crate_references(&code, &s.module) {
                if forbidden.contains(&name.as_str()) {
                    broken.push(format!(
                        "{}:{line}: `{said}` names {name}: {rule} ({} must name none of {})",
                        s.name,
                        modules.join(", "),
                        forbidden.join(", ")
                    ));
                }
            }
        }
        if !BINARY_FILES.contains(&s.name.as_str()) {
            for word in BINARY_CRATES {
                for (line, text) in mentions(&s.text, word) {
                    broken.push(format!(
                        "{}:{line}: mentions {word} (`{text}`): the command line and terminal live in {} only",
                        s.name,
                        BINARY_FILES.join(" and ")
                    ));
                }
            }
        }
    }
    // The rules looked at something: a moved folder must not make them pass by default.
    for (k, (rule, ..)) in RULES.iter().enumerate() {
        assert!(covered[k] > 0, "no source file falls under the rule '{rule}'");
    }
    assert!(
        broken.is_empty(),
        "{} broken import rules:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
fn the_scan_finds_every_form_of_a_crate_path() {
    let module = |m: &str| m.split('/').map(str::to_string).collect::<Vec<_>>();
    let text = "use crate::math::Vec3;\n\
                // crate::viewer in a comment\n\
                use crate::{film::Film,\n    integrator::{Progress, render}, self};\n\
                let x = super::super::photon::map();\n\
                let y = super::sibling::f();\n\
                let s = \"crate::state_file\"; let c = '\"'; fn f<'a>() -> my_crate::scene::X {}\n\
                /* crate::viewer */ $crate::settings::X\n";
    let found: Vec<(usize, String)> = crate_references(text, &module("scene/builtin"))
        .into_iter()
        .map(|(l, n, _)| (l, n))
        .collect();
    let want = [
        (1, "math"),
        (3, "film"),
        (3, "integrator"),
        (3, "self"),
        (5, "photon"),
        (8, "settings"),
    ];
    assert_eq!(found, want.iter().map(|(l, n)| (*l, n.to_string())).collect::<Vec<_>>());
    // From `scene/mod.rs`, one `super::` reaches the root.
    let found = crate_references("use super::viewer;", &module("scene"));
    assert_eq!(found[0].1, "viewer");

    // Test modules are left out, up to their end; what follows them is not.
    let text = "use x;\n#[cfg(test)]\nmod other;\nfn a() {}\n#[cfg(test)]\n#[allow(unused)]\nmod tests {\n    \
                use crate::viewer;\n    fn f() { let c = '}'; }\n}\nuse crate::photon;\n";
    let (code, test_files) = non_test_part(text);
    assert!(code.contains("fn a()") && !code.contains("viewer"), "{code}");
    assert_eq!(test_files, ["other"]);
    let found = crate_references(&code, &module("scene"));
    assert_eq!(found, [(11, "photon".to_string(), "crate::photon".to_string())]);

    assert_eq!(mentions("use clap::Parser;\n// Clap's\nclapping", "clap").len(), 2);
}
