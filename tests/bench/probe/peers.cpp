/* peers.cpp — sidx's `bvh8` and `bvh` beside tinybvh, bvh v2 and Embree 3
 * on the rays of `sidx-bench run` / `sidx-bench stream`, in one
 * interleaved run (docs/performance.md, "Beside tinybvh and bvh v2").
 * Not part of the build, and C++ (tinybvh and bvh v2 are C++ headers);
 * compile and run it by hand from the top of the tree.
 *
 * The peers, header-only, outside the tree (commits measured: tinybvh
 * 4735685f64d8b2bb0ad2c6c4643f291bf58774ad, bvh v2
 * ac41ab88a32d0c247009d8ed456fd2795c1ee023):
 *
 *   git clone https://github.com/jbikker/tinybvh /tmp/peers/tinybvh
 *   git -C /tmp/peers/tinybvh checkout 4735685f64d8b2bb0ad2c6c4643f291bf58774ad
 *   git clone https://github.com/madmann91/bvh /tmp/peers/bvh
 *   git -C /tmp/peers/bvh checkout ac41ab88a32d0c247009d8ed456fd2795c1ee023
 *
 * Build (libsidx.a from `make`; Embree 3 from libembree-dev; g++ 12,
 * C++20 for bvh v2's std::span; -march=native for tinybvh's AVX2 paths):
 *
 *   g++ -std=c++20 -O3 -march=native -DNDEBUG -Ilib/include \
 *       -I/tmp/peers/tinybvh -I/tmp/peers/bvh/src tests/bench/probe/peers.cpp \
 *       build/lib/libsidx.a -lembree3 -lm -pthread -o /tmp/peers/peers
 *
 * Rays, the sets `sidx-bench run` and `sidx-bench stream` trace (seed 1):
 *
 *   for s in bunny sponza_dabrovic; do for k in primary diffuse; do
 *     build/bin/sidx-bench rays /work/shared/scenes/$s.obj $k 100000 1 /tmp/peers/$s-$k.bin
 *   done; done
 *
 * Run, one triple per table row:
 *
 *   nice ./peers [--rounds R] [--passes P] SCENE.obj LABEL RAYS.bin [SCENE.obj LABEL RAYS.bin ...]
 *
 * Method (as `sidx-bench stream`, docs/performance.md "Benchmark method"):
 * every tracer runs once per round, the order rotated from round to round;
 * in its turn one untimed warm-up pass, then the rays and its hit array
 * are touched, then P timed passes (best and median kept).  Thread CPU
 * time, one thread.  Per row: each round's ratio Embree HIGH best / the
 * tracer's best, median [min..max] over R rounds.
 *
 * What each tracer does in its timed loop:
 *   sidx     rays prepared by sidx_ray_init beforehand; t and prim asked
 *            (query flags 0: no u, v); `bvh8` single (sidx_accel_intersect
 *            per ray) and stream (sidx_accel_intersect_n over the buffer),
 *            `bvh` and `bvh-sbvh` single.  Default build options.
 *   Embree   device "threads=1", build quality HIGH, no scene flags (the
 *            reference) or RTC_SCENE_FLAG_ROBUST; RTCRayHit set up per ray,
 *            rtcIntersect1, t, prim, u, v and Ng stored (tests/bench/embree.c).
 *   tinybvh  BVH8_CPU::Build, and BVH::BuildHQ (binary, spatial splits),
 *            over the triangle soup; a tinybvh::Ray built per ray (it
 *            normalises d, so its t is a distance: t / |d| is compared),
 *            Intersect, t, prim, u, v stored.
 *   bvh v2   DefaultBuilder, Quality::High, single-threaded (sweep SAH and
 *            reinsertion), primitives permuted into PrecomputedTri; a Ray
 *            built per ray, bvh.intersect<false, false> with a 64-entry
 *            SmallStack as its README's example, t, u, v and the original
 *            prim (through prim_ids) stored.
 * Before timing, every tracer's hits are compared with sidx `bvh8`'s: a
 * ray counts as different when the hit triangle differs (or one misses) or
 * t differs by more than 1e-4 relative. */
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <bvh/v2/bvh.h>
#include <bvh/v2/default_builder.h>
#include <bvh/v2/node.h>
#include <bvh/v2/ray.h>
#include <bvh/v2/stack.h>
#include <bvh/v2/tri.h>
#include <bvh/v2/vec.h>

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <tuple>
#include <vector>

#include "sidx/sidx.h"

