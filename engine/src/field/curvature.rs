//! Principal curvatures of a triangle mesh and the sampling tensor made from them.
//!
//! Input: a [`TriMesh`]. Output: per-vertex second fundamental forms, principal
//! curvatures and directions ([`PrincipalCurvatures`]); [`FieldSpec::Curvature`]
//! turns them into a [`TensorField`].
//!
//! Method: Rusinkiewicz 2004, "Estimating curvatures and their derivatives on triangle
//! meshes" (as in his trimesh2 library).
//! 1. Vertex normals by Max 1999 (weights `1 / (|e1|^2 |e2|^2)` per corner), which are
//!    exact for vertices whose one-ring lies on a sphere.
//! 2. Per face, a least-squares fit of the second fundamental form `II` (3 unknowns)
//!    to the normal differences along its three edges, `II e = dn` (6 equations), in
//!    an orthonormal frame of the face.
//! 3. Per vertex, each adjacent face's `II` is carried into the vertex's tangent plane
//!    by the smallest rotation taking the face normal onto the vertex normal (the
//!    paper's "rotate the coordinate system"), and averaged with weights
//!    `corner Voronoi area / vertex Voronoi area` (Meyer et al. 2003 mixed areas, as in
//!    trimesh2's `need_pointareas`).
//! 4. Optional smoothing: Jacobi iterations replacing each tensor by the Voronoi-area-
//!    weighted mean of itself and its one-ring, each carried into the vertex's plane by
//!    the same minimal rotation.
//!
//! Tensors are kept as world-space symmetric 3x3 matrices restricted to the tangent
//! plane (like the field's tensors), so frames never need to be stored or combed.
//! Sign: `II = dn / ds`, so curvatures are positive where the surface bends away from
//! its normal (a sphere with outward normals has `k = +1/r`).
//!
//! Cost: O(F + V * valence * smoothing_iterations), single-threaded and deterministic.

use glam::{DMat3, DVec3};

use super::params::{eigenvalues, non_negative, positive, smoothing_iterations};
use super::{FieldError, TensorField, eigen_in_plane, outer};
use crate::mesh::TriMesh;

/// Default of [`FieldSpec::Curvature`](super::FieldSpec::Curvature)`::floor`.
pub(crate) const DEFAULT_FLOOR: f64 = 0.2;
/// Default `max_anisotropy`.
pub(crate) const DEFAULT_MAX_ANISOTROPY: f64 = 4.0;
/// Default `isotropy_curvature`.
pub(crate) const DEFAULT_ISOTROPY_CURVATURE: f64 = 0.05;
/// Default `smoothing_iterations`.
pub(crate) const DEFAULT_SMOOTHING_ITERATIONS: u32 = 2;

/// Below this (after multiplying by the mesh's area radius) the largest curvature of a
/// mesh counts as zero, so [`CurvatureNormalization::Max`] does not blow round-off up.
const FLAT_CURVATURE: f64 = 1e-9;

#[cfg(feature = "serde")]
pub(crate) fn default_floor() -> f64 {
    DEFAULT_FLOOR
}
#[cfg(feature = "serde")]
pub(crate) fn default_max_anisotropy() -> f64 {
    DEFAULT_MAX_ANISOTROPY
}
#[cfg(feature = "serde")]
pub(crate) fn default_isotropy_curvature() -> f64 {
    DEFAULT_ISOTROPY_CURVATURE
}
#[cfg(feature = "serde")]
pub(crate) fn default_smoothing_iterations() -> u32 {
    DEFAULT_SMOOTHING_ITERATIONS
}

/// Which scalar of the principal curvatures `k1, k2` sets the sampling density. All
/// are curvatures (unit 1 / length) and equal `1 / r` on a sphere of radius `r`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum CurvatureMeasure {
    /// Mean curvature `|H| = |k1 + k2| / 2` (what the paper's wing example uses). Zero
    /// on saddles with `k1 = -k2`.
    Mean,
    /// Square root of the Gaussian curvature's magnitude, `sqrt(|k1 k2|)` (the root
    /// keeps the unit 1 / length). Zero on developable parts such as cylinders.
    Gaussian,
    /// Largest magnitude, `max(|k1|, |k2|)`.
    MaxAbs,
    /// Root mean square, `sqrt((k1^2 + k2^2) / 2)`: zero only where flat. The default.
    #[default]
    Rms,
}

