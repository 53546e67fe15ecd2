#!/bin/sh
# run_bench.sh — sidx-bench's timing options on a small built-in scene.
#
#   BUILD=build sh tests/run_bench.sh        (make test-run does this)
#
# Every traced row is timed as a cold pass, then warm passes (--passes N):
# checks that `trace` reports the cold, best and median figures and the
# number of warm passes, for a sidx structure and for Embree, that its
# headline (mrays_per_s) is the best warm pass, that the best is at least
# the median (the same passes, sorted), that the hits written do not
# depend on the number of passes, that a bad --passes exits 2, and that `run` and `scale` take
# --passes and report it (run's CSV: mrays_median, mrays_cold, passes); that
# `scale --scene FILE` subdivides the mesh level by level.
# Times themselves are never checked.  Without sidx-bench (no Embree) it
# says so in one line and passes.  Run from the repository root.

BUILD=${BUILD:-build}
BENCH=$BUILD/bin/sidx-bench

if [ ! -x "$BENCH" ]; then
    echo "bench: skipped: no $BENCH (built only with Embree, libembree-dev)"
    exit 0
fi
TMP=$(mktemp -d "${TMPDIR:-/tmp}/sidx-bench-test.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
failed=0
fail() {
    echo "bench: FAILED: $*"
    failed=1
}

# A JSON number: key KEY of the one-line object in file FILE.
num() {
    sed -n "s/.*\"$1\":\\([-0-9.e+]*\\).*/\\1/p" "$2"
}

"$BENCH" trace --help >"$TMP/help" 2>&1 || fail "trace --help exits $?"
grep -q -- "--passes N" "$TMP/help" || fail "trace --help does not name --passes"
"$BENCH" rays teapot primary 3000 1 "$TMP/rays.bin" >/dev/null || fail "rays exits $?"

for accel in bvh8 embree; do
    out=$TMP/$accel.json
    if ! "$BENCH" trace --accel $accel --passes 3 teapot "$TMP/rays.bin" "$TMP/$accel.hits" >"$out"; then
        fail "trace --accel $accel --passes 3 exits $?"
        continue
    fi
    for key in mrays_per_s mrays_best mrays_median mrays_cold cold_ms trace_ms passes; do
        [ -n "$(num $key "$out")" ] || fail "trace --accel $accel: no \"$key\" in $(cat "$out")"
    done
    [ "$(num passes "$out")" = 3 ] || fail "trace --accel $accel --passes 3: passes $(num passes "$out")"
    [ "$(num mrays_per_s "$out")" = "$(num mrays_best "$out")" ] ||
        fail "trace --accel $accel: mrays_per_s $(num mrays_per_s "$out") is not mrays_best $(num mrays_best "$out")"
    awk -v b="$(num mrays_best "$out")" -v m="$(num mrays_median "$out")" -v c="$(num mrays_cold "$out")" \
        'BEGIN { exit !(b >= m && m > 0 && c > 0) }' ||
        fail "trace --accel $accel: best $(num mrays_best "$out") < median $(num mrays_median "$out"), or a zero figure"
done
"$BENCH" trace --accel bvh8 --passes 1 teapot "$TMP/rays.bin" "$TMP/one.hits" >/dev/null ||
    fail "trace --passes 1 exits $?"
cmp -s "$TMP/bvh8.hits" "$TMP/one.hits" || fail "trace writes other hits with --passes 3 than with --passes 1"

for bad in 0 x 1001; do
    "$BENCH" trace --accel bvh8 --passes $bad teapot "$TMP/rays.bin" "$TMP/x.hits" >/dev/null 2>&1
    rc=$?
    [ $rc = 2 ] || fail "trace --passes $bad exits $rc, not 2"
done

if "$BENCH" run --builtin teapot --accel bvh,embree --kinds primary --rays 1000 --passes 2 --no-methods \
    --no-hooks --no-packets --no-targets --timeout 0 --csv "$TMP/run.csv" >"$TMP/run.txt" 2>&1; then
    head -1 "$TMP/run.csv" | grep -q ",mrays_median,mrays_cold,passes$" || fail "run's CSV header: $(head -1 "$TMP/run.csv")"
    rows=$(awk -F, 'NR > 1 && $NF == 2' "$TMP/run.csv" | wc -l)
    [ "$rows" -ge 2 ] || fail "run --passes 2: $rows CSV rows with passes = 2 (want bvh and embree)"
    grep -q "up to 2 warm passes after a cold one" "$TMP/run.txt" || fail "run does not say how rows are timed"
else
    fail "run --passes 2 exits $?: $(tail -3 "$TMP/run.txt")"
fi
"$BENCH" run --passes 0 --builtin teapot >/dev/null 2>&1
rc=$?
[ $rc = 2 ] || fail "run --passes 0 exits $rc, not 2"

if "$BENCH" scale --accel bvh8,embree --max-tris 2000 --rays 500 --passes 2 >"$TMP/scale.txt" 2>&1; then
    grep -q "up to 2 warm passes after a cold one" "$TMP/scale.txt" || fail "scale does not say how it times"
    grep -q "^embree " "$TMP/scale.txt" || fail "scale has no embree row"
else
    fail "scale --passes 2 exits $?: $(tail -3 "$TMP/scale.txt")"
fi

# scale --scene FILE: the mesh swept by midpoint subdivision, four times
# the triangles per level, a midpoint shared by the two triangles of its
# edge (a closed cube keeps V = T/2 + 2: 8, 26, 98 vertices); a missing or
# malformed file exits 2 naming it
cat >"$TMP/cube.obj" <<'EOF_OBJ'
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
EOF_OBJ
if "$BENCH" scale --scene "$TMP/cube.obj" --accel bvh8 --min-tris 1 --max-tris 200 --rays 400 --passes 1 >"$TMP/scalef.txt" 2>&1; then
    for want in "level 0: 12 triangles, 8 vertices" "level 1: 48 triangles, 26 vertices" "level 2: 192 triangles, 98 vertices"; do
        grep -q "$want" "$TMP/scalef.txt" || fail "scale --scene FILE: no \"$want\" in $(cat "$TMP/scalef.txt")"
    done
    grep -q "level 3" "$TMP/scalef.txt" && fail "scale --scene FILE went past --max-tris: $(cat "$TMP/scalef.txt")"
    [ "$(grep -c '^bvh8 ' "$TMP/scalef.txt")" = 4 ] || fail "scale --scene FILE: not 3 sizes of bvh8 and its growth: $(cat "$TMP/scalef.txt")"
else
    fail "scale --scene FILE exits $?: $(tail -3 "$TMP/scalef.txt")"
fi
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >"$TMP/bad.obj"
for f in "$TMP/none.obj" "$TMP/bad.obj"; do
    "$BENCH" scale --scene "$f" --accel bvh8 >"$TMP/scaleb.txt" 2>&1
    rc=$?
    [ $rc = 2 ] || fail "scale --scene $f exits $rc, not 2"
    grep -q "$f" "$TMP/scaleb.txt" || fail "scale --scene $f: the message does not name it: $(cat "$TMP/scaleb.txt")"
done

# lazy: both kinds of first image (bounce and shadow), their ratios, and
# the lazy hits equal to the eager ones (a small terrain, one round)
if "$BENCH" lazy --accel bvh --size 24 --frames 2 --rounds 1 heightfield:24 >"$TMP/lazy.txt" 2>&1; then
    for key in first_ratio total_ratio shadow_first_ratio shadow_total_ratio shadow_built_first; do
        [ -n "$(num $key "$TMP/lazy.txt")" ] || fail "lazy: no \"$key\" in $(cat "$TMP/lazy.txt")"
    done
    [ "$(num shadow_rays "$TMP/lazy.txt")" -gt 0 ] 2>/dev/null || fail "lazy: no shadow ray in $(cat "$TMP/lazy.txt")"
    grep -q '"hits_identical":true' "$TMP/lazy.txt" || fail "lazy: hits differ: $(cat "$TMP/lazy.txt")"
else
    fail "lazy exits $?: $(tail -3 "$TMP/lazy.txt")"
fi
# the fraction built lies in [0, 1] for every structure, duplicated
# references (kd-tree, spatial splits) included; some part stays unbuilt
for accel in bvh bvh8 kdtree; do
    if "$BENCH" lazy --accel $accel --lazy-size 64 --size 16 --frames 2 --rounds 1 heightfield:24 >"$TMP/lazyf.txt" 2>&1; then
        for key in built_first built_total shadow_built_first shadow_built_total; do
            awk -v f="$(num $key "$TMP/lazyf.txt")" 'BEGIN { exit !(f != "" && f + 0 >= 0 && f + 0 <= 1) }' ||
                fail "lazy $accel: \"$key\" outside [0, 1]: $(cat "$TMP/lazyf.txt")"
        done
        awk -v f="$(num shadow_built_first "$TMP/lazyf.txt")" 'BEGIN { exit !(f + 0 < 1) }' ||
            fail "lazy $accel: the first shadow image built everything: $(cat "$TMP/lazyf.txt")"
    else
        fail "lazy $accel exits $?: $(tail -3 "$TMP/lazyf.txt")"
    fi
done
# --lazy-only: one line per round with the lazy figures, no ratio
if "$BENCH" lazy --lazy-only --accel kdtree --size 16 --frames 2 --rounds 2 heightfield:24 >"$TMP/lazyo.txt" 2>&1; then
    [ "$(grep -c '"shadow_lazy_first_ms":' "$TMP/lazyo.txt")" = 2 ] || fail "lazy --lazy-only: not 2 rounds: $(cat "$TMP/lazyo.txt")"
    grep -q '_ratio' "$TMP/lazyo.txt" && fail "lazy --lazy-only prints a ratio: $(cat "$TMP/lazyo.txt")"
else
    fail "lazy --lazy-only exits $?: $(tail -3 "$TMP/lazyo.txt")"
fi

[ $failed = 0 ] && echo "bench: trace, run and scale time a cold pass and warm passes (--passes); lazy times both first images"
exit $failed
