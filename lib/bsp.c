/* bsp.c — the BSP tree: space split recursively by planes of arbitrary
 * position and orientation (slides, "BSP Trees"), the generalisation of
 * the kd-tree that drops "axis-aligned".
 *
 * Build (autopartition with a balance/split heuristic).  Each node holds
 * a list of convex polygon pieces — at the root, the mesh's triangles.
 * Candidate planes are
 *   - the planes of k pieces sampled evenly from the list (a Doom / Quake
 *     style node builder takes its partition lines/planes from the
 *     level's own walls/faces: pieces lying in the plane are then
 *     "consumed" by the node), and
 *   - three free axis-aligned planes through the middle of the pieces'
 *     centroid box: a convex object (a sphere) has no face plane with
 *     anything in front of it, so pure autopartition degenerates into a
 *     list; the free planes keep such parts balanced.
 * Each candidate is scored as the classic node builders did:
 *     score = |front − back| + w·splits + (coplanar − 1)⁺
 * (imbalance, plus w = BSP_SPLIT_WEIGHT per polygon the plane would cut,
 * plus a charge for piling many coplanar pieces on one node, which a ray
 * crossing the plane would have to test one by one).  The lowest score
 * wins.  Pieces that straddle the winning plane are really cut in two
 * (Sutherland–Hodgman against one plane); each half keeps its original
 * triangle id.  Pieces in the plane stay at the node, which is what makes
 * the back-to-front enumeration exact (sidx_bsp_paint).
 *
 * Ray queries use the same tree, but leaves list original triangle ids:
 * a leaf's list holds every triangle with a piece in the leaf, plus every
 * triangle that comes within ε of the leaf's region (triangles lying in
 * an ancestor's plane, and pieces touching a plane), so the ray test runs
 * on the original, uncut triangle — exactly the triangle brute force
 * tests — and a hit found in a leaf is final when it lies before the point
 * where the ray leaves the leaf.  Such a neighbour is passed to the other
 * side as only its part within ε of the plane (add_contact): routed down
 * whole, a triangle touching the plane with one vertex would reach every
 * leaf its far vertices point into.
 *
 * Traversal (front to back, as the kd-tree's, with a general plane): the
 * near child is the side holding the ray origin (sign of n·o − d), the
 * plane is crossed at t = (d − n·o)/(n·dir), and the same three cases as
 * the kd-tree decide which children the segment [t_near, t_far] visits.
 *
 * Events: BUILD_CANDIDATE / BUILD_SPLIT carry axis = -1 and the plane as
 * bounds.min = unit normal n, pos = offset d (n·x = d; front is n·x > d);
 * BUILD_NODE / BUILD_LEAF as usual (bounds = box of the node's pieces); a
 * NOTE at the end of the build carries the number of cuts in `count`.
 * Traversal: NODE_ENTER, PRIM_TEST, HIT_UPDATE, TERMINATE. */
#include <stdio.h>
#include "sidx_internal.h"
#include "sidx/bsp.h"

#define SIDX_STRUCTURE_NAME "bsp"

#define BSP_CANDIDATES 12      /* polygon planes sampled per node */
#define BSP_SPLIT_WEIGHT 4.0   /* one cut costs as much as 4 pieces of imbalance */
#define BSP_DEFAULT_DEPTH 48
#define BSP_MAX_DEPTH 64
#define BSP_MAX_VERTS (3 + BSP_MAX_DEPTH + 2) /* each cut adds at most one vertex to a convex piece */
#define BSP_STACK (2 * BSP_MAX_DEPTH + 4)

typedef struct bsp_node {
    double n[3], d;         /* plane n·x = d (unit n); front: n·x > d */
    uint32_t child[2];      /* [0] front, [1] back; UINT32_MAX in leaves */
    uint32_t piece_first;   /* pieces: coplanar ones (inner) or all of the leaf's (leaf) */
    uint32_t piece_count;
    uint32_t ref_first;     /* leaves: original triangle ids for ray queries */
    uint32_t ref_count;
    uint32_t free_plane;    /* 1 if the plane is axis-aligned and not a polygon's */
} bsp_node;

typedef struct bsp_piece {
    uint32_t first;         /* into verts */
    uint32_t num;
    uint32_t tri;
} bsp_piece;

typedef struct bsp_tree {
    bsp_node *nodes;
    uint32_t num_nodes;
    bsp_piece *pieces;      /* every piece ever made (cut parents included); node lists index it */
    uint32_t num_pieces;
    sidx_vec3 *verts;
    uint32_t num_verts;
    uint32_t *piece_refs;   /* node piece lists */
    uint32_t num_piece_refs;
    uint32_t *refs;         /* leaf triangle lists */
    uint32_t num_refs;
    sidx_aabb bounds;
    sidx_bsp_info info;
} bsp_tree;

/* ---- build ------------------------------------------------------------- */

