//! Unit tests of the readers' internals; file-level behaviour is tested in
//! `tests/tests/io.rs` over the corpus. `obj_fast` checks the OBJ reader against the
//! one it replaced (`obj_reference`).

mod obj_chunks;
mod obj_fast;
mod obj_reference;

use std::path::Path;

use super::*;
use crate::mesh::MeshWarning;

fn ply(text: &str) -> Result<TriMesh, MeshError> {
    parse_ply(text.as_bytes(), Path::new("t.ply"))
}

fn obj(text: &str) -> Result<TriMesh, MeshError> {
    parse_obj(text.as_bytes(), Path::new("t.obj"))
}

const TETRA_VERTICES: &str = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
const TETRA_FACES: &str = "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";

fn ascii_tetra(vertex_props: &str, face_prop: &str) -> String {
    format!(
        "ply\nformat ascii 1.0\nelement vertex 4\n{vertex_props}element face 4\n{face_prop}end_header\n{TETRA_VERTICES}{TETRA_FACES}"
    )
}

const XYZ: &str = "property float x\nproperty float y\nproperty float z\n";

#[test]
fn header_accepts_every_type_name_and_both_styles() {
    let names = [
        "char", "int8", "uchar", "uint8", "short", "int16", "ushort", "uint16", "int", "int32",
    ];
    let names = names
        .iter()
        .chain(&["uint", "uint32", "float", "float32", "double", "float64"]);
    let mut text =
        String::from("ply\nformat binary_big_endian 1.0\ncomment c\nobj_info o\nelement e 0\n");
    for (i, n) in names.enumerate() {
        text.push_str(&format!("property {n} p{i}\n"));
    }
    text.push_str("property list uint16 float64 l\nend_header\n");
    let header = ply::parse_header(text.as_bytes()).expect("valid header");
    assert_eq!(header.elements[0].properties.len(), 17);
    assert_eq!(header.body_start, text.len());
    assert_eq!(header.end_line, 23);
}

#[test]
fn header_errors_name_their_line() {
    let cases = [
        ("plyx\n", 1, "first line"),
        ("ply\nformat ascii 2.0\n", 2, "format"),
        ("ply\nformat ascii 1.0\nelement vertex -1\n", 3, "bad count"),
        ("ply\nformat ascii 1.0\nproperty float x\n", 3, "before any"),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty flt x\n",
            4,
            "unknown property type `flt`",
        ),
        (
            "ply\nformat ascii 1.0\nelement f 1\nproperty list float int v\n",
            4,
            "non-integer length",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\n",
            3,
            "no `end_header`",
        ),
        ("ply\nelement vertex 1\nend_header\n", 3, "no `format`"),
        (
            "ply\nformat ascii 1.0\nbogus\n",
            3,
            "unknown header keyword",
        ),
    ];
    for (text, line, what) in cases {
        let (got_line, got_what) = ply::parse_header(text.as_bytes()).expect_err(text);
        assert_eq!(got_line, line, "{text}");
        assert!(
            got_what.contains(what),
            "{got_what:?} should contain {what:?}"
        );
    }
}

#[test]
fn ascii_ply_reads_a_tetrahedron() {
    let mesh = ply(&ascii_tetra(
        XYZ,
        "property list uchar int vertex_indices\n",
    ))
    .expect("valid");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (4, 4));
    assert_eq!(mesh.euler_characteristic(), 2);
    assert_eq!(mesh.triangles()[0], [0, 2, 1]);
}

#[test]
fn ascii_ply_with_crlf_and_vertex_index_name() {
    let text = ascii_tetra(XYZ, "property list uchar uint vertex_index\n").replace('\n', "\r\n");
    assert_eq!(ply(&text).expect("valid").face_count(), 4);
}

#[test]
fn ply_skips_list_properties_of_the_vertex_element() {
    let props =
        "property float x\nproperty list uchar float junk\nproperty float y\nproperty float z\n";
    let text = ascii_tetra(props, "property list uchar int vertex_indices\n").replace(
        "0 0 0\n1 0 0\n0 1 0\n0 0 1\n",
        "0 2 9 9 0 0\n1 0 0 0\n0 1 7 1 0\n0 0 0 1\n",
    );
    let mesh = ply(&text).expect("valid");
    assert_eq!(mesh.positions()[1], DVec3::X);
    assert_eq!(mesh.positions()[3], DVec3::Z);
}

#[test]
fn ply_negative_index_is_out_of_range_not_wrapped() {
    // -4 as a wrapping u32 would be 4294967292; as i8 bits it would be 252. Neither
    // may turn into a valid vertex.
    let text = ascii_tetra(XYZ, "property list uchar char vertex_indices\n")
        .replace("3 0 3 2", "3 0 -4 2");
    match ply(&text) {
        Err(MeshError::InFile { source, .. }) => match *source {
            MeshError::IndexOutOfRange {
                face: 3,
                index: -4,
                vertex_count: 4,
            } => {}
            other => panic!("wrong inner error {other:?}"),
        },
        other => panic!("expected InFile, got {other:?}"),
    }
}

#[test]
fn ply_strips_restart_and_alternate_winding() {
    // A strip over a 2x3 grid, then a restart with one more triangle.
    let text = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n\
                element tristrips 1\nproperty list int int vertex_indices\nend_header\n\
                0 0 0\n0 1 0\n1 0 0\n1 1 0\n2 0 0\n2 1 0\n\
                9 0 2 1 3 -1 2 4 3 5\n";
    let mesh = ply(text).expect("valid");
    assert_eq!(
        mesh.triangles(),
        &[[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]][..]
    );
    // Alternating winding keeps every face facing the same way (+z here).
    assert!(
        mesh.face_normals().iter().all(|n| n.z > 0.0),
        "{:?}",
        mesh.face_normals()
    );
}

