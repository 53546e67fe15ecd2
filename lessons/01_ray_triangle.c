/* 01_ray_triangle.c — ray–plane and ray–triangle intersection, three ways.
 *
 * Slides (deck 001, "Spatial Data Structures"): "Ray-Plane Intersection",
 * "Ray-Triangle Intersection", "Moller-Trumbore Algorithm" (with its two
 * questions "What if D=0? What does it mean?" and "Q: What if t is
 * negative?") and "Moller-Trumbore Visualized".
 *
 * What it shows:
 *   1. one ray and one triangle worked through by hand with all three
 *      methods the library has — the deck's two-step method (ray–plane,
 *      then barycentric test), Möller–Trumbore by Cramer's rule exactly as
 *      on the slide, and the watertight test (Woop, Benthin, Wald 2013) —
 *      every intermediate number printed, then the library's own answer
 *      through the printer sink;
 *   2. the awkward cases: a ray on an edge, through a vertex, parallel to
 *      the plane (D = 0), lying in the plane, a degenerate triangle, and a
 *      triangle behind the origin (t < 0) — each question answered by
 *      running it;
 *   3. why "be careful about the numerical rounding errors": rays aimed at
 *      the shared edges and the shared vertex of a fan of triangles.  A
 *      ray that slips through between two triangles is a leak; the
 *      watertight test has none, Möller–Trumbore has some;
 *   4. the same leak count on a closed mesh, rays shot from inside it at
 *      its vertices and edges (SCENE, default icosphere).
 *
 * Read:  lib/intersect.c, sidx_intersect_triangle
 * Run:   build/lessons/01_ray_triangle [SCENE]
 *        SCENE = a built-in scene name ("icosphere", "teapot:2", ...) or an
 *        .obj/.ply file; it should be closed and contain its box centre.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include "sidx/sidx.h"
#include "lesson.h"

static const char *const method_label[SIDX_TRI_METHOD_COUNT] = {"watertight", "Moller-Trumbore", "two-step"};

static void usage(FILE *f)
{
    fprintf(f, "usage: 01_ray_triangle [--help] [SCENE]\n"
               "\n"
               "Ray-triangle intersection: worked numbers for one ray with the two-step method,\n"
               "Moller-Trumbore and the watertight test; edges, vertices, D = 0, t < 0; and the\n"
               "number of rays that leak between triangles sharing an edge.\n"
               "\n"
               "  SCENE   closed mesh for the last leak test: built-in name or .obj/.ply\n"
               "          (default: icosphere)\n");
}

/* xorshift32: the same numbers on every machine. */
static uint32_t rng_state = 0x9E3779B9u;
static float frand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return (float)(rng_state >> 8) / 16777216.0f;
}

static void pv(const char *name, sidx_vec3 v) { printf("    %-6s = (%g, %g, %g)\n", name, v.x, v.y, v.z); }

/* ---- 1. one ray, worked by hand --------------------------------------------------- */

/* The deck's two-step method: plane N·x = c, then is p inside? */
static void worked_two_step(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2)
{
    printf("\n  (a) two-step: ray-plane, then a point-in-triangle test\n");
    const sidx_vec3 e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0);
    const sidx_vec3 n = sidx_v3_cross(e1, e2);
    const float c = sidx_v3_dot(n, p0), nd = sidx_v3_dot(n, r->dir), no = sidx_v3_dot(n, r->org);
    pv("N=e1xe2", n);
    printf("    c = N.p0 = %g    N.o = %g    N.d = %g\n", c, no, nd);
    const float t = (c - no) / nd;
    const sidx_vec3 p = sidx_ray_at(r, t);
    printf("    t = (c - N.o) / (N.d) = (%g - %g) / %g = %g\n", c, no, nd, t);
    printf("    p = o + t d = (%g, %g, %g)\n", p.x, p.y, p.z);
    /* barycentric coordinates of p from the 2x2 system w = u e1 + v e2 */
    const sidx_vec3 w = sidx_v3_sub(p, p0);
    const float d00 = sidx_v3_dot(e1, e1), d01 = sidx_v3_dot(e1, e2), d11 = sidx_v3_dot(e2, e2);
    const float d20 = sidx_v3_dot(w, e1), d21 = sidx_v3_dot(w, e2), den = d00 * d11 - d01 * d01;
    const float u = (d11 * d20 - d01 * d21) / den, v = (d00 * d21 - d01 * d20) / den;
    printf("    p - p0 = u e1 + v e2  ->  u = %g, v = %g, 1-u-v = %g  -> %s\n", u, v, 1.0f - u - v,
           (u >= 0 && v >= 0 && u + v <= 1) ? "inside" : "outside");
}

