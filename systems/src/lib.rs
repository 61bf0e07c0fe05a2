//! # strata-systems
//!
//! The application layer of strata: scene files, the streaming engine as a bevy_ecs
//! world with hot reload, GPU streaming and splat rendering with wgpu, report writers,
//! and the `strata` command-line tool. The pure algorithms are in `strata-engine`.
//!
//! - [`config`]: scene files (RON) as [`config::SceneConfig`], and their one mapping to
//!   the engine's options ([`config::SceneConfig::surface_options`]).
//! - [`scene`]: a scene turned into engine data (mesh, field, sampler).
//! - [`ecs`]: the streaming engine's components and systems.
//! - [`plugin`]: [`StrataPlugin`], the engine as a `bevy_app` plugin for Bevy hosts.
//! - [`hot_reload`]: the scene watcher and its application to the world.
//! - [`gpu`]: wgpu streaming, splat rendering, offscreen pictures.
//! - [`viewer`]: the interactive window over the streaming engine.
//! - [`report`]: report writers (SVG atlas, PNG plots, JSON reports, the analysis).
//! - [`budget`]: whether a request's samples fit (indices, memory, disk space).
//! - [`cli`]: the `strata` command line, one file per command.

pub mod budget;
pub mod cli;
pub mod config;
pub mod ecs;
pub mod frame_thread;
pub mod gpu;
pub mod hot_reload;
#[cfg(feature = "bevy-mesh")]
pub mod mesh_asset;
pub mod plugin;
pub mod report;
pub mod scene;
pub mod viewer;

pub use plugin::StrataPlugin;
