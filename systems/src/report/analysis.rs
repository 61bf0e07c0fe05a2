//! `strata analyze`: quality measures of a scene's samples (or of a sample file) as
//! JSON numbers and PNG plots.
//!
//! - Every input: differential domain analysis (`dda.json`, `dda_rapsd.png`,
//!   `dda_anisotropy.png`, `dda_spectrum.png`), which works on surfaces and for
//!   non-uniform and anisotropic fields.
//! - Flat inputs (all samples in one `z = const` plane), mapped to the unit square by
//!   their domain's bounding box: discrepancy over rectangles, origin triangles and
//!   quarter discs (sup and L2; for a scene, a curve over N = 2^l and 2^l + 2^(l-1)
//!   with fitted slopes), periodogram, RAPSD and anisotropy (`planar.json`,
//!   `discrepancy_*.png`, `rapsd.png`, `anisotropy.png`, `periodogram.png`). These
//!   measures assume a uniform density in that frame: for a constant anisotropic field
//!   axis-aligned with the domain they are the measures in the field's metric.
//! - `--alignment` on a flat scene: the per-face angle between the field and the
//!   parameter axes after the surface pipeline's segmentation (`alignment.json`,
//!   `alignment.png`).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use glam::DVec2;
use strata_engine::analysis::dda::{DdaOptions, dda};
use strata_engine::analysis::spectrum::periodogram;
use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, ShapeFamily, alignment};
use strata_engine::sample::Sample;
use strata_engine::surface::{Preprocessed, SurfaceOptions};

use crate::config::SceneConfig;
use crate::plot::{self, Axes, Series};
use crate::scene::Scene;

/// Arguments of `strata analyze`.
#[derive(Debug, clap::Args)]
pub struct AnalyzeArgs {
    /// Scene file (`.ron`) to sample, or a sample file (`.ply`, as `strata sample`
    /// writes) to analyse as it is.
    pub input: PathBuf,
    /// Output folder for the JSON and PNG files (created if missing).
    #[arg(long, short = 'o', default_value = "analysis")]
    pub out: PathBuf,
    /// Samples per realization (scene only; overrides `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Realizations to average (scene only): seeds `seed, seed + 1, ...`.
    #[arg(long, default_value_t = 4)]
    pub runs: u64,
    /// First seed (scene only; overrides `sampling.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// DDA kernel support in expected spacings (the paper's epsilon).
    #[arg(long, default_value_t = 10.0)]
    pub epsilon: f64,
    /// Write only the JSON numbers, no PNG plots.
    #[arg(long)]
    pub no_plots: bool,
    /// Also map the angle between the field and the parameter axes (flat scenes).
    #[arg(long)]
    pub alignment: bool,
}

/// Draws one plot into the given file.
type DrawFn<'a> = dyn Fn(&Path) -> Result<(), plot::PlotError> + 'a;

/// What was analysed.
struct Input {
    sets: Vec<Vec<Sample>>,
    /// A scene to draw more counts from (discrepancy curves), with its first seed.
    scene: Option<(Scene, u64)>,
    config: Option<SceneConfig>,
}

