//! The layout rules of `ARCHITECTURE.md` that a test can hold: no source file over 700
//! lines of non-test code, no import circle between the modules of a folder, and no
//! global mutable state in the engine.
//!
//! Input: the sources of `engine/src`, `systems/src` and `bench/`, read as text (a small
//! lexer, no parser: enough for `mod`, `use` and paths). Cost: a fraction of a second.

use std::path::{Path, PathBuf};

/// Largest number of non-test lines in one source file of `engine/src`, `systems/src`
/// and `bench/`.
const MAX_LINES: usize = 700;

/// The workspace root (the parent of this crate's folder).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate lives in the workspace root")
        .to_path_buf()
}

/// The folders whose sources the layout rules hold for.
const SOURCE_DIRS: [&str; 3] = ["engine/src", "systems/src", "bench"];

/// Every `.rs` file under `dir`, sorted, leaving out build output and results
/// (`target`, `results`).
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let mut entries: Vec<_> = std::fs::read_dir(&d)
            .unwrap_or_else(|e| panic!("reading {}: {e}", d.display()))
            .map(|e| e.expect("directory entry").path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                if !p
                    .file_name()
                    .is_some_and(|n| n == "target" || n == "results")
                {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Whether a file holds only tests: `tests.rs`, `*_tests.rs`, or anything in a `tests`
/// folder (they are included with `#[cfg(test)] mod tests;`).
fn is_test_file(relative: &Path) -> bool {
    let name = relative.file_name().and_then(|n| n.to_str()).unwrap_or("");
    name == "tests.rs"
        || name.ends_with("_tests.rs")
        || relative.components().any(|c| c.as_os_str() == "tests")
}

/// Braces opened minus braces closed on one line of Rust, ignoring those in `//`
/// comments, string literals and character literals (enough for our sources: no raw
/// strings with braces spanning lines, no block comments holding unbalanced braces).
fn brace_balance(line: &str) -> i64 {
    let b = line.as_bytes();
    let (mut i, mut depth) = (0, 0i64);
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => break,
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
            }
            // A character literal ('{', '\'' or '\u{7b}'), not a lifetime.
            b'\'' if b.get(i + 2) == Some(&b'\'') => i += 2,
            b'\'' if b.get(i + 1) == Some(&b'\\') => {
                i += 2;
                while i < b.len() && b[i] != b'\'' {
                    i += 1;
                }
            }
            b'{' => depth += 1,
            b'}' => depth -= 1,
            _ => {}
        }
        i += 1;
    }
    depth
}

/// Lines of non-test code in `source`: every line except those of `#[cfg(test)]`
/// inline modules (`#[cfg(test)]` then `mod name {` up to its closing brace).
fn non_test_lines(source: &str) -> usize {
    let mut count = 0;
    let mut lines = source.lines().peekable();
    while let Some(line) = lines.next() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            let next = lines.peek().map(|l| l.trim_start()).unwrap_or("");
            let is_module = next.starts_with("mod ")
                || next.starts_with("pub mod ")
                || next.starts_with("pub(crate) mod ");
            if is_module && next.contains('{') {
                let mut depth = 0;
                for l in lines.by_ref() {
                    depth += brace_balance(l);
                    if depth <= 0 {
                        break;
                    }
                }
                continue;
            }
        }
        count += 1;
    }
    count
}

#[test]
fn the_line_counter_skips_inline_test_modules_only() {
    let src = "fn a() {\n    let s = \"}\";\n}\n#[cfg(test)]\nmod tests {\n    fn b() { let c = '}'; }\n    // }\n}\nfn after() {}\n";
    // `fn a` (3 lines) and `fn after` count; the test module's 5 lines do not.
    assert_eq!(non_test_lines(src), 4);
    // A `#[cfg(test)]` item that is not an inline module counts.
    assert_eq!(non_test_lines("#[cfg(test)]\nmod tests;\nfn x() {}\n"), 3);
    assert_eq!(brace_balance("let x = '{'; if y { // }"), 1);
    assert_eq!(brace_balance("fn f<'a>(x: &'a str) {"), 1);
}

#[test]
fn no_source_file_is_over_700_lines_of_non_test_code() {
    let root = root();
    let mut over = Vec::new();
    for dir in SOURCE_DIRS {
        for path in rust_files(&root.join(dir)) {
            let relative = path.strip_prefix(&root).unwrap_or(&path);
            if is_test_file(relative) {
                continue;
            }
            let source = std::fs::read_to_string(&path).expect("readable source");
            let n = non_test_lines(&source);
            if n > MAX_LINES {
                over.push(format!("{}: {n}", relative.display()));
            }
        }
    }
    assert!(
        over.is_empty(),
        "files over {MAX_LINES} lines of non-test code (split them by concern): {over:?}"
    );
}

