#!/bin/sh
# run_borrowed.sh — no borrowed answers: sidx-check refuses a submission
# that calls the library's own version of what the exercise asks for, or
# relays the reference's events from a library walk or query, or reaches
# the checker's reference or looks functions up at run time.
#
#   BUILD=build sh tests/run_borrowed.sh        (make test-run does this)
#
# Each file of tests/exercises/borrowed/ (EXERCISE--WAY.c) states on its
# `expect:` line the verdict's first line; the check wants exit 1, that
# line first and BORROWED last.  Then the proof that the verdict comes from
# the check and not from a wrong answer: with nm blinded to undefined
# symbols (NM=a filter), the relayed walk of 14 and the library's tests in
# 01 pass every case.  About 2.5 s of CPU (14 compiles, 2 short runs).

BUILD=${BUILD:-build}
CHECK=$BUILD/bin/sidx-check
DIR=tests/exercises/borrowed
case $BUILD in
*/san | */tsan) echo "borrowed: skipped under the sanitizers (the check reads symbols, the same in every build)"; exit 0 ;;
esac
if [ ! -d "$DIR" ]; then echo "borrowed: skipped (no $DIR: a hand-out tree)"; exit 0; fi
if [ ! -x "$CHECK" ]; then echo "borrowed: no $CHECK"; exit 1; fi
fail=0
n=0
for f in "$DIR"/*.c; do
    b=$(basename "$f" .c)
    ex=${b%%--*}
    want=$(sed -n 's/^ \* expect: //p' "$f")
    [ -n "$want" ] || { echo "borrowed: FAIL: $f has no expect: line"; fail=1; continue; }
    out=$("$CHECK" "$ex" "$f" 2>&1)
    rc=$?
    first=$(printf '%s\n' "$out" | grep -m1 "^sidx-check $ex: ")
    case "$first" in
    *"your code $want"*) ;;
    *) echo "borrowed: FAIL: $b: first line is not \"... your code $want\":"; printf '%s\n' "$out" | sed 's/^/  | /'; fail=1 ;;
    esac
    [ "$rc" = 1 ] || { echo "borrowed: FAIL: $b: exit $rc, not 1"; fail=1; }
    printf '%s\n' "$out" | tail -1 | grep -q '^BORROWED (exit 1)$' || { echo "borrowed: FAIL: $b: no BORROWED verdict"; fail=1; }
    n=$((n + 1))
done
# 15's file borrows three tests: the report names each
out=$("$CHECK" 15_sphere_obb_dop "$DIR/15_sphere_obb_dop--calls.c" 2>&1)
for s in sidx_intersect_sphere sidx_intersect_obb sidx_intersect_kdop; do
    printf '%s\n' "$out" | grep -q "uses $s, which this exercise asks you to write" ||
        { echo "borrowed: FAIL: 15_sphere_obb_dop--calls: $s not named"; fail=1; }
done

# The check blinded: these borrowed answers are right answers, only the
# check tells them apart.
T=$(mktemp -d /tmp/sidx-borrowed-XXXXXX) || exit 1
trap 'rm -rf "$T"' EXIT
printf '#!/bin/sh\nnm "$@" | grep -v " [Uwv] *$"\n' > "$T/nm"
chmod +x "$T/nm"
for b in 14_bsp_painter--paint 01_ray_triangle--calls; do
    out=$(NM=$T/nm "$CHECK" "${b%%--*}" "$DIR/$b.c" 2>&1)
    printf '%s\n' "$out" | tail -1 | grep -q "all .* cases pass" ||
        { echo "borrowed: FAIL: $b blinded does not pass (so the check proves nothing):"; printf '%s\n' "$out" | tail -3; fail=1; }
done
[ $fail = 0 ] && echo "borrowed: $n borrowed answers refused, 2 of them shown to pass every case unchecked"
exit $fail