/// Runs `strata analyze`.
pub fn analyze(args: &AnalyzeArgs) -> anyhow::Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let input = load(args)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut written: Vec<PathBuf> = Vec::new();
    let mut plot_errors: Vec<String> = Vec::new();
    let mut plot_to = |name: &str, f: &DrawFn| {
        if args.no_plots {
            return;
        }
        let path = args.out.join(name);
        match f(&path) {
            Ok(()) => written.push(path),
            Err(e) => plot_errors.push(e.to_string()),
        }
    };
    let n = input.sets[0].len();
    // Differential domain analysis: every input.
    let options = DdaOptions {
        epsilon: args.epsilon,
        ..Default::default()
    };
    let spectrum = dda(&input.sets, &options).context("differential domain analysis")?;
    let radial = spectrum.radial();
    write_json(
        &args.out.join("dda.json"),
        &serde_json::json!({
            "samples": n, "realizations": input.sets.len(), "options": options_json(&options),
            "frequency": radial.frequency, "rapsd": radial.rapsd,
            "anisotropy_db": radial.anisotropy_db,
        }),
    )?;
    let extent = spectrum.half_size as f64 * spectrum.frequency_step;
    plot_to("dda_rapsd.png", &|p| {
        plot::line_chart(
            p,
            &Axes {
                title: format!("DDA radial mean, {n} samples x {}", input.sets.len()),
                x_label: "frequency (local spacings^-1)".into(),
                y_label: "power".into(),
                y_range: Some((0.0, 2.2)),
                reference: vec![(1.0, "white noise".into())],
                ..Default::default()
            },
            &[Series::line(
                "DDA",
                radial.frequency.clone(),
                radial.rapsd.clone(),
            )],
        )
    });
    plot_to("dda_anisotropy.png", &|p| {
        plot::line_chart(
            p,
            &Axes {
                title: "DDA anisotropy".into(),
                x_label: "frequency (local spacings^-1)".into(),
                y_label: "dB".into(),
                ..Default::default()
            },
            &[Series::line(
                "DDA",
                radial.frequency.clone(),
                radial.anisotropy_db.clone(),
            )],
        )
    });
    plot_to("dda_spectrum.png", &|p| {
        plot::spectrum_image(
            p,
            "DDA spectrum",
            &spectrum.power,
            spectrum.side(),
            extent,
            2.0,
        )
    });

    // Planar measures.
    if let Some(frame) = planar_frame(&input) {
        let unit: Vec<Vec<DVec2>> = input.sets.iter().map(|s| frame.map(s)).collect();
        let families = [
            (ShapeFamily::Rectangles, "rectangles"),
            (ShapeFamily::OriginTriangles, "triangles"),
            (ShapeFamily::QuarterDiscs, "quarter_discs"),
        ];
        let mut disc = serde_json::Map::new();
        for (family, name) in families {
            let d = Discrepancy::new(family);
            let sup = unit.iter().map(|p| d.sup(p)).sum::<f64>() / unit.len() as f64;
            let l2 = unit.iter().map(|p| d.l2(p)).sum::<f64>() / unit.len() as f64;
            let mut entry = serde_json::json!({"n": n, "sup": sup, "l2": l2});
            if let Some((scene, seed)) = &input.scene {
                let ns: Vec<usize> = (6..=13)
                    .flat_map(|l| [1usize << l, (1 << l) + (1 << (l - 1))])
                    .filter(|&k| k <= n.clamp(64, 8192))
                    .collect();
                let seeds: Vec<u64> = (0..args.runs).map(|k| seed + k).collect();
                if ns.len() >= 2 {
                    let curve = DiscrepancyCurve::measure(
                        &d,
                        |k, s| frame.map(&scene.sampler.sample(k, s)),
                        &ns,
                        &seeds,
                    )?;
                    entry["curve"] = serde_json::json!({"n": curve.ns, "sup": curve.sup,
                        "l2": curve.l2, "sup_slope": curve.sup_slope(), "l2_slope": curve.l2_slope()});
                    plot_to(&format!("discrepancy_{name}.png"), &|p| {
                        plot::line_chart(
                            p,
                            &Axes {
                                title: format!("discrepancy, {}", name.replace('_', " ")),
                                x_label: "log10 N".into(),
                                y_label: "log10 discrepancy".into(),
                                log_x: true,
                                log_y: true,
                                ..Default::default()
                            },
                            &[
                                Series::line(
                                    format!("sup (slope {:.3})", curve.sup_slope()),
                                    curve.ns_f64(),
                                    curve.sup.clone(),
                                )
                                .with_markers(),
                                Series::line(
                                    format!("L2 (slope {:.3})", curve.l2_slope()),
                                    curve.ns_f64(),
                                    curve.l2.clone(),
                                )
                                .with_markers(),
                            ],
                        )
                    });
                }
            }
            disc.insert(name.to_string(), entry);
        }
        let spec = periodogram(&unit, 2.5).context("periodogram")?;
        let r = spec.radial();
        write_json(
            &args.out.join("planar.json"),
            &serde_json::json!({
                "domain_lo": [frame.lo.x, frame.lo.y], "domain_size": [frame.size.x, frame.size.y],
                "discrepancy": disc,
                "spectrum": {"frequency": r.frequency, "rapsd": r.rapsd, "anisotropy_db": r.anisotropy_db,
                    "low_frequency_energy": r.mean_below(0.5), "peak": r.peak().1,
                    "peak_frequency": r.peak().0, "noise_floor_db": spec.noise_floor_db()},
            }),
        )?;
        plot_to("rapsd.png", &|p| {
            plot::line_chart(
                p,
                &Axes {
                    title: format!("RAPSD, {n} points x {}", unit.len()),
                    x_label: "frequency / sqrt(N)".into(),
                    y_label: "power".into(),
                    y_range: Some((0.0, 2.2)),
                    reference: vec![(1.0, "white noise".into())],
                    ..Default::default()
                },
                &[Series::line("RAPSD", r.frequency.clone(), r.rapsd.clone())],
            )
        });
        plot_to("anisotropy.png", &|p| {
            plot::line_chart(
                p,
                &Axes {
                    title: "anisotropy".into(),
                    x_label: "frequency / sqrt(N)".into(),
                    y_label: "dB".into(),
                    reference: vec![(spec.noise_floor_db(), "noise floor".into())],
                    ..Default::default()
                },
                &[Series::line(
                    "anisotropy",
                    r.frequency.clone(),
                    r.anisotropy_db.clone(),
                )],
            )
        });
        let k = spec.half_size as f64 / (n as f64).sqrt();
        plot_to("periodogram.png", &|p| {
            plot::spectrum_image(p, "mean periodogram", &spec.power, spec.side(), k, 2.0)
        });
        plot_to("points.png", &|p| {
            plot::points(p, "samples (unit-square frame)", &unit[0], DVec2::ONE)
        });
        if args.alignment {
            alignment_map(args, &input, &mut plot_to)?;
        }
    } else if args.alignment {
        bail!("--alignment needs a flat scene (the map is drawn in the plane)");
    }
    write_json(
        &args.out.join("summary.json"),
        &serde_json::json!({"input": args.input, "samples": n, "realizations": input.sets.len()}),
    )?;
    println!(
        "analysed {} x {n} samples: wrote JSON{} to {}",
        input.sets.len(),
        if args.no_plots { "" } else { " and PNG" },
        args.out.display()
    );
    for e in plot_errors.iter().take(1) {
        eprintln!("warning: plots skipped: {e}");
    }
    Ok(())
}

