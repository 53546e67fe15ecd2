/* sidx/rayclass.h — ray classification (Arvo & Kirk 1987), registered as
 * "rayclass" for closest-hit and any-hit queries.
 *
 * The deck: "partitioning of space and direction ... roughly pre-computes
 * visibility for the entire scene ... very costly preprocessing, cheap
 * traversal ... memory hungry, even with lazy evaluation ... seldom used in
 * practice".  sidx_rayclass_info_get gives the numbers to judge that by:
 * what the 5D subdivision holds, next to sidx_accel_stats.bytes.
 *
 * Options used: leaf_size (default 8 candidates), max_depth (default 8
 * levels of 5D bisection per direction face, at most 24). */
#ifndef SIDX_RAYCLASS_H
#define SIDX_RAYCLASS_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_rayclass_info {
    uint32_t nodes, leaves, max_depth;
    uint64_t candidates;          /* candidate references in all leaves (the memory) */
    double mean_candidates;       /* per leaf */
    uint32_t max_candidates;      /* largest leaf list */
    uint64_t beam_tests;          /* beam-vs-box tests made by the build (the preprocessing) */
    size_t bytes;
} sidx_rayclass_info;

/* SIDX_ERR_INVALID_ARG if a is not a "rayclass" structure. */
sidx_status sidx_rayclass_info_get(const sidx_accel *a, sidx_rayclass_info *out);

#ifdef __cplusplus
}
#endif
#endif
