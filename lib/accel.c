/* accel.c — the common accelerator interface: the registry, build,
 * queries (with RAY_BEGIN / RAY_END events, the final hit finished once
 * by sidx__hit_finish, hit.c), statistics and "auto". */
#include <stdio.h>
#include "sidx_internal.h"
#include "hit.h"
#include "lazy.h"

#define SIDX_STRUCTURE_NAME "accel"

typedef struct registry_entry {
    const char *name;
    const sidx_accel_vtable *vt;
    int variant;
    const char *description;
} registry_entry;

static const registry_entry registry[] = {
#define SIDX_ACCEL(name, vt, variant, desc) {name, &vt, variant, desc},
#include "accel_registry.def"
#undef SIDX_ACCEL
};
#define REGISTRY_SIZE (sizeof registry / sizeof registry[0])

size_t sidx_accel_registered_count(void) { return REGISTRY_SIZE; }
const char *sidx_accel_registered_name(size_t i) { return i < REGISTRY_SIZE ? registry[i].name : NULL; }
const char *sidx_accel_registered_description(size_t i)
{
    return i < REGISTRY_SIZE ? registry[i].description : NULL;
}

static const registry_entry *find_entry(const char *name)
{
    if (!name) return NULL;
    for (size_t i = 0; i < REGISTRY_SIZE; ++i)
        if (strcmp(registry[i].name, name) == 0) return &registry[i];
    return NULL;
}
int sidx_accel_is_registered(const char *name) { return find_entry(name) != NULL || (name && !strcmp(name, "auto")); }

static void *default_alloc(size_t size, void *user) { (void)user; return malloc(size); }
static void default_free(void *p, void *user) { (void)user; free(p); }

sidx_status sidx__accel_build_with(const char *name, const sidx_accel_vtable *vt, int variant, const sidx_mesh *mesh,
                                   const sidx_build_options *opt, sidx__build_fn build, void *arg, sidx_accel **out,
                                   sidx_error *err)
{
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    if (opt) o = *opt;
    if ((unsigned)o.tri >= SIDX_TRI_METHOD_COUNT || (unsigned)o.box >= SIDX_BOX_METHOD_COUNT || !(o.c_trav >= 0.0f) ||
        !(o.c_tri >= 0.0f) || !(o.empty_bonus >= 0.0f && o.empty_bonus < 1.0f) || !(o.grid_density >= 0.0f) ||
        isinf(o.grid_density) || isinf(o.c_trav) || isinf(o.c_tri) || !(o.optimize_ms >= 0.0f))
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "build options out of range");
    sidx_status s = sidx_mesh_validate(mesh, err);
    if (s != SIDX_OK) return s;

    sidx_allocator al = {default_alloc, default_free, NULL};
    if (o.alloc) {
        if (!o.alloc->alloc || !o.alloc->free)
            return sidx__fail(err, SIDX_ERR_INVALID_ARG, "allocator needs both alloc and free");
        al = *o.alloc;
    }
    sidx_accel *a = al.alloc(sizeof *a, al.user);
    if (!a) return sidx__fail(err, SIDX_ERR_NOMEM, "out of memory allocating the %s structure", name);
    memset(a, 0, sizeof *a);
    a->vt = vt;
    a->name = name;
    a->variant = variant;
    a->mesh = mesh;
    a->opt = o;
    a->alloc = al;
    s = build(a, arg, err);
    a->opt.hook = NULL; /* the build hook is the caller's; do not keep it */
    a->opt.alloc = NULL;
    if (s != SIDX_OK) {
        if (err && err->message[0] == '\0') sidx__fail(err, s, "building %s: %s", name, sidx_status_str(s));
        al.free(a, al.user);
        return s;
    }
    *out = a;
    return SIDX_OK;
}

static sidx_status vtable_build(sidx_accel *a, void *arg, sidx_error *err)
{
    (void)arg;
    return a->vt->build(a, err);
}

static sidx_status build_entry(const registry_entry *e, const sidx_mesh *mesh, const sidx_build_options *opt,
                               sidx_accel **out, sidx_error *err)
{
    return sidx__accel_build_with(e->name, e->vt, e->variant, mesh, opt, vtable_build, NULL, out, err);
}

sidx_status sidx_accel_build(const char *name, const sidx_mesh *mesh, const sidx_build_options *opt,
                             sidx_accel **out, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "out is NULL");
    *out = NULL;
    if (!name || !mesh) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "name or mesh is NULL");
    if (strcmp(name, "auto") == 0) return sidx_accel_auto(mesh, opt, out, err);
    const registry_entry *e = find_entry(name);
    if (!e) return sidx__fail(err, SIDX_ERR_UNKNOWN_ACCEL, "no structure named '%s'", name);
    return build_entry(e, mesh, opt, out, err);
}