/// Whether a line declares global mutable state: a `static mut`, or a `static` of a
/// type with interior mutability.
fn is_mutable_static(line: &str) -> bool {
    let t = line.trim_start();
    let t = t
        .strip_prefix("pub(crate) ")
        .or_else(|| t.strip_prefix("pub "))
        .unwrap_or(t);
    let Some(rest) = t.strip_prefix("static ") else {
        return false;
    };
    const INTERIOR: [&str; 8] = [
        "Atomic",
        "Mutex",
        "RwLock",
        "Cell",
        "OnceLock",
        "LazyLock",
        "Lazy<",
        "thread_local",
    ];
    rest.starts_with("mut ") || INTERIOR.iter().any(|k| rest.contains(k))
}

#[test]
fn the_engine_has_no_global_mutable_state() {
    assert!(is_mutable_static(
        "static NEXT: AtomicU64 = AtomicU64::new(0);"
    ));
    assert!(is_mutable_static("pub static mut X: u32 = 0;"));
    assert!(!is_mutable_static("static TABLE: [u8; 4] = [0, 1, 2, 3];"));
    assert!(!is_mutable_static("fn f(x: &'static str) {}"));
    let root = root();
    let mut found = Vec::new();
    for path in rust_files(&root.join("engine/src")) {
        let source = std::fs::read_to_string(&path).expect("readable source");
        for (i, line) in source.lines().enumerate() {
            if is_mutable_static(line) || line.contains("thread_local!") {
                found.push(format!(
                    "{}:{}: {}",
                    path.strip_prefix(&root).unwrap_or(&path).display(),
                    i + 1,
                    line.trim()
                ));
            }
        }
    }
    assert!(
        found.is_empty(),
        "global mutable state in engine/src (pass state as an argument or keep it in a struct): {found:?}"
    );
}

// ---------------------------------------------------------------------------------------
// Import circles inside a folder.
// ---------------------------------------------------------------------------------------

/// Circles that other changes are breaking, allowed until those land:
/// `(folder, modules of the circle, sorted)`. Any circle not listed here fails
/// [`no_folder_has_an_import_circle`], and so does a listed one that is gone (so the list
/// cannot go stale): remove an entry when its circle is broken. Meant to be empty.
const KNOWN_CIRCLES: &[(&str, &[&str])] = &[];

/// One token of Rust source: enough to follow `mod`, `use` and paths.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    /// An identifier or keyword.
    Ident(String),
    /// A string literal's contents (escapes left as written).
    Str(String),
    /// `::`.
    Sep,
    /// Any other character (literals other than strings are dropped).
    Punct(char),
}

/// The tokens of `source` with their 1-based line numbers: comments, numbers and
/// character literals dropped; a lifetime `'a` becomes the identifier `a`.
fn lex(source: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = source.chars().collect();
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    let ident_char = |ch: char| ch.is_alphanumeric() || ch == '_';
    while i < c.len() {
        let ch = c[i];
        let next = c.get(i + 1).copied();
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && next == Some('*') {
            let mut depth = 0;
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
                    line += usize::from(c[i] == '\n');
                    i += 1;
                }
            }
        } else if ch == 'r'
            && (next == Some('"')
                || (next == Some('#') && c.get(i + 2).is_some_and(|&x| x == '"' || x == '#')))
        {
            // A raw string: r"..." or r#"..."#.
            let mut hashes = 0;
            i += 1;
            while c.get(i) == Some(&'#') {
                hashes += 1;
                i += 1;
            }
            i += 1;
            let (start, start_line) = (i, line);
            loop {
                if i >= c.len() {
                    break;
                }
                if c[i] == '"' && (0..hashes).all(|k| c.get(i + 1 + k) == Some(&'#')) {
                    break;
                }
                line += usize::from(c[i] == '\n');
                i += 1;
            }
            out.push((
                Tok::Str(c[start..i.min(c.len())].iter().collect()),
                start_line,
            ));
            i += 1 + hashes;
        } else if ch == '"' {
            i += 1;
            let (start, start_line) = (i, line);
            while i < c.len() && c[i] != '"' {
                line += usize::from(c[i] == '\n');
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            out.push((
                Tok::Str(c[start..i.min(c.len())].iter().collect()),
                start_line,
            ));
            i += 1;
        } else if ch == '\'' {
            if next == Some('\\') {
                // An escaped character literal: '\n', '\'', '\u{7b}'.
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                // A lifetime or label: its name is lexed as an identifier.
                i += 1;
            }
        } else if ch.is_ascii_digit() {
            while i < c.len() && ident_char(c[i]) {
                i += 1;
            }
        } else if ident_char(ch) {
            let start = i;
            while i < c.len() && ident_char(c[i]) {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            // `b"..."` and `br"..."` are strings: drop the prefix, lex the rest.
            if !(word == "b" && matches!(c.get(i), Some('"' | '\''))) {
                out.push((Tok::Ident(word), line));
            }
        } else if ch == ':' && next == Some(':') {
            out.push((Tok::Sep, line));
            i += 2;
        } else {
            out.push((Tok::Punct(ch), line));
            i += 1;
        }
    }
    out
}

