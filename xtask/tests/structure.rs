//! The workspace's structural rules (issue 13), checked on the source text:
//!
//! - no library or binary source file over [`MAX_FILE_LINES`] lines, not counting items under
//!   `#[cfg(test)]` (unit tests live beside the code they test);
//! - no function over [`MAX_FN_LINES`] lines outside `#[cfg(test)]` items;
//! - no `use` cycle between the files of one crate (file A uses an item of file B while B,
//!   directly or through other files, uses an item of A). Re-exports (`pub use`,
//!   `pub(crate) use`) make a facade, not a dependency, and do not count.
//!
//! Integration tests, benches and examples are exempt: the rules are about the code a reader
//! navigates. The scan is a small lexer (comments, strings, raw strings, chars vs lifetimes),
//! enough for brace matching on this workspace; a failure names the file and line.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 800;
const MAX_FN_LINES: usize = 120;

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// `src` folders of every crate of the workspace (crates/* and xtask).
fn source_roots() -> Vec<(String, PathBuf)> {
    let root = workspace_root();
    let mut out = vec![("xtask".to_string(), root.join("xtask/src"))];
    let mut crates: Vec<_> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("src").is_dir())
        .collect();
    crates.sort();
    for c in crates {
        let name = c.file_name().unwrap().to_string_lossy().into_owned();
        out.push((name, c.join("src")));
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// A token of the lexer: an identifier/keyword, a punctuation character, or a literal
/// (strings and chars, whose content never matters here). Each carries its 1-based line.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Punct(char),
    Lit,
}

