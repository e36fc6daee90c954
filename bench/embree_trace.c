/* Embree 3's closest-hit rate on an OBJ's triangles, the rays uniform in the scene's bounds with
 * uniformly distributed directions (the kind `examples/trace_file.rs` traces through kalos' BVH
 * and `bench/mitsuba_trace.py` through Mitsuba), one thread, best of five passes:
 * one ray at a time (rtcIntersect1), packets of 4, 8 and 16 rays (rtcIntersect4/8/16, the calls a
 * wavefront renderer such as Mitsuba's LLVM backend makes), and the whole array as one incoherent
 * stream (rtcIntersect1M). A peer measurement, not part of kalos' build:
 *
 *   apt-get install libembree-dev
 *   cc -O2 -o /tmp/embree_trace bench/embree_trace.c -lembree3 -lm
 *   taskset -c 0 /tmp/embree_trace SCENE.obj [RAYS] [high|medium]
 *
 * The OBJ reader takes `v` and `f` lines only (faces as fans; v, v/t, v/t/n, v//n, negative
 * indices). */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static uint64_t rng_state = 1;
static float next_f32(void) { /* PCG32 */
    uint64_t old = rng_state;
    rng_state = old * 6364136223846793005ULL + 1442695040888963407ULL;
    uint32_t x = (uint32_t)(((old >> 18) ^ old) >> 27), r = (uint32_t)(old >> 59);
    x = (x >> r) | (x << ((32 - r) & 31));
    return (x >> 8) * (1.0f / 16777216.0f);
}

typedef struct { float *v; size_t nv, cv; unsigned *f; size_t nf, cf; } Mesh;

static void push_v(Mesh *m, float x, float y, float z) {
    if (m->nv == m->cv) { m->cv = m->cv ? 2 * m->cv : 1024; m->v = realloc(m->v, m->cv * 3 * sizeof(float)); }
    m->v[3 * m->nv] = x; m->v[3 * m->nv + 1] = y; m->v[3 * m->nv + 2] = z; m->nv++;
}
static void push_f(Mesh *m, unsigned a, unsigned b, unsigned c) {
    if (m->nf == m->cf) { m->cf = m->cf ? 2 * m->cf : 1024; m->f = realloc(m->f, m->cf * 3 * sizeof(unsigned)); }
    m->f[3 * m->nf] = a; m->f[3 * m->nf + 1] = b; m->f[3 * m->nf + 2] = c; m->nf++;
}

