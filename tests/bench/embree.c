/* embree.c — Embree 3 as the peer every structure is measured against.
 *
 * Set-up (documented in the table's header too):
 *   device  rtcNewDevice("threads=1"): builds on one thread, like sidx's
 *           builders by default; tracing is one thread (rtcIntersect1).
 *           bench_embree_build_threads makes a "threads=N" device for the
 *           parallel-build comparison.
 *   scene   RTC_SCENE_FLAG_ROBUST for the "-robust" rows, no flags otherwise;
 *           build quality MEDIUM (Embree's default: binned SAH BVH, the same
 *           family as sidx's bvh) or HIGH for the "-hq" rows (adds spatial
 *           splits, an SBVH).
 *   geometry one RTC_GEOMETRY_TYPE_TRIANGLE, vertices copied into an Embree
 *           buffer (FLOAT3, padded as Embree requires), indices UINT3.
 * Memory is the sum of the bytes Embree reports through its memory monitor
 * after the commit. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include <embree3/rtcore.h>

#include "bench.h"

struct bench_embree {
    RTCDevice device;
    RTCScene scene;
    atomic_llong bytes;
};

static bool memory_monitor(void *user, ssize_t bytes, bool post)
{
    (void)post;
    struct bench_embree *e = user;
    atomic_fetch_add(&e->bytes, (long long)bytes);
    return true;
}

int bench_embree_parse(const char *name, bench_embree_cfg *cfg)
{
    static const struct { const char *name; int robust, quality; } names[] = {
        {"embree", 0, RTC_BUILD_QUALITY_MEDIUM},
        {"embree-robust", 1, RTC_BUILD_QUALITY_MEDIUM},
        {"embree-hq", 0, RTC_BUILD_QUALITY_HIGH},
        {"embree-robust-hq", 1, RTC_BUILD_QUALITY_HIGH},
    };
    for (size_t i = 0; name && i < sizeof names / sizeof names[0]; ++i)
        if (!strcmp(name, names[i].name)) {
            if (cfg) {
                cfg->robust = names[i].robust;
                cfg->quality = names[i].quality;
            }
            return 1;
        }
    return 0;
}

const char *bench_embree_version(void) { return RTC_VERSION_STRING; }

/* threads = 0: the table's rows (a "threads=1" device, timed with the
 * bench's build clock like sidx's one-thread builds).  threads >= 1: the
 * parallel-build comparison (run.c's packet and parallel section), where
 * the device gets "threads=N" and the build is timed in wall-clock (CPU
 * time would add the threads up). */
static int embree_build(const sidx_mesh *m, bench_embree_cfg cfg, unsigned threads, bench_embree **out,
                        double *build_ms, char *msg, size_t msg_size);

int bench_embree_build(const sidx_mesh *m, bench_embree_cfg cfg, bench_embree **out, double *build_ms, char *msg,
                       size_t msg_size)
{
    return embree_build(m, cfg, 0, out, build_ms, msg, msg_size);
}

int bench_embree_build_threads(const sidx_mesh *m, bench_embree_cfg cfg, unsigned threads, bench_embree **out,
                               double *build_ms, char *msg, size_t msg_size)
{
    return embree_build(m, cfg, threads ? threads : 1, out, build_ms, msg, msg_size);
}

