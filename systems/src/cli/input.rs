//! What a command's input names: a scene file (RON), or a mesh (OBJ or PLY) that stands
//! for a scene with the field its flags ask for (`--field`, `--anisotropy`,
//! `--density-from`; uniform density by default). [`MeshFieldArgs::scene_for_mesh`]
//! is also what `strata scene` prints.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use strata_engine::field::FieldSpec;
use strata_engine::field::design::{Anisotropy, Density, Design, Guidance};

use crate::config::SceneConfig;

/// The field of a mesh given as input, from its flags.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct MeshFieldArgs {
    /// With a mesh as input: the field. `uniform` (uniform density, the default),
    /// `smooth` (the smoothest line field), `curvature` (density and direction from
    /// the principal curvatures) or `direction:X,Y,Z` (that world direction projected
    /// into the surface).
    #[arg(long, value_parser = parse_field)]
    pub field: Option<FieldChoice>,
    /// With a mesh as input: the spacing ratio across / along the field's direction,
    /// at least 1 (default 1 for `uniform`, 3 for the others; for `curvature`, the
    /// largest ratio).
    #[arg(long)]
    pub anisotropy: Option<f64>,
    /// With a mesh as input: per-vertex densities from a field file (the
    /// `strata-field 1` format, one line per vertex of the mesh file; its density
    /// `sqrt(l1 l2)` is used); the direction comes from `--field` (smooth by default).
    #[arg(long)]
    pub density_from: Option<PathBuf>,
}

/// The fields `--field` names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FieldChoice {
    /// Uniform density; with `--anisotropy`, along the world x axis.
    Uniform,
    /// The smoothest line field of the surface.
    Smooth,
    /// The principal-curvature field.
    Curvature,
    /// A world direction projected into the tangent planes.
    Direction([f64; 3]),
}

/// Parses `--field`.
fn parse_field(text: &str) -> Result<FieldChoice, String> {
    let usage = "give uniform, smooth, curvature or direction:X,Y,Z";
    match text {
        "uniform" => Ok(FieldChoice::Uniform),
        "smooth" => Ok(FieldChoice::Smooth),
        "curvature" => Ok(FieldChoice::Curvature),
        _ => {
            let Some(xyz) = text.strip_prefix("direction:") else {
                return Err(usage.to_owned());
            };
            let v: Vec<f64> = xyz
                .split(',')
                .map(|c| c.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| format!("direction:X,Y,Z takes three numbers; {usage}"))?;
            match v[..] {
                [x, y, z]
                    if [x, y, z].iter().all(|c| c.is_finite()) && (x, y, z) != (0.0, 0.0, 0.0) =>
                {
                    Ok(FieldChoice::Direction([x, y, z]))
                }
                _ => Err(format!(
                    "direction:X,Y,Z takes three finite numbers, not all 0; {usage}"
                )),
            }
        }
    }
}

/// Whether `path` names a mesh (`.obj` or `.ply`, any case) rather than a scene.
pub fn is_mesh(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj") || e.eq_ignore_ascii_case("ply"))
}

impl MeshFieldArgs {
    /// Whether any of the mesh flags was given.
    fn any(&self) -> bool {
        self.field.is_some() || self.anisotropy.is_some() || self.density_from.is_some()
    }

    /// The field these flags ask for.
    pub fn field_spec(&self) -> anyhow::Result<FieldSpec> {
        if let Some(a) = self.anisotropy
            && !(a >= 1.0 && a.is_finite())
        {
            bail!("--anisotropy must be a number of at least 1, not {a}");
        }
        let choice = self.field.unwrap_or(match self.density_from {
            Some(_) => FieldChoice::Smooth,
            None => FieldChoice::Uniform,
        });
        let designed = |guidance: Guidance| {
            let density = match &self.density_from {
                Some(path) => Density::File(absolute(path)),
                None => Density::default(),
            };
            FieldSpec::Designed(Design {
                guidance,
                anisotropy: Anisotropy::Constant(self.anisotropy.unwrap_or(3.0)),
                density,
                ..Design::default()
            })
        };
        Ok(match choice {
            FieldChoice::Uniform | FieldChoice::Direction(_) if self.density_from.is_some() => {
                match choice {
                    FieldChoice::Direction(d) => designed(Guidance::Direction(d)),
                    _ => designed(Guidance::Smoothest),
                }
            }
            FieldChoice::Uniform => FieldSpec::Constant {
                direction: [1.0, 0.0, 0.0],
                anisotropy: self.anisotropy.unwrap_or(1.0),
                density: 1.0,
            },
            FieldChoice::Direction(d) => FieldSpec::Constant {
                direction: d,
                anisotropy: self.anisotropy.unwrap_or(3.0),
                density: 1.0,
            },
            FieldChoice::Smooth => designed(Guidance::Smoothest),
            FieldChoice::Curvature if self.density_from.is_some() => designed(Guidance::default()),
            FieldChoice::Curvature => match FieldSpec::default_curvature() {
                FieldSpec::Curvature {
                    measure,
                    normalization,
                    floor,
                    scale,
                    max_anisotropy,
                    isotropy_curvature,
                    smoothing_iterations,
                } => FieldSpec::Curvature {
                    measure,
                    normalization,
                    floor,
                    scale,
                    max_anisotropy: self.anisotropy.unwrap_or(max_anisotropy),
                    isotropy_curvature,
                    smoothing_iterations,
                },
                other => other,
            },
        })
    }

