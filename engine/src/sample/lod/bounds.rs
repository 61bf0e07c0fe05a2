//! Upper bounds of a view's multiplier over regions of a mesh, for the level-of-detail
//! pool ([`LodPool`](super::LodPool)): a sphere around a region's faces and a cone
//! around their normals ([`RegionBound`]), and the same bounds stored as columns
//! ([`BoundSet`]) so that one view is checked against thousands of them in a loop
//! without branches, which the compiler turns into vector code.
//!
//! Input: per region, points and unit normals whose convex combinations hold its
//! surface ([`bin_bound`] gives them for a pool's bins); a [`ViewLod`]. Output: per
//! region, an upper bound of [`ViewLod::multiplier`] over every such point and
//! normalised blend of the normals (the pool turns it into the rank `ceil(N bound)` a
//! base count `N` needs there). Cost: O(1) per region and view, no trigonometric call.

use std::ops::Range;

use glam::{DVec3, DVec4, Vec4Swizzles};

use super::view::ViewLod;
#[cfg(target_arch = "x86_64")]
use crate::cpu::Level;
use crate::sample::Sampler;

/// A sphere holding some faces and a cone holding their vertex normals (hence every
/// normal interpolated on them), for an upper bound of a view's multiplier there.
#[derive(Clone, Copy, Debug)]
pub(super) struct RegionBound {
    centre: DVec3,
    radius: f64,
    /// Unit axis of the normal cone.
    axis: DVec3,
    /// Half-angle of the normal cone in radians (pi: no bound).
    spread: f64,
    /// Its cosine and sine.
    spread_cos: f64,
    spread_sin: f64,
}

/// A view made ready to bound many regions: its frustum planes with unit normals
/// (world space), the depth's row and its gradient's length.
pub(super) struct Frustum<'a> {
    view: &'a ViewLod,
    planes: [DVec4; 6],
    depth: DVec4,
    depth_slope: f64,
}

impl<'a> Frustum<'a> {
    /// The frustum of `view`.
    pub(super) fn new(view: &'a ViewLod) -> Self {
        let m = view.clip_from_world;
        let [x, y, z, w] = [m.row(0), m.row(1), m.row(2), m.row(3)];
        // The planes w - x >= 0, w + x >= 0, ..., z >= 0, scaled to unit normals (a
        // degenerate plane keeps its scale: it culls nothing).
        let planes = [w - x, w + x, w - y, w + y, z, w - z].map(|p| {
            let len = p.xyz().length();
            if len > 0.0 { p / len } else { p }
        });
        Self {
            view,
            planes,
            depth: w,
            depth_slope: w.xyz().length(),
        }
    }
}

impl RegionBound {
    /// The bound of points `points` and unit normals `normals` (a zero one leaves the
    /// normals unbounded), the cone's axis fitted by
    /// [`enclosing_axis`] when `fit` ([`AXIS_STEPS`] passes over the normals) or their mean
    /// direction otherwise. The sphere is widened by a millionth of the coordinates'
    /// size, more than the rounding of the points to the `f32` positions a renderer
    /// and the samples' records carry.
    pub(super) fn new(points: &[DVec3], normals: &[DVec3], fit: bool) -> Self {
        let (lo, hi) = points.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let centre = 0.5 * (lo + hi);
        let radius = points
            .iter()
            .map(|p| p.distance(centre))
            .fold(0.0, f64::max);
        let size = lo.abs().max(hi.abs()).max_element();
        let radius = radius + 1e-6 * size;
        let least_to = |axis: DVec3| normals.iter().map(|n| n.dot(axis)).fold(1.0f64, f64::min);
        let mean = normals.iter().sum::<DVec3>().normalize_or_zero();
        let axis = match fit.then(|| enclosing_axis(mean, normals)) {
            Some(fitted) if least_to(fitted) > least_to(mean) => fitted,
            _ => mean,
        };
        // The smallest cosine to the axis; a cone of half-angle under 90 degrees is
        // convex, so it holds every normalised blend of its corner normals too.
        let least = least_to(axis);
        let spread = if axis != DVec3::ZERO && least > 1e-3 {
            // A little slack for the f32 normals a renderer interpolates.
            least.clamp(-1.0, 1.0).acos() + 1e-4
        } else {
            std::f64::consts::PI
        };
        Self {
            centre,
            radius,
            axis,
            spread,
            spread_cos: spread.cos(),
            spread_sin: spread.sin(),
        }
    }
}

/// Steps of [`enclosing_axis`]: on the bunny's bins sixteen give most of what more
/// give (the ranks a pool holds for a view are 1.318 times the visible ones, against
/// 1.314 after 512 steps and 1.364 around the mean normal).
const AXIS_STEPS: u32 = 16;

