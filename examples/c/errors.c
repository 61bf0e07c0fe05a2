/* strata's C API on bad input, from C: null pointers, zero and mismatched sizes, a wrong
 * struct_size, a cancelled build, a handle freed twice or of another kind. Each check
 * expects a status and a non-empty message; the program prints one line per failed
 * check and "errors: N checks passed", and exits 1 if any failed.
 *
 *   cc -O2 -I capi/include examples/c/errors.c -L target/release -lstrata \
 *      -Wl,-rpath,target/release -o errors && ./errors */

#include <stdio.h>
#include <string.h>
#include <time.h>

#include "strata.h"

static int passed, failed;

static void expect(const char *what, enum StrataStatus got, enum StrataStatus want) {
    const char *message = strata_last_error();
    if (got == want && (want == STRATA_STATUS_OK || (message && message[0]))) {
        passed++;
    } else {
        failed++;
        printf("FAILED %s: status %d, expected %d (%s)\n", what, (int)got, (int)want, message);
    }
}

static void sleep_ms(long ms) {
    struct timespec t = {0, ms * 1000000L};
    nanosleep(&t, NULL);
}

int main(void) {
    struct StrataMesh *mesh = NULL;
    struct StrataField *field = NULL;
    struct StrataSampler *sampler = NULL;

    /* Meshes. */
    float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t indices[3] = {0, 1, 2};
    struct StrataMeshArrays arrays = {sizeof arrays, STRATA_F32, positions, 3,
                                      STRATA_U32,    indices,    3};
    expect("null arrays", strata_mesh_from_arrays(NULL, &mesh), STRATA_STATUS_NULL_POINTER);
    expect("null out", strata_mesh_from_arrays(&arrays, NULL), STRATA_STATUS_NULL_POINTER);
    struct StrataMeshArrays bad = arrays;
    bad.struct_size = 4;
    expect("old struct_size", strata_mesh_from_arrays(&bad, &mesh), STRATA_STATUS_INVALID_ARGUMENT);
    bad = arrays;
    bad.index_count = 0;
    expect("zero indices", strata_mesh_from_arrays(&bad, &mesh), STRATA_STATUS_INVALID_ARGUMENT);
    bad = arrays;
    bad.index_count = 2;
    expect("indices not triples", strata_mesh_from_arrays(&bad, &mesh),
           STRATA_STATUS_INVALID_ARGUMENT);
    bad = arrays;
    bad.positions = NULL;
    expect("null positions", strata_mesh_from_arrays(&bad, &mesh), STRATA_STATUS_NULL_POINTER);
    bad = arrays;
    bad.position_type = STRATA_U32;
    expect("unknown position type", strata_mesh_from_arrays(&bad, &mesh),
           STRATA_STATUS_INVALID_ARGUMENT);
    indices[2] = 3;
    expect("index past the vertices", strata_mesh_from_arrays(&arrays, &mesh),
           STRATA_STATUS_INVALID_ARGUMENT);
    indices[2] = 2;
    expect("null path", strata_mesh_load(NULL, &mesh), STRATA_STATUS_NULL_POINTER);
    expect("missing file", strata_mesh_load("/nonexistent/bunny.obj", &mesh), STRATA_STATUS_MESH);
    expect("unknown shape", strata_mesh_shape("Teapot()", &mesh), STRATA_STATUS_CONFIG);
    expect("a sphere", strata_mesh_shape("Sphere(radius: 1.0, resolution: 5)", &mesh),
           STRATA_STATUS_OK);

    /* Fields and builds. */
    expect("bad field", strata_field_from_spec(mesh, "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 0.1)", &field),
           STRATA_STATUS_FIELD);
    double tensors[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    expect("mismatched tensor count", strata_field_from_tensors(mesh, tensors, 9, &field),
           STRATA_STATUS_INVALID_ARGUMENT);
    expect("a field",
           strata_field_from_spec(
               mesh, "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0)", &field),
           STRATA_STATUS_OK);
    expect("mesh as field", strata_build((const struct StrataField *)mesh, NULL, &sampler),
           STRATA_STATUS_INVALID_HANDLE);
    struct StrataBuildOptions options = {sizeof options, "(min_segment_faces: 0)"};
    expect("bad surface options", strata_build(field, &options, &sampler),
           STRATA_STATUS_INVALID_ARGUMENT);
    options.surface_ron = "(no_such_setting: 1)";
    expect("unknown surface option", strata_build(field, &options, &sampler),
           STRATA_STATUS_CONFIG);

    struct StrataBuild *build = NULL;
    expect("start", strata_build_start(field, NULL, &build), STRATA_STATUS_OK);
    expect("cancel", strata_build_cancel(build), STRATA_STATUS_OK);
    struct StrataBuildProgress progress = {0};
    for (int i = 0; i < 30000 && !progress.finished; i++) {
        strata_build_poll(build, &progress);
        sleep_ms(1);
    }
    expect("take a cancelled build", strata_build_take(build, &sampler), STRATA_STATUS_CANCELLED);
    expect("poll into null", strata_build_poll(build, NULL), STRATA_STATUS_NULL_POINTER);
    expect("free build", strata_build_free(build), STRATA_STATUS_OK);
    expect("free build twice", strata_build_free(build), STRATA_STATUS_INVALID_HANDLE);
    expect("poll a freed build", strata_build_poll(build, &progress), STRATA_STATUS_INVALID_HANDLE);

    /* Sampling. */
    expect("blocking build", strata_build(field, NULL, &sampler), STRATA_STATUS_OK);
    struct StrataSample records[8];
    struct StrataSampleRequest request = {sizeof request, STRATA_STRATIFIED, 8, 1, 0};
    struct StrataSampleOutput output = {0};
    output.struct_size = sizeof output;
    output.capacity = 8;
    output.records = records;
    expect("sample", strata_sample(sampler, &request, &output), STRATA_STATUS_OK);
    request.count = 9;
    expect("count past capacity", strata_sample(sampler, &request, &output),
           STRATA_STATUS_INVALID_ARGUMENT);
    request.count = 8;
    request.mode = 42;
    expect("unknown mode", strata_sample(sampler, &request, &output),
           STRATA_STATUS_INVALID_ARGUMENT);
    request.mode = STRATA_STRATIFIED;
    output.records = NULL;
    expect("no output array", strata_sample(sampler, &request, &output),
           STRATA_STATUS_NULL_POINTER);
    output.records = records;
    expect("null request", strata_sample(sampler, NULL, &output), STRATA_STATUS_NULL_POINTER);
    expect("field as sampler", strata_sample((const struct StrataSampler *)field, &request, &output),
           STRATA_STATUS_INVALID_HANDLE);

    /* Level of detail. */
    struct StrataLod *lod = NULL;
    expect("zero prefix", strata_lod_create(sampler, 1, 0, 100, &lod), STRATA_STATUS_INVALID_ARGUMENT);
    expect("pool", strata_lod_create(sampler, 1, 1000, 1000, &lod), STRATA_STATUS_OK);
    struct StrataView view = {0};
    view.struct_size = sizeof view;
    expect("zero view", strata_lod_update(lod, &view, NULL), STRATA_STATUS_INVALID_ARGUMENT);
    size_t n = 0;
    expect("unknown change list", strata_lod_changes(lod, 9, NULL, 0, &n),
           STRATA_STATUS_INVALID_ARGUMENT);
    expect("free pool", strata_lod_free(lod), STRATA_STATUS_OK);
    expect("free pool twice", strata_lod_free(lod), STRATA_STATUS_INVALID_HANDLE);

    expect("free sampler", strata_sampler_free(sampler), STRATA_STATUS_OK);
    expect("sample a freed sampler", strata_sample(sampler, &request, &output),
           STRATA_STATUS_INVALID_HANDLE);
    expect("free sampler twice", strata_sampler_free(sampler), STRATA_STATUS_INVALID_HANDLE);
    expect("free field", strata_field_free(field), STRATA_STATUS_OK);
    expect("free mesh", strata_mesh_free(mesh), STRATA_STATUS_OK);
    expect("free mesh twice", strata_mesh_free(mesh), STRATA_STATUS_INVALID_HANDLE);
    expect("free null", strata_mesh_free(NULL), STRATA_STATUS_OK);

    printf("errors: %d checks passed\n", passed);
    if (failed) printf("errors: %d checks FAILED\n", failed);
    return failed ? 1 : 0;
}
