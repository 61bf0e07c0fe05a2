/* strata's C API, generated from capi/src by cbindgen (capi/cbindgen.toml): do not edit.
 *
 * Every function returns a StrataStatus; on failure strata_last_error() gives a
 * one-line message (per thread). Handles are opaque pointers made by a strata_ function
 * and freed once by their strata_*_free. Option structs begin with struct_size: set it
 * to sizeof the struct. docs/c-api.md is the guide: thread safety, the build loop,
 * examples in C, C++ and C#. */

#ifndef STRATA_H
#define STRATA_H



#include <stddef.h>
#include <stdint.h>

// The API version this library implements: `major * 10000 + minor * 100 + patch`.
// Hosts compare it with the header's `STRATA_API_VERSION`; the major part changes
// when a function or struct changes incompatibly.
#define STRATA_API_VERSION 100

// `StrataBuildProgress::stage`: waiting for a build thread.
#define STRATA_STAGE_QUEUED 0

// Preparing the field and segmenting.
#define STRATA_STAGE_SEGMENTATION 1

// Parameterizing segments, splitting invalid ones.
#define STRATA_STAGE_PARAMETERIZATION 2

// Building adaptive Hilbert cells.
#define STRATA_STAGE_CELLS 3

// Linking segments into chains.
#define STRATA_STAGE_CHAINS 4

// Done: successfully, with an error, or cancelled (`strata_build_take` says which).
#define STRATA_STAGE_FINISHED 5

// `strata_lod_changes`: the ranks that became visible.
#define STRATA_LOD_SHOWN 0

// `strata_lod_changes`: the ranks that became hidden.
#define STRATA_LOD_HIDDEN 1

// `StrataMeshArrays::position_type`: three `float`s per vertex.
#define STRATA_F32 1

// `StrataMeshArrays::position_type`: three `double`s per vertex.
#define STRATA_F64 2

// `StrataMeshArrays::index_type`: `uint32_t` indices.
#define STRATA_U32 3

// `StrataMeshArrays::index_type`: `uint64_t` indices.
#define STRATA_U64 4

// `StrataSampleRequest::mode`: `count` samples stratified for exactly that count
// (the engine's `sample_into`).
#define STRATA_STRATIFIED 0

// `StrataSampleRequest::mode`: ranks `first_rank..first_rank + count` of the seed's
// progressive sequence (fewer samples are a prefix of more; `progressive_into`).
#define STRATA_PROGRESSIVE 1

// The result of every `strata_` function that can fail. On anything but
// `STRATA_STATUS_OK`, `strata_last_error` holds a one-line message with the cause.
typedef enum StrataStatus {
  // Success.
  STRATA_STATUS_OK = 0,
  // A required pointer was null.
  STRATA_STATUS_NULL_POINTER = 1,
  // An argument out of range: a zero or mismatched size, an unknown mode, a
  // `struct_size` this library does not know, a string that is not UTF-8.
  STRATA_STATUS_INVALID_ARGUMENT = 2,
  // A handle that is not live (freed already, or never made by this library), or
  // of another kind than the function takes.
  STRATA_STATUS_INVALID_HANDLE = 3,
  // The mesh could not be read or built (the engine's message says why).
  STRATA_STATUS_MESH = 4,
  // The field could not be built.
  STRATA_STATUS_FIELD = 5,
  // Preprocessing failed.
  STRATA_STATUS_BUILD = 6,
  // The build was cancelled.
  STRATA_STATUS_CANCELLED = 7,
  // The build has not finished: poll again later.
  STRATA_STATUS_NOT_READY = 8,
  // A scene file or a RON text could not be read.
  STRATA_STATUS_CONFIG = 9,
  // A level-of-detail view or pool was refused.
  STRATA_STATUS_LOD = 10,
  // A panic inside the library was caught (a bug in strata; the message says where).
  STRATA_STATUS_PANIC = 11,
} StrataStatus;

// A background build (opaque). Any thread may poll, cancel or take it; `take`
// succeeds once. Freeing a running build cancels it (the build thread stops at its
// next check and drops its result).
typedef struct StrataBuild StrataBuild;

// A tensor field on a mesh, with the preprocessing settings a build uses by default
// (opaque). Immutable: any thread, concurrently; free it once, after the calls that
// use it returned.
typedef struct StrataField StrataField;

