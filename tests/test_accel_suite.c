/* test_accel_suite.c — every registered structure against brute force,
 * plus the numerical stress cases.
 *
 * The structures are taken from the registry at run time, so a structure
 * joins these tests by being registered.  Each case builds brute force
 * (float, the same triangle test) for the expected closest hits and then
 * checks every structure on the same rays:
 *   - closest hit agrees (tk_hits_agree: same prim, or |t - t_ref| <=
 *     1e-5·max(1, |t_ref|) for coincident surfaces; both miss otherwise);
 *   - u, v requested: same prim and t as without, u, v barycentric;
 *     not requested: u = v = 0;
 *   - any-hit (sidx_accel_occluded) agrees with "brute force hits";
 *   - the traversal variants (stack, ordered, naive) agree too.
 * Cases: random rays on every built-in scene at small sizes; grazing rays
 * aimed at shared edges and vertices; zero leaks from inside closed
 * icospheres; axis-parallel rays with ±0 components; rays starting on a
 * surface; scenes translated to ±1e6 and scaled by 1e-6; slivers and
 * zero-area triangles; coincident duplicates; flat scenes; a single
 * triangle; one degenerate triangle; NULL and invalid arguments; the ray and
 * hit file readers of sidx-bench.  SIDX_FAST_TESTS=1 shrinks ray counts. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "sidx/sidx.h"
#include "common/testkit.h"

/* ---- watchdog ----------------------------------------------------------------
 * Structures are written concurrently with this suite; one that loops or
 * explodes must fail the suite with its name, not hang `make test` or
 * swallow the machine's memory.  Each structure gets SIDX_TEST_TIMEOUT
 * seconds per case (default 120, 900 with SIDX_FAST_TESTS), and outside
 * sanitizers the address space is capped (SIDX_TEST_MEM_MB, default 4096),
 * so a runaway build fails with SIDX_ERR_NOMEM instead. */
static const char *volatile g_case = "", *volatile g_structure = "";

static void put(const char *s) { (void)!write(2, s, strlen(s)); }

static void on_alarm(int sig)
{
    (void)sig;
    put("\n!! test_accel_suite: ");
    put((const char *)g_structure);
    put(" on case '");
    put((const char *)g_case);
    put("' exceeded SIDX_TEST_TIMEOUT: the structure hangs or is far too slow\n");
    _exit(1);
}

static unsigned watchdog_seconds(void)
{
    const char *e = getenv("SIDX_TEST_TIMEOUT");
    if (e && atoi(e) > 0) return (unsigned)atoi(e);
    return tk_fast_tests() ? 900u : 120u;
}

/* A crash inside a structure: name it, then hand over to cmocka's handler. */
static const int crash_signals[4] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL};
static struct sigaction saved_actions[4];

static void on_crash(int sig)
{
    alarm(0);
    put("\n!! test_accel_suite: crash (signal) in ");
    put((const char *)g_structure);
    put(" on case '");
    put((const char *)g_case);
    put("'\n");
    for (int k = 0; k < 4; ++k)
        if (crash_signals[k] == sig) {
            sigaction(sig, &saved_actions[k], NULL);
            if (saved_actions[k].sa_handler != SIG_DFL && saved_actions[k].sa_handler != SIG_IGN)
                saved_actions[k].sa_handler(sig);
            else
                raise(sig);
        }
}

static void watchdog_start(const char *label, const char *structure)
{
    g_case = label;
    g_structure = structure;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_crash;
    sigemptyset(&sa.sa_mask);
    for (int k = 0; k < 4; ++k) sigaction(crash_signals[k], &sa, &saved_actions[k]);
    alarm(watchdog_seconds());
}

static void watchdog_stop(void)
{
    alarm(0);
    for (int k = 0; k < 4; ++k) sigaction(crash_signals[k], &saved_actions[k], NULL);
}

static void install_limits(void)
{
    signal(SIGALRM, on_alarm);
#if !defined(__SANITIZE_ADDRESS__)
    if (!tk_fast_tests()) { /* ASan and valgrind need their own huge mappings */
        const char *e = getenv("SIDX_TEST_MEM_MB");
        rlim_t mb = (e && atoi(e) > 0) ? (rlim_t)atoi(e) : 4096;
        struct rlimit rl = {mb << 20, mb << 20};
        setrlimit(RLIMIT_AS, &rl);
    }
#endif
}

#define CHECK_ALL_HIT 1u    /* every ray must hit (closed mesh seen from inside) */
#define CHECK_ALL_MISS 2u   /* every ray must miss degenerate geometry, except exactly on its segment */
#define CHECK_TRAVERSALS 4u /* also the stack / ordered / naive traversals */
#define MAX_REPORTS 4       /* mismatches printed per structure and case */

static size_t nrays(size_t normal) { return tk_test_size(normal); }

static void describe_ray(const tk_rayrec *r, char *buf, size_t size)
{
    snprintf(buf, size, "o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g) t=[%g, %g]", r->o[0], r->o[1], r->o[2], r->d[0],
             r->d[1], r->d[2], r->tmin, r->tmax);
}

static long hit_prim(const sidx_hit *h) { return h->prim == SIDX_NO_HIT ? -1L : (long)h->prim; }

/* Distance from p to the segment ab. */
static float segment_distance(sidx_vec3 p, sidx_vec3 a, sidx_vec3 b)
{
    const sidx_vec3 ab = sidx_v3_sub(b, a), ap = sidx_v3_sub(p, a);
    const float len2 = sidx_v3_dot(ab, ab);
    float s = len2 > 0.0f ? sidx_v3_dot(ap, ab) / len2 : 0.0f;
    s = s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s);
    return sidx_v3_length(sidx_v3_sub(ap, sidx_v3_scale(ab, s)));
}

/* intersect.h: a ray aimed exactly at a point of a collinear (zero-area)
 * triangle may register a hit, but only there, at the right t.  A hit on
 * degenerate geometry is fine iff its point lies on one of the triangle's
 * edges (within float rounding of the scene's scale); anything else is
 * garbage. */
static int degenerate_hit_ok(const sidx_mesh *m, const sidx_ray *r, const sidx_hit *h)
{
    if (h->prim == SIDX_NO_HIT) return 1;
    const sidx_vec3 p = sidx_ray_at(r, h->t);
    const sidx_vec3 v0 = sidx_mesh_vertex(m, h->prim, 0), v1 = sidx_mesh_vertex(m, h->prim, 1),
                    v2 = sidx_mesh_vertex(m, h->prim, 2);
    const sidx_aabb b = sidx_mesh_bounds(m);
    const sidx_vec3 e = sidx_aabb_extent(b);
    const float scale = fmaxf(fmaxf(e.x, e.y), e.z) + sidx_v3_length(sidx_v3_sub(r->org, sidx_aabb_centroid(b)));
    const float tol = 1e-5f * scale;
    return segment_distance(p, v0, v1) <= tol || segment_distance(p, v1, v2) <= tol ||
           segment_distance(p, v2, v0) <= tol;
}

/* A set of rays checked on one mesh, with its label and rule (CHECK_*). */
typedef struct ray_set {
    const char *label;
    const tk_rayrec *rays;
    size_t n;
    unsigned flags;
} ray_set;

/* The expected hits of one set: brute force's, and per ray whether the ray
 * is valid and whether brute force itself keeps the set's rule. */