fn lex(src: &str) -> Vec<(Tok, usize)> {
    let b: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0usize, 1usize);
    let n = b.len();
    while i < n {
        let c = b[i];
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && i + 1 < n && b[i + 1] == '/' {
            while i < n && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && i + 1 < n && b[i + 1] == '*' {
            let mut depth = 0;
            while i < n {
                if b[i] == '/' && i + 1 < n && b[i + 1] == '*' {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && i + 1 < n && b[i + 1] == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if b[i] == '\n' {
                        line += 1;
                    }
                    i += 1;
                }
            }
        } else if (c == 'r' || c == 'b')
            && raw_string_start(&b, i).is_some()
            && !prev_is_ident(&b, i)
        {
            let (hashes, start) = raw_string_start(&b, i).unwrap();
            let l0 = line;
            i = start;
            loop {
                if i >= n {
                    break;
                }
                if b[i] == '"' && (0..hashes).all(|k| i + 1 + k < n && b[i + 1 + k] == '#') {
                    i += 1 + hashes;
                    break;
                }
                if b[i] == '\n' {
                    line += 1;
                }
                i += 1;
            }
            out.push((Tok::Lit, l0));
        } else if c == '"' || (c == 'b' && i + 1 < n && b[i + 1] == '"' && !prev_is_ident(&b, i)) {
            let l0 = line;
            i += if c == 'b' { 2 } else { 1 };
            while i < n && b[i] != '"' {
                if b[i] == '\\' {
                    i += 1;
                }
                if i < n && b[i] == '\n' {
                    line += 1;
                }
                i += 1;
            }
            i += 1;
            out.push((Tok::Lit, l0));
        } else if c == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime / label ('a).
            if i + 1 < n && b[i + 1] == '\\' {
                i += 2;
                while i < n && b[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push((Tok::Lit, line));
            } else if i + 2 < n && b[i + 2] == '\'' {
                i += 3;
                out.push((Tok::Lit, line));
            } else {
                i += 1;
                while i < n && (b[i].is_alphanumeric() || b[i] == '_') {
                    i += 1;
                }
            }
        } else if c.is_alphabetic() || c == '_' {
            let s = i;
            while i < n && (b[i].is_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            out.push((Tok::Ident(b[s..i].iter().collect()), line));
        } else if c.is_ascii_digit() {
            while i < n && (b[i].is_alphanumeric() || b[i] == '_' || b[i] == '.') {
                // `0..n` is a range, not a float.
                if b[i] == '.' && i + 1 < n && b[i + 1] == '.' {
                    break;
                }
                i += 1;
            }
            out.push((Tok::Lit, line));
        } else {
            out.push((Tok::Punct(c), line));
            i += 1;
        }
    }
    out
}

fn prev_is_ident(b: &[char], i: usize) -> bool {
    i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_')
}

/// `r"`, `r#"`, `br"`, `br##"` ...: the number of hashes and the index after the quote.
fn raw_string_start(b: &[char], i: usize) -> Option<(usize, usize)> {
    let mut j = i;
    if b[j] == 'b' {
        j += 1;
    }
    if j >= b.len() || b[j] != 'r' {
        return None;
    }
    j += 1;
    let mut hashes = 0;
    while j < b.len() && b[j] == '#' {
        hashes += 1;
        j += 1;
    }
    (j < b.len() && b[j] == '"').then_some((hashes, j + 1))
}

/// Index of the token closing the group opened at `open` (`{`, `(` or `[`).
fn matching(toks: &[(Tok, usize)], open: usize) -> usize {
    let mut depth = 0i64;
    for (k, (t, _)) in toks.iter().enumerate().skip(open) {
        match t {
            Tok::Punct('{' | '(' | '[') => depth += 1,
            Tok::Punct('}' | ')' | ']') => {
                depth -= 1;
                if depth == 0 {
                    return k;
                }
            }
            _ => {}
        }
    }
    toks.len() - 1
}

/// Token ranges of items under `#[cfg(test)]` (the attribute through the item's end).
fn test_ranges(toks: &[(Tok, usize)]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut k = 0;
    while k + 6 < toks.len() {
        let is_cfg_test = toks[k].0 == Tok::Punct('#')
            && toks[k + 1].0 == Tok::Punct('[')
            && toks[k + 2].0 == Tok::Ident("cfg".into())
            && toks[k + 3].0 == Tok::Punct('(')
            && toks[k + 4].0 == Tok::Ident("test".into())
            && toks[k + 5].0 == Tok::Punct(')');
        if !is_cfg_test {
            k += 1;
            continue;
        }
        // The item ends at its body's closing brace or at a `;` before any body.
        let mut j = matching(toks, k + 1) + 1;
        while j < toks.len() {
            match toks[j].0 {
                Tok::Punct('{') => {
                    j = matching(toks, j);
                    break;
                }
                Tok::Punct(';') => break,
                _ => j += 1,
            }
        }
        out.push((k, j.min(toks.len() - 1)));
        k = j + 1;
    }
    out
}

fn in_ranges(r: &[(usize, usize)], k: usize) -> bool {
    r.iter().any(|&(a, b)| a <= k && k <= b)
}

/// Lines of the file outside `#[cfg(test)]` items.
fn counted_lines(src: &str, toks: &[(Tok, usize)], tests: &[(usize, usize)]) -> usize {
    let total = src.lines().count();
    let excluded: usize = tests.iter().map(|&(a, b)| toks[b].1 - toks[a].1 + 1).sum();
    total - excluded
}

/// (name, first line, line count) of every `fn` with a body outside test items.
fn functions(toks: &[(Tok, usize)], tests: &[(usize, usize)]) -> Vec<(String, usize, usize)> {
    let mut out = Vec::new();
    for k in 0..toks.len().saturating_sub(1) {
        if toks[k].0 != Tok::Ident("fn".into()) || in_ranges(tests, k) {
            continue;
        }
        let Tok::Ident(name) = &toks[k + 1].0 else {
            continue;
        };
        // The body is the first `{` at depth 0 after the signature, unless a `;` comes first.
        let mut j = k + 2;
        let mut depth = 0i64;
        let mut body = None;
        while j < toks.len() {
            match toks[j].0 {
                Tok::Punct('(' | '[') => depth += 1,
                Tok::Punct(')' | ']') => depth -= 1,
                Tok::Punct('<') if depth == 0 => {}
                Tok::Punct(';') if depth == 0 => break,
                Tok::Punct('{') if depth == 0 => {
                    body = Some(j);
                    break;
                }
                _ => {}
            }
            j += 1;
        }
        if let Some(open) = body {
            let close = matching(toks, open);
            out.push((name.clone(), toks[k].1, toks[close].1 - toks[k].1 + 1));
        }
    }
    out
}

/// Module path of a file below `src`: `src/a/b.rs` and `src/a/b/mod.rs` are `a::b`; the crate
/// root (`lib.rs`, `main.rs`) is the empty path.
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") || !parts.is_empty() && stem != "mod" {
        parts.push(stem.to_string());
    }
    parts
}

