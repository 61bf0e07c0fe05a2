//! What `strata field` writes: the field as a PLY mesh for a viewer (MeshLab,
//! Polyscope) and its singularities as a JSON report with a one-line summary.
//!
//! Input: a mesh, its [`TensorField`] and the singularities of the field's major line
//! field ([`detect_singularities`](strata_engine::segment::detect_singularities)).
//! Output: a [`FieldReport`] (serializable; [`FieldReport::summary`] is the printed
//! line) and a binary little-endian PLY ([`write_field_ply`]). Cost: O(V + F), one
//! closed-form 2x2 eigen-decomposition per vertex.
//!
//! The PLY's `vertex` element has the [`FIELD_VERTEX_PROPERTIES`] (all `float`):
//! position, vertex normal, the unit major direction of the tensor in the vertex's
//! tangent plane ([`eigen_in_plane`]; a line field, so its sign is arbitrary), the
//! anisotropy `sqrt(l1 / l2)` and the density `sqrt(l1 l2)`. The `face` element has
//! `list uchar int vertex_indices` and `float singularity`, the face's index (+-0.5,
//! rarely a larger multiple of 0.5; 0 for regular faces).

use std::io::{self, Write};
use std::path::Path;

use strata_engine::field::{TensorField, eigen_in_plane};
use strata_engine::mesh::TriMesh;
use strata_engine::segment::{Singularity, singularity_clusters};

/// The `float` properties of a vertex of the field PLY, in file order.
pub const FIELD_VERTEX_PROPERTIES: [&str; 11] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "dx",
    "dy",
    "dz",
    "anisotropy",
    "density",
];

/// The JSON report of `strata field` (schema in docs/cli.md).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FieldReport {
    /// Faces of the mesh.
    pub faces: usize,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Euler characteristic of the mesh with each pinched vertex split into its cones
    /// (what the indices sum to on a closed mesh).
    pub euler_characteristic: i64,
    /// Boundary loops of the mesh (0: closed).
    pub boundary_loops: usize,
    /// Singular faces in ascending face order.
    pub singularities: Vec<SingularityEntry>,
    /// Sum of the singularities' indices.
    pub index_sum: f64,
    /// The singularities grouped into clusters of faces that share a vertex
    /// ([`singularity_clusters`]): the singularities seen at the scale of the mesh.
    pub clusters: Vec<ClusterEntry>,
    /// Clusters whose index is not zero: the field's singularities once dipoles
    /// (touching +1/2 and -1/2 faces, no winding around both) are set aside.
    pub net_singularities: usize,
    /// Vertices whose anisotropy `sqrt(l1 / l2)` is below the isotropy threshold given
    /// to [`FieldReport::new`]: there the major direction is barely defined.
    pub near_isotropic_vertices: usize,
    /// The threshold `near_isotropic_vertices` was counted with (a spacing ratio).
    pub isotropy_threshold: f64,
    /// Wall time of building the field, seconds.
    pub field_s: f64,
}

/// One singularity in the report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SingularityEntry {
    /// Face index.
    pub face: u32,
    /// Index of the line-field singularity (+0.5 or -0.5; rarely a larger multiple).
    pub index: f64,
    /// Barycentre of the face, world space.
    pub position: [f64; 3],
}

/// One cluster of touching singular faces in the report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClusterEntry {
    /// Its faces, ascending.
    pub faces: Vec<u32>,
    /// The sum of their indices (0 for a dipole).
    pub index: f64,
    /// The mean of its faces' barycentres, world space.
    pub position: [f64; 3],
}