typedef struct ray_set_ref {
    sidx_hit *ref;
    sidx_ray *rr;
    uint8_t *valid, *brute_ok;
} ray_set_ref;

/* Brute force's hits for one set; returns the number of rays on which the
 * triangle test itself breaks the set's rule (each printed, up to
 * MAX_REPORTS), reported here once, not for every structure. */
static unsigned brute_reference(const sidx_accel *brute, const sidx_mesh *m, const ray_set *set, ray_set_ref *out)
{
    const size_t n = set->n;
    out->ref = calloc(n ? n : 1, sizeof *out->ref);
    out->rr = calloc(n ? n : 1, sizeof *out->rr);
    out->valid = calloc(n ? n : 1, 1);
    out->brute_ok = calloc(n ? n : 1, 1);
    assert_non_null(out->ref);
    assert_non_null(out->rr);
    assert_non_null(out->valid);
    assert_non_null(out->brute_ok);
    unsigned brute_bad = 0;
    for (size_t i = 0; i < n; ++i) {
        out->valid[i] = tk_ray_from(&set->rays[i], &out->rr[i]) == SIDX_OK;
        if (!out->valid[i]) continue;
        assert_int_equal(sidx_accel_intersect(brute, &out->rr[i], NULL, &out->ref[i]), SIDX_OK);
        const int hit = out->ref[i].prim != SIDX_NO_HIT;
        out->brute_ok[i] = !(((set->flags & CHECK_ALL_HIT) && !hit) ||
                             ((set->flags & CHECK_ALL_MISS) && !degenerate_hit_ok(m, &out->rr[i], &out->ref[i])));
        if (!out->brute_ok[i] && brute_bad++ < MAX_REPORTS) {
            char d[200];
            describe_ray(&set->rays[i], d, sizeof d);
            print_message("%s: brute force (the triangle test itself): ray %zu %s: prim %ld t=%.9g (%s)\n",
                          set->label, i, hit ? "hits degenerate geometry" : "leaks", hit_prim(&out->ref[i]),
                          out->ref[i].t, d);
        }
    }
    if (brute_bad > MAX_REPORTS) print_message("%s: brute force: %u rays failed in all\n", set->label, brute_bad);
    return brute_bad;
}

/* One structure, built once, on one set; returns the number of failed rays. */
static unsigned check_structure(const char *name, const sidx_accel *a, const sidx_mesh *m, const ray_set *set,
                                const ray_set_ref *b)
{
    const unsigned flags = set->flags;
    unsigned bad = 0;
    for (size_t i = 0; i < set->n; ++i) {
        if (!b->valid[i]) continue;
        const sidx_hit *const ref = &b->ref[i];
        const sidx_ray *const rr = &b->rr[i];
        const char *what = NULL;
        sidx_hit h0, h1;
        sidx_query q0 = {0, SIDX_TRAVERSE_DEFAULT, NULL, (uint32_t)i};
        sidx_query q1 = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, NULL, (uint32_t)i};
        int occ = -1;
        sidx_accel_intersect(a, rr, &q0, &h0);
        sidx_accel_intersect(a, rr, &q1, &h1);
        sidx_accel_occluded(a, rr, &q0, &occ);
        const int ref_hit = ref->prim != SIDX_NO_HIT;
        sidx_hit hv = h0;
        if (!tk_hits_agree(ref, &h0)) what = "closest hit differs from brute force";
        else if (b->brute_ok[i] && (flags & CHECK_ALL_HIT) && h0.prim == SIDX_NO_HIT)
            what = "leak: the ray slipped through";
        else if (b->brute_ok[i] && (flags & CHECK_ALL_MISS) && !degenerate_hit_ok(m, rr, &h0))
            what = "hit on degenerate geometry away from its segment";
        else if (h1.prim != h0.prim || !(h1.t == h0.t || (isinf(h1.t) && isinf(h0.t)))) {
            what = "asking for u, v changed the hit";
            hv = h1;
        } else if (h0.u != 0.0f || h0.v != 0.0f) what = "u, v filled although not asked for";
        else if (h1.prim != SIDX_NO_HIT && !(h1.u >= -1e-4f && h1.v >= -1e-4f && h1.u + h1.v <= 1.0001f)) {
            what = "u, v are not barycentric";
            hv = h1;
        } else if (occ != ref_hit) what = ref_hit ? "any-hit query missed" : "any-hit query hit nothing real";
        if (!what && (flags & CHECK_TRAVERSALS)) {
            for (int t = SIDX_TRAVERSE_STACK; t < SIDX_TRAVERSE_COUNT && !what; ++t) {
                sidx_query qt = {0, (sidx_traversal)t, NULL, (uint32_t)i};
                sidx_accel_intersect(a, rr, &qt, &hv);
                if (!tk_hits_agree(ref, &hv)) what = sidx_traversal_name((sidx_traversal)t);
            }
        }
        if (what && bad++ < MAX_REPORTS) {
            char d[200];
            describe_ray(&set->rays[i], d, sizeof d);
            print_message("%s: %s: ray %zu: %s%s: ref prim %ld t=%.9g, got prim %ld t=%.9g (%s)\n", set->label, name,
                          i, what, (flags & CHECK_TRAVERSALS) && strlen(what) < 10 ? " traversal differs" : "",
                          hit_prim(ref), ref->t, hit_prim(&hv), hv.t, d);
        }
    }
    if (bad > MAX_REPORTS) print_message("%s: %s: %u rays failed in all\n", set->label, name, bad);
    return bad;
}

/* Checks every registered structure on the sets of rays of one mesh m;
 * returns the number of failed checks (each one printed, up to
 * MAX_REPORTS per structure and set).  Each structure is built once for
 * all the sets (scene names it in the watchdog's message). */
static unsigned check_sets(const char *scene, const sidx_mesh *m, const ray_set *sets, size_t nsets,
                           const sidx_build_options *bo)
{
    unsigned failures = 0;
    sidx_error err = {SIDX_OK, ""};
    sidx_accel *brute = NULL;
    if (sidx_accel_build("brute", m, bo, &brute, &err) != SIDX_OK) {
        print_message("%s: brute force does not build: %s\n", scene, err.message);
        return 1;
    }
    ray_set_ref *refs = calloc(nsets ? nsets : 1, sizeof *refs);
    assert_non_null(refs);
    for (size_t k = 0; k < nsets; ++k) failures += brute_reference(brute, m, &sets[k], &refs[k]);

    /* The smallest sizes (valgrind): on a mesh of more than a few dozen
     * triangles every other structure, the other half on the next such
     * mesh, so each structure still meets every kind of scene; its builds,
     * not its rays, are what takes minutes under memcheck. */
    static unsigned rotation = 0;
    const int half = tk_tiny_tests() && m->num_triangles > 64;
    rotation += half;
    for (size_t ai = 0; ai < sidx_accel_registered_count(); ++ai) {
        const char *name = sidx_accel_registered_name(ai);
        if (!strcmp(name, "brute")) continue;
        if (half && (ai + rotation) % 2 != 0) continue;
        sidx_accel *a = NULL;
        watchdog_start(scene, name);
        if (sidx_accel_build(name, m, bo, &a, &err) != SIDX_OK) {
            watchdog_stop();
            print_message("%s: %s does not build: %s\n", scene, name, err.message);
            ++failures;
            continue;
        }
        for (size_t k = 0; k < nsets; ++k) failures += check_structure(name, a, m, &sets[k], &refs[k]);
        sidx_accel_destroy(a);
        watchdog_stop();
    }
    sidx_accel_destroy(brute);
    for (size_t k = 0; k < nsets; ++k) {
        free(refs[k].ref);
        free(refs[k].rr);
        free(refs[k].valid);
        free(refs[k].brute_ok);
    }
    free(refs);
    return failures;
}

