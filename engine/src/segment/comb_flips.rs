//! Vertices where the per-face major directions cannot be combed: going once around
//! the vertex, the direction carried from face to face comes back reversed.
//!
//! The parameterization combs each face's major direction (the field's mean tensor on
//! the face, [`face_frames`](super::face_frames)) to a consistent sign by carrying it
//! across glued edges with the hinge map. Around an interior vertex where the carried
//! direction returns with the opposite sign, no sign choice is consistent: a piece
//! holding that vertex inside (not on a cut or its border) has a glued side across
//! which its combed frames turn by about 180 degrees, and its map overlaps or flips.
//! These vertices are the per-face field's half-index singularities, the dual of the
//! singular faces of the per-vertex field ([`singularity`](super::singularity)); the
//! two usually sit side by side, but on a singular face the flip is at whichever
//! corner the per-face directions wind around, not at a corner fixed by index.
//!
//! Cost: O(E) for the edges' signs, O(V + E) for the vertices, parallel, each value
//! computed alone (the result does not depend on the thread count).

use glam::DVec3;
use rayon::prelude::*;

use crate::mesh::{NONE, TriMesh};

/// Per vertex, whether the per-face directions `major` (one unit vector per face, in
/// its plane, sign arbitrary) flip around it: an odd number of the vertex's edges
/// join two faces whose directions, one carried into the other's plane about the
/// shared edge, point in opposite senses. A vertex with an edge that does not have
/// exactly two faces (a boundary or non-manifold edge) is never flagged; at a vertex
/// pinching two closed fans the edges of both count.
pub fn comb_flip_vertices(mesh: &TriMesh, major: &[DVec3]) -> Vec<bool> {
    assert_eq!(major.len(), mesh.face_count(), "one direction per face");
    let pos = mesh.positions();
    let normals = mesh.face_normals();
    let valence = mesh.edge_valence();
    let reversed: Vec<bool> = mesh
        .edges()
        .par_iter()
        .zip(mesh.edge_faces())
        .zip(valence)
        .map(|((&[a, b], &[f, g]), &valence)| {
            if valence != 2 || f == NONE || g == NONE {
                return false;
            }
            let (f, g) = (f as usize, g as usize);
            let e = (pos[b as usize] - pos[a as usize]).normalize_or_zero();
            let (nf, ng) = (normals[f], normals[g]);
            // The hinge map about `e` from f's plane into g's (as the comb carries it).
            let m = major[f];
            let carried = e * m.dot(e) + ng.cross(e) * m.dot(nf.cross(e));
            carried.dot(major[g]) < 0.0
        })
        .collect();
    (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map(|v| {
            let edges = mesh.vertex_edges(v);
            !edges.is_empty()
                && edges.iter().all(|&e| valence[e as usize] == 2)
                && edges.iter().filter(|&&e| reversed[e as usize]).count() % 2 == 1
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use glam::{DVec2, DVec3};

    use super::comb_flip_vertices;
    use crate::mesh::{TriMesh, shapes};

    /// Per face, the direction at angle `sum s_k atan2(p - c_k) / 2` at its barycentre
    /// `p`: a `+1/2` (`s = 1`) or `-1/2` (`s = -1`) singularity at each `c_k`.
    fn planar_directions(mesh: &TriMesh, singularities: &[(DVec2, f64)]) -> Vec<DVec3> {
        (0..mesh.face_count())
            .map(|f| {
                let t = mesh.triangles()[f];
                let p = t
                    .iter()
                    .map(|&v| mesh.positions()[v as usize])
                    .sum::<DVec3>()
                    / 3.0;
                let angle: f64 = singularities
                    .iter()
                    .map(|&(c, s)| 0.5 * s * (p.y - c.y).atan2(p.x - c.x))
                    .sum();
                DVec3::new(angle.cos(), angle.sin(), 0.0)
            })
            .collect()
    }

    fn flagged(flags: &[bool]) -> Vec<u32> {
        (0..flags.len() as u32)
            .filter(|&v| flags[v as usize])
            .collect()
    }

    /// The vertex of the 20 x 20 unit grid at `(i, j) / 20`.
    fn grid_vertex(i: u32, j: u32) -> u32 {
        j * 21 + i
    }

    fn at(i: u32, j: u32) -> DVec2 {
        DVec2::new(f64::from(i), f64::from(j)) / 20.0
    }

    #[test]
    fn a_half_index_singularity_flags_exactly_its_vertex() {
        let mesh = shapes::plane(1.0, 20).expect("plane");
        for s in [1.0, -1.0] {
            let major = planar_directions(&mesh, &[(at(9, 11), s)]);
            assert_eq!(
                flagged(&comb_flip_vertices(&mesh, &major)),
                vec![grid_vertex(9, 11)],
                "index {s}/2"
            );
        }
    }

    #[test]
    fn a_dipole_flags_both_ends_and_a_whole_turn_none() {
        let mesh = shapes::plane(1.0, 20).expect("plane");
        let major = planar_directions(&mesh, &[(at(6, 7), 1.0), (at(13, 12), -1.0)]);
        assert_eq!(
            flagged(&comb_flip_vertices(&mesh, &major)),
            vec![grid_vertex(6, 7), grid_vertex(13, 12)]
        );
        // Index +1 (two half turns at one point): combable, nothing flagged.
        let major = planar_directions(&mesh, &[(at(10, 10), 1.0), (at(10, 10), 1.0)]);
        assert!(flagged(&comb_flip_vertices(&mesh, &major)).is_empty());
    }

    #[test]
    fn boundary_vertices_are_never_flagged() {
        let mesh = shapes::plane(1.0, 20).expect("plane");
        // A half turn centred on a boundary vertex, and directions that alternate
        // wildly: only interior vertices may be flagged.
        let mut major = planar_directions(&mesh, &[(at(0, 10), 1.0)]);
        for (f, m) in major.iter_mut().enumerate() {
            if f % 7 == 3 {
                *m = DVec3::new(-m.y, m.x, 0.0);
            }
        }
        let flags = comb_flip_vertices(&mesh, &major);
        for v in flagged(&flags) {
            let p = mesh.positions()[v as usize];
            assert!(
                p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0,
                "boundary vertex {v} flagged"
            );
        }
    }

    #[test]
    fn smooth_fields_on_a_torus_flag_nothing() {
        // Directions along the torus's big circles and along its small ones, each in
        // its face's plane: the hinge map carries them into each other across every
        // edge of the curved surface.
        let mesh = shapes::torus(1.0, 0.4, 12).expect("torus");
        let along_ring: Vec<DVec3> = (0..mesh.face_count())
            .map(|f| {
                let t = mesh.triangles()[f];
                let p: DVec3 = t.iter().map(|&v| mesh.positions()[v as usize]).sum();
                let n = mesh.face_normals()[f];
                let d = DVec3::Z.cross(p / 3.0);
                (d - n * n.dot(d)).normalize()
            })
            .collect();
        assert!(flagged(&comb_flip_vertices(&mesh, &along_ring)).is_empty());
        let across: Vec<DVec3> = along_ring
            .iter()
            .zip(mesh.face_normals())
            .map(|(d, n)| n.cross(*d))
            .collect();
        assert!(flagged(&comb_flip_vertices(&mesh, &across)).is_empty());
    }
}