impl FieldReport {
    /// The report of `field` on `mesh` with its `singularities`; vertices with an
    /// anisotropy below `isotropy_threshold` count as near-isotropic. `field_s` is the
    /// time it took to build the field.
    pub fn new(
        mesh: &TriMesh,
        field: &TensorField,
        singularities: &[Singularity],
        isotropy_threshold: f64,
        field_s: f64,
    ) -> Self {
        let near_isotropic_vertices = field
            .tensors()
            .iter()
            .zip(mesh.vertex_normals())
            .filter(|(t, n)| eigen_in_plane(t, **n).anisotropy() < isotropy_threshold)
            .count();
        let clusters = singularity_clusters(mesh, singularities);
        Self {
            faces: mesh.face_count(),
            vertices: mesh.vertex_count(),
            euler_characteristic: strata_engine::field::tangent_space::split_euler_characteristic(
                mesh,
            ),
            boundary_loops: mesh.boundary_loops().len(),
            singularities: singularities
                .iter()
                .map(|s| {
                    let [a, b, c] = mesh.face_positions(s.face);
                    SingularityEntry {
                        face: s.face,
                        index: s.index,
                        position: ((a + b + c) / 3.0).to_array(),
                    }
                })
                .collect(),
            // A fold from +0, not `sum` (which starts at -0 and prints "-0" for none).
            index_sum: singularities.iter().fold(0.0, |sum, s| sum + s.index),
            net_singularities: clusters.iter().filter(|c| c.is_singular()).count(),
            clusters: clusters
                .iter()
                .map(|c| {
                    let centre = c
                        .faces
                        .iter()
                        .map(|&f| mesh.face_positions(f).iter().sum::<glam::DVec3>() / 3.0)
                        .sum::<glam::DVec3>()
                        / c.faces.len() as f64;
                    ClusterEntry {
                        faces: c.faces.clone(),
                        index: c.index,
                        position: centre.to_array(),
                    }
                })
                .collect(),
            near_isotropic_vertices,
            isotropy_threshold,
            field_s,
        }
    }

    /// The one-line summary `strata field` prints: counts, the singularities by index
    /// and net of dipoles,
    /// their sum and, on a closed mesh, whether it equals the Euler characteristic
    /// (Poincare-Hopf), the near-isotropic vertices if any, and the build time.
    pub fn summary(&self) -> String {
        let count = |index: f64| {
            self.singularities
                .iter()
                .filter(|s| s.index == index)
                .count()
        };
        let (plus, minus) = (count(0.5), count(-0.5));
        let other = self.singularities.len() - plus - minus;
        let sum = self.index_sum;
        let chi = self.euler_characteristic;
        let check = if self.boundary_loops > 0 {
            "(open mesh: no Poincare-Hopf check)".to_owned()
        } else if sum == chi as f64 {
            "= Euler characteristic (Poincare-Hopf holds)".to_owned()
        } else {
            format!("!= Euler characteristic {chi} (Poincare-Hopf fails)")
        };
        let isotropic = if self.near_isotropic_vertices > 0 {
            format!(
                "; {} near-isotropic vertices (anisotropy under {})",
                self.near_isotropic_vertices, self.isotropy_threshold
            )
        } else {
            String::new()
        };
        format!(
            "{} faces, {} vertices (Euler characteristic {chi}, {} boundary loops): {} singularities ({plus} of +1/2, {minus} of -1/2, {other} other) in {} clusters of touching faces, {} with a non-zero index, index sum {sum} {check}{isotropic}; field {:.3} s",
            self.faces,
            self.vertices,
            self.boundary_loops,
            self.singularities.len(),
            self.clusters.len(),
            self.net_singularities,
            self.field_s,
        )
    }
}

/// Writes the field PLY (see the [module docs](self)) to `path`, atomically.
pub fn write_field_ply(
    path: &Path,
    mesh: &TriMesh,
    field: &TensorField,
    singularities: &[Singularity],
) -> io::Result<()> {
    strata_engine::io::write_atomically(path, |w| write_field_ply_to(w, mesh, field, singularities))
}

