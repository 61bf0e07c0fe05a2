//! strata integration tests: one binary, one module per stage.
mod analysis;
mod chains;
mod discrepancy;
mod ecs;
mod field;
mod fuzz;
mod gpu;
mod hostile;
mod hot_reload;
mod io;
mod layout;
mod lod;
mod param;
mod pipeline;
mod segment;
mod soak;
mod surface;