/* At or below this many triangles a structure's set-up and traversal
 * overhead is more than testing every triangle; above it the BVH wins,
 * on primary rays (most miss the root box) from the smallest scenes on
 * (figures: docs/performance.md, "The automatic choice"). */
#define AUTO_BRUTE_MAX_TRIS 4u
#define AUTO_FLAT_KDTREE_MAX_TRIS 65536u

sidx_status sidx_accel_auto(const sidx_mesh *mesh, const sidx_build_options *opt, sidx_accel **out, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "out is NULL");
    *out = NULL;
    if (!mesh) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "mesh is NULL");
    const char *choice, *why;
    /* A BVH adapts to any density; a uniform grid collapses on uneven
     * scenes (teapot in a stadium), so it is never the automatic pick.
     * The wide BVHs, when registered, beat the binary one on every scene
     * `sidx-bench run` measures, so the widest one registered wins
     * (docs/performance.md, "The automatic choice"). */
    static const char *const bvh_pref[] = {"bvh8", "bvh4", "bvh"};
    const char *bvh = NULL;
    for (size_t i = 0; i < sizeof bvh_pref / sizeof bvh_pref[0] && !bvh; ++i)
        if (find_entry(bvh_pref[i])) bvh = bvh_pref[i];
    /* A flat scene (every triangle in one plane: the box has no thickness)
     * of moderate size: the kd-tree's cells tile the plane without overlap
     * and beat the BVHs; on large flat scenes the 8-wide BVH is faster
     * again (docs/performance.md, "The automatic choice"). */
    const sidx_aabb box = sidx_mesh_bounds(mesh);
    const sidx_vec3 ext = sidx_aabb_extent(box);
    const float lo = fminf(ext.x, fminf(ext.y, ext.z)), hi = fmaxf(ext.x, fmaxf(ext.y, ext.z));
    const int flat = !sidx_aabb_is_empty(box) && lo <= 1e-6f * hi && hi > 0.0f;
    if (mesh->num_triangles <= AUTO_BRUTE_MAX_TRIS || !bvh) {
        choice = "brute";
        why = "auto: tiny scene (<= 4 triangles): testing every triangle beats building a structure";
    } else if (flat && mesh->num_triangles < AUTO_FLAT_KDTREE_MAX_TRIS && find_entry("kdtree-binned")) {
        choice = "kdtree-binned";
        why = "auto: flat scene (all triangles in one plane), < 65536 triangles: binned kd-tree, measured fastest";
    } else if (bvh[3] == '8') {
        choice = bvh;
        why = "auto: 8-wide binned-SAH BVH: adapts to uneven density and has the best measured Mrays/s";
    } else if (bvh[3] == '4') {
        choice = bvh;
        why = "auto: 4-wide binned-SAH BVH: adapts to uneven density and has the best measured Mrays/s";
    } else {
        choice = bvh;
        why = "auto: binned-SAH BVH: adapts to uneven density and has the best measured Mrays/s";
    }
    if (opt && opt->hook) {
        sidx_event ev = sidx_event_blank(SIDX_EV_NOTE);
        ev.structure = "auto";
        ev.text = why;
        ev.count = mesh->num_triangles;
        sidx_hook_emit(opt->hook, &ev);
    }
    return build_entry(find_entry(choice), mesh, opt, out, err);
}

static const sidx_query default_query = {0, SIDX_TRAVERSE_DEFAULT, NULL, 0};

/* A traced query: the same steps between its RAY_BEGIN and RAY_END
 * events.  A function of its own so that the untraced call below needs
 * no event on its stack and stays a short frame around the structure's
 * walk: it runs once per ray, a visible share of a short walk such as
 * bvh8's (docs/performance.md, "The entry path"). */
static SIDX_NOINLINE void intersect_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,
                                           sidx_hit *hit)
{
    const int traced = 1;
    SIDX_EMIT(traced, q->hook, SIDX_EV_RAY_BEGIN, e_.structure = a->name; e_.ray_id = q->ray_id;
              e_.t_near = r->tmin; e_.t_far = r->tmax);
    a->vt->intersect(a, r, q, hit);
    sidx__finish_hit(a, r, q, hit);
    SIDX_EMIT(traced, q->hook, SIDX_EV_RAY_END, e_.structure = a->name; e_.ray_id = q->ray_id; e_.prim = hit->prim;
              e_.t = hit->t; e_.result = hit->prim != SIDX_NO_HIT);
}


/* A query on a lazy tree: the walk may expand nodes, and an expansion
 * without memory makes the query fail (sidx_internal.h). */
