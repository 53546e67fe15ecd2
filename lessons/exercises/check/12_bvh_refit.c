/* 12_bvh_refit.c — checker driver: the BVH refit after the vertices
 * moved (deck 001, "Primitive vs. Spatial": "Easier to update
 * (animation)").  Reference: the library's sidx_accel_refit of a "bvh"
 * over the moved vertices, its boxes read through sidx/bvh.h.  The
 * student gets the same tree as built before the move and the moved
 * mesh; every node's box, and its two index fields, are compared after
 * the student's function returns, from the last node to the root (so
 * both children of a node come before it, and the first divergence is
 * the deepest wrong box: a leaf, or an inner node whose children agree):
 * three NOTEs per node, one
 * per axis (cell[0] = node, cell[1] = count_axis, cell[2] = axis, count =
 * left_or_first, [t_near, t_far] = the box's extent on that axis).  Any
 * bottom-up order passes; a parent refitted before its children keeps
 * their stale boxes. */
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "sidx/bvh.h"

void bvh_refit(sidx_bvh_node *nodes, uint32_t num_nodes, const uint32_t *prims, const sidx_mesh *mesh);

#define NSCENES 4
#define NMOVES 6
static const char *const scene_names[NSCENES] = {"one triangle", "flat2d", "soup:200", "cornell"};
static const char *const move_names[NMOVES] = {
    "no vertex moved", "every vertex translated by (0.5, -0.25, 2)", "every vertex jittered at random",
    "one vertex moved far away", "the first triangle collapsed to a point", "the scene scaled by 1.5 about the origin"};

typedef struct refit_case {
    sidx_mesh mesh;                  /* the moved vertices */
    sidx_bvh_node *before, *after;   /* the tree as built; the library's refit */
    uint32_t *prims;
    uint32_t num_nodes, num_prims;
} refit_case;

static refit_case cases[NSCENES * NMOVES];

static int open_scene(int s, sidx_mesh *m)
{
    if (s == 0) {
        const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        const uint32_t idx[3] = {0, 1, 2};
        return sidx_mesh_from_arrays(m, xyz, 3, idx, 1, NULL) == SIDX_OK ? 0 : -1;
    }
    return sidx_scene_open(scene_names[s], m, NULL) == SIDX_OK ? 0 : -1;
}

static void move(int mv, sidx_mesh *m)
{
    uint32_t st = 7u + (uint32_t)mv;
    const sidx_aabb b = sidx_mesh_bounds(m);
    const sidx_vec3 e = sidx_aabb_extent(b);
    for (uint32_t v = 0; v < m->num_vertices; ++v) {
        sidx_vec3 *p = &m->positions[v];
        if (mv == 1) *p = sidx_v3_add(*p, sidx_v3(0.5f, -0.25f, 2.0f));
        if (mv == 2)
            *p = sidx_v3_add(*p, sidx_v3((ex_rand(&st) - 0.5f) * 0.1f * e.x, (ex_rand(&st) - 0.5f) * 0.1f * e.y,
                                         (ex_rand(&st) - 0.5f) * 0.1f * e.z));
        if (mv == 5) *p = sidx_v3_scale(*p, 1.5f);
    }
    if (mv == 3) {
        const uint32_t v = m->indices[3 * (m->num_triangles / 2)];
        m->positions[v] = sidx_v3_add(b.max, sidx_v3(3.0f * e.x + 1.0f, 2.0f * e.y + 1.0f, -e.z - 1.0f));
    }
    if (mv == 4) {
        const uint32_t *t = m->indices;
        m->positions[t[1]] = m->positions[t[0]];
        m->positions[t[2]] = m->positions[t[0]];
    }
}

static void *dup(const void *p, size_t n)
{
    void *q = malloc(n ? n : 1);
    if (q && n) memcpy(q, p, n);
    return q;
}

static int setup(void)
{
    for (int s = 0; s < NSCENES; ++s)
        for (int mv = 0; mv < NMOVES; ++mv) {
            refit_case *c = &cases[s * NMOVES + mv];
            if (open_scene(s, &c->mesh) != 0) return -1;
            sidx_accel *a = NULL;
            if (sidx_accel_build("bvh", &c->mesh, NULL, &a, NULL) != SIDX_OK) return -1;
            const sidx_bvh_node *nodes;
            const uint32_t *prims;
            if (sidx_bvh_nodes(a, &nodes, &c->num_nodes, NULL) != SIDX_OK ||
                sidx_bvh_prims(a, &prims, &c->num_prims, NULL) != SIDX_OK) {
                sidx_accel_destroy(a);
                return -1;
            }
            c->before = dup(nodes, c->num_nodes * sizeof *nodes);
            c->prims = dup(prims, c->num_prims * sizeof *prims);
            move(mv, &c->mesh);
            const int ok = sidx_accel_refit(a, NULL) == SIDX_OK && sidx_bvh_nodes(a, &nodes, &c->num_nodes, NULL) == SIDX_OK;
            c->after = ok ? dup(nodes, c->num_nodes * sizeof *nodes) : NULL;
            sidx_accel_destroy(a);
            if (!c->before || !c->prims || !c->after) return -1;
        }
    return 0;
}

