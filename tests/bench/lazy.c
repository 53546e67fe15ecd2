/* lazy.c — sidx-bench lazy: what a lazy build (sidx_build_options.lazy)
 * saves when the camera sees part of a scene.
 *
 * Per scene, eager and lazy in interleaved rounds, on one thread, in the
 * thread's CPU time (so other load on the machine does not count), two
 * kinds of frame, each from a build of its own:
 *   bounce       one PX x PX primary frame from the scene's camera
 *                (closest hits with the hit point) and one diffuse bounce
 *                from every hit (sidx_ray_spawn, a direction drawn on the
 *                hemisphere facing the camera): a path tracer's first pass;
 *   shadow       the same primary frame and one shadow ray per hit to a
 *                point light above the camera's target (sidx_ray_spawn_to,
 *                sidx_accel_occluded): what an interactive viewer shows
 *                first.  A shadow ray runs towards the light, so it
 *                enters far fewer of the unbuilt subtrees than a bounce.
 * For each kind: the first image (the build and one frame) and N frames
 * (the same build, then N frames from viewpoints spread around the scene,
 * the first one the camera's), the total.
 * Printed per scene: the medians over the rounds, their ratios lazy / eager,
 * the fraction built after the first image and after N frames (the
 * primitive references in built leaves over those plus the ones the
 * unbuilt subtrees hold: sidx_accel_stats), the build alone (eager, and
 * the lazy build's eager top), one pass over the triangles' boxes and
 * centroids (the floor of any build, lazy or not), and whether every hit
 * of the lazy runs equals the eager run's bit for bit (an FNV hash over t,
 * prim, u, v, normal, and each shadow ray's answer).
 *
 * Scenes: "stadium" (built-in stadium, detail 16384: the teapot among
 * ~100k triangles of stands, seen from beside the teapot) and
 * "heightfield:D" (2 D^2 triangles of terrain, seen from a low camera at
 * one edge); any other SCENE (file or built-in) is seen from outside its
 * box, as the test kit's primary rays, and "inside:FILE" (the mesh of FILE
 * seen from the middle of its box, a third of the way up, facing the
 * nearer of the two long walls: Sponza's atrium from inside).
 *
 * "city:N[:D]" is an aggregate of lazy instances instead
 * (sidx_aggregate_build_meshes): the N distinct buildings of
 * sidx_city_make (detail D, default 36: >= 10k triangles each), each
 * with its own BVH (--accel), all built at once (eager) or each the first
 * time a ray enters its box (lazy), seen from the city's street-level
 * camera, the frames looking around the street; shadow frames only, and
 * the instances built after the first image and after N frames.  An
 * instanced hit has no point for sidx_ray_spawn_to: its shadow ray starts
 * at o + t d, 1e-3 off the surface along the normal. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "bench.h"

typedef struct cam {
    sidx_vec3 eye, at, light; /* light: the shadow frames' point light */
    float fov;                /* vertical, radians */
    int look_around;          /* the frames turn the view about the eye (inside:), not the eye about the target */
} cam;

typedef struct frame_out {
    uint64_t hash;
    size_t hits, bounces;
    int nomem;
} frame_out;

static sidx_vec3 unit(sidx_vec3 v) { return sidx_v3_scale(v, 1.0f / sidx_v3_length(v)); }

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 0x100000001b3ull;
    return h;
}

static uint64_t hash_hit(uint64_t h, const sidx_hit *x)
{
    h = fnv(h, &x->t, sizeof x->t);
    h = fnv(h, &x->prim, sizeof x->prim);
    h = fnv(h, &x->u, sizeof x->u);
    h = fnv(h, &x->v, sizeof x->v);
    return fnv(h, &x->ng, sizeof x->ng);
}

/* One frame: px x px primary rays through the camera, closest hits with
 * their points, then one diffuse bounce (shadow = 0) or one shadow ray to
 * the light (shadow = 1) per hit. */