// A level-of-detail pool (opaque). Any thread may call it; calls on one pool take
// turns (it holds a lock). It keeps its own reference to the sampler's data, so the
// sampler may be freed before it.
typedef struct StrataLod StrataLod;

// A validated triangle mesh (opaque). Immutable once made: any thread may use it,
// concurrently; free it once, after the calls that use it returned (builds and
// samplers keep their own reference, so it may be freed while they live).
typedef struct StrataMesh StrataMesh;

// A preprocessed surface, ready to sample (opaque). Any thread may sample it,
// concurrently: calls that write records only run in parallel; calls that ask for
// separate arrays without records share the sampler's scratch and take turns. Free
// it once, after the calls that use it (and the level-of-detail pools made from it)
// are done with it.
typedef struct StrataSampler StrataSampler;

// Build settings, for `strata_build` and `strata_build_start`. A null pointer means
// the field's settings.
typedef struct StrataBuildOptions {
  // `sizeof(StrataBuildOptions)`.
  uint32_t struct_size;
  // The engine's `SurfaceOptions` in RON (for example
  // `"(curve: (max_cells: 4096))"`; omitted settings keep their defaults), or null
  // for the field's settings (a scene's, or the defaults).
  const char *surface_ron;
} StrataBuildOptions;

// A background build's state, as `strata_build_poll` writes it.
typedef struct StrataBuildProgress {
  // One of the `STRATA_STAGE_` values.
  uint32_t stage;
  // 1 when the result can be taken (`stage` is `STRATA_STAGE_FINISHED`), else 0.
  uint32_t finished;
  // Items of the stage done (segments).
  uint64_t done;
  // Items of the stage in all (0 when the stage does not count items).
  uint64_t total;
  // `done / total` in [0, 1] (0 for a stage of no items).
  double fraction;
} StrataBuildProgress;

// A camera, for `strata_lod_update`.
typedef struct StrataView {
  // `sizeof(StrataView)`.
  uint32_t struct_size;
  // 1: faces turned away from the eye show nothing; 0: they show like the others.
  uint32_t cull_back_faces;
  // Clip-from-world matrix (projection times view) of a perspective camera with a
  // rigid view, column-major, clip z in [0, w] (Direct3D, Vulkan, Metal, wgpu). The
  // eye and the focal length are taken from it.
  double view_projection[16];
  // Viewport width in pixels (> 0).
  double viewport_width;
  // Viewport height in pixels (> 0).
  double viewport_height;
  // Screen area (pixels^2) that a unit of surface area covers where the density
  // multiplier is 1 (> 0): larger shows fewer samples up close.
  double reference;
  // Largest multiplier (> 0; infinity for none).
  double max;
  // The base count: samples over the whole surface where the multiplier is 1.
  double base_count;
  // A point budget: when > 0, the base count is chosen so that about this many
  // samples show (`base_count` then applies only to a view of nothing).
  uint32_t shown;
} StrataView;

// What one `strata_lod_update` did.
typedef struct StrataLodFrame {
  // The base count the frame thresholds with.
  double base;
  // Entries (sites) the pool holds.
  uint64_t entries;
  // Ranks visible now.
  uint64_t visible;
  // Ranks that became visible since the last update (`strata_lod_changes`).
  uint64_t became_visible;
  // Ranks that became hidden since the last update.
  uint64_t became_hidden;
  // 1 when the pool's extension was rebuilt (its entry order changed), else 0.
  uint32_t rebuilt;
} StrataLodFrame;

// One sample, 64 bytes, the layout of the engine's `Sample` (and of the WGSL
// `Sample` in strata's shaders), so an array of them can be uploaded to a GPU as is:
//
// | offset | field | |
// | --- | --- | --- |
// | 0 | `position[3]` | world space |
// | 12 | `face` | the mesh face it lies on |
// | 16 | `normal[3]` | unit normal |
// | 28 | `segment` | the face's segment |
// | 32 | `major_axis[3]` | unit tangent of densest spacing |
// | 44 | `index` | rank (stratified: in this request; progressive: in the sequence) |
// | 48 | `bary[2]` | barycentrics of corners 1 and 2 (corner 0: `1 - bary[0] - bary[1]`) |
// | 56 | `spacing[2]` | expected spacing along the major and minor axis (world units) |
typedef struct StrataSample {
  // Position in world space.
  float position[3];
  // The face the sample lies on.
  uint32_t face;
  // Unit surface normal.
  float normal[3];
  // Segment id of the face.
  uint32_t segment;
  // Unit tangent along the field's major axis (densest spacing).
  float major_axis[3];
  // Rank of the sample in its sequence.
  uint32_t index;
  // Barycentric coordinates of corners 1 and 2 of `face`.
  float bary[2];
  // Expected spacing along the major and the minor axis (world units).
  float spacing[2];
} StrataSample;

