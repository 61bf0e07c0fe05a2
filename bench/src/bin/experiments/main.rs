//! The paper's section 7 experiments, measured with strata's own analysis tools, beside
//! baselines: writes `bench/results/*.json` and `*.png` and `bench/RESULTS.md`.
//!
//! `cargo run --release -p strata-bench --bin experiments [-- --quick] [--out DIR]`
//!
//! `--quick` uses fewer sample counts and realizations (a smoke run, about a minute);
//! the committed results are from the full run. Plots need a TrueType font (see
//! `strata_systems::report::plot`); without one the numbers are still written.
//!
//! One module per section of the paper, each returning a [`table::Section`]:
//! [`strokes`] (7.1), [`discrepancy`] (7.2), [`alignment`] (7.3.1), [`boundary`] (7.3.2),
//! [`quantization`] (7.3.3), [`spectrum`] (7.4), [`dda`] (7.5); the samplers and
//! domains they share are in [`samplers`], the output folder in [`output`], and the
//! markdown writer in [`table`]. The measures themselves are in
//! `strata_engine::analysis`.

mod alignment;
mod boundary;
mod dda;
mod discrepancy;
mod output;
mod progressive;
mod quantization;
mod samplers;
mod spectrum;
mod strokes;
mod table;

use std::path::PathBuf;
use std::time::Instant;

use output::Ctx;
use table::Section;

/// The error of every experiment step.
type BoxError = Box<dyn std::error::Error + Send + Sync>;

/// One experiment: the paper's section number and the function that runs it.
type Experiment = (&'static str, fn(&mut Ctx) -> Result<Section, BoxError>);

/// Every experiment, in the order of the paper (and of `RESULTS.md`).
const EXPERIMENTS: [Experiment; 8] = [
    ("7.1", strokes::section_7_1),
    ("7.2", discrepancy::section_7_2),
    ("7.3.1", alignment::section_7_3_1),
    ("7.3.2", boundary::section_7_3_2),
    ("7.3.3", quantization::section_7_3_3),
    ("7.4", spectrum::section_7_4),
    ("7.5", dda::section_7_5),
    ("progressive", progressive::section_progressive),
];

fn main() -> Result<(), BoxError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("results"));
    std::fs::create_dir_all(&out)?;
    let mut ctx = Ctx {
        out: out.clone(),
        quick,
        plot_errors: Vec::new(),
    };
    let t0 = Instant::now();
    let mut sections = Vec::new();
    for (name, run) in EXPERIMENTS {
        let t = Instant::now();
        let s = run(&mut ctx)?;
        eprintln!("{name}: {:.1} s", t.elapsed().as_secs_f64());
        sections.push(s);
    }
    let md = table::render(
        &sections,
        quick,
        t0.elapsed().as_secs_f64(),
        &ctx.plot_errors,
    );
    let md_path = if out == root.join("results") {
        root.join("RESULTS.md")
    } else {
        out.join("RESULTS.md")
    };
    strata_engine::io::write_atomically(&md_path, |w| std::io::Write::write_all(w, md.as_bytes()))?;
    eprintln!("wrote {} and {}", md_path.display(), out.display());
    for e in &ctx.plot_errors {
        eprintln!("plot skipped: {e}");
    }
    Ok(())
}
