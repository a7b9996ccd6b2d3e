/* What the Embree peers (embree_cast.c, embree_gather.c) share: reading hmdist's exported
 * OBJ and building Embree's BVH of it. */
#ifndef HMDIST_EMBREE_SCENE_H
#define HMDIST_EMBREE_SCENE_H

#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* The OBJ at `path` (v and f lines only: what `hmdist scene export` writes) as an Embree
 * scene, built with RTC_BUILD_QUALITY_HIGH (and RTC_SCENE_FLAG_ROBUST where `robust`) by
 * `threads` threads. Sets `*tnear` to the spec's d_min (1e-6 of the bounding box's diagonal; with
 * tnear = 0 Embree finds the surface a ray leaves at t = 0) and `*build` to the seconds the
 * build took (rtcCommitScene and the buffers, not the file). Exits with status 2 on an
 * unreadable file. */
static RTCScene load_scene(const char *path, int threads, int robust, float *tnear, double *build) {
    FILE *obj = fopen(path, "r");
    if (!obj) { perror(path); exit(2); }
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
    *tnear = 1e-6f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                           (hi[2] - lo[2]) * (hi[2] - lo[2]));

    char config[64];
    snprintf(config, sizeof config, "threads=%d", threads);
    RTCDevice device = rtcNewDevice(config);
    double start = now();
    RTCScene scene = rtcNewScene(device);
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
    *build = now() - start;
    free(v);
    free(f);
    return scene;
}

#endif
