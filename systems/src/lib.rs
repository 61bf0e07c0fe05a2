//! # strata-systems
//!
//! The application layer of strata: scene configuration files (RON), turning a scene
//! into engine inputs, and the `strata` command-line tool. (The ECS, hot reload and GPU
//! layers will live here too; the pure algorithms are in `strata-engine`.)

pub mod analyze;
pub mod atlas;
pub mod cli;
pub mod config;
pub mod gpu;
pub mod plot;
pub mod render;
pub mod scene;
pub mod view;
