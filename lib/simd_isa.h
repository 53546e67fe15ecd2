/* simd_isa.h — what the compiler targets, read in one place: the rest of
 * the library tests SIDX_SIMD_X86 and SIDX_SIMD_SSE2, never the
 * compiler's own __SSE2__ or __x86_64__, and names SIMD types and
 * intrinsics only inside the simd_*.h kernel headers (docs/architecture.md,
 * "SIMD kernels"; tests/run_simd_rules.sh checks it).
 *
 *   SIDX_SIMD_X86   x86 or x86-64: the CPU may have SSE4.1, AVX2 or
 *                   AVX-512, picked at run time (__builtin_cpu_supports)
 *   SIDX_SIMD_SSE2  SSE2 at compile time (baseline on x86-64), or
 *                   WebAssembly SIMD through emscripten's SSE headers
 *                   (emcc -msimd128 -msse4.1: `make web`), where nothing
 *                   is picked at run time: SIDX_SIMD_X86 stays undefined,
 *                   so no cpuid test and no AVX kernel is compiled
 *
 * Also the two things plain code needs from SSE2: a 4-float row as a
 * struct member (sidx__f32x4, for kernels' data kept in a structure's
 * own types) and the spin-wait hint (SIDX_SPIN_PAUSE). */
#ifndef SIDX_SIMD_ISA_H
#define SIDX_SIMD_ISA_H

#if defined(__x86_64__) || defined(__i386__)
#define SIDX_SIMD_X86 1
#if defined(__SSE2__)
#define SIDX_SIMD_SSE2 1
#endif
#elif defined(__EMSCRIPTEN__) && defined(__wasm_simd128__) && defined(__SSE2__)
#define SIDX_SIMD_SSE2 1
#endif

#ifdef SIDX_SIMD_SSE2
#include <emmintrin.h>
typedef __m128 sidx__f32x4;
#define SIDX_SPIN_PAUSE() _mm_pause()
#else
#define SIDX_SPIN_PAUSE() ((void)0)
#endif

#endif
