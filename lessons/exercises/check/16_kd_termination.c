/* 16_kd_termination.c — checker driver: the kd-tree build's termination
 * rule (deck 000, "Termination Criteria").  Reference: the library's
 * "kdtree" build, recorded once per case in setup: each node's triangle
 * count and depth (BUILD_NODE), its cheapest plane (the least
 * BUILD_CANDIDATE cost, which is the one the build compares) and its
 * decision (BUILD_SPLIT, or BUILD_LEAF with its reason).  Both traces are
 * one NOTE per node reached, depth first: cell[0] = node, cell[1] = the
 * leaf reason (0: split), count = n; t_near, t_far = the best split's
 * cost and the leaf's (the inputs, for the report). */
#include <stdlib.h>
#include <string.h>
#include "check.h"

int kd_terminate(uint32_t n, uint32_t depth, float best_cost, float c_tri, uint32_t leaf_size, uint32_t max_depth,
                 uint32_t *bad);

typedef struct kt_node {
    uint32_t id, parent, depth, n; /* parent: its index in the case's list, UINT32_MAX for the root */
    float best;
    int reason;                    /* SIDX_LEAF_NONE: split */
    uint32_t bad;                  /* *bad after the library's decision (case_rules) */
} kt_node;

typedef struct kt_case {
    const char *scene;
    float c_trav, c_tri;
    uint32_t leaf_size, max_depth;
    kt_node *nodes;
    uint32_t count;
} kt_case;

static kt_case cases[] = {
    {"soup:150", 16, 1, 1, 20, NULL, 0},  {"soup:150", 4, 1, 1, 20, NULL, 0},  {"soup:150", 40, 1, 2, 20, NULL, 0},
    {"soup:150", 16, 1, 1, 4, NULL, 0},   {"cornell", 16, 1, 1, 20, NULL, 0},  {"cornell", 2, 1, 1, 20, NULL, 0},
    {"flat2d:6", 16, 1, 1, 20, NULL, 0},  {"flat2d:6", 1, 1, 1, 20, NULL, 0},  {"soup:16", 70, 1, 1, 20, NULL, 0},
    {"soup:16", 60, 1, 1, 20, NULL, 0},   {"soup:40", 24, 1, 3, 20, NULL, 0},  {"soup:400", 16, 1, 1, 30, NULL, 0},
    {"soup:400", 30, 2, 4, 30, NULL, 0},  {"soup:15", 61, 1, 1, 20, NULL, 0},  {"overlap:24", 1, 1, 1, 20, NULL, 0},
    {"overlap:40", 2, 1, 1, 20, NULL, 0}, {"overlap:12", 1, 1, 1, 20, NULL, 0}, {"soup:12", -4, 1, 1, 20, NULL, 0},
    {"overlap:12", -4, 1, 1, 20, NULL, 0}, {"soup:40", -1, 1, 1, 20, NULL, 0},   {"soup:150", -1, 1, 1, 20, NULL, 0},
    {"cornell", -1, 1, 1, 20, NULL, 0},    {"soup:400", -1, 1, 1, 30, NULL, 0},
    /* few triangles at the depth limit: the order of those two checks */
    {"soup:40", 4, 1, 24, 1, NULL, 0},     {"cornell", 4, 1, 4, 2, NULL, 0},    {"flat2d:6", 4, 1, 3, 2, NULL, 0},
};
#define NCASES (sizeof cases / sizeof cases[0])
static char case_ids[NCASES][160]; /* the ids of the rules each case's nodes test (setup) */

static const char *const hint_order =
    "\"When should we stop splitting?\": check in order an empty cell (n == 0), few triangles (n <= leaf size), "
    "the depth limit (depth >= max_depth), no plane at all (best cost +inf), then the cost";

