//! File formats: the real meshes, the project's corpus, every PLY encoding and type,
//! error reports, writers and round trips, and no panics on damaged files.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;
use strata_engine::io;
use strata_engine::mesh::{MeshError, MeshWarning, TriMesh};
use strata_engine::sample::Sample;
use strata_tests::{corpus_dir, shared_mesh_dir};

fn corpus(name: &str) -> PathBuf {
    corpus_dir().join(name)
}

fn load(name: &str) -> TriMesh {
    io::load(&corpus(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn load_err(name: &str) -> MeshError {
    match io::load(&corpus(name)) {
        Ok(_) => panic!("{name} should not load"),
        Err(e) => e,
    }
}

/// The tetrahedron every small file in the corpus describes.
fn tetrahedron() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    (
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
}

fn assert_is_tetrahedron(mesh: &TriMesh, what: &str) {
    let (positions, triangles) = tetrahedron();
    assert_eq!(mesh.positions(), &positions[..], "{what}");
    assert_eq!(mesh.triangles(), &triangles[..], "{what}");
    assert!(mesh.warnings().is_empty(), "{what}: {:?}", mesh.warnings());
}

// ---------------------------------------------------------------------------------
// Real meshes

/// (file, vertices, faces, boundary loops, Euler characteristic) from the shared
/// README; Euler characteristic 2 - 2g - b for genus g and b boundary loops.
///
/// Spot: the README's 3,225 vertices is its number of texture coordinates (`vt`
/// records; a UV-split count). By position it has 2,930 vertices (its `v` records),
/// and with 5,856 faces only 2,930 makes it the closed genus-0 surface it is.
///
/// Cow: the README says "open (one boundary)", but every edge of the file has two
/// faces (no boundary); one vertex (253, at z = 0) is pinched, joining two cones of
/// faces, which makes the Euler characteristic odd: a sphere with two points
/// identified, 2 - 1 = 1.
const SHARED: [(&str, usize, usize, usize, i64); 8] = [
    ("stanford-bunny.obj", 34_834, 69_451, 5, 2 - 5),
    ("rocker-arm.obj", 10_044, 20_088, 0, 0),
    ("fandisk.obj", 6_475, 12_946, 0, 2),
    ("homer.obj", 6_002, 12_000, 0, 2),
    ("spot.obj", 2_930, 5_856, 0, 2),
    ("cow.obj", 2_903, 5_804, 0, 1),
    ("two-torus.obj", 3_880, 7_764, 0, -2),
    ("wing.obj", 4_956, 9_908, 0, 2),
];

#[test]
fn shared_meshes_match_their_readme() {
    let Some(dir) = shared_mesh_dir() else {
        println!("shared meshes not found (set STRATA_MESH_DIR); skipping");
        return;
    };
    for (name, vertices, faces, loops, euler) in SHARED {
        let start = Instant::now();
        let mesh = io::load(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
        let elapsed = start.elapsed();
        println!(
            "{name}: {} vertices, {} faces, loaded in {elapsed:.2?}",
            mesh.vertex_count(),
            mesh.face_count()
        );
        assert_eq!(
            (mesh.vertex_count(), mesh.face_count()),
            (vertices, faces),
            "{name}"
        );
        assert_eq!(mesh.boundary_loops().len(), loops, "{name}");
        assert_eq!(mesh.euler_characteristic(), euler, "{name}");
        assert_eq!(mesh.component_count(), 1, "{name}");
        // The README promises clean meshes: nothing repaired, nothing found, except
        // that the bunny file has 35,947 `v` records of which 1,113 no face uses.
        let expected: &[MeshWarning] = if name == "stanford-bunny.obj" {
            &[MeshWarning::RemovedUnreferencedVertices { count: 1_113 }]
        } else {
            &[]
        };
        assert_eq!(mesh.warnings(), expected, "{name}");
    }
}

#[test]
fn shared_bunny_has_223_boundary_edges_and_loads_fast() {
    let Some(dir) = shared_mesh_dir() else {
        println!("shared meshes not found (set STRATA_MESH_DIR); skipping");
        return;
    };
    let start = Instant::now();
    let mesh = io::load(&dir.join("stanford-bunny.obj")).unwrap_or_else(|e| panic!("{e}"));
    let elapsed = start.elapsed();
    let boundary_edges: usize = mesh.boundary_loops().iter().map(Vec::len).sum();
    assert_eq!(boundary_edges, 223);
    assert_eq!(mesh.edge_valence().iter().filter(|&&v| v == 1).count(), 223);
    // Generous bound for a shared 2-core machine; typically far less (printed).
    println!("bunny load: {elapsed:.2?}");
    assert!(elapsed.as_secs_f64() < 2.0, "bunny took {elapsed:?}");
}

#[test]
fn shared_mesh_survives_a_binary_ply_round_trip_fast() {
    let Some(dir) = shared_mesh_dir() else {
        println!("shared meshes not found (set STRATA_MESH_DIR); skipping");
        return;
    };
    let mesh = io::load(&dir.join("stanford-bunny.obj")).unwrap_or_else(|e| panic!("{e}"));
    let mut bytes = Vec::new();
    io::write_mesh_ply_to(&mut bytes, &mesh, None).expect("write to memory");
    let start = Instant::now();
    let back = io::parse_ply(&bytes, Path::new("bunny.ply")).unwrap_or_else(|e| panic!("{e}"));
    let elapsed = start.elapsed();
    println!(
        "bunny binary PLY ({} bytes) parsed in {elapsed:.2?}",
        bytes.len()
    );
    assert!(elapsed.as_secs_f64() < 1.0, "took {elapsed:?}");
    assert_eq!(back.triangles(), mesh.triangles());
    for (a, b) in back.positions().iter().zip(mesh.positions()) {
        assert_eq!(a.as_vec3(), b.as_vec3());
    }
}

// ---------------------------------------------------------------------------------
// The project's corpus

#[test]
fn corpus_tetrahedron_obj_and_ply_agree() {
    assert_is_tetrahedron(&load("tetrahedron.obj"), "tetrahedron.obj");
    assert_is_tetrahedron(&load("tetrahedron-ascii.ply"), "tetrahedron-ascii.ply");
    assert!(load("tetrahedron.obj").boundary_loops().is_empty());
}

#[test]
fn corpus_cube_quads_are_triangulated_and_uv_seams_do_not_split() {
    let mesh = load("cube.obj");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (8, 12));
    assert_eq!(mesh.euler_characteristic(), 2);
    assert!(mesh.boundary_loops().is_empty());
    assert_eq!(
        mesh.warnings(),
        &[MeshWarning::TriangulatedPolygons { count: 6 }][..]
    );
    assert!((mesh.area() - 6.0).abs() < 1e-12);
    // Consistent outward winding: the signed volume is +1.
    let volume: f64 = (0..mesh.face_count() as u32)
        .map(|f| mesh.face_positions(f))
        .map(|[a, b, c]| a.dot(b.cross(c)) / 6.0)
        .sum();
    assert!((volume - 1.0).abs() < 1e-12, "volume {volume}");
}

#[test]
fn corpus_open_disk_has_one_boundary_loop() {
    let mesh = load("open-disk.obj");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (7, 6));
    assert_eq!(mesh.boundary_loops().len(), 1);
    assert_eq!(mesh.boundary_loops()[0].len(), 6);
    assert_eq!(mesh.euler_characteristic(), 1);
    // Relative indices -7 -6 -5 resolve to the centre and two rim vertices.
    assert_eq!(mesh.triangles()[0], [0, 1, 2]);
}

#[test]
fn corpus_two_components_from_two_objects() {
    let mesh = load("two-components.obj");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (8, 8));
    assert_eq!(mesh.component_count(), 2);
    assert_eq!(mesh.euler_characteristic(), 4);
    assert_eq!(
        mesh.warnings(),
        &[MeshWarning::SeveralComponents { count: 2 }][..]
    );
}

#[test]
fn corpus_slivers_are_kept() {
    let mesh = load("sliver.obj");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (7, 5));
    assert_eq!(
        (mesh.euler_characteristic(), mesh.boundary_loops().len()),
        (1, 1)
    );
    assert!(mesh.warnings().is_empty(), "{:?}", mesh.warnings());
    assert!(
        mesh.face_areas().iter().all(|&a| a > 0.0 && a < 1e-6),
        "{:?}",
        mesh.face_areas()
    );
}