/* The slide's Cramer's rule, term by term. */
static float moller_D(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2)
{
    const sidx_vec3 e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0);
    return sidx_v3_dot(sidx_v3_cross(e1, r->dir), e2);
}

static void worked_moller(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2)
{
    printf("\n  (b) Moller-Trumbore: o + t d = (1-u-v) p0 + u p1 + v p2, solved by Cramer's rule\n");
    const sidx_vec3 s = sidx_v3_sub(r->org, p0), e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0);
    pv("s", s);
    pv("e1", e1);
    pv("e2", e2);
    const sidx_vec3 e1xd = sidx_v3_cross(e1, r->dir), sxe2 = sidx_v3_cross(s, e2);
    const float D = sidx_v3_dot(e1xd, e2);
    printf("    D = (e1 x d).e2 = %g\n", D);
    const float u = -sidx_v3_dot(sxe2, r->dir) / D;
    const float v = sidx_v3_dot(e1xd, s) / D;
    const float t = -sidx_v3_dot(sxe2, e1) / D;
    printf("    u = -(s x e2).d / D = %g\n", u);
    printf("    v =  (e1 x d).s / D = %g\n", v);
    printf("    t = -(s x e2).e1 / D = %g\n", t);
    printf("    t >= 0, u >= 0, v >= 0, u+v <= 1 ?  %s\n", (t >= 0 && u >= 0 && v >= 0 && u + v <= 1) ? "yes: hit" : "no");
}

/* Woop et al.: move the origin to 0, permute so the ray's largest
 * component is z, shear so the ray is the +z axis, then 2D edge tests. */
static void worked_watertight(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2)
{
    printf("\n  (c) watertight: shear the ray onto the z axis, then three 2D edge functions\n");
    const char *xyz = "xyz";
    printf("    largest |d| component: %c -> kz = %c, kx = %c, ky = %c\n", xyz[r->kz], xyz[r->kz], xyz[r->kx],
           xyz[r->ky]);
    printf("    shear: Sx = -dx/dz = %g, Sy = -dy/dz = %g, Sz = 1/dz = %g\n", r->sx, r->sy, r->sz);
    const sidx_vec3 pts[3] = {p0, p1, p2};
    float X[3], Y[3], Z[3];
    for (int i = 0; i < 3; ++i) {
        const sidx_vec3 p = sidx_v3_sub(pts[i], r->org);
        const float x = sidx_v3_get(p, r->kx), y = sidx_v3_get(p, r->ky), z = sidx_v3_get(p, r->kz);
        X[i] = x - r->sx * z;
        Y[i] = y - r->sy * z;
        Z[i] = r->sz * z;
        printf("    p%d in ray space: (%g, %g, %g)\n", i, X[i], Y[i], Z[i]);
    }
    const float U = X[2] * Y[1] - Y[2] * X[1], V = X[0] * Y[2] - Y[0] * X[2], W = X[1] * Y[0] - Y[1] * X[0];
    printf("    edge functions U = %g, V = %g, W = %g  (all one sign -> the ray passes inside)\n", U, V, W);
    const float det = U + V + W, T = U * Z[0] + V * Z[1] + W * Z[2];
    printf("    det = U+V+W = %g, T = U z0 + V z1 + W z2 = %g\n", det, T);
    printf("    t = T/det = %g, u = V/det = %g, v = W/det = %g\n", T / det, V / det, W / det);
}