/// Whether `toks[i..]` starts with `#[cfg(test)]`.
fn is_cfg_test(toks: &[(Tok, usize)], i: usize) -> bool {
    let want = [
        Tok::Punct('#'),
        Tok::Punct('['),
        Tok::Ident("cfg".into()),
        Tok::Punct('('),
        Tok::Ident("test".into()),
        Tok::Punct(')'),
        Tok::Punct(']'),
    ];
    toks.len() >= i + want.len() && want.iter().enumerate().all(|(k, w)| &toks[i + k].0 == w)
}

/// The index just past the bracketed group opened at `toks[i]` (`(`, `[` or `{`).
fn skip_group(toks: &[(Tok, usize)], mut i: usize) -> usize {
    let mut depth = 0i64;
    while i < toks.len() {
        match toks[i].0 {
            Tok::Punct('(' | '[' | '{') => depth += 1,
            Tok::Punct(')' | ']' | '}') => depth -= 1,
            _ => {}
        }
        i += 1;
        if depth <= 0 {
            break;
        }
    }
    i
}

/// `toks` without the items marked `#[cfg(test)]` (the attribute, the attributes after
/// it, and the item up to its `;` or through its braced body).
fn without_test_items(toks: &[(Tok, usize)]) -> Vec<(Tok, usize)> {
    let mut out = Vec::with_capacity(toks.len());
    let mut i = 0;
    while i < toks.len() {
        if !is_cfg_test(toks, i) {
            out.push(toks[i].clone());
            i += 1;
            continue;
        }
        i += 7;
        while toks.get(i).map(|t| &t.0) == Some(&Tok::Punct('#')) {
            i = skip_group(toks, i + 1);
        }
        while i < toks.len() {
            match toks[i].0 {
                Tok::Punct(';') => {
                    i += 1;
                    break;
                }
                Tok::Punct('{') => {
                    i = skip_group(toks, i);
                    break;
                }
                Tok::Punct('(' | '[') => i = skip_group(toks, i),
                // The end of the enclosing group (a `#[cfg(test)]` field or argument).
                Tok::Punct(')' | ']' | '}') => break,
                _ => i += 1,
            }
        }
    }
    out
}

/// A module path inside one crate (`["sample", "sampler"]`; the crate root is empty).
type ModPath = Vec<String>;

/// A path named in code, with where it was named.
struct Reference {
    /// The module whose code names it.
    from: ModPath,
    /// The path as written (`super::x::Y`), `self` segments from `use` groups removed.
    path: Vec<String>,
    /// `file:line` of the reference.
    at: String,
}

/// What one module's code says: its `use` bindings and glob imports, and the names of
/// the items it defines.
#[derive(Clone, Default)]
struct ModuleFacts {
    /// `name -> path as written`, from `use` declarations (aliases included).
    bindings: Vec<(String, Vec<String>)>,
    /// Paths of `use path::*` declarations.
    globs: Vec<Vec<String>>,
    /// Names of the items defined at the module's top level.
    defined: Vec<String>,
}

/// Everything read from one crate: its modules and the paths its code names.
#[derive(Default)]
struct CrateFacts {
    /// Every module, with its facts and the file that holds it (`x/mod.rs`, `x.rs` or the
    /// file holding an inline module, then `::name`).
    modules: Vec<(ModPath, String, ModuleFacts)>,
    /// Every `crate::`, `super::` and `self::` path named in code.
    references: Vec<Reference>,
}

