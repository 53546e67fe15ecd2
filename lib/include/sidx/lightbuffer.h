/* sidx/lightbuffer.h — the light buffer (Haines & Greenberg 1986): directional
 * partitioning around one point light, for shadow rays only.
 *
 * The deck: directional partitioning is "useful only for rays that start
 * from a single point ... point light sources"; its "variation: light
 * buffer (for shadow rays)" is built "lazy and conservative", and "stores
 * the last found occluder in the directional structure" to "test that entry
 * first for the next shadow test".
 *
 * A direction cube around the light: 6 faces × res × res cells.  Each cell
 * lists every triangle that could be seen from the light through it
 * (conservative: the bounding rectangle of the triangle's projection,
 * clipped to the face's pyramid), sorted by distance from the light.  A
 * shadow query for a surface point p looks up the cell of the direction
 * light → p and tests only that cell's list — nearest to the light first,
 * stopping at triangles farther from the light than p.
 *
 *     sidx_lightbuffer *lb;
 *     sidx_lightbuffer_build(&mesh, light, 32, 0, NULL, &lb, &err);
 *     sidx_lightbuffer_cache cache;               // one per thread
 *     sidx_lightbuffer_cache_init(lb, &cache);
 *     int shadowed;
 *     sidx_lightbuffer_occluded(lb, p, 1e-3f, 1.0f - 1e-3f, &cache, NULL, &shadowed);
 *
 * Lazy cells: with eager = 0 a cell's list is made on the first query that
 * lands in it (a scan of that face's triangle rectangles: the deck's
 * "expensive and linear in # of objects", paid only for cells some shadow
 * ray needs).  Filling is guarded by a mutex and published with an atomic
 * flag, so one built light buffer may be queried from many threads.
 *
 * The last-occluder cache lives in a caller-owned sidx_lightbuffer_cache,
 * not in the structure as in the original: written by every query, it would
 * be a data race between threads (and a shared cache line).  Give each
 * thread its own.
 *
 * The mesh must outlive the light buffer. */
#ifndef SIDX_LIGHTBUFFER_H
#define SIDX_LIGHTBUFFER_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_lightbuffer sidx_lightbuffer;

/* res: cells along a face edge (0 = 32, at most 1024).  eager: 1 fills
 * every cell now, 0 lazily.  opt: hook (build events), alloc, tri (the
 * triangle test); other fields are ignored; NULL = defaults.
 * Errors: SIDX_ERR_INVALID_ARG (NULL, light not finite, res > 1024),
 * SIDX_ERR_BAD_GEOMETRY, SIDX_ERR_NOMEM. */
sidx_status sidx_lightbuffer_build(const sidx_mesh *m, sidx_vec3 light, uint32_t res, int eager,
                                   const sidx_build_options *opt, sidx_lightbuffer **out, sidx_error *err);
void sidx_lightbuffer_destroy(sidx_lightbuffer *lb); /* NULL is fine */

/* Per-thread state: the last occluder found in each cell, and counters. */
typedef struct sidx_lightbuffer_cache {
    uint32_t *last;          /* per cell; SIDX_NO_HIT = none yet */
    uint32_t cells;
    uint64_t queries;        /* shadow queries answered */
    uint64_t occluded;       /* ... of which in shadow */
    uint64_t cache_tests;    /* queries that tested a cached occluder */
    uint64_t cache_hits;     /* ... and found it still blocks the light */
    uint64_t tri_tests;      /* triangle tests, cached ones included */
} sidx_lightbuffer_cache;
sidx_status sidx_lightbuffer_cache_init(const sidx_lightbuffer *lb, sidx_lightbuffer_cache *c);
void sidx_lightbuffer_cache_free(sidx_lightbuffer_cache *c);

/* The shadow ray of point p: origin p, direction light − p (not
 * normalized: t = 1 is the light), t in [tmin, tmax).  Use it to ask any
 * other structure the same question.  SIDX_ERR_INVALID_ARG if p is the
 * light or not finite. */
sidx_status sidx_lightbuffer_shadow_ray(const sidx_lightbuffer *lb, sidx_vec3 p, float tmin, float tmax,
                                        sidx_ray *out);

/* *occluded = 1 if a triangle blocks that shadow ray.  cache may be NULL
 * (no last-occluder cache).  q: hook (events below) and ray_id; NULL = none.
 * Events: NODE_ENTER (node = cell id = (face·res + j)·res + i, cell =
 * {face, i, j}, count = list length), a NOTE when the cell is filled
 * lazily, PRIM_TEST per triangle (the cached one first), TERMINATE
 * (ANY_HIT, or STACK_EMPTY when the list ran out or reached p's distance). */
sidx_status sidx_lightbuffer_occluded(const sidx_lightbuffer *lb, sidx_vec3 p, float tmin, float tmax,
                                      sidx_lightbuffer_cache *cache, const sidx_query *q, int *occluded);

/* A read-only view of the cell a shadow ray looks up (exercise
 * 18_light_buffer walks it as the query does): the cell of the direction
 * light -> ray origin, its list (filled now if the cell is lazy), and the
 * distance from the light beyond which no listed triangle can block the
 * ray, (1 - tmin)·|dir| widened for the float distances: the bound the
 * query stops at.  SIDX_ERR_INVALID_ARG for NULL, SIDX_ERR_NOMEM if a lazy
 * cell cannot be filled.  The pointers stay valid while lb lives. */
typedef struct sidx_lightbuffer_cell_view {
    uint32_t id;            /* (face·res + j)·res + i: the index of the cache's `last` */
    int face, i, j;         /* faces +x, -x, +y, -y, +z, -z */
    uint32_t count;         /* triangles in the list */
    const uint32_t *tris;   /* nearest to the light first */
    const float *dist;      /* their distances from the light */
    float reach;            /* a triangle with dist > reach cannot block */
} sidx_lightbuffer_cell_view;
sidx_status sidx_lightbuffer_cell_get(const sidx_lightbuffer *lb, const sidx_ray *shadow_ray,
                                      sidx_lightbuffer_cell_view *out);

typedef struct sidx_lightbuffer_stats {
    uint32_t res, cells;
    uint32_t cells_filled;     /* lists made so far (all of them when eager) */
    uint64_t refs;             /* triangle references in the filled lists */
    uint64_t face_entries;     /* (triangle, face) rectangles kept for filling */
    size_t bytes;              /* memory held now (mesh excluded) */
    sidx_vec3 light;
} sidx_lightbuffer_stats;
sidx_status sidx_lightbuffer_stats_get(const sidx_lightbuffer *lb, sidx_lightbuffer_stats *s);

#ifdef __cplusplus
}
#endif
#endif
