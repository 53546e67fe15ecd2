/* sidx/bsp.h — what the BSP tree ("bsp") offers beyond ray queries.
 *
 * The deck's BSP tree "recursively splits space with planes" of arbitrary
 * position and orientation and is "used for visibility computation, e.g. in
 * games (Doom!): enumerating objects in back to front order".  Build it like
 * any structure (sidx_accel_build("bsp", ...)); then, from any viewpoint,
 *
 *     sidx_bsp_paint(bsp, eye, SIDX_BSP_BACK_TO_FRONT, draw, user);
 *
 * calls draw() once per polygon piece, farthest first — the painter's
 * algorithm with no sorting at draw time.  Triangles that straddle a
 * splitting plane were cut into convex pieces during the build (each piece
 * remembers its original triangle); sidx_bsp_info_get reports how many cuts
 * the build made.
 *
 * 2D (Doom-style): build over the "flat2d" scene (one tilted triangle per
 * 2D shape, crossing z = 0 along its longest median) and put the eye in
 * the plane z = 0: the order is then that of a 2D BSP over those
 * segments.  3D: any mesh, any eye.
 *
 * The order is exact when every leaf holds at most one piece (the default
 * leaf size, 1).  A leaf forced by the depth limit or the split budget may
 * hold several; their mutual order is then arbitrary and
 * sidx_bsp_info.unordered_leaves counts such leaves. */
#ifndef SIDX_BSP_H
#define SIDX_BSP_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_bsp_piece {
    uint32_t tri;            /* original triangle index in the mesh */
    uint32_t num_verts;      /* 3 for an uncut triangle; a cut adds at most one vertex */
    const sidx_vec3 *verts;  /* convex polygon in the triangle's winding (valid during the callback) */
    uint32_t node;           /* node holding it: an inner node (piece lies in its plane) or a leaf */
} sidx_bsp_piece;

typedef enum sidx_bsp_order {
    SIDX_BSP_BACK_TO_FRONT = 0, /* painter's algorithm: far pieces first, near ones drawn over them */
    SIDX_BSP_FRONT_TO_BACK      /* nearest first (e.g. for a span buffer that fills each pixel once) */
} sidx_bsp_order;

/* Return non-zero to stop the enumeration. */
typedef int (*sidx_bsp_piece_fn)(const sidx_bsp_piece *piece, void *user);

typedef struct sidx_bsp_info {
    uint32_t input_tris;       /* triangles in the mesh */
    uint32_t pieces;           /* pieces in the tree (input_tris + splits, minus nothing) */
    uint32_t splits;           /* polygons cut in two by a splitting plane */
    uint32_t nodes, leaves, max_depth;
    uint32_t polygon_planes;   /* inner nodes whose plane is a triangle's plane (autopartition) */
    uint32_t free_planes;      /* inner nodes with an axis-aligned plane (no polygon plane separated) */
    uint32_t coplanar_pieces;  /* pieces stored at inner nodes, in their plane */
    uint32_t unordered_leaves; /* leaves with more than one piece (painter order inside is arbitrary) */
    uint64_t ray_refs;         /* triangle references in leaves (what ray queries test) */
} sidx_bsp_info;

/* SIDX_ERR_INVALID_ARG if a is NULL or not a "bsp" structure. */
sidx_status sidx_bsp_info_get(const sidx_accel *a, sidx_bsp_info *out);

/* Enumerates every piece once, in the given order as seen from eye.
 * SIDX_ERR_INVALID_ARG if a is not a "bsp" structure, fn is NULL or eye is
 * not finite.  The walk emits NODE_ENTER events (node id, depth) and one
 * PRIM_TEST per piece (prim = original triangle) to hook, which may be NULL. */
sidx_status sidx_bsp_paint(const sidx_accel *a, sidx_vec3 eye, sidx_bsp_order order, sidx_bsp_piece_fn fn,
                           void *user, const sidx_hook *hook);

/* A read-only view of one node, for code that walks the tree itself
 * (lessons/exercises/14_bsp_painter): node ids run from 0 (the root) to
 * sidx_bsp_info.nodes - 1. */
typedef struct sidx_bsp_node_view {
    double n[3], d;          /* inner nodes: the plane n·x = d (unit n); the front side is n·x > d */
    uint32_t child[2];       /* [0] front, [1] back; UINT32_MAX for a leaf */
    uint32_t piece_count;    /* pieces kept here: those lying in the plane (inner) or the leaf's */
} sidx_bsp_node_view;

/* SIDX_ERR_INVALID_ARG if a is not a "bsp" structure, out is NULL or node
 * is out of range. */
sidx_status sidx_bsp_node_get(const sidx_accel *a, uint32_t node, sidx_bsp_node_view *out);
/* Piece i (0 <= i < piece_count) of node, in the node's order (the one
 * sidx_bsp_paint draws back to front); verts stay valid as long as the
 * structure.  SIDX_ERR_INVALID_ARG as above, or for i out of range. */
sidx_status sidx_bsp_node_piece(const sidx_accel *a, uint32_t node, uint32_t i, sidx_bsp_piece *out);

#ifdef __cplusplus
}
#endif
#endif
