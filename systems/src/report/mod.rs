//! Report writers: what the commands write for a person or a tool to read, beyond the
//! samples and meshes (which `strata_engine::io` writes).
//!
//! - [`atlas`]: the SVG atlas of every segment's parameter layout (`strata segment --atlas`).
//! - [`plot`]: PNG plots (line charts, spectra, point sets, per-face maps).
//! - [`segment`]: the JSON report of `strata segment` and the segment mesh's colours.
//! - [`field`]: the field PLY and the JSON report of `strata field`.
//! - [`analysis`]: the quality measures of `strata analyze` as JSON and plots.
//!
//! Every file is written atomically ([`strata_engine::io::write_atomically`]).

pub mod analysis;
pub mod atlas;
pub mod field;
pub mod plot;
pub mod segment;