#[test]
fn corpus_non_manifold_edge_is_reported() {
    let mesh = load("non-manifold.obj");
    assert_eq!(mesh.face_count(), 3);
    assert!(mesh.edge_valence().contains(&3));
    assert!(
        mesh.warnings().iter().any(
            |w| matches!(w, MeshWarning::NonManifoldEdges { count: 1, first } if first == &[[0, 1]])
        ),
        "{:?}",
        mesh.warnings()
    );
}

#[test]
fn corpus_degenerate_faces_are_removed_with_warnings() {
    let mesh = load("degenerate.obj");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (4, 4));
    let w = mesh.warnings();
    assert!(
        w.contains(&MeshWarning::RemovedDegenerateFaces {
            count: 2,
            first: vec![4, 5]
        }),
        "{w:?}"
    );
    assert!(
        w.contains(&MeshWarning::RemovedDuplicateFaces { count: 1 }),
        "{w:?}"
    );
    assert!(
        w.contains(&MeshWarning::RemovedUnreferencedVertices { count: 1 }),
        "{w:?}"
    );
}

#[test]
fn corpus_ply_extras_are_skipped() {
    assert_is_tetrahedron(&load("extras-ascii.ply"), "extras-ascii.ply");
}

#[test]
fn corpus_ply_triangle_strips() {
    let mesh = load("strips.ply");
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (12, 12));
    assert_eq!(mesh.euler_characteristic(), 1);
    assert_eq!(mesh.boundary_loops().len(), 1);
    assert!((mesh.area() - 6.0).abs() < 1e-12);
    // Alternating winding: every triangle faces +z, none is flipped.
    assert!(
        mesh.face_normals().iter().all(|n| n.z > 0.99),
        "{:?}",
        mesh.face_normals()
    );
    assert!(mesh.warnings().is_empty(), "{:?}", mesh.warnings());
}

