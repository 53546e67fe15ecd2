/* 13_octree_traversal.c — checker driver: the octree's front-to-back walk
 * (deck 000, "Octrees and Quadtrees"; the child order of Revelles et al.
 * 2000).  Reference: the library's traced octree query (octree_walk in
 * lib/octree.c) over an "octree" or "quadtree" built with the slides'
 * Möller–Trumbore test and no mailbox, so that a leaf's events are one
 * PRIM_TEST per reference.  Its stack events are left out of the
 * reference: what is compared is every cell entered with its depth and
 * interval, every triangle test and closer hit, and the end of the walk
 * (why, the best t, the number of cells entered), so a walk with its own
 * stack and a recursive one pass alike. */
#include <string.h>
#include "check.h"
#include "sidx/octree.h"

int oct_walk(const sidx_ex *ex, const sidx_oct_node *nodes, const uint32_t *refs, sidx_aabb root, int axes,
             float t_near, float t_far, sidx_hit *best);

#define NSCENES 5
#define RAYS 35
/* icosphere: a closed surface, rays meet it in cells far from the root;
 * flat2d: the slide's 2D board as a quadtree (z never cut); soup:
 * overlapping triangles straddling cells; kd-slide: deck 000's 2D scene
 * as an octree, whose z mid-plane is the board's own plane (rays across
 * the board lie in it, d.z = ±0); ties: small triangles at integer
 * coordinates in [0, 4]^3, some in the root's mid-planes, so that
 * crossings, cell faces and hits meet at exactly the same t.  Leaf sizes
 * that give each tree two to four levels. */
static const char *const scene_names[NSCENES] = {"icosphere:2", "flat2d", "soup:200", "kd-slide", "ties"};
static const char *const accel_names[NSCENES] = {"octree", "quadtree", "octree", "octree", "octree"};
static const uint32_t leaf_sizes[NSCENES] = {8, 2, 0, 1, 1};
static const char *const view_knobs[NSCENES] = {"--no-mailbox --leaf-size 8", "--no-mailbox --leaf-size 2",
                                                "--no-mailbox", "--no-mailbox --leaf-size 1",
                                                "--no-mailbox --leaf-size 1"};
static sidx_mesh meshes[NSCENES];
static sidx_accel *accels[NSCENES];
static sidx_ray rays[NSCENES][RAYS];
static const char *ray_kind[NSCENES][RAYS];

enum { K_OUTSIDE = 0, K_BEYOND = 8, K_INSIDE = 12, K_ON_MID = 16, K_TMAX_MID = 20, K_ZERO = 22, K_ZERO_ON = 26,
       K_DIAG = 28, K_DIAG2 = 29, K_ENTRY_TIE = 30, K_TMAX = 31, K_MISS = 32, K_HIT_TIE = 33,
       K_EXIT_TIE = 34 };

/* The "ties" scene: triangles at integer and half-integer coordinates. */
static int make_ties(sidx_mesh *m)
{
    static const float tri[][9] = {
        {0, 0, 0, 0.5f, 0, 0, 0, 0.5f, 0},       {4, 4, 4, 3.5f, 4, 4, 4, 3.5f, 4},       /* the box's corners */
        {2, 1, 1, 2, 2, 1, 2, 1, 2},             {1, 2, 1, 1, 2, 2, 1.5f, 2, 1},          /* in the mid-planes */
        {3, 3, 2, 3.5f, 3, 2, 3, 3.5f, 2},       {2, 3, 3, 2, 3.5f, 3, 2, 3, 3.5f},
        {1, 1.25f, 1, 1, 1.75f, 1, 1, 1.25f, 1.5f}, {3, 1, 3, 3, 1.5f, 3, 3, 1, 3.5f},   /* in the quarter planes */
        {0.5f, 0.5f, 1, 1.5f, 0.5f, 1, 0.5f, 1.5f, 1.5f}, {2.5f, 0.5f, 1, 3.5f, 0.5f, 1, 2.5f, 1.5f, 1.5f},
        {0.5f, 2.5f, 1, 1.5f, 2.5f, 1, 0.5f, 3.5f, 1.5f}, {2.5f, 2.5f, 1, 3.5f, 2.5f, 1, 2.5f, 3.5f, 1.5f},
        {0.5f, 0.5f, 3, 1.5f, 0.5f, 3, 0.5f, 1.5f, 3.5f}, {2.5f, 0.5f, 3, 3.5f, 0.5f, 3, 2.5f, 1.5f, 3.5f},
        {0.5f, 2.5f, 3, 1.5f, 2.5f, 3, 0.5f, 3.5f, 3.5f}, {2.5f, 2.5f, 3, 3.5f, 2.5f, 3, 2.5f, 3.5f, 3.5f},
    };
    enum { N = sizeof tri / sizeof tri[0] };
    uint32_t idx[3 * N];
    for (uint32_t i = 0; i < 3 * N; ++i) idx[i] = i;
    return sidx_mesh_from_arrays(m, &tri[0][0], 3 * N, idx, N, NULL) == SIDX_OK ? 0 : -1;
}

