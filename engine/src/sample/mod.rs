//! Stratified sampling: 1D stratified values mapped through Hilbert cells onto a
//! surface, producing GPU-ready [`Sample`]s.

mod types;

pub use types::Sample;