// ---------------------------------------------------------------------------------
// Error reports: the variant, and a message naming the file and the line or element

fn assert_message(e: &MeshError, file: &str, parts: &[&str]) {
    let message = e.to_string();
    assert!(message.contains(file), "{message:?} should name {file}");
    for part in parts {
        assert!(
            message.contains(part),
            "{message:?} should contain {part:?}"
        );
    }
}

#[test]
fn error_ply_bad_magic_format_and_type_name_the_header_line() {
    for (file, line, what) in [
        ("bad-magic.ply", 1, "not a PLY file"),
        ("bad-format.ply", 2, "bad format line"),
        ("bad-type.ply", 5, "unknown property type `flaot`"),
        ("missing-z.ply", 3, "no property `z`"),
        ("no-faces.ply", 8, "no `face` element"),
    ] {
        let e = load_err(file);
        match &e {
            MeshError::Syntax { line: l, .. } if *l == line => {}
            other => panic!("{file}: expected Syntax at line {line}, got {other:?}"),
        }
        assert_message(&e, file, &[&format!("{file}:{line}:"), what]);
    }
}

#[test]
fn error_ply_ascii_non_number_names_the_line_and_record() {
    let e = load_err("bad-number.ply");
    assert!(matches!(e, MeshError::Syntax { line: 12, .. }), "{e:?}");
    assert_message(
        &e,
        "bad-number.ply",
        &["bad-number.ply:12:", "vertex 2", "`1.0.0` is not a number"],
    );
}

#[test]
fn error_ply_truncated_names_element_and_record() {
    let e = load_err("truncated.ply");
    match &e {
        MeshError::Truncated {
            element,
            index: 3,
            count: 4,
            ..
        } if element == "face" => {}
        other => panic!("expected Truncated face 3 of 4, got {other:?}"),
    }
    assert_message(&e, "truncated.ply", &["face 3 of 4"]);
}