/* One set of rays on m. */
static unsigned check_case(const char *label, const sidx_mesh *m, const tk_rayrec *rays, size_t n,
                           const sidx_build_options *bo, unsigned flags)
{
    const ray_set set = {label, rays, n, flags};
    return check_sets(label, m, &set, 1, bo);
}

/* ---- scenes ------------------------------------------------------------------- */

/* Small details of the built-in scenes; unknown (new) scenes use their default. */
static uint32_t small_detail(const char *name)
{
    static const struct { const char *name; uint32_t detail; } d[] = {
        {"icosphere", 2}, {"teapot", 8}, {"stadium", 8}, {"soup", 300}, {"menger", 1}, {"flat2d", 4}, {"grid", 8},
        {"heightfield", 8},
    };
    for (size_t i = 0; i < sizeof d / sizeof d[0]; ++i)
        if (!strcmp(d[i].name, name)) return d[i].detail;
    return 0;
}

static void make_scene(const char *name, sidx_mesh *m)
{
    sidx_error err = {SIDX_OK, ""};
    memset(m, 0, sizeof *m);
    if (sidx_scene_make(name, small_detail(name), m, &err) != SIDX_OK)
        fail_msg("scene %s: %s", name, err.message);
}

/* Rays of several kinds for m, concatenated. */
static tk_rayrec *kinds_rays(const sidx_mesh *m, const tk_ray_kind *kinds, int nk, size_t per_kind, uint64_t seed,
                             size_t *n)
{
    tk_rayrec *r = malloc((size_t)nk * per_kind * sizeof *r + 1);
    assert_non_null(r);
    for (int k = 0; k < nk; ++k) tk_make_rays(m, kinds[k], per_kind, seed + (uint64_t)k, r + (size_t)k * per_kind);
    *n = (size_t)nk * per_kind;
    return r;
}

static unsigned check_kinds(const char *label, const sidx_mesh *m, const tk_ray_kind *kinds, int nk, size_t per_kind,
                            unsigned flags)
{
    size_t n;
    tk_rayrec *r = kinds_rays(m, kinds, nk, per_kind, 1234, &n);
    unsigned f = check_case(label, m, r, n, NULL, flags);
    free(r);
    return f;
}

/* ---- the tests: every built-in scene ----------------------------------------- */

/* Each built-in scene, each structure built once for three sets of rays:
 *   - random primary, diffuse and shadow rays, with the traversal variants;
 *   - grazing rays (shared edges and vertices) and axis-parallel rays;
 *   - rays starting exactly on a surface point: tmin = 0 (self hit at
 *     t ~ 0 allowed, as long as every structure agrees with brute force;
 *     half of them leave the surface the other way) and tmin = 1e-3 (the
 *     usual shadow-ray offset). */
