/* 02_bounding_volumes.c — sphere, AABB, OBB and slabs around the same objects.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Bounding Volumes" —
 * "Sphere: very fast intersection computation, often inefficient because
 * it is too large"; "AABB: very simple intersection computation (min-max),
 * sometimes too large"; "OBB: often better fit, fairly complex
 * computation"; "Slabs: ... pretty fast computation, but more expensive
 * than AABB".  Deck 001: "Bounding Box" and "Surface Area Heuristic"
 * ("the probability that a random ray that hits B also hits A is given by
 * the ratio of the surface areas S_A / S_B").
 *
 * What it shows: the four volumes fitted with sidx_sphere_fit,
 * sidx_aabb_fit, sidx_obb_fit and sidx_kdop_fit (a 14-DOP: the three axes
 * plus the four cube diagonals) around three objects — a scene (default
 * the teapot), a round one (an icosphere) and a long tilted rod — and for
 * each volume, measured on the spot:
 *   - tightness: its surface area;
 *   - how many uniformly random rays it lets through, against the surface
 *     area ratio that predicts it (the SAH's assumption, checked here);
 *   - cost: nanoseconds per ray test;
 *   - and what the two add up to: expected time per ray when the object
 *     behind the volume costs what its brute-force test costs.
 * One random ray is traced through the printer: each volume's test, then
 * the object's triangles.
 *
 * Read:  lib/intersect.c, sidx_intersect_aabb; lib/intersect.c, sidx_obb_fit
 * Run:   build/lessons/02_bounding_volumes [SCENE]
 *        SCENE = a built-in scene name or an .obj/.ply file (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "sidx/sidx.h"
#include "lesson.h"

enum { BV_SPHERE, BV_AABB, BV_OBB, BV_KDOP, BV_COUNT };
static const char *const bv_name[BV_COUNT] = {"sphere", "AABB", "OBB", "14-DOP"};

static void usage(FILE *f)
{
    fprintf(f, "usage: 02_bounding_volumes [--help] [SCENE]\n"
               "\n"
               "Sphere, AABB, OBB and 14-DOP around the same objects: surface area against the\n"
               "measured cost of a ray test and the share of random rays each one culls.\n"
               "\n"
               "  SCENE   the first object: built-in scene name or .obj/.ply (default: teapot)\n");
}

static uint32_t rng_state = 0x2545F491u;
static float frand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return (float)(rng_state >> 8) / 16777216.0f;
}

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

typedef struct {
    sidx_sphere sphere;
    sidx_aabb aabb;
    sidx_obb obb;
    sidx_kdop kdop;
} volumes;

static int bv_test(const volumes *v, int which, const sidx_ray *r, float *tn, float *tf)
{
    switch (which) {
    case BV_SPHERE: return sidx_intersect_sphere(r, &v->sphere, r->tmin, r->tmax, tn, tf);
    case BV_AABB: return sidx_intersect_aabb(SIDX_BOX_ROBUST, r, &v->aabb, r->tmin, r->tmax, tn, tf);
    case BV_OBB: return sidx_intersect_obb(r, &v->obb, r->tmin, r->tmax, tn, tf);
    default: return sidx_intersect_kdop(r, &v->kdop, r->tmin, r->tmax, tn, tf);
    }
}

/* A box 4 x 0.2 x 0.2 turned 30 degrees about z, then 25 about x: the
 * shape an axis-aligned box fits worst and an oriented box fits exactly. */