fn assert_in_file(e: &MeshError, check: impl Fn(&MeshError) -> bool) {
    match e {
        MeshError::InFile { source, .. } if check(source) => {}
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn error_ply_index_out_of_range_names_the_face() {
    let e = load_err("out-of-range.ply");
    assert_in_file(&e, |s| {
        matches!(
            s,
            MeshError::IndexOutOfRange {
                face: 2,
                index: 7,
                vertex_count: 4
            }
        )
    });
    assert_message(&e, "out-of-range.ply", &["face 2", "vertex 7"]);
}

#[test]
fn error_ply_negative_index_is_not_wrapped() {
    let e = load_err("negative-index.ply");
    assert_in_file(&e, |s| {
        matches!(
            s,
            MeshError::IndexOutOfRange {
                face: 1,
                index: -1,
                ..
            }
        )
    });
    assert_message(&e, "negative-index.ply", &["face 1", "vertex -1"]);
}

#[test]
fn error_non_finite_coordinate_names_the_vertex() {
    for file in ["nan.ply", "nan.obj"] {
        let e = load_err(file);
        assert_in_file(
            &e,
            |s| matches!(s, MeshError::NonFiniteVertex { vertex: 1, x, .. } if x.is_nan()),
        );
        assert_message(&e, file, &["vertex 1", "non-finite"]);
    }
}

#[test]
fn error_obj_bad_lines_are_named() {
    for (file, line, what) in [
        (
            "out-of-range.obj",
            8,
            "face 2 refers to vertex 9, but 4 vertices are defined",
        ),
        ("zero-index.obj", 5, "face 0 refers to vertex 0"),
        ("bad-number.obj", 9, "`zero` is not a number"),
        ("truncated.obj", 5, "needs 3 coordinates"),
    ] {
        let e = load_err(file);
        assert!(
            matches!(&e, MeshError::Syntax { line: l, .. } if *l == line),
            "{file}: {e:?}"
        );
        assert_message(&e, file, &[&format!("{file}:{line}:"), what]);
    }
}

#[test]
fn error_unknown_extension_and_missing_file() {
    let e = io::load(Path::new("mesh.stl")).expect_err("stl");
    assert!(
        matches!(&e, MeshError::UnknownFormat { extension, .. } if extension == "stl"),
        "{e:?}"
    );
    assert_message(&e, "mesh.stl", &[]);
    let missing = corpus("does-not-exist.obj");
    let e = io::load(&missing).expect_err("missing");
    assert!(
        matches!(&e, MeshError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound),
        "{e:?}"
    );
    assert_message(&e, "does-not-exist.obj", &[]);
}

#[test]
fn load_picks_the_format_by_extension_in_any_case() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (from, to) in [
        ("tetrahedron.obj", "a.OBJ"),
        ("tetrahedron-ascii.ply", "b.Ply"),
    ] {
        let path = dir.path().join(to);
        std::fs::copy(corpus(from), &path).expect("copy");
        assert_is_tetrahedron(&io::load(&path).unwrap_or_else(|e| panic!("{e}")), to);
    }
    // The extension decides, not the content.
    let path = dir.path().join("c.ply");
    std::fs::copy(corpus("tetrahedron.obj"), &path).expect("copy");
    assert!(matches!(
        io::load(&path),
        Err(MeshError::Syntax { line: 1, .. })
    ));
}

// ---------------------------------------------------------------------------------
// PLY encodings and types, generated

#[derive(Clone, Copy, Debug, PartialEq)]
enum Fmt {
    Ascii,
    Le,
    Be,
}

#[derive(Clone, Copy, Debug)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    const ALL: [Ty; 8] = [
        Ty::I8,
        Ty::U8,
        Ty::I16,
        Ty::U16,
        Ty::I32,
        Ty::U32,
        Ty::F32,
        Ty::F64,
    ];

    fn name(self, sized: bool) -> &'static str {
        let (old, new) = match self {
            Ty::I8 => ("char", "int8"),
            Ty::U8 => ("uchar", "uint8"),
            Ty::I16 => ("short", "int16"),
            Ty::U16 => ("ushort", "uint16"),
            Ty::I32 => ("int", "int32"),
            Ty::U32 => ("uint", "uint32"),
            Ty::F32 => ("float", "float32"),
            Ty::F64 => ("double", "float64"),
        };
        if sized { new } else { old }
    }

    fn encode(self, v: f64, fmt: Fmt, out: &mut Vec<u8>) {
        macro_rules! put {
            ($t:ty) => {{
                let x = v as $t;
                out.extend_from_slice(&if fmt == Fmt::Be {
                    x.to_be_bytes()
                } else {
                    x.to_le_bytes()
                })
            }};
        }
        match self {
            Ty::I8 => put!(i8),
            Ty::U8 => put!(u8),
            Ty::I16 => put!(i16),
            Ty::U16 => put!(u16),
            Ty::I32 => put!(i32),
            Ty::U32 => put!(u32),
            Ty::F32 => put!(f32),
            Ty::F64 => put!(f64),
        }
    }
}

