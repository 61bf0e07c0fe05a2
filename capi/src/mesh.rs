//! Meshes and fields: `StrataMesh` from caller arrays (f32 or f64 positions, u32 or
//! u64 indices), a mesh file or a built-in shape; `StrataField` from a field
//! description, per-vertex tensors or a scene file (which also gives its mesh and its
//! preprocessing settings).
//!
//! Cost: that of the engine's mesh construction (O(faces), validated) and field builds.

#![allow(unsafe_code)] // `#[unsafe(no_mangle)]` exports only; see `handle.rs` for the rest.

use std::ffi::{c_char, c_void};
use std::path::Path;
use std::sync::Arc;

use glam::{DMat3, DVec3};
use strata_engine::field::{FieldSpec, TensorField};
use strata_engine::mesh::TriMesh;
use strata_engine::mesh::shapes::Shape;
use strata_engine::surface::SurfaceOptions;
use strata_systems::config::SceneConfig;
use strata_systems::scene::load_mesh;

use crate::handle::{
    Failure, Handle, Kind, Outcome, StrataStatus, borrow, check_struct_size, engine_error, guard,
    register, release, require_out, slice, text, write_out,
};

/// A validated triangle mesh (opaque). Immutable once made: any thread may use it,
/// concurrently; free it once, after the calls that use it returned (builds and
/// samplers keep their own reference, so it may be freed while they live).
pub struct StrataMesh {
    pub(crate) mesh: Arc<TriMesh>,
}

impl Handle for StrataMesh {
    const KIND: Kind = Kind::Mesh;
}

/// A tensor field on a mesh, with the preprocessing settings a build uses by default
/// (opaque). Immutable: any thread, concurrently; free it once, after the calls that
/// use it returned.
pub struct StrataField {
    pub(crate) mesh: Arc<TriMesh>,
    pub(crate) field: Arc<TensorField>,
    pub(crate) options: SurfaceOptions,
}

impl Handle for StrataField {
    const KIND: Kind = Kind::Field;
}

/// `StrataMeshArrays::position_type`: three `float`s per vertex.
pub const STRATA_F32: u32 = 1;
/// `StrataMeshArrays::position_type`: three `double`s per vertex.
pub const STRATA_F64: u32 = 2;
/// `StrataMeshArrays::index_type`: `uint32_t` indices.
pub const STRATA_U32: u32 = 3;
/// `StrataMeshArrays::index_type`: `uint64_t` indices.
pub const STRATA_U64: u32 = 4;

/// A mesh as caller arrays, for `strata_mesh_from_arrays`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct StrataMeshArrays {
    /// `sizeof(StrataMeshArrays)`.
    pub struct_size: u32,
    /// `STRATA_F32` or `STRATA_F64`.
    pub position_type: u32,
    /// `vertex_count * 3` coordinates (x, y, z per vertex), of `position_type`.
    pub positions: *const c_void,
    /// Vertices; at least 3.
    pub vertex_count: usize,
    /// `STRATA_U32` or `STRATA_U64`.
    pub index_type: u32,
    /// `index_count` vertex indices, three per triangle, of `index_type`.
    pub indices: *const c_void,
    /// Indices; a positive multiple of 3.
    pub index_count: usize,
}