/// The flattened paths of a `use` tree starting at `toks[*i]`, up to its `;`, each with
/// the name it binds (`None` for a glob).
fn use_tree(
    toks: &[(Tok, usize)],
    i: &mut usize,
    prefix: &[String],
    out: &mut Vec<(Option<String>, Vec<String>)>,
) {
    let mut path = prefix.to_vec();
    loop {
        match toks.get(*i).map(|t| &t.0) {
            Some(Tok::Ident(w)) if w == "as" => {
                *i += 1;
                if let Some((Tok::Ident(alias), _)) = toks.get(*i) {
                    *i += 1;
                    out.push((Some(alias.clone()), strip_self(&path)));
                }
                return;
            }
            Some(Tok::Ident(w)) => {
                path.push(w.clone());
                *i += 1;
            }
            Some(Tok::Sep) => *i += 1,
            Some(Tok::Punct('*')) => {
                *i += 1;
                out.push((None, strip_self(&path)));
                return;
            }
            Some(Tok::Punct('{')) => {
                *i += 1;
                loop {
                    match toks.get(*i).map(|t| &t.0) {
                        Some(Tok::Punct('}')) => {
                            *i += 1;
                            return;
                        }
                        Some(Tok::Punct(',')) => *i += 1,
                        None => return,
                        _ => use_tree(toks, i, &path, out),
                    }
                }
            }
            _ => {
                if path.len() > prefix.len() {
                    let name = path.last().cloned();
                    let name = if name.as_deref() == Some("self") {
                        path.get(path.len().wrapping_sub(2)).cloned()
                    } else {
                        name
                    };
                    out.push((name, strip_self(&path)));
                }
                return;
            }
        }
    }
}

/// `path` without `self` segments after the first (`a::b::self` is `a::b`).
fn strip_self(path: &[String]) -> Vec<String> {
    path.iter()
        .enumerate()
        .filter(|(k, s)| *k == 0 || s.as_str() != "self")
        .map(|(_, s)| s.clone())
        .collect()
}

/// Whether a file's `mod x;` children live beside it (`mod.rs`, `lib.rs`, `main.rs`, a
/// binary or bench root) rather than in a folder named after it.
fn is_mod_rs_like(path: &str) -> bool {
    path.ends_with("/mod.rs") || is_crate_root(path)
}

/// One file read: its modules' facts (relative module paths, the file's own module
/// first as `[]`), its references (relative), and the files it declares as children
/// (`relative module path of the child, file path`).
struct FileFacts {
    modules: Vec<(ModPath, String, ModuleFacts)>,
    references: Vec<Reference>,
    children: Vec<(ModPath, String)>,
}

/// Reads one file (`path` relative to the workspace, `/`-separated).
fn read_file_facts(path: &str, source: &str, with_tests: bool) -> FileFacts {
    let toks = lex(source);
    let toks = if with_tests {
        toks
    } else {
        without_test_items(&toks)
    };
    let dir = Path::new(path)
        .parent()
        .map(|d| d.to_string_lossy().replace('\\', "/"))
        .unwrap_or_default();
    let own_dir = if is_mod_rs_like(path) {
        dir.clone()
    } else {
        path.trim_end_matches(".rs").to_string()
    };
    let mut facts = FileFacts {
        modules: vec![(Vec::new(), path.to_string(), ModuleFacts::default())],
        references: Vec::new(),
        children: Vec::new(),
    };
    // Open inline modules: (relative path, index in facts.modules, brace depth inside).
    let mut stack: Vec<(ModPath, usize, i64)> = vec![(Vec::new(), 0, 0)];
    let mut depth = 0i64;
    let mut path_attr: Option<String> = None;
    let mut i = 0;
    while i < toks.len() {
        let (tok, line) = (&toks[i].0, toks[i].1);
        let (here, slot, base) = stack.last().cloned().expect("the file's module is open");
        let at_top = depth == base;
        let word = |k: usize| match toks.get(k).map(|t| &t.0) {
            Some(Tok::Ident(w)) => Some(w.as_str()),
            _ => None,
        };
        match tok {
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => {
                depth -= 1;
                if stack.len() > 1 && depth == base - 1 {
                    stack.pop();
                }
            }
            Tok::Punct('#') if word(i + 2) == Some("path") => {
                if let Some((Tok::Str(s), _)) = toks.get(i + 4) {
                    path_attr = Some(s.clone());
                }
            }
            Tok::Ident(w) if w == "mod" => {
                if let (Some(name), Some(next)) = (word(i + 1), toks.get(i + 2).map(|t| &t.0)) {
                    let mut child = here.clone();
                    child.push(name.to_string());
                    if at_top {
                        facts.modules[slot].2.defined.push(name.to_string());
                    }
                    if next == &Tok::Punct('{') {
                        facts.modules.push((
                            child.clone(),
                            format!("{path}::{}", child.join("::")),
                            ModuleFacts::default(),
                        ));
                        stack.push((child, facts.modules.len() - 1, depth + 1));
                        depth += 1;
                        i += 3;
                        path_attr = None;
                        continue;
                    }
                    let file = match path_attr.take() {
                        Some(p) => format!("{dir}/{p}"),
                        None => {
                            let folder = [own_dir.clone()]
                                .into_iter()
                                .chain(here.iter().cloned())
                                .collect::<Vec<_>>()
                                .join("/");
                            format!("{folder}/{name}.rs")
                        }
                    };
                    facts.children.push((child, file));
                }
            }
            Tok::Ident(w) if w == "use" => {
                let mut j = i + 1;
                let mut paths = Vec::new();
                use_tree(&toks, &mut j, &[], &mut paths);
                for (name, p) in paths {
                    let first = p.first().map(String::as_str);
                    if matches!(first, Some("crate" | "super" | "self")) {
                        facts.references.push(Reference {
                            from: here.clone(),
                            path: p.clone(),
                            at: format!("{path}:{line}"),
                        });
                    }
                    match name {
                        Some(n) => facts.modules[slot].2.bindings.push((n, p)),
                        None => facts.modules[slot].2.globs.push(p),
                    }
                }
                i = j;
                continue;
            }
            Tok::Ident(w)
                if w == "in"
                    && i >= 2
                    && toks[i - 1].0 == Tok::Punct('(')
                    && word(i - 2) == Some("pub") =>
            {
                // `pub(in path)`: a visibility, not a use.
                while i < toks.len() && toks[i].0 != Tok::Punct(')') {
                    i += 1;
                }
                continue;
            }
            Tok::Ident(w)
                if matches!(w.as_str(), "crate" | "super" | "self")
                    && toks.get(i + 1).map(|t| &t.0) == Some(&Tok::Sep) =>
            {
                let mut p = vec![w.clone()];
                let mut j = i + 1;
                while toks.get(j).map(|t| &t.0) == Some(&Tok::Sep) {
                    match word(j + 1) {
                        Some(s) => p.push(s.to_string()),
                        None => break,
                    }
                    j += 2;
                }
                facts.references.push(Reference {
                    from: here.clone(),
                    path: p,
                    at: format!("{path}:{line}"),
                });
                i = j;
                continue;
            }
            Tok::Ident(w)
                if at_top
                    && matches!(
                        w.as_str(),
                        "fn" | "struct" | "enum" | "trait" | "type" | "const" | "static" | "union"
                    ) =>
            {
                if let Some(name) = word(i + 1) {
                    facts.modules[slot].2.defined.push(name.to_string());
                }
            }
            _ => {}
        }
        i += 1;
    }
    facts
}