enum Prop {
    Scalar(&'static str, Ty),
    List(&'static str, Ty, Ty),
}

enum Val {
    S(f64),
    L(Vec<f64>),
}

struct El {
    name: &'static str,
    props: Vec<Prop>,
    rows: Vec<Vec<Val>>,
}

/// Encodes a PLY file; `sized` picks the `int8`-style type names.
fn ply_bytes(fmt: Fmt, sized: bool, elements: &[El]) -> Vec<u8> {
    let format = match fmt {
        Fmt::Ascii => "ascii",
        Fmt::Le => "binary_little_endian",
        Fmt::Be => "binary_big_endian",
    };
    let mut out = format!("ply\nformat {format} 1.0\ncomment generated by tests/io.rs\n");
    for el in elements {
        out.push_str(&format!("element {} {}\n", el.name, el.rows.len()));
        for p in &el.props {
            match p {
                Prop::Scalar(name, t) => {
                    out.push_str(&format!("property {} {name}\n", t.name(sized)))
                }
                Prop::List(name, c, t) => out.push_str(&format!(
                    "property list {} {} {name}\n",
                    c.name(sized),
                    t.name(sized)
                )),
            }
        }
    }
    out.push_str("end_header\n");
    let mut out = out.into_bytes();
    for el in elements {
        for row in &el.rows {
            let mut words: Vec<String> = Vec::new();
            let mut put = |t: Ty, x: f64, out: &mut Vec<u8>| match fmt {
                Fmt::Ascii => words.push(x.to_string()),
                Fmt::Le | Fmt::Be => t.encode(x, fmt, out),
            };
            for (p, v) in el.props.iter().zip(row) {
                match (p, v) {
                    (Prop::Scalar(_, t), Val::S(x)) => put(*t, *x, &mut out),
                    (Prop::List(_, c, t), Val::L(xs)) => {
                        put(*c, xs.len() as f64, &mut out);
                        for x in xs {
                            put(*t, *x, &mut out);
                        }
                    }
                    _ => panic!("value does not match property"),
                }
            }
            if fmt == Fmt::Ascii {
                out.extend_from_slice(words.join(" ").as_bytes());
                out.push(b'\n');
            }
        }
    }
    out
}

fn find(hay: &[u8], needle: &[u8]) -> usize {
    hay.windows(needle.len())
        .position(|w| w == needle)
        .expect("needle")
}

fn vertex_element(coord: Ty) -> El {
    let (positions, _) = tetrahedron();
    El {
        name: "vertex",
        props: vec![
            Prop::Scalar("x", coord),
            Prop::Scalar("y", coord),
            Prop::Scalar("z", coord),
        ],
        rows: positions
            .iter()
            .map(|p| vec![Val::S(p.x), Val::S(p.y), Val::S(p.z)])
            .collect(),
    }
}

fn face_element(count: Ty, index: Ty) -> El {
    let (_, triangles) = tetrahedron();
    El {
        name: "face",
        props: vec![Prop::List("vertex_indices", count, index)],
        rows: triangles
            .iter()
            .map(|t| vec![Val::L(t.iter().map(|&v| v as f64).collect())])
            .collect(),
    }
}

/// The tetrahedron wrapped in elements and properties to skip, lists included.
fn tetrahedron_with_extras(coord: Ty, count: Ty, index: Ty) -> Vec<El> {
    let (positions, triangles) = tetrahedron();
    let camera = El {
        name: "camera",
        props: vec![
            Prop::Scalar("px", Ty::F32),
            Prop::List("path", Ty::U8, Ty::F64),
            Prop::Scalar("flags", Ty::I32),
        ],
        rows: vec![
            vec![Val::S(0.5), Val::L(vec![1.0, 2.0]), Val::S(7.0)],
            vec![Val::S(1.5), Val::L(vec![]), Val::S(-3.0)],
        ],
    };
    let vertex = El {
        name: "vertex",
        props: vec![
            Prop::Scalar("nx", Ty::F64),
            Prop::List("weights", Ty::U16, Ty::F32),
            Prop::Scalar("x", coord),
            Prop::Scalar("red", Ty::U8),
            Prop::Scalar("y", coord),
            Prop::Scalar("label", Ty::I16),
            Prop::Scalar("z", coord),
        ],
        rows: positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                vec![
                    Val::S(0.25),
                    Val::L(vec![1.0; i]),
                    Val::S(p.x),
                    Val::S(200.0),
                    Val::S(p.y),
                    Val::S(-(i as f64)),
                    Val::S(p.z),
                ]
            })
            .collect(),
    };
    let material = El {
        name: "material",
        props: vec![Prop::List("name", Ty::I32, Ty::I8)],
        rows: vec![vec![Val::L(vec![109.0, 101.0, 115.0, 104.0, 0.0])]],
    };
    let face = El {
        name: "face",
        props: vec![
            Prop::Scalar("flags", Ty::I32),
            Prop::List("texcoord", Ty::U8, Ty::F32),
            Prop::List("vertex_indices", count, index),
            Prop::Scalar("green", Ty::U8),
        ],
        rows: triangles
            .iter()
            .map(|t| {
                vec![
                    Val::S(1.0),
                    Val::L(vec![0.5; 6]),
                    Val::L(t.iter().map(|&v| v as f64).collect()),
                    Val::S(9.0),
                ]
            })
            .collect(),
    };
    let edge = El {
        name: "edge",
        props: vec![
            Prop::Scalar("vertex1", Ty::I32),
            Prop::Scalar("vertex2", Ty::I32),
        ],
        rows: vec![
            vec![Val::S(0.0), Val::S(1.0)],
            vec![Val::S(1.0), Val::S(2.0)],
        ],
    };
    vec![camera, vertex, material, face, edge]
}

const FORMATS: [Fmt; 3] = [Fmt::Ascii, Fmt::Le, Fmt::Be];
/// (count type, index type) pairs for face lists.
const LISTS: [(Ty, Ty); 7] = [
    (Ty::U8, Ty::I32),
    (Ty::U8, Ty::U32),
    (Ty::I16, Ty::U16),
    (Ty::U16, Ty::I16),
    (Ty::U32, Ty::U32),
    (Ty::I8, Ty::U8),
    (Ty::I32, Ty::I8),
];

#[test]
fn ply_every_encoding_and_type_reads_the_same_mesh() {
    let mut checked = 0;
    for fmt in FORMATS {
        for sized in [false, true] {
            for coord in Ty::ALL {
                for (count, index) in LISTS {
                    let what =
                        format!("{fmt:?} sized={sized} coord={coord:?} list {count:?} {index:?}");
                    let bytes = ply_bytes(
                        fmt,
                        sized,
                        &[vertex_element(coord), face_element(count, index)],
                    );
                    let mesh = io::parse_ply(&bytes, Path::new("gen.ply"))
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_is_tetrahedron(&mesh, &what);
                    checked += 1;
                }
            }
        }
    }
    assert_eq!(checked, 3 * 2 * 8 * 7);
}

