/*
 * Embree 3 side of the BVH comparison (see BENCHMARKS.md).
 *
 * Reads the ray file written by `cargo run --release --example bvh_rays --
 * --write FILE` (triangles plus ray sets), times Embree's BVH build at
 * RTC_BUILD_QUALITY_MEDIUM and RTC_BUILD_QUALITY_HIGH on a one-thread and on a
 * two-thread device, then builds one scene at each quality on the one-thread
 * device and times rtcIntersect1 (closest-hit sets) and rtcOccluded1 (shadow
 * sets) on the identical rays. Builds are timed on the wall clock (median of
 * fresh scenes; one-thread builds also in the thread's CPU time; all builds
 * also in the CPU time of all the process's threads), ray sets in
 * the thread's CPU time (best of `reps` passes), as the example does. Prints
 * lines in the same format as the example:
 *
 *   build impl=embree quality=high threads=1 triangles=N ms=X cpu_ms=Y process_cpu_ms=Z
 *   build impl=embree quality=high threads=2 triangles=N ms=X process_cpu_ms=Z
 *   result impl=embree set=NAME rays=N hits=H mrays_per_s=R          (HIGH)
 *   result impl=embree-medium set=NAME rays=N hits=H mrays_per_s=R   (MEDIUM)
 *
 * With --kernels, it only builds the scene once at each quality on a device
 * made with "threads=1,verbose=2" and exits: Embree then prints the CPU's
 * instruction sets, the ones it was compiled for, and the builder and ray
 * kernels it picked (verbose=1 prints only the first two).
 *
 * Build: gcc -O3 -o embree_bench embree_bench.c -lembree3
 * Run:   embree_bench FILE [reps] [builds]
 *        embree_bench --kernels FILE
 */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

typedef struct {
    uint32_t query; /* 0 closest hit, 1 occluded */
    char name[64];
    uint32_t count;
    float *rays; /* ox oy oz t_min dx dy dz t_max, per ray */
} RaySet;

/* Wall clock, for builds. */
static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* This thread's CPU time, for ray sets: other work on the machine does not count. */
static double thread_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* CPU time of all the process's threads, for multithreaded builds. */
static double process_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void die(const char *what) {
    fprintf(stderr, "embree_bench: %s\n", what);
    exit(2);
}

static void read_exact(FILE *f, void *p, size_t n) {
    if (fread(p, 1, n, f) != n) die("ray file is truncated");
}

static uint32_t read_u32(FILE *f) {
    unsigned char b[4];
    read_exact(f, b, 4);
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static RTCScene build_scene(RTCDevice dev, const float *tris, uint32_t ntri, enum RTCBuildQuality quality) {
    RTCScene scene = rtcNewScene(dev);
    rtcSetSceneBuildQuality(scene, quality);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, quality);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                       (size_t)ntri * 3);
    unsigned *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), ntri);
    if (!v || !idx) die("cannot allocate Embree buffers");
    memcpy(v, tris, (size_t)ntri * 9 * sizeof(float));
    for (uint32_t i = 0; i < 3 * ntri; i++) idx[i] = i;
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    return scene;
}

