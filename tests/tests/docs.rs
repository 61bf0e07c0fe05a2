//! The user docs cannot drift from the tool: every `strata` command shown in a ```` ```sh ````
//! block of `README.md` and `docs/*.md` is run, and every ```` ```ron ```` block is parsed
//! as a scene.
//!
//! Input: the Markdown files. Output: one failure line per command that no longer runs
//! or block that no longer parses (file and line), all reported together.
//!
//! Commands are recognised as lines (joined over trailing `\`) that start with `strata `
//! or `cargo run --release -- `; other lines of a block (`cargo test`, `apt-get`, ...)
//! are not run. They run in process through the same [`strata_systems::cli::run`] the
//! binary calls, like the other CLI tests, made small: `--count`/`-n` and
//! `--lod-shown` at most [`SMALL_COUNT`], `--frames` at most 2, `--repeat` and `--runs`
//! 1, images [`SMALL_WIDTH`] pixels wide, `watch` stops after its first update, and
//! every output (`--out`, `-o`, `--report`, `--atlas`, `--json`) goes into a temporary
//! folder. Inputs that exist relative to the workspace (`configs/...`) are made
//! absolute, and an input an earlier command wrote (`-o torus.ply`, then
//! `strata analyze torus.ply`) is read from the temporary folder. A line whose comment
//! says `# not run` is skipped, and a redirection (`> scene.ron`) is dropped, the output
//! going to the test's own: the docs mark so only the
//! commands that need a window (`strata view`). `render` needs a GPU adapter (a
//! software one will do); without one it is skipped with a note, unless
//! `STRATA_REQUIRE_GPU=1`.
//!
//! A ```` ```ron ```` block that starts with `(` is a whole scene; one that starts with a
//! key (`field: Designed(...)`) is that section of a scene, parsed inside a scene with a
//! small built-in plane as its mesh.
//!
//! Further checks: every relative link of those files points at a file that exists;
//! the CLI reference names every option clap defines; and every decimal number in the
//! README's prose occurs in the benchmark report (`bench/README.md`) or the paper's
//! experiments (`bench/RESULTS.md`), so measured numbers are not typed twice.
//!
//! Cost: one preprocessing per command (the bunny's designed field dominates); about a
//! minute in release on 2 cores.

use std::path::{Path, PathBuf};

use clap::Parser;
use strata_systems::cli::{Cli, one_line, run};
use strata_systems::config::SceneConfig;

/// The largest sample count a documented command runs with.
const SMALL_COUNT: u64 = 400;
/// The image width documented renders run at (height follows at 3:4).
const SMALL_WIDTH: u32 = 96;
/// The marker that skips a command (one that needs a window).
const NOT_RUN: &str = "# not run";

/// The workspace root (the folder above `tests/`).
fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from(".."), Path::to_path_buf)
}

/// The user docs: `README.md` and every `docs/*.md`.
fn doc_files() -> Vec<PathBuf> {
    let root = workspace();
    let mut files = vec![root.join("README.md")];
    let mut guides: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/ exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    guides.sort();
    files.extend(guides);
    files
}

/// A fenced code block: its language, the 1-based line of its first body line, its body.
struct Block {
    lang: String,
    line: usize,
    body: Vec<String>,
}

/// The fenced code blocks of a Markdown text.
fn blocks(text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut open: Option<Block> = None;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        match (&mut open, trimmed.strip_prefix("```")) {
            (None, Some(lang)) => {
                open = Some(Block {
                    lang: lang.trim().to_owned(),
                    line: i + 2,
                    body: Vec::new(),
                });
            }
            (Some(_), Some(_)) => out.extend(open.take()),
            (Some(block), None) => block.body.push(line.to_owned()),
            (None, None) => {}
        }
    }
    out
}