static void teardown(void)
{
    for (size_t i = 0; i < NSCENES * NMOVES; ++i) {
        free(cases[i].before);
        free(cases[i].after);
        free(cases[i].prims);
        sidx_mesh_free(&cases[i].mesh);
    }
}

static size_t num_cases(void) { return NSCENES * NMOVES; }

static void describe(size_t i, ex_case_info *out)
{
    const refit_case *c = &cases[i];
    snprintf(out->name, sizeof out->name, "scene %s, %s", scene_names[i / NMOVES], move_names[i % NMOVES]);
    snprintf(out->what, sizeof out->what, "%u triangles, %u nodes (%s)", c->mesh.num_triangles, c->num_nodes,
             c->num_nodes == 1 ? "the root is a leaf" : "compared from the last node to the root");
    out->hint = NULL;
    /* one triangle: the root is a leaf, prims[] is {0}; no vertex moved:
     * the old boxes are right */
    static const char *const ids[2][2] = {
        {"fields-kept leaf-vertices all-axes", "fields-kept leaf-vertices box-from-empty all-axes"},
        {"fields-kept leaf-vertices leaf-through-prims inner-union all-axes",
         "fields-kept leaf-vertices leaf-through-prims box-from-empty inner-union bottom-up all-axes"}};
    out->rules = ids[i / NMOVES > 0][i % NMOVES > 0];
}

static void emit(const sidx_hook *h, const sidx_bvh_node *nodes, uint32_t n)
{
    for (uint32_t i = n; i-- > 0;)
        for (int k = 0; k < 3; ++k) {
            sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
            e.structure = "bvh";
            e.cell[0] = (int32_t)i;
            e.cell[1] = (int32_t)nodes[i].count_axis;
            e.cell[2] = k;
            e.count = nodes[i].left_or_first;
            e.t_near = nodes[i].bmin[k];
            e.t_far = nodes[i].bmax[k];
            sidx_hook_emit(h, &e);
        }
}

static void reference(size_t i, const sidx_hook *h) { emit(h, cases[i].after, cases[i].num_nodes); }

static void student(size_t i, const sidx_hook *h)
{
    const refit_case *c = &cases[i];
    sidx_bvh_node *nodes = dup(c->before, c->num_nodes * sizeof *nodes);
    if (!nodes) return;
    bvh_refit(nodes, c->num_nodes, c->prims, &c->mesh);
    emit(h, nodes, c->num_nodes);
    free(nodes);
}

/* The hand-out's rules, in its order. */
enum { R_FIELDS, R_VERTS, R_PRIMS, R_EMPTY, R_UNION, R_BOTTOM_UP, R_AXES, NRULES };
static const ex_rule rules[NRULES] = {
    {"fields-kept", "left_or_first and count_axis stay as they are; only bmin[] and bmax[] change",
     "the tree stays as it is: refit changes only bmin and bmax, keep left_or_first and count_axis"},
    {"leaf-vertices", "a leaf's box is the bounding box of all three vertices of each of its triangles, at their new "
     "positions",
     "a leaf's box is the bounding box of its triangles' vertices at their new positions: every vertex k = 0, 1, 2 "
     "of each triangle prims[first .. first + count), min and max on each axis"},
    {"leaf-through-prims", "a leaf's triangles are prims[first .. first + count), indices into the mesh",
     "a leaf's box is the bounding box of its triangles' vertices at their new positions, and its triangles are "
     "prims[first .. first + count): the mesh's triangle prims[first + j], not first + j"},
    {"box-from-empty", "each box is computed afresh from its triangles or children (not grown from the old box, "
     "nor from a zero box)",
     "start each box empty (sidx_aabb_empty(), or its first vertex or child) - not from the node's old box (a "
     "box must be able to shrink) and not from a zero box at the origin (the origin is not one of its points)"},
    {"inner-union", "an inner node's box is the union of its two children's boxes, i + 1 and left_or_first",
     "\"Root node encompasses all primitives\": an inner node's box is the union of its two children's boxes "
     "(i + 1 and left_or_first) - both of them"},
    {"bottom-up", "both children are refitted before their parent",
     "\"Root node encompasses all primitives\": an inner node's box is the union of its two children's boxes "
     "(i + 1 and left_or_first), refitted first: bottom-up (children follow their parent in the array, so a "
     "backward pass sees both children before the node)"},
    {"all-axes", "bmin[k] and bmax[k] on every axis k = 0, 1, 2 from the box's own axis",
     "bmin[k] and bmax[k] hold the box on axis k (0 = x, 1 = y, 2 = z): min.x in bmin[0], min.y in bmin[1], "
     "min.z in bmin[2], and the same for max"},
};

