//! View-dependent level of detail over progressive samples: a camera's density
//! multiplier over the surface ([`ViewLod`]), and a pool of progressive sample sites
//! that holds every rank a view shows ([`LodPool`]), updated by one call per frame.
//!
//! Input: a [`Sampler`](crate::sample::Sampler), a seed, and per frame a view and a
//! [`Budget`]. Output: the pool's sites and ranks (appended to, or rebuilt) and the
//! base count the frame thresholds with. Cost per frame: in proportion to the bins
//! (about [`BINS`]) plus the ranks drawn.
//!
//! The pool is composed of parts that own their data, each in its own file, listed
//! from the bottom up (a part uses only those above it in this list):
//!
//! - `view`: [`ViewLod`], its multiplier and the visible set's rule ([`visible`],
//!   [`fade`]).
//! - `bounds`: upper bounds of a view's multiplier over regions, as columns.
//! - `split`: when a bin splits into finer ones, and where it is cut.
//! - `key`: which sampler a pool was built from.
//! - `estimate`: the point budget's estimator ([`ShownEstimate`]).
//! - `bins`: the bins, their bounds, needs and reaches; their splits.
//! - `entries`: the sites and ranks held, and the draws that append them.
//! - `pool`: [`LodPool`], the parts put together, and its one call per frame
//!   ([`LodPool::update`]).

mod bins;
mod bounds;
mod entries;
mod estimate;
mod key;
mod pool;
mod split;
#[cfg(test)]
mod tests;
mod view;

pub use bins::BINS;
pub use entries::{DRAW_AHEAD, Placement, PoolChange};
pub use estimate::{CLOSE_ROOM, IN_VIEW, MeanMultiplier, PROBES, REFINE_LIMIT, ShownEstimate};
pub use pool::{Budget, FrameUpdate, LodPool};
pub use split::{SPLIT_ENTRIES, SPLIT_LOOSE, SPLIT_ROOM, SPLIT_WAYS};
pub use view::{LodError, SIMILARITY_TOLERANCE, ViewLod, fade, visible};