/* The hand-out's rules, in its order. */
enum { R_EMPTY, R_FEW, R_FEW_DEPTH, R_DEPTH, R_PLANE, R_PAYS, R_STRETCH, R_THIRD, R_WORSE, NRULES };
static const ex_rule rules[NRULES] = {
    {"empty-first", "SIDX_LEAF_EMPTY when n == 0, checked first (an empty cell is not \"few triangles\")",
     "\"When should we stop splitting?\": an empty cell (n == 0) is SIDX_LEAF_EMPTY, checked before anything "
     "else: it also has n <= leaf size, but its reason is \"empty\""},
    {"few-inclusive", "SIDX_LEAF_FEW_PRIMS when n <= leaf_size (a node of exactly leaf_size triangles is a leaf)",
     "few triangles (n <= leaf size) is inclusive: a node of exactly leaf_size triangles is a leaf, "
     "SIDX_LEAF_FEW_PRIMS"},
    {"few-before-depth", "few triangles is checked before the depth limit",
     "the order of the checks: few triangles (n <= leaf size) comes before the depth limit; a node that has "
     "both is SIDX_LEAF_FEW_PRIMS"},
    /* At the depth limit the build seeks no plane (best_cost is +inf
     * there), so "depth > max_depth" and "no plane first" give the same
     * decisions: one rule. */
    {"depth-limit", "SIDX_LEAF_MAX_DEPTH when depth >= max_depth (the root has depth 0), checked before \"no plane\"",
     "\"Threshold of cell size\": the depth limit is depth >= max_depth (the root has depth 0), checked before "
     "\"no plane\": a node at depth max_depth is SIDX_LEAF_MAX_DEPTH (the build seeks no plane there, so "
     "best_cost is +inf)"},
    {"no-plane", "SIDX_LEAF_NO_SPLIT when best_cost is +inf (no plane strictly inside the cell)",
     "best_cost +inf means the cell has no plane to split at: SIDX_LEAF_NO_SPLIT, checked before the cost"},
    {"pays-strict", "a split pays when best_cost < c_tri·n, and is then taken; best_cost >= c_tri·n does not pay",
     "\"Use the cost estimates in your termination criteria\": the leaf costs c_tri·n; a split whose best cost is "
     "below it pays and is always taken; one that costs as much as the leaf or more (best >= c_tri·n) does not "
     "pay"},
    {"bad-carried", "*bad counts the splits that do not pay on the path from the root; the children start from "
     "the new count",
     "\"Threshold of cost improvement — but stretch decision over multiple levels, to avoid local minima\": a split "
     "that does not pay (best >= c_tri·n) is still taken unless it is the 3rd such split on the path from the root "
     "(count them in *bad: the parent's count plus one; the children start from it)"},
    {"third-stops", "the 3rd split on the path that does not pay (*bad >= 3) is SIDX_LEAF_NO_GAIN",
     "stretched over several levels, but not forever: the 3rd split on the path that does not pay (*bad >= 3 "
     "after counting this node) ends the path, SIDX_LEAF_NO_GAIN"},
    {"much-worse", "best_cost > 4·c_tri·n with n < 16 is SIDX_LEAF_NO_GAIN at once",
     "a split much worse than the leaf on few triangles is not worth exploring: best > 4·c_tri·n with n < 16 ends "
     "the path at once (pbrt's rule), even before the 3rd split that does not pay; best = 4·c_tri·n or n = 16 "
     "does not"},
};

/* "overlap:N": N triangles from near the corner (-1,-1,-1) to near (1,1,1)
 * and a third vertex anywhere in the cube: every plane cuts nearly all of
 * them, so no split pays and the look-ahead decides, level after level. */
static int make_overlap(uint32_t n, sidx_mesh *m)
{
    float xyz[3 * 3 * 64];
    uint32_t idx[3 * 64];
    if (n > 64) return -1;
    uint32_t st = 1616u + n;
    for (uint32_t t = 0; t < n; ++t) {
        for (int c = 0; c < 3; ++c) {
            xyz[9 * t + c] = -1.0f + 0.2f * ex_rand(&st);
            xyz[9 * t + 3 + c] = 1.0f - 0.2f * ex_rand(&st);
            xyz[9 * t + 6 + c] = 2.0f * ex_rand(&st) - 1.0f;
        }
        for (uint32_t k = 0; k < 3; ++k) idx[3 * t + k] = 3 * t + k;
    }
    return sidx_mesh_from_arrays(m, xyz, 3 * n, idx, n, NULL) == SIDX_OK ? 0 : -1;
}

static sidx_status build(const kt_case *k, const sidx_mesh *m, const sidx_hook *h)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.hook = h;
    bo.c_trav = k->c_trav;
    bo.c_tri = k->c_tri;
    bo.leaf_size = k->leaf_size;
    bo.max_depth = k->max_depth;
    sidx_accel *a = NULL;
    const sidx_status s = sidx_accel_build("kdtree", m, &bo, &a, NULL);
    sidx_accel_destroy(a);
    return s;
}

