/* sidx/exercise.h — how an exercise reports its steps.
 *
 * A student's solution to one of lessons/exercises/ runs on plain data
 * (the mesh, a structure's nodes through a read-only view such as
 * sidx/bvh.h or sidx/kdtree.h) and says what it does through these calls.
 * Each call emits exactly the event a structure of the library emits for
 * the same step (sidx/hook.h, docs/events.md), so sidx-check can hold the
 * student's trace against the library's one event at a time.
 *
 * The context is filled by the checker; the student only passes it on.
 * Every call is a no-op when ex or its hook is NULL. */
#ifndef SIDX_EXERCISE_H
#define SIDX_EXERCISE_H

#include <stdint.h>
#include "hook.h"
#include "intersect.h"
#include "mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_ex {
    const sidx_hook *hook;   /* where the events go */
    uint32_t ray_id;         /* copied into the events */
    const char *structure;   /* "bvh", "grid", ... (static) */
    const sidx_ray *ray;     /* the ray of this case (NULL for build exercises) */
    const sidx_mesh *mesh;   /* the scene of this case */
    sidx_tri_method tri;     /* the triangle test sidx_ex_test_triangle runs */
    sidx_box_method box;     /* the slab test sidx_ex_test_box runs */
} sidx_ex;

/* ---- traversal steps ---------------------------------------------------- */

/* BOX_TEST: node's box tested; t_near, t_far reported only when result is 1. */
void sidx_ex_box_test(const sidx_ex *ex, uint32_t node, const sidx_aabb *box, int result, float t_near, float t_far);
/* NODE_ENTER: the walk visits node at tree depth `depth` over [t_near, t_far]. */
void sidx_ex_node_enter(const sidx_ex *ex, uint32_t node, uint32_t depth, float t_near, float t_far);
/* NODE_ENTER of a grid cell (x, y, z); the cell id is x + res_x·(y + res_y·z). */
void sidx_ex_cell_enter(const sidx_ex *ex, uint32_t cell_id, int x, int y, int z, float t_near, float t_far);
/* STACK_PUSH / STACK_POP: stack_size is the size after the push / before the pop. */
void sidx_ex_push(const sidx_ex *ex, uint32_t node, uint32_t stack_size, float t_near, float t_far);
void sidx_ex_pop(const sidx_ex *ex, uint32_t node, uint32_t stack_size, float t_near, float t_far);
/* PRIM_TEST: triangle prim tested; t only when result is 1. */
void sidx_ex_prim_test(const sidx_ex *ex, uint32_t prim, int result, float t);
/* HIT_UPDATE: the closest hit so far is now prim at t. */
void sidx_ex_hit_update(const sidx_ex *ex, uint32_t prim, float t);
/* MAILBOX_HIT: prim was already tested for this ray and is skipped. */
void sidx_ex_mailbox_hit(const sidx_ex *ex, uint32_t prim);

/* The per-ray cache of object IDs of exercise 07 (deck 000, "Uniform Grid
 * Traversal": "Per-ray cache of object IDs — data local to a ray"): the
 * library's grids keep the same table, direct-mapped, slot prim mod 32. */
#define SIDX_EX_MAILBOX_SIZE 32u
typedef struct sidx_ex_mailbox {
    uint32_t id[SIDX_EX_MAILBOX_SIZE];
} sidx_ex_mailbox;

/* ---- build steps ------------------------------------------------------------ */

/* BUILD_CANDIDATE / BUILD_SPLIT: a split plane of node evaluated / chosen. */
void sidx_ex_candidate(const sidx_ex *ex, uint32_t node, int axis, float pos, float cost, uint32_t n_left,
                       uint32_t n_right);
void sidx_ex_split(const sidx_ex *ex, uint32_t node, int axis, float pos, float cost, uint32_t n_left,
                   uint32_t n_right);

/* ---- the library's elementary tests, reporting themselves -------------------- */

/* The slab test ex->box of ex->ray against *box over [tmin, tmax], then
 * BOX_TEST for node.  Returns 1 on a hit and fills *t_near, *t_far. */
int sidx_ex_test_box(const sidx_ex *ex, uint32_t node, const sidx_aabb *box, float tmin, float tmax, float *t_near,
                     float *t_far);
/* The triangle test ex->tri of ex->ray against triangle prim of ex->mesh,
 * hits in [ray.tmin, tmax), then PRIM_TEST.  Returns 1 and fills *t on a hit. */
int sidx_ex_test_triangle(const sidx_ex *ex, uint32_t prim, float tmax, float *t);

/* ---- references sidx-check compares a student's function with ------------ */

/* Möller–Trumbore in the slide's Cramer form (deck 001, "Moller-Trumbore
 * Algorithm"), computed term by term as the slide writes it: e1 = p1 - p0,
 * e2 = p2 - p0, s = o - p0, D = (e1 x d)·e2; no hit when D = 0; u =
 * -(s x e2)·d / D, v = (e1 x d)·s / D, t = -(s x e2)·e1 / D; a hit when
 * u, v >= 0, u + v <= 1 and ray.tmin <= t < tmax, then *t, *u, *v are
 * filled (each may be NULL); r NULL: 0.  sidx_intersect_triangle's Möller–Trumbore
 * is the paper's arrangement of the same solution, which rounds
 * differently; exercise 02 is held against this one. */
int sidx_ex_reference_moller_cramer(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax,
                                    float *t, float *u, float *v);
/* The SAH cost of one split (deck 001, "Surface Area Heuristic"), with the
 * arithmetic of the "bvh" builds: C_trav + C_tri·(A_L·N_L + A_R·N_R)·(1/A). */
float sidx_ex_reference_sah_cost(sidx_aabb parent, sidx_aabb left, uint32_t n_left, sidx_aabb right,
                                 uint32_t n_right, float c_trav, float c_tri);

#ifdef __cplusplus
}
#endif
#endif