// A mesh as caller arrays, for `strata_mesh_from_arrays`.
typedef struct StrataMeshArrays {
  // `sizeof(StrataMeshArrays)`.
  uint32_t struct_size;
  // `STRATA_F32` or `STRATA_F64`.
  uint32_t position_type;
  // `vertex_count * 3` coordinates (x, y, z per vertex), of `position_type`.
  const void *positions;
  // Vertices; at least 3.
  size_t vertex_count;
  // `STRATA_U32` or `STRATA_U64`.
  uint32_t index_type;
  // `index_count` vertex indices, three per triangle, of `index_type`.
  const void *indices;
  // Indices; a positive multiple of 3.
  size_t index_count;
} StrataMeshArrays;

// What to draw, for `strata_sample`.
typedef struct StrataSampleRequest {
  // `sizeof(StrataSampleRequest)`.
  uint32_t struct_size;
  // `STRATA_STRATIFIED` or `STRATA_PROGRESSIVE`.
  uint32_t mode;
  // Samples to draw (0 writes nothing).
  size_t count;
  // The seed: the same seed gives the same samples.
  uint64_t seed;
  // Progressive mode: the first rank drawn (`first_rank + count` at most 2^32).
  uint32_t first_rank;
} StrataSampleRequest;

// Where `strata_sample` writes: each non-null array receives `count` entries and
// must hold `capacity` (at least `count`). At least one array must be given.
typedef struct StrataSampleOutput {
  // `sizeof(StrataSampleOutput)`.
  uint32_t struct_size;
  // Entries each non-null array holds (in samples, not floats).
  size_t capacity;
  // 64-byte records, or null.
  struct StrataSample *records;
  // 3 floats per sample (x, y, z), or null.
  float *positions;
  // 3 floats per sample, or null.
  float *normals;
  // 3 floats per sample, or null.
  float *major_axes;
  // 1 `uint32_t` per sample, or null.
  uint32_t *face_ids;
  // 2 floats per sample (corners 1 and 2), or null.
  float *barycentrics;
  // 2 floats per sample (major, minor), or null.
  float *spacings;
} StrataSampleOutput;