/// The axis of a narrow cone around unit vectors `normals`, starting from `start`:
/// the centre of their enclosing ball by Badoiu and Clarkson's iteration (each step
/// moves the centre toward the vector farthest from it by `1 / (k + 1)` of the way),
/// normalised. The smallest enclosing ball of unit vectors is nearly the smallest
/// enclosing cone while the cone is narrow, and the mean direction is not: it leans
/// toward where most normals lie, not to the middle of the farthest ones.
fn enclosing_axis(start: DVec3, normals: &[DVec3]) -> DVec3 {
    let mut centre = start;
    for k in 1..=AXIS_STEPS {
        let towards = centre.normalize_or_zero();
        let far = normals
            .iter()
            .fold((f64::INFINITY, centre), |(least, far), &n| {
                let cos = n.dot(towards);
                if cos < least { (cos, n) } else { (least, far) }
            })
            .1;
        centre += (far - centre) / f64::from(k + 1);
    }
    centre.normalize_or_zero()
}

/// [`RegionBound`]s as columns, one entry per region.
#[derive(Clone, Debug, Default)]
pub(super) struct BoundSet {
    centre: [Vec<f64>; 3],
    radius: Vec<f64>,
    axis: [Vec<f64>; 3],
    /// Whether the cone's half-angle is under 90 degrees (else it bounds nothing).
    narrow: Vec<bool>,
    spread_cos: Vec<f64>,
    spread_sin: Vec<f64>,
}

impl BoundSet {
    /// An upper bound of the multiplier of `frustum`'s view over region `i`: 0 when
    /// its sphere lies outside the frustum or (back faces culled) every normal faces
    /// away; the view's clamp when the sphere reaches the eye's plane.
    pub(super) fn multiplier(&self, i: usize, frustum: &Frustum) -> f64 {
        let mut out = [0.0];
        self.multipliers_into(frustum, i, &mut out);
        out[0]
    }

    /// Appends `bound`.
    pub(super) fn push(&mut self, bound: &RegionBound) {
        for k in 0..3 {
            self.centre[k].push(bound.centre[k]);
            self.axis[k].push(bound.axis[k]);
        }
        self.radius.push(bound.radius);
        self.narrow.push(bound.spread < std::f64::consts::FRAC_PI_2);
        self.spread_cos.push(bound.spread_cos);
        self.spread_sin.push(bound.spread_sin);
    }

    /// Region `i`'s sphere's centre and its normal cone's axis.
    pub(super) fn centre_axis(&self, i: usize) -> (DVec3, DVec3) {
        let column = |c: &[Vec<f64>; 3]| DVec3::new(c[0][i], c[1][i], c[2][i]);
        (column(&self.centre), column(&self.axis))
    }

    /// Keeps the first `len` regions' bounds.
    pub(super) fn truncate(&mut self, len: usize) {
        for k in 0..3 {
            self.centre[k].truncate(len);
            self.axis[k].truncate(len);
        }
        self.radius.truncate(len);
        self.narrow.truncate(len);
        self.spread_cos.truncate(len);
        self.spread_sin.truncate(len);
    }

    /// Replaces region `i`'s bound with `bound`.
    pub(super) fn set(&mut self, i: usize, bound: &RegionBound) {
        for k in 0..3 {
            self.centre[k][i] = bound.centre[k];
            self.axis[k][i] = bound.axis[k];
        }
        self.radius[i] = bound.radius;
        self.narrow[i] = bound.spread < std::f64::consts::FRAC_PI_2;
        self.spread_cos[i] = bound.spread_cos;
        self.spread_sin[i] = bound.spread_sin;
    }

    /// Writes into `out` the upper bound of the multiplier of `frustum`'s view over
    /// each region from `first` on, with the loop compiled for AVX2 (four lanes) where
    /// the CPU has it: the same operations, so the same bits (nothing fused, no
    /// approximate instruction).
    pub(super) fn multipliers_into(&self, frustum: &Frustum, first: usize, out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if Level::detected() >= Level::Avx2 {
            // SAFETY: the CPU has every feature of `Level::Avx2`, which is what the
            // function is compiled with.
            #[allow(unsafe_code)]
            unsafe {
                self.multipliers_into_v3(frustum, first, out);
            }
            return;
        }
        self.multipliers_body(frustum, first, out);
    }