impl CurvatureMeasure {
    /// The measure of principal curvatures `k1`, `k2` (any order, any sign).
    pub fn eval(self, k1: f64, k2: f64) -> f64 {
        match self {
            Self::Mean => 0.5 * (k1 + k2).abs(),
            Self::Gaussian => (k1 * k2).abs().sqrt(),
            Self::MaxAbs => k1.abs().max(k2.abs()),
            Self::Rms => (0.5 * (k1 * k1 + k2 * k2)).sqrt(),
        }
    }
}

/// The factor `c` that makes curvatures comparable across meshes before they set
/// density and anisotropy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum CurvatureNormalization {
    /// `c = sqrt(A / (4 pi))` with `A` the mesh's area: the radius of the sphere of the
    /// same area, so normalized curvatures are dimensionless, independent of the
    /// mesh's scale, and 1 on any sphere. The default.
    #[default]
    AreaRadius,
    /// `c = 1 / max` of the measure over all vertices, so `c * measure` is in `[0, 1]`
    /// and the density in `[floor, floor + scale]`; `c = 0` (density `floor`,
    /// isotropic) on a mesh whose largest curvature is round-off. Sensitive to a
    /// single noisy vertex.
    Max,
    /// `c = 1`: raw curvatures in 1 / (mesh units); `isotropy_curvature` is then in
    /// the same unit.
    Raw,
}

/// Per-vertex curvature of a mesh, ordered by magnitude: `|k1| >= |k2|`.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipalCurvatures {
    /// Per vertex, the second fundamental form as a world-space symmetric tensor in the
    /// tangent plane of [`TriMesh::vertex_normals`]: `k1 d1 d1^T + k2 d2 d2^T`.
    pub tensors: Vec<DMat3>,
    /// Principal curvature of largest magnitude (signed, 1 / length).
    pub k1: Vec<f64>,
    /// The other principal curvature.
    pub k2: Vec<f64>,
    /// Unit direction of `k1`, tangent (sign arbitrary; arbitrary where `|k1| = |k2|`).
    pub d1: Vec<DVec3>,
    /// Unit direction of `k2`: `normal x d1`.
    pub d2: Vec<DVec3>,
}

/// Estimates per-vertex principal curvatures and directions (module docs: Rusinkiewicz
/// 2004 with Max normals and Voronoi weights), then smooths the curvature tensors with
/// `smoothing_iterations` rounds of one-ring averaging.
///
/// ```
/// use glam::DVec3;
/// use strata_engine::{field::principal_curvatures, mesh::{TriMesh, shapes}};
/// // Cylinder-like trough z = x^2 / 2: |k1| = 1 along x at x = 0, k2 = 0 along y.
/// let flat = shapes::plane(1.0, 10)?;
/// let bent: Vec<DVec3> = flat.positions().iter()
///     .map(|p| DVec3::new(p.x - 0.5, p.y, 0.5 * (p.x - 0.5).powi(2)))
///     .collect();
/// let mesh = TriMesh::new(bent, flat.triangles().to_vec())?;
/// let k = principal_curvatures(&mesh, 0);
/// let v = 5 * 11 + 5; // the vertex at x = 0, y = 0.5
/// assert!((k.k1[v].abs() - 1.0).abs() < 0.02 && k.k2[v].abs() < 1e-9);
/// assert!(k.d1[v].x.abs() > 0.999);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn principal_curvatures(mesh: &TriMesh, smoothing_iterations: u32) -> PrincipalCurvatures {
    let normals = max_normals(mesh);
    let (corner_areas, point_areas) = voronoi_areas(mesh);
    let positions = mesh.positions();
    let mut tensors = vec![DMat3::ZERO; mesh.vertex_count()];

    for (f, tri) in mesh.triangles().iter().enumerate() {
        let p = tri.map(|v| positions[v as usize]);
        let nf = mesh.face_normals()[f];
        let Some(ii) = face_second_fundamental_form(p, tri.map(|v| normals[v as usize]), nf) else {
            continue;
        };
        for (corner, &v) in tri.iter().enumerate() {
            let area = point_areas[v as usize];
            if area > 0.0 {
                let w = corner_areas[f][corner] / area;
                tensors[v as usize] += transport(&ii, nf, normals[v as usize]) * w;
            }
        }
    }

    // Into the mesh's own tangent planes, where the field's tensors live.
    let mesh_normals = mesh.vertex_normals();
    for ((t, n_from), n_to) in tensors.iter_mut().zip(&normals).zip(mesh_normals) {
        *t = restrict(&transport(t, *n_from, *n_to), *n_to);
    }

    for _ in 0..smoothing_iterations {
        tensors = smooth_once(mesh, &tensors, &point_areas);
    }

    let count = mesh.vertex_count();
    let mut out = PrincipalCurvatures {
        tensors,
        k1: Vec::with_capacity(count),
        k2: Vec::with_capacity(count),
        d1: Vec::with_capacity(count),
        d2: Vec::with_capacity(count),
    };
    for (t, n) in out.tensors.iter().zip(mesh_normals) {
        let e = eigen_in_plane(t, *n);
        let (k1, d1, k2) = if e.l2.abs() > e.l1.abs() {
            (e.l2, e.minor, e.l1)
        } else {
            (e.l1, e.major, e.l2)
        };
        out.k1.push(k1);
        out.k2.push(k2);
        out.d1.push(d1);
        out.d2.push(n.cross(d1));
    }
    out
}