int main(int argc, char **argv) {
    int kernels = argc > 1 && strcmp(argv[1], "--kernels") == 0;
    if (kernels) {
        argv++;
        argc--;
    }
    if (argc < 2) die("usage: embree_bench RAYFILE [reps] [builds] | embree_bench --kernels RAYFILE");
    int reps = argc > 2 ? atoi(argv[2]) : 5;
    int builds = argc > 3 ? atoi(argv[3]) : 9;
    if (reps < 1) reps = 1;
    if (builds < 1) builds = 1;

    FILE *f = fopen(argv[1], "rb");
    if (!f) die("cannot open the ray file");
    char magic[8];
    read_exact(f, magic, 8);
    if (memcmp(magic, "RTRAYS01", 8) != 0) die("not a ray file (bad magic)");
    uint32_t ntri = read_u32(f);
    float *tris = malloc((size_t)ntri * 9 * sizeof(float));
    if (!tris) die("out of memory");
    read_exact(f, tris, (size_t)ntri * 9 * sizeof(float));
    uint32_t nsets = read_u32(f);
    RaySet *sets = calloc(nsets, sizeof(RaySet));
    for (uint32_t s = 0; s < nsets; s++) {
        sets[s].query = read_u32(f);
        uint32_t len = read_u32(f);
        if (len >= sizeof sets[s].name) die("ray set name too long");
        read_exact(f, sets[s].name, len);
        sets[s].count = read_u32(f);
        sets[s].rays = malloc((size_t)sets[s].count * 8 * sizeof(float));
        if (!sets[s].rays) die("out of memory");
        read_exact(f, sets[s].rays, (size_t)sets[s].count * 8 * sizeof(float));
    }
    fclose(f);

    /* Embree asks every application thread for flush-to-zero and denormals-are-zero. */
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    static const struct {
        enum RTCBuildQuality q;
        const char *name;
    } qualities[] = {{RTC_BUILD_QUALITY_MEDIUM, "medium"}, {RTC_BUILD_QUALITY_HIGH, "high"}};

    if (kernels) {
        RTCDevice dev = rtcNewDevice("threads=1,verbose=2");
        if (!dev) die("rtcNewDevice failed");
        for (int k = 0; k < 2; k++) {
            fflush(stdout);
            printf("kernels quality=%s\n", qualities[k].name);
            fflush(stdout);
            rtcReleaseScene(build_scene(dev, tris, ntri, qualities[k].q));
        }
        rtcReleaseDevice(dev);
        return 0;
    }

    /* Median build times over fresh scenes, per thread count and quality. The
     * one-thread device comes first and goes before the two-thread one is
     * made, so no worker thread of the latter runs during its builds. */
    double *bt = malloc(builds * sizeof(double));
    double *bc = malloc(builds * sizeof(double));
    double *bp = malloc(builds * sizeof(double));
    for (int d = 0; d < 2; d++) {
        RTCDevice bdev = rtcNewDevice(d == 0 ? "threads=1" : "threads=2");
        if (!bdev) die("rtcNewDevice failed");
        for (int k = 0; k < 2; k++) {
            for (int b = 0; b < builds; b++) {
                double t0 = now(), c0 = thread_now(), p0 = process_now();
                RTCScene sc = build_scene(bdev, tris, ntri, qualities[k].q);
                bt[b] = now() - t0;
                bc[b] = thread_now() - c0;
                bp[b] = process_now() - p0;
                rtcReleaseScene(sc);
            }
            qsort(bt, builds, sizeof(double), cmp_double);
            qsort(bc, builds, sizeof(double), cmp_double);
            qsort(bp, builds, sizeof(double), cmp_double);
            printf("build impl=embree quality=%s threads=%d triangles=%u ms=%.2f", qualities[k].name, d + 1, ntri,
                   bt[builds / 2] * 1e3);
            if (d == 0) printf(" cpu_ms=%.2f", bc[builds / 2] * 1e3);
            printf(" process_cpu_ms=%.2f\n", bp[builds / 2] * 1e3);
            fflush(stdout);
        }
        rtcReleaseDevice(bdev);
    }
    RTCDevice dev = rtcNewDevice("threads=1");
    if (!dev) die("rtcNewDevice failed");

    /* Rays against the MEDIUM scene, then the HIGH one (reported as plain "embree"). */
    for (int k = 0; k < 2; k++) {
        RTCScene scene = build_scene(dev, tris, ntri, qualities[k].q);
        const char *impl = k == 0 ? "embree-medium" : "embree";
        struct RTCIntersectContext ctx;
        for (uint32_t s = 0; s < nsets; s++) {
            RaySet *set = &sets[s];
            double best = INFINITY;
            size_t hits = 0;
            for (int r = 0; r < reps; r++) {
                hits = 0;
                double t0 = thread_now();
                for (uint32_t i = 0; i < set->count; i++) {
                    const float *q = set->rays + (size_t)i * 8;
                    rtcInitIntersectContext(&ctx);
                    if (set->query == 0) {
                        struct RTCRayHit rh;
                        rh.ray.org_x = q[0];
                        rh.ray.org_y = q[1];
                        rh.ray.org_z = q[2];
                        rh.ray.tnear = q[3];
                        rh.ray.dir_x = q[4];
                        rh.ray.dir_y = q[5];
                        rh.ray.dir_z = q[6];
                        rh.ray.tfar = q[7];
                        rh.ray.time = 0.0f;
                        rh.ray.mask = 0xFFFFFFFFu;
                        rh.ray.id = 0;
                        rh.ray.flags = 0;
                        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                        rtcIntersect1(scene, &ctx, &rh);
                        hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                    } else {
                        struct RTCRay ray;
                        ray.org_x = q[0];
                        ray.org_y = q[1];
                        ray.org_z = q[2];
                        ray.tnear = q[3];
                        ray.dir_x = q[4];
                        ray.dir_y = q[5];
                        ray.dir_z = q[6];
                        ray.tfar = q[7];
                        ray.time = 0.0f;
                        ray.mask = 0xFFFFFFFFu;
                        ray.id = 0;
                        ray.flags = 0;
                        rtcOccluded1(scene, &ctx, &ray);
                        /* Occluded rays come back with tfar = -inf. */
                        hits += ray.tfar < 0.0f;
                    }
                }
                double t = thread_now() - t0;
                if (t < best) best = t;
            }
            printf("result impl=%s set=%s rays=%u hits=%zu mrays_per_s=%.3f\n", impl, set->name, set->count, hits,
                   set->count / best / 1e6);
            fflush(stdout);
        }
        rtcReleaseScene(scene);
    }
    rtcReleaseDevice(dev);
    for (uint32_t s = 0; s < nsets; s++) free(sets[s].rays);
    free(sets);
    free(tris);
    free(bt);
    free(bc);
    free(bp);
    return 0;
}