#[test]
fn ply_extras_are_skipped_in_every_encoding() {
    for fmt in FORMATS {
        for (count, index) in LISTS {
            let what = format!("{fmt:?} list {count:?} {index:?}");
            let bytes = ply_bytes(fmt, false, &tetrahedron_with_extras(Ty::F64, count, index));
            let mesh = io::parse_ply(&bytes, Path::new("extras.ply"))
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_is_tetrahedron(&mesh, &what);
        }
    }
}

#[test]
fn ply_binary_big_endian_is_not_read_as_little_endian() {
    // A wrong byte order would read 1.0f32 as 4.6e-41 and index 1 as 16777216.
    let bytes = ply_bytes(
        Fmt::Be,
        false,
        &[vertex_element(Ty::F32), face_element(Ty::U8, Ty::I32)],
    );
    assert_is_tetrahedron(
        &io::parse_ply(&bytes, Path::new("be.ply")).expect("valid"),
        "be",
    );
}

#[test]
fn ply_binary_strips_with_negative_restart() {
    for fmt in FORMATS {
        let strip = El {
            name: "tristrips",
            props: vec![Prop::List("vertex_indices", Ty::I32, Ty::I32)],
            rows: vec![vec![Val::L(vec![
                0.0, 2.0, 1.0, -1.0, 0.0, 1.0, 3.0, -1.0, 1.0, 2.0, 3.0, -1.0, 0.0, 3.0, 2.0,
            ])]],
        };
        let bytes = ply_bytes(fmt, false, &[vertex_element(Ty::F32), strip]);
        let mesh = io::parse_ply(&bytes, Path::new("strips.ply"))
            .unwrap_or_else(|e| panic!("{fmt:?}: {e}"));
        assert_is_tetrahedron(&mesh, &format!("{fmt:?}"));
    }
}

#[test]
fn ply_binary_truncated_body_reports_element_and_record() {
    for fmt in [Fmt::Le, Fmt::Be] {
        let bytes = ply_bytes(
            fmt,
            false,
            &[vertex_element(Ty::F32), face_element(Ty::U8, Ty::I32)],
        );
        // Cut in the middle of face 2 (each face takes 1 + 3 * 4 bytes).
        let cut = bytes.len() - 13 - 6;
        match io::parse_ply(&bytes[..cut], Path::new("cut.ply")) {
            Err(MeshError::Truncated {
                element,
                index: 2,
                count: 4,
                ..
            }) if element == "face" => {}
            other => panic!("{fmt:?}: {other:?}"),
        }
    }
}

#[test]
fn ply_binary_negative_index_of_every_signed_type_is_rejected() {
    for index in [Ty::I8, Ty::I16, Ty::I32] {
        let mut face = face_element(Ty::U8, index);
        face.rows[3] = vec![Val::L(vec![0.0, -1.0, 2.0])];
        let bytes = ply_bytes(Fmt::Le, false, &[vertex_element(Ty::F32), face]);
        let e = io::parse_ply(&bytes, Path::new("neg.ply")).expect_err("negative index");
        assert_in_file(&e, |s| {
            matches!(
                s,
                MeshError::IndexOutOfRange {
                    face: 3,
                    index: -1,
                    vertex_count: 4
                }
            )
        });
    }
}

#[test]
fn ply_binary_negative_list_length_is_a_syntax_error() {
    let mut face = face_element(Ty::I8, Ty::I32);
    face.rows[1] = vec![Val::L(vec![])];
    let mut bytes = ply_bytes(Fmt::Le, false, &[vertex_element(Ty::F32), face]);
    // Face 1 is the 1-byte record after face 0 (13 bytes); make its length -1.
    let face1 = bytes.len() - 13 - 13 - 1;
    assert_eq!(bytes[face1], 0);
    bytes[face1] = 0xff;
    let e = io::parse_ply(&bytes, Path::new("neg.ply")).expect_err("negative length");
    assert!(matches!(e, MeshError::Syntax { .. }), "{e:?}");
    assert_message(&e, "neg.ply", &["face 1", "negative list length -1"]);
}