/// The paths that `use` declarations of a file (outside test items and re-exports) name,
/// resolved to absolute module paths within the crate (`crate::`, `super::`, `self::`).
fn used_paths(
    toks: &[(Tok, usize)],
    tests: &[(usize, usize)],
    me: &[String],
    is_mod_rs: bool,
) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut k = 0;
    while k < toks.len() {
        if toks[k].0 != Tok::Ident("use".into()) || in_ranges(tests, k) {
            k += 1;
            continue;
        }
        let reexport = k > 0
            && (toks[k - 1].0 == Tok::Ident("pub".into()) || toks[k - 1].0 == Tok::Punct(')'));
        let mut end = k + 1;
        while end < toks.len() && toks[end].0 != Tok::Punct(';') {
            end += 1;
        }
        if !reexport {
            expand_use(&toks[k + 1..end], Vec::new(), &mut out);
        }
        k = end + 1;
    }
    out.extend(inline_paths(toks, tests));
    // Resolve relative heads; a path without one is relative to this module (2018 paths)
    // and only matters when it names one of the crate's own modules.
    let _ = is_mod_rs;
    out.into_iter()
        .filter_map(|p| {
            let head = p.first()?.as_str();
            match head {
                "crate" => Some(p[1..].to_vec()),
                "self" => Some([me.to_vec(), p[1..].to_vec()].concat()),
                "super" => {
                    let mut base = me.to_vec();
                    let mut rest = &p[..];
                    while rest.first().is_some_and(|s| s == "super") {
                        base.pop();
                        rest = &rest[1..];
                    }
                    Some([base, rest.to_vec()].concat())
                }
                _ => Some([me.to_vec(), p].concat()),
            }
        })
        .collect()
}

/// Paths written in code (`crate::a::f()`, `super::B`, `child::g()`), outside `use`
/// declarations and test items.
fn inline_paths(toks: &[(Tok, usize)], tests: &[(usize, usize)]) -> Vec<Vec<String>> {
    let colons = |j: usize| {
        j + 1 < toks.len() && toks[j].0 == Tok::Punct(':') && toks[j + 1].0 == Tok::Punct(':')
    };
    let mut out = Vec::new();
    let mut k = 0;
    while k < toks.len() {
        if toks[k].0 == Tok::Ident("use".into()) {
            while k < toks.len() && toks[k].0 != Tok::Punct(';') {
                k += 1;
            }
            continue;
        }
        let starts = matches!(toks[k].0, Tok::Ident(_))
            && colons(k + 1)
            && !(k >= 1 && toks[k - 1].0 == Tok::Punct(':'))
            && !in_ranges(tests, k);
        if !starts {
            k += 1;
            continue;
        }
        let mut path = Vec::new();
        while let Tok::Ident(s) = &toks[k].0 {
            path.push(s.clone());
            if !colons(k + 1) || k + 3 >= toks.len() {
                k += 1;
                break;
            }
            k += 3;
        }
        out.push(path);
    }
    out
}