/* Whether the library's walk of ray r finds a hit in a leaf and goes on
 * into another cell because the hit lies beyond that leaf's cell. */
typedef struct beyond_state {
    int pending, found;
} beyond_state;

static void beyond_fn(const sidx_event *ev, void *user)
{
    beyond_state *b = user;
    if (ev->type == SIDX_EV_HIT_UPDATE) b->pending = 1;
    else if (ev->type == SIDX_EV_NODE_ENTER && b->pending) b->found = 1;
}

static int hit_beyond_cell(const sidx_accel *a, const sidx_ray *r)
{
    beyond_state b = {0, 0};
    const sidx_hook h = {beyond_fn, &b, 0};
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &h;
    sidx_hit hit;
    sidx_accel_intersect(a, r, &q, &hit);
    return b.found;
}

static float comp(sidx_vec3 v, int k) { return sidx_v3_array(&v)[k]; }
static void set_comp(sidx_vec3 *v, int k, float x) { sidx_v3_array_rw(v)[k] = x; }

/* The t at which a ray from o along d (d_k = ±1) meets the plane x_k = p,
 * computed as the walk computes it. */
static float t_plane(sidx_vec3 o, sidx_vec3 d, int k, float p)
{
    const sidx_ray tmp = ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0, INFINITY);
    return (p - comp(o, k)) * comp(tmp.inv_dir, k);
}

/* Moves o_k by single floats until the ray meets the plane x_k = p at
 * exactly t (d_k = ±1, so t falls as o_k moves towards p). */
static void tie_to(sidx_vec3 *o, sidx_vec3 d, int k, float p, float t)
{
    for (int n = 0; n < 64; ++n) {
        const float tk = t_plane(*o, d, k, p);
        if (tk == t) return;
        const float dk = comp(d, k);
        const float toward = (tk > t) == (dk > 0.0f) ? INFINITY : -INFINITY;
        set_comp(o, k, nextafterf(comp(*o, k), toward));
    }
}