static void test_builtin_scenes(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const tk_ray_kind random_kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE, TK_RAYS_SHADOW};
    static const tk_ray_kind grazing_kinds[] = {TK_RAYS_GRAZING, TK_RAYS_AXIS};
    for (const char *const *s = sidx_scene_names(); *s; ++s) {
        sidx_mesh m;
        make_scene(*s, &m);
        size_t n_random, n_grazing;
        tk_rayrec *random = kinds_rays(&m, random_kinds, 3, nrays(150), 1234, &n_random);
        tk_rayrec *grazing = kinds_rays(&m, grazing_kinds, 2, nrays(250), 1234, &n_grazing);
        const size_t n = nrays(200);
        tk_rayrec *surface = malloc(2 * n * sizeof *surface);
        assert_non_null(surface);
        tk_make_rays(&m, TK_RAYS_SHADOW, n, 99, surface);
        for (size_t i = 0; i < n; ++i) {
            surface[n + i] = surface[i];
            surface[n + i].tmin = 0.0f;
            surface[n + i].tmax = INFINITY;
            if (i & 1)
                for (int k = 0; k < 3; ++k) surface[n + i].d[k] = -surface[n + i].d[k];
        }
        char grazing_label[64], surface_label[64];
        snprintf(grazing_label, sizeof grazing_label, "%s (grazing, axis)", *s);
        snprintf(surface_label, sizeof surface_label, "%s (on surface)", *s);
        const ray_set sets[] = {{*s, random, n_random, CHECK_TRAVERSALS},
                                {grazing_label, grazing, n_grazing, 0},
                                {surface_label, surface, 2 * n, 0}};
        failures += check_sets(*s, &m, sets, 3, NULL);
        free(random);
        free(grazing);
        free(surface);
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* ---- closed meshes: no leaks --------------------------------------------------- */

/* Leak rays from each point of `insides` (every structure built once for
 * all of them), checked on every structure; the double-precision
 * reference must see no leak either. */
static unsigned leak_cases(const char *label, const sidx_mesh *m, const sidx_vec3 *insides, size_t count,
                           size_t max)
{
    ray_set sets[3];
    tk_rayrec *rays[3];
    char labels[3][80];
    unsigned failures = 0;
    assert_true(count <= 3);
    for (size_t k = 0; k < count; ++k) {
        rays[k] = malloc(max * sizeof *rays[k]);
        assert_non_null(rays[k]);
        const size_t n = tk_make_leak_rays(m, insides[k], max, rays[k]);
        if (count > 1) snprintf(labels[k], sizeof labels[k], "%s from inside #%zu", label, k);
        else snprintf(labels[k], sizeof labels[k], "%s", label);
        sets[k] = (ray_set){labels[k], rays[k], n, CHECK_ALL_HIT};
        unsigned ref_leaks = 0;
        for (size_t i = 0; i < n; ++i) {
            sidx_hit h;
            tk_ref_intersect(m, &rays[k][i], &h);
            if (h.prim == SIDX_NO_HIT && ref_leaks++ < 3)
                print_message("%s: reference leaks ray %zu\n", labels[k], i);
        }
        failures += ref_leaks;
    }
    failures += check_sets(label, m, sets, count, NULL);
    for (size_t k = 0; k < count; ++k) free(rays[k]);
    return failures;
}

static void test_icosphere_no_leaks(void **state)
{
    (void)state;
    unsigned failures = 0;
    const size_t max = tk_tiny_tests() ? 400 : tk_fast_tests() ? 1200 : 6000;
    for (uint32_t level = 1; level <= (tk_fast_tests() ? 2u : 3u); ++level) {
        sidx_mesh m = {0};
        assert_int_equal(sidx_scene_make("icosphere", level, &m, NULL), SIDX_OK);
        const sidx_vec3 c = sidx_aabb_centroid(sidx_mesh_bounds(&m));
        const sidx_vec3 insides[3] = {c, sidx_v3_add(c, sidx_v3(0.1f, -0.2f, 0.3f)),
                                      sidx_v3_add(c, sidx_v3(-0.5f, 0.25f, 0.125f))};
        char label[64];
        snprintf(label, sizeof label, "icosphere:%u", (unsigned)level);
        failures += leak_cases(label, &m, insides, 3, max);
        /* far from the origin and tiny: still closed, so still no leak */
        static const struct { double scale; float off; const char *what; } tf[] = {
            {100.0, 1e6f, "x100 at +1e6"}, {100.0, -1e6f, "x100 at -1e6"}, {1e-6, 0.0f, "x1e-6"}};
        for (size_t t = 0; t < 3; ++t) {
            sidx_mesh tm;
            assert_int_equal(tk_mesh_transform(&m, tf[t].scale, sidx_v3(tf[t].off, tf[t].off, -tf[t].off), &tm),
                             SIDX_OK);
            const sidx_vec3 tc = sidx_aabb_centroid(sidx_mesh_bounds(&tm));
            snprintf(label, sizeof label, "icosphere:%u %s", (unsigned)level, tf[t].what);
            failures += leak_cases(label, &tm, &tc, 1, max);
            sidx_mesh_free(&tm);
        }
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* Exact ±0 direction components, e.g. (0, -0, 1), through vertices of the
 * axis-aligned Menger sponge and Cornell box (coplanar faces, shared edges). */
static void test_axis_rays_signed_zero(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const char *const scenes[] = {"menger", "cornell", "grid", "icosphere"};
    for (size_t s = 0; s < 4; ++s) {
        sidx_mesh m;
        make_scene(scenes[s], &m);
        const sidx_aabb b = sidx_mesh_bounds(&m);
        const size_t per = nrays(40);
        tk_rayrec *r = malloc(6 * 4 * per * sizeof *r);
        assert_non_null(r);
        size_t n = 0;
        tk_rng g;
        tk_rng_seed(&g, 5 + s);
        for (int axis = 0; axis < 3; ++axis)
            for (int sign = 0; sign < 2; ++sign)
                for (int zeros = 0; zeros < 4; ++zeros)
                    for (size_t i = 0; i < per; ++i) {
                        float d[3];
                        for (int k = 0, bit = 0; k < 3; ++k) {
                            if (k == axis) d[k] = sign ? -1.0f : 1.0f;
                            else d[k] = ((zeros >> bit++) & 1) ? -0.0f : 0.0f;
                        }
                        /* origin: a vertex's other two coordinates, outside the box along the axis */
                        const uint32_t v = tk_rng_below(&g, m.num_vertices);
                        float o[3] = {m.positions[v].x, m.positions[v].y, m.positions[v].z};
                        o[axis] = sign ? sidx_v3_get(b.max, axis) + 1.0f : sidx_v3_get(b.min, axis) - 1.0f;
                        r[n++] = tk_rayrec_make(sidx_v3(o[0], o[1], o[2]), sidx_v3(d[0], d[1], d[2]), 0.0f,
                                                INFINITY);
                    }
        failures += check_case(scenes[s], &m, r, n, NULL, CHECK_TRAVERSALS);
        free(r);
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* ---- transformed scenes ---------------------------------------------------------- */

static void test_translated_and_scaled_scenes(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const tk_ray_kind kinds[] = {TK_RAYS_DIFFUSE, TK_RAYS_GRAZING, TK_RAYS_AXIS};
    static const struct { double scale; float ox, oy, oz; const char *what; } tf[] = {
        {1.0, 1e6f, 1e6f, 1e6f, "+1e6"}, {1.0, -1e6f, 1e6f, -1e6f, "-1e6"}, {1e-6, 0, 0, 0, "x1e-6"}};
    /* At the small sizes: the first six scenes, each under one of the
     * transforms in turn (every structure is built for each scene). */
    const int fast = tk_fast_tests();
    int count = 0;
    for (const char *const *s = sidx_scene_names(); *s && !(fast && count >= 6); ++s, ++count) {
        sidx_mesh m;
        make_scene(*s, &m);
        for (size_t t = fast ? (size_t)count % 3 : 0; t < (fast ? (size_t)count % 3 + 1 : 3); ++t) {
            sidx_mesh tm;
            assert_int_equal(tk_mesh_transform(&m, tf[t].scale, sidx_v3(tf[t].ox, tf[t].oy, tf[t].oz), &tm), SIDX_OK);
            char label[64];
            snprintf(label, sizeof label, "%s %s", *s, tf[t].what);
            failures += check_kinds(label, &tm, kinds, 3, nrays(80), 0);
            sidx_mesh_free(&tm);
        }
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* ---- odd geometry ------------------------------------------------------------------ */

static void mesh_from(sidx_mesh *m, const float *xyz, uint32_t nv, const uint32_t *idx, uint32_t nt)
{
    memset(m, 0, sizeof *m);
    sidx_error err = {SIDX_OK, ""};
    if (sidx_mesh_from_arrays(m, xyz, nv, idx, nt, &err) != SIDX_OK) fail_msg("mesh: %s", err.message);
}

/* Slivers (1e-7 wide), needles, collinear and repeated-vertex triangles among ordinary ones. */
static void test_slivers_and_zero_area(void **state)
{
    (void)state;
    tk_rng g;
    tk_rng_seed(&g, 77);
    enum { NT = 240 };
    float xyz[NT * 9];
    uint32_t idx[NT * 3];
    for (uint32_t t = 0; t < NT; ++t) {
        float *p = xyz + 9 * t;
        const float cx = (float)tk_rng_unit(&g), cy = (float)tk_rng_unit(&g), cz = (float)tk_rng_unit(&g);
        const float ex = (float)tk_rng_range(&g, -0.2, 0.2), ey = (float)tk_rng_range(&g, -0.2, 0.2),
                    ez = (float)tk_rng_range(&g, -0.2, 0.2);
        p[0] = cx; p[1] = cy; p[2] = cz;
        p[3] = cx + ex; p[4] = cy + ey; p[5] = cz + ez;
        switch (t % 6) {
        case 0: /* sliver: third vertex 1e-7 off the first edge */
            p[6] = cx + 0.5f * ex + 1e-7f; p[7] = cy + 0.5f * ey; p[8] = cz + 0.5f * ez - 1e-7f;
            break;
        case 1: /* collinear: zero area */
            p[6] = cx + 2.0f * ex; p[7] = cy + 2.0f * ey; p[8] = cz + 2.0f * ez;
            break;
        case 2: /* repeated vertex */
            p[6] = p[3]; p[7] = p[4]; p[8] = p[5];
            break;
        case 3: /* all three equal */
            p[3] = p[6] = cx; p[4] = p[7] = cy; p[5] = p[8] = cz;
            break;
        default: /* ordinary */
            p[6] = cx + (float)tk_rng_range(&g, -0.2, 0.2); p[7] = cy + (float)tk_rng_range(&g, -0.2, 0.2);
            p[8] = cz + (float)tk_rng_range(&g, -0.2, 0.2);
            break;
        }
        idx[3 * t] = 3 * t;
        idx[3 * t + 1] = 3 * t + 1;
        idx[3 * t + 2] = 3 * t + 2;
    }
    sidx_mesh m;
    mesh_from(&m, xyz, NT * 3, idx, NT);
    static const tk_ray_kind kinds[] = {TK_RAYS_DIFFUSE, TK_RAYS_GRAZING, TK_RAYS_AXIS, TK_RAYS_PRIMARY};
    unsigned failures = check_kinds("slivers", &m, kinds, 4, nrays(200), CHECK_TRAVERSALS);
    sidx_mesh_free(&m);
    assert_int_equal(failures, 0);
}

static void test_coincident_duplicates(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const char *const scenes[] = {"icosphere", "teapot", "menger"};
    static const tk_ray_kind kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE, TK_RAYS_GRAZING};
    for (size_t s = 0; s < 3; ++s) {
        sidx_mesh m, d;
        make_scene(scenes[s], &m);
        assert_int_equal(tk_mesh_duplicate_tris(&m, &d), SIDX_OK);
        char label[64];
        snprintf(label, sizeof label, "%s duplicated", scenes[s]);
        failures += check_kinds(label, &d, kinds, 3, nrays(120), 0);
        sidx_mesh_free(&d);
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* Every triangle in one plane: many overlapping coplanar triangles. */
static void test_flat_scenes(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const char *const scenes[] = {"teapot", "soup", "grid", "icosphere"};
    static const tk_ray_kind kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE, TK_RAYS_GRAZING, TK_RAYS_AXIS};
    for (size_t s = 0; s < 4; ++s) {
        sidx_mesh m, f;
        make_scene(scenes[s], &m);
        assert_int_equal(tk_mesh_flatten(&m, 0.25f, &f), SIDX_OK);
        char label[64];
        snprintf(label, sizeof label, "%s flattened", scenes[s]);
        failures += check_kinds(label, &f, kinds, 4, nrays(100), 0);
        sidx_mesh_free(&f);
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

static void test_single_triangle(void **state)
{
    (void)state;
    static const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const uint32_t idx[] = {0, 1, 2};
    sidx_mesh m;
    mesh_from(&m, xyz, 3, idx, 1);
    static const tk_ray_kind kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE, TK_RAYS_GRAZING, TK_RAYS_AXIS,
                                        TK_RAYS_SHADOW};
    unsigned failures = check_kinds("single triangle", &m, kinds, 5, nrays(100), CHECK_TRAVERSALS);
    /* straight at it: a hit with the expected t, u, v for every structure */
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.25f, 0.5f, 2.0f), sidx_v3(0, -0.0f, -1.0f), 0.0f, INFINITY),
                     SIDX_OK);
    for (size_t ai = 0; ai < sidx_accel_registered_count(); ++ai) {
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build(sidx_accel_registered_name(ai), &m, NULL, &a, NULL), SIDX_OK);
        sidx_hit h;
        sidx_query q = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
        assert_int_equal(sidx_accel_intersect(a, &r, &q, &h), SIDX_OK);
        assert_int_equal(h.prim, 0);
        assert_float_equal(h.t, 2.0f, 1e-6f);
        assert_float_equal(h.u, 0.25f, 1e-6f);
        assert_float_equal(h.v, 0.5f, 1e-6f);
        assert_float_equal(h.ng.z, 1.0f, 1e-6f);
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
    assert_int_equal(failures, 0);
}

/* An empty-ish scene: one degenerate triangle; every ray misses it, except
 * rays aimed exactly at a point of its segment (see degenerate_hit_ok). */
static void test_one_degenerate_triangle(void **state)
{
    (void)state;
    static const float xyz[] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    static const uint32_t idx[] = {0, 1, 2};
    sidx_mesh m;
    mesh_from(&m, xyz, 3, idx, 1);
    static const tk_ray_kind kinds[] = {TK_RAYS_DIFFUSE, TK_RAYS_GRAZING, TK_RAYS_AXIS};
    unsigned failures = check_kinds("one degenerate triangle", &m, kinds, 3, nrays(100), CHECK_ALL_MISS);
    sidx_mesh_free(&m);
    assert_int_equal(failures, 0);
}

/* No triangles at all: building may succeed (then every ray misses) or fail cleanly. */
static void test_empty_mesh(void **state)
{
    (void)state;
    sidx_mesh m = {NULL, NULL, 0, 0};
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, -1), sidx_v3(0, 0, 1), 0.0f, INFINITY), SIDX_OK);
    for (size_t ai = 0; ai < sidx_accel_registered_count(); ++ai) {
        const char *name = sidx_accel_registered_name(ai);
        sidx_accel *a = (sidx_accel *)&m; /* must be overwritten */
        sidx_status s = sidx_accel_build(name, &m, NULL, &a, NULL);
        if (s != SIDX_OK) {
            assert_null(a);
            continue;
        }
        sidx_hit h;
        int occ = 1;
        assert_int_equal(sidx_accel_intersect(a, &r, NULL, &h), SIDX_OK);
        assert_int_equal(h.prim, SIDX_NO_HIT);
        assert_true(isinf(h.t));
        assert_int_equal(sidx_accel_occluded(a, &r, NULL, &occ), SIDX_OK);
        assert_int_equal(occ, 0);
        sidx_accel_destroy(a);
    }
}

/* Same non-default triangle test on both sides: structures must agree with
 * brute force using that test (the box test is robust by default). */
static void test_other_triangle_tests(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const char *const scenes[] = {"teapot", "menger"};
    static const tk_ray_kind kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE};
    for (size_t s = 0; s < 2; ++s) {
        sidx_mesh m;
        make_scene(scenes[s], &m);
        size_t n;
        tk_rayrec *r = kinds_rays(&m, kinds, 2, nrays(100), 55, &n);
        for (int t = SIDX_TRI_MOLLER_TRUMBORE; t < SIDX_TRI_METHOD_COUNT; ++t) {
            sidx_build_options bo;
            memset(&bo, 0, sizeof bo);
            bo.tri = (sidx_tri_method)t;
            char label[64];
            snprintf(label, sizeof label, "%s with %s", scenes[s], sidx_tri_method_name(bo.tri));
            failures += check_case(label, &m, r, n, &bo, 0);
        }
        free(r);
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* ---- the reference itself ------------------------------------------------------------ */

/* u, v and the normal that bvh (and bvh-obb, bvh-sbvh), bvh4, bvh8 and kdtree keep
 * from their own traversal (from their copies of the triangles) are the
 * bits the core would compute from the mesh: the same triangle test re-run
 * on the hit triangle just past t, and (p1 - p0) x (p2 - p0) — and brute
 * force, which gets them from the core, agrees wherever it hits the same
 * triangle at the same t.  Every traversal, traced (a hook attached) and
 * not, UV and NORMAL asked together and alone (what is not asked stays 0),
 * and every triangle test. */
static int same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

static int attrs_ok(const sidx_mesh *m, sidx_tri_method tm, const sidx_ray *r, uint32_t flags, const sidx_hit *h,
                    const char **why)
{
    if (h->prim == SIDX_NO_HIT) return 1;
    const sidx_vec3 p0 = sidx_mesh_vertex(m, h->prim, 0), p1 = sidx_mesh_vertex(m, h->prim, 1),
                    p2 = sidx_mesh_vertex(m, h->prim, 2);
    float t = 0.0f, u = 0.0f, v = 0.0f;
    if (!sidx_intersect_triangle(tm, r, p0, p1, p2, nextafterf(h->t, INFINITY), &t, &u, &v)) {
        *why = "the hit triangle does not reproduce the hit";
        return 0;
    }
    const sidx_vec3 ng = sidx_v3_cross(sidx_v3_sub(p1, p0), sidx_v3_sub(p2, p0));
    if (!(flags & SIDX_QUERY_UV)) u = v = 0.0f;
    const sidx_vec3 want = (flags & SIDX_QUERY_NORMAL) ? ng : sidx_v3(0.0f, 0.0f, 0.0f);
    if (!same_bits(h->u, u) || !same_bits(h->v, v)) {
        *why = flags & SIDX_QUERY_UV ? "u, v differ from the mesh's" : "u, v filled although not asked for";
        return 0;
    }
    if (!same_bits(h->ng.x, want.x) || !same_bits(h->ng.y, want.y) || !same_bits(h->ng.z, want.z)) {
        *why = flags & SIDX_QUERY_NORMAL ? "normal differs from the mesh's" : "normal filled although not asked for";
        return 0;
    }
    return 1;
}

static void test_uv_normal_match_the_mesh(void **state)
{
    (void)state;
    static const char *const scenes[] = {"teapot", "icosphere", "soup", "cornell"};
    static const char *const accels[] = {"bvh", "bvh-obb", "bvh-sbvh", "bvh4", "bvh8", "kdtree", "kdtree-binned"};
    static const uint32_t flag_sets[] = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_QUERY_UV, SIDX_QUERY_NORMAL};
    static const tk_ray_kind kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE, TK_RAYS_GRAZING};
    const size_t n = tk_tiny_tests() ? 20 : tk_fast_tests() ? 60 : 250;
    unsigned failures = 0;
    size_t checked_hits = 0, brute_same = 0;
    for (size_t si = 0; si < sizeof scenes / sizeof scenes[0]; ++si) {
        sidx_mesh m = {0};
        sidx_error err;
        if (tk_fast_tests()) make_scene(scenes[si], &m); /* 6 structures x 3 triangle tests built per scene */
        else assert_int_equal(sidx_scene_open(scenes[si], &m, &err), SIDX_OK);
        tk_rayrec *rec = malloc(n * sizeof *rec);
        sidx_ray *rr = malloc(n * sizeof *rr);
        uint8_t *valid = malloc(n);
        assert_non_null(rec);
        assert_non_null(rr);
        assert_non_null(valid);
        for (int tm = 0; tm < SIDX_TRI_METHOD_COUNT; ++tm) {
            sidx_build_options bo;
            memset(&bo, 0, sizeof bo);
            bo.tri = (sidx_tri_method)tm;
            sidx_accel *brute = NULL;
            assert_int_equal(sidx_accel_build("brute", &m, &bo, &brute, &err), SIDX_OK);
            for (size_t ai = 0; ai < sizeof accels / sizeof accels[0]; ++ai) {
                if (!sidx_accel_is_registered(accels[ai])) continue;
                sidx_accel *a = NULL;
                assert_int_equal(sidx_accel_build(accels[ai], &m, &bo, &a, &err), SIDX_OK);
                for (size_t ki = 0; ki < sizeof kinds / sizeof kinds[0]; ++ki) {
                    tk_make_rays(&m, kinds[ki], n, 7 + ki, rec);
                    for (size_t i = 0; i < n; ++i) valid[i] = tk_ray_from(&rec[i], &rr[i]) == SIDX_OK;
                    for (size_t i = 0; i < n; ++i) {
                        if (!valid[i]) continue;
                        sidx_hit ref;
                        const sidx_query qb = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
                        sidx_accel_intersect(brute, &rr[i], &qb, &ref);
                        for (int tr = SIDX_TRAVERSE_DEFAULT; tr < SIDX_TRAVERSE_COUNT; ++tr)
                            for (int traced = 0; traced < 2; ++traced)
                                for (size_t fi = 0; fi < sizeof flag_sets / sizeof flag_sets[0]; ++fi) {
                                    sidx_counters c;
                                    sidx_counters_init(&c);
                                    sidx_hook hk = sidx_counters_hook(&c);
                                    const sidx_query q = {flag_sets[fi], (sidx_traversal)tr, traced ? &hk : NULL,
                                                          (uint32_t)i};
                                    sidx_hit h;
                                    sidx_accel_intersect(a, &rr[i], &q, &h);
                                    const char *why = NULL;
                                    if (!attrs_ok(&m, (sidx_tri_method)tm, &rr[i], flag_sets[fi], &h, &why)) {
                                        if (failures++ < 10)
                                            print_message("%s %s %s ray %zu (%s, traversal %d, traced %d, "
                                                          "flags %u): %s\n",
                                                          scenes[si], accels[ai], sidx_tri_method_name(bo.tri), i,
                                                          tk_ray_kind_name(kinds[ki]), tr, traced,
                                                          (unsigned)flag_sets[fi], why);
                                    }
                                    if (h.prim == SIDX_NO_HIT || fi != 0) continue;
                                    ++checked_hits;
                                    if (h.prim != ref.prim || !same_bits(h.t, ref.t)) continue;
                                    ++brute_same;
                                    if (!same_bits(h.u, ref.u) || !same_bits(h.v, ref.v) ||
                                        !same_bits(h.ng.x, ref.ng.x) || !same_bits(h.ng.y, ref.ng.y) ||
                                        !same_bits(h.ng.z, ref.ng.z)) {
                                        if (failures++ < 10)
                                            print_message("%s %s ray %zu: u, v, normal differ from brute "
                                                          "force's\n", scenes[si], accels[ai], i);
                                    }
                                }
                    }
                }
                sidx_accel_destroy(a);
            }
            sidx_accel_destroy(brute);
        }
        free(rec);
        free(rr);
        free(valid);
        sidx_mesh_free(&m);
    }
    print_message("u, v, normal: %zu hits checked against the mesh, %zu of them against brute force too\n",
                  checked_hits, brute_same);
    assert_int_equal(failures, 0);
    /* the comparison above is not vacuous: most rays hit, and on the same
     * triangle at the same t as brute force */
    assert_true(checked_hits > 500);
    assert_true(brute_same * 10 > checked_hits * 9);
}

static void test_reference_matches_brute_on_random_rays(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", &m);
    const size_t n = nrays(400);
    tk_rayrec *r = malloc(n * sizeof *r);
    assert_non_null(r);
    tk_make_rays(&m, TK_RAYS_DIFFUSE, n, 3, r);
    sidx_accel *b = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &b, NULL), SIDX_OK);
    size_t disagree = 0;
    for (size_t i = 0; i < n; ++i) {
        sidx_ray ray;
        sidx_hit hb, hr;
        assert_int_equal(tk_ray_from(&r[i], &ray), SIDX_OK);
        sidx_accel_intersect(b, &ray, NULL, &hb);
        tk_ref_intersect(&m, &r[i], &hr);
        disagree += !tk_hits_agree(&hr, &hb);
    }
    assert_true(disagree <= n / 100);
    /* and the threaded version gives the same as the plain one */
    sidx_hit *all = malloc(n * sizeof *all);
    assert_non_null(all);
    tk_ref_intersect_all(&m, r, n, all, 3);
    for (size_t i = 0; i < n; ++i) {
        sidx_hit h;
        tk_ref_intersect(&m, &r[i], &h);
        assert_int_equal(h.prim, all[i].prim);
    }
    free(all);
    sidx_accel_destroy(b);
    free(r);
    sidx_mesh_free(&m);
}