static void frame(const sidx_accel *a, const cam *c, uint32_t px, uint64_t seed, int shadow, frame_out *out)
{
    const sidx_vec3 fwd = unit(sidx_v3_sub(c->at, c->eye));
    sidx_vec3 right = sidx_v3_cross(fwd, sidx_v3(0, 1, 0));
    if (sidx_v3_length(right) < 1e-6f) right = sidx_v3(1, 0, 0);
    right = unit(right);
    const sidx_vec3 up = sidx_v3_cross(right, fwd);
    const float half = tanf(0.5f * c->fov);
    const sidx_query qp = {SIDX_QUERY_POINT | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    const sidx_query qb = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    tk_rng g;
    tk_rng_seed(&g, seed);
    for (uint32_t y = 0; y < px; ++y)
        for (uint32_t x = 0; x < px; ++x) {
            const float sx = (2.0f * ((float)x + 0.5f) / (float)px - 1.0f) * half;
            const float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)px) * half;
            const sidx_vec3 d = sidx_v3_add(fwd, sidx_v3_add(sidx_v3_scale(right, sx), sidx_v3_scale(up, sy)));
            sidx_ray r;
            sidx_hit h;
            if (sidx_ray_init(&r, c->eye, d, 0.0f, INFINITY) != SIDX_OK) continue;
            if (sidx_accel_intersect(a, &r, &qp, &h) != SIDX_OK) out->nomem = 1;
            out->hash = hash_hit(out->hash, &h);
            if (h.prim == SIDX_NO_HIT) continue;
            out->hits++;
            if (shadow) {
                sidx_ray sr;
                int blocked = 0;
                if (h.instance != SIDX_NO_HIT) {
                    /* an instanced hit: no point to spawn from (sidx/spawn.h) */
                    const sidx_vec3 p = sidx_v3_add(r.org, sidx_v3_scale(r.dir, h.t));
                    sidx_vec3 n = unit(h.ng);
                    if (sidx_v3_dot(n, r.dir) > 0.0f) n = sidx_v3_scale(n, -1.0f);
                    const sidx_vec3 so = sidx_v3_add(p, sidx_v3_scale(n, 1e-3f));
                    if (sidx_ray_init(&sr, so, sidx_v3_sub(c->light, so), 0.0f, 1.0f) != SIDX_OK) continue;
                } else if (sidx_ray_spawn_to(&h, c->light, &sr) != SIDX_OK) {
                    continue;
                }
                if (sidx_accel_occluded(a, &sr, NULL, &blocked) != SIDX_OK) out->nomem = 1;
                out->hash = fnv(out->hash, &blocked, sizeof blocked);
                out->bounces++;
                continue;
            }
            /* a direction on the hemisphere facing the camera */
            sidx_vec3 n = unit(h.ng);
            if (sidx_v3_dot(n, d) > 0.0f) n = sidx_v3_scale(n, -1.0f);
            sidx_vec3 b = tk_rng_sphere(&g);
            if (sidx_v3_dot(b, n) < 0.0f) b = sidx_v3_scale(b, -1.0f);
            sidx_ray br;
            sidx_hit bh;
            if (sidx_ray_spawn(&h, b, &br) != SIDX_OK) continue;
            if (sidx_accel_intersect(a, &br, &qb, &bh) != SIDX_OK) out->nomem = 1;
            out->hash = hash_hit(out->hash, &bh);
            out->bounces++;
        }
}

/* Viewpoint k of n: the camera's eye turned about the vertical axis
 * through its target by 2 pi k / n; inside a scene, the target turned
 * about the eye (the camera looks around the room). */
static cam turned(const cam *c, uint32_t k, uint32_t n)
{
    const float phi = 6.28318531f * (float)k / (float)n, cs = cosf(phi), sn = sinf(phi);
    if (c->look_around) {
        const sidx_vec3 rel = sidx_v3_sub(c->at, c->eye);
        cam o = *c;
        o.at = sidx_v3_add(c->eye, sidx_v3(cs * rel.x + sn * rel.z, rel.y, -sn * rel.x + cs * rel.z));
        return o;
    }
    const sidx_vec3 rel = sidx_v3_sub(c->eye, c->at), lrel = sidx_v3_sub(c->light, c->at);
    cam o = *c;
    o.eye = sidx_v3_add(c->at, sidx_v3(cs * rel.x + sn * rel.z, rel.y, -sn * rel.x + cs * rel.z));
    o.light = sidx_v3_add(c->at, sidx_v3(cs * lrel.x + sn * lrel.z, lrel.y, -sn * lrel.x + cs * lrel.z));
    return o;
}