static sidx_status make_rod(sidx_mesh *out, sidx_error *err)
{
    float xyz[24];
    const float cz = cosf(0.5236f), sz = sinf(0.5236f), cx = cosf(0.4363f), sx = sinf(0.4363f);
    for (int i = 0; i < 8; ++i) {
        const float x = (i & 1) ? 2.0f : -2.0f, y = (i & 2) ? 0.1f : -0.1f, z = (i & 4) ? 0.1f : -0.1f;
        const float x1 = cz * x - sz * y, y1 = sz * x + cz * y;            /* about z */
        const float y2 = cx * y1 - sx * z, z2 = sx * y1 + cx * z;          /* about x */
        xyz[3 * i] = x1;
        xyz[3 * i + 1] = y2;
        xyz[3 * i + 2] = z2;
    }
    static const uint32_t idx[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                     2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    return sidx_mesh_from_arrays(out, xyz, 8, idx, 12, err);
}

typedef struct {
    const char *name;
    double area[BV_COUNT];       /* surface area (14-DOP: estimated from its hit rate) */
    double frac[BV_COUNT];       /* share of the random rays that hit the volume */
    double predicted[BV_COUNT];  /* area / area of the outer sphere */
    double ns[BV_COUNT];         /* time per test */
    double obj_ns;               /* time per ray for the object itself (brute force) */
    double obj_frac;             /* share of the sampled rays that hit the object */
    double useful[BV_COUNT];     /* of the rays that entered the volume, share that hit the object */
    int conservative;            /* no ray hit the object but missed a volume */
} result;

/* Uniformly distributed random lines through the ball (c, R): a uniform
 * direction, then a uniform point of the disk across it.  For such lines
 * the chance to meet a convex body is proportional to its surface area
 * (Cauchy–Crofton) — the reason the SAH uses surface areas. */
static void random_rays(sidx_ray *rays, long n, sidx_vec3 c, float R)
{
    for (long i = 0; i < n; ++i) {
        const float z = 2.0f * frand() - 1.0f, phi = 6.2831853f * frand(), s = sqrtf(1.0f - z * z);
        const sidx_vec3 d = sidx_v3(s * cosf(phi), s * sinf(phi), z);
        /* two unit vectors across d */
        sidx_vec3 a = fabsf(d.x) < 0.9f ? sidx_v3(1, 0, 0) : sidx_v3(0, 1, 0);
        a = sidx_v3_cross(d, a);
        a = sidx_v3_scale(a, 1.0f / sidx_v3_length(a));
        const sidx_vec3 b = sidx_v3_cross(d, a);
        const float rad = R * sqrtf(frand()), ang = 6.2831853f * frand();
        const sidx_vec3 p = sidx_v3_add(c, sidx_v3_add(sidx_v3_scale(a, rad * cosf(ang)), sidx_v3_scale(b, rad * sinf(ang))));
        const sidx_vec3 o = sidx_v3_sub(p, sidx_v3_scale(d, 2.0f * R));
        sidx_ray_init(&rays[i], o, d, 0.0f, INFINITY);
    }
}

static int study(const char *name, const sidx_mesh *mesh, result *res, int trace_one)
{
    memset(res, 0, sizeof *res);
    res->name = name;
    volumes v;
    sidx_sphere_fit(mesh->positions, mesh->num_vertices, &v.sphere);
    sidx_aabb_fit(mesh->positions, mesh->num_vertices, &v.aabb);
    sidx_obb_fit(mesh->positions, mesh->num_vertices, &v.obb);
    sidx_kdop_fit(mesh->positions, mesh->num_vertices, &v.kdop);

    /* An outer ball that holds all four volumes. */
    const sidx_vec3 c = sidx_aabb_centroid(v.aabb);
    float R = 0.5f * sidx_v3_length(sidx_aabb_extent(v.aabb));
    const float rs = sidx_v3_length(sidx_v3_sub(v.sphere.center, c)) + v.sphere.radius;
    if (rs > R) R = rs;
    for (int k = 0; k < 8; ++k) {
        sidx_vec3 p = v.obb.center;
        for (int a = 0; a < 3; ++a) {
            const float h = sidx_v3_get(v.obb.half, a);
            p = sidx_v3_add(p, sidx_v3_scale(v.obb.axis[a], (k >> a & 1) ? h : -h));
        }
        const float d = sidx_v3_length(sidx_v3_sub(p, c));
        if (d > R) R = d;
    }
    R *= 1.001f;
    const double outer_area = 4.0 * 3.14159265358979 * (double)R * R;

    const long n = 200000;
    sidx_ray *rays = malloc((size_t)n * sizeof *rays);
    unsigned char *hitbv = malloc((size_t)n * BV_COUNT);
    if (!rays || !hitbv) { free(rays); free(hitbv); return 0; }
    random_rays(rays, n, c, R);

    /* Which rays each volume lets through, and the time per test. */
    for (int b = 0; b < BV_COUNT; ++b) {
        long hits = 0;
        for (long i = 0; i < n; ++i) {
            float tn, tf;
            hitbv[i * BV_COUNT + b] = (unsigned char)bv_test(&v, b, &rays[i], &tn, &tf);
            hits += hitbv[i * BV_COUNT + b];
        }
        res->frac[b] = (double)hits / (double)n;
        volatile int sink = 0;
        int reps = 0;
        const double t0 = now_ns();
        double t1;
        do {
            for (long i = 0; i < n; ++i) {
                float tn, tf;
                sink += bv_test(&v, b, &rays[i], &tn, &tf);
            }
            ++reps;
            t1 = now_ns();
        } while (t1 - t0 < 2e7 && reps < 50);
        (void)sink;
        res->ns[b] = (t1 - t0) / ((double)reps * (double)n);
    }
    res->area[BV_SPHERE] = sidx_sphere_area(&v.sphere);
    res->area[BV_AABB] = sidx_aabb_area(v.aabb);
    res->area[BV_OBB] = sidx_obb_area(&v.obb);
    res->area[BV_KDOP] = res->frac[BV_KDOP] * outer_area; /* no closed formula in the library */
    for (int b = 0; b < BV_COUNT; ++b) res->predicted[b] = res->area[b] / outer_area;

    /* The object itself, by brute force, on as many rays as stay quick. */
    sidx_accel *acc = NULL;
    sidx_error err = {0};
    if (sidx_accel_build("brute", mesh, NULL, &acc, &err) != SIDX_OK) {
        fprintf(stderr, "02_bounding_volumes: %s\n", err.message);
        free(rays);
        free(hitbv);
        return 0;
    }
    long m = 10000000L / (long)mesh->num_triangles;
    if (m > n) m = n;
    if (m < 100) m = 100;
    long obj_hits = 0, entered[BV_COUNT] = {0}, useful[BV_COUNT] = {0};
    res->conservative = 1;
    const double t0 = now_ns();
    for (long i = 0; i < m; ++i) {
        int occ = 0;
        sidx_accel_occluded(acc, &rays[i], NULL, &occ);
        obj_hits += occ;
        for (int b = 0; b < BV_COUNT; ++b) {
            entered[b] += hitbv[i * BV_COUNT + b];
            if (occ && hitbv[i * BV_COUNT + b]) useful[b]++;
            if (occ && !hitbv[i * BV_COUNT + b]) res->conservative = 0;
        }
    }
    res->obj_ns = (now_ns() - t0) / (double)m;
    res->obj_frac = (double)obj_hits / (double)m;
    for (int b = 0; b < BV_COUNT; ++b) res->useful[b] = entered[b] ? (double)useful[b] / (double)entered[b] : 0.0;

    if (trace_one) {
        /* The first ray that enters the AABB, traced through the printer. */
        long pick = 0;
        for (long i = 0; i < n; ++i)
            if (hitbv[i * BV_COUNT + BV_AABB]) { pick = i; break; }
        const sidx_ray *r = &rays[pick];
        printf("\n  One random ray through '%s': o = (%g, %g, %g), d = (%g, %g, %g)\n", name, r->org.x, r->org.y,
               r->org.z, r->dir.x, r->dir.y, r->dir.z);
        for (int b = 0; b < BV_COUNT; ++b) {
            float tn, tf;
            if (bv_test(&v, b, r, &tn, &tf))
                printf("    %-7s hit   t=[%g, %g]\n", bv_name[b], tn, tf);
            else
                printf("    %-7s miss  (the object's triangles are never looked at)\n", bv_name[b]);
        }
        printf("    the AABB once more, through the printer sink:\n    ");
        fflush(stdout);
        sidx_printer pr;
        sidx_printer_init(&pr, stdout);
        pr.show_bounds = 1;
        const sidx_hook hook = sidx_printer_hook(&pr);
        float tn, tf;
        sidx_trace_aabb(&hook, SIDX_BOX_ROBUST, 0, r, &v.aabb, r->tmin, r->tmax, &tn, &tf);
        printf("    and the object behind it (brute force; showing only the hits):\n");
        pr.mask = SIDX_EVMASK(SIDX_EV_RAY_BEGIN) | SIDX_EVMASK(SIDX_EV_HIT_UPDATE) | SIDX_EVMASK(SIDX_EV_TERMINATE) |
                  SIDX_EVMASK(SIDX_EV_RAY_END);
        pr.show_bounds = 0;
        sidx_counters cnt;
        sidx_counters_init(&cnt);
        sidx_tee tee = {{hook, sidx_counters_hook(&cnt)}, 2};
        const sidx_hook th = sidx_tee_hook(&tee);
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &th, 1};
        sidx_hit h;
        sidx_accel_intersect(acc, r, &q, &h);
        printf("    -> %llu triangle tests for this one ray, %llu of them hits\n",
               (unsigned long long)cnt.n[SIDX_EV_PRIM_TEST], (unsigned long long)cnt.prim_hits);
    }

    sidx_accel_destroy(acc);
    free(rays);
    free(hitbv);

    printf("\n  %s: %u triangles; %ld random rays through a ball of radius %.3g around it\n", name,
           mesh->num_triangles, n, R);
    printf("  %-7s %10s %8s %10s %10s %9s %9s %12s\n", "volume", "area", "vs AABB", "P predicted", "P measured",
           "culled", "ns/test", "useful hits");
    for (int b = 0; b < BV_COUNT; ++b)
        printf("  %-7s %10.4g %7.2fx %10.4f %10.4f %8.1f%% %9.2f %11.1f%%%s\n", bv_name[b], res->area[b],
               res->area[b] / res->area[BV_AABB], res->predicted[b], res->frac[b], 100.0 * (1.0 - res->frac[b]),
               res->ns[b], 100.0 * res->useful[b], b == BV_KDOP ? "  (area estimated from P measured)" : "");
    printf("  the object itself: P(hit) = %.4f, %.0f ns per ray by brute force (%ld rays)\n", res->obj_frac,
           res->obj_ns, m);
    printf("  expected ns per ray = test + P(hit volume) x %.0f ns:", res->obj_ns);
    for (int b = 0; b < BV_COUNT; ++b) printf("  %s %.0f", bv_name[b], res->ns[b] + res->frac[b] * res->obj_ns);
    printf("\n");
    return 1;
}