static void root_best_fn(const sidx_event *e, void *user)
{
    float *best = user;
    if (e->type == SIDX_EV_BUILD_CANDIDATE && e->node == 0 && e->cost < *best) *best = e->cost;
}

/* A case with c_trav < 0 asks for a tie at the root: the C_trav whose
 * cheapest root plane costs exactly ratio times the leaf (c_tri·n), found
 * by bisection over the floats (the cost grows with C_trav). */
static int tie_c_trav(kt_case *k, const sidx_mesh *m, float ratio)
{
    const float want = ratio * k->c_tri * (float)m->num_triangles;
    const sidx_hook h = {root_best_fn, NULL, SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE)};
    uint32_t lo = 0x3f800000u /* 1 */, hi = 0x3f800000u;
    memcpy(&hi, &want, sizeof hi);
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        memcpy(&k->c_trav, &mid, sizeof mid);
        float best = INFINITY;
        sidx_hook hh = h;
        hh.user = &best;
        if (build(k, m, &hh) != SIDX_OK) return -1;
        if (best >= want) hi = mid;
        else lo = mid + 1;
    }
    memcpy(&k->c_trav, &lo, sizeof lo);
    return 0;
}

/* The rules case k tests: those whose condition one of its nodes meets
 * (*bad along the path follows the library's decisions). */
static void case_rules(const kt_case *k, char *ids, size_t size)
{
    int has[NRULES] = {0};
    uint32_t *bad = malloc((k->count ? k->count : 1) * sizeof *bad);
    if (!bad) return;
    for (uint32_t j = 0; j < k->count; ++j) {
        const kt_node *nd = &k->nodes[j];
        const float leaf = k->c_tri * (float)nd->n;
        const uint32_t from = nd->parent == UINT32_MAX ? 0u : bad[nd->parent];
        const int cost = nd->reason == SIDX_LEAF_NONE || nd->reason == SIDX_LEAF_NO_GAIN;
        bad[j] = from + (cost && nd->best >= leaf);
        k->nodes[j].bad = bad[j];
        has[R_EMPTY] |= nd->n == 0;
        has[R_FEW] |= nd->n > 0 && nd->n == k->leaf_size;
        has[R_FEW_DEPTH] |= nd->n > 0 && nd->n <= k->leaf_size && nd->depth >= k->max_depth;
        has[R_DEPTH] |= nd->reason == SIDX_LEAF_MAX_DEPTH;
        has[R_PLANE] |= nd->reason == SIDX_LEAF_NO_SPLIT;
        has[R_PAYS] |= cost && nd->best <= leaf;
        has[R_STRETCH] |= cost && from > 0 && nd->best >= leaf;
        has[R_THIRD] |= nd->reason == SIDX_LEAF_NO_GAIN && bad[j] >= 3;
        has[R_WORSE] |= cost && nd->best >= leaf && nd->best >= 4.0f * leaf && nd->n <= 16 && bad[j] < 3;
    }
    free(bad);
    ids[0] = '\0';
    for (int r = 0; r < NRULES; ++r)
        if (has[r]) {
            const size_t len = strlen(ids);
            snprintf(ids + len, size - len, "%s%s", len ? " " : "", rules[r].id);
        }
}