fn mesh_from_arrays(arrays: &StrataMeshArrays) -> Outcome<TriMesh> {
    check_struct_size(
        arrays.struct_size,
        size_of::<StrataMeshArrays>(),
        "StrataMeshArrays",
    )?;
    let invalid = |m: String| Failure::new(StrataStatus::InvalidArgument, m);
    if arrays.vertex_count < 3 {
        return Err(invalid(format!(
            "vertex_count is {}, a mesh needs at least 3",
            arrays.vertex_count
        )));
    }
    if arrays.index_count == 0 || !arrays.index_count.is_multiple_of(3) {
        return Err(invalid(format!(
            "index_count is {}, it must be a positive multiple of 3",
            arrays.index_count
        )));
    }
    let coords = arrays
        .vertex_count
        .checked_mul(3)
        .ok_or_else(|| invalid("vertex_count is too large".into()))?;
    let positions: Vec<DVec3> = match arrays.position_type {
        STRATA_F32 => slice(arrays.positions.cast::<f32>(), coords, "positions")?
            .chunks_exact(3)
            .map(|p| DVec3::new(p[0].into(), p[1].into(), p[2].into()))
            .collect(),
        STRATA_F64 => slice(arrays.positions.cast::<f64>(), coords, "positions")?
            .chunks_exact(3)
            .map(|p| DVec3::new(p[0], p[1], p[2]))
            .collect(),
        other => {
            return Err(invalid(format!(
                "position_type is {other}, expected STRATA_F32 or STRATA_F64"
            )));
        }
    };
    let n = arrays.index_count;
    let vertices = arrays.vertex_count;
    let index = |i: u64| -> Outcome<u32> {
        u32::try_from(i)
            .ok()
            .filter(|&v| (v as usize) < vertices)
            .ok_or_else(|| invalid(format!("index {i} is not a vertex (of {vertices})")))
    };
    let flat: Vec<u32> = match arrays.index_type {
        STRATA_U32 => slice(arrays.indices.cast::<u32>(), n, "indices")?
            .iter()
            .map(|&i| index(u64::from(i)))
            .collect::<Outcome<_>>()?,
        STRATA_U64 => slice(arrays.indices.cast::<u64>(), n, "indices")?
            .iter()
            .map(|&i| index(i))
            .collect::<Outcome<_>>()?,
        other => {
            return Err(invalid(format!(
                "index_type is {other}, expected STRATA_U32 or STRATA_U64"
            )));
        }
    };
    let triangles = flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    TriMesh::new(positions, triangles).map_err(|e| engine_error(StrataStatus::Mesh, "mesh", e))
}

/// Makes a mesh from caller arrays (copied: the arrays may be freed after the call).
/// Errors: null pointers, a wrong `struct_size`, counts out of range, an index that is
/// not a vertex, and the engine's mesh validation (degenerate or non-manifold faces,
/// NaN positions).
///
/// # Safety
/// `arrays` points to a `StrataMeshArrays` whose arrays hold the counts it gives;
/// `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_mesh_from_arrays(
    arrays: *const StrataMeshArrays,
    out: *mut *mut StrataMesh,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let arrays = slice(arrays, 1, "arrays")?;
        let mesh = mesh_from_arrays(&arrays[0])?;
        write_out(out, register(StrataMesh { mesh: mesh.into() }), "out")
    })
}

/// Loads a mesh file (OBJ or PLY, by extension).
///
/// # Safety
/// `path` is a NUL-terminated UTF-8 string; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_mesh_load(
    path: *const c_char,
    out: *mut *mut StrataMesh,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let path = text(path, "path")?;
        let mesh = strata_engine::io::load(Path::new(path))
            .map_err(|e| engine_error(StrataStatus::Mesh, "mesh", e))?;
        write_out(out, register(StrataMesh { mesh: mesh.into() }), "out")
    })
}

/// Builds a built-in shape from its RON description, for example
/// `"Sphere(radius: 1.0, resolution: 8)"` or `"Torus(major_radius: 1.0, minor_radius: 0.4)"`.
///
/// # Safety
/// `shape` is a NUL-terminated UTF-8 string; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_mesh_shape(
    shape: *const c_char,
    out: *mut *mut StrataMesh,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let shape: Shape = ron::from_str(text(shape, "shape")?)
            .map_err(|e| engine_error(StrataStatus::Config, "shape", e))?;
        let mesh = shape
            .build()
            .map_err(|e| engine_error(StrataStatus::Mesh, "shape", e))?;
        write_out(out, register(StrataMesh { mesh: mesh.into() }), "out")
    })
}

/// The mesh's vertex and face counts (either out-pointer may be null).
///
/// # Safety
/// `mesh` is a handle from this library; non-null out-pointers are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_mesh_counts(
    mesh: *const StrataMesh,
    vertices: *mut usize,
    faces: *mut usize,
) -> StrataStatus {
    guard(|| {
        let mesh = &borrow(mesh, "mesh")?.mesh;
        if !vertices.is_null() {
            write_out(vertices, mesh.vertex_count(), "vertices")?;
        }
        if !faces.is_null() {
            write_out(faces, mesh.face_count(), "faces")?;
        }
        Ok(())
    })
}

/// The mesh's axis-aligned bounds: `min` and `max` each receive 3 doubles (x, y, z).
///
/// # Safety
/// `mesh` is a handle from this library; `min` and `max` hold 3 doubles each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_mesh_bounds(
    mesh: *const StrataMesh,
    min: *mut f64,
    max: *mut f64,
) -> StrataStatus {
    guard(|| {
        let mesh = &borrow(mesh, "mesh")?.mesh;
        let min = crate::handle::slice_mut(min, 3, "min")?;
        let max = crate::handle::slice_mut(max, 3, "max")?;
        let (lo, hi) = mesh.bounds();
        min.copy_from_slice(&lo.to_array());
        max.copy_from_slice(&hi.to_array());
        Ok(())
    })
}