/// The commands of a `sh` block: (1-based line, the words after `strata`), skipping
/// lines marked [`NOT_RUN`]. Comments after ` # ` are dropped.
fn commands(block: &Block) -> Vec<(usize, Vec<String>)> {
    let mut out = Vec::new();
    let mut joined = String::new();
    let mut start = block.line;
    for (i, line) in block.body.iter().enumerate() {
        if joined.is_empty() {
            start = block.line + i;
        }
        let line = line.trim();
        if let Some(head) = line.strip_suffix('\\') {
            joined.push_str(head);
            joined.push(' ');
            continue;
        }
        joined.push_str(line);
        let full = std::mem::take(&mut joined);
        if full.contains(NOT_RUN) {
            continue;
        }
        // A comment after ` # ` is dropped, and so is a redirection of standard output
        // (`strata scene mesh.obj > scene.ron` prints to the test's output instead).
        let code = full.split(" # ").next().unwrap_or_default();
        let code = code.split(" > ").next().unwrap_or_default().trim();
        let rest = code
            .strip_prefix("strata ")
            .or_else(|| code.strip_prefix("cargo run --release -- "));
        if let Some(rest) = rest {
            let words = shlex::split(rest).unwrap_or_else(|| vec![rest.to_owned()]);
            out.push((start, words));
        }
    }
    out
}

/// Whether an option takes the next word as its value and that value is an output path.
fn is_output_option(word: &str) -> bool {
    matches!(word, "-o" | "--out" | "--report" | "--atlas" | "--json")
}

/// A documented command made small and pointed at `tmp` (see the module header).
fn shrink(words: &[String], tmp: &Path) -> Vec<String> {
    let root = workspace();
    let command = words.first().map_or("", String::as_str);
    let mut out = vec!["strata".to_owned()];
    let mut i = 0;
    while i < words.len() {
        let word = &words[i];
        let value = words.get(i + 1);
        let small = |limit: u64| {
            let v = value.and_then(|v| v.parse::<u64>().ok()).unwrap_or(limit);
            v.min(limit).to_string()
        };
        let rewritten = match word.as_str() {
            "-n" | "--count" | "--lod-shown" => Some(small(SMALL_COUNT)),
            "--frames" if command == "render" => Some(small(2)),
            "--repeat" | "--runs" => Some("1".to_owned()),
            "--width" => Some(SMALL_WIDTH.to_string()),
            "--height" => Some((SMALL_WIDTH * 3 / 4).to_string()),
            w if is_output_option(w) => value.map(|v| {
                let name = Path::new(v)
                    .file_name()
                    .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
                tmp.join(name).to_string_lossy().into_owned()
            }),
            _ => None,
        };
        out.push(word.clone());
        if let Some(v) = rewritten {
            out.push(v);
            i += 2;
            continue;
        }
        if i > 0 && !word.starts_with('-') {
            // An input: a project file (`configs/...`), or one an earlier command of
            // the docs wrote into the temporary folder.
            let earlier = Path::new(word).file_name().map(|n| tmp.join(n));
            let input = Some(root.join(word))
                .filter(|p| p.exists())
                .or(earlier.filter(|p| p.exists()));
            if let (Some(input), Some(last)) = (input, out.last_mut()) {
                *last = input.to_string_lossy().into_owned();
            }
        }
        i += 1;
    }
    let has = |flag: &str| words.iter().any(|w| w == flag);
    let scene_input = words.get(1).is_some_and(|w| w.ends_with(".ron"));
    let counted = scene_input && matches!(command, "sample" | "bench" | "analyze" | "render");
    if counted && !has("-n") && !has("--count") {
        out.extend(["--count".to_owned(), SMALL_COUNT.to_string()]);
    }
    if command == "render" && !has("--width") {
        out.extend(["--width".to_owned(), SMALL_WIDTH.to_string()]);
        out.extend(["--height".to_owned(), (SMALL_WIDTH * 3 / 4).to_string()]);
    }
    if command == "watch" && !has("--updates") {
        out.extend(["--updates".to_owned(), "1".to_owned()]);
    }
    if command == "analyze" && !has("--out") && !has("-o") {
        out.extend([
            "--out".to_owned(),
            tmp.join("analysis").to_string_lossy().into_owned(),
        ]);
    }
    out
}