static int embree_build(const sidx_mesh *m, bench_embree_cfg cfg, unsigned threads, bench_embree **out,
                        double *build_ms, char *msg, size_t msg_size)
{
    *out = NULL;
    struct bench_embree *e = calloc(1, sizeof *e);
    if (!e) {
        snprintf(msg, msg_size, "embree: out of memory");
        return 0;
    }
    atomic_init(&e->bytes, 0);
    char devcfg[32];
    snprintf(devcfg, sizeof devcfg, "threads=%u", threads ? threads : 1u);
    e->device = rtcNewDevice(devcfg);
    if (!e->device) {
        snprintf(msg, msg_size, "embree: rtcNewDevice failed (error %d)", (int)rtcGetDeviceError(NULL));
        free(e);
        return 0;
    }
    rtcSetDeviceMemoryMonitorFunction(e->device, memory_monitor, e);
    double (*clock_ms)(void) = threads ? tk_now_ms : bench_build_clock_ms;
    const double t0 = clock_ms();
    e->scene = rtcNewScene(e->device);
    rtcSetSceneFlags(e->scene, cfg.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(e->scene, (enum RTCBuildQuality)cfg.quality);
    RTCGeometry g = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, (enum RTCBuildQuality)cfg.quality);
    /* One extra vertex of padding: Embree reads 16 bytes for a FLOAT3. */
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                       (size_t)m->num_vertices + 1);
    unsigned *ix = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                           m->num_triangles ? m->num_triangles : 1);
    if (!v || !ix) {
        snprintf(msg, msg_size, "embree: buffer allocation failed (error %d)", (int)rtcGetDeviceError(e->device));
        rtcReleaseGeometry(g);
        bench_embree_free(e);
        return 0;
    }
    for (uint32_t i = 0; i < m->num_vertices; ++i) {
        v[3 * i + 0] = m->positions[i].x;
        v[3 * i + 1] = m->positions[i].y;
        v[3 * i + 2] = m->positions[i].z;
    }
    memset(v + 3 * (size_t)m->num_vertices, 0, 3 * sizeof(float));
    memcpy(ix, m->indices, 3 * (size_t)m->num_triangles * sizeof(unsigned));
    if (m->num_triangles == 0) memset(ix, 0, 3 * sizeof(unsigned));
    rtcCommitGeometry(g);
    rtcAttachGeometry(e->scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(e->scene);
    *build_ms = clock_ms() - t0;
    enum RTCError rerr = rtcGetDeviceError(e->device);
    if (rerr != RTC_ERROR_NONE) {
        snprintf(msg, msg_size, "embree: build failed (error %d)", (int)rerr);
        bench_embree_free(e);
        return 0;
    }
    *out = e;
    return 1;
}

size_t bench_embree_bytes(const bench_embree *e)
{
    long long b = e ? atomic_load(&((struct bench_embree *)e)->bytes) : 0;
    return b > 0 ? (size_t)b : 0;
}

/* Everything rtcIntersect1 returns is stored (t, prim, u, v, Ng), so the
 * Embree side does the same work as a sidx query asking for u, v and the
 * normal (the targets section's "fair" timing). */
static void to_hit(sidx_hit *h, unsigned geom, unsigned prim, float t, float u, float v, float nx, float ny,
                   float nz)
{
    *h = sidx_hit_none();
    if (geom != RTC_INVALID_GEOMETRY_ID) {
        h->t = t;
        h->prim = prim;
        h->u = u;
        h->v = v;
        h->ng = sidx_v3(nx, ny, nz);
    }
}

#define PACKET_FN(W)                                                                                              \
    static void trace_packet##W(RTCScene scene, struct RTCIntersectContext *ctx, const tk_rayrec *rays, size_t n,        \
                                sidx_hit *hits)                                                                   \
    {                                                                                                             \
        struct RTCRayHit##W rh;                                                                                   \
        int valid[W];                                                                                             \
        for (size_t base = 0; base < n; base += W) {                                                              \
            for (int k = 0; k < W; ++k) {                                                                         \
                const size_t i = base + (size_t)k;                                                                \
                const tk_rayrec *r = &rays[i < n ? i : n - 1];                                                    \
                valid[k] = i < n ? -1 : 0;                                                                        \
                rh.ray.org_x[k] = r->o[0]; rh.ray.org_y[k] = r->o[1]; rh.ray.org_z[k] = r->o[2];                  \
                rh.ray.dir_x[k] = r->d[0]; rh.ray.dir_y[k] = r->d[1]; rh.ray.dir_z[k] = r->d[2];                  \
                rh.ray.tnear[k] = r->tmin; rh.ray.tfar[k] = r->tmax; rh.ray.time[k] = 0.0f;                       \
                rh.ray.mask[k] = 0xffffffffu; rh.ray.id[k] = (unsigned)k; rh.ray.flags[k] = 0;                    \
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID; rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;        \
            }                                                                                                     \
            rtcIntersect##W(valid, scene, ctx, &rh);                                                              \
            for (int k = 0; k < W && base + (size_t)k < n; ++k)                                                   \
                to_hit(&hits[base + (size_t)k], rh.hit.geomID[k], rh.hit.primID[k], rh.ray.tfar[k], rh.hit.u[k],  \
                       rh.hit.v[k], rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]);                              \
        }                                                                                                         \
    }
PACKET_FN(4)
PACKET_FN(8)
PACKET_FN(16)

