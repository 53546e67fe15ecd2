/* 24_spawning_rays.c — spawning secondary rays: the epsilon hack against
 * error bounds.
 *
 * Slides (deck 000 / 001, shadow and secondary rays): "be careful about
 * the numerical rounding errors".  A shadow or bounce ray starts at a hit
 * point that is itself rounded.  The usual answer is a constant: start the
 * new ray at tmin = 1e-3.  The constant has a unit, the scene has none:
 *   - on a small model (a millimetre-sized part, or the box scaled by
 *     1e-6) 1e-3 is larger than the gaps between surfaces, so the ray
 *     skips the occluder right next to its start (light leaks);
 *   - a million units from the origin the float hit point is off by more
 *     than 1e-3 (one ulp of 1e6 is 0.0625), so the ray starts behind the
 *     surface it left and hits it again ("shadow acne").
 * sidx answers with the hit point's own error bound (SIDX_QUERY_POINT,
 * Pharr, Jakob, Humphreys, "Physically Based Rendering" 3rd ed. §3.9):
 * the origin is moved off the surface along the normal by exactly as much
 * as the point may be wrong, then rounded away (sidx_ray_spawn,
 * sidx_ray_spawn_to; sidx/spawn.h has the derivation).
 *
 * What it shows, on the Cornell box (blocks resting on the floor) as it
 * is, scaled by 1e-3 and 1e-6 and moved 1e6 from the origin:
 *   1. one floor hit 1e6 from the origin: the float point, its bound, how
 *      far the hack's and the spawned origin lie from the exact plane, and
 *      where a bounce ray from each goes;
 *   2. per scale and method (tmin = 1e-3, tmin = 1e-4, spawned): bounce
 *      rays that hit the triangle they left, shadow rays that hit the
 *      triangle they left, and shadow rays that miss an occluder the
 *      double-precision reference finds between the point and the light.
 *
 * Read:  lib/spawn.c, sidx_ray_spawn
 * Run:   build/lessons/24_spawning_rays [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default cornell); the
 *        light is put at 90% of the box height above its centre, the
 *        camera in front of the box (-z)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include "sidx/sidx.h"
#include "lesson.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 24_spawning_rays [--help] [SCENE]\n"
               "\n"
               "Secondary rays from hit points: the tmin = 1e-3 hack against origins offset by the\n"
               "hit point's error bound, on the scene at unit scale, x1e-3, x1e-6 and 1e6 away.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: cornell)\n");
}

/* The scene moved: positions * scale + offset (in double, then rounded). */
static sidx_mesh transformed(const lesson_args *args, const sidx_mesh *m, double scale, double offset)
{
    float *xyz = malloc(3 * sizeof(float) * (m->num_vertices ? m->num_vertices : 1));
    if (!xyz) lesson_fail(args, "out of memory");
    for (uint32_t i = 0; i < m->num_vertices; ++i) {
        xyz[3 * i + 0] = (float)(m->positions[i].x * scale + offset);
        xyz[3 * i + 1] = (float)(m->positions[i].y * scale + offset);
        xyz[3 * i + 2] = (float)(m->positions[i].z * scale + offset);
    }
    sidx_mesh out;
    sidx_error err = {0};
    if (sidx_mesh_from_arrays(&out, xyz, m->num_vertices, m->indices, m->num_triangles, &err) != SIDX_OK)
        lesson_fail(args, err.message);
    free(xyz);
    return out;
}

/* ---- the double-precision reference ---- */

