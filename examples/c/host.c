/* A C host of strata's C API: loads a mesh (the Stanford bunny when given its path, a
 * built-in torus otherwise), starts a background build and keeps "rendering" frames
 * while it runs (reporting the longest frame), then samples every frame and runs a
 * level-of-detail camera path, streaming only the ranks that became visible.
 *
 *   cc -O2 -I capi/include examples/c/host.c -L target/release -lstrata \
 *      -Wl,-rpath,target/release -o host
 *   ./host ../shared/meshes/stanford-bunny.obj
 *
 * Output: one "key: values" line per result; "hash:" is an FNV-1a hash of the bytes of
 * a 10,000-sample stratified request with seed 11, which the Rust tests compare with the
 * engine's. Exit status 0 on success. */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "strata.h"

#define CHECK(call)                                                                    \
    do {                                                                               \
        enum StrataStatus status_ = (call);                                            \
        if (status_ != STRATA_STATUS_OK) {                                             \
            fprintf(stderr, "%s failed (%d): %s\n", #call, (int)status_,               \
                    strata_last_error());                                              \
            exit(1);                                                                   \
        }                                                                              \
    } while (0)

static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

static void sleep_ms(double ms) {
    struct timespec t = {0, (long)(ms * 1e6)};
    nanosleep(&t, NULL);
}

static uint64_t fnv1a(const void *data, size_t len) {
    const unsigned char *p = data;
    uint64_t h = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < len; i++) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

/* Column-major clip-from-world of a right-handed camera at `eye` looking at `target`
 * (y up), with a perspective projection whose clip z is in [0, w]. */
static void view_projection(const double eye[3], const double target[3], double fov_y,
                            double aspect, double near, double far, double out[16]) {
    double f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    double fl = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int i = 0; i < 3; i++) f[i] /= fl;
    double up[3] = {0, 1, 0};
    double s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2],
                   f[0] * up[1] - f[1] * up[0]};
    double sl = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int i = 0; i < 3; i++) s[i] /= sl;
    double u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2],
                   s[0] * f[1] - s[1] * f[0]};
    /* View rows: s, u, -f; translation -R eye. */
    double v[4][4] = {
        {s[0], s[1], s[2], -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2])},
        {u[0], u[1], u[2], -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2])},
        {-f[0], -f[1], -f[2], f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2]},
        {0, 0, 0, 1}};
    double h = 1.0 / tan(0.5 * fov_y);
    double r = far / (near - far);
    double p[4][4] = {{h / aspect, 0, 0, 0}, {0, h, 0, 0}, {0, 0, r, r * near}, {0, 0, -1, 0}};
    for (int row = 0; row < 4; row++)
        for (int col = 0; col < 4; col++) {
            double acc = 0;
            for (int k = 0; k < 4; k++) acc += p[row][k] * v[k][col];
            out[col * 4 + row] = acc;
        }
}

/* The mesh: the file at `path`, or a built-in torus when it is NULL or unreadable. */
static struct StrataMesh *load_mesh(const char *path, const char **name) {
    struct StrataMesh *mesh = NULL;
    if (path && strata_mesh_load(path, &mesh) == STRATA_STATUS_OK) {
        *name = path;
        return mesh;
    }
    if (path) fprintf(stderr, "note: %s: %s; using a built-in torus\n", path, strata_last_error());
    CHECK(strata_mesh_shape("Torus(major_radius: 1.0, minor_radius: 0.4, resolution: 48)", &mesh));
    *name = "built-in torus";
    return mesh;
}

/* Frames while the build runs: each polls it and "renders" (a 2 ms stand-in). */
static struct StrataSampler *build_in_background(struct StrataField *field) {
    struct StrataBuild *build = NULL;
    double start = now_ms();
    CHECK(strata_build_start(field, NULL, &build));
    double longest = 0;
    int frames = 0;
    struct StrataBuildProgress progress = {0};
    for (;;) {
        double t0 = now_ms();
        CHECK(strata_build_poll(build, &progress));
        volatile double work = 0;
        for (int i = 0; i < 20000; i++) work += i * 1e-9; /* the frame's own work */
        double took = now_ms() - t0;
        if (took > longest) longest = took;
        frames++;
        if (progress.finished) break;
        sleep_ms(2.0);
    }
    struct StrataSampler *sampler = NULL;
    CHECK(strata_build_take(build, &sampler));
    CHECK(strata_build_free(build));
    printf("build: %.1f ms in the background, %d frames, longest frame %.3f ms\n",
           now_ms() - start, frames, longest);
    return sampler;
}

