//! Quality measures of samples as JSON numbers and PNG plots (`strata analyze`).
//!
//! Input: an [`AnalysisInput`] (realizations of one sample count, and the scene they
//! were drawn from, if any) and [`AnalysisOptions`]. Output: files in a folder, and an
//! [`AnalysisSummary`].
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
//! - `alignment` on a flat scene: the per-face angle between the field and the
//!   parameter axes after the surface pipeline's segmentation (`alignment.json`,
//!   `alignment.png`).
//!
//! Cost: the DDA is O(realizations x samples x neighbours); the exact sup discrepancy
//! is quadratic in the count per realization (curves stop at 8192 samples).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use glam::DVec2;
use strata_engine::analysis::dda::{DdaOptions, dda};
use strata_engine::analysis::spectrum::periodogram;
use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, ShapeFamily, alignment};
use strata_engine::sample::Sample;
use strata_engine::surface::Preprocessed;

use super::plot::{self, Axes, Series};
use crate::config::SceneConfig;
use crate::scene::Scene;

/// Draws one plot into the given file.
type DrawFn<'a> = dyn Fn(&Path) -> Result<(), plot::PlotError> + 'a;

/// What to analyse.
pub struct AnalysisInput {
    /// Realizations, each the same non-zero number of samples; at least one.
    pub sets: Vec<Vec<Sample>>,
    /// The scene they were drawn from, if any: discrepancy curves draw more counts
    /// from it, and the alignment map preprocesses it.
    pub scene: Option<SampledScene>,
}

/// A scene and how its realizations were drawn.
pub struct SampledScene {
    /// The scene, preprocessed.
    pub scene: Scene,
    /// Its configuration.
    pub config: SceneConfig,
    /// The seed of the first realization; realization `k` used `first_seed + k`.
    pub first_seed: u64,
}

impl AnalysisInput {
    /// One realization read from a file (at least one sample).
    pub fn from_samples(samples: Vec<Sample>) -> Self {
        Self {
            sets: vec![samples],
            scene: None,
        }
    }

    /// `runs` realizations of `count` samples of `scene`, with seeds `first_seed`,
    /// `first_seed + 1`, ...
    pub fn from_scene(
        scene: Scene,
        config: SceneConfig,
        count: usize,
        first_seed: u64,
        runs: u64,
    ) -> Self {
        let sets = (0..runs)
            .map(|k| scene.sampler.sample(count, first_seed + k))
            .collect();
        Self {
            sets,
            scene: Some(SampledScene {
                scene,
                config,
                first_seed,
            }),
        }
    }
}

/// What to measure and draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalysisOptions {
    /// DDA kernel support in expected spacings (the paper's epsilon).
    pub epsilon: f64,
    /// Draw the PNG plots (the JSON numbers are always written).
    pub plots: bool,
    /// Also map the angle between the field and the parameter axes (flat scenes only).
    pub alignment: bool,
}

/// What [`write_analysis`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnalysisSummary {
    /// Realizations analysed.
    pub realizations: usize,
    /// Samples per realization.
    pub samples: usize,
    /// The plots written.
    pub plots: Vec<PathBuf>,
    /// Why plots were skipped (for example no font), one entry per failed plot.
    pub plot_errors: Vec<String>,
}

