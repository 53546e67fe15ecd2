/* sidx/viz.h — visualisation helpers (libsidxviz.a, code in viz/).
 *
 * Everything here is rebuilt from the hook events alone: a structure that
 * emits BUILD_NODE with parent links can be drawn as a tree without the
 * viewer knowing anything about its node layout.
 *
 *   sidx_viz_tree      the tree rebuilt from BUILD_* events (and, with a
 *                      ray, what the ray did at each node)
 *   sidx_dot_write     the tree as a Graphviz graph: .dot/.gv text, or
 *                      .svg/.png/.pdf laid out with dot
 *
 * Link with libsidxviz.a, libsidx.a and `pkg-config --libs libcgraph libgvc`.
 * Not part of sidx.h: include <sidx/viz.h> explicitly. */
#ifndef SIDX_VIZ_H
#define SIDX_VIZ_H

#include <stddef.h>
#include <stdio.h>
#include <stdint.h>
#include "accel.h"
#include "hook.h"
#include "mesh.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the tree model ------------------------------------------------------ */

#define SIDX_VIZ_NONE UINT32_MAX
/* id of the node added above several roots (a two-level grid's top cells) */
#define SIDX_VIZ_VIRTUAL_ROOT (UINT32_MAX - 1u)

typedef struct sidx_viz_node {
    uint32_t id;            /* the structure's node id (as in events) */
    uint32_t parent;        /* index into sidx_viz_tree.nodes; SIDX_VIZ_NONE for the root */
    uint32_t child_base;    /* children: child_count consecutive entries of */
    uint32_t child_count;   /* sidx_viz_tree.children starting at child_base */
    uint32_t depth;
    uint32_t count;         /* primitives below (BUILD_NODE count) */
    sidx_aabb bounds;
    int32_t cell[3];        /* grids: cell coordinates, -1 otherwise */
    /* decision taken at the node */
    int is_leaf;            /* BUILD_LEAF seen */
    int has_split;          /* BUILD_SPLIT seen */
    int32_t axis;           /* split axis, -1 none (BSP: plane normal in plane_n) */
    float pos, cost;        /* split position (or BSP plane offset), SAH cost of split / leaf */
    sidx_vec3 plane_n;      /* BSP planes (axis -1 split) */
    uint32_t n_left, n_right;
    int32_t leaf_reason;    /* sidx_leaf_reason */
    uint32_t leaf_count;    /* BUILD_LEAF count */
    const uint32_t *prims;  /* leaf: its leaf_count primitive ids from BUILD_LEAF's prims (the tree's own
                               copy, in sidx_viz_tree.prim_ids); NULL when the events did not list them */
    uint32_t candidates;    /* BUILD_CANDIDATE events for this node */
    size_t build_event;     /* index of its BUILD_NODE in the build event array */
    /* filled by sidx_viz_tree_apply_ray */
    uint32_t visit_order;   /* 1-based order of the first NODE_ENTER; 0 = not entered */
    int box_result;         /* last BOX_TEST on this node: 1 hit, 0 miss, -1 not tested */
    int hit_leaf;           /* 1: the final hit was found here */
    uint32_t prims_tested;  /* PRIM_TEST events while this node was current */
    uint32_t tested_ids[4]; /* the first few primitive ids tested here */
} sidx_viz_node;

typedef struct sidx_viz_tree {
    const char *structure;  /* from the events ("bvh", ...), static */
    sidx_viz_node *nodes;   /* in BUILD_NODE order; nodes[root] is the root */
    size_t count;
    uint32_t *children;     /* node indices, grouped by parent */
    uint32_t root;
    uint32_t max_depth;
    uint32_t leaves;
    int virtual_root;       /* 1: nodes[root] was added above the structure's several roots */
    uint32_t *prim_ids;     /* every leaf's prims list, leaf after leaf (nodes[i].prims point here) */
    size_t num_prim_ids;
    uint64_t *lookup;       /* internal: (id << 32 | index), sorted, for sidx_viz_tree_find */
    uint32_t visited;       /* nodes entered by the applied ray */
    uint32_t hit_prim;      /* final hit of the applied ray, SIDX_NO_HIT if none */
    float hit_t;
} sidx_viz_tree;

/* Rebuilds the tree from recorded build events (other event types are
 * ignored, so a whole recording can be passed).  Fails with
 * SIDX_ERR_UNSUPPORTED and "<structure> does not emit a tree" when there is
 * no BUILD_NODE, several roots and no parent links at all (a uniform grid's
 * cells), or a parent that was never created.  Several roots with children
 * (a two-level grid) get one virtual root above them (virtual_root = 1);
 * SIDX_ERR_NOMEM on allocation failure.  Free with sidx_viz_tree_free. */
sidx_status sidx_viz_tree_from_events(const sidx_event *ev, size_t n, sidx_viz_tree *out, sidx_error *err);
void sidx_viz_tree_free(sidx_viz_tree *t);
/* Index of the node with structure id `id`, or SIDX_VIZ_NONE. */
uint32_t sidx_viz_tree_find(const sidx_viz_tree *t, uint32_t id);
/* Marks visit order, box results, prim tests and the hit leaf from one
 * ray's traversal events (build events are ignored).  Clears earlier marks. */