/// Whether a file is a crate root: `lib.rs`, `main.rs`, or a file right in `bin/` or
/// `benches/`.
fn is_crate_root(path: &str) -> bool {
    let p = Path::new(path);
    let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let parent = p
        .parent()
        .and_then(|d| d.file_name())
        .and_then(|n| n.to_str())
        .unwrap_or("");
    matches!(name, "lib.rs" | "main.rs") || matches!(parent, "bin" | "benches")
}

/// The crates in `files` (`(path, source)`, paths `/`-separated), each followed from its
/// root (see [`is_crate_root`]) through its `mod` declarations; files no root declares
/// (test files when tests are left out) are not read.
fn read_crates(files: &[(String, String)], with_tests: bool) -> Vec<(String, CrateFacts)> {
    let facts: Vec<FileFacts> = files
        .iter()
        .map(|(p, s)| read_file_facts(p, s, with_tests))
        .collect();
    let index = |path: &str| -> Option<usize> {
        let dir_mod = format!("{}/mod.rs", path.trim_end_matches(".rs"));
        files
            .iter()
            .position(|(p, _)| p == path)
            .or_else(|| files.iter().position(|(p, _)| *p == dir_mod))
    };
    let mut crates = Vec::new();
    for (root, (root_path, _)) in files.iter().enumerate() {
        if !is_crate_root(root_path) {
            continue;
        }
        let mut krate = CrateFacts::default();
        let mut todo: Vec<(usize, ModPath)> = vec![(root, Vec::new())];
        while let Some((file, base)) = todo.pop() {
            let f = &facts[file];
            let prefixed = |p: &ModPath| base.iter().chain(p).cloned().collect::<ModPath>();
            for (m, shown, mf) in &f.modules {
                krate.modules.push((prefixed(m), shown.clone(), mf.clone()));
            }
            for r in &f.references {
                krate.references.push(Reference {
                    from: prefixed(&r.from),
                    path: r.path.clone(),
                    at: r.at.clone(),
                });
            }
            for (child, file) in &f.children {
                if let Some(k) = index(file) {
                    todo.push((k, prefixed(child)));
                }
            }
        }
        crates.push((root_path.clone(), krate));
    }
    crates
}

