/* 18_light_buffer.c — checker driver: the light buffer's cached occluder
 * (deck 000, "Directional Partitioning": "Variation: Light buffer (for
 * shadow rays)").  Reference: the library's sidx_lightbuffer_occluded with
 * one sidx_lightbuffer_cache per case, its events relayed; the student's
 * lb_shadow_test gets the same cell through sidx_lightbuffer_cell_get and
 * a cache of its own.  Per shadow ray both traces hold: the cell entered
 * (its list's length), every triangle test, TERMINATE (any hit / none) and
 * a HIT_UPDATE naming the cell's cached occluder after the ray. */
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "sidx/lightbuffer.h"

int lb_shadow_test(const sidx_lightbuffer_cell_view *cell, uint32_t *last, const sidx_ex *ex);

/* The slide's scene, by hand: a floor at z = 0, small occluders under a
 * light at (0, 0, 8), a square at z = 4 (t = 0.5 exactly from the floor's
 * centre) and a triangle through the light. */
static const float hand_xyz[] = {
    -6, -6, 0, 6, -6, 0, 6, 6, 0, -6, 6, 0,                 /* floor: tris 0, 1 */
    0, 0, 2, 1, 0, 2, 1, 1, 2, 0, 1, 2,                     /* occluder A at z = 2, x, y in [0, 1]: 2, 3 */
    2, 2, 3, 3, 2, 3, 3, 3, 3, 2, 3, 3,                     /* occluder B at z = 3, x, y in [2, 3]: 4, 5 */
    -2, -2, 4, -1, -2, 4, -1, -1, 4, -2, -1, 4,             /* occluder C at z = 4, x, y in [-2, -1]: 6, 7 */
    -1, -1, 7, 1, -1, 7, 0, 1, 9,                           /* through the light (0, 0, 8): 8 */
};
static const uint32_t hand_idx[] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7, 8, 9, 10, 8, 10, 11,
                                    12, 13, 14, 12, 14, 15, 16, 17, 18};

#define NSCENES 3
static const char *const scene_names[NSCENES] = {"hand", "cornell", "soup:60"};
static const sidx_vec3 lights[NSCENES] = {{0, 0, 8}, {2.78f, 5.2f, 2.79f}, {0.05f, 0.1f, -0.02f}};
static sidx_mesh meshes[NSCENES];

typedef struct lb_point { sidx_vec3 p; float tmin, tmax; } lb_point;

#define MAXPTS 48
typedef struct lb_case {
    const char *name;
    int scene;
    uint32_t res;
    int eager;
    int npts;            /* 0: random points on the scene's triangles, filled in setup */
    lb_point pts[MAXPTS];
    const char *rules;   /* the ids of the rules it tests */
    int tie;             /* setup moves pts[0].tmin until reach equals a listed triangle's dist */
} lb_case;

/* The hand-out's rules, in its order. */
enum { R_FIRST, R_CACHE_STAYS, R_ORDER, R_REACH, R_REACH_INCL, R_SKIP, R_RANGE, R_UPDATE, R_STOP, R_MISS, NRULES };
static const ex_rule rules[NRULES] = {
    {"cache-first", "a cell's cached occluder (*last != SIDX_NO_HIT) is tested first, before the list",
     "\"Store last found occluder in directional structure\" - \"Test entry first for next shadow test\": when the "
     "cell has a cached occluder (*last != SIDX_NO_HIT), test it before the list"},
    {"cache-hit-stays", "the cached occluder blocks: return 1, the cache stays as it is",
     "\"Store last found occluder in directional structure\": a triangle of the list that blocks the ray becomes the "
     "cell's cached occluder (*last = it); a cached one that still blocks stays, a miss changes nothing"},
    {"list-order", "the list is walked in its order, nearest to the light first",
     "when the cached occluder misses (or there is none), walk the cell's list nearest to the light first, testing "
     "every triangle up to reach"},
    {"reach-stop", "the walk stops (return 0) at the first triangle with dist > reach",
     "the list is sorted by distance from the light: stop at the first triangle with dist > reach, nothing after it "
     "can lie between the point and the light"},
    {"reach-inclusive", "a triangle with dist == reach is still tested (only dist > reach stops)",
     "only dist > reach stops the walk: a triangle exactly at reach (dist == reach) may still touch the shadow "
     "segment and is tested"},
    {"skip-cached", "the cached triangle is skipped in the list (tested in 1)",
     "the cached occluder was tested first: skip it in the list (tris[k] == the cached one)"},
    {"range-tmax", "each triangle is tested over [tmin, ray.tmax): a hit at or beyond tmax does not shadow p",
     "the shadow ray ends at the light: test over [tmin, ray.tmax) - an occluder at or beyond tmax (at or behind the "
     "light) does not shadow the point"},
    {"cache-update", "a list triangle that blocks becomes the cell's cached occluder (*last = it)",
     "\"Store last found occluder in directional structure\": a triangle of the list that blocks the ray becomes the "
     "cell's cached occluder (*last = it), so the next shadow ray of the cell tests it first"},
    {"stop-on-hit", "on a hit return 1 at once (any occluder will do, the cached one or the list's)",
     "on a hit stop: one occluder is enough for a shadow (return 1 at the first hit, the cached one or the list's)"},
    {"miss-unchanged", "the list ran out or reached reach: return 0, *last unchanged",
     "no occluder (the list ran out, or reach stopped it): return 0 and leave *last as it was - a miss says "
     "nothing about the next ray of the cell"},
};