int main(int argc, char **argv)
{
    lesson_args args = {.name = "02_bounding_volumes",
                        .usage = usage,
                        .scene = "teapot",
                        .refused = "the lesson compares bounding volumes of whole objects; it builds no tree"};
    lesson_parse(&args, argc, argv);
    sidx_mesh objs[3] = {lesson_open_scene(&args), lesson_open(&args, "icosphere:2")};
    const char *names[3] = {args.scene, "icosphere:2", "rod"};
    sidx_error err = {0};
    if (make_rod(&objs[2], &err) != SIDX_OK) lesson_fail(&args, err.message);

    printf("== Bounding volumes: tightness against test cost\n");
    printf("  P predicted = area / area of the outer ball (Cauchy-Crofton: what the SAH assumes);\n"
           "  P measured  = share of the random rays whose test said hit; culled = 1 - P measured;\n"
           "  useful hits = of the rays that entered the volume, the share that hit the object.\n");
    result res[3];
    int ok = 1;
    for (int i = 0; i < 3 && ok; ++i) ok = study(names[i], &objs[i], &res[i], i == 0);
    for (int i = 0; i < 3; ++i) sidx_mesh_free(&objs[i]);
    if (!ok) return 1;

    int conservative = 1, predicts = 1, kdop_le_aabb = 1;
    double worst = 0.0;
    for (int i = 0; i < 3; ++i) {
        conservative &= res[i].conservative;
        for (int b = 0; b < BV_KDOP; ++b) {
            const double dev = fabs(res[i].frac[b] - res[i].predicted[b]) / res[i].predicted[b];
            if (dev > worst) worst = dev;
        }
        if (res[i].frac[BV_KDOP] > res[i].frac[BV_AABB] * 1.001 + 1e-5) kdop_le_aabb = 0;
    }
    predicts = worst < 0.05;
    const int obb_rod = res[2].area[BV_OBB] < 0.5 * res[2].area[BV_AABB] && res[2].frac[BV_OBB] < res[2].frac[BV_AABB];
    const int sphere_round = res[1].area[BV_SPHERE] < 1.3 * res[1].area[BV_AABB];
    printf("\n== Key figures\n");
    printf("  surface area predicts the share of rays that hit a volume to within %.1f%% (sphere, AABB, OBB)\n",
           100.0 * worst);
    printf("  rod:  OBB area %.3g vs AABB %.3g (%.1fx tighter); it lets %.1f%% of the rays through vs %.1f%%\n",
           res[2].area[BV_OBB], res[2].area[BV_AABB], res[2].area[BV_AABB] / res[2].area[BV_OBB],
           100 * res[2].frac[BV_OBB], 100 * res[2].frac[BV_AABB]);
    printf("  test cost (ns, '%s'): sphere %.2f  AABB %.2f  OBB %.2f  14-DOP %.2f\n", res[0].name, res[0].ns[0],
           res[0].ns[1], res[0].ns[2], res[0].ns[3]);
    lesson_check("conservative", conservative);
    lesson_check("area_predicts_hit_rate", predicts);
    lesson_check("kdop_within_aabb", kdop_le_aabb);
    lesson_check("obb_tighter_on_rod", obb_rod);
    lesson_check("sphere_fits_round_object", sphere_round);
    return 0;
}