static int setup(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        if (s == 4 ? make_ties(&meshes[s]) != 0 : sidx_scene_open(scene_names[s], &meshes[s], NULL) != SIDX_OK)
            return -1;
        sidx_build_options bo;
        memset(&bo, 0, sizeof bo);
        bo.tri = SIDX_TRI_MOLLER_TRUMBORE;
        bo.no_mailbox = 1;
        bo.leaf_size = leaf_sizes[s];
        if (sidx_accel_build(accel_names[s], &meshes[s], &bo, &accels[s], NULL) != SIDX_OK) return -1;
        sidx_aabb b;
        int axes = 3;
        if (sidx_octree_info(accels[s], &b, &axes, NULL) != SIDX_OK) return -1;
        const sidx_vec3 e = sidx_aabb_extent(b);
        const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
        const sidx_vec3 c = sidx_v3(0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2]));
        const int flat = axes == 2 || e.z < 0.05f * fminf(e.x, e.y);
        uint32_t st = 1313u + (uint32_t)s;
        for (int i = 0, tries = 0; i < RAYS; ++i) {
            const float u = ex_rand(&st), v = ex_rand(&st), w = ex_rand(&st);
            sidx_vec3 p = sidx_v3(lo[0] + (0.1f + 0.8f * u) * e.x, lo[1] + (0.1f + 0.8f * v) * e.y,
                                  lo[2] + (0.1f + 0.8f * w) * e.z);
            sidx_vec3 o, d = sidx_v3(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f);
            float tmin = 0.0f, tmax = INFINITY;
            const int k = i % (flat ? 2 : 3);
            if (i < K_INSIDE || i == K_HIT_TIE) { /* from outside, towards a point of the scene */
                const float a = ex_rand(&st) * 6.2831853f;
                o = sidx_v3(c.x + 1.5f * cosf(a) * e.x, c.y + 1.5f * sinf(a) * e.y,
                            flat ? c.z + 2.0f * e.z + 1.0f : c.z + 1.5f * e.z);
                d = sidx_v3_sub(p, o);
                ray_kind[s][i] = "from outside, front to back";
                if (s == 4 && i == K_HIT_TIE) { /* along x onto the triangle in the plane x = 2 */
                    o = sidx_v3(0.5f, 1.25f, 1.625f);
                    d = sidx_v3(1.0f, 0.0f, 0.0f);
                    ray_kind[s][i] = "a hit on the face between two cells (best->t == t_far)";
                }
            } else if (i < K_ON_MID) {
                o = p;
                ray_kind[s][i] = "starting inside";
            } else if (i < K_TMAX_MID) { /* on the root's mid-plane k, or on the quarter plane below it */
                o = p;
                const float m = 0.5f * (lo[k] + hi[k]);
                set_comp(&o, k, i & 1 ? 0.5f * (lo[k] + m) : m);
                if (comp(d, k) == 0.0f) set_comp(&d, k, 0.5f);
                if (i & 2) set_comp(&d, k, -comp(d, k));
                ray_kind[s][i] = i & 1 ? "starting on a child's mid-plane (t_k = t_near = 0)"
                                       : "starting on the root's mid-plane (t_k = t_near = 0)";
            } else if (i < K_ZERO) { /* tmax = the crossing of the root's mid-plane k */
                o = p;
                const float m = 0.5f * (lo[k] + hi[k]);
                set_comp(&d, k, comp(o, k) < m ? 1.0f : -1.0f);
                tmax = t_plane(o, d, k, m);
                ray_kind[s][i] = "ending on the root's mid-plane (t_k = t_far)";
            } else if (i < K_ZERO_ON) { /* along one axis, +0 or -0 on the others */
                o = p;
                const float z = i & 1 ? -0.0f : 0.0f;
                d = sidx_v3(z, z, z);
                set_comp(&d, k, i & 2 ? -1.0f : 1.0f);
                ray_kind[s][i] = i & 1 ? "axis-parallel, -0 components (inv_dir = -inf)"
                                       : "axis-parallel, +0 components (inv_dir = +inf)";
            } else if (i < K_DIAG) { /* along x, in the root's mid-plane y (and z), d = ±0 there */
                o = p;
                o.y = c.y;
                if (!flat) o.z = c.z;
                const float z = i & 1 ? -0.0f : 0.0f;
                d = sidx_v3(i & 1 ? -1.0f : 1.0f, z, z);
                ray_kind[s][i] = "axis-parallel, the origin in a mid-plane of a ±0 axis (the upper side)";
            } else if (i == K_DIAG || i == K_DIAG2) { /* through the centre, or the line x = mid_x, y = mid_y */
                d = sidx_v3(1.0f, i == K_DIAG ? -1.0f : 1.0f, flat ? 0.0f : (i == K_DIAG ? 1.0f : 0.375f));
                o = sidx_v3(c.x - 0.75f * e.x, c.y + (i == K_DIAG ? 0.75f : -0.75f) * e.x,
                            flat ? c.z : c.z - (i == K_DIAG ? 0.75f * e.x : 0.28125f * e.x));
                const float t = t_plane(o, d, 0, c.x);
                tie_to(&o, d, 1, c.y, t);
                if (!flat && i == K_DIAG) tie_to(&o, d, 2, c.z, t);
                ray_kind[s][i] = i == K_DIAG ? "through the centre: mid-planes crossed at one t (x, then y, then z)"
                                             : "through the line where two mid-planes meet (x, then y)";
            } else if (i == K_ENTRY_TIE) { /* entering through the face x = lo on the mid-plane of y */
                d = sidx_v3(1.0f, 1.0f, flat ? 0.0f : 0.25f);
                o = sidx_v3(lo[0] - 0.125f * e.x, c.y - 0.125f * e.x, flat ? c.z : p.z);
                const float t = t_plane(o, d, 0, lo[0]);
                tie_to(&o, d, 1, c.y, t);
                ray_kind[s][i] = "entering the root's cell on a mid-plane (t_k = t_near > 0)";
            } else if (i == K_TMAX) { /* tmax cutting the scene */
                o = sidx_v3(lo[0] - 0.5f * e.x, p.y, p.z);
                d = sidx_v3(1.0f, flat ? 0.0f : (ex_rand(&st) - 0.5f) * 0.3f, 0.0f);
                tmax = e.x;
                ray_kind[s][i] = "with a finite tmax";
            } else if (i == K_EXIT_TIE) { /* leaving the lower child through the root's plane x at its own y */
                const float qy = 0.5f * (lo[1] + c.y); /* the lower child's mid-plane y */
                d = sidx_v3(1.0f, 1.0f, flat ? 0.0f : 0.125f);
                o = sidx_v3(c.x - 0.5f * e.x, qy - 0.5f * e.x, flat ? c.z : lo[2] + 0.0625f * e.z);
                const float t = t_plane(o, d, 0, c.x);
                tie_to(&o, d, 1, qy, t);
                ray_kind[s][i] = "leaving a child where its own mid-plane meets the root's (t_k = t_far)";
            } else { /* K_MISS */
                o = sidx_v3(lo[0] - e.x, hi[1] + 0.5f * e.y + 1.0f, c.z);
                d = sidx_v3(1.0f, 0.25f, 0.0f);
                ray_kind[s][i] = "missing the root's cell";
            }
            if (flat && i < K_ZERO) { /* the board: rays across it in its middle plane, or onto it */
                if (i < K_INSIDE && i % 2 == 0) {
                    o.z = c.z;
                    d.z = (i & 2) ? -0.0f : 0.0f;
                }
            }
            if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) d.x = 1.0f;
            rays[s][i] = ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, tmin, tmax);
            if (i >= K_BEYOND && i < K_INSIDE) { /* search for a hit beyond its cell */
                if (hit_beyond_cell(accels[s], &rays[s][i])) ray_kind[s][i] = "a hit beyond its cell: the walk goes on";
                else if (++tries < 2000) --i;
            }
        }
    }
    return 0;
}