/* Many rays per cell over a scene: the cache, the list and the reach all in play. */
#define RANDOM_RULES "cache-first cache-hit-stays list-order reach-stop skip-cached range-tmax cache-update stop-on-hit " \
                     "miss-unchanged"
static lb_case cases[] = {
    {"hand: a cell with no cached occluder (the first shadow ray)", 0, 2, 0, 1, {{{0.5f, 0.5f, 0}, 1e-3f, 1}},
     "list-order range-tmax cache-update stop-on-hit", 0},
    {"hand: the same occluder twice (the cache hits)", 0, 2, 0, 2,
     {{{0.5f, 0.5f, 0}, 1e-3f, 1}, {{0.75f, 0.25f, 0}, 1e-3f, 1}},
     "cache-first cache-hit-stays stop-on-hit", 0},
    {"hand: a cached occluder that misses this ray, then another occluder in the same cell", 0, 2, 0, 5,
     {{{0.5f, 0.5f, 0}, 1e-3f, 1}, {{5.0f, 0.5f, 0}, 1e-3f, 1}, {{4.5f, 4.5f, 0}, 1e-3f, 1},
      {{0.5f, 0.25f, 0}, 1e-3f, 1}, {{4.5f, 4.5f, 0}, 1e-3f, 1}},
     "cache-first skip-cached cache-update miss-unchanged", 0},
    {"hand: an occluder exactly at tmax (t = 0.5 = tmax), then inside", 0, 2, 0, 3,
     {{{-3, -3, 0}, 1e-3f, 0.5f}, {{-3, -3, 0}, 1e-3f, 0.5000001f}, {{-3, -3, 0}, 1e-3f, 1}},
     "range-tmax", 0},
    {"hand: a triangle through the light (t = 1 = tmax)", 0, 2, 1, 3,
     {{{0.5f, 0, 1}, 0, 1}, {{0, 3, 5}, 1e-3f, 1}, {{0.5f, -0.5f, 6}, 1e-3f, 1}}, "range-tmax", 0},
    {"hand: rays starting on a surface (on occluder A and the floor; tmin = 0 and 1e-3)", 0, 2, 1, 4,
     {{{0.5f, 0.5f, 2}, 0, 1}, {{0.5f, 0.5f, 2}, 1e-3f, 1}, {{3.5f, -4, 0}, 0, 1}, {{-1.5f, -1.5f, 4}, 0, 1}},
     "range-tmax list-order reach-stop", 0},
    {"hand: rays from above the occluders (nothing in reach)", 0, 4, 0, 3,
     {{{0.5f, 0.5f, 6}, 1e-3f, 1}, {{2.5f, 2.5f, 5}, 1e-3f, 1}, {{-1.5f, -1.5f, 7.5f}, 1e-3f, 1}},
     "reach-stop miss-unchanged", 0},
    {"hand: a triangle exactly at reach (dist == reach: it is still tested)", 0, 2, 0, 1, {{{3.5f, -4, 0}, 0, 1}},
     "reach-inclusive", 1},
    {"cornell, light under the ceiling, res 4, lazy: points on the surfaces", 1, 4, 0, 0, {{{0, 0, 0}, 0, 0}}, RANDOM_RULES, 0},
    {"cornell, res 2, eager: many rays per cell", 1, 2, 1, 0, {{{0, 0, 0}, 0, 0}}, RANDOM_RULES, 0},
    {"cornell, res 16, lazy", 1, 16, 0, 0, {{{0, 0, 0}, 0, 0}}, RANDOM_RULES, 0},
    {"soup:60, light inside the soup, res 2, lazy", 2, 2, 0, 0, {{{0, 0, 0}, 0, 0}}, RANDOM_RULES, 0},
    {"soup:60, res 4, eager, tmin = 0 (rays start on their triangle)", 2, 4, 1, 0, {{{0, 0, 0}, 0, 0}}, RANDOM_RULES, 0},
};
#define NCASES (sizeof cases / sizeof cases[0])
static sidx_lightbuffer *lbs[NCASES];