typedef struct bsp_build {
    sidx_accel *a;
    bsp_tree *t;
    size_t cap_nodes, cap_pieces, cap_verts, cap_piece_refs, cap_refs;
    uint32_t *stamp;        /* per triangle: last leaf that listed it (dedup) */
    /* ray-only pieces ("extras", see build_node): the part of a piece
     * within ε of a plane it touches, a pool of its own that lives only
     * during the build (they are never painted, so the tree keeps none) */
    bsp_piece *xp;
    sidx_vec3 *xv;
    size_t cap_xp, cap_xv;
    uint32_t num_xp, num_xv;
    double eps;             /* distance under which a point counts as on a plane */
    uint32_t leaf_size, max_depth;
    uint32_t piece_budget;  /* stop cutting beyond this many pieces */
    int failed;
} bsp_build;

#define GROW(b, field, capfield, need)                                                         \
    sidx__grow((b)->a, (void **)&(b)->t->field, &(b)->capfield, (need), sizeof *(b)->t->field)

static uint32_t add_piece(bsp_build *b, const sidx_vec3 *v, uint32_t n, uint32_t tri)
{
    bsp_tree *t = b->t;
    if (!GROW(b, verts, cap_verts, (size_t)t->num_verts + n) || !GROW(b, pieces, cap_pieces, (size_t)t->num_pieces + 1)) {
        b->failed = 1;
        return UINT32_MAX;
    }
    bsp_piece *p = &t->pieces[t->num_pieces];
    p->first = t->num_verts;
    p->num = n;
    p->tri = tri;
    memcpy(t->verts + t->num_verts, v, n * sizeof *v);
    t->num_verts += n;
    return t->num_pieces++;
}

typedef struct plane { double n[3], d; int is_free; } plane;

static uint32_t add_extra(bsp_build *b, const sidx_vec3 *v, uint32_t n, uint32_t tri)
{
    if (!sidx__grow(b->a, (void **)&b->xv, &b->cap_xv, (size_t)b->num_xv + n, sizeof *b->xv) ||
        !sidx__grow(b->a, (void **)&b->xp, &b->cap_xp, (size_t)b->num_xp + 1, sizeof *b->xp)) {
        b->failed = 1;
        return UINT32_MAX;
    }
    bsp_piece *p = &b->xp[b->num_xp];
    p->first = b->num_xv;
    p->num = n;
    p->tri = tri;
    memcpy(b->xv + b->num_xv, v, n * sizeof *v);
    b->num_xv += n;
    return b->num_xp++;
}

static double plane_dist(const plane *pl, sidx_vec3 p)
{
    return pl->n[0] * (double)p.x + pl->n[1] * (double)p.y + pl->n[2] * (double)p.z - pl->d;
}

/* The plane of a piece's original triangle; 0 if the triangle is degenerate. */
static int tri_plane(const sidx_mesh *m, uint32_t tri, plane *out)
{
    const sidx_vec3 a = sidx_mesh_vertex(m, tri, 0), b = sidx_mesh_vertex(m, tri, 1), c = sidx_mesh_vertex(m, tri, 2);
    const double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
    const double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0)) return 0;
    for (int i = 0; i < 3; ++i) out->n[i] = n[i] / len;
    out->d = out->n[0] * a.x + out->n[1] * a.y + out->n[2] * a.z;
    out->is_free = 0;
    return 1;
}

enum { SIDE_COPLANAR, SIDE_FRONT, SIDE_BACK, SIDE_STRADDLE };

static int classify(const bsp_build *b, const plane *pl, const sidx_vec3 *v, uint32_t n, double *dmin, double *dmax)
{
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = 0; i < n; ++i) {
        const double d = plane_dist(pl, v[i]);
        if (d < lo) lo = d;
        if (d > hi) hi = d;
    }
    if (dmin) *dmin = lo;
    if (dmax) *dmax = hi;
    if (hi <= b->eps && lo >= -b->eps) return SIDE_COPLANAR;
    if (lo >= -b->eps) return SIDE_FRONT;
    if (hi <= b->eps) return SIDE_BACK;
    return SIDE_STRADDLE;
}

/* Cuts convex polygon v[0..n) by the plane (Sutherland–Hodgman for one
 * plane): vertices within ε of the plane go to both halves, an edge that
 * crosses from one side to the other adds its crossing point to both. */
static void cut_polygon(const bsp_build *b, const plane *pl, const sidx_vec3 *v, uint32_t n, sidx_vec3 *front,
                        uint32_t *nf, sidx_vec3 *back, uint32_t *nb)
{
    *nf = *nb = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_vec3 p = v[i], q = v[(i + 1) % n];
        const double dp = plane_dist(pl, p), dq = plane_dist(pl, q);
        const int sp = dp > b->eps ? 1 : dp < -b->eps ? -1 : 0;
        const int sq = dq > b->eps ? 1 : dq < -b->eps ? -1 : 0;
        if (sp >= 0 && *nf < BSP_MAX_VERTS) front[(*nf)++] = p;
        if (sp <= 0 && *nb < BSP_MAX_VERTS) back[(*nb)++] = p;
        if (sp * sq < 0) {
            const double s = dp / (dp - dq);
            const sidx_vec3 x = sidx_v3((float)(p.x + s * ((double)q.x - p.x)), (float)(p.y + s * ((double)q.y - p.y)),
                                        (float)(p.z + s * ((double)q.z - p.z)));
            if (*nf < BSP_MAX_VERTS) front[(*nf)++] = x;
            if (*nb < BSP_MAX_VERTS) back[(*nb)++] = x;
        }
    }
}