/// `path` as written in module `at` made absolute in the crate, or `None` for a path
/// outside it (another crate) or not starting at a module the crate knows.
fn absolute(krate: &CrateFacts, at: &[String], path: &[String]) -> Option<ModPath> {
    let first = path.first()?;
    let (mut base, rest) = match first.as_str() {
        "crate" => (Vec::new(), &path[1..]),
        "self" => (at.to_vec(), &path[1..]),
        "super" => (at.to_vec(), path),
        _ => {
            // A 2018 relative path from a child module (`use child::Item;`).
            let mut child = at.to_vec();
            child.push(first.clone());
            if !krate.modules.iter().any(|(m, _, _)| *m == child) {
                return None;
            }
            (at.to_vec(), path)
        }
    };
    let mut rest = rest.iter().peekable();
    while rest.peek().is_some_and(|s| s.as_str() == "super") {
        base.pop()?;
        rest.next();
    }
    base.extend(rest.cloned());
    Some(base)
}

/// The module part of an absolute path: its longest prefix that is a module.
fn module_of<'a>(krate: &'a CrateFacts, path: &[String]) -> (usize, Option<&'a ModuleFacts>) {
    for n in (0..=path.len()).rev() {
        if let Some((_, _, facts)) = krate.modules.iter().find(|(m, _, _)| m[..] == path[..n]) {
            return (n, Some(facts));
        }
    }
    (0, None)
}

/// An absolute path with every `use` re-export on its way followed: `sample::Sampler`,
/// re-exported in `sample/mod.rs` from `sample::sampler`, becomes
/// `sample::sampler::Sampler`. A name met in a glob import is followed into the globbed
/// module when that module defines or imports it.
fn resolve(krate: &CrateFacts, mut path: ModPath) -> ModPath {
    for _ in 0..16 {
        let (n, Some(facts)) = module_of(krate, &path) else {
            return path;
        };
        let Some(name) = path.get(n).cloned() else {
            return path;
        };
        let module = path[..n].to_vec();
        let binding = facts
            .bindings
            .iter()
            .find(|(b, _)| *b == name)
            .map(|(_, p)| p.clone());
        let target = if let Some(p) = binding {
            absolute(krate, &module, &p)
        } else if facts.defined.contains(&name) {
            None
        } else {
            facts.globs.iter().find_map(|g| {
                let g = absolute(krate, &module, g)?;
                let (k, f) = module_of(krate, &g);
                let f = f.filter(|_| k == g.len())?;
                let known = f.defined.contains(&name) || f.bindings.iter().any(|(b, _)| *b == name);
                known.then(|| g.iter().cloned().chain([name.clone()]).collect())
            })
        };
        match target {
            Some(t) if t != path[..=n] => {
                path = t.into_iter().chain(path[n + 1..].iter().cloned()).collect()
            }
            _ => return path,
        }
    }
    path
}

/// An arrow between two modules of one folder: `from` uses `to`, first at `at`.
struct Arrow {
    folder: ModPath,
    from: String,
    to: String,
    at: String,
}

/// Every arrow between sibling modules of a crate: a reference from code in module
/// `a::b::...` to an item in `a::c::...` is an arrow `b -> c` in folder `a` (code in a
/// module's children counts as the module's).
fn sibling_arrows(krate: &CrateFacts) -> Vec<Arrow> {
    let mut arrows: Vec<Arrow> = Vec::new();
    for r in &krate.references {
        let Some(path) = absolute(krate, &r.from, &r.path) else {
            continue;
        };
        let path = resolve(krate, path);
        let (n, _) = module_of(krate, &path);
        let target = &path[..n];
        let common = r
            .from
            .iter()
            .zip(target)
            .take_while(|(a, b)| a == b)
            .count();
        if common == r.from.len() || common == target.len() {
            // A module's own items, an ancestor's or a descendant's: not a sibling.
            continue;
        }
        let folder = r.from[..common].to_vec();
        let (from, to) = (r.from[common].clone(), target[common].clone());
        if !arrows
            .iter()
            .any(|a| a.folder == folder && a.from == from && a.to == to)
        {
            arrows.push(Arrow {
                folder,
                from,
                to,
                at: r.at.clone(),
            });
        }
    }
    arrows
}

/// The modules that `from` reaches through `arrows` (itself first), by repeated
/// relaxation: folders are small.
fn reachable<'a>(arrows: &[&'a Arrow], from: &'a str) -> Vec<&'a str> {
    let mut seen = vec![from];
    let mut k = 0;
    while k < seen.len() {
        for a in arrows {
            if a.from == seen[k] && !seen.contains(&a.to.as_str()) {
                seen.push(&a.to);
            }
        }
        k += 1;
    }
    seen
}