/// Whether an error says that no GPU adapter could be opened.
fn no_adapter(message: &str) -> bool {
    message.contains("no GPU adapter") || message.contains("opening a GPU")
}

/// Runs one documented command; `Err` with the one-line error when it fails.
fn run_command(words: &[String], tmp: &Path) -> Result<(), String> {
    let argv = shrink(words, tmp);
    let cli = Cli::try_parse_from(&argv).map_err(|e| format!("{argv:?}: {e}"))?;
    match run(cli) {
        Ok(()) => Ok(()),
        Err(e) => {
            let message = one_line(&e);
            let require_gpu = std::env::var("STRATA_REQUIRE_GPU").as_deref() == Ok("1");
            if words.first().is_some_and(|c| c == "render") && no_adapter(&message) && !require_gpu
            {
                eprintln!("skipping {argv:?}: {message}");
                return Ok(());
            }
            Err(format!("{argv:?}: {message}"))
        }
    }
}

/// Parses a `ron` block as a scene, or as the section of one it is.
fn parse_ron(body: &str, name: &Path) -> Result<(), String> {
    let text = body.trim();
    let scene = if text.starts_with('(') {
        text.to_owned()
    } else if text.starts_with("mesh:") {
        format!("({text})")
    } else {
        format!("(mesh: Shape(Plane(size: 1.0, resolution: 4)), {text})")
    };
    SceneConfig::from_ron(&scene, name)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// Every failure of one Markdown text (`name` for messages): commands that do not run
/// and `ron` blocks that do not parse, each as `name:line: what`.
fn check_markdown(text: &str, name: &Path, tmp: &Path) -> Vec<String> {
    let mut failures = Vec::new();
    for block in blocks(text) {
        match block.lang.as_str() {
            "sh" => {
                for (line, words) in commands(&block) {
                    if let Err(e) = run_command(&words, tmp) {
                        failures.push(format!("{}:{line}: {e}", name.display()));
                    }
                }
            }
            "ron" => {
                if let Err(e) = parse_ron(&block.body.join("\n"), name) {
                    failures.push(format!("{}:{}: {e}", name.display(), block.line));
                }
            }
            _ => {}
        }
    }
    failures
}

/// Every command in the README and the guides runs, and every RON block parses.
#[test]
fn every_documented_command_runs_and_every_scene_parses() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mut failures = Vec::new();
    let mut commands_seen = 0;
    for file in doc_files() {
        let text = std::fs::read_to_string(&file).expect("readable doc");
        commands_seen += blocks(&text)
            .iter()
            .filter(|b| b.lang == "sh")
            .map(|b| commands(b).len())
            .sum::<usize>();
        let name = file
            .strip_prefix(workspace())
            .unwrap_or(&file)
            .to_path_buf();
        failures.extend(check_markdown(&text, &name, tmp.path()));
    }
    assert!(commands_seen > 10, "only {commands_seen} commands found");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The decimal numbers of a Markdown text's prose (fenced blocks, inline code and link
/// targets left out), each as written: `0.670`, `2.43`, `7.3.2`.
fn prose_numbers(text: &str) -> Vec<String> {
    let mut prose = String::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Inline code spans are the odd pieces between backticks.
        for (i, piece) in line.split('`').enumerate() {
            if i % 2 == 0 {
                prose.push_str(piece);
            }
        }
        prose.push('\n');
    }
    // Link targets (`](...)`) are addresses, not numbers.
    let mut text = String::new();
    let mut rest = prose.as_str();
    while let Some(at) = rest.find("](") {
        text.push_str(&rest[..at]);
        rest = rest[at..].find(')').map_or("", |end| &rest[at + end + 1..]);
    }
    text.push_str(rest);
    numbers(&text)
}

