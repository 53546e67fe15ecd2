/* Exercise 10 — the private exercise: a worst case.
 *
 * Slides: deck 000, "Spatial index structures": "Can reduce complexity to
 * O(log n) on average; worst case complexity is still O(n).  Private
 * exercise: come up with a worst case example."  Deck 001, "Uniform
 * Grid" ("cannot adapt to non-uniform distribution of geometry").
 *
 * worst_case_scene writes into *out (sidx_mesh_from_arrays) a scene of
 * exactly n triangles on which `structure` — "bvh", "grid" or "kdtree",
 * the library's own, built with its defaults — needs about n triangle
 * tests per ray.  The checker builds it for n = 64, 256 and 1024 and
 * shoots 24 rays, each aimed at the centre of one of your triangles from
 * a random direction outside the scene, and counts the triangle tests:
 * at every n they must average at least n/2 per ray (they grow like n,
 * not like log n).
 *
 * As handed out it writes n random small triangles, a "good" scene: run
 * the checker to see how few tests each structure needs on it, then think
 * about what each structure cannot separate.
 *
 * Check with:   make exercise EX=10_worst_case
 * Only the function body is yours to write. */
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"

void worst_case_scene(const char *structure, uint32_t n, sidx_mesh *out)
{
    (void)structure;
    float *xyz = malloc((size_t)n * 9 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * 3 * sizeof *idx);
    uint32_t st = 1u;
    for (uint32_t i = 0; xyz && idx && i < 3 * n; ++i) { /* n random triangles of size 0.05 in the unit cube */
        idx[i] = i;
        for (int k = 0; k < 3; ++k) {
            st = st * 1664525u + 1013904223u;
            const float r = (float)(st >> 8) / 16777216.0f;
            xyz[3 * i + (uint32_t)k] = i % 3 ? xyz[3 * (i - i % 3) + (uint32_t)k] + 0.05f * r : r;
        }
    }
    if (xyz && idx) sidx_mesh_from_arrays(out, xyz, 3 * n, idx, n, NULL);
    free(xyz);
    free(idx);
}