/* Leaf node's extent on axis k over the first nv vertices of each of its
 * triangles (at their new positions); direct: triangles first + j of the
 * mesh, not through prims[]. */
static void leaf_extent(const refit_case *c, const sidx_bvh_node *n, int k, int nv, int direct, float *lo, float *hi)
{
    sidx_aabb bb = sidx_aabb_empty();
    for (uint32_t j = 0; j < sidx_bvh_count(n) && n->left_or_first + j < c->num_prims; ++j) {
        const uint32_t t = direct ? n->left_or_first + j : c->prims[n->left_or_first + j];
        for (int v = 0; v < nv; ++v) bb = sidx_aabb_grow(bb, sidx_mesh_vertex(&c->mesh, t, v));
    }
    *lo = sidx_v3_get(bb.min, k);
    *hi = sidx_v3_get(bb.max, k);
}

/* What differs decides: a node's index fields are the topology; another
 * axis's extent; a box grown from the origin or from the old box; the
 * old box of an inner node (its stale children); a leaf's box smaller
 * than its vertices' (a vertex left out) or another (other triangles);
 * an inner node's box otherwise (its children). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const refit_case *c = &cases[i];
    if (!ref || !stu || ref->type != SIDX_EV_NOTE || stu->type != SIDX_EV_NOTE) return rules[R_BOTTOM_UP].hint;
    if (ref->cell[0] != stu->cell[0] || ref->cell[2] != stu->cell[2]) return rules[R_BOTTOM_UP].hint;
    if (ref->cell[1] != stu->cell[1] || ref->count != stu->count) return rules[R_FIELDS].hint;
    const uint32_t node = (uint32_t)ref->cell[0];
    const int k = ref->cell[2];
    if (node >= c->num_nodes || k < 0 || k > 2) return rules[R_BOTTOM_UP].hint;
    const sidx_bvh_node *after = &c->after[node], *before = &c->before[node];
    if (sidx_bvh_is_leaf(before)) {
        float lo, hi;
        for (int nv = 1; nv < 3; ++nv) {
            leaf_extent(c, before, k, nv, 0, &lo, &hi);
            if (stu->t_near == lo && stu->t_far == hi) return rules[R_VERTS].hint;
        }
        leaf_extent(c, before, k, 3, 1, &lo, &hi);
        if (stu->t_near == lo && stu->t_far == hi) return rules[R_PRIMS].hint;
    }
    for (int j = 0; j < 3; ++j)
        if (j != k && ((stu->t_near == after->bmin[j] && stu->t_near != after->bmin[k]) ||
                       (stu->t_far == after->bmax[j] && stu->t_far != after->bmax[k])))
            return rules[R_AXES].hint;
    const float rlo = ref->t_near, rhi = ref->t_far, slo = stu->t_near, shi = stu->t_far;
    const int grown = slo <= rlo && shi >= rhi;
    if (grown && ((slo == 0.0f && rlo > 0.0f) || (shi == 0.0f && rhi < 0.0f))) return rules[R_EMPTY].hint;
    const float olo = before->bmin[k] < rlo ? before->bmin[k] : rlo, ohi = before->bmax[k] > rhi ? before->bmax[k] : rhi;
    if (grown && slo == olo && shi == ohi) return rules[R_EMPTY].hint;
    if (sidx_bvh_is_leaf(before)) return rules[R_VERTS].hint;
    if (slo == before->bmin[k] && shi == before->bmax[k]) return rules[R_BOTTOM_UP].hint;
    return rules[R_UNION].hint;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    const uint32_t ca = (uint32_t)e->cell[1];
    if (ca & SIDX_BVH_COUNT_MASK)
        snprintf(buf, size, "node %d (leaf: first %u, count %u)  %c in [%g, %g]", e->cell[0], e->count,
                 ca & SIDX_BVH_COUNT_MASK, "xyz"[e->cell[2] % 3], (double)e->t_near, (double)e->t_far);
    else
        snprintf(buf, size, "node %d (inner: children %d, %u, split on %c)  %c in [%g, %g]", e->cell[0], e->cell[0] + 1,
                 e->count, "xyzw"[(ca >> 30) & 3], "xyz"[e->cell[2] % 3], (double)e->t_near, (double)e->t_far);
    return 1;
}

const ex_driver ex_driver_this = {
    "12_bvh_refit",
    "BVH refit: the vertices moved, every node's box recomputed bottom-up",
    "deck 001, \"Primitive vs. Spatial\" (\"Easier to update (animation)\") and \"Bounding Volume Hierarchy (BVH)\"",
    setup, num_cases, describe, reference, student, hint, teardown, format, rules, NRULES,
};