/// Every maximal run of digits and dots in `text` that holds a dot between digits and
/// does not continue a word (so `x86` or `v0.2` do not count).
fn numbers(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut run = String::new();
    let mut after_word = false;
    for c in text.chars().chain(std::iter::once(' ')) {
        if c.is_ascii_digit() || (c == '.' && !run.is_empty()) {
            run.push(c);
            continue;
        }
        let token = run.trim_end_matches('.');
        if !after_word && token.contains('.') {
            out.push(token.to_owned());
        }
        run.clear();
        after_word = c.is_alphanumeric() || c == '_';
    }
    out
}

/// The README quotes measured numbers from the benchmark report and the paper's
/// experiments, not typed twice: every decimal number of its prose occurs, as the
/// same token, in `bench/README.md` or `bench/RESULTS.md`.
#[test]
fn readme_numbers_come_from_the_benchmark_report() {
    let root = workspace();
    let read = |p: &str| std::fs::read_to_string(root.join(p)).expect("readable");
    let report = [read("bench/README.md"), read("bench/RESULTS.md")].concat();
    let known: std::collections::HashSet<String> = numbers(&report).into_iter().collect();
    let quoted = prose_numbers(&read("README.md"));
    assert!(quoted.len() >= 5, "only {quoted:?}");
    let missing: Vec<_> = quoted.iter().filter(|n| !known.contains(*n)).collect();
    assert!(
        missing.is_empty(),
        "README numbers not in the report: {missing:?}"
    );
}

/// Numbers are whole tokens: a number that is only part of a reported one, or sits in
/// code or a link, does not count.
#[test]
fn numbers_are_whole_tokens() {
    assert_eq!(
        numbers("0.26-0.41 s, 2.43. x86 v0.2 7.3.2"),
        ["0.26", "0.41", "2.43", "7.3.2"]
    );
    let prose = prose_numbers("a 1.5 `2.5` [b](c/3.5.md)\n```\n4.5\n```\n6.5");
    assert_eq!(prose, ["1.5", "6.5"]);
    assert!(!numbers("2.43").contains(&"2.4".to_owned()));
}

/// The CLI reference names every command and every long option that clap defines
/// in its own section of `docs/cli.md` (`render` and `view` share the camera and look
/// table, the commands that take a mesh share its section), so a new option cannot go
/// undocumented.
#[test]
fn the_cli_reference_lists_every_command_and_option() {
    use clap::CommandFactory;
    let reference = std::fs::read_to_string(workspace().join("docs/cli.md")).expect("cli.md");
    // The text from a heading to the next heading of level two.
    let section = |heading: &str| {
        reference.find(heading).map_or("", |at| {
            let rest = &reference[at + heading.len()..];
            &rest[..rest.find("\n## ").unwrap_or(rest.len())]
        })
    };
    let camera = section("### Camera and look options");
    let mesh_input = section("## A mesh as input");
    let mut missing = Vec::new();
    for command in Cli::command().get_subcommands() {
        let name = command.get_name();
        let own = section(&format!("## `strata {name}`"));
        if own.is_empty() {
            missing.push(format!("strata {name}"));
        }
        let text = format!("{own}{camera}{mesh_input}");
        for arg in command.get_arguments() {
            let documented = match (arg.get_long(), arg.get_short()) {
                (Some(long), _) => text.contains(&format!("`--{long}")),
                (None, Some(short)) => text.contains(&format!("`-{short}")),
                (None, None) => true, // a positional argument: the usage lines show it
            };
            if !documented && arg.get_id() != "help" {
                missing.push(format!("strata {name} --{}", arg.get_id()));
            }
        }
    }
    assert!(missing.is_empty(), "not in docs/cli.md: {missing:?}");
}

/// Guides that other work adds; a link to one is not checked until it exists.
const PENDING_GUIDES: [&str; 2] = ["docs/python.md", "docs/c-api.md"];