/// The settings of [`FieldSpec::Curvature`](super::FieldSpec::Curvature) that map
/// curvatures to tensors (validated by the spec).
pub(crate) struct Settings {
    pub measure: CurvatureMeasure,
    pub normalization: CurvatureNormalization,
    pub floor: f64,
    pub scale: f64,
    pub max_anisotropy: f64,
    pub isotropy_curvature: f64,
}

/// `sqrt(area / 4 pi)`: the radius of the sphere of the mesh's area, the factor `c`
/// of [`CurvatureNormalization::AreaRadius`].
pub(crate) fn area_radius(mesh: &TriMesh) -> f64 {
    (mesh.area() / (4.0 * std::f64::consts::PI)).sqrt()
}

/// The normalization factor `c` of [`CurvatureNormalization`] for per-vertex
/// `measures` on `mesh`.
fn normalization_factor(
    mesh: &TriMesh,
    normalization: CurvatureNormalization,
    measures: &[f64],
) -> f64 {
    let area_radius = area_radius(mesh);
    match normalization {
        CurvatureNormalization::AreaRadius => area_radius,
        CurvatureNormalization::Raw => 1.0,
        CurvatureNormalization::Max => {
            let max = measures.iter().copied().fold(0.0, f64::max);
            if max * area_radius > FLAT_CURVATURE {
                1.0 / max
            } else {
                0.0
            }
        }
    }
}

/// The curvature-density block of every curvature source: per vertex the density
/// `floor + scale * c * measure(k1, k2)`, with `c` the factor of `normalization` (see
/// [`FieldSpec::Curvature`](super::FieldSpec::Curvature)); returns `c` with the
/// densities, for the spacing ratios ([`ratios`]) of the same source. Used by
/// [`FieldSpec::Curvature`](super::FieldSpec::Curvature) and the designed field's
/// [`Density::Curvature`](crate::field::Density::Curvature).
pub(crate) fn densities(
    mesh: &TriMesh,
    k: &PrincipalCurvatures,
    measure: CurvatureMeasure,
    normalization: CurvatureNormalization,
    floor: f64,
    scale: f64,
) -> (f64, Vec<f64>) {
    let measures: Vec<f64> =
        k.k1.iter()
            .zip(&k.k2)
            .map(|(&k1, &k2)| measure.eval(k1, k2))
            .collect();
    let c = normalization_factor(mesh, normalization, &measures);
    let densities = measures.iter().map(|m| floor + scale * c * m).collect();
    (c, densities)
}

/// Per vertex the spacing ratio `clamp((c |k1| + eps) / (c |k2| + eps), min, max)`:
/// high where the surface bends one way only, 1 where it is flat or umbilic. Used by
/// [`FieldSpec::Curvature`](super::FieldSpec::Curvature) (`c` its normalization,
/// `min` 1) and the designed field's
/// [`Anisotropy::Curvature`](crate::field::Anisotropy::Curvature) (`c` the area radius).
pub(crate) fn ratios(k: &PrincipalCurvatures, c: f64, eps: f64, [min, max]: [f64; 2]) -> Vec<f64> {
    k.k1.iter()
        .zip(&k.k2)
        .map(|(k1, k2)| ((c * k1.abs() + eps) / (c * k2.abs() + eps)).clamp(min, max))
        .collect()
}

