//! The level-of-detail options that `strata render` and `strata view` share:
//! `--lod`, `--lod-max` and `--lod-shown`.

/// Level-of-detail options shared by `strata render` and `strata view`.
#[derive(Debug, Clone, clap::Args)]
pub struct LodArgs {
    /// Level of detail: the count is the base count of progressive samples that follow
    /// the camera, the samples over the whole surface where a unit of surface covers
    /// as many pixels as one facing the camera at its target's distance; nearer
    /// surface gets more (zooming in adds samples and moves none), farther less,
    /// hidden none.
    #[arg(long)]
    pub lod: bool,
    /// With `--lod`: the largest multiplier of the count's density.
    #[arg(long, default_value_t = 4.0, requires = "lod")]
    pub lod_max: f32,
    /// With `--lod`: a point budget: about this many samples are shown in every frame
    /// at any camera distance (each frame's base count is chosen for it); the count is
    /// then the pool's prefix, drawn up front.
    #[arg(long, requires = "lod")]
    pub lod_shown: Option<u32>,
}

impl LodArgs {
    /// Checks the numeric options: a positive finite `--lod-max`, a `--lod-shown` of at
    /// least 1.
    pub fn validate(&self) -> anyhow::Result<()> {
        if !(self.lod_max > 0.0 && self.lod_max.is_finite()) {
            anyhow::bail!("--lod-max must be a positive number, not {}", self.lod_max);
        }
        if self.lod_shown == Some(0) {
            anyhow::bail!("--lod-shown must be at least 1");
        }
        Ok(())
    }
}
