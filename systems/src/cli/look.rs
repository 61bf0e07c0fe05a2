//! The camera and look options that `strata render` and `strata view` share, and what
//! they turn into: GPU options, a camera framing the mesh, a splat style.

use crate::gpu::layout::log_density_range;
use crate::gpu::{ColorMode, Footprint, GpuOptions, MeshMode, OrbitCamera, SplatStyle};
use crate::scene::Scene;

/// Camera and look options shared by `strata render` and `strata view`.
#[derive(Debug, Clone, clap::Args)]
pub struct LookArgs {
    /// Number of samples (overrides the scene's `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Random seed (overrides the scene's `sampling.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Camera rotation about the vertical (Y) axis, degrees; 0 looks from +Z.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    pub yaw: f32,
    /// Camera elevation, degrees (-89 to 89).
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true)]
    pub pitch: f32,
    /// Distance as a multiple of the one that frames the mesh's bounding box (< 1 is closer).
    #[arg(long, default_value_t = 1.0)]
    pub zoom: f32,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 35.0)]
    pub fov: f32,
    /// Splat colours.
    #[arg(long, value_enum, default_value_t = ColorMode::Density)]
    pub color: ColorMode,
    /// Splat shape.
    #[arg(long, value_enum, default_value_t = Footprint::Disc)]
    pub footprint: Footprint,
    /// Draw each sample as a thin line along the field's major direction instead of an
    /// ellipse (hatching that shows the field; the same as `--footprint glyph`).
    #[arg(long, conflicts_with = "footprint")]
    pub glyphs: bool,
    /// The mesh under the splats.
    #[arg(long, value_enum, default_value_t = MeshMode::Plain)]
    pub mesh: MeshMode,
    /// Splat size as a fraction of the sample spacing (1: neighbours touch on average);
    /// with glyphs, their length as a fraction of the larger spacing.
    #[arg(long, default_value_t = 0.8)]
    pub scale: f32,
    /// Use the GPU adapter whose name contains this (case-insensitive); default:
    /// `WGPU_ADAPTER_NAME`, else wgpu's choice. `WGPU_BACKEND=vulkan|gl` picks backends.
    #[arg(long)]
    pub adapter: Option<String>,
}

impl LookArgs {
    /// Checks the numeric options.
    pub fn validate(&self) -> anyhow::Result<()> {
        if !(self.zoom > 0.0 && self.zoom.is_finite()) {
            anyhow::bail!("--zoom must be a positive number, not {}", self.zoom);
        }
        if !(self.fov > 1.0 && self.fov < 170.0) {
            anyhow::bail!("--fov must be between 1 and 170 degrees, not {}", self.fov);
        }
        if !(self.scale > 0.0 && self.scale.is_finite()) {
            anyhow::bail!("--scale must be a positive number, not {}", self.scale);
        }
        if !(self.pitch.abs() <= 89.0) {
            anyhow::bail!(
                "--pitch must be between -89 and 89 degrees, not {}",
                self.pitch
            );
        }
        if !self.yaw.is_finite() {
            anyhow::bail!("--yaw must be a number");
        }
        Ok(())
    }

    /// The GPU options these arguments ask for.
    pub fn gpu_options(&self) -> GpuOptions {
        GpuOptions {
            backends: None,
            adapter_name: self.adapter.clone(),
        }
    }

    /// The camera framing `scene`'s mesh for a target of `aspect` (width / height).
    pub fn camera(&self, scene: &Scene, aspect: f32) -> OrbitCamera {
        self.camera_for_mesh(&scene.mesh, aspect)
    }

    /// The camera framing `mesh` for a target of `aspect` (width / height).
    pub fn camera_for_mesh(&self, mesh: &strata_engine::mesh::TriMesh, aspect: f32) -> OrbitCamera {
        self.orientation().fitted_to_mesh(mesh, aspect, self.zoom)
    }

    /// The camera's yaw, pitch and field of view (target and distance not yet fitted).
    pub fn orientation(&self) -> OrbitCamera {
        OrbitCamera {
            yaw: self.yaw.to_radians(),
            pitch: self.pitch.to_radians(),
            fov_y: self.fov.to_radians(),
            ..OrbitCamera::default()
        }
    }

    /// The footprint asked for: [`Footprint::Glyph`] with `--glyphs`, else `--footprint`.
    pub fn footprint(&self) -> Footprint {
        if self.glyphs {
            Footprint::Glyph
        } else {
            self.footprint
        }
    }

    /// The style these arguments ask for, with the colour map fitted to `samples`.
    pub fn style(&self, samples: &[strata_engine::sample::Sample]) -> SplatStyle {
        SplatStyle {
            color_mode: self.color,
            footprint: self.footprint(),
            mesh_mode: self.mesh,
            splat_scale: self.scale,
            log_density_range: log_density_range(samples),
            ..SplatStyle::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    #[derive(Debug, Parser)]
    struct Args {
        #[command(flatten)]
        look: LookArgs,
    }

    fn parse(args: &[&str]) -> Result<LookArgs, clap::Error> {
        Args::try_parse_from(std::iter::once("strata").chain(args.iter().copied())).map(|a| a.look)
    }

    #[test]
    fn glyphs_flag_picks_the_glyph_footprint() {
        assert_eq!(parse(&[]).expect("defaults").footprint(), Footprint::Disc);
        assert_eq!(
            parse(&["--glyphs"]).expect("glyphs").footprint(),
            Footprint::Glyph
        );
        assert_eq!(
            parse(&["--footprint", "glyph"]).expect("glyph").footprint(),
            Footprint::Glyph
        );
        let style = parse(&["--glyphs", "--scale", "1.5"])
            .expect("glyphs")
            .style(&[]);
        assert_eq!(
            (style.footprint, style.splat_scale),
            (Footprint::Glyph, 1.5)
        );
        assert!(parse(&["--glyphs", "--footprint", "gaussian"]).is_err());
    }
}