static void teardown(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        sidx_accel_destroy(accels[s]);
        sidx_mesh_free(&meshes[s]);
    }
}

static size_t num_cases(void) { return NSCENES * RAYS; }

static void describe(size_t i, ex_case_info *out)
{
    const int s = (int)(i / RAYS), r = (int)(i % RAYS);
    snprintf(out->name, sizeof out->name, "%s over %s, ray %d (%s)", accel_names[s], scene_names[s], r + 1,
             ray_kind[s][r]);
    ex_describe_walk(out, &rays[s][r], accel_names[s], view_knobs[s], s == 4 ? NULL : scene_names[s], &meshes[s]);
    /* every walk: the general rules; the ray's kind and the quadtree add theirs */
#define WALK "start-root depth entry-child crossings-in-order every-child child-interval leaf-tests stop-inclusive " \
             "stop-returns"
    static char ids[NSCENES * RAYS][240];
    const char *kind = r >= K_BEYOND && r < K_INSIDE                   ? " hit-beyond-goes-on"
                       : (r >= K_ON_MID && r < K_TMAX_MID) || r == K_ENTRY_TIE ? " start-tie"
                       : (r >= K_TMAX_MID && r < K_ZERO) || r == K_EXIT_TIE    ? " end-tie"
                       : r >= K_ZERO && r < K_DIAG                            ? " zero-dir"
                       : r == K_DIAG || r == K_DIAG2                          ? " ties-xyz"
                                                                              : "";
    const int beyond = r >= K_BEYOND && r < K_INSIDE ? 0 : hit_beyond_cell(accels[s], &rays[s][r]);
    snprintf(ids[i], sizeof ids[i], "%s%s%s%s", WALK, kind, beyond ? " hit-beyond-goes-on" : "",
             s == 1 ? " axes-only" : "");
#undef WALK
    out->rules = ids[i];
}

/* The reference's events without its stack steps; a cell entered right
 * after its inner parent (the child holding the entry point) carries
 * aux = 1, which the comparison ignores and the hint reads. */