/// Frees a mesh (null: nothing). A handle freed twice is refused with
/// `STRATA_STATUS_INVALID_HANDLE` while its address has not been reused.
///
/// # Safety
/// `mesh` is null or a handle from this library, used by no other call now.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_mesh_free(mesh: *mut StrataMesh) -> StrataStatus {
    guard(|| release(mesh, "mesh"))
}

/// Builds a field on `mesh` from its RON description (the `field:` of a scene file),
/// for example `"Constant(direction: (1.0, 0.0, 0.0), anisotropy: 3.0, density: 1.0)"`
/// or `"Curvature(max_anisotropy: 3.0)"`. Its build settings are the defaults.
///
/// # Safety
/// `mesh` is a handle from this library; `spec` a NUL-terminated UTF-8 string; `out`
/// is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_field_from_spec(
    mesh: *const StrataMesh,
    spec: *const c_char,
    out: *mut *mut StrataField,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let mesh = borrow(mesh, "mesh")?.mesh.clone();
        let spec: FieldSpec = ron::from_str(text(spec, "spec")?)
            .map_err(|e| engine_error(StrataStatus::Config, "field spec", e))?;
        let field = spec
            .build(&mesh)
            .map_err(|e| engine_error(StrataStatus::Field, "field", e))?;
        let handle = StrataField {
            mesh,
            field: field.into(),
            options: SurfaceOptions::default(),
        };
        write_out(out, register(handle), "out")
    })
}

/// Makes a field from one symmetric 3x3 tensor per vertex, 9 doubles each in
/// column-major order (`tensor_len` = 9 x vertices).
///
/// # Safety
/// `mesh` is a handle from this library; `tensors` holds `tensor_len` doubles; `out`
/// is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_field_from_tensors(
    mesh: *const StrataMesh,
    tensors: *const f64,
    tensor_len: usize,
    out: *mut *mut StrataField,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let mesh = borrow(mesh, "mesh")?.mesh.clone();
        let expected = mesh.vertex_count() * 9;
        if tensor_len != expected {
            return Err(Failure::new(
                StrataStatus::InvalidArgument,
                format!(
                    "tensor_len is {tensor_len}, expected 9 per vertex: {expected} for {} vertices",
                    mesh.vertex_count()
                ),
            ));
        }
        let values = slice(tensors, tensor_len, "tensors")?;
        let tensors = values
            .chunks_exact(9)
            .map(|c| DMat3::from_cols_slice(c))
            .collect();
        let field = TensorField::new(&mesh, tensors)
            .map_err(|e| engine_error(StrataStatus::Field, "field", e))?;
        let handle = StrataField {
            mesh,
            field: field.into(),
            options: SurfaceOptions::default(),
        };
        write_out(out, register(handle), "out")
    })
}

/// Loads a scene file (RON, as `strata sample --config` reads): its mesh and its
/// field, the field carrying the scene's preprocessing settings.
///
/// # Safety
/// `path` is a NUL-terminated UTF-8 string; `mesh` and `field` are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_scene_load(
    path: *const c_char,
    mesh: *mut *mut StrataMesh,
    field: *mut *mut StrataField,
) -> StrataStatus {
    guard(|| {
        require_out(mesh, "mesh")?;
        require_out(field, "field")?;
        let path = text(path, "path")?;
        let config = SceneConfig::load(Path::new(path))
            .map_err(|e| engine_error(StrataStatus::Config, "scene", e))?;
        let loaded =
            load_mesh(&config).map_err(|e| engine_error(StrataStatus::Mesh, "scene mesh", e))?;
        let loaded = Arc::new(loaded);
        let built = config
            .field
            .build(&loaded)
            .map_err(|e| engine_error(StrataStatus::Field, "scene field", e))?;
        let field_handle = StrataField {
            mesh: loaded.clone(),
            field: built.into(),
            options: config.surface_options(),
        };
        write_out(mesh, register(StrataMesh { mesh: loaded }), "mesh")?;
        write_out(field, register(field_handle), "field")
    })
}

/// Frees a field (null: nothing); see `strata_mesh_free`.
///
/// # Safety
/// `field` is null or a handle from this library, used by no other call now.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_field_free(field: *mut StrataField) -> StrataStatus {
    guard(|| release(field, "field"))
}