    /// [`multipliers_body`](Self::multipliers_body) compiled with AVX2 (AVX's 256-bit
    /// registers are what the loop needs; no fused multiply-add is enabled).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    fn multipliers_into_v3(&self, frustum: &Frustum, first: usize, out: &mut [f64]) {
        self.multipliers_body(frustum, first, out);
    }

    /// The bounds: [`BoundSet::multiplier`]'s cases, computed for all and selected, so
    /// that the loop has no branch and vectorizes. Always inlined, so that each
    /// caller's target features apply to it.
    ///
    /// The angle bound (back faces culled or not): normals lie within `spread` of the
    /// axis and directions to the eye within `seen` of the centre's (at angle `off`
    /// from the axis), so a normal meets a direction to the eye at an angle of at least
    /// `off - spread - seen` (front) and at most `off + spread + seen` (its cosine's
    /// least value; the back's bound). Cosines of sums, without trigonometric calls.
    #[inline(always)]
    fn multipliers_body(&self, frustum: &Frustum, first: usize, out: &mut [f64]) {
        let view = frustum.view;
        let n = out.len();
        // Every column cut to `n` entries, so that the loop needs no bounds check.
        fn cut<T>(column: &[T], first: usize, n: usize) -> &[T] {
            &column[first..first + n]
        }
        let [cx, cy, cz] = self.centre.each_ref().map(|c| cut(c, first, n));
        let [ax, ay, az] = self.axis.each_ref().map(|a| cut(a, first, n));
        let (radius, narrow) = (cut(&self.radius, first, n), cut(&self.narrow, first, n));
        let (sc, ss) = (
            cut(&self.spread_cos, first, n),
            cut(&self.spread_sin, first, n),
        );
        let planes = frustum.planes.map(|p| p.to_array());
        let (w, eye) = (frustum.depth.to_array(), view.eye.to_array());
        let (slope, max, cull) = (frustum.depth_slope, view.max, view.cull_back_faces);
        let scale = view.focal_pixels * view.focal_pixels / view.reference;
        // Selects rather than `f64::min`/`max`, whose NaN rules cost blends.
        let lesser = |a: f64, b: f64| if a < b { a } else { b };
        let greater = |a: f64, b: f64| if a > b { a } else { b };
        for i in 0..n {
            let (x, y, z, r) = (cx[i], cy[i], cz[i], radius[i]);
            let plane = |q: [f64; 4]| q[0] * x + q[1] * y + q[2] * z + q[3];
            // Outside the frustum: some plane has the whole sphere on its far side.
            let inside = planes
                .iter()
                .fold(f64::INFINITY, |m, &q| lesser(m, plane(q) + r));
            let nearest = plane(w) - r * slope;
            let (ex, ey, ez) = (eye[0] - x, eye[1] - y, eye[2] - z);
            let d = (ex * ex + ey * ey + ez * ez).sqrt();
            let seen_sin = r / d;
            let off_cos = greater(
                lesser((ax[i] * ex + ay[i] * ey + az[i] * ez) / d, 1.0),
                -1.0,
            );
            let seen_cos = greater(1.0 - seen_sin * seen_sin, 0.0).sqrt();
            let off_sin = greater(1.0 - off_cos * off_cos, 0.0).sqrt();
            // theta = spread + seen, in [0, pi).
            let theta_cos = sc[i] * seen_cos - ss[i] * seen_sin;
            let theta_sin = ss[i] * seen_cos + sc[i] * seen_sin;
            // cos(off - theta) when off > theta, else 1.
            let front = if off_cos >= theta_cos {
                1.0
            } else {
                off_cos * theta_cos + off_sin * theta_sin
            };
            // The back: cos(pi - off - theta) = -cos(off + theta), 1 when off + theta
            // >= pi.
            let back = if -off_cos >= theta_cos {
                1.0
            } else {
                -(off_cos * theta_cos - off_sin * theta_sin)
            };
            let facing = if cull { front } else { greater(front, back) };
            let cos = if narrow[i] && d > r {
                greater(facing, 0.0)
            } else {
                1.0
            };
            let area = scale * cos * (d + r) / (nearest * nearest * nearest);
            let bound = if nearest > 0.0 {
                lesser(area, max)
            } else {
                max
            };
            out[i] = if inside < 0.0 { 0.0 } else { bound };
        }
    }
}

/// The bound of the parts of cells `leaves` of segment `segment` in the domain, with
/// the vertex positions and normals `geometry` (the sampler's mesh's, or a
/// deformation's).
///
/// `tight`: a sphere and a normal cone (its axis fitted) around the points and
/// interpolated vertex normals at the corners of each overlapping triangle's part
/// inside each cell ([`leaf_part_corners`](crate::curve::SegmentCurve::leaf_part_corners)).
/// Every sample of the cells is a convex combination of its part's corners, so it lies
/// in the sphere and its normal in the cone, and the parts are far smaller than the
/// triangles they are cut from (a cell is smaller than a face on a fine mesh): on the
/// bunny a view's pool holds 1.32 times its visible ranks, against 1.53 around the
/// triangles. Otherwise, around the overlapping triangles' corners and vertex normals
/// (the cone around their mean): about eight times cheaper, for a mesh deforming
/// every frame.
pub(super) fn bin_bound(
    sampler: &Sampler,
    (positions, normals): (&[DVec3], &[DVec3]),
    segment: usize,
    leaves: Range<usize>,
    tight: bool,
    (points, directions): &mut (Vec<DVec3>, Vec<DVec3>),
) -> RegionBound {
    let seg = &sampler.segments()[segment];
    let triangles = sampler.mesh().triangles();
    let corners_of = |t: u32| triangles[seg.faces[t as usize] as usize].map(|v| v as usize);
    points.clear();
    directions.clear();
    for leaf in leaves {
        if tight {
            seg.curve.leaf_part_corners(leaf, |t, b| {
                let corners = corners_of(t);
                let blend = |x: &[DVec3]| (0..3).map(|i| x[corners[i]] * b[i]).sum::<DVec3>();
                points.push(blend(positions));
                directions.push(blend(normals).normalize_or_zero());
            });
        } else {
            for &t in seg.curve.leaf_triangles(leaf) {
                for v in corners_of(t) {
                    points.push(positions[v]);
                    directions.push(normals[v]);
                }
            }
        }
    }
    RegionBound::new(points, directions, tight)
}