using V2Vec = bvh::v2::Vec<float, 3>;
using V2BBox = bvh::v2::BBox<float, 3>;
using V2Tri = bvh::v2::Tri<float, 3>;
using V2Node = bvh::v2::Node<float, 3>;
using V2Bvh = bvh::v2::Bvh<V2Node>;
using V2Ray = bvh::v2::Ray<float, 3>;
using V2PreTri = bvh::v2::PrecomputedTri<float>;

struct rayrec { float o[3], d[3], tmin, tmax; }; /* 32 bytes on disk, little endian (tests/common/testkit.c) */

static double cpu_ms()
{
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

enum { T_EMB, T_EMBR, T_B8, T_B8S, T_BVH, T_SBVH, T_TINY8, T_TINYHQ, T_V2, NT };
static const char *const tracer_names[NT] = {"Embree HIGH", "Embree robust", "bvh8 single", "bvh8 stream", "bvh",
                                             "bvh-sbvh", "tinybvh BVH8_CPU", "tinybvh BuildHQ", "bvh v2"};

struct embree_scene { RTCDevice dev = nullptr; RTCScene scene = nullptr; };

static bool embree_build(const sidx_mesh &m, bool robust, embree_scene &e)
{
    e.dev = rtcNewDevice("threads=1");
    if (!e.dev) return false;
    e.scene = rtcNewScene(e.dev);
    rtcSetSceneFlags(e.scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(e.scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(e.dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    /* one vertex of padding: Embree reads 16 bytes per FLOAT3 */
    float *v = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                (size_t)m.num_vertices + 1);
    unsigned *ix = (unsigned *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                       3 * sizeof(unsigned), m.num_triangles);
    if (!v || !ix) return false;
    for (uint32_t i = 0; i < m.num_vertices; ++i) {
        v[3 * i] = m.positions[i].x;
        v[3 * i + 1] = m.positions[i].y;
        v[3 * i + 2] = m.positions[i].z;
    }
    std::memset(v + 3 * (size_t)m.num_vertices, 0, 3 * sizeof(float));
    std::memcpy(ix, m.indices, 3 * (size_t)m.num_triangles * sizeof(unsigned));
    rtcCommitGeometry(g);
    rtcAttachGeometry(e.scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(e.scene);
    return rtcGetDeviceError(e.dev) == RTC_ERROR_NONE;
}

struct peers {
    sidx_accel *b8 = nullptr, *bvh = nullptr, *sbvh = nullptr;
    embree_scene emb, embr;
    std::vector<tinybvh::bvhvec4> soup; /* 3 vertices per triangle, kept alive: the BVHs point into it */
    tinybvh::BVH8_CPU tiny8;
    tinybvh::BVH tinyhq;
    V2Bvh v2;
    std::vector<V2PreTri> v2tris;
};

/* the rays */
static size_t n_rays;
static const rayrec *rec;
static const sidx_ray *srays;
static sidx_hit *out[NT]; /* each tracer's own hit array */

static double run(peers &p, int t)
{
    const size_t n = n_rays;
    sidx_hit *h = out[t];
    const sidx_query q = {0u, SIDX_TRAVERSE_DEFAULT, nullptr, 0};
    const double t0 = cpu_ms();
    switch (t) {
    case T_EMB:
    case T_EMBR: {
        RTCScene sc = t == T_EMB ? p.emb.scene : p.embr.scene;
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        for (size_t i = 0; i < n; ++i) {
            const rayrec *r = &rec[i];
            RTCRayHit rh;
            rh.ray = RTCRay{r->o[0], r->o[1], r->o[2], r->tmin, r->d[0], r->d[1], r->d[2], 0.0f,
                            r->tmax, 0xffffffffu, (unsigned)i, 0};
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(sc, &ctx, &rh);
            h[i] = sidx_hit_none();
            if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
                h[i].t = rh.ray.tfar;
                h[i].prim = rh.hit.primID;
                h[i].u = rh.hit.u;
                h[i].v = rh.hit.v;
                h[i].ng = sidx_v3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
            }
        }
        break;
    }
    case T_B8: for (size_t i = 0; i < n; ++i) (void)sidx_accel_intersect(p.b8, &srays[i], &q, &h[i]); break;
    case T_B8S: (void)sidx_accel_intersect_n(p.b8, srays, n, &q, h); break;
    case T_BVH: for (size_t i = 0; i < n; ++i) (void)sidx_accel_intersect(p.bvh, &srays[i], &q, &h[i]); break;
    case T_SBVH: for (size_t i = 0; i < n; ++i) (void)sidx_accel_intersect(p.sbvh, &srays[i], &q, &h[i]); break;
    case T_TINY8:
    case T_TINYHQ:
        for (size_t i = 0; i < n; ++i) {
            const rayrec *r = &rec[i];
            /* its t is a distance along the normalised direction: a finite tmax is scaled by |d| */
            const float tmax = r->tmax < BVH_FAR
                                   ? r->tmax * std::sqrt(r->d[0] * r->d[0] + r->d[1] * r->d[1] + r->d[2] * r->d[2])
                                   : BVH_FAR;
            tinybvh::Ray ray(tinybvh::bvhvec3(r->o[0], r->o[1], r->o[2]), tinybvh::bvhvec3(r->d[0], r->d[1], r->d[2]),
                             tmax);
            if (t == T_TINY8) p.tiny8.Intersect(ray);
            else p.tinyhq.Intersect(ray);
            h[i].t = ray.hit.t;
            h[i].prim = ray.hit.t < BVH_FAR ? ray.hit.prim : SIDX_NO_HIT;
            h[i].u = ray.hit.u;
            h[i].v = ray.hit.v;
        }
        break;
    case T_V2: {
        static constexpr size_t invalid = ~(size_t)0;
        for (size_t i = 0; i < n; ++i) {
            const rayrec *r = &rec[i];
            V2Ray ray{V2Vec(r->o[0], r->o[1], r->o[2]), V2Vec(r->d[0], r->d[1], r->d[2]), r->tmin, r->tmax};
            size_t prim = invalid;
            float u = 0, v = 0;
            bvh::v2::SmallStack<V2Bvh::Index, 64> stack;
            p.v2.intersect<false, false>(ray, p.v2.get_root().index, stack, [&](size_t begin, size_t end) {
                for (size_t k = begin; k < end; ++k)
                    if (auto hit = p.v2tris[k].intersect(ray)) {
                        prim = k;
                        std::tie(ray.tmax, u, v) = *hit;
                    }
                return prim != invalid;
            });
            h[i].t = ray.tmax;
            h[i].prim = prim != invalid ? (uint32_t)p.v2.prim_ids[prim] : SIDX_NO_HIT;
            h[i].u = u;
            h[i].v = v;
        }
        break;
    }
    }
    return cpu_ms() - t0;
}

/* Every byte the pass reads or writes, in cache before the clock. */
static void touch(int t)
{
    volatile unsigned char sink = 0;
    const unsigned char *a = (const unsigned char *)rec, *b = (const unsigned char *)srays;
    for (size_t i = 0; i < n_rays * sizeof *rec; i += 64) sink = sink + a[i];
    for (size_t i = 0; i < n_rays * sizeof *srays; i += 64) sink = sink + b[i];
    std::fill(out[t], out[t] + n_rays, sidx_hit{});
    (void)sink;
}

/* hits that differ from sidx bvh8's: another triangle, or t off by more
 * than 1e-4 relative (tinybvh's t is along the normalised direction) */
static size_t differ(int t)
{
    size_t bad = 0;
    for (size_t i = 0; i < n_rays; ++i) {
        const sidx_hit &a = out[T_B8][i], &b = out[t][i];
        if (a.prim != b.prim) { ++bad; continue; }
        if (a.prim == SIDX_NO_HIT) continue;
        const double len = std::sqrt((double)rec[i].d[0] * rec[i].d[0] + (double)rec[i].d[1] * rec[i].d[1] +
                                     (double)rec[i].d[2] * rec[i].d[2]);
        const double tb = (t == T_TINY8 || t == T_TINYHQ) ? b.t / len : b.t;
        if (std::fabs(tb - a.t) > 1e-4 * std::fabs((double)a.t)) ++bad;
    }
    return bad;
}

static bool read_rays(const char *path, std::vector<rayrec> &v)
{
    FILE *f = std::fopen(path, "rb");
    if (!f) return false;
    unsigned char buf[32];
    while (std::fread(buf, 1, 32, f) == 32) {
        rayrec r;
        std::memcpy(&r, buf, 32); /* x86-64: little endian, as written */
        v.push_back(r);
    }
    std::fclose(f);
    return !v.empty();
}

static double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
static void cell(char *s, size_t size, const std::vector<double> &v)
{
    std::snprintf(s, size, "%.2f [%.2f..%.2f]", median(v), *std::min_element(v.begin(), v.end()),
                  *std::max_element(v.begin(), v.end()));
}

int main(int argc, char **argv)
{
    int rounds = 5, passes = 5, a = 1;
    for (; a + 1 < argc && argv[a][0] == '-'; a += 2) {
        if (!std::strcmp(argv[a], "--rounds")) rounds = std::atoi(argv[a + 1]);
        else if (!std::strcmp(argv[a], "--passes")) passes = std::atoi(argv[a + 1]);
        else break;
    }
    if ((argc - a) % 3 || argc == a || rounds < 1 || passes < 1) {
        std::fprintf(stderr, "usage: peers [--rounds R] [--passes P] SCENE.obj LABEL RAYS.bin ...\n");
        return 2;
    }
    std::printf("peers: %d rounds of (1 warm-up + %d passes per tracer, order rotated), thread CPU time, one thread;\n"
                "ratio = Embree HIGH best / the tracer's best per round, median [min..max]; Embree %s\n\n",
                rounds, passes, RTC_VERSION_STRING);
    std::vector<std::string> table, detail;
    for (; a < argc; a += 3) {
        const char *scene = argv[a], *label = argv[a + 1], *raypath = argv[a + 2];
        sidx_mesh m = {};
        sidx_error err = {SIDX_OK, ""};
        if (sidx_scene_open(scene, &m, &err) != SIDX_OK) { std::fprintf(stderr, "%s: %s\n", scene, err.message); return 1; }
        std::vector<rayrec> rv;
        if (!read_rays(raypath, rv)) { std::fprintf(stderr, "%s: no rays\n", raypath); return 1; }
        const size_t n = rv.size();
        std::vector<sidx_ray> sr(n);
        size_t refused = 0, tmin_nonzero = 0, tmax_finite = 0;
        for (size_t i = 0; i < n; ++i) {
            const rayrec &r = rv[i];
            if (r.tmin != 0.0f) ++tmin_nonzero; /* tinybvh has no tmin */
            if (std::isfinite(r.tmax)) ++tmax_finite; /* nor a tmax in the ray's parameter */
            if (sidx_ray_init(&sr[i], sidx_v3(r.o[0], r.o[1], r.o[2]), sidx_v3(r.d[0], r.d[1], r.d[2]), r.tmin, r.tmax) !=
                SIDX_OK) { /* as sidx-bench stream: a refused ray becomes one that misses, on every side */
                rv[i] = rayrec{{0, 0, 0}, {1, 0, 0}, 0.0f, 0.0f};
                (void)sidx_ray_init(&sr[i], sidx_v3(0, 0, 0), sidx_v3(1, 0, 0), 0.0f, 0.0f);
                ++refused;
            }
        }
        n_rays = n;
        rec = rv.data();
        srays = sr.data();
        std::vector<sidx_hit> store((size_t)NT * n);
        for (int t = 0; t < NT; ++t) out[t] = store.data() + (size_t)t * n;

        peers p;
        const char *names[3] = {"bvh8", "bvh", "bvh-sbvh"};
        sidx_accel **acc[3] = {&p.b8, &p.bvh, &p.sbvh};
        for (int k = 0; k < 3; ++k)
            if (sidx_accel_build(names[k], &m, nullptr, acc[k], &err) != SIDX_OK) {
                std::fprintf(stderr, "build %s: %s\n", names[k], err.message);
                return 1;
            }
        if (!embree_build(m, false, p.emb) || !embree_build(m, true, p.embr)) { std::fprintf(stderr, "embree build failed\n"); return 1; }
        p.soup.resize(3 * (size_t)m.num_triangles);
        std::vector<V2Tri> tris(m.num_triangles);
        std::vector<V2BBox> boxes(m.num_triangles);
        std::vector<V2Vec> centers(m.num_triangles);
        for (uint32_t i = 0; i < m.num_triangles; ++i) {
            V2Vec v[3];
            for (int k = 0; k < 3; ++k) {
                const sidx_vec3 q = m.positions[m.indices[3 * i + k]];
                p.soup[3 * (size_t)i + k] = tinybvh::bvhvec4(q.x, q.y, q.z, 0.0f);
                v[k] = V2Vec(q.x, q.y, q.z);
            }
            tris[i] = V2Tri(v[0], v[1], v[2]);
            boxes[i] = tris[i].get_bbox();
            centers[i] = tris[i].get_center();
        }
        p.tiny8.Build(p.soup.data(), m.num_triangles);
        p.tinyhq.BuildHQ(p.soup.data(), m.num_triangles);
        bvh::v2::DefaultBuilder<V2Node>::Config cfg;
        cfg.quality = bvh::v2::DefaultBuilder<V2Node>::Quality::High;
        p.v2 = bvh::v2::DefaultBuilder<V2Node>::build(boxes, centers, cfg); /* one thread */
        p.v2tris.resize(m.num_triangles);
        for (size_t i = 0; i < m.num_triangles; ++i) p.v2tris[i] = tris[p.v2.prim_ids[i]]; /* permuted */

        /* the hits, each against sidx bvh8's */
        size_t diff[NT];
        for (int t = 0; t < NT; ++t) run(p, t);
        for (int t = 0; t < NT; ++t) diff[t] = differ(t);

        std::vector<double> best[NT], med[NT];
        for (int r = 0; r < rounds; ++r)
            for (int j = 0; j < NT; ++j) {
                const int t = (j + r) % NT; /* rotated: a slow spell falls on every tracer alike */
                (void)run(p, t);            /* warm-up */
                touch(t);
                std::vector<double> ms;
                for (int k = 0; k < passes; ++k) ms.push_back(run(p, t));
                best[t].push_back(*std::min_element(ms.begin(), ms.end()));
                med[t].push_back(median(ms));
            }
        auto ratio = [&](int t) {
            std::vector<double> v;
            for (int r = 0; r < rounds; ++r) v.push_back(best[T_EMB][r] / best[t][r]);
            return v;
        };
        char row[1024], c[64];
        std::snprintf(row, sizeof row, "| %s%s |", label, refused ? "*" : "");
        const int cols[] = {T_B8, T_B8S, T_TINY8, T_EMBR, T_BVH, T_SBVH, T_V2, T_TINYHQ};
        for (int t : cols) {
            cell(c, sizeof c, ratio(t));
            std::strncat(row, " ", sizeof row - std::strlen(row) - 1);
            std::strncat(row, c, sizeof row - std::strlen(row) - 1);
            std::strncat(row, " |", sizeof row - std::strlen(row) - 1);
        }
        /* head to head, per round: the peer's time / sidx's */
        std::vector<double> h8, hb, hs;
        for (int r = 0; r < rounds; ++r) {
            const double peer2 = std::min(best[T_V2][r], best[T_TINYHQ][r]); /* the faster binary peer that round */
            h8.push_back(best[T_TINY8][r] / best[T_B8][r]);
            hb.push_back(peer2 / best[T_BVH][r]);
            hs.push_back(peer2 / best[T_SBVH][r]);
        }
        for (auto *v : {&h8, &hb, &hs}) {
            cell(c, sizeof c, *v);
            std::strncat(row, " ", sizeof row - std::strlen(row) - 1);
            std::strncat(row, c, sizeof row - std::strlen(row) - 1);
            std::strncat(row, " |", sizeof row - std::strlen(row) - 1);
        }
        table.push_back(row);
        for (int t = 0; t < NT; ++t) {
            std::snprintf(row, sizeof row, "| %s | %s | %.2f | %.2f | %zu |", label, tracer_names[t],
                          n / 1e3 / median(best[t]), n / 1e3 / median(med[t]), diff[t]);
            detail.push_back(row);
        }
        std::fprintf(stderr, "%s: %zu rays, %zu refused by sidx_ray_init, %zu with tmin != 0, %zu with a finite tmax;"
                     " %u triangles\n", label, n, refused, tmin_nonzero, tmax_finite, m.num_triangles);
        for (int k = 0; k < 3; ++k) sidx_accel_destroy(*acc[k]);
        for (embree_scene *e : {&p.emb, &p.embr}) {
            rtcReleaseScene(e->scene);
            rtcReleaseDevice(e->dev);
        }
        sidx_mesh_free(&m);
    }
    std::printf("Speed / Embree HIGH `rtcIntersect1`, and head to head (the peer's time / sidx's):\n\n"
                "| rays | bvh8 single | bvh8 stream | tinybvh BVH8_CPU | Embree robust | bvh | bvh-sbvh | bvh v2 |"
                " tinybvh BuildHQ | bvh8 / BVH8_CPU | bvh / best binary peer | bvh-sbvh / best binary peer |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (auto &s : table) std::printf("%s\n", s.c_str());
    std::printf("\nMrays/s (median over rounds of the best pass, and of the median pass), and rays whose hit differs"
                " from sidx `bvh8`'s:\n\n| rays | tracer | Mrays/s best | Mrays/s median | hits differing |\n"
                "|---|---|---|---|---|\n");
    for (auto &s : detail) std::printf("%s\n", s.c_str());
    return 0;
}
