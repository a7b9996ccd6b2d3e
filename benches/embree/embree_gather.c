/* The whole gather with Embree 3 (Debian's libembree-dev), end to end, for
 * benches/embree/compare.sh's end-to-end mode: what a user who writes the gather around
 * Embree themselves would time against `hmdist render`.
 *
 *   embree_gather SCENE.obj POINTS.hmdp N THREADS robust|fast [CAST]
 *
 * SCENE.obj: `hmdist scene export`. POINTS.hmdp (gather_rays.rs `points`): per surface pixel
 * the gather origin (hmdist's robust offset of the primary hit), the unit normal facing the
 * camera, and the pixel index. For each pixel this program does what `hmdist render
 * --method gather --rays N` does after the primary rays: N cosine-weighted directions on the
 * most nearly square a x b grid of strata, jittered with the same counter-based random numbers
 * (seed 1, keyed by pixel and ray), turned into world space by the same frame (Duff et al.
 * 2017), cast with rtcIntersect1 (tnear = 1e-6 of the scene's diagonal, the spec's d_min), and
 * H = N / sum(1/t) in double. Only the gather is timed: generation, casting and sums, from
 * THREADS threads. CAST says how:
 *   loop  (default) each ray made inside the cast loop and cast at once with rtcIntersect1
 *         (pixels handed out 16 at a time);
 *   1, 4, 8, 16, stream   every pixel's rays made first, for all pixels, on all threads
 *         (timed apart: gen_s), then cast: one at a time (rtcIntersect1), as packets of 4,
 *         8 or 16 consecutive rays of one pixel (rtcIntersect4/8/16), or as streams of 64
 *         (rtcIntersect1M); sums per pixel in ray order as the loop.
 * Prints one line:
 *   embree_e2e_robust_loop build_s B gen_s G gather_s S mrays_per_s M rays R escaped E mean_inverse I
 * (gather_s includes gen_s). With EMBREE_HMD_OUT=FILE set, also writes each point's H there
 * (little-endian float32, in the points file's order; `gather_rays exr` makes it an EXR). */
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

/* The next 16 points for this thread, [first, last); 0 once every point is taken. */
static inline int next_batch(uint32_t *first, uint32_t *last) {
    *first = atomic_fetch_add(&next_point, 16);
    if (*first >= point_count) return 0;
    *last = *first + 16 < point_count ? *first + 16 : point_count;
    return 1;
}

/* The pixel's frame (Duff et al. 2017): tangent t, bitangent b. */
static inline void frame_of(const float *n, float t[3], float b[3]) {
    float sign = copysignf(1.0f, n[2]);
    float fa = -1.0f / (sign + n[2]);
    float fb = n[0] * n[1] * fa;
    t[0] = 1.0f + sign * n[0] * n[0] * fa; t[1] = sign * fb; t[2] = -sign * n[0];
    b[0] = fb; b[1] = sign + n[1] * n[1] * fa; b[2] = -n[1];
}

/* Ray j of a pixel whose random stream is `stream`: its world direction. */
static inline void direction(uint64_t stream, uint32_t j, const float *n, const float *t, const float *b,
                             float dir[3]) {
    const float scale = 1.0f / (float)(1u << 24);
    uint64_t bits = mix64(stream + (uint64_t)j * 0x9E3779B97F4A7C15ull);
    float xi_x = (float)(bits >> 40) * scale, xi_y = (float)((bits >> 8) & 0xFFFFFF) * scale;
    float ux = ((float)(j % grid_a) + xi_x) / (float)grid_a;
    float uy = ((float)(j / grid_a) + xi_y) / (float)grid_b;
    if (ux > 1.0f - 1.1920929e-7f) ux = 1.0f - 1.1920929e-7f;
    if (uy > 1.0f - 1.1920929e-7f) uy = 1.0f - 1.1920929e-7f;
    float sin_theta = sqrtf(ux), cos_theta = sqrtf(1.0f - ux);
    float phi = 2.0f * (float)M_PI * uy;
    float lx = cosf(phi) * sin_theta, ly = sinf(phi) * sin_theta, lz = cos_theta;
    dir[0] = lx * t[0] + ly * b[0] + lz * n[0];
    dir[1] = lx * t[1] + ly * b[1] + lz * n[1];
    dir[2] = lx * t[2] + ly * b[2] + lz * n[2];
}

