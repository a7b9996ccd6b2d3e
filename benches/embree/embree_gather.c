/* The whole gather with Embree 3 (Debian's libembree-dev), end to end, for
 * benches/embree/compare.sh's end-to-end mode: what a user who writes the gather around
 * Embree themselves would time against `hmdist render`.
 *
 *   embree_gather SCENE.obj POINTS.hmdp N THREADS robust|fast
 *
 * SCENE.obj: `hmdist scene export`. POINTS.hmdp (gather_rays.rs `points`): per surface pixel
 * the gather origin (hmdist's robust offset of the primary hit), the unit normal facing the
 * camera, and the pixel index. For each pixel this program does what `hmdist render
 * --method gather --rays N` does after the primary rays: N cosine-weighted directions on the
 * most nearly square a x b grid of strata, jittered with the same counter-based random numbers
 * (seed 1, keyed by pixel and ray), turned into world space by the same frame (Duff et al.
 * 2017), cast with rtcIntersect1 (tnear = 1e-6 of the scene's diagonal, SPEC's d_min), and
 * H = N / sum(1/t) in double. Only the gather is timed: generation, casting and sums, as a
 * whole, from THREADS threads (pixels handed out 16 at a time). Prints one line:
 *   embree_e2e_robust build_s B gather_s S mrays_per_s M rays R escaped E mean_inverse I */
#include "embree_scene.h"
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* src/sampling.rs: mix64, random_bits, random_pair, strata, stratified, hemisphere, Frame. */
static inline uint64_t mix64(uint64_t x) {
    x ^= x >> 27;
    x *= 0x3C79AC492BA7B653ull;
    x ^= x >> 33;
    x *= 0x1C69B3F74AC4AE35ull;
    return x ^ (x >> 27);
}

typedef struct {
    float origin[3], normal[3];
    uint32_t pixel;
} Point;

static RTCScene scene;
static const Point *points;
static uint32_t point_count, rays_per_point, grid_a, grid_b;
static atomic_uint next_point;
static float tnear;
static double *hmd;

typedef struct {
    uint64_t escaped;
    double inverse_sum;
} Tally;

static void *gather(void *arg) {
    Tally *tally = arg;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    const uint64_t key = mix64(1 ^ 0x9E3779B97F4A7C15ull); /* seed 1 */
    const float scale = 1.0f / (float)(1u << 24);
    for (;;) {
        uint32_t first = atomic_fetch_add(&next_point, 16);
        if (first >= point_count) break;
        uint32_t last = first + 16 < point_count ? first + 16 : point_count;
        for (uint32_t p = first; p < last; p++) {
            const Point *pt = &points[p];
            const float *n = pt->normal;
            float sign = copysignf(1.0f, n[2]);
            float fa = -1.0f / (sign + n[2]);
            float fb = n[0] * n[1] * fa;
            float t[3] = {1.0f + sign * n[0] * n[0] * fa, sign * fb, -sign * n[0]};
            float b[3] = {fb, sign + n[1] * n[1] * fa, -n[1]};
            uint64_t stream = mix64(key ^ pt->pixel);
            double inverse_sum = 0.0;
            for (uint32_t j = 0; j < rays_per_point; j++) {
                uint64_t bits = mix64(stream + (uint64_t)j * 0x9E3779B97F4A7C15ull);
                float xi_x = (float)(bits >> 40) * scale, xi_y = (float)((bits >> 8) & 0xFFFFFF) * scale;
                float ux = ((float)(j % grid_a) + xi_x) / (float)grid_a;
                float uy = ((float)(j / grid_a) + xi_y) / (float)grid_b;
                if (ux > 1.0f - 1.1920929e-7f) ux = 1.0f - 1.1920929e-7f;
                if (uy > 1.0f - 1.1920929e-7f) uy = 1.0f - 1.1920929e-7f;
                float sin_theta = sqrtf(ux), cos_theta = sqrtf(1.0f - ux);
                float phi = 2.0f * (float)M_PI * uy;
                float lx = cosf(phi) * sin_theta, ly = sinf(phi) * sin_theta, lz = cos_theta;
                struct RTCRayHit rh;
                rh.ray.org_x = pt->origin[0];
                rh.ray.org_y = pt->origin[1];
                rh.ray.org_z = pt->origin[2];
                rh.ray.dir_x = lx * t[0] + ly * b[0] + lz * n[0];
                rh.ray.dir_y = lx * t[1] + ly * b[1] + lz * n[1];
                rh.ray.dir_z = lx * t[2] + ly * b[2] + lz * n[2];
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
                    inverse_sum += 1.0 / (double)(rh.ray.tfar > tnear ? rh.ray.tfar : tnear);
            }
            tally->inverse_sum += inverse_sum;
            hmd[p] = rays_per_point / inverse_sum;
        }
    }
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 6) {
        fprintf(stderr, "usage: embree_gather SCENE.obj POINTS.hmdp N THREADS robust|fast\n");
        return 2;
    }
    rays_per_point = (uint32_t)atoi(argv[3]);
    int threads = atoi(argv[4]);
    int robust = strcmp(argv[5], "robust") == 0;
    if (rays_per_point == 0 || threads < 1 || threads > 64) {
        fprintf(stderr, "embree_gather: N must be at least 1 and THREADS 1 to 64\n");
        return 2;
    }
    /* strata(): the most nearly square factorisation a x b, a <= b. */
    grid_a = (uint32_t)sqrt((double)rays_per_point);
    while (grid_a > 1 && rays_per_point % grid_a) grid_a--;
    if (grid_a < 1) grid_a = 1;
    grid_b = rays_per_point / grid_a;

    double build;
    scene = load_scene(argv[1], threads, robust, &tnear, &build);

    FILE *pf = fopen(argv[2], "rb");
    if (!pf) { perror(argv[2]); return 2; }
    fseek(pf, 0, SEEK_END);
    long size = ftell(pf);
    fseek(pf, 0, SEEK_SET);
    unsigned char *bytes = malloc(size);
    if (size < 12 || fread(bytes, 1, size, pf) != (size_t)size || memcmp(bytes, "HMDP", 4)) {
        fprintf(stderr, "%s: not a points file\n", argv[2]);
        return 2;
    }
    fclose(pf);
    memcpy(&point_count, bytes + 8, 4);
    if ((size_t)size != 12 + (size_t)point_count * sizeof(Point)) {
        fprintf(stderr, "%s: truncated\n", argv[2]);
        return 2;
    }
    points = (const Point *)(bytes + 12);
    hmd = malloc(sizeof(double) * (point_count ? point_count : 1));


    pthread_t workers[64];
    Tally tallies[64];
    memset(tallies, 0, sizeof tallies);
    double start = now();
    for (int i = 0; i < threads; i++) pthread_create(&workers[i], NULL, gather, &tallies[i]);
    uint64_t escaped = 0;
    double inverse_sum = 0;
    for (int i = 0; i < threads; i++) {
        pthread_join(workers[i], NULL);
        escaped += tallies[i].escaped;
        inverse_sum += tallies[i].inverse_sum;
    }
    double seconds = now() - start;
    double rays = (double)point_count * rays_per_point;
    printf("embree_e2e_%s build_s %.3f gather_s %.3f mrays_per_s %.3f rays %.0f escaped %llu mean_inverse %.6f\n",
           robust ? "robust" : "fast", build, seconds, rays / seconds / 1e6, rays,
           (unsigned long long)escaped, inverse_sum / rays);
    return 0;
}