#[test]
fn ply_strip_joins_with_repeated_vertices_are_dropped_silently() {
    let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                element tristrip 1\nproperty list int int vertex_index\nend_header\n\
                0 0 0\n0 1 0\n1 0 0\n1 1 0\n6 0 1 2 2 1 3\n";
    let mesh = ply(text).expect("valid");
    assert!(mesh.warnings().is_empty(), "{:?}", mesh.warnings());
    assert_eq!(mesh.face_count(), 2);
}

#[test]
fn ply_zero_property_element_with_huge_count_is_skipped_instantly() {
    let text = ascii_tetra(XYZ, "property list uchar int vertex_indices\n").replace(
        "element face",
        "element nothing 18446744073709551615\nelement face",
    );
    assert_eq!(ply(&text).expect("valid").face_count(), 4);
}

#[test]
fn obj_relative_indices_and_quads() {
    let mesh = obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n").expect("valid");
    assert_eq!(mesh.face_count(), 2);
    assert!(
        mesh.warnings()
            .contains(&MeshWarning::TriangulatedPolygons { count: 1 })
    );
}

#[test]
fn obj_polylines_do_not_become_faces() {
    let mesh =
        obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nl 1 2 4\n  l 2 3 4\n").expect("valid");
    assert_eq!(mesh.face_count(), 1);
}

#[test]
fn obj_byte_order_mark_is_ignored() {
    let mesh = obj("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("valid");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (3, 1));
}

#[test]
fn obj_groups_share_vertices() {
    let text =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng a\nf 1 3 2\nf 1 2 4\ng b\nf 2 3 4\no c\nf 1 4 3\n";
    let mesh = obj(text).expect("valid");
    assert_eq!(
        (
            mesh.vertex_count(),
            mesh.face_count(),
            mesh.euler_characteristic()
        ),
        (4, 4, 2)
    );
    assert!(mesh.boundary_loops().is_empty());
    assert!(mesh.warnings().is_empty(), "{:?}", mesh.warnings());
}

#[test]
fn obj_scan_finds_the_first_bad_line() {
    let cases = [
        ("v 0 0 0\nv 1 x 0\n", 2, "`x` is not a number"),
        ("v 0 0 0\nv 1 0\n", 2, "needs 3 coordinates"),
        ("v 0 0 0\nv 1 0 0 0\n", 2, "weight"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n",
            4,
            "face 0 refers to vertex 0",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 5\n",
            5,
            "face 1 refers to vertex 5, but 3",
        ),
        (
            "v 0 0 0\nv 1 0 0\nf 1 2 -3\nv 0 1 0\n",
            3,
            "vertex -3, but 2 vertices are defined before it",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            5,
            "texture coordinate 2",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//0 2//1 3//1\n",
            5,
            "normal 0",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2/3/4 2 3\n",
            4,
            "malformed corner",
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.5\n", 4, "non-integer"),
    ];
    for (text, line, what) in cases {
        let (got_line, got_what) = obj::scan(text.as_bytes()).problem.expect(text);
        assert_eq!(
            obj_reference::prescan(text.as_bytes()).problem,
            Some((got_line, got_what.clone())),
            "{text}"
        );
        assert_eq!(got_line, line, "{text}");
        assert!(
            got_what.contains(what),
            "{got_what:?} should contain {what:?}"
        );
    }
    // Valid files have no problem (texture indices are ignored when there are none).
    let fine = obj::scan(b"v 0 0 0\nv 1 0 0 1 0 0\nv 0 1 0 2\nf 1/1 2/9 -1\n# x\n");
    assert_eq!(fine.problem, None);
    assert_eq!(
        fine.positions,
        [DVec3::ZERO, DVec3::X, DVec3::new(0.0, 0.5, 0.0)]
    );
}

#[test]
fn obj_non_finite_vertex_is_named_in_file_order() {
    // The NaN vertex is the 2nd in the file but the 3rd tobj sees (first-use order).
    match obj("v 0 0 0\nv nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 2\nf 1 3 4\n") {
        Err(MeshError::InFile { source, .. }) => {
            assert!(
                matches!(*source, MeshError::NonFiniteVertex { vertex: 1, .. }),
                "{source:?}"
            );
        }
        other => panic!("expected InFile, got {other:?}"),
    }
}

#[test]
fn obj_vertices_keep_file_order_across_objects() {
    // tobj numbers vertices per object by first use; the mesh must use file order,
    // and vertices no face uses are dropped with a warning, as for PLY.
    let text = "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\no a\nf 5 3 2\no b\nf 2 3 4\nf 3 5 4\nf 2 4 5\n";
    let mesh = obj(text).expect("valid");
    assert_eq!(
        mesh.positions(),
        &[DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z][..]
    );
    assert_eq!(
        mesh.input_vertex_map(),
        &[crate::mesh::NONE, 0, 1, 2, 3][..]
    );
    assert_eq!(mesh.triangles()[0], [3, 1, 0]);
    assert_eq!(
        mesh.warnings(),
        &[MeshWarning::RemovedUnreferencedVertices { count: 1 }][..]
    );
}

#[test]
fn obj_duplicate_vertices_are_merged_with_a_warning() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 0 0\nf 1 3 2\nf 1 5 4\nf 2 3 4\nf 1 4 3\n";
    let mesh = obj(text).expect("valid");
    assert_eq!((mesh.vertex_count(), mesh.euler_characteristic()), (4, 2));
    assert_eq!(
        mesh.warnings(),
        &[MeshWarning::MergedDuplicateVertices { count: 1 }][..]
    );
    assert_eq!(mesh.input_vertex_map()[4], 1);
}