typedef struct ref_relay {
    const sidx_hook *h;
    const sidx_oct_node *nodes;
    uint32_t num_nodes;
    int after_inner;
} ref_relay;

static void no_stack_fn(const sidx_event *ev, void *user)
{
    ref_relay *r = user;
    if (ev->type == SIDX_EV_STACK_PUSH || ev->type == SIDX_EV_STACK_POP) return;
    if (ev->type != SIDX_EV_NODE_ENTER) {
        r->after_inner = 0;
        sidx_hook_emit(r->h, ev);
        return;
    }
    sidx_event e = *ev;
    e.aux = (uint32_t)r->after_inner;
    r->after_inner = e.node < r->num_nodes && r->nodes[e.node].n == SIDX_OCT_INNER;
    sidx_hook_emit(r->h, &e);
}

static void reference(size_t i, const sidx_hook *h)
{
    const int s = (int)(i / RAYS), r = (int)(i % RAYS);
    ref_relay rr = {h, NULL, 0, 0};
    sidx_octree_nodes(accels[s], &rr.nodes, &rr.num_nodes, NULL);
    const sidx_hook fh = {no_stack_fn, &rr, 0};
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &fh;
    sidx_hit hit;
    sidx_accel_intersect(accels[s], &rays[s][r], &q, &hit);
}

/* The hand-out's rules, in its order. */
enum { R_START, R_DEPTH, R_ENTRY, R_START_TIE, R_ZERO, R_ORDER, R_END_TIE, R_TIES, R_EVERY, R_INTERVAL, R_AXES,
       R_LEAF, R_STOP, R_BEYOND, R_RETURN, NRULES };
static const ex_rule rules[NRULES] = {
    {"start-root", "every cell entered is reported, sidx_ex_node_enter(ex, node, depth, t_near, t_far), the root "
     "first over the clipped [t_near, t_far]",
     "start at the root: sidx_ex_node_enter(ex, 0, 0, t_near, t_far), and report every cell you enter"},
    {"depth", "the root has depth 0, a child its parent's depth + 1",
     "the root has depth 0, a child its parent's depth + 1"},
    {"entry-child", "an inner node starts in the child holding the entry point, by its own mid-planes "
     "(mid = 0.5f * (lo + hi) of its cell)",
     "children in the order the ray meets them: start in the child holding the entry point (bit k set = the "
     "upper half: t_k <= t_near with d_k > 0, or t_k > t_near with d_k < 0), with mid_k = 0.5f * (lo + hi) of the "
     "cell being split, then flip bit k at each crossing t_k strictly inside (t_near, t_far), in increasing t"},
    {"start-tie", "a ray on mid-plane k at t_near (t_k == t_near) starts past it, in the child it moves into",
     "a ray on the mid-plane at t_near (t_k == t_near) is already past it: it starts in the child it moves "
     "into (upper for d_k > 0), and the plane is no crossing inside (t_near, t_far)"},
    {"zero-dir", "a ±0 direction component never crosses (t_k = +inf) and takes the origin's side (upper on the "
     "plane)",
     "a direction component +0 or -0 never crosses its mid-plane (t_k = +inf, whatever the sign of inv_dir): "
     "the child is on the origin's side, the upper one when the origin lies on the plane"},
    {"crossings-in-order", "each crossing strictly inside (t_near, t_far), in increasing t, flips bit k and starts "
     "the next child; each child before any later one",
     "children in the order the ray meets them: start in the child holding the entry point, then flip bit k at "
     "each crossing t_k strictly inside (t_near, t_far), in increasing t, and enter each child (and its subtree) "
     "before any later one"},
    {"end-tie", "a crossing at t_far (t_k == t_far) is none",
     "a crossing at t_far (t_k == t_far) is none: only t_k strictly inside (t_near, t_far) starts a child"},
    {"ties-xyz", "crossings at the same t are taken x, then y, then z",
     "crossings at the same t are taken x, then y, then z: each flips its bit and starts a child over a "
     "zero-length interval [t, t], entered like any other"},
    {"every-child", "every child the ray meets is entered, even over a zero-length interval (at most 4)",
     "a child left out: the ray meets the entry child and one more per mid-plane crossing inside (t_near, "
     "t_far) (at most 4 in an octree, 3 in a quadtree), and each of them is entered, empty or not, even over a "
     "zero-length interval [t, t]"},
    {"child-interval", "children c0 over [t_near, t_1], c1 over [t_1, t_2], ..., the last over [t_m, t_far]",
     "the same child with another interval: child c0 runs over [t_near, t_1], each next one from the crossing "
     "that started it to the next crossing, the last to t_far, with t_k = (mid_k - org[k]) * inv_dir[k] and "
     "mid_k = 0.5f * (lo + hi) of the cell being split"},
    {"axes-only", "only the first `axes` axes are cut: the quadtree never cuts z",
     "cut only the first `axes` axes (k < axes): a quadtree never cuts z, its children are a + c with c = 0 .. 3 "
     "(bit 2 never set)"},
    {"leaf-tests", "a leaf tests each triangle, sidx_ex_test_triangle(ex, prim, best->t, &t), and reports a closer "
     "hit with sidx_ex_hit_update",
     "a leaf tests each of its triangles refs[a .. a + n) against the best hit so far, "
     "sidx_ex_test_triangle(ex, prim, best->t, &t), and reports a closer one with sidx_ex_hit_update"},
    {"stop-inclusive", "after a leaf, empty or not, the walk stops when best->t <= t_far",
     "\"Traversal can be terminated as soon as surface intersection is found in the current node\": after a "
     "leaf (empty or not), stop if best->t <= t_far: the next cell starts at t_far, nothing in it lies in front"},
    {"hit-beyond-goes-on", "a hit beyond t_far does not stop the walk",
     "a hit beyond the current cell (best->t > t_far) may be hidden by a triangle in a cell the ray meets "
     "later: keep it as the best so far and go on"},
    {"stop-returns", "a stop returns 1 with a hit, 0 without (tmax ended it); 0 when every cell is visited",
     "only a hit stops the walk with 1: with no hit (best->prim == SIDX_NO_HIT) go on, and return 0 when "
     "every cell along the ray is done"},
};

