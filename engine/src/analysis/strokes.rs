//! Coverage of the unit square by brush strokes (paper section 7.1, Fig. 3, as a
//! measurement).
//!
//! Input: [`Stroke`]s, oriented rectangles given by centre, unit direction, length and
//! width (usually made from samples by [`strokes_from_samples`]). Output: a
//! [`StrokeRaster`] (strokes per pixel on an `n x n` grid over `[0, 1]^2`) and its
//! [`Coverage`]: the covered fraction, the mean overlap and the radius of the largest
//! hole.
//!
//! - A pixel counts a stroke if its centre `((i + 1/2) / n, (j + 1/2) / n)` lies in the
//!   closed rectangle (exact test in the stroke's frame). Parts of strokes outside the
//!   square are ignored.
//! - The largest hole is the largest distance from an uncovered pixel centre to the
//!   nearest covered pixel centre: the radius of the largest disc, centred on a pixel,
//!   that holds no covered pixel centre. The square's border does not count as covered,
//!   so a hole at the border is not cut short by it. Computed exactly on the raster by a
//!   Euclidean distance transform (Felzenszwalb and Huttenlocher, "Distance transforms of
//!   sampled functions", Theory of Computing 2012): 1D squared distances along rows,
//!   then along columns.
//!
//! Cost: rasterising visits, per stroke and per pixel row it crosses, the pixels of the
//! row's exact span plus at most two, so O(total stroke area x n^2 + rows); the distance
//! transform is O(n^2), parallel over rows (each row is independent, so the result does
//! not depend on the thread count). Memory: 4 bytes per pixel for the raster, 16 more
//! during [`StrokeRaster::coverage`].

use rayon::prelude::*;

use crate::rng;

/// The largest raster side accepted (`8192^2` pixels take about 1.3 GB while the
/// distance transform runs).
pub const MAX_RASTER: usize = 8192;

/// Stream of the size variation in [`strokes_from_samples`].
const STREAM_STROKE_SIZE: u64 = 0xa11a_0400;

/// What can go wrong rasterising strokes.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StrokeError {
    /// A stroke's centre is not finite.
    #[error("stroke {index} has a non-finite centre")]
    NonFiniteCentre {
        /// Index of the stroke (or sample).
        index: usize,
    },
    /// A stroke's direction is not finite or has zero length.
    #[error("stroke {index} has a zero or non-finite direction")]
    BadDirection {
        /// Index of the stroke (or sample).
        index: usize,
    },
    /// A stroke's length or width is not finite and positive.
    #[error(
        "stroke {index} has length {length} and width {width}; both must be finite and positive"
    )]
    BadSize {
        /// Index of the stroke.
        index: usize,
        /// Its length.
        length: f64,
        /// Its width.
        width: f64,
    },
    /// The raster side is 0 or above [`MAX_RASTER`].
    #[error("raster side {size} must be in 1..={MAX_RASTER}")]
    BadRaster {
        /// The side asked for.
        size: usize,
    },
    /// More strokes than a pixel count can hold.
    #[error("{count} strokes are more than a u32 pixel count can hold")]
    TooManyStrokes {
        /// Number of strokes given.
        count: usize,
    },
    /// A [`StrokeStyle`] field is out of range.
    #[error("stroke style {name} = {value} is out of range")]
    BadStyle {
        /// The field.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// [`strokes_from_samples`] was given a different number of directions than positions.
    #[error("{positions} positions but {directions} directions")]
    LengthMismatch {
        /// Number of positions.
        positions: usize,
        /// Number of directions.
        directions: usize,
    },
}

/// A brush stroke: the closed rectangle of `length` along `direction` and `width` across
/// it, centred on `centre` (unit-square coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Stroke {
    /// Centre.
    pub centre: [f64; 2],
    /// Unit direction of the length.
    pub direction: [f64; 2],
    /// Extent along `direction`.
    pub length: f64,
    /// Extent across `direction`.
    pub width: f64,
}

impl Stroke {
    /// A stroke with `direction` normalised.
    ///
    /// # Errors
    /// [`StrokeError::NonFiniteCentre`], [`StrokeError::BadDirection`] or
    /// [`StrokeError::BadSize`] (with index 0).
    pub fn new(
        centre: [f64; 2],
        direction: [f64; 2],
        length: f64,
        width: f64,
    ) -> Result<Self, StrokeError> {
        let norm = direction[0].hypot(direction[1]);
        if !(norm.is_finite() && norm > 0.0) {
            return Err(StrokeError::BadDirection { index: 0 });
        }
        let s = Self {
            centre,
            direction: [direction[0] / norm, direction[1] / norm],
            length,
            width,
        };
        s.validate(0)?;
        Ok(s)
    }