/* The ray-only copy of piece v[0..n) for the other side of plane pl: only
 * its part within ε of the plane (side = +1: a piece in front, keep
 * n·x − d <= ε; −1: a piece behind, keep n·x − d >= −ε; 0: coplanar, all
 * of it).  A point of the piece farther from the plane than ε is farther
 * than ε from every region on the other side, so nothing is lost; the
 * whole piece, routed down the other subtree by its far vertices, would
 * land in leaves it comes nowhere near (docs/performance.md, "Octree,
 * BSP"). */
static uint32_t add_contact(bsp_build *b, const plane *pl, const sidx_vec3 *v, uint32_t n, uint32_t tri, int side)
{
    if (side == 0) return add_extra(b, v, n, tri);
    const plane shifted = {{pl->n[0], pl->n[1], pl->n[2]}, pl->d + (double)side * b->eps, pl->is_free};
    sidx_vec3 src[BSP_MAX_VERTS], fr[BSP_MAX_VERTS], bk[BSP_MAX_VERTS];
    uint32_t nf, nb;
    memcpy(src, v, n * sizeof *src); /* add_extra may move the pool v points into */
    cut_polygon(b, &shifted, src, n, fr, &nf, bk, &nb);
    return side > 0 ? add_extra(b, bk, nb, tri) : add_extra(b, fr, nf, tri);
}

typedef struct score_t { uint32_t front, back, splits, coplanar; double score; } score_t;

static score_t score_plane(const bsp_build *b, const plane *pl, const uint32_t *pieces, uint32_t np)
{
    score_t s = {0, 0, 0, 0, 0.0};
    const bsp_tree *t = b->t;
    for (uint32_t i = 0; i < np; ++i) {
        const bsp_piece *p = &t->pieces[pieces[i]];
        switch (classify(b, pl, t->verts + p->first, p->num, NULL, NULL)) {
        case SIDE_COPLANAR: s.coplanar++; break;
        case SIDE_FRONT: s.front++; break;
        case SIDE_BACK: s.back++; break;
        default: s.front++; s.back++; s.splits++; break;
        }
    }
    const double imbalance = s.front > s.back ? (double)(s.front - s.back) : (double)(s.back - s.front);
    s.score = imbalance + BSP_SPLIT_WEIGHT * s.splits + (s.coplanar > 1 ? s.coplanar - 1 : 0);
    return s;
}

static sidx_aabb pieces_box(const bsp_tree *t, const uint32_t *pieces, uint32_t np)
{
    sidx_aabb box = sidx_aabb_empty();
    for (uint32_t i = 0; i < np; ++i) {
        const bsp_piece *p = &t->pieces[pieces[i]];
        for (uint32_t k = 0; k < p->num; ++k) box = sidx_aabb_grow(box, t->verts[p->first + k]);
    }
    return box;
}

static int append_u32(bsp_build *b, uint32_t **arr, size_t *cap, uint32_t *n, uint32_t v)
{
    if (!sidx__grow(b->a, (void **)arr, cap, (size_t)*n + 1, sizeof **arr)) { b->failed = 1; return 0; }
    (*arr)[(*n)++] = v;
    return 1;
}

static uint32_t new_node(bsp_build *b)
{
    if (!GROW(b, nodes, cap_nodes, (size_t)b->t->num_nodes + 1)) { b->failed = 1; return UINT32_MAX; }
    bsp_node *nd = &b->t->nodes[b->t->num_nodes];
    memset(nd, 0, sizeof *nd);
    nd->child[0] = nd->child[1] = UINT32_MAX;
    return b->t->num_nodes++;
}

static void make_leaf(bsp_build *b, uint32_t id, const uint32_t *pieces, uint32_t np, const uint32_t *extras,
                      uint32_t ne, uint32_t depth, int reason)
{
    bsp_tree *t = b->t;
    const uint32_t stamp = id + 1;
    t->nodes[id].piece_first = t->num_piece_refs;
    for (uint32_t i = 0; i < np; ++i)
        if (!append_u32(b, &t->piece_refs, &b->cap_piece_refs, &t->num_piece_refs, pieces[i])) return;
    t->nodes[id].piece_count = np;
    t->nodes[id].ref_first = t->num_refs;
    for (uint32_t i = 0; i < np + ne; ++i) {
        const uint32_t tri = i < np ? t->pieces[pieces[i]].tri : b->xp[extras[i - np]].tri;
        if (b->stamp[tri] == stamp) continue;
        b->stamp[tri] = stamp;
        if (!append_u32(b, &t->refs, &b->cap_refs, &t->num_refs, tri)) return;
    }
    t->nodes[id].ref_count = t->num_refs - t->nodes[id].ref_first;
    t->info.leaves++;
    if (np > 1) t->info.unordered_leaves++;
    if (depth > t->info.max_depth) t->info.max_depth = depth;
    SIDX_EMIT(1, b->a->opt.hook, SIDX_EV_BUILD_LEAF, e_.node = id; e_.depth = depth;
              e_.count = t->nodes[id].ref_count; e_.cost = (float)t->nodes[id].ref_count; e_.reason = reason;
              e_.prims = t->nodes[id].ref_count ? t->refs + t->nodes[id].ref_first : NULL);
}