/// Measures `input` and writes the JSON files (and, with `options.plots`, the PNG
/// plots) into `out`, creating it if missing; `source` names the input in
/// `summary.json`. See the [module docs](self) for the files. A plot that fails is
/// reported in the summary, not as an error: the numbers never depend on plots. An
/// input without samples is an error.
pub fn write_analysis(
    input: &AnalysisInput,
    source: &Path,
    out: &Path,
    options: &AnalysisOptions,
) -> anyhow::Result<AnalysisSummary> {
    if input.sets.is_empty() || input.sets.iter().any(Vec::is_empty) {
        bail!("nothing to analyse: every realization needs at least one sample");
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut written: Vec<PathBuf> = Vec::new();
    let mut plot_errors: Vec<String> = Vec::new();
    let mut plot_to = |name: &str, f: &DrawFn| {
        if !options.plots {
            return;
        }
        let path = out.join(name);
        match f(&path) {
            Ok(()) => written.push(path),
            Err(e) => plot_errors.push(e.to_string()),
        }
    };
    let n = input.sets[0].len();
    write_dda(input, options, out, &mut plot_to)?;
    if let Some(frame) = planar_frame(input) {
        write_planar(input, frame, out, &mut plot_to)?;
        if options.alignment {
            alignment_map(out, input, &mut plot_to)?;
        }
    } else if options.alignment {
        bail!("--alignment needs a flat scene (the map is drawn in the plane)");
    }
    write_json(
        &out.join("summary.json"),
        &serde_json::json!({"input": source, "samples": n, "realizations": input.sets.len()}),
    )?;
    Ok(AnalysisSummary {
        realizations: input.sets.len(),
        samples: n,
        plots: written,
        plot_errors,
    })
}

/// Differential domain analysis of every input: `dda.json` and its three plots.
fn write_dda(
    input: &AnalysisInput,
    options: &AnalysisOptions,
    out: &Path,
    plot_to: &mut dyn FnMut(&str, &DrawFn),
) -> anyhow::Result<()> {
    let n = input.sets[0].len();
    let dda_options = DdaOptions {
        epsilon: options.epsilon,
        ..Default::default()
    };
    let spectrum = dda(&input.sets, &dda_options).context("differential domain analysis")?;
    let radial = spectrum.radial();
    write_json(
        &out.join("dda.json"),
        &serde_json::json!({
            "samples": n, "realizations": input.sets.len(), "options": options_json(&dda_options),
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
    Ok(())
}

/// The planar measures of a flat input mapped by `frame` to the unit square:
/// `planar.json` (discrepancies and spectrum) and its plots.
fn write_planar(
    input: &AnalysisInput,
    frame: Frame,
    out: &Path,
    plot_to: &mut dyn FnMut(&str, &DrawFn),
) -> anyhow::Result<()> {
    let n = input.sets[0].len();
    let unit: Vec<Vec<DVec2>> = input.sets.iter().map(|s| frame.map(s)).collect();
    let families = [
        (ShapeFamily::Rectangles, "rectangles"),
        (ShapeFamily::OriginTriangles, "triangles"),
        (ShapeFamily::QuarterDiscs, "quarter_discs"),
    ];
    let mut disc = serde_json::Map::new();
    for (family, name) in families {
        let entry = discrepancy_entry(input, frame, &unit, family, name, plot_to)?;
        disc.insert(name.to_string(), entry);
    }
    let spec = periodogram(&unit, 2.5).context("periodogram")?;
    let r = spec.radial();
    write_json(
        &out.join("planar.json"),
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
    Ok(())
}

/// The discrepancy of the unit-square realizations `unit` over one shape `family`
/// (mean sup and L2), and for a scene its curve over more counts with the curve's
/// plot `discrepancy_<name>.png`.
fn discrepancy_entry(
    input: &AnalysisInput,
    frame: Frame,
    unit: &[Vec<DVec2>],
    family: ShapeFamily,
    name: &str,
    plot_to: &mut dyn FnMut(&str, &DrawFn),
) -> anyhow::Result<serde_json::Value> {
    let n = input.sets[0].len();
    let d = Discrepancy::new(family);
    let sup = unit.iter().map(|p| d.sup(p)).sum::<f64>() / unit.len() as f64;
    let l2 = unit.iter().map(|p| d.l2(p)).sum::<f64>() / unit.len() as f64;
    let mut entry = serde_json::json!({"n": n, "sup": sup, "l2": l2});
    let Some(sampled) = &input.scene else {
        return Ok(entry);
    };
    let (scene, seed) = (&sampled.scene, sampled.first_seed);
    let ns: Vec<usize> = (6..=13)
        .flat_map(|l| [1usize << l, (1 << l) + (1 << (l - 1))])
        .filter(|&k| k <= n.clamp(64, 8192))
        .collect();
    let seeds: Vec<u64> = (0..input.sets.len() as u64).map(|k| seed + k).collect();
    if ns.len() < 2 {
        return Ok(entry);
    }
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
    Ok(entry)
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
fn planar_frame(input: &AnalysisInput) -> Option<Frame> {
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
        Some(sampled) => {
            let (lo, hi) = sampled.scene.mesh.bounds();
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

/// The alignment map of a scene input: `alignment.json` and `alignment.png`.
fn alignment_map(
    out: &Path,
    input: &AnalysisInput,
    plot_to: &mut dyn FnMut(&str, &DrawFn),
) -> anyhow::Result<()> {
    let Some(SampledScene { scene, config, .. }) = &input.scene else {
        bail!("--alignment needs a scene file");
    };
    // The surface pipeline also on a flat scene: the map shows how the segments'
    // parameterizations align with the field, which the planar path has none of.
    let pre = Preprocessed::build_surface(
        scene.mesh.clone(),
        scene.field.clone(),
        &config.surface_options(),
    )
    .context("surface preprocessing for the alignment map")?;
    let angles = alignment::face_angles(&scene.mesh, &scene.field, &pre.params);
    let max = angles
        .iter()
        .copied()
        .filter(|a| a.is_finite())
        .fold(0.0, f64::max);
    write_json(
        &out.join("alignment.json"),
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

/// The DDA options as JSON.
fn options_json(o: &DdaOptions) -> serde_json::Value {
    serde_json::json!({"epsilon": o.epsilon, "max_frequency": o.max_frequency,
        "frequency_step": o.frequency_step, "bins_per_spacing": o.bins_per_spacing,
        "min_normal_cos": o.min_normal_cos, "arc_tolerance": o.arc_tolerance})
}

/// Writes `value` as pretty JSON, atomically.
fn write_json(path: &Path, value: &serde_json::Value) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    strata_engine::io::write_atomically(path, |w| std::io::Write::write_all(w, text.as_bytes()))
        .with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_json(path: &Path) -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(path).expect("read")).expect("json")
    }

    #[test]
    fn a_flat_scene_gets_dda_planar_measures_and_a_summary() {
        let config = SceneConfig::from_ron(
            "(mesh: Shape(Plane(size: 1.0, resolution: 4)), sampling: (count: 256, seed: 5))",
            Path::new("flat.ron"),
        )
        .expect("scene");
        let scene = Scene::build(&config).expect("build");
        let input = AnalysisInput::from_scene(scene, config, 256, 5, 2);
        assert_eq!(input.sets.len(), 2);
        assert_ne!(input.sets[0], input.sets[1], "seeds 5 and 6 differ");
        let dir = tempfile::tempdir().expect("tempdir");
        let options = AnalysisOptions {
            epsilon: 10.0,
            plots: false,
            alignment: false,
        };
        let summary =
            write_analysis(&input, Path::new("flat.ron"), dir.path(), &options).expect("analysis");
        assert_eq!((summary.realizations, summary.samples), (2, 256));
        assert!(summary.plots.is_empty() && summary.plot_errors.is_empty());
        let s = read_json(&dir.path().join("summary.json"));
        assert_eq!(s["input"], "flat.ron");
        assert_eq!(
            (s["samples"].as_u64(), s["realizations"].as_u64()),
            (Some(256), Some(2))
        );
        let dda = read_json(&dir.path().join("dda.json"));
        assert_eq!(dda["options"]["epsilon"], 10.0);
        let planar = read_json(&dir.path().join("planar.json"));
        let rect = &planar["discrepancy"]["rectangles"];
        // A scene input gets a discrepancy curve over counts up to its own.
        let ns: Vec<u64> = rect["curve"]["n"]
            .as_array()
            .expect("curve")
            .iter()
            .filter_map(|v| v.as_u64())
            .collect();
        assert_eq!(ns, [64, 96, 128, 192, 256]);
        let sup = rect["sup"].as_f64().expect("sup");
        assert!(sup > 0.0 && sup < 0.1, "stratified samples: {sup}");
        assert!(!dir.path().join("alignment.json").exists());
    }

    #[test]
    fn inputs_without_samples_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let options = AnalysisOptions {
            epsilon: 10.0,
            plots: false,
            alignment: false,
        };
        for input in [
            AnalysisInput {
                sets: Vec::new(),
                scene: None,
            },
            AnalysisInput::from_samples(Vec::new()),
        ] {
            let e = write_analysis(&input, Path::new("x.ply"), dir.path(), &options)
                .expect_err("no samples");
            assert!(e.to_string().contains("at least one sample"), "{e}");
        }
    }
}