/// The relative link targets of a Markdown text (`](target)`, without `#anchor`), with
/// the 1-based line of each; web addresses and pure anchors are left out.
fn local_links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            rest = &rest[at + 2..];
            let target = &rest[..rest.find(')').unwrap_or(rest.len())];
            let path = target.split('#').next().unwrap_or_default();
            if !path.is_empty() && !path.contains("://") {
                out.push((i + 1, path.to_owned()));
            }
        }
    }
    out
}

/// Every relative link in the README and the guides points at a file that exists
/// (pictures included).
#[test]
fn every_local_link_points_at_a_file() {
    let root = workspace();
    let mut broken = Vec::new();
    for file in doc_files() {
        let text = std::fs::read_to_string(&file).expect("readable doc");
        let folder = file.parent().unwrap_or(&root);
        for (line, target) in local_links(&text) {
            let path = folder.join(&target);
            let pending = PENDING_GUIDES.iter().any(|g| path.ends_with(g));
            if !path.exists() && !pending {
                broken.push(format!("{}:{line}: {target}", file.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
    let found = local_links("[a](docs/x.md#y) ![p](p.png) [w](https://e.org) [z](#top)");
    assert_eq!(
        found,
        [(1, "docs/x.md".to_owned()), (1, "p.png".to_owned())]
    );
}

/// A planted broken command (a scene that does not exist, an option that does not)
/// and a broken scene block are reported with their lines; good ones are not.
#[test]
fn a_broken_command_or_scene_fails() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let text = "intro\n\n```sh\nstrata sample configs/no-such-scene.ron -n 10\n\
        strata sample configs/plane-isotropic.ron --no-such-flag\n\
        strata sample configs/plane-isotropic.ron -n 50000 -o samples.ply\n\
        cargo test --workspace --release\n\
        strata view configs/default.ron   # not run\n```\n\n\
        ```ron\nfield: Designed(guidance: Direction(0.0, 1.0, 0.0), weight: 10.0),\n```\n\n\
        ```ron\n(mesh: Shape(Plane(size: 1.0)), sampling: (cuont: 3))\n```\n";
    let failures = check_markdown(text, Path::new("planted.md"), tmp.path());
    assert_eq!(failures.len(), 3, "{failures:#?}");
    assert!(failures[0].starts_with("planted.md:4: "), "{}", failures[0]);
    assert!(failures[0].contains("no-such-scene.ron"), "{}", failures[0]);
    assert!(failures[1].starts_with("planted.md:5: "), "{}", failures[1]);
    assert!(failures[1].contains("--no-such-flag"), "{}", failures[1]);
    assert!(
        failures[2].starts_with("planted.md:16: "),
        "{}",
        failures[2]
    );
    assert!(failures[2].contains("cuont"), "{}", failures[2]);
    // The good command ran small, into the temporary folder.
    let written = strata_engine::io::read_samples_ply(&tmp.path().join("samples.ply"));
    assert_eq!(written.map(|s| s.len()).ok(), Some(SMALL_COUNT as usize));
}

/// Commands are joined over `\`, `cargo run --release --` counts as `strata`, and
/// outputs, counts and image sizes are rewritten.
#[test]
fn commands_are_extracted_and_shrunk() {
    let block = &blocks(
        "```sh\ncargo run --release -- render configs/default.ron --out docs/x.png \\\n    \
         --width 1024 -n 6000 --frames 20\nstrata watch configs/watch-example.ron\n```\n",
    )[0];
    let found = commands(block);
    assert_eq!(found.len(), 2);
    assert_eq!(found[0].0, 2);
    let tmp = Path::new("/tmp/t");
    let argv = shrink(&found[0].1, tmp);
    let config = workspace().join("configs/default.ron");
    let expected = [
        "strata",
        "render",
        config.to_str().expect("utf-8"),
        "--out",
        "/tmp/t/x.png",
        "--width",
        "96",
        "-n",
        "400",
        "--frames",
        "2",
    ];
    assert_eq!(argv, expected);
    let watch = shrink(&found[1].1, tmp);
    assert_eq!(watch[watch.len() - 2..], ["--updates", "1"]);
}