/* Builds the subtree over pieces[0..np) (owned by the caller) and the
 * ray-only pieces extras[0..ne) — pieces of other regions that come within
 * ε of this one: their triangles go into the leaves' ray lists but they
 * are neither cut nor painted here; returns the node id. */
static uint32_t build_node(bsp_build *b, const uint32_t *pieces, uint32_t np, const uint32_t *extras, uint32_t ne,
                           uint32_t parent, uint32_t depth)
{
    bsp_tree *t = b->t;
    const sidx_mesh *m = b->a->mesh;
    const uint32_t id = new_node(b);
    if (id == UINT32_MAX) return id;
    SIDX_EMIT(1, b->a->opt.hook, SIDX_EV_BUILD_NODE, e_.node = id; e_.parent = parent; e_.depth = depth;
              e_.count = np; e_.bounds = pieces_box(t, pieces, np));

    if (np <= b->leaf_size) {
        make_leaf(b, id, pieces, np, extras, ne, depth, np ? SIDX_LEAF_FEW_PRIMS : SIDX_LEAF_EMPTY);
        return id;
    }
    if (depth >= b->max_depth) {
        make_leaf(b, id, pieces, np, extras, ne, depth, SIDX_LEAF_MAX_DEPTH);
        return id;
    }
    if (t->num_pieces >= b->piece_budget) {
        /* The cut budget is spent (BSP size can grow quadratically with
         * the input in 3D): stop here rather than run out of memory. */
        make_leaf(b, id, pieces, np, extras, ne, depth, SIDX_LEAF_NO_GAIN);
        return id;
    }

    /* ---- choose the plane */
    plane best = {{0, 0, 0}, 0, 0};
    score_t best_s = {0, 0, 0, 0, INFINITY};
    const uint32_t k = np < BSP_CANDIDATES ? np : BSP_CANDIDATES;
    const uint32_t ncand = k + 3;
    sidx_aabb cbox = sidx_aabb_empty();
    for (uint32_t i = 0; i < np; ++i) {
        const bsp_piece *p = &t->pieces[pieces[i]];
        sidx_vec3 c = sidx_v3(0, 0, 0);
        for (uint32_t j = 0; j < p->num; ++j) c = sidx_v3_add(c, t->verts[p->first + j]);
        cbox = sidx_aabb_grow(cbox, sidx_v3_scale(c, 1.0f / (float)p->num));
    }
    for (uint32_t c = 0; c < ncand; ++c) {
        plane pl;
        if (c < k) {
            /* evenly spaced sample, deterministic (same mesh, same tree) */
            const uint32_t pick = (uint32_t)(((uint64_t)c * np) / k);
            if (!tri_plane(m, t->pieces[pieces[pick]].tri, &pl)) continue;
        } else {
            const int axis = (int)(c - k);
            const float lo = sidx_v3_get(cbox.min, axis), hi = sidx_v3_get(cbox.max, axis);
            if (!(hi > lo)) continue;
            pl.n[0] = pl.n[1] = pl.n[2] = 0.0;
            pl.n[axis] = 1.0;
            pl.d = 0.5 * ((double)lo + hi);
            pl.is_free = 1;
        }
        const score_t s = score_plane(b, &pl, pieces, np);
        /* progress: at least one piece is consumed, or both sides shrink */
        const int progress = s.coplanar > 0 || (s.front < np && s.back < np);
        SIDX_EMIT(1, b->a->opt.hook, SIDX_EV_BUILD_CANDIDATE, e_.node = id; e_.depth = depth; e_.axis = -1;
                  e_.bounds.min = sidx_v3((float)pl.n[0], (float)pl.n[1], (float)pl.n[2]);
                  e_.bounds.max = e_.bounds.min; e_.pos = (float)pl.d; e_.cost = (float)s.score;
                  e_.count = s.front; e_.aux = s.back; e_.result = progress);
        if (progress && s.score < best_s.score) { best = pl; best_s = s; }
    }
    if (!(best_s.score < INFINITY)) {
        make_leaf(b, id, pieces, np, extras, ne, depth, SIDX_LEAF_NO_SPLIT);
        return id;
    }
    SIDX_EMIT(1, b->a->opt.hook, SIDX_EV_BUILD_SPLIT, e_.node = id; e_.depth = depth; e_.axis = -1;
              e_.bounds.min = sidx_v3((float)best.n[0], (float)best.n[1], (float)best.n[2]);
              e_.bounds.max = e_.bounds.min; e_.pos = (float)best.d; e_.cost = (float)best_s.score;
              e_.count = best_s.front; e_.aux = best_s.back);

    /* ---- partition */
    bsp_node *nd = &t->nodes[id];
    for (int i = 0; i < 3; ++i) nd->n[i] = best.n[i];
    nd->d = best.d;
    nd->free_plane = (uint32_t)best.is_free;
    if (best.is_free) t->info.free_planes++;
    else t->info.polygon_planes++;

    uint32_t *fp = NULL, *bp = NULL, *fe = NULL, *be = NULL;
    size_t cfp = 0, cbp = 0, cfe = 0, cbe = 0;
    uint32_t nfp = 0, nbp = 0, nfe = 0, nbe = 0;
    nd->piece_first = t->num_piece_refs;
    uint32_t coplanar = 0;
    sidx_vec3 va[BSP_MAX_VERTS], vb[BSP_MAX_VERTS];
    for (uint32_t i = 0; i < np && !b->failed; ++i) {
        const uint32_t pid = pieces[i];
        const bsp_piece p = t->pieces[pid];
        double dmin, dmax;
        const int side = classify(b, &best, t->verts + p.first, p.num, &dmin, &dmax);
        if (side == SIDE_COPLANAR) {
            /* stays at the node (painter); for rays it lies on the
             * boundary of both children, so both list it */
            append_u32(b, &t->piece_refs, &b->cap_piece_refs, &t->num_piece_refs, pid);
            ++coplanar;
            const uint32_t x = add_contact(b, &best, t->verts + p.first, p.num, p.tri, 0);
            if (b->failed) break;
            append_u32(b, &fe, &cfe, &nfe, x);
            append_u32(b, &be, &cbe, &nbe, x);
        } else if (side == SIDE_FRONT) {
            append_u32(b, &fp, &cfp, &nfp, pid);
            if (dmin <= b->eps) { /* touches the plane */
                const uint32_t x = add_contact(b, &best, t->verts + p.first, p.num, p.tri, 1);
                if (b->failed) break;
                append_u32(b, &be, &cbe, &nbe, x);
            }
        } else if (side == SIDE_BACK) {
            append_u32(b, &bp, &cbp, &nbp, pid);
            if (dmax >= -b->eps) {
                const uint32_t x = add_contact(b, &best, t->verts + p.first, p.num, p.tri, -1);
                if (b->failed) break;
                append_u32(b, &fe, &cfe, &nfe, x);
            }
        } else {
            uint32_t na, nb;
            sidx_vec3 src[BSP_MAX_VERTS]; /* add_piece may move t->verts */
            memcpy(src, t->verts + p.first, p.num * sizeof *src);
            cut_polygon(b, &best, src, p.num, va, &na, vb, &nb);
            const uint32_t fa = add_piece(b, va, na, p.tri);
            const uint32_t fb = add_piece(b, vb, nb, p.tri);
            if (b->failed) break;
            t->info.splits++;
            /* both halves touch the plane: each is also a ray-only
             * neighbour of the other side, as any piece touching it is */
            append_u32(b, &fp, &cfp, &nfp, fa);
            append_u32(b, &bp, &cbp, &nbp, fb);
            const uint32_t xa = add_contact(b, &best, va, na, p.tri, 1);
            const uint32_t xb = add_contact(b, &best, vb, nb, p.tri, -1);
            if (b->failed) break;
            append_u32(b, &be, &cbe, &nbe, xa);
            append_u32(b, &fe, &cfe, &nfe, xb);
        }
    }
    for (uint32_t i = 0; i < ne && !b->failed; ++i) {
        /* ray-only pieces: routed by their own vertices, never cut */
        const bsp_piece p = b->xp[extras[i]];
        double dmin, dmax;
        classify(b, &best, b->xv + p.first, p.num, &dmin, &dmax);
        if (dmax >= -b->eps) append_u32(b, &fe, &cfe, &nfe, extras[i]);
        if (dmin <= b->eps) append_u32(b, &be, &cbe, &nbe, extras[i]);
    }
    t->nodes[id].piece_count = coplanar;
    t->info.coplanar_pieces += coplanar;
    if (depth > t->info.max_depth) t->info.max_depth = depth;
    if (!b->failed) {
        const uint32_t f = build_node(b, fp, nfp, fe, nfe, id, depth + 1);
        if (!b->failed) t->nodes[id].child[0] = f;
    }
    if (!b->failed) {
        const uint32_t bk = build_node(b, bp, nbp, be, nbe, id, depth + 1);
        if (!b->failed) t->nodes[id].child[1] = bk;
    }
    sidx__free(b->a, fp);
    sidx__free(b->a, bp);
    sidx__free(b->a, fe);
    sidx__free(b->a, be);
    return id;
}