/* ---- 2. the awkward cases ------------------------------------------------------- */

typedef struct {
    const char *name;
    sidx_vec3 p0, p1, p2, org, dir;
} tcase;

/* Runs all three methods on one case through the printer, returns a bit
 * mask of which hit (bit = method). */
static int run_case(const tcase *c, float tmin, const sidx_hook *hook)
{
    sidx_ray r;
    if (sidx_ray_init(&r, c->org, c->dir, tmin, INFINITY) != SIDX_OK) return -1;
    int mask = 0;
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m) {
        printf("      %-16s ", method_label[m]);
        fflush(stdout);
        float t, u, v;
        if (sidx_trace_triangle(hook, (sidx_tri_method)m, 0, &r, c->p0, c->p1, c->p2, INFINITY, &t, &u, &v)) mask |= 1 << m;
    }
    return mask;
}

/* ---- 3. the fan ---------------------------------------------------------------- */

#define FAN 12

typedef struct {
    sidx_vec3 c, rim[FAN];
    sidx_vec3 normal;
} fan;

static void make_fan(fan *f)
{
    /* a tilted plane through an awkward centre, so nothing is exact */
    f->c = sidx_v3(0.1234567f, -0.7654321f, 0.3141593f);
    sidx_vec3 a = sidx_v3(0.8f, 0.35f, -0.2f), b = sidx_v3(-0.25f, 0.6f, 0.7f);
    a = sidx_v3_scale(a, 1.0f / sidx_v3_length(a));
    const sidx_vec3 nrm = sidx_v3_cross(a, b);
    f->normal = sidx_v3_scale(nrm, 1.0f / sidx_v3_length(nrm));
    b = sidx_v3_cross(f->normal, a);
    for (int i = 0; i < FAN; ++i) {
        const float ang = 6.2831853f * ((float)i + 0.3f * frand()) / FAN, rad = 0.7f + 0.6f * frand();
        f->rim[i] = sidx_v3_add(f->c, sidx_v3_add(sidx_v3_scale(a, rad * cosf(ang)), sidx_v3_scale(b, rad * sinf(ang))));
    }
}

/* Rays from above the fan aimed at a shared edge or at the centre vertex;
 * each must hit at least one of the triangles. */
static void fan_leaks(const fan *f, long rays, long leaks[SIDX_TRI_METHOD_COUNT], long twice[SIDX_TRI_METHOD_COUNT])
{
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m) leaks[m] = twice[m] = 0;
    for (long k = 0; k < rays; ++k) {
        const int e = (int)(frand() * FAN) % FAN;
        const float s = (k % 8 == 0) ? 0.0f : 0.05f + 0.9f * frand(); /* every 8th ray: the shared vertex */
        const sidx_vec3 target = sidx_v3_add(f->c, sidx_v3_scale(sidx_v3_sub(f->rim[e], f->c), s));
        /* one draw per statement (z first, the order gcc happened to take):
         * C leaves the order of a call's arguments open */
        const float oz = frand(), oy = frand(), ox = frand();
        const sidx_vec3 off = sidx_v3((ox - 0.5f) * 2.0f, (oy - 0.5f) * 2.0f, (oz - 0.5f) * 2.0f);
        const sidx_vec3 org = sidx_v3_add(sidx_v3_add(target, sidx_v3_scale(f->normal, 1.5f)), off);
        sidx_ray r;
        if (sidx_ray_init(&r, org, sidx_v3_sub(target, org), 0.0f, INFINITY) != SIDX_OK) continue;
        for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m) {
            int hits = 0;
            for (int i = 0; i < FAN; ++i) {
                float t, u, v;
                hits += sidx_intersect_triangle((sidx_tri_method)m, &r, f->c, f->rim[i], f->rim[(i + 1) % FAN],
                                                INFINITY, &t, &u, &v);
            }
            if (hits == 0) leaks[m]++;
            if (hits > 1) twice[m]++;
        }
    }
}

