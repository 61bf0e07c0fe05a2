//! The Hilbert curve on a `2^order x 2^order` grid: index to cell and back, and the
//! top-down state machine used to walk and refine it adaptively.
//!
//! Orientation: the curve of [`d2xy`] starts at cell (0, 0) and ends at
//! `(2^order - 1, 0)`; at order 1 it visits (0,0), (0,1), (1,1), (1,0).
//!
//! The state machine describes the same curve top-down. Each quadtree node has a
//! [`State`], one of the four symmetries of the square that map the canonical order-1
//! pattern onto the node's visiting order: identity, transpose `(y, x)`,
//! anti-transpose `(1 - y, 1 - x)` and the half turn `(1 - x, 1 - y)`. These form the
//! Klein four-group, so composing states is an `xor` of their codes.

/// Largest supported order (cells per side `2^32`; indices fit in `u64`).
pub const MAX_ORDER: u32 = 32;

/// Cell of Hilbert index `d` on the grid of order `order` (`d < 4^order`).
///
/// Bit-parallel formulation (Warren, "Hacker's Delight", 2nd ed., 16-2): one loop step
/// per level, no tables.
#[inline]
pub fn d2xy(order: u32, d: u64) -> (u32, u32) {
    debug_assert!(order <= MAX_ORDER);
    let (mut x, mut y) = (0u64, 0u64);
    let mut t = d;
    let mut s = 1u64;
    for _ in 0..order {
        let rx = 1 & (t >> 1);
        let ry = 1 & (t ^ rx);
        if ry == 0 {
            if rx == 1 {
                x = s - 1 - x;
                y = s - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        x += s * rx;
        y += s * ry;
        t >>= 2;
        s <<= 1;
    }
    (x as u32, y as u32)
}

/// Hilbert index of cell `(x, y)` on the grid of order `order` (inverse of [`d2xy`]).
#[inline]
pub fn xy2d(order: u32, x: u32, y: u32) -> u64 {
    debug_assert!(order <= MAX_ORDER);
    let (mut x, mut y) = (x as u64, y as u64);
    let mut d = 0u64;
    let last = if order == 0 { 0 } else { (1u64 << order) - 1 };
    let mut s = if order == 0 { 0 } else { 1u64 << (order - 1) };
    while s > 0 {
        let rx = ((x & s) > 0) as u64;
        let ry = ((y & s) > 0) as u64;
        d += s * s * ((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                x = last - x;
                y = last - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s >>= 1;
    }
    d
}

/// Orientation of a quadtree node of the Hilbert curve (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct State(pub u8);

/// Canonical order-1 visiting pattern (state 0).
const PATTERN: [(u8, u8); 4] = [(0, 0), (0, 1), (1, 1), (1, 0)];
/// State of each child of a state-0 node, by visiting rank.
const CHILD: [u8; 4] = [1, 0, 0, 2];

/// Quadrant `(qx, qy)` visited at `rank` by a node in `state`, and that child's state,
/// for every state and rank.
const TABLE: [[(u8, u8, u8); 4]; 4] = build_table();

const fn apply(state: u8, (x, y): (u8, u8)) -> (u8, u8) {
    match state {
        0 => (x, y),
        1 => (y, x),
        2 => (1 - y, 1 - x),
        _ => (1 - x, 1 - y),
    }
}

const fn build_table() -> [[(u8, u8, u8); 4]; 4] {
    let mut t = [[(0u8, 0u8, 0u8); 4]; 4];
    let mut s = 0;
    while s < 4 {
        let mut r = 0;
        while r < 4 {
            let (qx, qy) = apply(s as u8, PATTERN[r]);
            t[s][r] = (qx, qy, s as u8 ^ CHILD[r]);
            r += 1;
        }
        s += 1;
    }
    t
}

/// For each state, the visiting rank of quadrant `(qx, qy)` at index `qx + 2 qy`.
const RANK: [[u8; 4]; 4] = build_rank();

const fn build_rank() -> [[u8; 4]; 4] {
    let mut out = [[0u8; 4]; 4];
    let mut s = 0;
    while s < 4 {
        let mut r = 0;
        while r < 4 {
            let (qx, qy, _) = TABLE[s][r];
            out[s][(qx + 2 * qy) as usize] = r as u8;
            r += 1;
        }
        s += 1;
    }
    out
}

impl State {
    /// The root state of the curve of [`d2xy`].
    pub const ROOT: State = State(0);

    /// The child visited at `rank` (0..4): its quadrant `(qx, qy)` in `{0, 1}^2` and
    /// its state.
    #[inline]
    pub fn child(self, rank: u8) -> (u8, u8, State) {
        let (qx, qy, s) = TABLE[self.0 as usize][rank as usize];
        (qx, qy, State(s))
    }

    /// The visiting rank of quadrant `(qx, qy)`.
    #[inline]
    pub fn rank_of(self, qx: u8, qy: u8) -> u8 {
        RANK[self.0 as usize][(qx + 2 * qy) as usize]
    }
}

/// Two levels at once: for each state and 4-bit pair of ranks (first rank in the high
/// bits), the 2-bit column and row offsets and the state after both levels.
const TABLE2: [[(u8, u8, u8); 16]; 4] = build_table2();

const fn build_table2() -> [[(u8, u8, u8); 16]; 4] {
    let mut t = [[(0u8, 0u8, 0u8); 16]; 4];
    let mut s = 0;
    while s < 4 {
        let mut r = 0;
        while r < 16 {
            let (x1, y1, s1) = TABLE[s][r >> 2];
            let (x2, y2, s2) = TABLE[s1 as usize][r & 3];
            t[s][r] = (2 * x1 + x2, 2 * y1 + y2, s2);
            r += 1;
        }
        s += 1;
    }
    t
}

/// Four levels at once: for each state and 8-bit group of four ranks (first rank in the
/// high bits), packed as `dx | dy << 4 | state << 8` (4-bit column and row offsets).
const TABLE4: [[u16; 256]; 4] = build_table4();

const fn build_table4() -> [[u16; 256]; 4] {
    let mut t = [[0u16; 256]; 4];
    let mut s = 0;
    while s < 4 {
        let mut r = 0;
        while r < 256 {
            let (x1, y1, s1) = TABLE2[s][r >> 4];
            let (x2, y2, s2) = TABLE2[s1 as usize][r & 15];
            let (x, y) = ((4 * x1 + x2) as u16, (4 * y1 + y2) as u16);
            t[s][r] = x | (y << 4) | ((s2 as u16) << 8);
            r += 1;
        }
        s += 1;
    }
    t
}

/// Continuous Hilbert map inside a node: the point at curve parameter `t` in `[0, 1)`
/// of the node in `state`, in the node's own unit square, resolved to `levels` levels
/// and placed at the centre of the final sub-cell (at `2^-levels` of the node's size
/// the remaining fraction no longer matters). Steigleder and McCool's generalized
/// stratified sampling maps stratified 1D values through exactly this map. Walks four
/// levels per table look-up (see [`cell_in_node`]); `levels` is at most 26 (52 bits of
/// `t`).
#[inline]
pub fn point_in_node(state: State, t: f64, levels: u32) -> (f64, f64) {
    let (x, y) = cell_in_node(state, t, levels);
    let inv = pow2_neg(levels);
    ((x as f64 + 0.5) * inv, (y as f64 + 0.5) * inv)
}

/// The sub-cell `(x, y)` (each below `2^levels`) of the node in `state` that the
/// continuous Hilbert map reaches at `t` in `[0, 1)`, resolved to `levels` levels:
/// [`point_in_node`] without the conversion to coordinates, for callers that place the
/// sub-cell in a larger grid. Walks four levels per table look-up (the index padded to
/// a multiple of four levels, the padding levels dropped from the cell at the end: the
/// curve is hierarchical); `levels` is at most 26 (52 bits of `t`).
#[inline]
pub fn cell_in_node(state: State, t: f64, levels: u32) -> (u64, u64) {
    debug_assert!((0.0..=1.0).contains(&t) && levels <= 26);
    // The first 2 * levels bits of t, as an integer index along the sub-curve.
    let bits = 2 * levels;
    // Signed conversion: one instruction on x86-64 (values stay below 2^53); 2^bits
    // built from its exponent.
    let d = ((t * pow2(bits)) as i64).min((1i64 << bits) - 1) as u64;
    let chunks = levels.div_ceil(4);
    let pad = 4 * chunks - levels;
    let (x, y) = walk_chunks(state, d << (2 * pad), chunks);
    (x >> pad, y >> pad)
}

/// The walk of [`cell_in_node`] from index `d`, `chunks` groups of four levels (the
/// first in the highest of its `8 * chunks` bits): the sub-cell at `4 * chunks`
/// levels, before the padding levels are dropped.
#[inline(always)]
pub(crate) fn walk_chunks(state: State, d: u64, chunks: u32) -> (u64, u64) {
    let mut s = state.0 as usize;
    let (mut x, mut y) = (0u64, 0u64);
    for c in (0..chunks).rev() {
        // States are 0..4: the mask spares the bounds check.
        let e = TABLE4[s & 3][((d >> (8 * c)) & 255) as usize];
        x = (x << 4) | (e & 15) as u64;
        y = (y << 4) | ((e >> 4) & 15) as u64;
        s = (e >> 8) as usize;
    }
    (x, y)
}

/// `2^k` for `k <= 1023`, built from its exponent bits (no conversion, no division).
#[inline(always)]
pub(crate) fn pow2(k: u32) -> f64 {
    f64::from_bits((1023 + k as u64) << 52)
}

/// `2^-k` for `k <= 1022`, built from its exponent bits.
#[inline(always)]
pub(crate) fn pow2_neg(k: u32) -> f64 {
    f64::from_bits((1023 - k as u64) << 52)
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// Walks the state machine top-down for index `d` at `order`.
    fn d2xy_states(order: u32, d: u64) -> (u32, u32) {
        let (mut x, mut y) = (0u32, 0u32);
        let mut s = State::ROOT;
        for level in (0..order).rev() {
            let rank = ((d >> (2 * level)) & 3) as u8;
            let (qx, qy, next) = s.child(rank);
            x = 2 * x + qx as u32;
            y = 2 * y + qy as u32;
            s = next;
        }
        (x, y)
    }

    #[test]
    fn order_one_pattern() {
        let cells: Vec<_> = (0..4).map(|d| d2xy(1, d)).collect();
        assert_eq!(cells, vec![(0, 0), (0, 1), (1, 1), (1, 0)]);
    }

    #[test]
    fn bijection_and_adjacency_orders_1_to_12() {
        for order in 1..=12u32 {
            let n = 1u64 << (2 * order);
            // Exhaustive up to order 8, sampled above (4^12 = 16M cells).
            let step = if order <= 8 { 1 } else { 997 };
            let mut seen = vec![false; if order <= 8 { n as usize } else { 0 }];
            let mut d = 0;
            while d < n {
                let (x, y) = d2xy(order, d);
                assert!(x < (1 << order) && y < (1 << order));
                assert_eq!(xy2d(order, x, y), d, "order {order} d {d}");
                assert_eq!(
                    d2xy_states(order, d),
                    (x, y),
                    "state machine, order {order} d {d}"
                );
                if order <= 8 {
                    assert!(!seen[(y as u64 * (1 << order) + x as u64) as usize]);
                    seen[(y as u64 * (1 << order) + x as u64) as usize] = true;
                }
                if d + 1 < n {
                    let (x2, y2) = d2xy(order, d + 1);
                    assert_eq!(x.abs_diff(x2) + y.abs_diff(y2), 1, "order {order} d {d}");
                }
                d += step;
            }
            assert!(seen.iter().all(|&s| s));
        }
    }

    #[test]
    fn rank_of_inverts_child() {
        for s in 0..4u8 {
            for r in 0..4u8 {
                let (qx, qy, _) = State(s).child(r);
                assert_eq!(State(s).rank_of(qx, qy), r);
            }
        }
    }

    #[test]
    fn continuous_map_matches_d2xy_at_every_depth() {
        for levels in 1..=13u32 {
            let n = 1u64 << (2 * levels);
            let step = (n / 5000).max(1);
            let mut d = 0;
            while d < n {
                let t = (d as f64 + 0.5) / n as f64;
                let (x, y) = point_in_node(State::ROOT, t, levels);
                let (cx, cy) = d2xy(levels, d);
                let side = (1u64 << levels) as f64;
                assert_eq!(
                    ((x * side) as u32, (y * side) as u32),
                    (cx, cy),
                    "levels {levels} d {d}"
                );
                d += step;
            }
        }
    }

    #[test]
    fn four_level_walk_matches_one_level_at_a_time() {
        // Reference: one rank (two bits of t) per level through the state machine.
        let reference = |state: State, t: f64, levels: u32| {
            let bits = 2 * levels;
            let d = ((t * (1u64 << bits) as f64) as u64).min((1u64 << bits) - 1);
            let (mut x, mut y, mut s) = (0u64, 0u64, state);
            for l in (0..levels).rev() {
                let (qx, qy, next) = s.child(((d >> (2 * l)) & 3) as u8);
                x = 2 * x + qx as u64;
                y = 2 * y + qy as u64;
                s = next;
            }
            let inv = 1.0 / (1u64 << levels) as f64;
            ((x as f64 + 0.5) * inv, (y as f64 + 0.5) * inv)
        };
        let mut rng = crate::rng::Rng::new(5, 0);
        for state in 0..4u8 {
            for levels in 0..=26u32 {
                for _ in 0..200 {
                    let t = rng.next_f64();
                    assert_eq!(
                        point_in_node(State(state), t, levels),
                        reference(State(state), t, levels),
                        "state {state} levels {levels} t {t}"
                    );
                }
            }
        }
    }

    #[test]
    fn continuous_map_is_monotone_along_curve() {
        // Points for increasing t visit cells in Hilbert order.
        let order = 6;
        let mut last = 0;
        for k in 0..4096 {
            let t = (k as f64 + 0.5) / 4096.0;
            let (x, y) = point_in_node(State::ROOT, t, 10);
            let d = xy2d(order, (x * 64.0) as u32, (y * 64.0) as u32);
            assert!(d >= last);
            last = d;
        }
    }

    proptest! {
        #[test]
        fn bijection_high_orders(order in 13u32..=32, raw in any::<u64>()) {
            let d = if order == 32 { raw } else { raw % (1u64 << (2 * order)) };
            let (x, y) = d2xy(order, d);
            prop_assert_eq!(xy2d(order, x, y), d);
            prop_assert_eq!(d2xy_states(order, d), (x, y));
            let n = if order == 32 { u64::MAX } else { (1u64 << (2 * order)) - 1 };
            if d < n {
                let (x2, y2) = d2xy(order, d + 1);
                prop_assert_eq!(x.abs_diff(x2) + y.abs_diff(y2), 1);
            }
        }
    }
}