#[test]
fn ply_huge_declared_counts_fail_cleanly() {
    // Declares 2^60 vertices; the reader must not try to allocate for them.
    let text = "ply\nformat binary_little_endian 1.0\nelement vertex 1152921504606846976\n\
                property float x\nproperty float y\nproperty float z\nelement face 0\n\
                property list uchar int vertex_indices\nend_header\n";
    match io::parse_ply(text.as_bytes(), Path::new("huge.ply")) {
        Err(MeshError::Truncated {
            index: 0,
            count: 1_152_921_504_606_846_976,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
}

// ---------------------------------------------------------------------------------
// Damaged files never panic

/// xorshift64*: a tiny seeded generator, so the test needs no extra crate.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

#[test]
fn fuzz_truncated_ply_errors_at_every_offset() {
    for fmt in FORMATS {
        let bytes = ply_bytes(
            fmt,
            false,
            &tetrahedron_with_extras(Ty::F32, Ty::U8, Ty::I32),
        );
        let body_start = find(&bytes, b"end_header\n") + "end_header\n".len();
        for cut in 0..bytes.len() {
            let result = io::parse_ply(&bytes[..cut], Path::new("cut.ply"));
            match (fmt, result) {
                // `end_header` without its line break still ends the header.
                (_, Err(MeshError::Syntax { .. })) if cut < body_start - 1 => {}
                (Fmt::Le | Fmt::Be, Err(MeshError::Truncated { .. })) if cut >= body_start - 1 => {}
                // ASCII: a cut inside a line leaves too few values on it, and the last
                // line is complete without its line break.
                (Fmt::Ascii, Err(MeshError::Truncated { .. } | MeshError::Syntax { .. }))
                    if cut >= body_start - 1 => {}
                (Fmt::Ascii, Ok(_)) if cut == bytes.len() - 1 => {}
                (_, other) => panic!("{fmt:?} cut at {cut} of {}: {other:?}", bytes.len()),
            }
        }
        assert!(io::parse_ply(&bytes, Path::new("whole.ply")).is_ok());
    }
}

#[test]
fn fuzz_flipped_bytes_never_panic() {
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let mut outcomes = [0usize; 2];
    for fmt in FORMATS {
        let original = ply_bytes(
            fmt,
            false,
            &tetrahedron_with_extras(Ty::F32, Ty::U8, Ty::I32),
        );
        for _ in 0..3000 {
            let mut bytes = original.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len());
                bytes[at] = rng.next() as u8;
            }
            let ok = io::parse_ply(&bytes, Path::new("flip.ply")).is_ok();
            outcomes[ok as usize] += 1;
        }
    }
    let text = std::fs::read(corpus("cube.obj")).expect("cube.obj");
    for _ in 0..3000 {
        let mut bytes = text.clone();
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(bytes.len());
            bytes[at] = b"0123456789 -/\nvf#.\xffe"[rng.below(19)];
        }
        let ok = io::parse_obj(&bytes, Path::new("flip.obj")).is_ok();
        outcomes[ok as usize] += 1;
    }
    for cut in 0..text.len() {
        let _ = io::parse_obj(&text[..cut], Path::new("cut.obj"));
    }
    // Both outcomes happen: the damage is neither always fatal nor always harmless.
    assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
}

// ---------------------------------------------------------------------------------
// Writers

#[test]
fn mesh_ply_round_trip_with_colours() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cube.ply");
    let mesh = load("cube.obj");
    let colors: Vec<[u8; 3]> = (0..mesh.face_count())
        .map(|f| [f as u8, 100, 255 - f as u8])
        .collect();
    io::write_mesh_ply(&path, &mesh, Some(&colors)).expect("write");
    let back = io::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back.triangles(), mesh.triangles());
    let as_f32 = |m: &TriMesh| {
        m.positions()
            .iter()
            .map(|p| p.as_vec3())
            .collect::<Vec<_>>()
    };
    assert_eq!(as_f32(&back), as_f32(&mesh));

    let bytes = std::fs::read(&path).expect("read");
    let header = String::from_utf8_lossy(&bytes[..find(&bytes, b"end_header\n")]).into_owned();
    assert!(
        header.contains("format binary_little_endian 1.0"),
        "{header}"
    );
    assert!(
        header.contains("property list uchar int vertex_indices\nproperty uchar red"),
        "{header}"
    );
    // The last record is the last face: 3, three ints, then its colour.
    let last = colors[colors.len() - 1];
    assert_eq!(&bytes[bytes.len() - 3..], &last);
    let t = mesh.triangles()[mesh.face_count() - 1];
    let record = &bytes[bytes.len() - 16..bytes.len() - 3];
    assert_eq!(record[0], 3);
    assert_eq!(
        i32::from_le_bytes([record[1], record[2], record[3], record[4]]),
        t[0] as i32
    );
    // Nothing left behind but the file itself.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, ["cube.ply"]);
}

#[test]
fn mesh_ply_without_colours_has_no_colour_properties() {
    let mesh = load("tetrahedron.obj");
    let mut bytes = Vec::new();
    io::write_mesh_ply_to(&mut bytes, &mesh, None).expect("write");
    let body = find(&bytes, b"end_header\n") + "end_header\n".len();
    assert!(!String::from_utf8_lossy(&bytes[..body]).contains("red"));
    assert_eq!(bytes.len() - body, 4 * 12 + 4 * 13);
    assert_is_tetrahedron(
        &io::parse_ply(&bytes, Path::new("mem.ply")).expect("valid"),
        "memory",
    );
}

#[test]
fn mesh_ply_with_wrong_colour_count_is_an_error_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("bad.ply");
    let mesh = load("tetrahedron.obj");
    let e =
        io::write_mesh_ply(&path, &mesh, Some(&[[0, 0, 0]; 3])).expect_err("3 colours for 4 faces");
    assert!(
        matches!(&e, MeshError::Io { source, .. } if source.kind() == std::io::ErrorKind::InvalidInput)
    );
    assert_message(&e, "bad.ply", &["3 face colours for 4 faces"]);
    assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0);
}