double bench_embree_trace(bench_embree *e, const tk_rayrec *rays, size_t n, int any_hit, int packet, sidx_hit *hits)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    const double t0 = bench_clock_ms();
    if (n && packet == 4 && !any_hit) trace_packet4(e->scene, &ctx, rays, n, hits);
    else if (n && packet == 8 && !any_hit) trace_packet8(e->scene, &ctx, rays, n, hits);
    else if (n && packet == 16 && !any_hit) trace_packet16(e->scene, &ctx, rays, n, hits);
    else if (any_hit) {
        for (size_t i = 0; i < n; ++i) {
            const tk_rayrec *r = &rays[i];
            struct RTCRay ray = {r->o[0], r->o[1], r->o[2], r->tmin, r->d[0], r->d[1], r->d[2], 0.0f,
                                 r->tmax, 0xffffffffu, (unsigned)i, 0};
            rtcOccluded1(e->scene, &ctx, &ray);
            hits[i] = sidx_hit_none();
            if (ray.tfar == -INFINITY) {
                hits[i].prim = 0;
                hits[i].t = 0.0f;
            }
        }
    } else {
        for (size_t i = 0; i < n; ++i) {
            const tk_rayrec *r = &rays[i];
            struct RTCRayHit rh;
            rh.ray = (struct RTCRay){r->o[0], r->o[1], r->o[2], r->tmin, r->d[0], r->d[1], r->d[2], 0.0f,
                                     r->tmax, 0xffffffffu, (unsigned)i, 0};
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(e->scene, &ctx, &rh);
            to_hit(&hits[i], rh.hit.geomID, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v, rh.hit.Ng_x, rh.hit.Ng_y,
                   rh.hit.Ng_z);
        }
    }
    return bench_clock_ms() - t0;
}

/* Embree's stream entry, rtcIntersect1M / rtcOccluded1M over the whole
 * buffer; the rays are written into `scratch` (n RTCRayHit) inside the
 * timed part, as the single-ray loop above builds its rays per call.
 * coherent: the context's RTC_INTERSECT_CONTEXT_FLAG_COHERENT (camera
 * rays), else the default, incoherent. */
double bench_embree_trace_stream(bench_embree *e, const tk_rayrec *rays, size_t n, int any_hit, int coherent,
                                 void *scratch, sidx_hit *hits)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    struct RTCRayHit *rh = scratch;
    const double t0 = bench_clock_ms();
    for (size_t i = 0; i < n; ++i) {
        const tk_rayrec *r = &rays[i];
        rh[i].ray = (struct RTCRay){r->o[0], r->o[1], r->o[2], r->tmin, r->d[0], r->d[1], r->d[2], 0.0f,
                                    r->tmax, 0xffffffffu, (unsigned)i, 0};
        rh[i].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    if (any_hit) {
        /* RTCRay is the head of RTCRayHit: the same array, its stride */
        rtcOccluded1M(e->scene, &ctx, &rh->ray, (unsigned)n, sizeof *rh);
        for (size_t i = 0; i < n; ++i) {
            hits[i] = sidx_hit_none();
            if (rh[i].ray.tfar == -INFINITY) {
                hits[i].prim = 0;
                hits[i].t = 0.0f;
            }
        }
    } else {
        rtcIntersect1M(e->scene, &ctx, rh, (unsigned)n, sizeof *rh);
        for (size_t i = 0; i < n; ++i)
            to_hit(&hits[i], rh[i].hit.geomID, rh[i].hit.primID, rh[i].ray.tfar, rh[i].hit.u, rh[i].hit.v,
                   rh[i].hit.Ng_x, rh[i].hit.Ng_y, rh[i].hit.Ng_z);
    }
    return bench_clock_ms() - t0;
}
size_t bench_embree_stream_scratch(void) { return sizeof(struct RTCRayHit); }

typedef struct embree_pass {
    bench_embree *e;
    const tk_rayrec *rays;
    size_t n;
    int any_hit, packet;
    sidx_hit *hits;
} embree_pass;

static double embree_pass_run(void *ctx, int cold)
{
    (void)cold;
    const embree_pass *p = ctx;
    return bench_embree_trace(p->e, p->rays, p->n, p->any_hit, p->packet, p->hits);
}

void bench_embree_trace_timed(bench_embree *e, const tk_rayrec *rays, size_t n, int any_hit, int packet, int passes,
                              double budget_ms, sidx_hit *hits, bench_timing *t)
{
    embree_pass p = {e, rays, n, any_hit, packet, hits};
    const bench_buf bufs[2] = {{hits, n * sizeof *hits, 1}, {rays, n * sizeof *rays, 0}};
    bench_time_passes(embree_pass_run, &p, bufs, 2, passes, budget_ms, t);
}

void bench_embree_free(bench_embree *e)
{
    if (!e) return;
    if (e->scene) rtcReleaseScene(e->scene);
    if (e->device) rtcReleaseDevice(e->device);
    free(e);
}