/* Samples every frame into a reused buffer; prints the hash of the seed-11 request. */
static void sample_frames(const struct StrataSampler *sampler) {
    enum { N = 10000, FRAMES = 30 };
    struct StrataSample *records = malloc(sizeof(struct StrataSample) * N);
    struct StrataSampleRequest request = {sizeof(struct StrataSampleRequest), STRATA_STRATIFIED,
                                          N, 11, 0};
    struct StrataSampleOutput output = {0};
    output.struct_size = sizeof output;
    output.capacity = N;
    output.records = records;
    CHECK(strata_sample(sampler, &request, &output));
    printf("hash: %016llx\n", (unsigned long long)fnv1a(records, sizeof(struct StrataSample) * N));
    printf("first: face %u position %.6f %.6f %.6f\n", records[0].face, records[0].position[0],
           records[0].position[1], records[0].position[2]);
    double longest = 0;
    for (int frame = 0; frame < FRAMES; frame++) {
        double t0 = now_ms();
        request.seed = (uint64_t)frame;
        CHECK(strata_sample(sampler, &request, &output));
        double took = now_ms() - t0;
        if (took > longest) longest = took;
    }
    printf("sampling: %d frames of %d samples, longest %.3f ms\n", FRAMES, N, longest);
    free(records);
}

/* A camera path around the mesh: each frame streams only the changed ranks. */
static void lod_path(const struct StrataSampler *sampler, const double center[3], double radius) {
    struct StrataLod *lod = NULL;
    CHECK(strata_lod_create(sampler, 7, 20000, 200000, &lod));
    uint32_t *ranks = NULL;
    size_t room = 0;
    struct StrataSample *records = NULL;
    unsigned long long streamed = 0, hidden = 0, most = 0, fewest = (unsigned long long)-1;
    enum { FRAMES = 40 };
    for (int frame = 0; frame < FRAMES; frame++) {
        double a = 6.283185307179586 * frame / FRAMES;
        double d = radius * (2.5 - 1.2 * sin(a)); /* in and out while orbiting */
        double eye[3] = {center[0] + d * sin(a), center[1] + 0.3 * radius, center[2] + d * cos(a)};
        const double *target = center;
        struct StrataView view = {0};
        view.struct_size = sizeof view;
        view.cull_back_faces = 1;
        view_projection(eye, target, 0.8, 4.0 / 3.0, 0.01 * radius, 100.0 * radius,
                        view.view_projection);
        view.viewport_width = 800;
        view.viewport_height = 600;
        view.reference = 2000.0 / (radius * radius);
        view.max = 8.0;
        view.base_count = 20000;
        struct StrataLodFrame out;
        CHECK(strata_lod_update(lod, &view, &out));
        size_t n = 0;
        CHECK(strata_lod_changes(lod, STRATA_LOD_SHOWN, NULL, 0, &n));
        if (n > room) {
            room = n * 2;
            ranks = realloc(ranks, room * sizeof *ranks);
            records = realloc(records, room * sizeof *records);
        }
        CHECK(strata_lod_changes(lod, STRATA_LOD_SHOWN, ranks, room, &n));
        CHECK(strata_lod_shown_records(lod, records, room)); /* what a host uploads */
        for (size_t i = 0; i < n; i++)
            if (records[i].index != ranks[i]) {
                fprintf(stderr, "record %zu has rank %u, expected %u\n", i, records[i].index,
                        ranks[i]);
                exit(1);
            }
        streamed += n;
        hidden += out.became_hidden;
        if (out.visible > most) most = out.visible;
        if (out.visible < fewest) fewest = out.visible;
    }
    printf("lod: %d frames, visible %llu..%llu, streamed %llu shown, %llu hidden\n", FRAMES,
           fewest, most, streamed, hidden);
    free(ranks);
    free(records);
    CHECK(strata_lod_free(lod));
}

int main(int argc, char **argv) {
    if (strata_version() != STRATA_API_VERSION) {
        fprintf(stderr, "library version %u, header %u\n", strata_version(), STRATA_API_VERSION);
        return 1;
    }
    /* The frame thread joins the pool that sampling runs on (before other calls). */
    size_t threads = 0;
    CHECK(strata_join_thread_pool(&threads));
    printf("threads: %zu\n", threads);
    const char *name = NULL;
    struct StrataMesh *mesh = load_mesh(argc > 1 ? argv[1] : NULL, &name);
    size_t vertices = 0, faces = 0;
    CHECK(strata_mesh_counts(mesh, &vertices, &faces));
    printf("mesh: %s, %zu vertices, %zu faces\n", name, vertices, faces);
    struct StrataField *field = NULL;
    CHECK(strata_field_from_spec(
        mesh, "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0)", &field));
    struct StrataSampler *sampler = build_in_background(field);
    sample_frames(sampler);
    double lo[3], hi[3], center[3], radius = 0;
    CHECK(strata_mesh_bounds(mesh, lo, hi));
    for (int i = 0; i < 3; i++) {
        center[i] = 0.5 * (lo[i] + hi[i]);
        radius += 0.25 * (hi[i] - lo[i]) * (hi[i] - lo[i]);
    }
    lod_path(sampler, center, sqrt(radius));
    CHECK(strata_sampler_free(sampler));
    CHECK(strata_field_free(field));
    CHECK(strata_mesh_free(mesh));
    printf("done\n");
    return 0;
}
