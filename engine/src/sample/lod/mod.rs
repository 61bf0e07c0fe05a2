//! View-dependent level of detail over progressive samples.

mod bins;
mod bounds;
mod estimate;
mod pool;
mod view;

pub use bins::{SPLIT_ENTRIES, SPLIT_LOOSE, SPLIT_ROOM, SPLIT_WAYS};
pub use estimate::{CLOSE_ROOM, IN_VIEW, MeanMultiplier, PROBES, REFINE_LIMIT, ShownEstimate};
pub use pool::{BINS, DRAW_AHEAD, LodPool, PoolChange};
pub use view::{LodError, SIMILARITY_TOLERANCE, ViewLod, fade, visible};
