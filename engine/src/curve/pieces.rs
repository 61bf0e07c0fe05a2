//! The pieces of a boundary-leaf descent: each candidate triangle's part of the
//! current node as a convex polygon with its area and exact measure ([`PieceSet`]),
//! split along a midline in one pass, and [`LeafScratch`], the caller-owned memory of
//! the descent with its cache of the last leaf's clipped pieces.

use glam::DVec2;

use super::clip::Poly;
use super::segment_curve::SegmentCurve;

/// Most candidate triangles of a boundary leaf that the polygon-splitting descent
/// handles (more take the general descent; 99.9% of the bunny's boundary leaves have
/// at most 6).
pub(super) const PIECES: usize = 6;

/// Scratch memory of the exact descent through boundary leaves
/// ([`SegmentCurve::point_in_leaf_with`]), with a cache of the last boundary leaf's
/// candidate triangles clipped to it (consecutive values often fall in one leaf).
///
/// Contract: the cache is keyed by the leaf and by the curve it was filled for, which
/// the scratch borrows for its lifetime `'a`. While the scratch exists that curve can
/// be neither dropped, moved nor changed, so its address names it and no other curve
/// can take that address. One scratch may therefore be reused across leaves and
/// curves (any borrowed for `'a`) without being reset, and the points never depend on
/// what it holds: a hit gives the points of a fresh scratch. A clone of a curve is
/// another curve to the cache (a miss, the same points). There is no global state.
///
/// ```
/// use glam::DVec2;
/// use strata_engine::curve::{CurveDomain, CurveOptions, LeafScratch, SegmentCurve};
///
/// let options = CurveOptions { max_cell_share: 0.01, boundary_level: 4, ..Default::default() };
/// let triangle = |uv: &[DVec2]| {
///     let corner_density = &[[1.0, 5.0, 1.0]];
///     let domain = CurveDomain { uv, triangles: &[[0, 1, 2]], corner_density };
///     SegmentCurve::build(&domain, &options)
/// };
/// let a = triangle(&[DVec2::ZERO, DVec2::new(0.9, 0.1), DVec2::new(0.2, 0.8)])?;
/// let b = triangle(&[DVec2::new(0.1, 0.0), DVec2::new(1.0, 0.3), DVec2::new(0.0, 0.9)])?;
/// let boundary = |c: &SegmentCurve, i: usize| !c.cells()[i].full();
/// let leaf = (0..a.cell_count().min(b.cell_count()))
///     .find(|&i| boundary(&a, i) && boundary(&b, i))
///     .expect("a boundary leaf in both");
/// let mut scratch = LeafScratch::default();
/// // The same leaf index in two curves, revisited: the cache tells them apart.
/// for curve in [&a, &b, &a] {
///     let fresh = curve.point_in_leaf_to(leaf, 0.3, 3);
///     assert_eq!(curve.point_in_leaf_with(leaf, 0.3, 3, &mut scratch), fresh);
/// }
/// # Ok::<(), strata_engine::curve::CurveError>(())
/// ```
///
/// The borrow is what makes the key sound: a scratch cannot outlive a curve it was
/// filled for.
///
/// ```compile_fail,E0597
/// # use glam::DVec2;
/// # use strata_engine::curve::{CurveDomain, CurveOptions, LeafScratch, SegmentCurve};
/// # let uv = [DVec2::ZERO, DVec2::new(0.9, 0.1), DVec2::new(0.2, 0.8)];
/// # let domain = CurveDomain { uv: &uv, triangles: &[[0, 1, 2]], corner_density: &[[1.0; 3]] };
/// let mut scratch = LeafScratch::default();
/// {
///     let curve = SegmentCurve::build(&domain, &CurveOptions::default()).expect("valid");
///     curve.point_in_leaf_with(0, 0.5, 0, &mut scratch);
/// } // `curve` dropped here while `scratch` still borrows it
/// drop(scratch);
/// ```
#[derive(Clone)]
pub struct LeafScratch<'a> {
    pub(super) bufs: [PieceSet; 3],
    /// The candidates of leaf `root_of.1` of curve `root_of.0`, clipped to the leaf.
    pub(super) root: PieceSet,
    /// `root` split by the leaf's first cut: below and above the midline.
    pub(super) halves: [PieceSet; 2],
    /// Whether `halves` holds the cut of `root`.
    pub(super) halves_ready: bool,
    pub(super) root_of: Option<(&'a SegmentCurve, usize)>,
}

impl LeafScratch<'_> {
    /// Whether `root` holds the candidates of leaf `leaf` of `curve`: the same curve
    /// (by address, see the type's contract) and the same leaf.
    #[inline]
    pub(crate) fn holds(&self, curve: &SegmentCurve, leaf: usize) -> bool {
        matches!(self.root_of, Some((c, l)) if std::ptr::eq(c, curve) && l == leaf)
    }
}