void sidx_viz_tree_apply_ray(sidx_viz_tree *t, const sidx_event *ev, size_t n);
/* Nodes and leaf primitive references in the subtree below (and including) node i. */
void sidx_viz_tree_subtree(const sidx_viz_tree *t, uint32_t i, uint32_t *nodes, uint64_t *prims);

/* ---- Graphviz -------------------------------------------------------------- */

#define SIDX_DOT_DEFAULT_DEPTH 6u
#define SIDX_DOT_ALL_DEPTHS UINT32_MAX
#define SIDX_DOT_DEFAULT_WIDTH 12u  /* bottom boxes: a drawing about 2,500 px (26 in) wide */
#define SIDX_DOT_DEFAULT_NODES 400u /* boxes in all: dot lays them out in a second or two */
#define SIDX_DOT_UNLIMITED UINT32_MAX

typedef struct sidx_dot_options {
    uint32_t max_depth;            /* levels drawn (depths 0 .. max_depth - 1); deeper subtrees
                                      become one summary node each; 0 =
                                      SIDX_DOT_DEFAULT_DEPTH; SIDX_DOT_ALL_DEPTHS = no cut */
    uint32_t max_width;            /* bottom boxes (drawn leaves, folds, summaries), about the
                                      drawing's width in boxes: nodes open best first (visited by
                                      the ray, then holding the most primitives), siblings past it
                                      fold into one "… N more cells (M empty)" box and the caption
                                      says so; 0 = SIDX_DOT_DEFAULT_WIDTH; SIDX_DOT_UNLIMITED = no
                                      fold */
    uint32_t max_nodes;            /* boxes in all, about; 0 = SIDX_DOT_DEFAULT_NODES;
                                      SIDX_DOT_UNLIMITED = no limit */
    FILE *progress;                /* stage lines (build, layout) go here; NULL = quiet */
    const sidx_build_options *build; /* passed to the build (its hook is replaced); NULL = defaults */
    int has_ray;                   /* 1: trace ray_org + t·ray_dir and colour what it did */
    sidx_vec3 ray_org, ray_dir;
    sidx_traversal traversal;      /* for the traced ray */
    const char *format;            /* NULL = from the path's extension: dot, gv, svg, png, pdf */
    const char *title;             /* graph label; NULL = "<structure>: <n> nodes" */
    const char *scene;             /* sidx_dot_write: the SCENE the mesh was opened from, so a scene
                                      with its own tree gets it (sidx_scene_accel_build); NULL = none */
    const sidx_accel *labels;      /* node labels (sidx_accel_node_label) shown before the node ids;
                                      NULL = none.  sidx_dot_write uses the structure it builds */
} sidx_dot_options;

/* Builds `accel_name` over mesh with a recording hook, rebuilds the tree
 * from the events, optionally traces the ray, and writes the graph to path
 * ("-" = stdout for the text formats).  opt may be NULL.  Errors:
 * SIDX_ERR_INVALID_ARG (NULL args, bad ray, unknown extension), the build's
 * errors, SIDX_ERR_UNSUPPORTED ("brute does not emit a tree", or a
 * libsidxviz built without Graphviz: HAVE_GRAPHVIZ=0 or libgraphviz-dev
 * missing), SIDX_ERR_IO. */
sidx_status sidx_dot_write(const sidx_mesh *mesh, const char *accel_name, const sidx_dot_options *opt,
                           const char *path, sidx_error *err);
/* The same from already recorded events: build (BUILD_*) events and,
 * optionally, one ray's traversal events (trav may be NULL). */
sidx_status sidx_dot_write_events(const sidx_event *build, size_t nbuild, const sidx_event *trav, size_t ntrav,
                                  const sidx_dot_options *opt, const char *path, sidx_error *err);

/* Parses "ox,oy,oz,dx,dy,dz" (programs' --ray).  Returns 0 on success. */
int sidx_viz_parse_ray(const char *s, sidx_vec3 *org, sidx_vec3 *dir);

/* The build knobs of the programs' and lessons' command lines: --bins N,
 * --c-trav X, --c-tri X, --leaf-size N, --max-depth N, --lambda X
 * (grid_density), --no-mailbox, --empty-bonus X and --optimize MS
 * (optimize_ms), each filling one field
 * of *bo.  flag is argv[i], value argv[i + 1] (NULL at the end).  Returns
 * 0 if flag is no knob (nothing written), 1 if it took flag alone, 2 if it
 * took flag and value, -1 on a missing or bad value (or NULL flag / bo):
 * then msg holds "--bins wants ..., not '1'" and *bo is unchanged. */
int sidx_viz_build_knob(const char *flag, const char *value, sidx_build_options *bo, char *msg, size_t size);
/* Their --help lines: a heading, then one "  --flag ..." line each. */
const char *sidx_viz_build_knobs_help(void);

#ifdef __cplusplus
}
#endif
#endif
