//! The layout rules of `ARCHITECTURE.md` that a test can hold: no source file over 700
//! lines of non-test code, and no global mutable state in the engine.

use std::path::{Path, PathBuf};

/// Largest number of non-test lines in one source file of `engine/src`, `systems/src`
/// and `bench/src`.
const MAX_LINES: usize = 700;

/// The workspace root (the parent of this crate's folder).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate lives in the workspace root")
        .to_path_buf()
}

/// Every `.rs` file under `dir`, sorted.
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
                stack.push(p);
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
    for dir in ["engine/src", "systems/src", "bench/src"] {
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