static float reach_at(const sidx_lightbuffer *lb, sidx_vec3 p, float tmin, sidx_lightbuffer_cell_view *v)
{
    sidx_ray r;
    if (sidx_lightbuffer_shadow_ray(lb, p, tmin, 1.0f, &r) != SIDX_OK || sidx_lightbuffer_cell_get(lb, &r, v) != SIDX_OK)
        return -1.0f;
    return v->reach;
}

/* The tmin (by bisection over the floats of [0, 1)) at which the reach of
 * pts[0]'s shadow ray equals the distance of the farthest listed triangle
 * within reach at tmin = 0: the tie of "dist > reach". */
static int make_tie(lb_case *c, const sidx_lightbuffer *lb)
{
    sidx_lightbuffer_cell_view v;
    const float r0 = reach_at(lb, c->pts[0].p, 0.0f, &v);
    float target = -1.0f;
    for (uint32_t k = 0; k < v.count; ++k)
        if (v.dist[k] < r0 && v.dist[k] > target) target = v.dist[k];
    if (!(target > 0.0f)) return -1;
    uint32_t lo = 0, hi = 0x3f800000u; /* the bits of 0 and 1 */
    while (hi - lo > 1) {
        const uint32_t mid = lo + (hi - lo) / 2;
        float t;
        memcpy(&t, &mid, sizeof t);
        if (reach_at(lb, c->pts[0].p, t, &v) <= target) hi = mid;
        else lo = mid;
    }
    float t;
    memcpy(&t, &hi, sizeof t);
    if (reach_at(lb, c->pts[0].p, t, &v) != target) return -1;
    c->pts[0].tmin = t;
    return 0;
}

static int setup(void)
{
    if (sidx_mesh_from_arrays(&meshes[0], hand_xyz, (uint32_t)(sizeof hand_xyz / sizeof hand_xyz[0] / 3), hand_idx,
                              (uint32_t)(sizeof hand_idx / sizeof hand_idx[0] / 3), NULL) != SIDX_OK)
        return -1;
    for (int s = 1; s < NSCENES; ++s)
        if (sidx_scene_open(scene_names[s], &meshes[s], NULL) != SIDX_OK) return -1;
    uint32_t seed = 18u;
    for (size_t i = 0; i < NCASES; ++i) {
        lb_case *c = &cases[i];
        if (sidx_lightbuffer_build(&meshes[c->scene], lights[c->scene], c->res, c->eager, NULL, &lbs[i], NULL) !=
            SIDX_OK)
            return -1;
        if (c->tie && make_tie(c, lbs[i]) != 0) return -1;
        if (c->npts) continue;
        const sidx_mesh *m = &meshes[c->scene];
        const int zero_tmin = strstr(c->name, "tmin = 0") != NULL;
        for (int k = 0; k < MAXPTS; ++k) {
            const uint32_t tri = (uint32_t)(ex_rand(&seed) * (float)m->num_triangles) % m->num_triangles;
            float u = ex_rand(&seed), v = ex_rand(&seed);
            if (u + v > 1) { u = 1 - u; v = 1 - v; }
            const sidx_vec3 a = sidx_mesh_vertex(m, tri, 0), b = sidx_mesh_vertex(m, tri, 1),
                            cc = sidx_mesh_vertex(m, tri, 2);
            c->pts[k].p = sidx_v3_add(a, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(b, a), u),
                                                     sidx_v3_scale(sidx_v3_sub(cc, a), v)));
            c->pts[k].tmin = zero_tmin ? 0.0f : 1e-3f;
            c->pts[k].tmax = (k % 5 == 4) ? 0.5f : 1.0f - 1e-3f;
        }
        c->npts = MAXPTS;
    }
    return 0;
}

