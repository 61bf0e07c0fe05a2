//! Stratified sampling: 1D stratified values mapped through each segment's Hilbert
//! cells onto the surface, producing GPU-ready [`Sample`]s (paper section 6.2, with
//! DESIGN.md's continuous mapping so that any count can be drawn without
//! re-preprocessing).
//!
//! Input: the mesh, the field and per-segment [`SegmentCurve`](crate::curve::SegmentCurve)s.
//! Output: exactly `N` samples, written into a caller's buffer. Cost: O(N + cells)
//! per call, parallel over fixed chunks of the output (so the result does not depend
//! on the thread count), no allocation.

mod chains;
pub(crate) mod faces;
pub mod flat;
mod leaves;
pub mod lod;
pub mod progressive;
mod sampler;
mod stratified;
mod types;

pub use lod::{BINS, Budget, CLOSE_ROOM, DRAW_AHEAD, FrameUpdate, LodPool, PoolChange};
pub use sampler::{SampleError, Sampler, SegmentSampling};
pub use stratified::{allocate, stratified_value};
pub use types::{Sample, SampleSite};