static void bsp_free_tree(const sidx_accel *a, bsp_tree *t)
{
    if (!t) return;
    sidx__free(a, t->nodes);
    sidx__free(a, t->pieces);
    sidx__free(a, t->verts);
    sidx__free(a, t->piece_refs);
    sidx__free(a, t->refs);
    sidx__free(a, t);
}

static sidx_status bsp_build_fn(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    bsp_tree *t = sidx__calloc(a, 1, sizeof *t);
    if (!t) return sidx__fail(err, SIDX_ERR_NOMEM, "bsp: out of memory");
    bsp_build b;
    memset(&b, 0, sizeof b);
    b.a = a;
    b.t = t;
    b.leaf_size = a->opt.leaf_size ? a->opt.leaf_size : 1;
    b.max_depth = a->opt.max_depth ? a->opt.max_depth : BSP_DEFAULT_DEPTH;
    if (b.max_depth > BSP_MAX_DEPTH) b.max_depth = BSP_MAX_DEPTH;
    /* Room for 4 cuts per input triangle: far beyond what the heuristic
     * makes on the built-in scenes (see tests/test_bsp.c). */
    b.piece_budget = m->num_triangles > (UINT32_MAX - 4096) / 5 ? UINT32_MAX : 5 * m->num_triangles + 4096;
    t->bounds = sidx_mesh_bounds(m);
    /* ε: a relative tolerance of the scene's size (float vertices carry
     * about 6e-8 relative error; 1e-6 leaves room for cut vertices). */
    double scale = 0.0;
    if (m->num_triangles) {
        const float c[6] = {t->bounds.min.x, t->bounds.min.y, t->bounds.min.z,
                            t->bounds.max.x, t->bounds.max.y, t->bounds.max.z};
        for (int i = 0; i < 6; ++i) if (fabs((double)c[i]) > scale) scale = fabs((double)c[i]);
    }
    b.eps = 1e-6 * (scale > 0.0 ? scale : 1.0);
    t->info.input_tris = m->num_triangles;

    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = t->bounds);
    uint32_t *root = sidx__alloc(a, m->num_triangles, sizeof *root);
    b.stamp = sidx__calloc(a, m->num_triangles, sizeof *b.stamp);
    if (!root || !b.stamp) b.failed = 1;
    for (uint32_t i = 0; i < m->num_triangles && !b.failed; ++i) {
        const sidx_vec3 v[3] = {sidx_mesh_vertex(m, i, 0), sidx_mesh_vertex(m, i, 1), sidx_mesh_vertex(m, i, 2)};
        root[i] = add_piece(&b, v, 3, i);
    }
    if (!b.failed) build_node(&b, root, b.failed ? 0 : m->num_triangles, NULL, 0, UINT32_MAX, 0);
    sidx__free(a, root);
    sidx__free(a, b.stamp);
    sidx__free(a, b.xp);
    sidx__free(a, b.xv);
    if (b.failed) {
        bsp_free_tree(a, t);
        return sidx__fail(err, SIDX_ERR_NOMEM, "bsp: out of memory");
    }
    t->info.nodes = t->num_nodes;
    t->info.pieces = 0;
    for (uint32_t i = 0; i < t->num_nodes; ++i) t->info.pieces += t->nodes[i].piece_count;
    t->info.ray_refs = t->num_refs;
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_NOTE,
              e_.text = "bsp: triangles cut by splitting planes (count = cuts, aux = pieces in the tree)";
              e_.count = t->info.splits; e_.aux = t->info.pieces);
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_END, e_.node = t->num_nodes; e_.count = t->num_refs;
              e_.depth = t->info.max_depth);
    a->impl = t;
    return SIDX_OK;
}