static void teardown(void)
{
    for (size_t i = 0; i < NCASES; ++i) sidx_lightbuffer_destroy(lbs[i]);
    for (int s = 0; s < NSCENES; ++s) sidx_mesh_free(&meshes[s]);
}

static size_t num_cases(void) { return NCASES; }

static void describe(size_t i, ex_case_info *out)
{
    const lb_case *c = &cases[i];
    snprintf(out->name, sizeof out->name, "%s", c->name);
    int n = snprintf(out->what, sizeof out->what, "light (%.9g, %.9g, %.9g), res %u, %s; %d shadow rays from",
                     (double)lights[c->scene].x, (double)lights[c->scene].y, (double)lights[c->scene].z, c->res,
                     c->eager ? "eager" : "lazy", c->npts);
    for (int k = 0; k < c->npts && k < 4 && n > 0 && (size_t)n < sizeof out->what; ++k)
        n += snprintf(out->what + n, sizeof out->what - (size_t)n, " (%.9g, %.9g, %.9g) t in [%g, %.9g)",
                      (double)c->pts[k].p.x, (double)c->pts[k].p.y, (double)c->pts[k].p.z,
                      (double)c->pts[k].tmin, (double)c->pts[k].tmax);
    if (c->npts > 4 && n > 0 && (size_t)n < sizeof out->what)
        snprintf(out->what + n, sizeof out->what - (size_t)n, " ...");
    out->hint = rules[R_FIRST].hint;
    out->rules = c->rules;
}

/* Events both sides emit alike: the cell, TERMINATE, the cache after the
 * ray.  Not compared, for the hint: PRIM_TEST carries in aux bit 0 that its
 * triangle is the cell's cached occluder at the ray's start, bit 1 that
 * its dist equals the cell's reach; the cache's HIT_UPDATE carries in aux
 * how the ray ended (0 lit, 1 a list triangle blocked it, 2 the cached
 * one did). */
static void emit(const sidx_hook *h, sidx_event e)
{
    e.structure = "lightbuffer";
    if (h && h->fn && (!h->mask || (h->mask & SIDX_EVMASK(e.type)))) h->fn(&e, h->user);
}

static void emit_cell(const sidx_hook *h, uint32_t ray, uint32_t id, int f, int ci, int cj, uint32_t count)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NODE_ENTER);
    e.ray_id = ray;
    e.node = id;
    e.depth = 0;
    e.cell[0] = f;
    e.cell[1] = ci;
    e.cell[2] = cj;
    e.count = count;
    e.t_near = e.t_far = 0.0f;
    emit(h, e);
}

static void emit_end(const sidx_hook *h, int occluded, uint32_t cached, uint32_t how)
{
    sidx_event e = sidx_event_blank(SIDX_EV_TERMINATE);
    e.reason = occluded ? SIDX_TERM_ANY_HIT : SIDX_TERM_STACK_EMPTY;
    e.t = 0.0f;
    e.count = 0;
    emit(h, e);
    e = sidx_event_blank(SIDX_EV_HIT_UPDATE);
    e.prim = cached;
    e.t = 0.0f;
    e.aux = how;
    emit(h, e);
}

/* aux of a PRIM_TEST of triangle prim in cell v, cached the cell's cached occluder. */
static uint32_t test_aux(const sidx_lightbuffer_cell_view *v, uint32_t prim, uint32_t cached)
{
    uint32_t aux = prim == cached;
    for (uint32_t k = 0; v && k < v->count; ++k)
        if (v->tris[k] == prim && v->dist[k] == v->reach) aux |= 2;
    return aux;
}