impl Default for LeafScratch<'_> {
    fn default() -> Self {
        Self {
            bufs: [PieceSet::EMPTY; 3],
            root: PieceSet::EMPTY,
            halves: [PieceSet::EMPTY; 2],
            halves_ready: false,
            root_of: None,
        }
    }
}

impl std::fmt::Debug for LeafScratch<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LeafScratch")
    }
}

/// A candidate triangle's part of the current node in a boundary-leaf descent.
#[derive(Clone, Copy)]
pub(super) struct Piece {
    pub(super) tri: u32,
    pub(super) poly: Poly,
    pub(super) area: f64,
    pub(super) measure: f64,
}

/// The non-empty pieces of one node, with their total measure and area.
#[derive(Clone, Copy)]
pub(super) struct PieceSet {
    pub(super) pieces: [Piece; PIECES],
    pub(super) len: usize,
    pub(super) measure: f64,
    pub(super) area: f64,
}

impl PieceSet {
    const EMPTY: PieceSet = PieceSet {
        pieces: [Piece {
            tri: 0,
            poly: Poly::EMPTY,
            area: 0.0,
            measure: 0.0,
        }; PIECES],
        len: 0,
        measure: 0.0,
        area: 0.0,
    };

    pub(super) fn clear(&mut self) {
        self.len = 0;
        self.measure = 0.0;
        self.area = 0.0;
    }

    /// Adds the part `poly` of triangle `tri` if it has positive area.
    #[inline]
    pub(super) fn add(&mut self, curve: &SegmentCurve, tri: u32, poly: Poly) {
        if self.len < PIECES {
            self.pieces[self.len].poly = poly;
            let _ = self.commit(curve, tri);
        }
    }

    /// Keeps the polygon written into the next free piece if it has positive area;
    /// returns the area and measure kept (zero when not kept).
    #[inline]
    fn commit(&mut self, curve: &SegmentCurve, tri: u32) -> (f64, f64) {
        let piece = &mut self.pieces[self.len];
        let (area, moment) = piece.poly.area_moment();
        if area > 0.0 {
            let measure = curve.part_measure(tri, area, moment);
            piece.tri = tri;
            piece.area = area;
            piece.measure = measure;
            self.len += 1;
            self.measure += measure;
            self.area += area;
            (area, measure)
        } else {
            (0.0, 0.0)
        }
    }

    /// Keeps the polygon written into the next free piece, the rest of `whole` after a
    /// split, with the given area and measure, if both its polygon and its area are
    /// non-degenerate.
    #[inline]
    fn commit_rest(&mut self, whole: &Piece, area: f64, measure: f64) {
        let piece = &mut self.pieces[self.len];
        if area > 0.0 && piece.poly.points().len() >= 3 {
            let measure = measure.max(0.0);
            piece.tri = whole.tri;
            piece.area = area;
            piece.measure = measure;
            self.len += 1;
            self.measure += measure;
            self.area += area;
        }
    }

    #[inline]
    fn keep(&mut self, piece: &Piece) {
        // At most one piece per candidate, and candidates are at most PIECES.
        if self.len < PIECES {
            self.pieces[self.len] = *piece;
            self.len += 1;
            self.measure += piece.measure;
            self.area += piece.area;
        }
    }

    /// Splits every piece by the line where coordinate `AXIS` (0: x, 1: y) is `at`
    /// into `below` and `above`; pieces on one side move whole, keeping their measure.
    #[inline]
    pub(super) fn split<const AXIS: usize>(
        &self,
        curve: &SegmentCurve,
        at: f64,
        below: &mut PieceSet,
        above: &mut PieceSet,
    ) {
        below.clear();
        above.clear();
        for piece in &self.pieces[..self.len] {
            let coord = |p: &DVec2| if AXIS == 0 { p.x } else { p.y };
            let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
            // Plain comparisons: `f64::min`/`max` pay for NaN handling the corners
            // (finite) do not need.
            for p in piece.poly.points() {
                let c = coord(p);
                if c < mn {
                    mn = c;
                }
                if c > mx {
                    mx = c;
                }
            }
            if mx <= at {
                below.keep(piece);
            } else if mn >= at {
                above.keep(piece);
            } else {
                // Both sets hold fewer pieces than this one: room for one more each.
                let (b, a) = (below.len, above.len);
                piece.poly.split_into::<AXIS>(
                    at,
                    &mut below.pieces[b].poly,
                    &mut above.pieces[a].poly,
                );
                // The part above gets the rest of the piece's area and measure (the
                // measure is linear in the polygon): one polygon integral, not two.
                let (area, measure) = below.commit(curve, piece.tri);
                above.commit_rest(piece, piece.area - area, piece.measure - measure);
            }
        }
    }

    /// The triangles of the pieces.
    pub(super) fn triangles(&self) -> ([u32; PIECES], usize) {
        let mut ids = [0u32; PIECES];
        for (id, piece) in ids.iter_mut().zip(&self.pieces[..self.len]) {
            *id = piece.tri;
        }
        (ids, self.len)
    }
}