/* ---- ray traversal ------------------------------------------------------ */

typedef struct bsp_entry { uint32_t node, depth; double t_near, t_far; } bsp_entry;

/* Mailbox (as the grid's and kd-tree's, Amanatides & Woo): a triangle
 * lies in many leaves here — every leaf whose cell it borders lists it —
 * so a ray meets the same id again and again.  A retest cannot change
 * anything (tmax only shrinks: a miss stays a miss, and a hit already
 * set tmax to its t), so a small direct-mapped table of the ids this ray
 * has tested, on the stack (queries stay read-only and thread-safe),
 * skips them. */
#define BSP_MAILBOX 64

/* One walk for both queries: any_hit = 1 returns at the first hit. */
static SIDX_INLINE int bsp_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                const int any_hit, const int traced)
{
    const bsp_tree *t = a->impl;
    const sidx_mesh *m = a->mesh;
    float tmax = any_hit ? r->tmax : hit->t;
    float root_t_near, root_t_far;
    if (t->num_nodes == 0 ||
        !sidx__box_test(a->opt.box == SIDX_BOX_ROBUST, r, &t->bounds, r->tmin, tmax, &root_t_near, &root_t_far)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }
    const double o[3] = {r->org.x, r->org.y, r->org.z}, dir[3] = {r->dir.x, r->dir.y, r->dir.z};
    bsp_entry stack[BSP_STACK];
    int stack_len = 0;
    uint32_t visited = 0;
    uint32_t mailbox[BSP_MAILBOX];
    memset(mailbox, 0xff, sizeof mailbox);
    stack[stack_len++] = (bsp_entry){0, 0, root_t_near, root_t_far};
    while (stack_len > 0) {
        --stack_len;
        uint32_t node = stack[stack_len].node, depth = stack[stack_len].depth;
        double t_near = stack[stack_len].t_near, t_far = stack[stack_len].t_far;
        if (t_near > (double)tmax) continue; /* the segment starts behind the best hit */
        for (;;) {
            const bsp_node *nd = &t->nodes[node];
            ++visited;
            SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
                      e_.t_near = (float)t_near; e_.t_far = (float)t_far);
            if (nd->child[0] == UINT32_MAX) break;
            const double dist = nd->n[0] * o[0] + nd->n[1] * o[1] + nd->n[2] * o[2] - nd->d;
            const double nd_dir = nd->n[0] * dir[0] + nd->n[1] * dir[1] + nd->n[2] * dir[2];
            /* the near side: the one holding the origin; on the plane, the one the ray heads into */
            const int near_side = dist > 0.0 ? 0 : dist < 0.0 ? 1 : (nd_dir >= 0.0 ? 0 : 1);
            const uint32_t near_child = nd->child[near_side], far_child = nd->child[1 - near_side];
            ++depth;
            if (nd_dir == 0.0 || dist == 0.0) {
                /* parallel: never crosses; starting on the plane: heads into the near side.
                 * A ray lying in the plane visits both (its hits are on both sides' lists). */
                if (nd_dir == 0.0 && dist == 0.0 && stack_len < BSP_STACK) {
                    stack[stack_len++] = (bsp_entry){far_child, depth, t_near, t_far};
                }
                node = near_child;
                continue;
            }
            const double t_split = -dist / nd_dir;
            if (t_split < 0.0 || t_split > t_far) { node = near_child; continue; } /* moving away, or crossing after */
            if (t_split < t_near) { node = far_child; continue; }                  /* crossed before the segment */
            if (stack_len < BSP_STACK) {
                stack[stack_len++] = (bsp_entry){far_child, depth, t_split, t_far};
            }
            node = near_child;
            t_far = t_split;
        }
        /* leaf */
        const bsp_node *leaf = &t->nodes[node];
        for (uint32_t i = 0; i < leaf->ref_count; ++i) {
            const uint32_t tri = t->refs[leaf->ref_first + i];
            if (mailbox[tri % BSP_MAILBOX] == tri) continue;
            mailbox[tri % BSP_MAILBOX] = tri;
            float t_hit;
            const int h = sidx__mesh_tri_test(m, a->opt.tri, tri, r, tmax, &t_hit);
            SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.prim = tri; e_.node = node;
                      e_.result = h; e_.t = h ? t_hit : INFINITY);
            if (!h) continue;
            if (any_hit) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                          e_.t = t_hit; e_.count = visited);
                return 1;
            }
            tmax = t_hit;
            hit->t = t_hit;
            hit->prim = tri;
            SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = tri; e_.t = t_hit);
        }
        /* A hit before the ray leaves this leaf is final: everything the
         * ray meets earlier lies in leaves already visited.  The small
         * relative margin keeps a hit exactly on the exit plane (a
         * triangle lying in it) from ending the walk on rounding alone. */
        if (!any_hit && hit->prim != SIDX_NO_HIT && (double)hit->t < t_far - 1e-6 * fabs(t_far)) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_HIT_IN_CELL;
                      e_.t = hit->t; e_.count = visited);
            return 1;
        }
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_STACK_EMPTY;
              e_.t = any_hit ? INFINITY : hit->t; e_.count = visited);
    return 0;
}