typedef struct run_out {
    double build_ms, first_ms, total_ms, built_first, built_total;
    uint64_t hash;
    size_t hits, bounces;
    int nomem;
} run_out;

static double built_fraction(const sidx_accel *a)
{
    sidx_accel_stats s;
    sidx_accel_stats_get(a, &s);
    /* prim_refs: the references in built leaves; unbuilt_prims: those the
     * unbuilt subtrees hold, as deferred (sidx/accel.h) */
    const double all = (double)s.prim_refs + (double)s.unbuilt_prims;
    return all > 0.0 ? (double)s.prim_refs / all : 1.0;
}

static int run_once(const char *accel, const sidx_mesh *m, uint32_t lazy, const cam *c, uint32_t px, uint32_t frames,
                    int shadow, run_out *o)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.lazy = lazy;
    sidx_accel *a = NULL;
    sidx_error err;
    memset(o, 0, sizeof *o);
    const double t0 = tk_thread_cpu_ms();
    if (sidx_accel_build(accel, m, &bo, &a, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench lazy: building %s: %s\n", accel, err.message);
        return 0;
    }
    o->build_ms = tk_thread_cpu_ms() - t0;
    frame_out f = {0xcbf29ce484222325ull, 0, 0, 0};
    frame(a, c, px, 1, shadow, &f);
    o->first_ms = tk_thread_cpu_ms() - t0;
    o->built_first = built_fraction(a);
    for (uint32_t k = 1; k < frames; ++k) {
        const cam ck = turned(c, k, frames);
        frame(a, &ck, px, 1 + k, shadow, &f);
    }
    o->total_ms = tk_thread_cpu_ms() - t0;
    o->built_total = built_fraction(a);
    o->hash = f.hash;
    o->hits = f.hits;
    o->bounces = f.bounces;
    o->nomem = f.nomem;
    sidx_accel_destroy(a);
    return 1;
}

/* One city run: the aggregate of the city's instances (each a structure
 * `accel`), built eager or lazy, then the shadow frames.  built_first /
 * built_total: the instances whose structure is built. */