fn some_samples() -> Vec<Sample> {
    (0..50u32)
        .map(|i| {
            let t = i as f32 * 0.37;
            Sample {
                position: [t.sin(), t.cos(), t * 0.1],
                face: i * 7,
                normal: [0.0, 0.0, 1.0],
                segment: i % 3,
                major_axis: [t.cos(), -t.sin(), 0.0],
                index: 1000 + i,
                bary: [0.25, 1.0 / 3.0],
                spacing: [0.01 + t, 0.02 * t],
            }
        })
        .collect()
}

#[test]
fn samples_ply_round_trip() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("samples.ply");
    let samples = some_samples();
    io::write_samples_ply(&path, &samples).expect("write");
    let back = io::read_samples_ply(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back, samples);
    let bytes = std::fs::read(&path).expect("read");
    let body = find(&bytes, b"end_header\n") + "end_header\n".len();
    assert_eq!(bytes.len() - body, 64 * samples.len());
    let header = String::from_utf8_lossy(&bytes[..body]).into_owned();
    assert!(header.contains(
        "property uint face\nproperty float bary1\nproperty float bary2\nproperty uint segment"
    ));
}

#[test]
fn samples_ply_reader_takes_what_is_there() {
    // A plain point cloud: only positions, as doubles, plus a property to skip.
    let cloud = El {
        name: "vertex",
        props: vec![
            Prop::Scalar("z", Ty::F64),
            Prop::Scalar("x", Ty::F64),
            Prop::Scalar("y", Ty::F64),
            Prop::Scalar("face", Ty::U8),
        ],
        rows: vec![vec![Val::S(3.0), Val::S(1.0), Val::S(2.0), Val::S(9.0)]],
    };
    let bytes = ply_bytes(Fmt::Be, false, &[cloud]);
    let samples = io::parse_samples_ply(&bytes, Path::new("cloud.ply")).expect("valid");
    assert_eq!(
        samples,
        [Sample {
            position: [1.0, 2.0, 3.0],
            face: 9,
            ..Default::default()
        }]
    );
}

#[test]
fn samples_csv_has_header_and_rows() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("samples.csv");
    let samples = some_samples();
    io::write_samples_csv(&path, &samples).expect("write");
    let text = std::fs::read_to_string(&path).expect("read");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "x,y,z,nx,ny,nz,major_x,major_y,major_z,spacing_major,spacing_minor,face,bary1,bary2,segment,index"
        )
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), samples.len());
    for (row, s) in rows.iter().zip(&samples) {
        assert_eq!(row.len(), 16);
        let f = |i: usize| row[i].parse::<f32>().expect("float");
        assert_eq!([f(0), f(1), f(2)], s.position);
        assert_eq!([f(9), f(10)], s.spacing);
        assert_eq!([f(12), f(13)], s.bary);
        assert_eq!(
            [row[11], row[14], row[15]].map(str::to_owned),
            [s.face, s.segment, s.index].map(|v| v.to_string())
        );
    }
}

#[test]
fn writers_replace_files_atomically_and_report_bad_paths() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.csv");
    std::fs::write(&path, "old contents").expect("write");
    io::write_samples_csv(&path, &some_samples()[..2]).expect("overwrite");
    let text = std::fs::read_to_string(&path).expect("read");
    assert!(text.starts_with("x,y,z,"), "{text}");
    assert_eq!(text.lines().count(), 3);
    let names = || {
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    assert_eq!(
        names(),
        ["out.csv"],
        "the temporary file was renamed over the target"
    );

    // When the last step, the rename over the target, fails (here the target is a
    // folder), the write fails, the target stays as it was and the temporary file
    // beside it is removed.
    let folder = dir.path().join("taken.csv");
    std::fs::create_dir(&folder).expect("mkdir");
    std::fs::write(folder.join("inside"), "x").expect("write");
    let e = io::write_samples_csv(&folder, &some_samples()).expect_err("target is a folder");
    assert!(
        matches!(&e, MeshError::Io { path, .. } if path == &folder),
        "{e:?}"
    );
    assert_eq!(
        std::fs::read_to_string(folder.join("inside")).expect("read"),
        "x"
    );
    assert_eq!(std::fs::read_to_string(&path).expect("read"), text);
    assert_eq!(names(), ["out.csv", "taken.csv"]);

    let missing = dir.path().join("no-such-folder").join("s.ply");
    let e = io::write_samples_ply(&missing, &some_samples()).expect_err("no folder");
    assert!(
        matches!(&e, MeshError::Io { path, .. } if path == &missing),
        "{e:?}"
    );
    assert_message(&e, "s.ply", &[]);
}
