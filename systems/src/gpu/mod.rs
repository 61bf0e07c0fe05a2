//! GPU streaming and field-aligned splat rendering with wgpu (the only module that
//! touches `wgpu::Buffer`).
//!
//! - [`backend`]: which sampler draws the samples (CPU or GPU, [`EngineSettings`](crate::ecs::EngineSettings)'s
//!   switch) and the ECS systems that draw them on the GPU.
//! - [`context`]: adapter and device with typed errors; error scopes.
//! - [`layout`]: the Pod structs shared with WGSL and their vertex layouts.
//! - [`buffers`]: the growable sample (and sites) buffers with their staging rings.
//! - [`expand`]: sample sites (16 bytes) expanded into full samples by a compute pass.
//! - [`sample`]: stratified sampling on the GPU: sites drawn by a compute pass from the
//!   sampler's flattened cells, then expanded into the sample buffer; [`sample_check`]
//!   times it and checks it against the CPU (`strata bench --gpu`).
//! - [`lod`]: GPU-resident progressive pools and the level-of-detail fade pass.
//! - [`pipeline`]: render and compute pipelines as plain, hashable descriptions, made
//!   into wgpu pipelines in one place.
//! - [`splat`]: the splat and mesh pipelines; [`splat::SplatRenderer`].
//! - [`npr`]: stroke and stipple pictures on paper from the same sample buffer;
//!   [`npr::NprRenderer`]; [`npr::StyledFrame`] draws either look into a window.
//! - [`headless`]: offscreen target, readback, PNG.
//! - [`camera`]: orbit camera and framing.
//! - [`stream`]: per-frame resampling + upload without ECS.
//! - [`upload`]: the ECS system streaming the engine's sample buffer to the GPU.
//! - [`shaders`]: the WGSL sources from `shaders/`.
//!
//! A frame: `SampleStream::sample` (CPU, `Sampler::sample_into` into a reused vector),
//! `SampleStream::upload` (into mapped staging memory, then a recorded copy; no wait
//! on the GPU), `SplatRenderer::encode` (one pass: mesh, then instanced quads).

pub mod backend;
pub mod buffers;
pub mod camera;
pub mod context;
pub mod expand;
pub mod headless;
pub mod layout;
pub mod lod;
pub mod npr;
pub mod pipeline;
pub mod sample;
pub mod sample_check;
pub mod shaders;
pub mod splat;
pub mod stream;
pub mod upload;
#[cfg(test)]
mod wgsl_layout;

/// The wgpu version this module is written against, re-exported so that callers (an
/// ECS render system, tests) name the same types.
pub use wgpu;

pub use buffers::GpuSampleBuffer;
pub use camera::OrbitCamera;
pub use context::{GpuContext, GpuError, GpuOptions};
pub use expand::SiteExpander;
pub use headless::{HeadlessTarget, RgbaImage};
pub use layout::{ColorMode, Footprint, MeshMode};
pub use lod::{GpuLodPool, LodFades, LodFrame, LodScene};
pub use npr::{Brush, NprKind, NprRenderer, NprStyle, RenderStyle, StyleChoice, StyledFrame};
pub use sample::GpuSampler;
pub use splat::{SplatLod, SplatRenderer, SplatStyle};
pub use stream::SampleStream;
pub use upload::{GpuSplats, upload_samples};