/// Checks the density settings of a curvature source (`floor` > 0, `scale` >= 0, at
/// most 1000 smoothing rounds), shared by [`FieldSpec::Curvature`](super::FieldSpec::Curvature)
/// and [`Density::Curvature`](crate::field::Density::Curvature).
pub(crate) fn check_density(floor: f64, scale: f64, smoothing: u32) -> Result<(), FieldError> {
    positive("floor", floor)?;
    non_negative("scale", scale)?;
    smoothing_iterations(smoothing)
}

/// The sampling tensor field of the curvature source (formulas on
/// [`FieldSpec::Curvature`](super::FieldSpec::Curvature)).
pub(crate) fn sampling_field(
    mesh: &TriMesh,
    k: &PrincipalCurvatures,
    s: &Settings,
) -> Result<TensorField, FieldError> {
    let (c, densities) = densities(mesh, k, s.measure, s.normalization, s.floor, s.scale);
    let ratios = ratios(k, c, s.isotropy_curvature, [1.0, s.max_anisotropy]);
    let eigen: Vec<[f64; 2]> = densities
        .iter()
        .zip(&ratios)
        .map(|(&density, &ratio)| eigenvalues(density, ratio))
        .collect();
    TensorField::from_frames(mesh, &k.d1, &eigen)
}

/// Vertex normals with Max's (1999) weights: each face's `e1 x e2` divided by
/// `|e1|^2 |e2|^2` of the two edges at the corner. Falls back to the mesh's normal
/// where the sum vanishes.
fn max_normals(mesh: &TriMesh) -> Vec<DVec3> {
    let positions = mesh.positions();
    let mut normals = vec![DVec3::ZERO; mesh.vertex_count()];
    for tri in mesh.triangles() {
        let p = tri.map(|v| positions[v as usize]);
        for k in 0..3 {
            let a = p[(k + 1) % 3] - p[k];
            let b = p[(k + 2) % 3] - p[k];
            let w = a.length_squared() * b.length_squared();
            if w > 0.0 {
                normals[tri[k] as usize] += a.cross(b) / w;
            }
        }
    }
    for (n, fallback) in normals.iter_mut().zip(mesh.vertex_normals()) {
        *n = n.try_normalize().unwrap_or(*fallback);
    }
    normals
}

/// Per face, the Voronoi area of each corner (obtuse triangles split as in Meyer et
/// al. 2003 / trimesh2), and per vertex their sum.
fn voronoi_areas(mesh: &TriMesh) -> (Vec<[f64; 3]>, Vec<f64>) {
    let positions = mesh.positions();
    let mut corners = Vec::with_capacity(mesh.face_count());
    let mut points = vec![0.0; mesh.vertex_count()];
    for (tri, &area) in mesh.triangles().iter().zip(mesh.face_areas()) {
        let p = tri.map(|v| positions[v as usize]);
        // Edge j is opposite corner j.
        let e = [p[2] - p[1], p[0] - p[2], p[1] - p[0]];
        let l2 = e.map(|v| v.length_squared());
        // Barycentric weights of the circumcentre; <= 0 means that corner is obtuse.
        // `l2[j+1] + l2[j+2] - l2[j]` is `-2 e[j+1].e[j+2]` (law of cosines); the dot
        // product keeps a needle's tiny terms that the sum of squares loses to
        // cancellation (1000 x 1e-6 made a right angle obtuse and divided by zero).
        let bcw: [f64; 3] =
            std::array::from_fn(|j| -2.0 * l2[j] * e[(j + 1) % 3].dot(e[(j + 2) % 3]));
        let mut c = [0.0; 3];
        if let Some(obtuse) = (0..3).find(|&j| bcw[j] <= 0.0) {
            // The two acute corners get the right triangles cut off by the
            // perpendicular bisectors of their edges; the obtuse corner the rest.
            let (a, b) = ((obtuse + 1) % 3, (obtuse + 2) % 3);
            c[a] = -0.25 * l2[b] * area / e[obtuse].dot(e[b]);
            c[b] = -0.25 * l2[a] * area / e[obtuse].dot(e[a]);
            c[obtuse] = area - c[a] - c[b];
        } else {
            let scale = 0.5 * area / (bcw[0] + bcw[1] + bcw[2]);
            for j in 0..3 {
                c[j] = scale * (bcw[(j + 1) % 3] + bcw[(j + 2) % 3]);
            }
        }
        if !c.iter().all(|x| x.is_finite() && *x >= 0.0) {
            // Round-off on a degenerate triangle: share its area equally.
            c = [area / 3.0; 3];
        }
        for j in 0..3 {
            points[tri[j] as usize] += c[j];
        }
        corners.push(c);
    }
    (corners, points)
}