/* A ray from `origin` along `dir`, from tnear on, with no hit yet. */
static inline void init_ray(struct RTCRayHit *rh, const float *origin, const float *dir) {
    rh->ray.org_x = origin[0]; rh->ray.org_y = origin[1]; rh->ray.org_z = origin[2];
    rh->ray.dir_x = dir[0]; rh->ray.dir_y = dir[1]; rh->ray.dir_z = dir[2];
    rh->ray.tnear = tnear; rh->ray.tfar = INFINITY; rh->ray.time = 0.0f;
    rh->ray.mask = 0xFFFFFFFF; rh->ray.id = 0; rh->ray.flags = 0;
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

static void *gather(void *arg) {
    Tally *tally = arg;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    const uint64_t key = mix64(1 ^ 0x9E3779B97F4A7C15ull); /* seed 1 */
    for (uint32_t first, last; next_batch(&first, &last);) {
        for (uint32_t p = first; p < last; p++) {
            const Point *pt = &points[p];
            const float *n = pt->normal;
            float t[3], b[3];
            frame_of(n, t, b);
            uint64_t stream = mix64(key ^ pt->pixel);
            double inverse_sum = 0.0;
            for (uint32_t j = 0; j < rays_per_point; j++) {
                float dir[3];
                direction(stream, j, n, t, b, dir);
                struct RTCRayHit rh;
                init_ray(&rh, pt->origin, dir);
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

/* Batched: every pixel's directions first (`dirs`: N per pixel), then the cast. */
static float *dirs;
static int cast_width; /* 1, 4, 8, 16, or 0 for rtcIntersect1M streams of 64 */

static void *generate(void *arg) {
    (void)arg;
    const uint64_t key = mix64(1 ^ 0x9E3779B97F4A7C15ull); /* seed 1 */
    for (uint32_t first, last; next_batch(&first, &last);) {
        for (uint32_t p = first; p < last; p++) {
            const float *n = points[p].normal;
            float t[3], b[3];
            frame_of(n, t, b);
            uint64_t stream = mix64(key ^ points[p].pixel);
            float *out = dirs + (size_t)p * rays_per_point * 3;
            for (uint32_t j = 0; j < rays_per_point; j++) direction(stream, j, n, t, b, out + 3 * j);
        }
    }
    return NULL;
}

/* Adds ray j's hit (t, or none) to the pixel's sums. */
static inline void count_hit(Tally *tally, double *inverse_sum, unsigned geom, float t) {
    if (geom == RTC_INVALID_GEOMETRY_ID)
        tally->escaped++;
    else
        *inverse_sum += 1.0 / (double)(t > tnear ? t : tnear);
}

#define PACKET_CAST(K, RAYHIT, INTERSECT)                                                     \
    for (uint32_t j0 = 0; j0 < rays_per_point; j0 += K) {                                     \
        RAYHIT rh __attribute__((aligned(64)));                                               \
        int valid[K] __attribute__((aligned(64)));                                            \
        for (int k = 0; k < K; k++) {                                                         \
            uint32_t j = j0 + k < rays_per_point ? j0 + k : j0;                               \
            valid[k] = j0 + k < rays_per_point ? -1 : 0;                                      \
            rh.ray.org_x[k] = o[0]; rh.ray.org_y[k] = o[1]; rh.ray.org_z[k] = o[2];           \
            rh.ray.dir_x[k] = d[3 * j]; rh.ray.dir_y[k] = d[3 * j + 1]; rh.ray.dir_z[k] = d[3 * j + 2]; \
            rh.ray.tnear[k] = tnear; rh.ray.tfar[k] = INFINITY; rh.ray.time[k] = 0.0f;        \
            rh.ray.mask[k] = 0xFFFFFFFF; rh.ray.id[k] = 0; rh.ray.flags[k] = 0;               \
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID; rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID; \
        }                                                                                     \
        INTERSECT(valid, scene, &context, &rh);                                               \
        for (int k = 0; k < K && j0 + k < rays_per_point; k++)                                \
            count_hit(tally, &inverse_sum, rh.hit.geomID[k], rh.ray.tfar[k]);                 \
    }

static void *cast(void *arg) {
    Tally *tally = arg;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit stream[64];
    for (uint32_t first, last; next_batch(&first, &last);) {
        for (uint32_t p = first; p < last; p++) {
            const float *o = points[p].origin;
            const float *d = dirs + (size_t)p * rays_per_point * 3;
            double inverse_sum = 0.0;
            switch (cast_width) {
            case 4: PACKET_CAST(4, struct RTCRayHit4, rtcIntersect4) break;
            case 8: PACKET_CAST(8, struct RTCRayHit8, rtcIntersect8) break;
            case 16: PACKET_CAST(16, struct RTCRayHit16, rtcIntersect16) break;
            default: {
                uint32_t width = cast_width == 1 ? 1 : 64;
                for (uint32_t j0 = 0; j0 < rays_per_point; j0 += width) {
                    uint32_t m = rays_per_point - j0 < width ? rays_per_point - j0 : width;
                    for (uint32_t k = 0; k < m; k++) init_ray(&stream[k], o, d + 3 * (j0 + k));
                    if (width == 1)
                        rtcIntersect1(scene, &context, &stream[0]);
                    else
                        rtcIntersect1M(scene, &context, stream, m, sizeof(struct RTCRayHit));
                    for (uint32_t k = 0; k < m; k++)
                        count_hit(tally, &inverse_sum, stream[k].hit.geomID, stream[k].ray.tfar);
                }
            }
            }
            tally->inverse_sum += inverse_sum;
            hmd[p] = rays_per_point / inverse_sum;
        }
    }
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 6 && argc != 7) {
        fprintf(stderr, "usage: embree_gather SCENE.obj POINTS.hmdp N THREADS robust|fast [loop|1|4|8|16|stream]\n");
        return 2;
    }
    const char *mode = argc == 7 ? argv[6] : "loop";
    int batched = strcmp(mode, "loop") != 0;
    cast_width = strcmp(mode, "stream") == 0 ? 0 : atoi(mode);
    if (batched && cast_width != 0 && cast_width != 1 && cast_width != 4 && cast_width != 8 && cast_width != 16) {
        fprintf(stderr, "embree_gather: CAST is loop, 1, 4, 8, 16 or stream, not %s\n", mode);
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
    double start = now(), generation = 0.0;
    if (batched) {
        dirs = malloc(sizeof(float) * 3 * (size_t)point_count * rays_per_point + 1);
        if (!dirs) { fprintf(stderr, "embree_gather: no memory for the directions\n"); return 2; }
        for (int i = 0; i < threads; i++) pthread_create(&workers[i], NULL, generate, NULL);
        for (int i = 0; i < threads; i++) pthread_join(workers[i], NULL);
        generation = now() - start;
        atomic_store(&next_point, 0);
    }
    for (int i = 0; i < threads; i++) pthread_create(&workers[i], NULL, batched ? cast : gather, &tallies[i]);
    uint64_t escaped = 0;
    double inverse_sum = 0;
    for (int i = 0; i < threads; i++) {
        pthread_join(workers[i], NULL);
        escaped += tallies[i].escaped;
        inverse_sum += tallies[i].inverse_sum;
    }
    double seconds = now() - start;
    double rays = (double)point_count * rays_per_point;
    const char *hmd_out = getenv("EMBREE_HMD_OUT");
    if (hmd_out) {
        FILE *out = fopen(hmd_out, "wb");
        if (!out) { perror(hmd_out); return 2; }
        for (uint32_t p = 0; p < point_count; p++) {
            float h = (float)hmd[p];
            fwrite(&h, sizeof h, 1, out);
        }
        if (fclose(out)) { perror(hmd_out); return 2; }
    }
    printf("embree_e2e_%s_%s build_s %.3f gen_s %.3f gather_s %.3f mrays_per_s %.3f rays %.0f escaped %llu mean_inverse %.6f\n",
           robust ? "robust" : "fast", mode, build, generation, seconds, rays / seconds / 1e6, rays,
           (unsigned long long)escaped, inverse_sum / rays);
    return 0;
}
