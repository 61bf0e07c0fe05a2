//! [`CellKey`]: a leaf cell's column, row, level, Hilbert state and coverage packed
//! into one `u64`, O(1) to pack and unpack (the cells are the largest per-face part of
//! the preprocessed data, paper section 6.1).

use glam::DVec2;

use super::hilbert::State;

/// Where a leaf cell lies and how the curve runs through it, packed into 8 bytes (the
/// cells are the largest per-face part of the preprocessed data).
///
/// Layout of the `u64`: bits 0..31 hold the column with a marker bit above it at bit
/// `level` (so the level is the position of the highest set bit and needs no field of
/// its own), bits 31..61 the row, bits 61..63 the Hilbert state and bit 63 whether the
/// domain covers the whole cell. Levels go up to 30
/// ([`CurveOptions::max_level`](super::CurveOptions::max_level)).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CellKey(u64);

impl CellKey {
    /// Deepest level a key can hold.
    pub const MAX_LEVEL: u8 = 30;
    const LOW: u64 = (1 << 31) - 1;

    /// The cell at column `x` and row `y` of level `level` (`x, y < 2^level`, `level <=`
    /// [`MAX_LEVEL`](Self::MAX_LEVEL); out-of-range bits are dropped).
    #[inline]
    pub fn new(x: u32, y: u32, level: u8, state: State, full: bool) -> Self {
        debug_assert!(level <= Self::MAX_LEVEL);
        debug_assert!((x as u64) < 1 << level && (y as u64) < 1 << level);
        let level = level.min(Self::MAX_LEVEL);
        let mask = (1u64 << level) - 1;
        let low = (x as u64 & mask) | 1 << level;
        Self(low | (y as u64 & mask) << 31 | ((state.0 & 3) as u64) << 61 | (full as u64) << 63)
    }

    /// Quadtree level (the cell's side is `2^-level`).
    #[inline]
    pub fn level(&self) -> u8 {
        (31 - ((self.0 & Self::LOW) as u32).leading_zeros()) as u8
    }

    /// Cell column at its level.
    #[inline]
    pub fn x(&self) -> u32 {
        let low = (self.0 & Self::LOW) as u32;
        low ^ (1 << self.level())
    }

    /// Cell row at its level.
    #[inline]
    pub fn y(&self) -> u32 {
        ((self.0 >> 31) & ((1 << 30) - 1)) as u32
    }

    /// Hilbert orientation of the cell.
    #[inline]
    pub fn state(&self) -> State {
        State(((self.0 >> 61) & 3) as u8)
    }

    /// Whether the domain covers the whole cell.
    #[inline]
    pub fn full(&self) -> bool {
        self.0 >> 63 != 0
    }

    /// Side length.
    #[inline]
    pub fn size(&self) -> f64 {
        // 2^-level, built from its exponent (no integer conversion, no division).
        f64::from_bits((1023 - self.level() as u64) << 52)
    }

    /// Lower-left corner.
    #[inline]
    pub fn origin(&self) -> DVec2 {
        DVec2::new(self.x() as f64, self.y() as f64) * self.size()
    }
}

impl std::fmt::Debug for CellKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CellKey")
            .field("x", &self.x())
            .field("y", &self.y())
            .field("level", &self.level())
            .field("state", &self.state())
            .field("full", &self.full())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::{CellKey, State};

    #[test]
    fn cell_size_is_the_power_of_two() {
        for level in 0..=30u8 {
            let (x, y) = if level >= 2 {
                (3, 1)
            } else {
                (level as u32, 0)
            };
            let key = CellKey::new(x, y, level, State::ROOT, true);
            assert_eq!(key.size(), 1.0 / (1u64 << level) as f64, "level {level}");
            assert_eq!(key.origin(), DVec2::new(x as f64, y as f64) * key.size());
        }
    }

    #[test]
    fn cell_keys_pack_every_field() {
        let mut rng = crate::rng::Rng::new(11, 0);
        for level in 0..=CellKey::MAX_LEVEL {
            for state in 0..4u8 {
                for full in [false, true] {
                    let side = 1u64 << level;
                    let corners = [(0, 0), (side - 1, side - 1), (side - 1, 0), (0, side - 1)];
                    let random = (
                        (rng.next_f64() * side as f64) as u64 % side,
                        (rng.next_f64() * side as f64) as u64 % side,
                    );
                    for (x, y) in corners.into_iter().chain([random]) {
                        let key = CellKey::new(x as u32, y as u32, level, State(state), full);
                        assert_eq!(
                            (key.x(), key.y(), key.level(), key.state(), key.full()),
                            (x as u32, y as u32, level, State(state), full),
                            "{key:?}"
                        );
                    }
                }
            }
        }
        assert_eq!(std::mem::size_of::<CellKey>(), 8);
    }
}