/// Least-squares second fundamental form of one face from its corner positions `p`,
/// corner normals `n` and unit face normal `nf`, as a world-space tensor in the face
/// plane; `None` if the fit is singular (it is not for a face of positive area).
fn face_second_fundamental_form(p: [DVec3; 3], n: [DVec3; 3], nf: DVec3) -> Option<DMat3> {
    // Edge j runs from corner j + 1 to corner j + 2 (opposite corner j).
    let e = [p[2] - p[1], p[0] - p[2], p[1] - p[0]];
    let t = e[0].try_normalize()?;
    let b = nf.cross(t);
    // Unknowns (e, f, g) of II = [[e, f], [f, g]] in the frame (t, b); each edge gives
    // II (u, v) = (dn.t, dn.b). Normal equations, accumulated as trimesh2 does.
    let (mut uu, mut uv, mut vv) = (0.0, 0.0, 0.0);
    let mut rhs = DVec3::ZERO;
    for j in 0..3 {
        let (u, v) = (e[j].dot(t), e[j].dot(b));
        let dn = n[(j + 2) % 3] - n[(j + 1) % 3];
        let (dnu, dnv) = (dn.dot(t), dn.dot(b));
        uu += u * u;
        uv += u * v;
        vv += v * v;
        rhs += DVec3::new(dnu * u, dnu * v + dnv * u, dnv * v);
    }
    let normal_matrix = DMat3::from_cols(
        DVec3::new(uu, uv, 0.0),
        DVec3::new(uv, uu + vv, uv),
        DVec3::new(0.0, uv, vv),
    );
    let det = normal_matrix.determinant();
    let scale = (uu + vv) * (uu + vv) * (uu + vv);
    if !(det.abs() > 1e-14 * scale) {
        return None;
    }
    let [ee, ff, gg] = (normal_matrix.inverse() * rhs).to_array();
    Some(outer(t, t) * ee + (outer(t, b) + outer(b, t)) * ff + outer(b, b) * gg)
}

/// The smallest rotation taking unit `from` onto unit `to` (Rodrigues). For opposite
/// vectors the identity: a tensor of the plane is then already in the target plane.
fn rotation_between(from: DVec3, to: DVec3) -> DMat3 {
    let c = from.cross(to);
    let d = from.dot(to);
    if d <= -1.0 + 1e-12 {
        return DMat3::IDENTITY;
    }
    let k = DMat3::from_cols(
        DVec3::new(0.0, c.z, -c.y),
        DVec3::new(-c.z, 0.0, c.x),
        DVec3::new(c.y, -c.x, 0.0),
    );
    DMat3::IDENTITY + k + k * k * (1.0 / (1.0 + d))
}

/// Carries a tensor of the plane with normal `from` into the plane with normal `to`:
/// `R T R^T` with `R` the smallest rotation taking `from` to `to`, so that
/// `x^T (R T R^T) x = (R^T x)^T T (R^T x)`.
fn transport(t: &DMat3, from: DVec3, to: DVec3) -> DMat3 {
    let r = rotation_between(from, to);
    r * *t * r.transpose()
}

/// `P T P` with `P = I - n n^T`, symmetrised against round-off.
fn restrict(t: &DMat3, n: DVec3) -> DMat3 {
    let p = DMat3::IDENTITY - outer(n, n);
    let r = p * *t * p;
    (r + r.transpose()) * 0.5
}

/// One Jacobi round of Voronoi-area-weighted one-ring averaging in the mesh's tangent
/// planes.
fn smooth_once(mesh: &TriMesh, tensors: &[DMat3], point_areas: &[f64]) -> Vec<DMat3> {
    let normals = mesh.vertex_normals();
    (0..mesh.vertex_count())
        .map(|v| {
            let nv = normals[v];
            let mut sum = tensors[v] * point_areas[v];
            let mut weight = point_areas[v];
            for &u in mesh.vertex_neighbors(v as u32) {
                let u = u as usize;
                sum += transport(&tensors[u], normals[u], nv) * point_areas[u];
                weight += point_areas[u];
            }
            if weight > 0.0 {
                restrict(&(sum * (1.0 / weight)), nv)
            } else {
                tensors[v]
            }
        })
        .collect()
}

#[cfg(test)]
#[path = "curvature_tests.rs"]
mod tests;