/* ---- 4. a closed mesh, shot from inside -------------------------------------------- */

static int mesh_leaks(const sidx_mesh *mesh, long rays, long leaks[SIDX_TRI_METHOD_COUNT])
{
    sidx_accel *acc[SIDX_TRI_METHOD_COUNT] = {NULL};
    sidx_error err = {0};
    int ok = 1;
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT && ok; ++m) {
        sidx_build_options opt = {0};
        opt.tri = (sidx_tri_method)m;
        if (sidx_accel_build("brute", mesh, &opt, &acc[m], &err) != SIDX_OK) {
            fprintf(stderr, "01_ray_triangle: %s\n", err.message);
            ok = 0;
        }
        leaks[m] = 0;
    }
    const sidx_vec3 centre = sidx_aabb_centroid(sidx_mesh_bounds(mesh));
    for (long k = 0; ok && k < rays; ++k) {
        const uint32_t tri = (uint32_t)(frand() * (float)mesh->num_triangles) % mesh->num_triangles;
        const int e = (int)(frand() * 3.0f) % 3;
        const sidx_vec3 a = sidx_mesh_vertex(mesh, tri, e), b = sidx_mesh_vertex(mesh, tri, (e + 1) % 3);
        const float s = (k % 4 == 0) ? 0.0f : frand(); /* every 4th ray: a vertex */
        const sidx_vec3 target = sidx_v3_add(a, sidx_v3_scale(sidx_v3_sub(b, a), s));
        sidx_ray r;
        if (sidx_ray_init(&r, centre, sidx_v3_sub(target, centre), 0.0f, INFINITY) != SIDX_OK) continue;
        for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m) {
            sidx_hit h;
            sidx_accel_intersect(acc[m], &r, NULL, &h);
            if (h.prim == SIDX_NO_HIT) leaks[m]++;
        }
    }
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m) sidx_accel_destroy(acc[m]);
    return ok;
}