/// The import circles of a crate: every group of two or more sibling modules that reach
/// each other through arrows (a strongly connected component), as
/// `(folder, sorted modules, the arrows between them)`.
fn circles(krate: &CrateFacts) -> Vec<(ModPath, Vec<String>, Vec<String>)> {
    let arrows = sibling_arrows(krate);
    let mut folders: Vec<ModPath> = arrows.iter().map(|a| a.folder.clone()).collect();
    folders.sort();
    folders.dedup();
    let mut out = Vec::new();
    for folder in folders {
        let here: Vec<&Arrow> = arrows.iter().filter(|a| a.folder == folder).collect();
        let mut nodes: Vec<&str> = here
            .iter()
            .flat_map(|a| [a.from.as_str(), a.to.as_str()])
            .collect();
        nodes.sort();
        nodes.dedup();
        let reach = |from| reachable(&here, from);
        let mut done: Vec<&str> = Vec::new();
        for &n in &nodes {
            if done.contains(&n) {
                continue;
            }
            let mut group: Vec<&str> = reach(n)
                .into_iter()
                .filter(|&m| reach(m).contains(&n))
                .collect();
            group.sort();
            done.extend(&group);
            if group.len() > 1 {
                let inside = here
                    .iter()
                    .filter(|a| group.contains(&a.from.as_str()) && group.contains(&a.to.as_str()))
                    .map(|a| format!("{} -> {} ({})", a.from, a.to, a.at))
                    .collect();
                out.push((
                    folder.clone(),
                    group.iter().map(|s| s.to_string()).collect(),
                    inside,
                ));
            }
        }
    }
    out
}

/// The folder of module `module` in the crate rooted at `root` (`engine/src/lib.rs`,
/// `["sample"]` -> `engine/src/sample`), as the circles are named.
fn folder_name(krate: &CrateFacts, root: &str, module: &[String]) -> String {
    let file = krate
        .modules
        .iter()
        .find(|(m, _, _)| m == module)
        .map(|(_, f, _)| f.as_str())
        .unwrap_or(root);
    if let Some((file, inline)) = file.split_once("::") {
        return format!("{file}::{inline}");
    }
    let p = Path::new(file);
    if let Some("mod.rs" | "lib.rs" | "main.rs") = p.file_name().and_then(|n| n.to_str()) {
        return p
            .parent()
            .map(|d| d.to_string_lossy().into_owned())
            .unwrap_or_default();
    }
    file.trim_end_matches(".rs").to_string()
}

/// Every import circle in `files`, one line each: `folder: {a, b}: a -> b (file:line), ...`,
/// with the folder and sorted modules apart for matching against [`KNOWN_CIRCLES`].
fn find_circles(
    files: &[(String, String)],
    with_tests: bool,
) -> Vec<(String, Vec<String>, String)> {
    let mut out = Vec::new();
    for (root, krate) in read_crates(files, with_tests) {
        for (folder, group, arrows) in circles(&krate) {
            let name = folder_name(&krate, &root, &folder);
            let line = format!("{name}: {{{}}}: {}", group.join(", "), arrows.join(", "));
            out.push((name, group, line));
        }
    }
    out.sort();
    out
}

/// Every source file of [`SOURCE_DIRS`] as `(path relative to the workspace, source)`.
fn workspace_sources() -> Vec<(String, String)> {
    let root = root();
    SOURCE_DIRS
        .iter()
        .flat_map(|dir| rust_files(&root.join(dir)))
        .map(|path| {
            let relative = path.strip_prefix(&root).unwrap_or(&path);
            let shown = relative.to_string_lossy().replace('\\', "/");
            let source =
                std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {shown}: {e}"));
            (shown, source)
        })
        .collect()
}

/// Sources of a small crate for the checker's own tests.
fn planted(files: &[(&str, &str)]) -> Vec<(String, String)> {
    files
        .iter()
        .map(|(p, s)| (p.to_string(), s.to_string()))
        .collect()
}