    /// The scene a mesh with these flags stands for: the mesh file (absolute), the
    /// field, every other section at its default.
    pub fn scene_for_mesh(&self, mesh: &Path) -> anyhow::Result<SceneConfig> {
        if !mesh.is_file() {
            bail!("{}: no such mesh file", mesh.display());
        }
        let text = format!("(mesh: File({:?}))", absolute(mesh));
        let mut config = SceneConfig::from_ron(&text, mesh)
            .with_context(|| format!("{}: as a scene", mesh.display()))?;
        config.field = self.field_spec()?;
        config
            .validate()
            .map_err(|e| anyhow::anyhow!("{}: {e}", mesh.display()))?;
        Ok(config)
    }

    /// The scene `input` names: a scene file as it is (refusing the mesh flags, which
    /// its own `field` replaces), or a mesh with these flags.
    pub fn load(&self, input: &Path) -> anyhow::Result<SceneConfig> {
        if is_mesh(input) {
            return self.scene_for_mesh(input);
        }
        if self.any() {
            bail!(
                "{}: --field, --anisotropy and --density-from apply to a mesh input (.obj, .ply); a scene file sets its own `field`",
                input.display()
            );
        }
        Ok(SceneConfig::load(input)?)
    }
}

/// Arguments of `strata scene`.
#[derive(Debug, clap::Args)]
pub struct SceneArgs {
    /// Mesh file (OBJ, PLY).
    pub mesh: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`.
    #[command(flatten)]
    pub input: MeshFieldArgs,
}

/// Runs `strata scene`: prints the scene of a mesh and its flags
/// (`strata scene m.obj --field smooth > m.ron`).
pub(super) fn run_scene(args: &SceneArgs) -> anyhow::Result<()> {
    if !is_mesh(&args.mesh) {
        bail!(
            "{}: strata scene takes a mesh (.obj, .ply)",
            args.mesh.display()
        );
    }
    let config = args.input.scene_for_mesh(&args.mesh)?;
    let text = scene_ron(&config)?;
    let mut out = std::io::stdout().lock();
    std::io::Write::write_all(&mut out, text.as_bytes())?;
    std::io::Write::flush(&mut out)?;
    Ok(())
}

/// `path` made absolute (left as it is if the working folder is unknown).
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The RON text of `config`, as `strata scene` prints it: a scene file that
/// [`SceneConfig::load`] reads back to the same scene.
pub fn scene_ron(config: &SceneConfig) -> anyhow::Result<String> {
    let pretty = ron::ser::PrettyConfig::new()
        .extensions(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES);
    let body = ron::ser::to_string_pretty(config, pretty).context("writing the scene as RON")?;
    Ok(format!(
        "// A strata scene: every section at its default but the mesh and field; see\n// the scene-file guide to change them. The mesh path is absolute.\n{body}\n"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_flags_parse() {
        assert_eq!(parse_field("smooth"), Ok(FieldChoice::Smooth));
        assert_eq!(
            parse_field("direction:0,1,0.5"),
            Ok(FieldChoice::Direction([0.0, 1.0, 0.5]))
        );
        assert!(parse_field("direction:0,0,0").is_err());
        assert!(parse_field("direction:1,2").is_err());
        assert!(parse_field("bumpy").is_err_and(|e| e.contains("uniform, smooth")));
    }
}