static void bsp_intersect_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    (void)bsp_walk(a, r, q, hit, 0, 0);
}
static void bsp_intersect_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    (void)bsp_walk(a, r, q, hit, 0, 1);
}
static int bsp_occluded_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    sidx_hit dummy = sidx_hit_none();
    return bsp_walk(a, r, q, &dummy, 1, 0);
}
static int bsp_occluded_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    sidx_hit dummy = sidx_hit_none();
    return bsp_walk(a, r, q, &dummy, 1, 1);
}

/* The walk table (sidx_internal.h): the same for every build. */
static const sidx__walk_table bsp_walks = {bsp_intersect_plain, bsp_intersect_traced, bsp_occluded_plain,
                                            bsp_occluded_traced};

static void bsp_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    sidx__walk_intersect(&bsp_walks, a, r, q, hit);
}

static int bsp_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return sidx__walk_occluded(&bsp_walks, a, r, q);
}

static void bsp_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const bsp_tree *t = a->impl;
    s->nodes = t->num_nodes;
    s->leaves = t->info.leaves;
    s->max_depth = t->info.max_depth;
    s->prim_refs = t->num_refs;
    s->bytes = sizeof *t + (size_t)t->num_nodes * sizeof *t->nodes + (size_t)t->num_pieces * sizeof *t->pieces +
               (size_t)t->num_verts * sizeof *t->verts + (size_t)t->num_piece_refs * sizeof *t->piece_refs +
               (size_t)t->num_refs * sizeof *t->refs;
    uint32_t nonempty = 0;
    for (uint32_t i = 0; i < t->num_nodes; ++i) {
        if (t->nodes[i].child[0] != UINT32_MAX) continue;
        if (t->nodes[i].ref_count) ++nonempty;
        else s->empty_leaves++;
    }
    s->mean_leaf_prims = nonempty ? (double)t->num_refs / nonempty : 0.0;
}

static void bsp_destroy(sidx_accel *a)
{
    bsp_free_tree(a, a->impl);
    a->impl = NULL;
}

const sidx_accel_vtable sidx__bsp_vtable = {bsp_build_fn, bsp_intersect, bsp_occluded, bsp_stats, bsp_destroy, NULL};

/* ---- painter's order ---------------------------------------------------- */

static int is_bsp(const sidx_accel *a) { return a && a->vt == &sidx__bsp_vtable && a->impl; }

sidx_status sidx_bsp_info_get(const sidx_accel *a, sidx_bsp_info *out)
{
    if (!is_bsp(a) || !out) return SIDX_ERR_INVALID_ARG;
    *out = ((const bsp_tree *)a->impl)->info;
    return SIDX_OK;
}