    /// A stroke at angle `angle` (radians, counter-clockwise from +x).
    ///
    /// # Errors
    /// As [`Stroke::new`].
    pub fn with_angle(
        centre: [f64; 2],
        angle: f64,
        length: f64,
        width: f64,
    ) -> Result<Self, StrokeError> {
        Self::new(centre, [angle.cos(), angle.sin()], length, width)
    }

    /// Checks the stroke, reporting it as stroke `index`.
    ///
    /// # Errors
    /// [`StrokeError::NonFiniteCentre`]; [`StrokeError::BadDirection`] if the direction
    /// is not unit length within 1e-9; [`StrokeError::BadSize`].
    pub fn validate(&self, index: usize) -> Result<(), StrokeError> {
        if !(self.centre[0].is_finite() && self.centre[1].is_finite()) {
            return Err(StrokeError::NonFiniteCentre { index });
        }
        let norm = self.direction[0].hypot(self.direction[1]);
        if !((norm - 1.0).abs() <= 1e-9) {
            return Err(StrokeError::BadDirection { index });
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(positive(self.length) && positive(self.width)) {
            return Err(StrokeError::BadSize {
                index,
                length: self.length,
                width: self.width,
            });
        }
        Ok(())
    }

    /// Whether point `p` lies in the closed rectangle.
    #[inline]
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let (dx, dy) = (p[0] - self.centre[0], p[1] - self.centre[1]);
        let [ux, uy] = self.direction;
        let along = dx * ux + dy * uy;
        let across = dy * ux - dx * uy;
        along.abs() <= 0.5 * self.length && across.abs() <= 0.5 * self.width
    }

    /// Area, `length * width`.
    pub fn area(&self) -> f64 {
        self.length * self.width
    }

    /// The x range of the rectangle on the horizontal line at height `y` (empty when
    /// `lo > hi`), before rounding: the intersection of the two slabs.
    fn span_at(&self, y: f64) -> (f64, f64) {
        let [ux, uy] = self.direction;
        let dy = y - self.centre[1];
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        // |dx * a + dy * b| <= h for the slabs (a, b, h) along and across the stroke.
        for (a, b, h) in [(ux, uy, 0.5 * self.length), (-uy, ux, 0.5 * self.width)] {
            let c = dy * b;
            if a == 0.0 {
                if c.abs() > h {
                    return (1.0, 0.0);
                }
            } else {
                let (t0, t1) = ((-h - c) / a, (h - c) / a);
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
        }
        (self.centre[0] + lo, self.centre[0] + hi)
    }
}

/// Size and size variation of the strokes made by [`strokes_from_samples`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StrokeStyle {
    /// Length before variation, positive.
    pub length: f64,
    /// Width before variation, positive.
    pub width: f64,
    /// Relative size variation `v` in `[0, 1)`: each stroke is scaled (length and width
    /// alike, so the aspect ratio is kept) by a factor uniform in `[1 - v, 1 + v]`.
    pub variation: f64,
}

impl StrokeStyle {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`StrokeError::BadStyle`] for the first field out of range.
    pub fn validate(&self) -> Result<(), StrokeError> {
        let bad = |name, value| Err(StrokeError::BadStyle { name, value });
        if !(self.length.is_finite() && self.length > 0.0) {
            return bad("length", self.length);
        }
        if !(self.width.is_finite() && self.width > 0.0) {
            return bad("width", self.width);
        }
        if !(0.0..1.0).contains(&self.variation) {
            return bad("variation", self.variation);
        }
        Ok(())
    }

    /// The size factor of sample `index` for `seed`: uniform in `[1 - v, 1 + v]`, a pure
    /// function of `(seed, index)`.
    pub fn factor(&self, seed: u64, index: usize) -> f64 {
        let u = rng::uniform(seed, STREAM_STROKE_SIZE, index as u64);
        1.0 + self.variation * (2.0 * u - 1.0)
    }
}