/// Expands a use tree (`a::{b, c::d}`) into its paths.
fn expand_use(toks: &[(Tok, usize)], prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut path = prefix.clone();
    let mut k = 0;
    while k < toks.len() {
        match &toks[k].0 {
            Tok::Ident(s) if s == "as" => {
                k += 2;
                continue;
            }
            Tok::Ident(s) => path.push(s.clone()),
            Tok::Punct('{') => {
                let close = matching(toks, k);
                let inner = &toks[k + 1..close];
                let mut start = 0;
                let mut depth = 0;
                for (j, (t, _)) in inner.iter().enumerate() {
                    match t {
                        Tok::Punct('{') => depth += 1,
                        Tok::Punct('}') => depth -= 1,
                        Tok::Punct(',') if depth == 0 => {
                            expand_use(&inner[start..j], path.clone(), out);
                            start = j + 1;
                        }
                        _ => {}
                    }
                }
                expand_use(&inner[start..], path.clone(), out);
                return;
            }
            Tok::Punct(',') => {
                out.push(std::mem::replace(&mut path, prefix.clone()));
            }
            _ => {}
        }
        k += 1;
    }
    if path.len() > prefix.len() || !path.is_empty() {
        out.push(path);
    }
}

struct Scan {
    violations: Vec<String>,
}

#[test]
fn structure_rules_hold() {
    let mut scan = Scan {
        violations: Vec::new(),
    };
    for (krate, src) in source_roots() {
        let mut files = Vec::new();
        rust_files(&src, &mut files);
        let mut modules: BTreeMap<Vec<String>, PathBuf> = BTreeMap::new();
        let mut uses: BTreeMap<PathBuf, Vec<Vec<String>>> = BTreeMap::new();
        for f in &files {
            let text = std::fs::read_to_string(f).unwrap();
            let toks = lex(&text);
            let tests = test_ranges(&toks);
            let rel = f
                .strip_prefix(workspace_root())
                .unwrap()
                .display()
                .to_string();
            let lines = counted_lines(&text, &toks, &tests);
            if lines > MAX_FILE_LINES {
                scan.violations.push(format!(
                    "{rel}: {lines} lines outside tests (max {MAX_FILE_LINES})"
                ));
            }
            for (name, line, len) in functions(&toks, &tests) {
                if len > MAX_FN_LINES {
                    scan.violations.push(format!(
                        "{rel}:{line}: fn {name} has {len} lines (max {MAX_FN_LINES})"
                    ));
                }
            }
            let me = module_path(&src, f);
            let is_mod_rs = f.file_name().is_some_and(|n| n == "mod.rs");
            uses.insert(f.clone(), used_paths(&toks, &tests, &me, is_mod_rs));
            modules.insert(me, f.clone());
        }
        // File graph: a used path maps to the file of its longest module prefix.
        let mut edges: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
        for (f, paths) in &uses {
            for p in paths {
                let target = (0..=p.len())
                    .rev()
                    .find_map(|l| modules.get(&p[..l]).filter(|_| l > 0));
                if let Some(t) = target
                    && t != f
                {
                    edges.entry(f.clone()).or_default().insert(t.clone());
                }
            }
        }
        for cycle in cycles(&edges) {
            let names: Vec<String> = cycle
                .iter()
                .map(|p| p.strip_prefix(&src).unwrap().display().to_string())
                .collect();
            scan.violations.push(format!(
                "{krate}: use cycle between files: {}",
                names.join(" -> ")
            ));
        }
    }
    assert!(
        scan.violations.is_empty(),
        "structure rules broken:\n{}",
        scan.violations.join("\n")
    );
}

