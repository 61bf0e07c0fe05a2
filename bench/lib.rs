//! Shared helpers for strata benchmarks.