fn load(args: &AnalyzeArgs) -> anyhow::Result<Input> {
    let ext = args
        .input
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("ply") => {
            let samples = strata_engine::io::read_samples_ply(&args.input)
                .with_context(|| args.input.display().to_string())?;
            if samples.is_empty() {
                bail!("{}: no samples", args.input.display());
            }
            Ok(Input {
                sets: vec![samples],
                scene: None,
                config: None,
            })
        }
        Some("ron") => {
            let config = SceneConfig::load(&args.input)?;
            let scene = Scene::build(&config).with_context(|| args.input.display().to_string())?;
            let count = args.count.unwrap_or(config.sampling.count);
            let count = usize::try_from(count).context("sample count does not fit in memory")?;
            if count == 0 {
                bail!("sample count must be at least 1");
            }
            let seed = args.seed.unwrap_or(config.sampling.seed);
            let sets = (0..args.runs)
                .map(|k| scene.sampler.sample(count, seed + k))
                .collect();
            Ok(Input {
                sets,
                scene: Some((scene, seed)),
                config: Some(config),
            })
        }
        _ => bail!(
            "{}: expected a scene (.ron) or a sample file (.ply)",
            args.input.display()
        ),
    }
}

/// The affine frame of a flat input: `q = (p - lo) / size` per axis.
#[derive(Clone, Copy, Debug)]
struct Frame {
    lo: DVec2,
    size: DVec2,
}

impl Frame {
    fn map(&self, samples: &[Sample]) -> Vec<DVec2> {
        samples
            .iter()
            .map(|s| {
                ((DVec2::new(s.position[0] as f64, s.position[1] as f64) - self.lo) / self.size)
                    .clamp(DVec2::ZERO, DVec2::ONE)
            })
            .collect()
    }
}

/// The frame of the domain if every sample lies in one `z = const` plane: the scene's
/// mesh bounds, or the samples' bounds for a sample file.
fn planar_frame(input: &Input) -> Option<Frame> {
    let z0 = input.sets[0][0].position[2];
    let flat = input
        .sets
        .iter()
        .flatten()
        .all(|s| (s.position[2] - z0).abs() <= 1e-6 * (1.0 + z0.abs()));
    if !flat {
        return None;
    }
    let (lo, hi) = match &input.scene {
        Some((scene, _)) => {
            let (lo, hi) = scene.mesh.bounds();
            (lo.truncate(), hi.truncate())
        }
        None => input.sets.iter().flatten().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), s| {
                let p = DVec2::new(s.position[0] as f64, s.position[1] as f64);
                (lo.min(p), hi.max(p))
            },
        ),
    };
    let size = hi - lo;
    (size.x > 0.0 && size.y > 0.0).then_some(Frame { lo, size })
}

fn alignment_map(
    args: &AnalyzeArgs,
    input: &Input,
    plot_to: &mut dyn FnMut(&str, &DrawFn),
) -> anyhow::Result<()> {
    let (Some((scene, _)), Some(config)) = (&input.scene, &input.config) else {
        bail!("--alignment needs a scene file");
    };
    let options = SurfaceOptions {
        segment: config.segment,
        param: config.param,
        curve: config.curve,
        ..Default::default()
    };
    let pre = Preprocessed::build(scene.mesh.clone(), scene.field.clone(), &options)
        .context("surface preprocessing for the alignment map")?;
    let angles = alignment::face_angles(&scene.mesh, &scene.field, &pre.params);
    let max = angles
        .iter()
        .copied()
        .filter(|a| a.is_finite())
        .fold(0.0, f64::max);
    write_json(
        &args.out.join("alignment.json"),
        &serde_json::json!({"segments": pre.params.len(), "max_angle_deg": max,
            "face_angle_deg": angles}),
    )?;
    let gamma = config.param.gamma.to_degrees();
    plot_to("alignment.png", &|p| {
        plot::face_map(
            p,
            &format!("angle to the u axis (max {max:.2} deg; red = gamma {gamma:.1})"),
            &scene.mesh,
            &angles,
            gamma,
        )
    });
    Ok(())
}

fn options_json(o: &DdaOptions) -> serde_json::Value {
    serde_json::json!({"epsilon": o.epsilon, "max_frequency": o.max_frequency,
        "frequency_step": o.frequency_step, "bins_per_spacing": o.bins_per_spacing,
        "min_normal_cos": o.min_normal_cos, "arc_tolerance": o.arc_tolerance})
}

fn write_json(path: &Path, value: &serde_json::Value) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}
