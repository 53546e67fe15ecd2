#!/bin/sh
# run_simd_rules.sh — SIMD intrinsics, their types and their headers
# appear only in the kernel headers lib/simd_*.h (docs/architecture.md,
# "SIMD kernels"): no _mm_*, _mm256_*, _mm512_*, __m128*, __m256*,
# __m512* and no #include <...intrin.h> in any other lib/*.c or lib/*.h,
# comments included.  Exit 0 when the rule holds, 1 with the offending
# lines when it does not, 2 on a usage error.
#   usage: sh tests/run_simd_rules.sh [LIBDIR]    (default: lib)
case "$1" in -h|--help) sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;; esac
LIB=${1:-lib}
[ -d "$LIB" ] || { echo "simd rules: no directory $LIB" >&2; exit 2; }
files=$(ls "$LIB"/*.c "$LIB"/*.h 2>/dev/null | grep -v '/simd_[^/]*\.h$')
[ -n "$files" ] || { echo "simd rules: no C files in $LIB" >&2; exit 2; }
# shellcheck disable=SC2086
bad=$(grep -nE '\b_mm(256|512)?_[a-z0-9_]+|\b__m(128|256|512)[a-z]?\b|#[[:space:]]*include[[:space:]]*<[a-z0-9]*intrin\.h>' $files)
if [ -n "$bad" ]; then
    echo "simd rules: SIMD intrinsics outside $LIB/simd_*.h (move them into a kernel header):"
    echo "$bad"
    exit 1
fi
echo "simd rules: intrinsics only in $LIB/simd_*.h ($(echo "$files" | wc -l) other files checked)"