/// One stroke per sample: centred on `positions[k]`, along `directions[k]` (normalised
/// here), of `style`'s size times [`StrokeStyle::factor`]`(seed, k)`.
///
/// # Errors
/// [`StrokeError::LengthMismatch`], [`StrokeError::BadStyle`], and the errors of
/// [`Stroke::validate`] with the sample's index.
///
/// # Example
/// ```
/// use strata_engine::analysis::strokes::{StrokeStyle, coverage, strokes_from_samples};
/// let style = StrokeStyle { length: 0.5, width: 0.5, variation: 0.0 };
/// let strokes = strokes_from_samples(&[[0.25, 0.5], [0.75, 0.5]], &[[1.0, 0.0]; 2], &style, 1)?;
/// let c = coverage(&strokes, 64)?;
/// assert_eq!((c.covered_fraction, c.mean_overlap), (0.5, 1.0));
/// # Ok::<(), strata_engine::analysis::strokes::StrokeError>(())
/// ```
pub fn strokes_from_samples(
    positions: &[[f64; 2]],
    directions: &[[f64; 2]],
    style: &StrokeStyle,
    seed: u64,
) -> Result<Vec<Stroke>, StrokeError> {
    if positions.len() != directions.len() {
        return Err(StrokeError::LengthMismatch {
            positions: positions.len(),
            directions: directions.len(),
        });
    }
    style.validate()?;
    positions
        .iter()
        .zip(directions)
        .enumerate()
        .map(|(index, (&centre, &d))| {
            let norm = d[0].hypot(d[1]);
            if !(norm.is_finite() && norm > 0.0) {
                return Err(StrokeError::BadDirection { index });
            }
            let f = style.factor(seed, index);
            let s = Stroke {
                centre,
                direction: [d[0] / norm, d[1] / norm],
                length: style.length * f,
                width: style.width * f,
            };
            s.validate(index)?;
            Ok(s)
        })
        .collect()
}

/// Strokes per pixel on an `n x n` grid over `[0, 1]^2`.
#[derive(Clone, Debug, PartialEq)]
pub struct StrokeRaster {
    /// Side `n`.
    pub size: usize,
    /// Row-major counts; entry `j n + i` is the pixel with centre
    /// `((i + 1/2) / n, (j + 1/2) / n)`.
    pub counts: Vec<u32>,
}

/// The coverage of the unit square by a set of strokes, on a raster.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Coverage {
    /// Pixels under at least one stroke over all pixels.
    pub covered_fraction: f64,
    /// Strokes per covered pixel (0 when no pixel is covered).
    pub mean_overlap: f64,
    /// Radius of the largest hole in unit-square lengths: the largest distance from an
    /// uncovered pixel centre to the nearest covered one (0 when every pixel is covered,
    /// infinite when none is). Divide by the mean spacing to compare point sets.
    pub largest_hole: f64,
}

/// Counts, for each pixel of an `n x n` raster of `[0, 1]^2`, the strokes whose closed
/// rectangle holds the pixel centre.
///
/// # Errors
/// [`StrokeError::BadRaster`] if `n` is 0 or above [`MAX_RASTER`],
/// [`StrokeError::TooManyStrokes`], and the first error of [`Stroke::validate`].
pub fn rasterise(strokes: &[Stroke], n: usize) -> Result<StrokeRaster, StrokeError> {
    if n == 0 || n > MAX_RASTER {
        return Err(StrokeError::BadRaster { size: n });
    }
    if u32::try_from(strokes.len()).is_err() {
        return Err(StrokeError::TooManyStrokes {
            count: strokes.len(),
        });
    }
    for (index, s) in strokes.iter().enumerate() {
        s.validate(index)?;
    }
    let mut counts = vec![0u32; n * n];
    let nf = n as f64;
    let last = (n - 1) as f64;
    // Pixel index range [lo, hi] whose centres (k + 1/2) / n lie in [a, b], widened by
    // one pixel on each side against rounding (the exact test decides).
    let pixels = |a: f64, b: f64| -> Option<(usize, usize)> {
        let lo = (a * nf - 0.5).ceil() - 1.0;
        let hi = (b * nf - 0.5).floor() + 1.0;
        if hi < 0.0 || lo > last || lo > hi {
            return None;
        }
        Some((lo.max(0.0) as usize, hi.min(last) as usize))
    };
    for s in strokes {
        let [ux, uy] = s.direction;
        let ey = 0.5 * (s.length * uy.abs() + s.width * ux.abs());
        let Some((j0, j1)) = pixels(s.centre[1] - ey, s.centre[1] + ey) else {
            continue;
        };
        for j in j0..=j1 {
            let y = (j as f64 + 0.5) / nf;
            let (a, b) = s.span_at(y);
            let Some((i0, i1)) = pixels(a, b) else {
                continue;
            };
            let row = &mut counts[j * n..(j + 1) * n];
            for (i, c) in row.iter_mut().enumerate().take(i1 + 1).skip(i0) {
                if s.contains([(i as f64 + 0.5) / nf, y]) {
                    *c += 1;
                }
            }
        }
    }
    Ok(StrokeRaster { size: n, counts })
}