static int setup(void)
{
    for (size_t c = 0; c < NCASES; ++c) {
        kt_case *k = &cases[c];
        sidx_mesh m;
        if (strncmp(k->scene, "overlap:", 8) == 0) {
            if (make_overlap((uint32_t)atoi(k->scene + 8), &m) != 0) return -1;
        } else if (sidx_scene_open(k->scene, &m, NULL) != SIDX_OK) {
            return -1;
        }
        ex_trace rec = {NULL, 0, 0};
        const sidx_hook h = {ex_trace_hook_fn, &rec,
                             SIDX_EVMASK(SIDX_EV_BUILD_NODE) | SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE) |
                                 SIDX_EVMASK(SIDX_EV_BUILD_SPLIT) | SIDX_EVMASK(SIDX_EV_BUILD_LEAF)};
        if (k->c_trav < 0 && tie_c_trav(k, &m, -k->c_trav) != 0) {
            sidx_mesh_free(&m);
            return -1;
        }
        const sidx_status s = build(k, &m, &h);
        sidx_mesh_free(&m);
        if (s != SIDX_OK) return -1;
        uint32_t maxid = 0, nn = 0;
        for (size_t i = 0; i < rec.n; ++i)
            if (rec.ev[i].type == SIDX_EV_BUILD_NODE) {
                ++nn;
                if (rec.ev[i].node > maxid) maxid = rec.ev[i].node;
            }
        k->nodes = calloc(nn ? nn : 1, sizeof *k->nodes);
        uint32_t *pos = malloc((maxid + 1) * sizeof *pos);
        if (!k->nodes || !pos) return -1;
        for (uint32_t i = 0; i <= maxid; ++i) pos[i] = UINT32_MAX;
        k->count = 0;
        for (size_t i = 0; i < rec.n; ++i) {
            const sidx_event *e = &rec.ev[i];
            if (e->type == SIDX_EV_BUILD_NODE) {
                kt_node *nd = &k->nodes[k->count];
                nd->id = e->node;
                nd->parent = e->parent == UINT32_MAX || e->parent > maxid ? UINT32_MAX : pos[e->parent];
                nd->depth = e->depth;
                nd->n = e->count;
                nd->best = INFINITY;
                nd->reason = -1;
                pos[e->node] = k->count++;
                continue;
            }
            if (e->node > maxid || pos[e->node] == UINT32_MAX) continue;
            kt_node *nd = &k->nodes[pos[e->node]];
            if (e->type == SIDX_EV_BUILD_CANDIDATE && e->cost < nd->best) nd->best = e->cost;
            else if (e->type == SIDX_EV_BUILD_SPLIT) nd->reason = SIDX_LEAF_NONE;
            else if (e->type == SIDX_EV_BUILD_LEAF) nd->reason = e->reason;
        }
        free(pos);
        free(rec.ev);
        for (uint32_t i = 0; i < k->count; ++i)
            if (k->nodes[i].reason < 0) return -1;
        case_rules(k, case_ids[c], sizeof case_ids[c]);
    }
    return 0;
}

static void teardown(void)
{
    for (size_t c = 0; c < NCASES; ++c) free(cases[c].nodes);
}

static size_t num_cases(void) { return NCASES; }

static void describe(size_t i, ex_case_info *out)
{
    const kt_case *k = &cases[i];
    snprintf(out->name, sizeof out->name, "kd-tree over %s, C_trav %g, C_tri %g, leaf size %u, depth limit %u",
             k->scene, (double)k->c_trav, (double)k->c_tri, k->leaf_size, k->max_depth);
    snprintf(out->what, sizeof out->what,
             "sidx_accel_build(\"kdtree\") of %s with c_trav %g, c_tri %g, leaf_size %u, max_depth %u: %u nodes, "
             "each decided in depth-first order",
             k->scene, (double)k->c_trav, (double)k->c_tri, k->leaf_size, k->max_depth, k->count);
    out->hint = hint_order;
    out->rules = case_ids[i][0] ? case_ids[i] : NULL;
}

/* One decision; aux (which the comparison ignores) carries *bad after it,
 * for the hint. */
static void note(const sidx_hook *h, const kt_case *k, const kt_node *nd, int reason, uint32_t bad)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "kdtree";
    e.node = nd->id;
    e.depth = nd->depth;
    e.cell[0] = (int32_t)nd->id;
    e.cell[1] = reason;
    e.count = nd->n;
    e.t_near = nd->best;
    e.t_far = k->c_tri * (float)nd->n;
    e.aux = bad;
    sidx_hook_emit(h, &e);
}

static void reference(size_t i, const sidx_hook *h)
{
    const kt_case *k = &cases[i];
    for (uint32_t j = 0; j < k->count; ++j) note(h, k, &k->nodes[j], k->nodes[j].reason, k->nodes[j].bad);
}