static void test_hits_agree_rule(void **state)
{
    (void)state;
    sidx_hit a = sidx_hit_none(), b = sidx_hit_none();
    assert_true(tk_hits_agree(&a, &b));
    a.prim = 3;
    a.t = 2.0f;
    assert_false(tk_hits_agree(&a, &b));
    b.prim = 4;
    b.t = 2.0f + 1e-5f;
    assert_true(tk_hits_agree(&a, &b));   /* coincident surfaces */
    b.t = 2.0f + 1e-4f;
    assert_false(tk_hits_agree(&a, &b));  /* a different surface */
    b.prim = 3;
    assert_true(tk_hits_agree(&a, &b));   /* same primitive */
    tk_errstats e;
    memset(&e, 0, sizeof e);
    sidx_hit none = sidx_hit_none();
    tk_errstats_add(&e, &a, &none);
    tk_errstats_add(&e, &none, &a);
    b.prim = 9;
    tk_errstats_add(&e, &a, &b);
    tk_errstats_add(&e, &a, &a);
    b.prim = 3;
    tk_errstats_add(&e, &a, &b);
    assert_int_equal(e.rays, 5);
    assert_int_equal(e.false_miss, 1);
    assert_int_equal(e.false_hit, 1);
    assert_int_equal(e.wrong_prim, 1);
    assert_true(e.max_rel_t > 4e-5 && e.max_rel_t < 6e-5);
}