typedef struct relay {
    const sidx_hook *h;
    const uint32_t *last; /* the cache slots */
    uint32_t cell, cached;
    const sidx_lightbuffer_cell_view *view; /* the ray's cell, or NULL */
    uint32_t how;                           /* 1: a list triangle hit, 2: the cached one */
} relay;

static void ref_fn(const sidx_event *ev, void *user)
{
    relay *r = user;
    if (ev->type == SIDX_EV_NODE_ENTER) {
        r->cell = ev->node;
        r->cached = r->last[ev->node];
        emit_cell(r->h, ev->ray_id, ev->node, ev->cell[0], ev->cell[1], ev->cell[2], ev->count);
    } else if (ev->type == SIDX_EV_PRIM_TEST) {
        sidx_event e = sidx_event_blank(SIDX_EV_PRIM_TEST);
        e.prim = ev->prim;
        e.result = ev->result ? 1 : 0;
        e.t = ev->result ? ev->t : INFINITY;
        e.aux = test_aux(r->view, ev->prim, r->cached);
        if (ev->result) r->how = ev->prim == r->cached ? 2 : 1;
        emit(r->h, e);
    }
}

static void reference(size_t i, const sidx_hook *h)
{
    const lb_case *c = &cases[i];
    sidx_lightbuffer_cache cache;
    if (sidx_lightbuffer_cache_init(lbs[i], &cache) != SIDX_OK) return;
    relay r = {h, cache.last, 0, SIDX_NO_HIT, NULL, 0};
    const sidx_hook lib = {ref_fn, &r, SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    for (int k = 0; k < c->npts; ++k) {
        const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &lib, (uint32_t)k};
        int occ = 0;
        sidx_ray ray;
        sidx_lightbuffer_cell_view view;
        r.view = sidx_lightbuffer_shadow_ray(lbs[i], c->pts[k].p, c->pts[k].tmin, c->pts[k].tmax, &ray) == SIDX_OK &&
                         sidx_lightbuffer_cell_get(lbs[i], &ray, &view) == SIDX_OK
                     ? &view
                     : NULL;
        r.how = 0;
        if (sidx_lightbuffer_occluded(lbs[i], c->pts[k].p, c->pts[k].tmin, c->pts[k].tmax, &cache, &q, &occ) !=
            SIDX_OK)
            break;
        emit_end(h, occ, cache.last[r.cell], occ ? r.how : 0);
    }
    sidx_lightbuffer_cache_free(&cache);
}

typedef struct stu_relay {
    const sidx_hook *h;
    uint32_t cached;
    const sidx_lightbuffer_cell_view *view;
} stu_relay;

static void stu_fn(const sidx_event *ev, void *user)
{
    const stu_relay *r = user;
    sidx_event e = *ev;
    if (e.type == SIDX_EV_PRIM_TEST) e.aux = test_aux(r->view, e.prim, r->cached);
    emit(r->h, e);
}