static int read_obj(const char *path, Mesh *m) {
    FILE *fp = fopen(path, "r");
    if (!fp) return 0;
    char line[4096];
    while (fgets(line, sizeof line, fp)) {
        if (line[0] == 'v' && line[1] == ' ') {
            float x, y, z;
            if (sscanf(line + 2, "%f %f %f", &x, &y, &z) == 3) push_v(m, x, y, z);
        } else if (line[0] == 'f' && line[1] == ' ') {
            long idx[64]; int n = 0;
            char *s = line + 2, *tok;
            while ((tok = strtok(s, " \t\r\n")) && n < 64) {
                s = NULL;
                long i = strtol(tok, NULL, 10);
                idx[n++] = i < 0 ? (long)m->nv + i : i - 1;
            }
            for (int k = 1; k + 1 < n; k++) push_f(m, idx[0], idx[k], idx[k + 1]);
        }
    }
    fclose(fp);
    return 1;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: embree_trace SCENE.obj [RAYS] [high|medium]\n"); return 2; }
    size_t n = argc > 2 ? strtoul(argv[2], NULL, 10) : (1u << 20);
    int high = !(argc > 3 && strcmp(argv[3], "medium") == 0);
    n &= ~(size_t)15;
    Mesh m = {0};
    if (!read_obj(argv[1], &m) || m.nf == 0) { fprintf(stderr, "embree_trace: cannot read triangles from %s\n", argv[1]); return 1; }

    RTCDevice dev = rtcNewDevice(NULL);
    RTCScene scene = rtcNewScene(dev);
    rtcSetSceneBuildQuality(scene, high ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (high) rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.nv);
    memcpy(vb, m.v, m.nv * 3 * sizeof(float));
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), m.nf);
    memcpy(ib, m.f, m.nf * 3 * sizeof(unsigned));
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    double tb = now();
    rtcCommitScene(scene);
    tb = now() - tb;
    struct RTCBounds b;
    rtcGetSceneBounds(scene, &b);

    float *o = malloc(n * 3 * sizeof(float)), *d = malloc(n * 3 * sizeof(float));
    for (size_t i = 0; i < n; i++) {
        float u0 = next_f32(), u1 = next_f32(), u2 = next_f32(), u3 = next_f32(), u4 = next_f32();
        o[3 * i] = b.lower_x + (b.upper_x - b.lower_x) * u0;
        o[3 * i + 1] = b.lower_y + (b.upper_y - b.lower_y) * u1;
        o[3 * i + 2] = b.lower_z + (b.upper_z - b.lower_z) * u2;
        float z = 1.0f - 2.0f * u3, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 6.2831853f * u4;
        d[3 * i] = r * cosf(phi); d[3 * i + 1] = r * sinf(phi); d[3 * i + 2] = z;
    }

    struct RTCIntersectContext ctx;
    const char *names[] = {"rtcIntersect1", "rtcIntersect4", "rtcIntersect8", "rtcIntersect16", "rtcIntersect1M"};
    struct RTCRayHit *stream = aligned_alloc(64, n * sizeof(struct RTCRayHit));
    for (int mode = 0; mode < 5; mode++) {
        double best = 0; size_t hits = 0;
        for (int pass = 0; pass < 5; pass++) {
            hits = 0;
            double t0 = now();
            if (mode == 0) {
                rtcInitIntersectContext(&ctx);
                for (size_t i = 0; i < n; i++) {
                    struct RTCRayHit rh;
                    rh.ray.org_x = o[3 * i]; rh.ray.org_y = o[3 * i + 1]; rh.ray.org_z = o[3 * i + 2];
                    rh.ray.dir_x = d[3 * i]; rh.ray.dir_y = d[3 * i + 1]; rh.ray.dir_z = d[3 * i + 2];
                    rh.ray.tnear = 0; rh.ray.tfar = INFINITY; rh.ray.mask = -1; rh.ray.flags = 0; rh.ray.time = 0;
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &ctx, &rh);
                    hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                }
            } else if (mode <= 3) {
                int w = mode == 1 ? 4 : mode == 2 ? 8 : 16;
                rtcInitIntersectContext(&ctx);
                ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
                _Alignas(64) struct RTCRayHit16 p;
                _Alignas(64) int valid[16];
                for (int k = 0; k < 16; k++) valid[k] = -1;
                /* The packet structs of widths 4, 8 and 16 share the SoA layout with stride w. */
                float *pf = (float *)&p;
                for (size_t i = 0; i < n; i += w) {
                    for (int k = 0; k < w; k++) {
                        size_t j = i + k;
                        pf[0 * w + k] = o[3 * j]; pf[1 * w + k] = o[3 * j + 1]; pf[2 * w + k] = o[3 * j + 2];
                        pf[3 * w + k] = 0.0f; /* tnear */
                        pf[4 * w + k] = d[3 * j]; pf[5 * w + k] = d[3 * j + 1]; pf[6 * w + k] = d[3 * j + 2];
                        pf[7 * w + k] = 0.0f; /* time */
                        pf[8 * w + k] = INFINITY; /* tfar */
                        ((unsigned *)pf)[9 * w + k] = -1; /* mask */
                        ((unsigned *)pf)[10 * w + k] = 0; /* id */
                        ((unsigned *)pf)[11 * w + k] = 0; /* flags */
                        ((unsigned *)pf)[12 * w + k + 6 * w] = RTC_INVALID_GEOMETRY_ID; /* hit.geomID */
                    }
                    if (w == 4) rtcIntersect4(valid, scene, &ctx, (struct RTCRayHit4 *)&p);
                    else if (w == 8) rtcIntersect8(valid, scene, &ctx, (struct RTCRayHit8 *)&p);
                    else rtcIntersect16(valid, scene, &ctx, &p);
                    for (int k = 0; k < w; k++) hits += ((unsigned *)pf)[12 * w + k + 6 * w] != RTC_INVALID_GEOMETRY_ID;
                }
            } else {
                for (size_t i = 0; i < n; i++) {
                    struct RTCRayHit *rh = &stream[i];
                    rh->ray.org_x = o[3 * i]; rh->ray.org_y = o[3 * i + 1]; rh->ray.org_z = o[3 * i + 2];
                    rh->ray.dir_x = d[3 * i]; rh->ray.dir_y = d[3 * i + 1]; rh->ray.dir_z = d[3 * i + 2];
                    rh->ray.tnear = 0; rh->ray.tfar = INFINITY; rh->ray.mask = -1; rh->ray.flags = 0; rh->ray.time = 0;
                    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
                }
                rtcInitIntersectContext(&ctx);
                ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
                rtcIntersect1M(scene, &ctx, stream, n, sizeof(struct RTCRayHit));
                for (size_t i = 0; i < n; i++) hits += stream[i].hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
            double r = n / (now() - t0);
            if (r > best) best = r;
        }
        printf("%s: %s %.2f M closest-hit rays/s on one thread, %zu hits of %zu (%s build, %zu triangles, built in %.3f s)\n",
               argv[1], names[mode], best / 1e6, hits, n, high ? "high" : "medium", m.nf, tb);
    }
    rtcReleaseScene(scene);
    rtcReleaseDevice(dev);
    return 0;
}