/* ---- invalid arguments ------------------------------------------------------------------ */

static void test_invalid_arguments(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("icosphere", &m);
    static const uint32_t bad_idx[] = {0, 1, 7};
    static const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    sidx_mesh bad;
    memset(&bad, 0, sizeof bad);
    bad.positions = (sidx_vec3 *)(void *)xyz;
    bad.indices = (uint32_t *)bad_idx;
    bad.num_vertices = 3;
    bad.num_triangles = 1;
    static const float nan_xyz[] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    sidx_mesh nanm = bad;
    nanm.positions = (sidx_vec3 *)(void *)nan_xyz;
    nanm.indices = (uint32_t *)(const uint32_t[]){0, 1, 2};
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, -5), sidx_v3(0, 0, 1), 0.0f, INFINITY), SIDX_OK);
    assert_int_equal(sidx_accel_build("no-such-structure", &m, NULL, &(sidx_accel *){NULL}, NULL),
                     SIDX_ERR_UNKNOWN_ACCEL);
    for (size_t ai = 0; ai < sidx_accel_registered_count(); ++ai) {
        const char *name = sidx_accel_registered_name(ai);
        sidx_accel *a = (sidx_accel *)&m;
        sidx_error err = {SIDX_OK, ""};
        assert_int_equal(sidx_accel_build(name, NULL, NULL, &a, &err), SIDX_ERR_INVALID_ARG);
        assert_null(a);
        assert_int_equal(sidx_accel_build(name, &m, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
        a = (sidx_accel *)&m;
        assert_int_equal(sidx_accel_build(name, &bad, NULL, &a, &err), SIDX_ERR_BAD_GEOMETRY);
        assert_null(a);
        assert_true(err.message[0] != '\0');
        a = (sidx_accel *)&m;
        assert_int_equal(sidx_accel_build(name, &nanm, NULL, &a, NULL), SIDX_ERR_BAD_GEOMETRY);
        assert_null(a);
        sidx_build_options bo;
        memset(&bo, 0, sizeof bo);
        bo.tri = SIDX_TRI_METHOD_COUNT;
        assert_int_equal(sidx_accel_build(name, &m, &bo, &a, NULL), SIDX_ERR_INVALID_ARG);
        memset(&bo, 0, sizeof bo);
        bo.c_trav = -1.0f;
        assert_int_equal(sidx_accel_build(name, &m, &bo, &a, NULL), SIDX_ERR_INVALID_ARG);

        assert_int_equal(sidx_accel_build(name, &m, NULL, &a, &err), SIDX_OK);
        sidx_hit h;
        int occ = 0;
        sidx_accel_stats st;
        assert_int_equal(sidx_accel_intersect(NULL, &r, NULL, &h), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_intersect(a, NULL, NULL, &h), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_intersect(a, &r, NULL, NULL), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_occluded(NULL, &r, NULL, &occ), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_occluded(a, NULL, NULL, &occ), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_occluded(a, &r, NULL, NULL), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_intersect_n(a, NULL, 3, NULL, &h), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_intersect_n(a, &r, 1, NULL, NULL), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_intersect_n(a, NULL, 0, NULL, NULL), SIDX_OK);
        assert_int_equal(sidx_accel_stats_get(NULL, &st), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_stats_get(a, NULL), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_accel_stats_get(a, &st), SIDX_OK);
        assert_string_equal(st.name, name);
        assert_string_equal(sidx_accel_name(a), name);
        assert_ptr_equal(sidx_accel_mesh(a), &m);
        assert_non_null(sidx_accel_options(a));
        /* a sane ray through the sphere hits */
        assert_int_equal(sidx_accel_intersect(a, &r, NULL, &h), SIDX_OK);
        assert_int_not_equal(h.prim, SIDX_NO_HIT);
        sidx_accel_destroy(a);
    }
    assert_int_equal(sidx_accel_refit(NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_null(sidx_accel_name(NULL));
    assert_null(sidx_accel_mesh(NULL));
    assert_null(sidx_accel_registered_name(sidx_accel_registered_count()));
    assert_false(sidx_accel_is_registered(NULL));
    assert_false(sidx_accel_is_registered("no-such-structure"));
    sidx_accel_destroy(NULL);
    sidx_accel *a = (sidx_accel *)&m;
    assert_int_equal(sidx_accel_auto(NULL, NULL, &a, NULL), SIDX_ERR_INVALID_ARG);
    assert_null(a);
    assert_int_equal(sidx_accel_auto(&m, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    sidx_mesh_free(&m);
}

/* "auto" builds on every built-in scene and agrees with brute force. */
static void test_auto_on_every_scene(void **state)
{
    (void)state;
    for (const char *const *s = sidx_scene_names(); *s; ++s) {
        sidx_mesh m;
        make_scene(*s, &m);
        sidx_accel *a = NULL, *b = NULL;
        assert_int_equal(sidx_accel_build("auto", &m, NULL, &a, NULL), SIDX_OK);
        assert_true(sidx_accel_is_registered(sidx_accel_name(a)));
        assert_int_equal(sidx_accel_build("brute", &m, NULL, &b, NULL), SIDX_OK);
        const size_t n = nrays(100);
        tk_rayrec *r = malloc(n * sizeof *r);
        assert_non_null(r);
        tk_make_rays(&m, TK_RAYS_DIFFUSE, n, 8, r);
        for (size_t i = 0; i < n; ++i) {
            sidx_ray ray;
            sidx_hit ha, hb;
            assert_int_equal(tk_ray_from(&r[i], &ray), SIDX_OK);
            sidx_accel_intersect(a, &ray, NULL, &ha);
            sidx_accel_intersect(b, &ray, NULL, &hb);
            assert_true(tk_hits_agree(&hb, &ha));
        }
        free(r);
        sidx_accel_destroy(a);
        sidx_accel_destroy(b);
        sidx_mesh_free(&m);
    }
}

/* ---- sidx-bench's ray and hit files --------------------------------------------------- */

static void test_ray_file_round_trip_and_bad_sizes(void **state)
{
    (void)state;
    char dir[] = "/tmp/sidx-suite-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[64];
    snprintf(path, sizeof path, "%s/rays.bin", dir);
    tk_rayrec r[3] = {tk_rayrec_make(sidx_v3(1, 2, 3), sidx_v3(0, -0.0f, 1), 0.0f, INFINITY),
                      tk_rayrec_make(sidx_v3(-1e6f, 1e-6f, 0), sidx_v3(1, 1, 1), 1e-3f, 0.999f),
                      tk_rayrec_make(sidx_v3(0, 0, 0), sidx_v3(0, 0, -1), 0.0f, 5.0f)};
    assert_int_equal(tk_write_rays(path, r, 3, NULL), SIDX_OK);
    tk_rayrec *back = NULL;
    size_t n = 0;
    assert_int_equal(tk_read_rays(path, &back, &n, NULL), SIDX_OK);
    assert_int_equal(n, 3);
    assert_memory_equal(back, r, sizeof r); /* bit-exact, -0 included */
    assert_true(signbit(back[0].d[1]));
    free(back);
    /* on-disk layout: little-endian float32 */
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    unsigned char raw[32];
    assert_int_equal(fread(raw, 1, 32, f), 32);
    fclose(f);
    assert_int_equal(raw[0], 0x00);
    assert_int_equal(raw[3], 0x3f); /* 1.0f = 0x3f800000 */
    assert_int_equal(raw[2], 0x80);
    /* bad sizes */
    sidx_error err = {SIDX_OK, ""};
    unsigned char buf[65] = {0};
    for (size_t size = 1; size < 65; ++size) {
        if (size % 32 == 0) continue;
        assert_int_equal(tk_parse_rays(buf, size, &back, &n, &err), SIDX_ERR_PARSE);
        assert_null(back);
        assert_int_equal(n, 0);
    }
    assert_non_null(strstr(err.message, "multiple"));
    f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(buf, 1, 33, f), 33);
    fclose(f);
    assert_int_equal(tk_read_rays(path, &back, &n, &err), SIDX_ERR_PARSE);
    assert_non_null(strstr(err.message, path));
    assert_int_equal(tk_read_hits(path, (tk_hitrec **)&back, &n, &err), SIDX_ERR_PARSE);
    /* empty is fine: zero records */
    assert_int_equal(tk_parse_rays(buf, 0, &back, &n, NULL), SIDX_OK);
    assert_int_equal(n, 0);
    assert_null(back);
    /* missing file */
    assert_int_equal(tk_read_rays("/nonexistent/sidx/rays.bin", &back, &n, &err), SIDX_ERR_IO);
    assert_int_equal(tk_parse_rays(NULL, 32, &back, &n, NULL), SIDX_ERR_INVALID_ARG);
    unlink(path);
    rmdir(dir);
}

static void test_hit_file_round_trip_and_miss_record(void **state)
{
    (void)state;
    char dir[] = "/tmp/sidx-suite-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[64];
    snprintf(path, sizeof path, "%s/hits.bin", dir);
    sidx_hit h = sidx_hit_none();
    tk_hitrec recs[2];
    recs[0] = tk_hitrec_from(&h);
    assert_true(isinf(recs[0].t) && recs[0].t > 0);
    assert_int_equal(recs[0].prim, -1);
    assert_true(recs[0].u == 0.0f && recs[0].v == 0.0f);
    h.prim = 7;
    h.t = 1.5f;
    h.u = 0.25f;
    h.v = 0.5f;
    recs[1] = tk_hitrec_from(&h);
    assert_int_equal(tk_write_hits(path, recs, 2, NULL), SIDX_OK);
    tk_hitrec *back = NULL;
    size_t n = 0;
    assert_int_equal(tk_read_hits(path, &back, &n, NULL), SIDX_OK);
    assert_int_equal(n, 2);
    assert_memory_equal(back, recs, sizeof recs);
    free(back);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    unsigned char raw[16];
    assert_int_equal(fread(raw, 1, 16, f), 16);
    fclose(f);
    static const unsigned char miss[16] = {0, 0, 0x80, 0x7f, 0xff, 0xff, 0xff, 0xff, 0, 0, 0, 0, 0, 0, 0, 0};
    assert_memory_equal(raw, miss, 16);
    unsigned char buf[40] = {0};
    sidx_error err = {SIDX_OK, ""};
    for (size_t size = 1; size < 40; ++size)
        if (size % 16) assert_int_equal(tk_parse_hits(buf, size, &back, &n, &err), SIDX_ERR_PARSE);
    unlink(path);
    rmdir(dir);
}

static void test_ray_sets_are_deterministic(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", &m);
    for (int k = 0; k < TK_RAYS_KIND_COUNT; ++k) {
        tk_rayrec a[64], b[64], c[64];
        tk_make_rays(&m, (tk_ray_kind)k, 64, 42, a);
        tk_make_rays(&m, (tk_ray_kind)k, 64, 42, b);
        tk_make_rays(&m, (tk_ray_kind)k, 64, 43, c);
        assert_memory_equal(a, b, sizeof a);
        if (k != TK_RAYS_PRIMARY) assert_memory_not_equal(a, c, sizeof a);
        for (int i = 0; i < 64; ++i) {
            sidx_ray r;
            assert_int_equal(tk_ray_from(&a[i], &r), SIDX_OK);
        }
        if (k == TK_RAYS_SHADOW)
            for (int i = 0; i < 64; ++i) assert_true(a[i].tmin > 0 && a[i].tmax < 1);
        if (k == TK_RAYS_AXIS)
            for (int i = 0; i < 64; ++i) {
                int zeros = (a[i].d[0] == 0) + (a[i].d[1] == 0) + (a[i].d[2] == 0);
                assert_int_equal(zeros, 2);
            }
        tk_ray_kind parsed;
        assert_true(tk_ray_kind_parse(tk_ray_kind_name((tk_ray_kind)k), &parsed));
        assert_int_equal(parsed, k);
    }
    assert_false(tk_ray_kind_parse("nope", NULL));
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hits_agree_rule),
        cmocka_unit_test(test_ray_file_round_trip_and_bad_sizes),
        cmocka_unit_test(test_hit_file_round_trip_and_miss_record),
        cmocka_unit_test(test_ray_sets_are_deterministic),
        cmocka_unit_test(test_reference_matches_brute_on_random_rays),
        cmocka_unit_test(test_invalid_arguments),
        cmocka_unit_test(test_empty_mesh),
        cmocka_unit_test(test_single_triangle),
        cmocka_unit_test(test_one_degenerate_triangle),
        cmocka_unit_test(test_builtin_scenes),
        cmocka_unit_test(test_icosphere_no_leaks),
        cmocka_unit_test(test_axis_rays_signed_zero),
        cmocka_unit_test(test_translated_and_scaled_scenes),
        cmocka_unit_test(test_slivers_and_zero_area),
        cmocka_unit_test(test_coincident_duplicates),
        cmocka_unit_test(test_flat_scenes),
        cmocka_unit_test(test_other_triangle_tests),
        cmocka_unit_test(test_uv_normal_match_the_mesh),
        cmocka_unit_test(test_auto_on_every_scene),
    };
    install_limits();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