static const char *const hint_extra =
    "a cell the ray does not meet: it enters the entry child and one more child per crossing strictly inside "
    "(t_near, t_far), on the first `axes` axes only";

/* Whether node stu is outside the four-child block of ref's parent in a
 * quadtree (the student cut z). */
static int quad_z_child(int s, uint32_t ref, uint32_t stu)
{
    const sidx_oct_node *nodes = NULL;
    uint32_t nn = 0;
    sidx_aabb root;
    int axes = 3;
    if (sidx_octree_info(accels[s], &root, &axes, NULL) != SIDX_OK || axes != 2 ||
        sidx_octree_nodes(accels[s], &nodes, &nn, NULL) != SIDX_OK)
        return 0;
    for (uint32_t p = 0; p < nn; ++p)
        if (nodes[p].n == SIDX_OCT_INNER && ref >= nodes[p].a && ref < nodes[p].a + 4)
            return stu < nodes[p].a || stu >= nodes[p].a + 4;
    return 0;
}

/* The hint follows what differs at the first divergence: a stop where the
 * reference goes on (or the reverse) is the termination rule; another
 * triangle step is the leaf; the same cell with another interval is the
 * interval; another child entered is the order rule (its ±0, tie and
 * start/end variants on the cases about them). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const int r = (int)(i % RAYS);
    const ex_walk_hints walk = {rules[R_STOP].hint, rules[R_BEYOND].hint, rules[R_RETURN].hint, rules[R_START].hint, rules[R_LEAF].hint};
    const char *w = ex_walk_hint(ref, stu, &walk);
    if (w) return w;
    if (ref && ref->type == SIDX_EV_NODE_ENTER && stu && stu->type == SIDX_EV_TERMINATE) return rules[R_EVERY].hint;
    if (ref && ref->type == SIDX_EV_TERMINATE && stu && stu->type == SIDX_EV_NODE_ENTER)
        return (r >= K_TMAX_MID && r < K_ZERO) || r == K_EXIT_TIE ? rules[R_END_TIE].hint : hint_extra;
    if (ref && stu && ref->type == SIDX_EV_NODE_ENTER && stu->type == SIDX_EV_NODE_ENTER) {
        if (ref->node == stu->node) return ref->depth != stu->depth ? rules[R_DEPTH].hint : rules[R_INTERVAL].hint;
        if (quad_z_child((int)(i / RAYS), ref->node, stu->node)) return rules[R_AXES].hint;
        /* a zero-length child skipped: the student's next child starts
         * where it starts but runs on */
        if (ref->t_near == ref->t_far && stu->t_near == ref->t_near && stu->t_far > stu->t_near)
            return rules[R_EVERY].hint;
        if (r >= K_ZERO && r < K_DIAG) return rules[R_ZERO].hint;
        if (r == K_DIAG || r == K_DIAG2) return rules[R_TIES].hint;
        if ((r >= K_ON_MID && r < K_TMAX_MID) || r == K_ENTRY_TIE) return rules[R_START_TIE].hint;
        if ((r >= K_TMAX_MID && r < K_ZERO) || r == K_EXIT_TIE) return rules[R_END_TIE].hint;
        /* the first child of an inner node, entered at the parent's t_near
         * too: another child holds the entry point (a later one: the order) */
        if (ref->aux && stu->t_near == ref->t_near) return rules[R_ENTRY].hint;
        return rules[R_ORDER].hint;
    }
    return rules[R_ORDER].hint;
}