sidx_status sidx_bsp_node_get(const sidx_accel *a, uint32_t node, sidx_bsp_node_view *out)
{
    if (!is_bsp(a) || !out) return SIDX_ERR_INVALID_ARG;
    const bsp_tree *t = a->impl;
    if (node >= t->num_nodes) return SIDX_ERR_INVALID_ARG;
    const bsp_node *nd = &t->nodes[node];
    for (int k = 0; k < 3; ++k) out->n[k] = nd->n[k];
    out->d = nd->d;
    out->child[0] = nd->child[0];
    out->child[1] = nd->child[1];
    out->piece_count = nd->piece_count;
    return SIDX_OK;
}

sidx_status sidx_bsp_node_piece(const sidx_accel *a, uint32_t node, uint32_t i, sidx_bsp_piece *out)
{
    if (!is_bsp(a) || !out) return SIDX_ERR_INVALID_ARG;
    const bsp_tree *t = a->impl;
    if (node >= t->num_nodes || i >= t->nodes[node].piece_count) return SIDX_ERR_INVALID_ARG;
    const bsp_piece *p = &t->pieces[t->piece_refs[t->nodes[node].piece_first + i]];
    out->tri = p->tri;
    out->num_verts = p->num;
    out->verts = t->verts + p->first;
    out->node = node;
    return SIDX_OK;
}

/* A node's own pieces do not overlap in depth (they lie in one plane, or
 * are the single piece of a leaf), so any order among them is right; the
 * two orders walk them in opposite directions so that front-to-back is
 * exactly the reverse of back-to-front. */
static int emit_pieces(const bsp_tree *t, uint32_t node, uint32_t depth, int reverse, sidx_bsp_piece_fn fn,
                       void *user, const sidx_hook *hook)
{
    const bsp_node *nd = &t->nodes[node];
    for (uint32_t j = 0; j < nd->piece_count; ++j) {
        const uint32_t i = reverse ? nd->piece_count - 1 - j : j;
        const bsp_piece *p = &t->pieces[t->piece_refs[nd->piece_first + i]];
        sidx_bsp_piece out = {p->tri, p->num, t->verts + p->first, node};
        SIDX_EMIT(1, hook, SIDX_EV_PRIM_TEST, e_.node = node; e_.depth = depth; e_.prim = p->tri; e_.result = 1;
                  e_.count = p->num);
        if (fn(&out, user)) return 1;
    }
    return 0;
}

/* The painter's walk (Fuchs, Kedem, Naylor 1980): at each node, first the
 * side the eye is NOT on (everything there can only be hidden by what is
 * on the eye's side or in the plane), then the pieces in the plane, then
 * the eye's side.  Front to back is the mirror image.  No sorting: the
 * tree was built once; any eye position reuses it. */
sidx_status sidx_bsp_paint(const sidx_accel *a, sidx_vec3 eye, sidx_bsp_order order, sidx_bsp_piece_fn fn,
                           void *user, const sidx_hook *hook)
{
    if (!is_bsp(a) || !fn || !sidx_v3_isfinite(eye) ||
        (order != SIDX_BSP_BACK_TO_FRONT && order != SIDX_BSP_FRONT_TO_BACK))
        return SIDX_ERR_INVALID_ARG;
    const bsp_tree *t = a->impl;
    /* stack entries: node to expand, or (phase 1) node whose own pieces are due */
    struct { uint32_t node, depth, pieces_only; } stack[BSP_STACK + 2];
    int stack_len = 0;
    stack[stack_len].node = 0; stack[stack_len].depth = 0; stack[stack_len++].pieces_only = 0;
    while (stack_len > 0) {
        --stack_len;
        const uint32_t node = stack[stack_len].node, depth = stack[stack_len].depth;
        const bsp_node *nd = &t->nodes[node];
        if (stack[stack_len].pieces_only) {
            if (emit_pieces(t, node, depth, order == SIDX_BSP_FRONT_TO_BACK, fn, user, hook)) return SIDX_OK;
            continue;
        }
        SIDX_EMIT(1, hook, SIDX_EV_NODE_ENTER, e_.node = node; e_.depth = depth);
        if (nd->child[0] == UINT32_MAX) {
            if (emit_pieces(t, node, depth, order == SIDX_BSP_FRONT_TO_BACK, fn, user, hook)) return SIDX_OK;
            continue;
        }
        const double dist = nd->n[0] * eye.x + nd->n[1] * eye.y + nd->n[2] * eye.z - nd->d;
        const int eye_side = dist >= 0.0 ? 0 : 1; /* on the plane: its pieces are seen edge-on, any order works */
        const uint32_t near_child = nd->child[eye_side], far_child = nd->child[1 - eye_side];
        const uint32_t first = order == SIDX_BSP_BACK_TO_FRONT ? far_child : near_child;
        const uint32_t last = order == SIDX_BSP_BACK_TO_FRONT ? near_child : far_child;
        /* pushed in reverse: first, then this node's pieces, then last */
        stack[stack_len].node = last; stack[stack_len].depth = depth + 1; stack[stack_len++].pieces_only = 0;
        stack[stack_len].node = node; stack[stack_len].depth = depth; stack[stack_len++].pieces_only = 1;
        stack[stack_len].node = first; stack[stack_len].depth = depth + 1; stack[stack_len++].pieces_only = 0;
    }
    return SIDX_OK;
}