int main(int argc, char **argv)
{
    lesson_args args = {.name = "01_ray_triangle",
                        .usage = usage,
                        .scene = "icosphere",
                        .refused = "the lesson compares triangle tests over every triangle; it builds no tree"};
    lesson_parse(&args, argc, argv);

    sidx_printer printer;
    sidx_printer_init(&printer, stdout);
    const sidx_hook hook = sidx_printer_hook(&printer);

    /* ---- 1 ---- */
    printf("== 1. One ray, one triangle, three methods\n");
    /* Built so the answer is known: the ray is aimed at the point
     * 0.2 p0 + 0.5 p1 + 0.3 p2 and reaches it at t = 2. */
    const sidx_vec3 p0 = sidx_v3(1, 0, -4), p1 = sidx_v3(3, 1, -5), p2 = sidx_v3(0, 3, -6);
    const sidx_vec3 org = sidx_v3(0.5f, 0.2f, 1.0f), dir = sidx_v3(0.6f, 0.6f, -3.05f);
    printf("  triangle p0 = (1, 0, -4), p1 = (3, 1, -5), p2 = (0, 3, -6)\n");
    printf("  ray      o  = (0.5, 0.2, 1), d = (0.6, 0.6, -3.05)\n");
    printf("  aimed at 0.2 p0 + 0.5 p1 + 0.3 p2, so the answer should be t = 2, u = 0.5, v = 0.3\n");
    sidx_ray ray;
    if (sidx_ray_init(&ray, org, dir, 0.0f, INFINITY) != SIDX_OK) { fprintf(stderr, "bad ray\n"); return 1; }
    worked_two_step(&ray, p0, p1, p2);
    worked_moller(&ray, p0, p1, p2);
    worked_watertight(&ray, p0, p1, p2);
    printf("\n  The library's tests, traced through the printer sink:\n");
    float tt[SIDX_TRI_METHOD_COUNT], uu[SIDX_TRI_METHOD_COUNT], vv[SIDX_TRI_METHOD_COUNT];
    int agree = 1;
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m) {
        printf("    %-16s ", method_label[m]);
        fflush(stdout);
        if (!sidx_trace_triangle(&hook, (sidx_tri_method)m, 0, &ray, p0, p1, p2, INFINITY, &tt[m], &uu[m], &vv[m])) {
            agree = 0;
            continue;
        }
        printf("    %-16s u = %.7g  v = %.7g\n", "", uu[m], vv[m]);
        if (fabsf(tt[m] - 2.0f) > 1e-5f || fabsf(uu[m] - 0.5f) > 1e-5f || fabsf(vv[m] - 0.3f) > 1e-5f) agree = 0;
    }
    printf("  All three agree with t = 2, u = 0.5, v = 0.3 (to 1e-5): %s\n", agree ? "yes" : "NO");

    /* ---- 2 ---- */
    printf("\n== 2. The awkward cases (each line below is a PRIM_TEST event from the printer)\n");
    const sidx_vec3 A = sidx_v3(0, 0, 0), B = sidx_v3(1, 0, 0), C = sidx_v3(0, 1, 0), down = sidx_v3(0, 0, -1);
    const tcase cases[] = {
        {"ray through the middle of edge p0-p1 (v = 0)", A, B, C, sidx_v3(0.5f, 0, 1), down},
        {"ray through the vertex p1 (u = 1)", A, B, C, sidx_v3(1, 0, 1), down},
        {"ray parallel to the plane, above it", A, B, C, sidx_v3(-1, 0.2f, 0.5f), sidx_v3(1, 0, 0)},
        {"ray lying IN the plane, crossing the triangle", A, B, C, sidx_v3(-1, 0.2f, 0), sidx_v3(1, 0, 0)},
        {"degenerate triangle (0,0,0) (1,1,0) (2,2,0), ray through (1,1,0)", A, sidx_v3(1, 1, 0), sidx_v3(2, 2, 0),
         sidx_v3(1, 1, 1), down},
        {"triangle BEHIND the origin (the line meets it at t = -1)", A, B, C, sidx_v3(0.2f, 0.2f, -1), down},
    };
    const int ncases = (int)(sizeof cases / sizeof cases[0]);
    int masks[8];
    for (int i = 0; i < ncases; ++i) {
        sidx_ray r;
        sidx_ray_init(&r, cases[i].org, cases[i].dir, 0.0f, INFINITY);
        printf("  %d) %s\n     D = (e1 x d).e2 = %g\n", i + 1, cases[i].name, moller_D(&r, cases[i].p0, cases[i].p1, cases[i].p2));
        masks[i] = run_case(&cases[i], 0.0f, &hook);
    }

    printf("\n  \"What if D = 0? What does it mean?\"\n");
    printf("     D is the determinant of [e1 e2 -d]: zero when d lies in the triangle's plane (cases 3, 4)\n"
           "     or when e1, e2 are parallel (case 5, no plane at all).  Cramer's rule then has no\n"
           "     unique solution, and every method reports a miss: %s.\n",
           (masks[2] | masks[3] | masks[4]) == 0 ? "measured above, all three miss" : "NOT what happened above");
    printf("     (A ray lying in the plane does touch the triangle along a segment, but a surface seen\n"
           "      exactly edge-on covers no area of the image: a miss is the right answer.)\n");

    printf("\n  \"Q: What if t is negative?\"  Case 6 again:\n");
    sidx_ray probe;
    const int tmin_refused =
        sidx_ray_init(&probe, cases[5].org, cases[5].dir, -INFINITY, INFINITY) == SIDX_ERR_INVALID_ARG;
    tcase mirrored = cases[5];
    mirrored.dir = sidx_v3_scale(cases[5].dir, -1.0f);
    printf("     The line meets the plane at t = -1: behind the origin, in the negative direction.\n"
           "     With tmin = 0 every method rejects it (%s).  sidx does not let a ray start\n"
           "     behind its origin: sidx_ray_init refuses tmin < 0 (%s), because a conservative\n"
           "     box test widens only positive distances.  The same line traced the other way:\n",
           masks[5] == 0 ? "measured: all miss" : "NOT measured so", tmin_refused ? "measured" : "NOT so");
    const int neg_mask = run_case(&mirrored, 0.0f, &hook);
    printf("     every method finds it at t = +1 (%s): t < 0 only means \"the other side\".\n",
           neg_mask == 7 ? "measured: all hit" : "NOT measured so");

    /* ---- 3 ---- */
    printf("\n== 3. Rounding: rays aimed at the shared edges and shared vertex of a fan of %d triangles\n", FAN);
    fan f;
    make_fan(&f);
    printf("  centre (%.7g, %.7g, %.7g), in a tilted plane; every ray points at a point of a shared\n"
           "  edge (every 8th at the centre vertex), so it must hit at least one triangle.\n",
           f.c.x, f.c.y, f.c.z);
    const long fan_rays = 200000;
    long leaks[SIDX_TRI_METHOD_COUNT], twice[SIDX_TRI_METHOD_COUNT];
    fan_leaks(&f, fan_rays, leaks, twice);
    printf("  %-16s %10s %14s\n", "method", "leaks", "hit 2+ tris");
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m)
        printf("  %-16s %10ld %14ld   (of %ld rays)\n", method_label[m], leaks[m], twice[m], fan_rays);
    printf("  A leak is a ray that sees straight through a closed surface: a black pixel, a light leak.\n"
           "  Watertight gives both triangles of a shared edge the bit-identical edge function with\n"
           "  opposite signs, so no ray can fall between them; Moller-Trumbore computes u, v of each\n"
           "  triangle separately, and their rounding does not line up.\n");

    /* ---- 4 ---- */
    sidx_mesh mesh = lesson_open_scene(&args);
    long mrays = 20000000L / (long)mesh.num_triangles;
    if (mrays > 20000) mrays = 20000;
    if (mrays < 200) mrays = 200;
    printf("\n== 4. The same on a closed mesh: '%s' (%u triangles), %ld rays from its box centre\n"
           "   aimed at its vertices and edges (\"brute\" built once per triangle test method)\n",
           args.scene, mesh.num_triangles, mrays);
    long mleaks[SIDX_TRI_METHOD_COUNT];
    if (!mesh_leaks(&mesh, mrays, mleaks)) { sidx_mesh_free(&mesh); return 1; }
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m)
        printf("  %-16s %8ld rays escaped\n", method_label[m], mleaks[m]);
    sidx_mesh_free(&mesh);

    printf("\n== Key figures\n");
    printf("  fan: watertight leaks %ld, Moller-Trumbore leaks %ld, two-step leaks %ld (of %ld rays)\n", leaks[0],
           leaks[1], leaks[2], fan_rays);
    lesson_check("worked_example_agrees", agree);
    lesson_check("d_zero_all_miss", (masks[2] | masks[3] | masks[4]) == 0);
    lesson_check("negative_t_rejected", masks[5] == 0 && neg_mask == 7 && tmin_refused);
    lesson_check("edge_vertex_hit", masks[0] == 7 && masks[1] == 7);
    lesson_check("watertight_leaks", leaks[0]);
    lesson_check("moller_leaks_more", leaks[1] > leaks[0]);
    lesson_check("mesh_watertight_leaks_le_moller", mleaks[0] <= mleaks[1]);
    return 0;
}
