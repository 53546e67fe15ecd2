/* packet_internal.h — what the two packet walks share: packet.c (the
 * binary "bvh", and the entry points of sidx/packet.h) and packet_wide.c
 * (the 4- and 8-wide "bvh4" / "bvh8").
 *
 * The entry points decide which walk a packet takes: a wide structure and
 * an untraced query go to sidx__packet_wide; everything else stays in
 * packet.c (the binary walk, or one ray at a time). */
#ifndef SIDX_PACKET_INTERNAL_H
#define SIDX_PACKET_INTERNAL_H

#include "sidx_internal.h"
#include "sidx/packet.h"

/* AVX2 kernels allowed?  The CPU has them and SIDX_SIMD (scalar, 0,
 * sse4.1) does not ask for less.  A getenv and a cached cpuid bit: asked
 * per call by the packet calls, once per image by sidx_trace_tiles. */
int sidx__packet_have_avx2(void);

/* What a packet's hit is finished with (sidx__hit_finish, hit.c), when
 * its options' flags ask: t refined, u, v and the geometric normal, all
 * from the mesh (the packet walks keep no u, v).  A packet's hits carry
 * no point: SIDX_QUERY_POINT is a single-ray query's. */
#define SIDX__PACKET_FINISH (SIDX__QUERY_REFINE_T | SIDX_QUERY_UV | SIDX_QUERY_NORMAL)

/* One packet over a bvh4 / bvh8 (sidx__is_wide(a)): rays are a tile of
 * w x (n / w) rays read in place, row y starting at rays + y·stride
 * (a plain packet: w = n, stride = n).  Closest hits into hits (same
 * layout as rays) or, for hits == NULL, any-hit flags into occ (packed,
 * n entries).  A packet whose rays do not share direction signs is
 * walked once per sign class present.  avx: as sidx__packet_have_avx2
 * answered.  n in 1 .. SIDX_PACKET_MAX, n a multiple of w. */
void sidx__packet_wide(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w, size_t stride,
                       const sidx_packet_options *opt, sidx_hit *hits, uint8_t *occ, sidx_packet_stats *stats, int avx);

#endif