#ifdef __cplusplus
extern "C" {
#endif // __cplusplus

// The version of the loaded library (`STRATA_API_VERSION` of its header).
uint32_t strata_version(void);

// This thread's last error message: NUL-terminated UTF-8, owned by the library,
// valid until this thread's next failing call (empty when none failed).
const char *strata_last_error(void);

// Makes the calling thread (a host's frame thread) a worker of the thread pool that
// sampling and level-of-detail updates run on, beside one worker per core, and
// writes the pool's thread count into `threads` (may be null). Call it once, on the
// thread that will call `strata_sample`, before any other `strata_` call that
// computes: parallel work then starts on that thread at once instead of waking a
// sleeping worker (1-2 ms on a small machine), and sampling calls allocate nothing
// (from another thread, each call hands its work to the pool through a queue that
// allocates a block every 63 calls). `STRATA_STATUS_INVALID_ARGUMENT` when the pool
// exists already (it then serves unchanged).
//
// # Safety
// `threads` is null or writable.
enum StrataStatus strata_join_thread_pool(size_t *threads);

// Preprocesses `field`'s mesh on the calling thread and returns its sampler.
//
// # Safety
// `field` is a handle from this library; `options` is null or a valid
// `StrataBuildOptions`; `out` is writable.
enum StrataStatus strata_build(const struct StrataField *field,
                               const struct StrataBuildOptions *options,
                               struct StrataSampler **out);

// Starts preprocessing `field`'s mesh on the build pool and returns at once; poll it
// with `strata_build_poll`, take the sampler with `strata_build_take`.
//
// # Safety
// As `strata_build`.
enum StrataStatus strata_build_start(const struct StrataField *field,
                                     const struct StrataBuildOptions *options,
                                     struct StrataBuild **out);

// Writes the build's stage and progress into `progress`. Never blocks.
//
// # Safety
// `build` is a handle from this library; `progress` is writable.
enum StrataStatus strata_build_poll(const struct StrataBuild *build,
                                    struct StrataBuildProgress *progress);

// Asks the build to stop (at its next check, between stages or segments); its
// `strata_build_take` then fails with `STRATA_STATUS_CANCELLED`. Never blocks.
//
// # Safety
// `build` is a handle from this library.
enum StrataStatus strata_build_cancel(const struct StrataBuild *build);

// Takes a finished build's sampler. `STRATA_STATUS_NOT_READY` while it runs (nothing
// changes; poll again), `STRATA_STATUS_CANCELLED` or `STRATA_STATUS_BUILD` when it ended without
// one, `STRATA_STATUS_INVALID_ARGUMENT` when its sampler was taken already. Never blocks.
//
// # Safety
// `build` is a handle from this library; `out` is writable.
enum StrataStatus strata_build_take(const struct StrataBuild *build, struct StrataSampler **out);

// Frees a build (null: nothing), cancelling it if it runs.
//
// # Safety
// `build` is null or a handle from this library, used by no other call now.
enum StrataStatus strata_build_free(struct StrataBuild *build);

// Makes a pool of `sampler`'s progressive sequence for `seed`, holding ranks
// `0..prefix` and with room for `budget` more ranks drawn where views need them.
//
// # Safety
// `sampler` is a handle from this library; `out` is writable.
enum StrataStatus strata_lod_create(const struct StrataSampler *sampler,
                                    uint64_t seed,
                                    uint32_t prefix,
                                    size_t budget,
                                    struct StrataLod **out);

// Brings the pool up to `view` and finds the ranks that became visible or hidden
// since the last update (the first update reports every visible rank as shown).
//
// # Safety
// `lod` is a handle from this library; `view` points to a valid `StrataView`;
// `frame` is null or writable.
enum StrataStatus strata_lod_update(const struct StrataLod *lod,
                                    const struct StrataView *view,
                                    struct StrataLodFrame *frame);

// Copies the ranks that became visible (`STRATA_LOD_SHOWN`) or hidden
// (`STRATA_LOD_HIDDEN`) at the last update into `ranks` (ascending), `capacity` at
// most; `count` receives how many there are (also when `ranks` is null, to size a
// buffer). Too small a buffer is an error and writes nothing.
//
// # Safety
// `lod` is a handle from this library; `ranks` is null or holds `capacity` entries;
// `count` is writable.
enum StrataStatus strata_lod_changes(const struct StrataLod *lod,
                                     uint32_t which,
                                     uint32_t *ranks,
                                     size_t capacity,
                                     size_t *count);

// Writes the records of the ranks that became visible at the last update, in the
// order `strata_lod_changes(STRATA_LOD_SHOWN)` lists them, into `records`
// (`capacity` at least that count; spacings for the frame's base count).
//
// # Safety
// `lod` is a handle from this library; `records` holds `capacity` entries.
enum StrataStatus strata_lod_shown_records(const struct StrataLod *lod,
                                           struct StrataSample *records,
                                           size_t capacity);

// Frees a pool (null: nothing); see `strata_mesh_free`.
//
// # Safety
// `lod` is null or a handle from this library, used by no other call now.
enum StrataStatus strata_lod_free(struct StrataLod *lod);

// Makes a mesh from caller arrays (copied: the arrays may be freed after the call).
// Errors: null pointers, a wrong `struct_size`, counts out of range, an index that is
// not a vertex, and the engine's mesh validation (degenerate or non-manifold faces,
// NaN positions).
//
// # Safety
// `arrays` points to a `StrataMeshArrays` whose arrays hold the counts it gives;
// `out` is writable.
enum StrataStatus strata_mesh_from_arrays(const struct StrataMeshArrays *arrays,
                                          struct StrataMesh **out);

// Loads a mesh file (OBJ or PLY, by extension).
//
// # Safety
// `path` is a NUL-terminated UTF-8 string; `out` is writable.
enum StrataStatus strata_mesh_load(const char *path, struct StrataMesh **out);

// Builds a built-in shape from its RON description, for example
// `"Sphere(radius: 1.0, resolution: 8)"` or `"Torus(major_radius: 1.0, minor_radius: 0.4)"`.
//
// # Safety
// `shape` is a NUL-terminated UTF-8 string; `out` is writable.
enum StrataStatus strata_mesh_shape(const char *shape, struct StrataMesh **out);

// The mesh's vertex and face counts (either out-pointer may be null).
//
// # Safety
// `mesh` is a handle from this library; non-null out-pointers are writable.
enum StrataStatus strata_mesh_counts(const struct StrataMesh *mesh,
                                     size_t *vertices,
                                     size_t *faces);

// The mesh's axis-aligned bounds: `min` and `max` each receive 3 doubles (x, y, z).
//
// # Safety
// `mesh` is a handle from this library; `min` and `max` hold 3 doubles each.
enum StrataStatus strata_mesh_bounds(const struct StrataMesh *mesh, double *min, double *max);

// Frees a mesh (null: nothing). A handle freed twice is refused with
// `STRATA_STATUS_INVALID_HANDLE` while its address has not been reused.
//
// # Safety
// `mesh` is null or a handle from this library, used by no other call now.
enum StrataStatus strata_mesh_free(struct StrataMesh *mesh);

// Builds a field on `mesh` from its RON description (the `field:` of a scene file),
// for example `"Constant(direction: (1.0, 0.0, 0.0), anisotropy: 3.0, density: 1.0)"`
// or `"Curvature(max_anisotropy: 3.0)"`. Its build settings are the defaults.
//
// # Safety
// `mesh` is a handle from this library; `spec` a NUL-terminated UTF-8 string; `out`
// is writable.
enum StrataStatus strata_field_from_spec(const struct StrataMesh *mesh,
                                         const char *spec,
                                         struct StrataField **out);

// Makes a field from one symmetric 3x3 tensor per vertex, 9 doubles each in
// column-major order (`tensor_len` = 9 x vertices).
//
// # Safety
// `mesh` is a handle from this library; `tensors` holds `tensor_len` doubles; `out`
// is writable.
enum StrataStatus strata_field_from_tensors(const struct StrataMesh *mesh,
                                            const double *tensors,
                                            size_t tensor_len,
                                            struct StrataField **out);

// Loads a scene file (RON, as `strata sample --config` reads): its mesh and its
// field, the field carrying the scene's preprocessing settings.
//
// # Safety
// `path` is a NUL-terminated UTF-8 string; `mesh` and `field` are writable.
enum StrataStatus strata_scene_load(const char *path,
                                    struct StrataMesh **mesh,
                                    struct StrataField **field);

// Frees a field (null: nothing); see `strata_mesh_free`.
//
// # Safety
// `field` is null or a handle from this library, used by no other call now.
enum StrataStatus strata_field_free(struct StrataField *field);

// Draws `request.count` samples into the arrays of `output` (see
// `StrataSampleOutput`). Stratified samples equal the engine's `sample_into` for the
// same sampler, count and seed bit for bit; progressive ones its `progressive_into`.
// No allocation once the sampler's scratch has grown to the count (none at all
// when `records` is given).
//
// # Safety
// `sampler` is a handle from this library; `request` and `output` point to valid
// structs whose non-null arrays hold `output->capacity` entries each and overlap
// nothing else given.
enum StrataStatus strata_sample(const struct StrataSampler *sampler,
                                const struct StrataSampleRequest *request,
                                const struct StrataSampleOutput *output);

// The sampler's mesh face count and total density measure (either out-pointer may
// be null).
//
// # Safety
// `sampler` is a handle from this library; non-null out-pointers are writable.
enum StrataStatus strata_sampler_info(const struct StrataSampler *sampler,
                                      size_t *faces,
                                      double *total_measure);

// Frees a sampler (null: nothing); see `strata_mesh_free`.
//
// # Safety
// `sampler` is null or a handle from this library, used by no other call now.
enum StrataStatus strata_sampler_free(struct StrataSampler *sampler);

#ifdef __cplusplus
}  // extern "C"
#endif  // __cplusplus

#endif  /* STRATA_H */