static void student(size_t i, const sidx_hook *h)
{
    const kt_case *k = &cases[i];
    int *dec = malloc((k->count ? k->count : 1) * sizeof *dec);
    uint32_t *bad = malloc((k->count ? k->count : 1) * sizeof *bad);
    if (!dec || !bad) {
        free(dec);
        free(bad);
        return;
    }
    for (uint32_t j = 0; j < k->count; ++j) {
        const kt_node *nd = &k->nodes[j];
        dec[j] = -1; /* not reached */
        if (nd->parent != UINT32_MAX && dec[nd->parent] != SIDX_LEAF_NONE) continue;
        bad[j] = nd->parent == UINT32_MAX ? 0u : bad[nd->parent];
        dec[j] = kd_terminate(nd->n, nd->depth, nd->best, k->c_tri, k->leaf_size, k->max_depth, &bad[j]);
        note(h, k, nd, dec[j], bad[j]);
    }
    free(dec);
    free(bad);
}

/* The hint by what differs: the rule whose leaf reason the reference
 * gives (and, between two leaf reasons, the order of the checks), or
 * split against "no gain" (the cost: pays, stretched over the levels,
 * the 3rd, much worse on few triangles). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const kt_case *k = &cases[i];
    if (!ref || !stu || ref->type != SIDX_EV_NOTE || stu->type != SIDX_EV_NOTE) return NULL;
    const int r = ref->cell[1], s = stu->cell[1];
    const uint32_t n = ref->count;
    switch (r) {
    case SIDX_LEAF_EMPTY: return rules[R_EMPTY].hint;
    case SIDX_LEAF_FEW_PRIMS:
        if (s == SIDX_LEAF_MAX_DEPTH) return rules[R_FEW_DEPTH].hint;
        if (s == SIDX_LEAF_EMPTY) return rules[R_EMPTY].hint;
        return n == k->leaf_size ? rules[R_FEW].hint : hint_order;
    case SIDX_LEAF_MAX_DEPTH:
        if (s == SIDX_LEAF_FEW_PRIMS) return n > k->leaf_size ? rules[R_FEW].hint : hint_order;
        return rules[R_DEPTH].hint;
    case SIDX_LEAF_NO_SPLIT: return rules[R_PLANE].hint;
    default: break;
    }
    if (s != SIDX_LEAF_NONE && s != SIDX_LEAF_NO_GAIN) {
        if (s == SIDX_LEAF_MAX_DEPTH && ref->depth + 1 == k->max_depth) return rules[R_DEPTH].hint;
        if (s == SIDX_LEAF_FEW_PRIMS && n == k->leaf_size + 1) return rules[R_FEW].hint;
        if (s == SIDX_LEAF_NO_SPLIT) return rules[R_PLANE].hint;
        return hint_order;
    }
    const float best = ref->t_near, leaf = ref->t_far;
    if (best <= leaf) return rules[R_PAYS].hint;
    /* another count: a split on the path that cost exactly the leaf */
    if (stu->aux != ref->aux)
        for (uint32_t j = 0; j < k->count; ++j)
            if ((int32_t)k->nodes[j].id == ref->cell[0]) {
                for (uint32_t a = k->nodes[j].parent; a != UINT32_MAX; a = k->nodes[a].parent)
                    if (k->nodes[a].best == k->c_tri * (float)k->nodes[a].n) return rules[R_PAYS].hint;
                break;
            }
    if (n <= 16 && best >= 4.0f * leaf) return rules[R_WORSE].hint;
    /* a decision against the stretched count: the same count, another
     * threshold (the 3rd); another count, not carried or not counted */
    if (stu->aux == ref->aux) return rules[R_THIRD].hint;
    return rules[R_STRETCH].hint;
}

static const char *const reason_name[] = {"split", "leaf: few triangles", "leaf: no gain", "leaf: depth limit",
                                          "leaf: no plane", "leaf: empty", "leaf: given"};

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    const int r = e->cell[1];
    snprintf(buf, size, "node %d depth %u, %u triangles, best split %g vs leaf %g: %s", (int)e->cell[0], e->depth,
             e->count, (double)e->t_near, (double)e->t_far,
             r >= 0 && r < (int)(sizeof reason_name / sizeof reason_name[0]) ? reason_name[r] : "reason ?");
    return 1;
}

const ex_driver ex_driver_this = {
    "16_kd_termination",
    "the kd-tree build's termination rule: split only if it pays, stretched over several levels",
    "deck 000, \"Termination Criteria\" and \"Building good kD-trees\"",
    setup, num_cases, describe, reference, student, hint, teardown, format, rules, NRULES,
};