typedef struct dv3 { double x, y, z; } dv3;
static dv3 dv(sidx_vec3 a) { return (dv3){a.x, a.y, a.z}; }
static dv3 dsub(dv3 a, dv3 b) { return (dv3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static double ddot(dv3 a, dv3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static dv3 dcross(dv3 a, dv3 b) { return (dv3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

/* The exact hit point: the hit's u, v on the float vertices. */
static dv3 exact_point(const sidx_mesh *m, const sidx_hit *h)
{
    const dv3 a = dv(sidx_mesh_vertex(m, h->prim, 0)), b = dv(sidx_mesh_vertex(m, h->prim, 1)),
              c = dv(sidx_mesh_vertex(m, h->prim, 2));
    const double w = 1.0 - (double)h->u - (double)h->v;
    return (dv3){w * a.x + h->u * b.x + h->v * c.x, w * a.y + h->u * b.y + h->v * c.y,
                 w * a.z + h->u * b.z + h->v * c.z};
}

/* Signed distance of x from the plane of triangle prim (exact normal). */
static double plane_distance(const sidx_mesh *m, uint32_t prim, dv3 x)
{
    const dv3 a = dv(sidx_mesh_vertex(m, prim, 0));
    const dv3 n = dcross(dsub(dv(sidx_mesh_vertex(m, prim, 1)), a), dsub(dv(sidx_mesh_vertex(m, prim, 2)), a));
    return ddot(dsub(x, a), n) / sqrt(ddot(n, n));
}

/* The nearest triangle other than skip along p + s·w (w unit), at a
 * distance s in (lo, hi); +inf if none.  Möller–Trumbore in double. */
static double ref_nearest(const sidx_mesh *m, dv3 p, dv3 w, uint32_t skip, double lo, double hi)
{
    double best = INFINITY;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        if (i == skip) continue;
        const dv3 a = dv(sidx_mesh_vertex(m, i, 0));
        const dv3 e1 = dsub(dv(sidx_mesh_vertex(m, i, 1)), a), e2 = dsub(dv(sidx_mesh_vertex(m, i, 2)), a);
        const dv3 pv = dcross(w, e2);
        const double det = ddot(e1, pv);
        if (det == 0.0) continue;
        const dv3 tv = dsub(p, a);
        const double u = ddot(tv, pv) / det;
        if (u < 0.0 || u > 1.0) continue;
        const dv3 qv = dcross(tv, e1);
        const double v = ddot(w, qv) / det;
        if (v < 0.0 || u + v > 1.0) continue;
        const double s = ddot(e2, qv) / det;
        if (s > lo && s < hi && s < best) best = s;
    }
    return best;
}

static dv3 dunit(dv3 a)
{
    const double l = sqrt(ddot(a, a));
    return (dv3){a.x / l, a.y / l, a.z / l};
}

enum { HACK3, HACK4, SPAWN, METHODS };
static const char *const method_name[METHODS] = {"tmin = 1e-3", "tmin = 1e-4", "spawned"};

typedef struct tally { long bounces, bounce_self, leaks, shadows, shadow_self, missed; } tally;

static sidx_vec3 unit(sidx_vec3 a) { return sidx_v3_scale(a, 1.0f / sidx_v3_length(a)); }

/* A bounce direction on the side the primary ray came from (cosine-ish:
 * a random unit vector flipped to that side). */
static sidx_vec3 bounce_dir(const sidx_hit *h, sidx_vec3 incoming, uint32_t *seed)
{
    const float z = 2 * lesson_random(seed) - 1, ang = 6.2831853f * lesson_random(seed), s = sqrtf(1 - z * z);
    sidx_vec3 w = sidx_v3(s * cosf(ang), s * sinf(ang), z);
    if (sidx_v3_dot(w, h->ng) * sidx_v3_dot(incoming, h->ng) > 0.0f) w = sidx_v3_scale(w, -1.0f);
    return w;
}

/* Every method on one version of the scene. */
static void run_scene(const lesson_args *args, const sidx_mesh *m, int nx, int ny, tally t[METHODS])
{
    sidx_accel *a = NULL;
    sidx_error err = {0};
    if (sidx_accel_build("bvh", m, NULL, &a, &err) != SIDX_OK) lesson_fail(args, err.message);
    const sidx_aabb box = sidx_mesh_bounds(m);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const sidx_vec3 light = sidx_v3(ctr.x + 0.03f * ext.x, box.min.y + 0.9f * ext.y, ctr.z + 0.02f * ext.z);
    const lesson_camera cam = lesson_camera_at(box, 0.0f, 0.0f, -1.0f);
    const sidx_query qp = {SIDX_QUERY_POINT, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    uint32_t seed = 24u;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) {
            sidx_ray r;
            const float u = (2.0f * ((float)x + 0.5f) / (float)nx - 1.0f) * 0.45f;
            const float v = (1.0f - 2.0f * ((float)y + 0.5f) / (float)ny) * 0.45f;
            if (sidx_ray_init(&r, cam.eye, lesson_camera_dir(&cam, u, v), 0.0f, INFINITY) != SIDX_OK) continue;
            sidx_hit h;
            sidx_accel_intersect(a, &r, &qp, &h);
            if (h.prim == SIDX_NO_HIT) continue;
            const sidx_vec3 w = bounce_dir(&h, r.dir, &seed);
            const sidx_vec3 hp = sidx_ray_at(&r, h.t); /* the hack's point */
            const double band = 4.0 * ((double)h.p_err.x + h.p_err.y + h.p_err.z);
            /* the reference follows the very rays traced, from their own
             * origin: what lies beyond the origin and short of the light
             * (ignoring the triangle left, and anything closer to the
             * origin than 1e-3 of the point's error bound: a hit point on a
             * shared edge starts on the neighbour too) */
            const double lo = 1e-3 * band;
            for (int k = 0; k < METHODS; ++k) {
                sidx_ray b, s;
                int shadow_ray = 1;
                if (k == SPAWN) {
                    if (sidx_ray_spawn(&h, w, &b) != SIDX_OK || sidx_ray_spawn_to(&h, light, &s) != SIDX_OK) continue;
                } else {
                    const float eps = k == HACK3 ? 1e-3f : 1e-4f;
                    const sidx_vec3 tl = sidx_v3_sub(light, hp);
                    const float dist = sidx_v3_length(tl);
                    sidx_ray_init(&b, hp, w, eps, INFINITY);
                    /* a light closer than 2 eps: no ray is left to trace, the point counts as lit */
                    shadow_ray = dist > 2 * eps && sidx_ray_init(&s, hp, unit(tl), eps, dist - eps) == SIDX_OK;
                }
                sidx_hit g;
                sidx_accel_intersect(a, &b, NULL, &g);
                t[k].bounces++;
                t[k].bounce_self += g.prim == h.prim;
                t[k].leaks += g.prim == SIDX_NO_HIT && ref_nearest(m, dv(b.org), dv(w), h.prim, lo, INFINITY) < INFINITY;
                const dv3 to_light = dsub(dv(light), dv(b.org));
                const double len = sqrt(ddot(to_light, to_light));
                const int blocked = ref_nearest(m, dv(b.org), dunit(to_light), h.prim, lo, len * (1.0 - 2e-4)) < INFINITY;
                g = sidx_hit_none();
                if (shadow_ray) sidx_accel_intersect(a, &s, NULL, &g);
                t[k].shadows++;
                t[k].shadow_self += g.prim == h.prim;
                t[k].missed += blocked && g.prim == SIDX_NO_HIT;
            }
        }
    sidx_accel_destroy(a);
}

int main(int argc, char **argv)
{
    lesson_args args = {.name = "24_spawning_rays",
                        .usage = usage,
                        .scene = "cornell",
                        .refused = "the lesson compares ways to start secondary rays; its BVH only finds hits"};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");
    sidx_mesh base = lesson_open_scene(&args);
    sidx_error err = {0};

    /* ---- 1. one hit, 1e6 from the origin ---- */
    {
        sidx_mesh far = transformed(&args, &base, 1.0, 1e6);
        sidx_accel *a = NULL;
        if (sidx_accel_build("bvh", &far, NULL, &a, &err) != SIDX_OK) lesson_fail(&args, err.message);
        const sidx_aabb box = sidx_mesh_bounds(&far);
        const lesson_camera cam = lesson_camera_at(box, 0.0f, 0.0f, -1.0f);
        const sidx_query qp = {SIDX_QUERY_POINT, SIDX_TRAVERSE_DEFAULT, NULL, 0};
        printf("== 1. '%s' moved 1e6 from the origin (one ulp of 1e6 is %g): a hit seen from the camera\n", args.scene,
               (double)(nextafterf(1e6f, INFINITY) - 1e6f));
        sidx_ray r;
        sidx_hit h = sidx_hit_none();
        sidx_vec3 w = sidx_v3(0, 1, 0);
        /* the first camera ray whose hit, left with tmin = 1e-3, is hit again */
        uint32_t seed = 5u;
        for (int i = 0; i < 1024; ++i) {
            const float u = ((float)(i % 32) / 31.0f - 0.5f) * 0.9f, v = (0.5f - (float)(i / 32) / 31.0f) * 0.9f;
            sidx_ray_init(&r, cam.eye, lesson_camera_dir(&cam, u, v), 0.0f, INFINITY);
            sidx_accel_intersect(a, &r, &qp, &h);
            if (h.prim == SIDX_NO_HIT) continue;
            w = bounce_dir(&h, r.dir, &seed);
            sidx_ray b;
            sidx_hit g;
            sidx_ray_init(&b, sidx_ray_at(&r, h.t), w, 1e-3f, INFINITY);
            sidx_accel_intersect(a, &b, NULL, &g);
            /* ... and whose spawned bounce starts clear of everything (1e6 away
             * the bound is ~9 ulps, and an offset that large can reach a
             * neighbouring wall in a corner) */
            sidx_hit g2;
            const double band = 4.0 * ((double)h.p_err.x + h.p_err.y + h.p_err.z);
            if (g.prim == h.prim && sidx_ray_spawn(&h, w, &b) == SIDX_OK &&
                sidx_accel_intersect(a, &b, NULL, &g2) == SIDX_OK && (g2.prim == SIDX_NO_HIT || g2.t > band))
                break;
            h = sidx_hit_none();
        }
        if (h.prim != SIDX_NO_HIT) {
            const dv3 P = exact_point(&far, &h);
            const sidx_vec3 hp = sidx_ray_at(&r, h.t);
            printf("  triangle %u, normal (%g, %g, %g)\n", h.prim, h.ng.x, h.ng.y, h.ng.z);
            printf("  exact point           (%.4f, %.4f, %.4f)\n", P.x, P.y, P.z);
            printf("  o + t*d (the hack's)  (%.4f, %.4f, %.4f)   %+.4f from the plane\n", hp.x, hp.y, hp.z,
                   plane_distance(&far, h.prim, dv(hp)));
            printf("  hit.p (SIDX_QUERY_POINT) (%.4f, %.4f, %.4f), error bound hit.p_err (%.4f, %.4f, %.4f)\n",
                   h.p.x, h.p.y, h.p.z, h.p_err.x, h.p_err.y, h.p_err.z);
            sidx_ray b;
            sidx_hit g;
            for (int k = 0; k < METHODS; ++k) {
                if (k == SPAWN) sidx_ray_spawn(&h, w, &b);
                else sidx_ray_init(&b, hp, w, k == HACK3 ? 1e-3f : 1e-4f, INFINITY);
                sidx_accel_intersect(a, &b, NULL, &g);
                printf("  bounce, %-12s origin %+.4f from the plane: ", method_name[k],
                       plane_distance(&far, h.prim, dv(b.org)));
                if (g.prim == SIDX_NO_HIT) printf("leaves the scene\n");
                else printf("hits triangle %u at t = %g%s\n", g.prim, g.t, g.prim == h.prim ? "  <- the one it left" : "");
            }
        }
        sidx_accel_destroy(a);
        sidx_mesh_free(&far);
    }

    /* ---- 2. counts ---- */
    static const struct { const char *label; double scale, offset; } variants[] = {
        {"as loaded", 1.0, 0.0}, {"x 1e-3", 1e-3, 0.0}, {"x 1e-6", 1e-6, 0.0}, {"+ 1e6", 1.0, 1e6}};
    enum { NV = sizeof variants / sizeof variants[0] };
    /* the reference is brute force in double: fewer rays on big meshes */
    int side = base.num_triangles > 20000 ? 12 : 48;
    printf("\n== 2. %d camera rays per scene; from each hit a bounce ray and a shadow ray to a point light\n",
           side * side);
    printf("  (self: the ray hits the triangle it left; leaks: the bounce ray leaves the scene although\n"
           "  its own line, traced in double precision from its origin, meets a surface; missed: the\n"
           "  double-precision segment from the same origin to the light is blocked and the shadow ray\n"
           "  reports it clear.  What the hack skips is what lies within tmin of its origin.)\n\n");
    printf("  %-10s %-12s %8s %7s %7s %8s %7s %8s\n", "scene", "method", "bounces", "self", "leaks", "shadows",
           "self", "missed");
    tally all[NV][METHODS] = {{{0}}};
    for (int vi = 0; vi < NV; ++vi) {
        sidx_mesh m = transformed(&args, &base, variants[vi].scale, variants[vi].offset);
        run_scene(&args, &m, side, side, all[vi]);
        for (int k = 0; k < METHODS; ++k) {
            const tally *t = &all[vi][k];
            printf("  %-10s %-12s %8ld %7ld %7ld %8ld %7ld %8ld\n", k == 0 ? variants[vi].label : "", method_name[k],
                   t->bounces, t->bounce_self, t->leaks, t->shadows, t->shadow_self, t->missed);
        }
        sidx_mesh_free(&m);
    }
    long spawn_self = 0, spawn_missed = 0;
    for (int vi = 0; vi < NV; ++vi) {
        spawn_self += all[vi][SPAWN].bounce_self + all[vi][SPAWN].shadow_self;
        spawn_missed += all[vi][SPAWN].missed + all[vi][SPAWN].leaks;
    }
    const tally *far3 = &all[3][HACK3], *tiny3 = &all[2][HACK3];
    printf("\n  The constant fails both ways: 1e6 away, %ld of %ld bounce rays and %ld of %ld shadow rays\n"
           "  with tmin = 1e-3 hit the triangle they left; at 1e-6 scale %ld bounce rays leak out and %ld\n"
           "  shadow rays miss their occluder.  The spawned rays: %ld self-intersections and %ld leaks or\n"
           "  missed occluders at every scale.\n",
           far3->bounce_self, far3->bounces, far3->shadow_self, far3->shadows, tiny3->leaks, tiny3->missed,
           spawn_self, spawn_missed);
    sidx_mesh_free(&base);
    lesson_check("spawn_self_intersections", spawn_self);
    lesson_check("spawn_missed_occluders", spawn_missed);
    lesson_check("hack_hits_itself_far_away", far3->bounce_self + far3->shadow_self > 0);
    lesson_check("hack_misses_when_small", tiny3->missed + tiny3->leaks > 0);
    return 0;
}