static SIDX_NOINLINE sidx_status intersect_lazy(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,
                                                sidx_hit *hit)
{
    sidx__lazy_failed = 0;
    if (SIDX_QUERY_TRACED(q)) {
        intersect_traced(a, r, q, hit);
    } else {
        a->vt->intersect(a, r, q, hit);
        sidx__finish_hit(a, r, q, hit);
    }
    return sidx__lazy_failed ? SIDX_ERR_NOMEM : SIDX_OK;
}

sidx_status sidx_accel_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    if (!a || !r || !hit) return SIDX_ERR_INVALID_ARG;
    if (!q) q = &default_query;
    *hit = sidx_hit_none();
    hit->t = r->tmax;
    if (SIDX_UNLIKELY(a->lazy)) return intersect_lazy(a, r, q, hit);
    if (SIDX_QUERY_TRACED(q)) {
        intersect_traced(a, r, q, hit);
        return SIDX_OK;
    }
    a->vt->intersect(a, r, q, hit);
    sidx__finish_hit(a, r, q, hit);
    return SIDX_OK;
}

sidx_status sidx_accel_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, int *occluded)
{
    if (!a || !r || !occluded) return SIDX_ERR_INVALID_ARG;
    if (!q) q = &default_query;
    const int traced = SIDX_QUERY_TRACED(q);
    SIDX_EMIT(traced, q->hook, SIDX_EV_RAY_BEGIN, e_.structure = a->name; e_.ray_id = q->ray_id;
              e_.t_near = r->tmin; e_.t_far = r->tmax);
    if (a->lazy) sidx__lazy_failed = 0;
    *occluded = a->vt->occluded(a, r, q) ? 1 : 0;
    SIDX_EMIT(traced, q->hook, SIDX_EV_RAY_END, e_.structure = a->name; e_.ray_id = q->ray_id;
              e_.result = *occluded);
    return a->lazy && sidx__lazy_failed ? SIDX_ERR_NOMEM : SIDX_OK;
}

/* A buffer of rays: the stream walk where the structure has one
 * (bvh_stream.c), else ray by ray; either way each ray's answer, status
 * and events are those of a single query with ray id q->ray_id + i. */
sidx_status sidx_accel_intersect_n(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                   sidx_hit *hits)
{
    if (!a || (n && (!rays || !hits))) return SIDX_ERR_INVALID_ARG;
    sidx_query qq = q ? *q : default_query;
    if (n && sidx__bvh_stream(a, rays, n, &qq, hits, NULL)) return SIDX_OK;
    const uint32_t base = qq.ray_id;
    sidx_status st = SIDX_OK;
    for (size_t i = 0; i < n; ++i) {
        qq.ray_id = base + (uint32_t)i;
        if (sidx_accel_intersect(a, &rays[i], &qq, &hits[i]) != SIDX_OK) st = SIDX_ERR_NOMEM;
    }
    return st;
}

sidx_status sidx_accel_occluded_n(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                  int *occluded)
{
    if (!a || (n && (!rays || !occluded))) return SIDX_ERR_INVALID_ARG;
    sidx_query qq = q ? *q : default_query;
    if (n && sidx__bvh_stream(a, rays, n, &qq, NULL, occluded)) return SIDX_OK;
    const uint32_t base = qq.ray_id;
    sidx_status st = SIDX_OK;
    for (size_t i = 0; i < n; ++i) {
        qq.ray_id = base + (uint32_t)i;
        if (sidx_accel_occluded(a, &rays[i], &qq, &occluded[i]) != SIDX_OK) st = SIDX_ERR_NOMEM;
    }
    return st;
}

sidx_status sidx_accel_stats_get(const sidx_accel *a, sidx_accel_stats *s)
{
    if (!a || !s) return SIDX_ERR_INVALID_ARG;
    memset(s, 0, sizeof *s);
    a->vt->stats(a, s);
    s->name = a->name;
    return SIDX_OK;
}

sidx_status sidx_accel_refit(sidx_accel *a, sidx_error *err)
{
    if (!a) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "accel is NULL");
    if (!a->vt->refit)
        return sidx__fail(err, SIDX_ERR_UNSUPPORTED, "%s cannot be refitted; rebuild it instead", a->name);
    sidx_status s = sidx_mesh_validate(a->mesh, err);
    if (s != SIDX_OK) return s;
    return a->vt->refit(a, err);
}

void sidx_accel_destroy(sidx_accel *a)
{
    if (!a) return;
    if (a->vt->destroy) a->vt->destroy(a);
    sidx__labels_free(a);
    sidx_allocator al = a->alloc;
    al.free(a, al.user);
}

const char *sidx_accel_name(const sidx_accel *a) { return a ? a->name : NULL; }
const sidx_mesh *sidx_accel_mesh(const sidx_accel *a) { return a ? a->mesh : NULL; }
const sidx_build_options *sidx_accel_options(const sidx_accel *a) { return a ? &a->opt : NULL; }