static void student(size_t i, const sidx_hook *h)
{
    const lb_case *c = &cases[i];
    sidx_lightbuffer_stats st;
    if (sidx_lightbuffer_stats_get(lbs[i], &st) != SIDX_OK) return;
    uint32_t *last = malloc((size_t)st.cells * sizeof *last);
    if (!last) return;
    for (uint32_t k = 0; k < st.cells; ++k) last[k] = SIDX_NO_HIT;
    for (int k = 0; k < c->npts; ++k) {
        sidx_ray ray;
        sidx_lightbuffer_cell_view cell;
        if (sidx_lightbuffer_shadow_ray(lbs[i], c->pts[k].p, c->pts[k].tmin, c->pts[k].tmax, &ray) != SIDX_OK ||
            sidx_lightbuffer_cell_get(lbs[i], &ray, &cell) != SIDX_OK)
            break;
        emit_cell(h, (uint32_t)k, cell.id, cell.face, cell.i, cell.j, cell.count);
        stu_relay r = {h, last[cell.id], &cell};
        const sidx_hook sh = {stu_fn, &r, SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
        sidx_ex ex;
        memset(&ex, 0, sizeof ex);
        ex.hook = &sh;
        ex.ray_id = (uint32_t)k;
        ex.structure = "lightbuffer";
        ex.ray = &ray;
        ex.mesh = &meshes[c->scene];
        ex.tri = SIDX_TRI_WATERTIGHT;
        uint32_t slot = last[cell.id];
        const int occ = lb_shadow_test(&cell, &slot, &ex);
        last[cell.id] = slot;
        emit_end(h, occ, slot, 0);
    }
    free(last);
}

/* The hint by what differs at the first divergence. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    (void)i;
    if (!ref || !stu) return rules[R_STOP].hint;
    if (ref->type == SIDX_EV_HIT_UPDATE && stu->type == SIDX_EV_HIT_UPDATE) {
        /* the cache after the ray: the verdicts agreed (TERMINATE came first) */
        return ref->aux == 2 ? rules[R_CACHE_STAYS].hint : ref->aux == 1 ? rules[R_UPDATE].hint : rules[R_MISS].hint;
    }
    if (ref->type == SIDX_EV_HIT_UPDATE || stu->type == SIDX_EV_HIT_UPDATE) return rules[R_UPDATE].hint;
    if (ref->type == SIDX_EV_PRIM_TEST && (ref->aux & 1) && !(stu->type == SIDX_EV_PRIM_TEST && stu->prim == ref->prim))
        return rules[R_FIRST].hint;
    if (ref->type == SIDX_EV_PRIM_TEST && stu->type == SIDX_EV_PRIM_TEST) {
        if (ref->prim == stu->prim) return rules[R_RANGE].hint;
        if (stu->aux & 1) return rules[R_SKIP].hint;
        return rules[R_ORDER].hint;
    }
    if (ref->type == SIDX_EV_TERMINATE && stu->type == SIDX_EV_PRIM_TEST)
        return ref->reason == SIDX_TERM_ANY_HIT ? rules[R_STOP].hint : rules[R_REACH].hint;
    if (ref->type == SIDX_EV_PRIM_TEST && stu->type == SIDX_EV_TERMINATE) {
        if (stu->reason == SIDX_TERM_ANY_HIT) return rules[R_STOP].hint;
        return ref->aux & 2 ? rules[R_REACH_INCL].hint : rules[R_ORDER].hint;
    }
    return rules[R_STOP].hint;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    static const char *const faces[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
    if (e->type == SIDX_EV_NODE_ENTER)
        snprintf(buf, size, "shadow ray %u: cell %u (face %s, i %d, j %d), %u triangles listed", e->ray_id, e->node,
                 faces[e->cell[0] >= 0 && e->cell[0] < 6 ? e->cell[0] : 0], e->cell[1], e->cell[2], e->count);
    else if (e->type == SIDX_EV_PRIM_TEST && e->result)
        snprintf(buf, size, "triangle %u test%s: hit t=%g", e->prim, e->aux & 1 ? " (the cached occluder)" : "",
                 (double)e->t);
    else if (e->type == SIDX_EV_PRIM_TEST)
        snprintf(buf, size, "triangle %u test%s: miss", e->prim, e->aux & 1 ? " (the cached occluder)" : "");
    else if (e->type == SIDX_EV_TERMINATE)
        snprintf(buf, size, "%s", e->reason == SIDX_TERM_ANY_HIT ? "in shadow (return 1)" : "lit (return 0)");
    else if (e->type == SIDX_EV_HIT_UPDATE && e->prim == SIDX_NO_HIT)
        snprintf(buf, size, "the cell's cached occluder: none");
    else if (e->type == SIDX_EV_HIT_UPDATE)
        snprintf(buf, size, "the cell's cached occluder: triangle %u", e->prim);
    else return 0;
    return 1;
}

const ex_driver ex_driver_this = {
    "18_light_buffer",
    "the light buffer's cached occluder: test the cell's last occluder first, then its list",
    "deck 000, \"Directional Partitioning\" (\"Variation: Light buffer (for shadow rays)\")",
    setup, num_cases, describe, reference, student, hint, teardown, format, rules, NRULES,
};