/// One representative cycle per strongly connected component of more than one file.
fn cycles(edges: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut reported: BTreeSet<PathBuf> = BTreeSet::new();
    for start in edges.keys() {
        if reported.contains(start) {
            continue;
        }
        // Breadth-first search for a path back to `start`.
        let mut prev: BTreeMap<PathBuf, PathBuf> = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([start.clone()]);
        let mut found = None;
        while let Some(u) = queue.pop_front() {
            for v in edges.get(&u).into_iter().flatten() {
                if v == start {
                    found = Some(u.clone());
                    break;
                }
                if !prev.contains_key(v) {
                    prev.insert(v.clone(), u.clone());
                    queue.push_back(v.clone());
                }
            }
            if found.is_some() {
                break;
            }
        }
        if let Some(mut u) = found {
            let mut cyc = vec![start.clone()];
            let mut back = vec![u.clone()];
            while &u != start {
                match prev.get(&u) {
                    Some(p) if p != start => {
                        back.push(p.clone());
                        u = p.clone();
                    }
                    _ => break,
                }
            }
            back.reverse();
            cyc.extend(back);
            cyc.push(start.clone());
            reported.extend(cyc.iter().cloned());
            out.push(cyc);
        }
    }
    out
}

#[test]
fn the_lexer_sees_through_strings_chars_and_lifetimes() {
    let src = "fn a<'x>(s: &'x str) -> char { let _ = \"}{\"; let _ = r#\"}\"#; '}' }\nfn b() {}\n";
    let toks = lex(src);
    let f = functions(&toks, &[]);
    assert_eq!(
        f.iter().map(|x| x.0.as_str()).collect::<Vec<_>>(),
        ["a", "b"]
    );
    assert_eq!(f[0].2, 1);
}

#[test]
fn the_scan_finds_a_long_function_a_cycle_and_skips_tests() {
    let body = "    let x = 1;\n".repeat(130);
    let src =
        format!("fn long() {{\n{body}}}\n#[cfg(test)]\nmod tests {{\n fn t() {{\n{body}}}\n}}\n");
    let toks = lex(&src);
    let tests = test_ranges(&toks);
    let f = functions(&toks, &tests);
    assert_eq!(f.len(), 1);
    assert!(f[0].2 > MAX_FN_LINES);
    assert_eq!(counted_lines(&src, &toks, &tests), 132);
    let a = PathBuf::from("a.rs");
    let b = PathBuf::from("b.rs");
    let edges = BTreeMap::from([
        (a.clone(), BTreeSet::from([b.clone()])),
        (b.clone(), BTreeSet::from([a.clone()])),
    ]);
    assert_eq!(cycles(&edges).len(), 1);
    let uses = used_paths(
        &lex("use super::{x::Y, z};\npub use crate::q::R;"),
        &[],
        &["m".into(), "n".into()],
        false,
    );
    assert_eq!(
        uses,
        vec![
            vec!["m".to_string(), "x".into(), "Y".into()],
            vec!["m".into(), "z".into()]
        ]
    );
}

/// Every source path that `docs/ARCHITECTURE.md` names in backquotes (`crate/src/x.rs`,
/// `crate/src/dir/`, with `{a,b}` alternatives) exists, so the map stays true as code moves.
#[test]
fn architecture_doc_paths_exist() {
    let root = workspace_root();
    let doc = std::fs::read_to_string(root.join("docs/ARCHITECTURE.md")).unwrap();
    let mut missing = Vec::new();
    let mut checked = 0;
    for (k, span) in doc.split('`').enumerate() {
        let is_path = k % 2 == 1
            && span.contains("/src/")
            && !span.contains(' ')
            && (span.ends_with(".rs") || span.ends_with('/') || span.ends_with('}'));
        if !is_path {
            continue;
        }
        let expanded: Vec<String> = match (span.find('{'), span.rfind('}')) {
            (Some(a), Some(b)) if a < b => span[a + 1..b]
                .split(',')
                .map(|alt| format!("{}{alt}{}", &span[..a], &span[b + 1..]))
                .collect(),
            _ => vec![span.to_string()],
        };
        for p in expanded {
            checked += 1;
            if !root.join(&p).exists() && !root.join("crates").join(&p).exists() {
                missing.push(p);
            }
        }
    }
    assert!(
        checked > 40,
        "only {checked} paths found: is the doc's format unchanged?"
    );
    assert!(
        missing.is_empty(),
        "docs/ARCHITECTURE.md names missing paths: {missing:?}"
    );
}
