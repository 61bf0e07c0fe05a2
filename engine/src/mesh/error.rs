//! Errors of the mesh stage: construction, validation and file I/O.

use std::path::PathBuf;

/// Everything that can go wrong building or loading a [`TriMesh`](super::TriMesh).
///
/// Every variant carries what a user needs to find the problem: the file, the line or
/// element, the offending index.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The mesh has no vertices or no (non-degenerate) triangles.
    #[error("mesh is empty: {vertices} vertices, {faces} usable faces")]
    Empty {
        /// Vertices given.
        vertices: usize,
        /// Faces left after removing degenerate ones.
        faces: usize,
    },
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index}, but the mesh has {vertex_count} vertices")]
    IndexOutOfRange {
        /// Face index (in input order).
        face: usize,
        /// The offending vertex index.
        index: i64,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFiniteVertex {
        /// Vertex index (in input order).
        vertex: usize,
        /// x coordinate.
        x: f64,
        /// y coordinate.
        y: f64,
        /// z coordinate.
        z: f64,
    },
    /// A vertex coordinate is beyond [`MAX_COORDINATE`](super::MAX_COORDINATE).
    #[error(
        "vertex {vertex} at ({x:.3e}, {y:.3e}, {z:.3e}) is beyond the supported coordinate \
         range of +-1e50; scale the mesh down"
    )]
    CoordinateOutOfRange {
        /// Vertex index (in input order).
        vertex: usize,
        /// x coordinate.
        x: f64,
        /// y coordinate.
        y: f64,
        /// z coordinate.
        z: f64,
    },
    /// The mesh's bounding box is smaller than [`MIN_EXTENT`](super::MIN_EXTENT).
    #[error(
        "the mesh spans only {extent:.3e} (its bounding-box diagonal); the smallest \
         supported is 1e-50, so scale the mesh up"
    )]
    TooSmall {
        /// The bounding-box diagonal.
        extent: f64,
    },
    /// A polygon with fewer than three corners.
    #[error("face {face} has {corners} corners; at least 3 are needed")]
    TooFewCorners {
        /// Face index (in input order).
        face: usize,
        /// Number of corners.
        corners: usize,
    },
    /// The file could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file's extension names no format we read.
    #[error("{path}: unknown mesh format {extension:?} (expected .obj or .ply)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its extension (empty if none).
        extension: String,
    },
    /// The file is not valid in its format.
    #[error("{path}:{line}: {what}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line (for text formats) or 0 for binary content.
        line: usize,
        /// What is wrong, in words.
        what: String,
    },
    /// The file ends before all declared data was read.
    #[error("{path}: file ends early: {element} {index} of {count} is missing or incomplete")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The PLY element (or OBJ record kind) being read.
        element: String,
        /// Index of the first missing item.
        index: usize,
        /// Number of items declared.
        count: usize,
    },
    /// The file uses an element or property we do not read (for example PLY `tristrips`).
    #[error("{path}: unsupported {what}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is unsupported, named as in the file.
        what: String,
    },
    /// A built-in [`shapes`](super::shapes) generator was given a parameter outside its
    /// valid range (a non-positive or non-finite length, a resolution of 0, or one that
    /// would need more than [`MAX_SHAPE_FACES`](super::shapes::MAX_SHAPE_FACES) faces).
    #[error("{shape}: {parameter} = {value} is invalid; expected {expected}")]
    InvalidShapeParameter {
        /// The shape, as its generator is named (`"sphere"`, `"genus2"`, ...).
        shape: &'static str,
        /// The parameter, as named in the generator's signature.
        parameter: &'static str,
        /// The value given (integer parameters converted exactly).
        value: f64,
        /// The valid range, in words.
        expected: &'static str,
    },
    /// A file was read, but its content does not make a valid mesh; `source` is the
    /// construction error (out-of-range or negative index, non-finite vertex, empty
    /// mesh, face with too few corners), with indices in file order.
    #[error("{path}: {source}")]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with the content.
        #[source]
        source: Box<MeshError>,
    },
}

/// Something that was repaired or is worth knowing about a mesh, reported as data
/// (the engine does not log).
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum MeshWarning {
    /// Vertices at bitwise-identical positions were merged into one.
    MergedDuplicateVertices {
        /// How many input vertices were merged away.
        count: usize,
    },
    /// Faces with a repeated vertex or zero area were removed.
    RemovedDegenerateFaces {
        /// How many.
        count: usize,
        /// The first few removed faces (input indices).
        first: Vec<usize>,
    },
    /// Faces that repeat another face's vertices were removed.
    RemovedDuplicateFaces {
        /// How many.
        count: usize,
    },
    /// Vertices used by no face were dropped.
    RemovedUnreferencedVertices {
        /// How many.
        count: usize,
    },
    /// Edges shared by more than two faces. They are kept, and treated as boundary
    /// edges by the face adjacency, so that later stages never walk across them.
    NonManifoldEdges {
        /// How many edges.
        count: usize,
        /// The first few, as vertex pairs (output indices).
        first: Vec<[u32; 2]>,
    },
    /// The mesh has several connected components.
    SeveralComponents {
        /// How many.
        count: usize,
    },
    /// Faces of one or two corners (points and lines in an OBJ file) were skipped: a
    /// surface has none, and a file cut short in a face line ends with one.
    SkippedPointsAndLines {
        /// How many.
        count: usize,
        /// The lines (from 1) of the first few.
        first_lines: Vec<usize>,
    },
    /// Polygons with more than three corners were triangulated (fan triangulation).
    TriangulatedPolygons {
        /// How many polygons.
        count: usize,
    },
}

impl std::fmt::Display for MeshWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::MergedDuplicateVertices { count } => {
                write!(f, "merged {count} duplicated vertices")
            }
            Self::RemovedDegenerateFaces { count, first } => {
                write!(f, "removed {count} degenerate faces (first: {first:?})")
            }
            Self::RemovedDuplicateFaces { count } => write!(f, "removed {count} duplicated faces"),
            Self::RemovedUnreferencedVertices { count } => {
                write!(f, "dropped {count} vertices used by no face")
            }
            Self::NonManifoldEdges { count, first } => write!(
                f,
                "{count} non-manifold edges (shared by more than two faces; first: {first:?}); treated as boundaries"
            ),
            Self::SeveralComponents { count } => write!(f, "mesh has {count} connected components"),
            Self::TriangulatedPolygons { count } => {
                write!(f, "triangulated {count} polygons with more than 3 corners")
            }
            Self::SkippedPointsAndLines { count, first_lines } => write!(
                f,
                "skipped {count} faces of one or two corners (points or lines; a file cut short ends with one) on lines {}",
                first_lines
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
                    + if *count > first_lines.len() {
                        ", ..."
                    } else {
                        ""
                    }
            ),
        }
    }
}