static int run_city(const char *accel, const sidx_city *city, int lazy, const cam *c, uint32_t px, uint32_t frames,
                    run_out *o)
{
    sidx_build_options bo, child;
    memset(&bo, 0, sizeof bo);
    memset(&child, 0, sizeof child);
    bo.lazy = lazy ? 1u : 0u;
    for (uint32_t i = 0; i < city->n; ++i) {
        city->instances[i].accel = accel;
        city->instances[i].opt = &child;
    }
    sidx_accel *a = NULL;
    sidx_error err;
    memset(o, 0, sizeof *o);
    const double t0 = tk_thread_cpu_ms();
    if (sidx_aggregate_build_meshes(city->instances, city->n, &bo, &a, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench lazy: building the city: %s\n", err.message);
        return 0;
    }
    frame_out f = {0xcbf29ce484222325ull, 0, 0, 0};
    frame(a, c, px, 1, 1, &f);
    o->first_ms = tk_thread_cpu_ms() - t0;
    sidx_aggregate_info in;
    sidx_aggregate_info_get(a, &in);
    o->built_first = in.built_instances;
    for (uint32_t k = 1; k < frames; ++k) {
        const cam ck = turned(c, k, frames);
        frame(a, &ck, px, 1 + k, 1, &f);
    }
    o->total_ms = tk_thread_cpu_ms() - t0;
    sidx_aggregate_info_get(a, &in);
    o->built_total = in.built_instances;
    o->hash = f.hash;
    o->hits = f.hits;
    o->bounces = f.bounces;
    o->nomem = f.nomem;
    sidx_accel_destroy(a);
    return 1;
}

/* The floor of any build, lazy or not: one pass over the n triangles for
 * their boxes and centroids (what sidx__prim_boxes does first in every
 * build), into arrays of the bench's own; thread CPU ms, or -1 when
 * memory runs out. */
static double box_pass_ms(const sidx_mesh *m)
{
    sidx_aabb *box = malloc((size_t)m->num_triangles * sizeof *box);
    sidx_vec3 *cen = malloc((size_t)m->num_triangles * sizeof *cen);
    double ms = -1.0;
    if (box && cen) {
        const double t0 = tk_thread_cpu_ms();
        for (uint32_t i = 0; i < m->num_triangles; ++i) {
            sidx_aabb b = sidx_aabb_empty();
            for (int k = 0; k < 3; ++k) b = sidx_aabb_grow(b, sidx_mesh_vertex(m, i, k));
            box[i] = b;
            cen[i] = sidx_aabb_centroid(b);
        }
        ms = tk_thread_cpu_ms() - t0;
        /* read them back, so that the pass is not optimised away */
        volatile float sink = box[m->num_triangles / 2].min.x + cen[m->num_triangles / 3].y;
        (void)sink;
    }
    free(box);
    free(cen);
    return ms;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The shadow frames' light: above the camera's target, three times the
 * camera's distance up, so that it lights what the camera sees. */
static void place_light(cam *c)
{
    const float dist = sidx_v3_length(sidx_v3_sub(c->eye, c->at));
    c->light = sidx_v3_add(c->at, sidx_v3(0.25f * dist, 3.0f * dist, 0.25f * dist));
}

/* The scene and its camera. */
static int open_scene(const char *spec, sidx_mesh *m, cam *c)
{
    sidx_error err;
    memset(m, 0, sizeof *m);
    memset(c, 0, sizeof *c);
    c->fov = 0.7f;
    if (!strcmp(spec, "stadium")) {
        if (sidx_scene_make("stadium", 16384, m, &err) != SIDX_OK) goto fail;
        /* beside the teapot, looking at it: the teapot, the floor, a slice of the stands */
        c->eye = sidx_v3(0.9f, 0.35f, 0.9f);
        c->at = sidx_v3(0.0f, 0.2f, 0.0f);
        place_light(c);
        return 1;
    }
    if (!strncmp(spec, "heightfield:", 12)) {
        if (sidx_scene_open(spec, m, &err) != SIDX_OK) goto fail;
        /* low over one edge, looking along the terrain */
        c->eye = sidx_v3(0.0f, 0.12f, 1.05f);
        c->at = sidx_v3(0.0f, 0.0f, 0.6f);
        place_light(c);
        return 1;
    }
    if (!strncmp(spec, "inside:", 7)) {
        if (sidx_scene_open(spec + 7, m, &err) != SIDX_OK) goto fail;
        const sidx_aabb b = sidx_mesh_bounds(m);
        const sidx_vec3 ctr = sidx_aabb_centroid(b), e = sidx_aabb_extent(b);
        /* the middle of the box, a third of the way up; the walls along
         * the longer horizontal axis are the long ones: face one of them */
        c->eye = sidx_v3(ctr.x, b.min.y + e.y / 3.0f, ctr.z);
        c->at = e.x >= e.z ? sidx_v3(ctr.x, c->eye.y, b.min.z) : sidx_v3(b.min.x, c->eye.y, ctr.z);
        /* the light high in the box above the camera (a point inside an
         * open atrium), not three camera distances up */
        c->light = sidx_v3(ctr.x, b.min.y + 0.9f * e.y, ctr.z);
        c->look_around = 1;
        return 1;
    }
    if (sidx_scene_open(spec, m, &err) != SIDX_OK) goto fail;
    const sidx_aabb b = sidx_mesh_bounds(m);
    const sidx_vec3 ctr = sidx_aabb_centroid(b), e = sidx_aabb_extent(b);
    const float r = sidx_v3_length(e);
    c->at = ctr;
    c->eye = sidx_v3_add(ctr, sidx_v3(0.3f * r, 0.4f * r, 1.2f * r));
    place_light(c);
    return 1;
fail:
    fprintf(stderr, "sidx-bench lazy: scene %s: %s\n", spec, err.message);
    return 0;
}

/* city:N[:D]: eager against lazy instances, shadow frames; one JSON line. */
static int bench_city(const char *spec, const char *accel, uint32_t px, uint32_t frames, int rounds)
{
    char *end;
    const unsigned long n = strtoul(spec + 5, &end, 10);
    unsigned long d = 0;
    if (*end == ':') d = strtoul(end + 1, &end, 10);
    if (*end || n < 1 || n > 65536 || d > 256) {
        fprintf(stderr, "sidx-bench lazy: '%s': city:N[:D] wants N in 1..65536 and D in 1..256\n", spec);
        return BENCH_USAGE;
    }
    sidx_city city;
    sidx_error err;
    if (sidx_city_make((uint32_t)n, (uint32_t)d, &city, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench lazy: %s: %s\n", spec, err.message);
        return BENCH_FAIL;
    }
    uint64_t tris = 0;
    for (uint32_t i = 0; i < city.n; ++i) tris += city.meshes[i].num_triangles;
    cam c;
    memset(&c, 0, sizeof c);
    c.fov = 0.9f;
    c.eye = city.eye;
    c.at = city.at;
    c.light = city.light;
    c.look_around = 1;
    static double first[2][99], total[2][99];
    run_out last[2];
    memset(last, 0, sizeof last);
    int same = 1, nomem = 0;
    for (int r = 0; r < rounds; ++r) {
        for (int k = 0; k < 2; ++k) {
            const int is_lazy = (k + r) % 2;
            run_out o;
            if (!run_city(accel, &city, is_lazy, &c, px, frames, &o)) {
                sidx_city_free(&city);
                return BENCH_FAIL;
            }
            nomem |= o.nomem;
            first[is_lazy][r] = o.first_ms;
            total[is_lazy][r] = o.total_ms;
            last[is_lazy] = o;
        }
        same &= last[0].hash == last[1].hash;
    }
    const double ef = median(first[0], rounds), lf = median(first[1], rounds);
    const double et = median(total[0], rounds), lt = median(total[1], rounds);
    printf("{\"scene\":\"%s\",\"accel\":\"%s\",\"instances\":%u,\"tris\":%llu,\"size\":%u,\"frames\":%u,"
           "\"rounds\":%d,\"hits\":%zu,\"shadow_rays\":%zu,"
           "\"shadow_eager_first_ms\":%.1f,\"shadow_lazy_first_ms\":%.1f,\"shadow_first_ratio\":%.3f,"
           "\"shadow_eager_total_ms\":%.1f,\"shadow_lazy_total_ms\":%.1f,\"shadow_total_ratio\":%.3f,"
           "\"instances_built_first\":%.0f,\"instances_built_total\":%.0f,\"hits_identical\":%s}\n",
           spec, accel, city.n, (unsigned long long)tris, px, frames, rounds, last[1].hits, last[1].bounces, ef, lf,
           lf / ef, et, lt, lt / et, last[1].built_first, last[1].built_total, same && !nomem ? "true" : "false");
    fflush(stdout);
    sidx_city_free(&city);
    return same && !nomem ? BENCH_OK : BENCH_FAIL;
}

static void lazy_usage(FILE *f)
{
    fprintf(f, "usage: sidx-bench lazy [--accel NAME] [--lazy-size N] [--size PX] [--frames N] [--rounds N]\n"
               "                       [--lazy-only] [SCENE ...]\n"
               "Time to the first image (the build and one PX x PX primary frame) and the total over N\n"
               "frames from viewpoints around the scene, lazy build (opt.lazy) against eager, for two\n"
               "kinds of frame: one diffuse bounce per hit (first_ratio, total_ratio) and one shadow ray\n"
               "per hit to a point light, what an interactive viewer shows first (shadow_first_ratio,\n"
               "shadow_total_ratio); on one thread in thread CPU time, medians over interleaved rounds;\n"
               "the fraction of primitive references built after the first image and after N frames; the\n"
               "build alone (eager_build_ms, lazy_build_ms: the lazy top) and one pass over the triangles'\n"
               "boxes (box_pass_ms: the floor of any build); whether the hits agree bit for bit.\n"
               "SCENE: stadium, heightfield:D, inside:FILE (from the middle of the box facing a long\n"
               "wall: Sponza's atrium), or a mesh file / built-in scene (seen from outside its box), or\n"
               "city:N[:D]: N buildings of D detail (default 36: >= 10k triangles each) as lazy\n"
               "instances against eager ones (an aggregate; shadow frames only; the instances built).\n"
               "Default: stadium heightfield:1024.\n"
               "  --accel NAME     a structure with lazy builds (default bvh)\n"
               "  --lazy-size N    opt.lazy (default 1: the library's default size)\n"
               "  --size PX        image side (default 512)\n"
               "  --frames N       frames of the second measure (default 16)\n"
               "  --rounds N       rounds (default 3)\n"
               "  --lazy-only      the lazy build's shadow runs only, each round's line, no ratio:\n"
               "                   what a profiler should see of the lazy first image\n"
               "Prints one JSON line per scene.  Exit status: 0 ok, 1 failure, 2 usage.\n");
}

int bench_cmd_lazy(int argc, char **argv)
{
    const char *accel = "bvh";
    uint32_t lazy = 1, px = 512, frames = 16;
    int rounds = 3, lazy_only = 0;
    const char *scenes[16];
    int ns = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            lazy_usage(stdout);
            return BENCH_OK;
        }
        if (!strcmp(a, "--lazy-only")) {
            lazy_only = 1;
            continue;
        }
        if (!strcmp(a, "--accel") || !strcmp(a, "--lazy-size") || !strcmp(a, "--size") || !strcmp(a, "--frames") ||
            !strcmp(a, "--rounds")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "sidx-bench lazy: %s needs a value\n", a);
                return BENCH_USAGE;
            }
            const char *v = argv[++i];
            if (!strcmp(a, "--accel")) {
                accel = v;
                continue;
            }
            char *end;
            const long x = strtol(v, &end, 10);
            if (*end || end == v || x < 1 || x > 1000000) {
                fprintf(stderr, "sidx-bench lazy: %s wants a whole number from 1 to 1000000, not '%s'\n", a, v);
                return BENCH_USAGE;
            }
            if (!strcmp(a, "--lazy-size")) lazy = (uint32_t)x;
            else if (!strcmp(a, "--size")) px = (uint32_t)x;
            else if (!strcmp(a, "--frames")) frames = (uint32_t)x;
            else rounds = x > 99 ? 99 : (int)x;
            continue;
        }
        if (a[0] == '-') {
            fprintf(stderr, "sidx-bench lazy: unknown option '%s'\n", a);
            lazy_usage(stderr);
            return BENCH_USAGE;
        }
        if (ns == 16) {
            fprintf(stderr, "sidx-bench lazy: at most 16 scenes\n");
            return BENCH_USAGE;
        }
        scenes[ns++] = a;
    }
    if (!sidx_accel_is_registered(accel)) {
        fprintf(stderr, "sidx-bench lazy: no structure named '%s'\n", accel);
        return BENCH_USAGE;
    }
    if (ns == 0) {
        scenes[ns++] = "stadium";
        scenes[ns++] = "heightfield:1024";
    }
    for (int s = 0; s < ns; ++s) {
        if (!strncmp(scenes[s], "city:", 5) && lazy_only) {
            fprintf(stderr, "sidx-bench lazy: --lazy-only takes no city\n");
            return BENCH_USAGE;
        }
        if (!strncmp(scenes[s], "city:", 5)) {
            const int rc = bench_city(scenes[s], accel, px, frames, rounds);
            if (rc != BENCH_OK) return rc;
            continue;
        }
        sidx_mesh m;
        cam c;
        if (!open_scene(scenes[s], &m, &c)) return BENCH_FAIL;
        if (lazy_only) { /* for a profiler: the lazy shadow runs alone, no ratio */
            for (int r = 0; r < rounds; ++r) {
                run_out o;
                if (!run_once(accel, &m, lazy, &c, px, frames, 1, &o)) {
                    sidx_mesh_free(&m);
                    return BENCH_FAIL;
                }
                printf("{\"scene\":\"%s\",\"accel\":\"%s\",\"tris\":%u,\"size\":%u,\"frames\":%u,\"round\":%d,"
                       "\"shadow_lazy_build_ms\":%.1f,\"shadow_lazy_first_ms\":%.1f,\"shadow_lazy_total_ms\":%.1f,"
                       "\"shadow_built_first\":%.4f,\"shadow_built_total\":%.4f}\n",
                       scenes[s], accel, m.num_triangles, px, frames, r, o.build_ms, o.first_ms, o.total_ms,
                       o.built_first, o.built_total);
                fflush(stdout);
            }
            sidx_mesh_free(&m);
            continue;
        }
        /* [kind][eager, lazy][round]: kind 0 bounce, 1 shadow */
        static double first[2][2][99], total[2][2][99], built[2][99], boxes[99];
        run_out last[2][2];
        memset(last, 0, sizeof last);
        int same = 1, nomem = 0;
        for (int r = 0; r < rounds; ++r) {
            boxes[r] = box_pass_ms(&m);
            for (int kind = 0; kind < 2; ++kind) {
                /* interleaved, the order swapped each round */
                for (int k = 0; k < 2; ++k) {
                    const int is_lazy = (k + r) % 2;
                    run_out o;
                    if (!run_once(accel, &m, is_lazy ? lazy : 0, &c, px, frames, kind, &o)) {
                        sidx_mesh_free(&m);
                        return BENCH_FAIL;
                    }
                    nomem |= o.nomem;
                    first[kind][is_lazy][r] = o.first_ms;
                    if (kind == 1) built[is_lazy][r] = o.build_ms;
                    total[kind][is_lazy][r] = o.total_ms;
                    last[kind][is_lazy] = o;
                }
                same &= last[kind][0].hash == last[kind][1].hash;
            }
        }
        double mf[2][2], mt[2][2];
        for (int kind = 0; kind < 2; ++kind)
            for (int z = 0; z < 2; ++z) {
                mf[kind][z] = median(first[kind][z], rounds);
                mt[kind][z] = median(total[kind][z], rounds);
            }
        const run_out *lb = &last[0][1], *ls = &last[1][1];
        /* the build alone (the shadow runs'): the lazy one is its eager top */
        const double eb = median(built[0], rounds), lzb = median(built[1], rounds), bp = median(boxes, rounds);
        printf("{\"scene\":\"%s\",\"accel\":\"%s\",\"tris\":%u,\"size\":%u,\"frames\":%u,\"rounds\":%d,"
               "\"hits\":%zu,\"bounces\":%zu,\"shadow_rays\":%zu,"
               "\"eager_first_ms\":%.1f,\"lazy_first_ms\":%.1f,\"first_ratio\":%.3f,"
               "\"eager_total_ms\":%.1f,\"lazy_total_ms\":%.1f,\"total_ratio\":%.3f,"
               "\"built_first\":%.4f,\"built_total\":%.4f,"
               "\"shadow_eager_first_ms\":%.1f,\"shadow_lazy_first_ms\":%.1f,\"shadow_first_ratio\":%.3f,"
               "\"shadow_eager_total_ms\":%.1f,\"shadow_lazy_total_ms\":%.1f,\"shadow_total_ratio\":%.3f,"
               "\"shadow_built_first\":%.4f,\"shadow_built_total\":%.4f,"
               "\"eager_build_ms\":%.1f,\"lazy_build_ms\":%.1f,\"box_pass_ms\":%.1f,\"hits_identical\":%s}\n",
               scenes[s], accel, m.num_triangles, px, frames, rounds, lb->hits, lb->bounces, ls->bounces, mf[0][0],
               mf[0][1], mf[0][1] / mf[0][0], mt[0][0], mt[0][1], mt[0][1] / mt[0][0], lb->built_first, lb->built_total,
               mf[1][0], mf[1][1], mf[1][1] / mf[1][0], mt[1][0], mt[1][1], mt[1][1] / mt[1][0], ls->built_first,
               ls->built_total, eb, lzb, bp, same && !nomem ? "true" : "false");
        fflush(stdout);
        sidx_mesh_free(&m);
        if (!same || nomem) return BENCH_FAIL;
    }
    return BENCH_OK;
}