/// Writes the field PLY (see the [module docs](self)) to `w`: binary little endian,
/// 44 bytes per vertex and 17 per face.
///
/// Errors: [`io::ErrorKind::InvalidInput`] if the field does not have one tensor per
/// vertex, a singularity names a face the mesh lacks, or a vertex index does not fit an
/// `int`; any error of `w`.
pub fn write_field_ply_to<W: Write>(
    mut w: W,
    mesh: &TriMesh,
    field: &TensorField,
    singularities: &[Singularity],
) -> io::Result<()> {
    let invalid = |message: String| io::Error::new(io::ErrorKind::InvalidInput, message);
    if field.tensors().len() != mesh.vertex_count() {
        return Err(invalid(format!(
            "{} tensors for {} vertices",
            field.tensors().len(),
            mesh.vertex_count()
        )));
    }
    if i32::try_from(mesh.vertex_count()).is_err() {
        return Err(invalid("too many vertices for PLY `int` indices".into()));
    }
    let mut index = vec![0.0f32; mesh.face_count()];
    for s in singularities {
        let slot = index
            .get_mut(s.face as usize)
            .ok_or_else(|| invalid(format!("singular face {} is not in the mesh", s.face)))?;
        *slot = s.index as f32;
    }
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by strata: tensor field\n\
         element vertex {}\n",
        mesh.vertex_count()
    );
    for name in FIELD_VERTEX_PROPERTIES {
        header.push_str(&format!("property float {name}\n"));
    }
    header.push_str(&format!(
        "element face {}\nproperty list uchar int vertex_indices\nproperty float singularity\nend_header\n",
        mesh.face_count()
    ));
    w.write_all(header.as_bytes())?;
    for ((p, n), t) in mesh
        .positions()
        .iter()
        .zip(mesh.vertex_normals())
        .zip(field.tensors())
    {
        let e = eigen_in_plane(t, *n);
        let values = [
            p.x,
            p.y,
            p.z,
            n.x,
            n.y,
            n.z,
            e.major.x,
            e.major.y,
            e.major.z,
            e.anisotropy(),
            e.density(),
        ];
        let mut record = [0u8; 4 * FIELD_VERTEX_PROPERTIES.len()];
        for (chunk, v) in record.chunks_exact_mut(4).zip(values) {
            chunk.copy_from_slice(&(v as f32).to_le_bytes());
        }
        w.write_all(&record)?;
    }
    for (t, s) in mesh.triangles().iter().zip(&index) {
        let mut record = [0u8; 17];
        record[0] = 3;
        for (chunk, v) in record[1..13].chunks_exact_mut(4).zip(t) {
            // In range: the vertex count fits an i32 (checked above).
            chunk.copy_from_slice(&(*v as i32).to_le_bytes());
        }
        record[13..17].copy_from_slice(&s.to_le_bytes());
        w.write_all(&record)?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use strata_engine::field::FieldSpec;
    use strata_engine::fixtures::{along_x_2to1_on, field_on, isotropic_on, oblique};
    use strata_engine::mesh::shapes;
    use strata_engine::segment::detect_singularities;

    use super::*;

    /// The header's lines and the body after `end_header\n`.
    fn split_header(bytes: &[u8]) -> (Vec<String>, &[u8]) {
        let marker = b"end_header\n";
        let end = bytes
            .windows(marker.len())
            .position(|w| w == marker)
            .expect("end_header")
            + marker.len();
        let text = std::str::from_utf8(&bytes[..end]).expect("ASCII header");
        (text.lines().map(str::to_owned).collect(), &bytes[end..])
    }

    fn f32_at(body: &[u8], offset: usize) -> f32 {
        f32::from_le_bytes(body[offset..offset + 4].try_into().expect("4 bytes"))
    }

    fn i32_at(body: &[u8], offset: usize) -> i32 {
        i32::from_le_bytes(body[offset..offset + 4].try_into().expect("4 bytes"))
    }

    /// A flat plane with a constant 4:1 field along (1, 1, 0): every vertex's direction
    /// is that line, its anisotropy 4 and its density 2; no face is singular.
    #[test]
    fn plane_with_a_constant_field_reads_back() {
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let field = FieldSpec::Constant {
            direction: [1.0, 1.0, 0.0],
            anisotropy: 4.0,
            density: 2.0,
        }
        .build(&mesh)
        .expect("field");
        let singularities = detect_singularities(&mesh, &field);
        assert!(singularities.is_empty());
        let mut bytes = Vec::new();
        write_field_ply_to(&mut bytes, &mesh, &field, &singularities).expect("write");
        let (header, body) = split_header(&bytes);
        assert_eq!(header[0], "ply");
        assert_eq!(header[1], "format binary_little_endian 1.0");
        let element = |name: &str| {
            header
                .iter()
                .find_map(|l| l.strip_prefix(&format!("element {name} ")))
                .and_then(|n| n.parse::<usize>().ok())
        };
        assert_eq!(element("vertex"), Some(mesh.vertex_count()));
        assert_eq!(element("face"), Some(mesh.face_count()));
        let vertex_properties: Vec<&str> = header
            .iter()
            .skip_while(|l| !l.starts_with("element vertex"))
            .skip(1)
            .take_while(|l| l.starts_with("property"))
            .map(|l| l.as_str())
            .collect();
        let expected: Vec<String> = FIELD_VERTEX_PROPERTIES
            .iter()
            .map(|n| format!("property float {n}"))
            .collect();
        assert_eq!(vertex_properties, expected);
        assert!(header.contains(&"property list uchar int vertex_indices".to_owned()));
        assert!(header.contains(&"property float singularity".to_owned()));
        let vertex_bytes = 4 * FIELD_VERTEX_PROPERTIES.len();
        assert_eq!(
            body.len(),
            mesh.vertex_count() * vertex_bytes + mesh.face_count() * 17
        );

        // A known vertex: position, normal, direction (up to sign), anisotropy, density.
        let v = mesh.vertex_count() / 2;
        let r = v * vertex_bytes;
        let p = mesh.positions()[v];
        for k in 0..3 {
            assert_eq!(f32_at(body, r + 4 * k), p[k] as f32);
        }
        let normal = DVec3::new(
            f32_at(body, r + 12).into(),
            f32_at(body, r + 16).into(),
            f32_at(body, r + 20).into(),
        );
        assert!((normal.z.abs() - 1.0).abs() < 1e-6, "{normal}");
        let d = DVec3::new(
            f32_at(body, r + 24).into(),
            f32_at(body, r + 28).into(),
            f32_at(body, r + 32).into(),
        );
        let expected = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!((d.length() - 1.0).abs() < 1e-6, "{d}");
        assert!(d.dot(expected).abs() > 1.0 - 1e-6, "{d} against {expected}");
        assert!((f32_at(body, r + 36) - 4.0).abs() < 1e-5);
        assert!((f32_at(body, r + 40) - 2.0).abs() < 1e-5);

        // Faces: three corners as stored, no singularity.
        let faces = &body[mesh.vertex_count() * vertex_bytes..];
        for (f, t) in mesh.triangles().iter().enumerate() {
            let r = f * 17;
            assert_eq!(faces[r], 3);
            for (k, &v) in t.iter().enumerate() {
                assert_eq!(i32_at(faces, r + 1 + 4 * k), v as i32);
            }
            assert_eq!(f32_at(faces, r + 13), 0.0);
        }
    }

    /// On a sphere a constant direction is singular (index sum 2): the singular faces
    /// carry their index in the PLY and in the report, with their barycentres.
    #[test]
    fn sphere_singularities_are_marked_and_reported() {
        let mesh = shapes::sphere(1.0, 4).expect("sphere");
        let field = field_on(&mesh, &oblique(2.0));
        let singularities = detect_singularities(&mesh, &field);
        assert!(!singularities.is_empty());
        let mut bytes = Vec::new();
        write_field_ply_to(&mut bytes, &mesh, &field, &singularities).expect("write");
        let (_, body) = split_header(&bytes);
        let faces = &body[mesh.vertex_count() * 4 * FIELD_VERTEX_PROPERTIES.len()..];
        let total: f64 = (0..mesh.face_count())
            .map(|f| f64::from(f32_at(faces, f * 17 + 13)))
            .sum();
        assert_eq!(total, 2.0);
        for s in &singularities {
            assert_eq!(f64::from(f32_at(faces, s.face as usize * 17 + 13)), s.index);
        }

        let report = FieldReport::new(&mesh, &field, &singularities, 1.05, 0.25);
        assert_eq!(report.index_sum, 2.0);
        assert_eq!(report.euler_characteristic, 2);
        assert_eq!(report.boundary_loops, 0);
        assert_eq!(report.near_isotropic_vertices, 0);
        for (entry, s) in report.singularities.iter().zip(&singularities) {
            let [a, b, c] = mesh.face_positions(s.face);
            let centre = (a + b + c) / 3.0;
            assert!((DVec3::from(entry.position) - centre).length() < 1e-12);
            // The barycentre of a face of the unit sphere lies just inside it.
            assert!(centre.length() > 0.9 && centre.length() < 1.0);
        }
        let line = report.summary();
        assert!(!line.contains('\n'));
        assert!(
            line.contains("index sum 2 = Euler characteristic (Poincare-Hopf holds)"),
            "{line}"
        );
        assert!(line.ends_with("field 0.250 s"), "{line}");
        assert!(!line.contains("near-isotropic"), "{line}");
    }

    #[test]
    fn summary_names_open_meshes_failures_and_isotropic_vertices() {
        let mesh = shapes::plane(1.0, 2).expect("plane");
        let field = isotropic_on(&mesh);
        let report = FieldReport::new(&mesh, &field, &[], 1.05, 0.0);
        assert_eq!(report.near_isotropic_vertices, mesh.vertex_count());
        let line = report.summary();
        assert!(
            line.contains("index sum 0 (open mesh: no Poincare-Hopf check)"),
            "{line}"
        );
        assert!(
            line.contains(&format!(
                "{} near-isotropic vertices (anisotropy under 1.05)",
                mesh.vertex_count()
            )),
            "{line}"
        );
        let closed = FieldReport {
            boundary_loops: 0,
            index_sum: 1.5,
            euler_characteristic: 2,
            ..report
        };
        assert!(
            closed.summary().contains("!= Euler characteristic 2"),
            "{}",
            closed.summary()
        );
    }

    #[test]
    fn touching_opposite_singularities_count_as_one_dipole_cluster() {
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let field = along_x_2to1_on(&mesh);
        // Faces 0 and 1 share an edge; face 31 is at the far corner.
        let found = [
            Singularity {
                face: 0,
                index: 0.5,
            },
            Singularity {
                face: 1,
                index: -0.5,
            },
            Singularity {
                face: 31,
                index: 0.5,
            },
        ];
        let report = FieldReport::new(&mesh, &field, &found, 1.05, 0.0);
        assert_eq!(report.clusters.len(), 2);
        assert_eq!(report.net_singularities, 1);
        assert_eq!(report.clusters[0].faces, vec![0, 1]);
        assert_eq!(report.clusters[0].index, 0.0);
        let line = report.summary();
        assert!(
            line.contains("3 singularities (2 of +1/2, 1 of -1/2, 0 other) in 2 clusters of touching faces, 1 with a non-zero index"),
            "{line}"
        );
    }

    #[test]
    fn singularities_outside_the_mesh_are_refused() {
        let mesh = shapes::plane(1.0, 2).expect("plane");
        let field = along_x_2to1_on(&mesh);
        let bad = [Singularity {
            face: mesh.face_count() as u32,
            index: 0.5,
        }];
        let e = write_field_ply_to(Vec::new(), &mesh, &field, &bad).expect_err("bad face");
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
    }
}
