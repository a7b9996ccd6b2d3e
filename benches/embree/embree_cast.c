/* Casts hmdist's gather rays with Embree 3 (Debian's libembree-dev), for
 * benches/embree/compare.sh.
 *
 *   embree_cast SCENE.obj RAYS.hmdr THREADS robust|fast
 *
 * SCENE.obj: `hmdist scene export` (v and f lines, triangles). RAYS.hmdr: see
 * gather_rays.rs. Builds with RTC_BUILD_QUALITY_HIGH (and RTC_SCENE_FLAG_ROBUST for
 * `robust`), then casts every ray with rtcIntersect1 from THREADS threads (pixels handed out
 * in chunks), with tnear = 1e-6 of the scene's bounding-box diagonal (the spec's d_min; with
 * tnear = 0 Embree finds the surface a ray leaves at t = 0). Times the build (rtcCommitScene) and the casting loop only. Prints one line in
 * the format of gather_rays.rs. */
#include "embree_scene.h"
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static RTCScene scene;
static unsigned char *rays_file;
static uint32_t pixels, rays_per_pixel;
static size_t record_bytes;
static atomic_uint next_pixel;
static float tnear;

typedef struct {
    uint64_t escaped;
    double inverse_sum;
} Tally;

static void *cast(void *arg) {
    Tally *tally = arg;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (;;) {
        uint32_t first = atomic_fetch_add(&next_pixel, 16);
        if (first >= pixels) break;
        uint32_t last = first + 16 < pixels ? first + 16 : pixels;
        for (uint32_t p = first; p < last; p++) {
            const unsigned char *record = rays_file + 16 + (size_t)p * record_bytes;
            float origin[3];
            memcpy(origin, record, 12);
            const float *dirs = (const float *)(record + 16);
            for (uint32_t j = 0; j < rays_per_pixel; j++) {
                struct RTCRayHit rh;
                rh.ray.org_x = origin[0];
                rh.ray.org_y = origin[1];
                rh.ray.org_z = origin[2];
                rh.ray.dir_x = dirs[3 * j];
                rh.ray.dir_y = dirs[3 * j + 1];
                rh.ray.dir_z = dirs[3 * j + 2];
                rh.ray.tnear = tnear;
                rh.ray.tfar = INFINITY;
                rh.ray.time = 0.0f;
                rh.ray.mask = 0xFFFFFFFF;
                rh.ray.id = 0;
                rh.ray.flags = 0;
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(scene, &context, &rh);
                if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
                    tally->escaped++;
                else
                    tally->inverse_sum += 1.0 / rh.ray.tfar;
            }
        }
    }
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: embree_cast SCENE.obj RAYS.hmdr THREADS robust|fast\n");
        return 2;
    }
    int threads = atoi(argv[3]);
    int robust = strcmp(argv[4], "robust") == 0;

    double build;
    scene = load_scene(argv[1], threads, robust, &tnear, &build);

    FILE *rf = fopen(argv[2], "rb");
    if (!rf) { perror(argv[2]); return 2; }
    fseek(rf, 0, SEEK_END);
    long size = ftell(rf);
    fseek(rf, 0, SEEK_SET);
    rays_file = malloc(size);
    if (fread(rays_file, 1, size, rf) != (size_t)size || memcmp(rays_file, "HMDR", 4)) {
        fprintf(stderr, "%s: not a rays file\n", argv[2]);
        return 2;
    }
    fclose(rf);
    memcpy(&pixels, rays_file + 8, 4);
    memcpy(&rays_per_pixel, rays_file + 12, 4);
    record_bytes = 16 + 12 * (size_t)rays_per_pixel;


    pthread_t workers[64];
    Tally tallies[64];
    memset(tallies, 0, sizeof tallies);
    double start = now();
    for (int i = 0; i < threads; i++) pthread_create(&workers[i], NULL, cast, &tallies[i]);
    uint64_t escaped = 0;
    double inverse_sum = 0;
    for (int i = 0; i < threads; i++) {
        pthread_join(workers[i], NULL);
        escaped += tallies[i].escaped;
        inverse_sum += tallies[i].inverse_sum;
    }
    double seconds = now() - start;
    double rays = (double)pixels * rays_per_pixel;
    printf("embree_%s build_s %.3f trace_s %.3f mrays_per_s %.3f rays %.0f escaped %llu mean_inverse %.6f\n",
           robust ? "robust" : "fast", build, seconds, rays / seconds / 1e6, rays,
           (unsigned long long)escaped, inverse_sum / rays);
    return 0;
}
