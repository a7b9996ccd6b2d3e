/* Casts hmdist's gather rays with Embree 3 (Debian's libembree-dev), for
 * benches/embree/compare.sh.
 *
 *   embree_cast SCENE.obj RAYS.hmdr THREADS robust|fast
 *
 * SCENE.obj: `hmdist scene export` (v and f lines, triangles). RAYS.hmdr: see
 * gather_rays.rs. Builds with RTC_BUILD_QUALITY_HIGH (and RTC_SCENE_FLAG_ROBUST for
 * `robust`), then casts every ray with rtcIntersect1 from THREADS threads (pixels handed out
 * in chunks), with tnear = 1e-6 of the scene's bounding-box diagonal (SPEC's d_min; with
 * tnear = 0 Embree finds the surface a ray leaves at t = 0). Times the build (rtcCommitScene) and the casting loop only. Prints one line in
 * the format of gather_rays.rs. */
#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

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

    /* The OBJ: v and f lines only (what hmdist exports). */
    FILE *obj = fopen(argv[1], "r");
    if (!obj) { perror(argv[1]); return 2; }
    size_t nv = 0, nf = 0, cv = 1 << 20, cf = 1 << 20;
    float *v = malloc(cv * 12);
    unsigned *f = malloc(cf * 12);
    char line[512];
    while (fgets(line, sizeof line, obj)) {
        if (line[0] == 'v' && line[1] == ' ') {
            if (nv == cv) v = realloc(v, (cv *= 2) * 12);
            sscanf(line + 2, "%f %f %f", &v[3 * nv], &v[3 * nv + 1], &v[3 * nv + 2]);
            nv++;
        } else if (line[0] == 'f' && line[1] == ' ') {
            if (nf == cf) f = realloc(f, (cf *= 2) * 12);
            unsigned a, b, c;
            sscanf(line + 2, "%u %u %u", &a, &b, &c);
            f[3 * nf] = a - 1; f[3 * nf + 1] = b - 1; f[3 * nf + 2] = c - 1;
            nf++;
        }
    }
    fclose(obj);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], v[3 * i + k]);
            hi[k] = fmaxf(hi[k], v[3 * i + k]);
        }
    tnear = 1e-6f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                          (hi[2] - lo[2]) * (hi[2] - lo[2]));

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

    char config[64];
    snprintf(config, sizeof config, "threads=%d", threads);
    RTCDevice device = rtcNewDevice(config);
    double start = now();
    scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    if (robust) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
    float *vb = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, nv);
    memcpy(vb, v, nv * 12);
    unsigned *ib = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, nf);
    memcpy(ib, f, nf * 12);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene);
    double build = now() - start;

    pthread_t workers[64];
    Tally tallies[64];
    memset(tallies, 0, sizeof tallies);
    start = now();
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