#[test]
fn the_circle_finder_sees_a_planted_circle_through_a_re_export() {
    // `x` uses `y` through the parent's re-export `Why`; `y` uses `x` by a path in code.
    let circle = planted(&[
        ("c/src/lib.rs", "pub mod a;\nmod top;\n"),
        (
            "c/src/a/mod.rs",
            "mod x;\nmod y;\nmod z;\npub use self::y::Why;\n",
        ),
        (
            "c/src/a/x.rs",
            "//! Uses `Why`.\nuse super::Why;\npub fn f() -> Why { Why }\n",
        ),
        (
            "c/src/a/y.rs",
            "pub struct Why;\nfn g() { let s = \"super::z::h\"; super::x::f(); }\n",
        ),
        ("c/src/a/z.rs", "pub fn h() { crate::top::t(); }\n"),
        ("c/src/top.rs", "pub fn t() {}\n"),
    ]);
    let found = find_circles(&circle, false);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, "c/src/a");
    assert_eq!(found[0].1, ["x", "y"]);
    assert!(
        found[0].2.contains("x -> y (c/src/a/x.rs:2)"),
        "{}",
        found[0].2
    );
    assert!(
        found[0].2.contains("y -> x (c/src/a/y.rs:2)"),
        "{}",
        found[0].2
    );

    // The same folder with `y` no longer calling back: a chain, not a circle. A test
    // module's use of a sibling counts only when tests are read.
    let chain = planted(&[
        ("c/src/lib.rs", "pub mod a;\n"),
        (
            "c/src/a/mod.rs",
            "mod x;\nmod y;\npub(crate) use y::{self as why_mod, Why};\n",
        ),
        (
            "c/src/a/x.rs",
            "use super::Why;\npub fn f() -> Why { Why }\n",
        ),
        (
            "c/src/a/y.rs",
            "pub struct Why;\n#[cfg(test)]\n#[path = \"y_tests.rs\"]\nmod tests;\n#[cfg(test)]\nmod inline { use crate::a::x::f; }\n",
        ),
        ("c/src/a/y_tests.rs", "fn t() { super::super::x::f(); }\n"),
    ]);
    assert!(find_circles(&chain, false).is_empty());
    let with_tests = find_circles(&chain, true);
    assert_eq!(with_tests.len(), 1, "{with_tests:?}");
    assert!(
        with_tests[0].2.contains("y -> x (c/src/a/y.rs:6)"),
        "{}",
        with_tests[0].2
    );
}

#[test]
fn the_circle_finder_follows_globs_and_inline_modules() {
    let files = planted(&[
        (
            "c/src/main.rs",
            "mod outer {\n    pub mod p { pub fn f() { super::q::g(); } }\n    pub mod q { pub fn g() {} pub fn h() { super::p::f(); } }\n}\nmod g;\n",
        ),
        (
            "c/src/g/mod.rs",
            "mod items;\nmod user;\npub use items::*;\n",
        ),
        (
            "c/src/g/items.rs",
            "pub struct Thing;\npub fn make() -> Thing { super::user::made() }\n",
        ),
        (
            "c/src/g/user.rs",
            "pub fn made() -> super::Thing { super::Thing }\n",
        ),
    ]);
    let found: Vec<String> = find_circles(&files, false)
        .into_iter()
        .map(|c| c.2)
        .collect();
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(
        found[1].starts_with("c/src/main.rs::outer: {p, q}"),
        "{found:?}"
    );
    assert!(found[0].starts_with("c/src/g: {items, user}"), "{found:?}");
}

/// No two modules of a folder use each other, directly or around a longer circle, in
/// `engine/src`, `systems/src` and `bench/`: what two siblings both need goes down a
/// level (a module of its own below both, or the parent). A sibling is used when a
/// module's code (its child modules included) names a path into it: `use super::x`,
/// `super::x::f()` in code, `crate::folder::x::...`, or `super::X` where the parent's
/// `mod.rs` re-exports `X` from `x` (`use` re-exports, globs included, are followed to
/// the module that defines the item). Paths in comments and strings do not count.
///
/// Test code (`#[cfg(test)]` items and the test files they declare) is left out: a
/// module's tests may borrow a sibling's fixtures without the modules themselves
/// depending on each other, so the rule is for the code that ships.
#[test]
fn no_folder_has_an_import_circle() {
    let found = find_circles(&workspace_sources(), false);
    let known = |c: &(String, Vec<String>, String)| {
        KNOWN_CIRCLES
            .iter()
            .any(|(folder, group)| c.0 == *folder && c.1 == *group)
    };
    let new: Vec<&str> = found
        .iter()
        .filter(|c| !known(c))
        .map(|c| c.2.as_str())
        .collect();
    assert!(
        new.is_empty(),
        "import circles inside folders (move what both modules need down a level):\n{}",
        new.join("\n")
    );
    let gone: Vec<String> = KNOWN_CIRCLES
        .iter()
        .filter(|(folder, group)| !found.iter().any(|c| c.0 == *folder && c.1 == *group))
        .map(|(folder, group)| format!("{folder}: {group:?}"))
        .collect();
    assert!(
        gone.is_empty(),
        "circles in KNOWN_CIRCLES that are gone (remove them): {gone:?}"
    );
}

/// Every circle, printed (`cargo test ... list_circles -- --ignored --nocapture`).
#[test]
#[ignore = "a report, not a check"]
fn list_circles() {
    for with_tests in [false, true] {
        println!("with tests: {with_tests}");
        for c in find_circles(&workspace_sources(), with_tests) {
            println!("  {}", c.2);
        }
    }
}