/// [`rasterise`] then [`StrokeRaster::coverage`].
///
/// # Errors
/// As [`rasterise`].
pub fn coverage(strokes: &[Stroke], n: usize) -> Result<Coverage, StrokeError> {
    Ok(rasterise(strokes, n)?.coverage())
}

impl StrokeRaster {
    /// Covered fraction, mean overlap and largest hole (see [`Coverage`]).
    pub fn coverage(&self) -> Coverage {
        let n = self.size;
        let covered = self.counts.iter().filter(|&&c| c > 0).count();
        let total: u64 = self.counts.iter().map(|&c| u64::from(c)).sum();
        let pixels = (n * n) as f64;
        Coverage {
            covered_fraction: covered as f64 / pixels,
            mean_overlap: if covered == 0 {
                0.0
            } else {
                total as f64 / covered as f64
            },
            largest_hole: if covered == 0 {
                f64::INFINITY
            } else {
                self.largest_hole_pixels().sqrt() / n as f64
            },
        }
    }

    /// The largest squared distance, in pixels, from an uncovered pixel to the nearest
    /// covered one (a 2D squared Euclidean distance transform, one row pass, a transpose,
    /// one more row pass).
    fn largest_hole_pixels(&self) -> f64 {
        let n = self.size;
        let mut rows: Vec<f64> = self
            .counts
            .iter()
            .map(|&c| if c > 0 { 0.0 } else { f64::INFINITY })
            .collect();
        rows.par_chunks_mut(n)
            .for_each_init(|| Envelope::new(n), |env, row| env.transform(row));
        let mut cols = vec![0.0; n * n];
        cols.par_chunks_mut(n).enumerate().for_each(|(i, col)| {
            for (j, v) in col.iter_mut().enumerate() {
                *v = rows[j * n + i];
            }
        });
        drop(rows);
        cols.par_chunks_mut(n)
            .map_init(
                || Envelope::new(n),
                |env, col| {
                    env.transform(col);
                    col.iter().copied().fold(0.0, f64::max)
                },
            )
            .reduce(|| 0.0, f64::max)
    }
}

/// Scratch of the 1D squared distance transform: the lower envelope of the parabolas
/// `(x - q)^2 + f(q)` over the sites `q` with finite `f(q)`.
struct Envelope {
    /// Sites of the parabolas on the envelope, left to right.
    sites: Vec<usize>,
    /// `bounds[k]..bounds[k + 1]` is where parabola `k` is lowest.
    bounds: Vec<f64>,
    /// A copy of the input (the transform is in place).
    input: Vec<f64>,
}

impl Envelope {
    fn new(n: usize) -> Self {
        Self {
            sites: Vec::with_capacity(n),
            bounds: Vec::with_capacity(n + 1),
            input: Vec::with_capacity(n),
        }
    }

    /// Replaces `f` by `d(x) = min_q (x - q)^2 + f(q)`; infinite sites are no parabola,
    /// so a row without a finite value stays infinite.
    fn transform(&mut self, f: &mut [f64]) {
        self.sites.clear();
        self.bounds.clear();
        self.input.clear();
        self.input.extend_from_slice(f);
        let g = &self.input;
        // Where the parabolas of sites p < q meet.
        let meet = |p: usize, q: usize| {
            let (pf, qf) = (p as f64, q as f64);
            ((g[q] + qf * qf) - (g[p] + pf * pf)) / (2.0 * (qf - pf))
        };
        for q in (0..g.len()).filter(|&q| g[q].is_finite()) {
            let mut s = f64::NEG_INFINITY;
            while let Some(&p) = self.sites.last() {
                s = meet(p, q);
                if s <= self.bounds[self.sites.len() - 1] {
                    self.sites.pop();
                    self.bounds.pop();
                    s = f64::NEG_INFINITY;
                } else {
                    break;
                }
            }
            self.sites.push(q);
            self.bounds.push(s);
        }
        if self.sites.is_empty() {
            return;
        }
        let mut k = 0;
        for (x, out) in f.iter_mut().enumerate() {
            let xf = x as f64;
            while k + 1 < self.sites.len() && self.bounds[k + 1] < xf {
                k += 1;
            }
            let d = xf - self.sites[k] as f64;
            *out = d * d + g[self.sites[k]];
        }
    }
}

#[cfg(test)]
#[path = "strokes_tests.rs"]
mod tests;