/* Counts the student's NODE_ENTER events on the way to the runner's hook. */
typedef struct counting {
    const sidx_hook *inner;
    uint32_t entered;
} counting;

static void counting_fn(const sidx_event *ev, void *user)
{
    counting *c = user;
    if (ev->type == SIDX_EV_NODE_ENTER) ++c->entered;
    sidx_hook_emit(c->inner, ev);
}

/* What the library's query does around the walk: RAY_BEGIN, the ray
 * clipped to the root's cell (no event; TERMINATE miss_root if it
 * misses), the walk, TERMINATE (hit_in_cell when oct_walk returns 1,
 * stack_empty when it returns 0, with the best t and the cells entered),
 * RAY_END. */
static void student(size_t i, const sidx_hook *h)
{
    const int s = (int)(i / RAYS), r = (int)(i % RAYS);
    const sidx_ray *ray = &rays[s][r];
    const sidx_oct_node *nodes = NULL;
    const uint32_t *refs = NULL;
    uint32_t nn = 0, nr = 0;
    sidx_aabb root;
    int axes = 3;
    sidx_octree_nodes(accels[s], &nodes, &nn, NULL);
    sidx_octree_refs(accels[s], &refs, &nr, NULL);
    sidx_octree_info(accels[s], &root, &axes, NULL);
    counting c = {h, 0};
    const sidx_hook ch = {counting_fn, &c, 0};
    sidx_ex ex;
    sidx_hit best;
    ex_walk_begin(&ex, &ch, h, accel_names[s], ray, &meshes[s], SIDX_TRI_MOLLER_TRUMBORE, SIDX_BOX_ROBUST, &best);
    sidx_ex quiet = ex;
    quiet.hook = NULL;
    float tn = 0.0f, tf = 0.0f;
    sidx_event e = sidx_event_blank(SIDX_EV_TERMINATE);
    e.structure = accel_names[s];
    if (!sidx_ex_test_box(&quiet, 0, &root, ray->tmin, best.t, &tn, &tf)) {
        e.reason = SIDX_TERM_MISS_ROOT;
        e.count = 0;
    } else {
        e.reason = oct_walk(&ex, nodes, refs, root, axes, tn, tf, &best) ? SIDX_TERM_HIT_IN_CELL
                                                                          : SIDX_TERM_STACK_EMPTY;
        e.prim = best.prim; /* not compared: the hint tells a stop with no hit */
        e.count = c.entered;
    }
    e.t = best.t;
    sidx_hook_emit(h, &e);
    ex_walk_end(h, accel_names[s], &best);
}

const ex_driver ex_driver_this = {
    "13_octree_traversal",
    "octree traversal: front to back, the children in the order the ray meets them",
    "deck 000, \"Octrees and Quadtrees\" (\"simplest hierarchical grid\") with the front-to-back walk of "
    "\"kD-Tree Traversal\"; Revelles et al. 2000 for the child order",
    setup, num_cases, describe, reference, student, hint, teardown, NULL, rules, NRULES,
};
