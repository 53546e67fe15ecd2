/* sidx/packet.h — packets of coherent rays, and frustum culling.
 *
 * The deck's "Packet Tracing: combine many similar rays (e.g. primary or
 * shadow rays), trace them together in SIMD fashion; all rays perform the
 * same traversal operations, all rays intersect the same geometry" (Wald,
 * Slusallek, Benthin, Wagner 2001, "Interactive rendering with coherent
 * ray tracing"), over the binary BVH as in Wald, Boulos, Shirley 2007
 * ("Ray tracing deformable scenes using dynamic bounding volume
 * hierarchies"):
 *
 *   - a packet is up to SIDX_PACKET_MAX rays (a 4x4 or 8x8 image tile);
 *     a node is tested against 8 rays at a time (AVX2, or a scalar loop);
 *   - "first hit" early descent: scanning stops at the first group of 8
 *     rays with a hit, the node is entered for the whole packet, and the
 *     index of that group is kept on the stack so children skip the rays
 *     known to miss;
 *   - early exit: a node no ray of the packet hits is dropped at once;
 *   - adaptive switch (the deck's "hybrid mix with adaptive switch"): a
 *     packet whose rays do not share direction signs is traced ray by ray
 *     from the start, and when only 1 or 2 rays of the last group — or,
 *     deeper than 8 levels, of the whole packet — still hit an inner
 *     node, those rays finish that subtree alone;
 *   - frustum culling (SIDX_PACKET_FRUSTUM; Reshetov, Soupikov, Hurley
 *     2005; Benthin & Wald): when every ray starts at one point (a pinhole
 *     camera), the 4 corner rays of the tile span a pyramid holding every
 *     ray; a node box entirely outside one of its 4 planes is culled with
 *     one test instead of up to 64 ray-box tests — that pays in the upper
 *     levels, where boxes are large and the frustum is small relative to
 *     them; deeper than frustum_depth the walk switches to per-ray tests.
 *     The frustum is tested only where the first active group of 8 rays
 *     missed and at least 2 more groups remain (it replaces those tests),
 *     so a 4x4 tile (2 groups) never uses it.
 *
 * Over the wide BVHs "bvh4" and "bvh8" (packet_wide.c) a node holds 4 or
 * 8 child boxes and the walk keeps, per child, the mask of the packet's
 * rays that hit it (Wald, Benthin, Boulos 2008; Embree's hybrid walk):
 *
 *   - interval arithmetic (Boulos et al. 2007): the box of the packet's
 *     origins and inverse directions bounds every ray's entry and exit
 *     distance for all children in one SIMD pass; children no ray can hit
 *     are culled for the whole packet, the rest are ordered near to far by
 *     the entry bound.  This is the wide walk's frustum: PLAIN and FRUSTUM
 *     both use it there (frustum_depth is not used);
 *   - then, whichever costs fewer SIMD passes, each active ray tests all
 *     children at once (few rays), or each surviving child is tested
 *     against the active groups of 8 rays (many rays);
 *   - leaves: each ray of the child's mask runs the 4-triangle block test
 *     of the single-ray walk;
 *   - a tile whose rays do not share direction signs (it straddles an
 *     axis) is walked once per sign class instead of ray by ray;
 *   - tiles are read and written in place in the caller's image.
 *
 * Results are those of single-ray sidx_accel_intersect (same watertight
 * test, same robust box test, every ray keeps its own closest hit, same t
 * bit for bit).  Near ties included: two triangles whose t differ by an
 * ulp, the nearer one in a box whose ROUNDED entry lies an ulp beyond the
 * farther hit — packets and single rays alike clip boxes to the best t
 * widened by Ize's factor, so neither drops that box, and both return
 * brute force's nearest t.  Packets run over "bvh"
 * (binned SAH; not bvh-obb), "bvh4" and "bvh8"; any other structure is
 * traced one ray at a time through sidx_accel_intersect, so the calls work
 * everywhere.  No hooks: a query with a hook is traced ray by ray too
 * (events then come from the single-ray walk). */
#ifndef SIDX_PACKET_H
#define SIDX_PACKET_H

#include <stddef.h>
#include <stdint.h>
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SIDX_PACKET_MAX 64u

typedef enum sidx_packet_mode {
    SIDX_PACKET_PLAIN = 0,   /* packet traversal, per-ray box tests with first-hit early descent */
    SIDX_PACKET_FRUSTUM = 1, /* plus corner-ray frustum culling (common-origin packets only) */
    SIDX_PACKET_SINGLE = 2   /* no packets: one ray at a time (the reference) */
} sidx_packet_mode;

typedef struct sidx_packet_options {
    sidx_packet_mode mode;
    uint32_t frustum_depth; /* frustum tests down to this node depth; 0 = every depth */
    uint32_t flags;         /* SIDX_QUERY_UV / SIDX_QUERY_NORMAL / SIDX_QUERY_PRECISE_T */
} sidx_packet_options;

/* Work counters, accumulated (zero them first). */
typedef struct sidx_packet_stats {
    uint64_t packets;           /* packets traced */
    uint64_t single_packets;    /* packets traced ray by ray (binary bvh: mixed signs; unsupported structure) */
    uint64_t node_visits;       /* nodes the packet walk processed */
    uint64_t box_tests;         /* ray-box slab tests (bvh: one per ray per group of 8 tested; wide: per ray and child) */
    uint64_t frustum_tests;     /* frustum-box tests (binary bvh) */
    uint64_t frustum_culls;     /* nodes culled by the frustum alone */
    uint64_t prim_tests;        /* ray-triangle tests */
    uint64_t switched_rays;     /* rays that finished a subtree alone (adaptive switch) */
    /* wide BVHs (bvh4, bvh8); appended last so the fields above keep their offsets */
    uint64_t interval_tests;    /* child boxes tested against the packet's interval bounds */
    uint64_t interval_culls;    /* child boxes those bounds culled for the whole packet */
    uint64_t split_packets;     /* packets of mixed direction signs walked once per sign class */
} sidx_packet_stats;

/* Closest hits for rays[0, n), n <= SIDX_PACKET_MAX.  For FRUSTUM, rays
 * must be a tile of w x h rays in row-major order (w·h = n) so the corner
 * rays are rays[0], rays[w-1], rays[n-w], rays[n-1]; other packets (or w =
 * 0) use PLAIN.  opt and stats may be NULL.  SIDX_ERR_INVALID_ARG for NULL
 * arguments or n too large. */
sidx_status sidx_packet_intersect(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w,
                                  const sidx_packet_options *opt, sidx_hit *hits, sidx_packet_stats *stats);

/* Any-hit for a packet (e.g. shadow rays from surface points to a point
 * light): occluded[i] = 1 if ray i hits anything in [tmin, tmax). */
sidx_status sidx_packet_occluded(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w,
                                 const sidx_packet_options *opt, uint8_t *occluded, sidx_packet_stats *stats);

/* An image of W x H rays (row-major) traced in tiles of tile x tile
 * (4 or 8; edge tiles are smaller). */
sidx_status sidx_trace_tiles(const sidx_accel *a, const sidx_ray *rays, uint32_t W, uint32_t H, uint32_t tile,
                             const sidx_packet_options *opt, sidx_hit *hits, sidx_packet_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
