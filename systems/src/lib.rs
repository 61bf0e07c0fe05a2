//! # strata-systems
//!
//! The application layer of strata: scene configuration files (RON), turning a scene
//! into engine inputs, the streaming engine as a bevy_ecs world ([`ecs`]) with scene
//! hot reload ([`hot_reload`]), GPU streaming and field-aligned splat rendering with
//! wgpu ([`gpu`]), and the `strata` command-line tool. The pure algorithms are in
//! `strata-engine`.

pub mod analyze;
pub mod atlas;
pub mod cli;
pub mod config;
pub mod ecs;
pub mod gpu;
pub mod hot_reload;
pub mod plot;
pub mod render;
pub mod scene;
pub mod view;
pub mod watch;
