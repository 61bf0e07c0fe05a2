//! strata integration tests: one binary, one module per stage.
mod io;
mod pipeline;
