#!/bin/sh
# runner.sh — run the test suites and checks, JOBS at a time, and print each
# one's output whole, in the order given.
#
#   JOBS=2 BUILD=build sh tests/runner.sh build/tests/test_bvh ... tests/run_lessons.sh
#
# Each argument is a program (a cmocka suite, run as it is) or a shell
# script (run with sh); all run from the repository root with BUILD in the
# environment and stdin from /dev/null.  Every one runs even if another
# fails.  A job's output goes to a file of its own and is printed, after a
# line "== NAME (S s)", once the job and every job before it have ended, so
# the output reads as if they ran one after the other.  The last line is
# "LABEL: N passed, N failed"; the exit status is 1 if any failed.
# PREFIX puts a command before every program (PREFIX="valgrind -q ...");
# QUIET=1 prints a job's output only when it fails.

JOBS=${JOBS:-2}
PREFIX=${PREFIX:-}
QUIET=${QUIET:-0}
LABEL=${LABEL:-runner}
export BUILD="${BUILD:-build}"

[ $# -gt 0 ] || { echo "usage: JOBS=2 BUILD=build sh tests/runner.sh PROGRAM|SCRIPT.sh ..."; exit 2; }
case $JOBS in '' | *[!0-9]* | 0) echo "runner: JOBS=$JOBS is not a positive number"; exit 2 ;; esac

dir=$(mktemp -d "${TMPDIR:-/tmp}/sidx_runner.XXXXXX") || exit 1
pids=""
stop() {
    for p in $pids; do kill "$p" 2>/dev/null; done
    rm -rf "$dir"
    exit 130
}
trap stop INT TERM

# start JOB-NUMBER ITEM: runs ITEM in the background; JOB.rc appears, with
# its exit status and seconds, when it has ended.
start() {
    (
        t0=$(date +%s)
        case $2 in
        *.sh) sh "$2" </dev/null >"$dir/$1.out" 2>&1 ;;
        *) $PREFIX "$2" </dev/null >"$dir/$1.out" 2>&1 ;;
        esac
        rc=$?
        echo "$rc $(($(date +%s) - t0))" >"$dir/$1.tmp" && mv "$dir/$1.tmp" "$dir/$1.rc"
    ) &
    pids="$pids $!"
}

n=$#
echo "$LABEL: $n to run, $JOBS at a time; each one's output follows when it and those before it have ended"
started=0 printed=0 passed=0 failed=0 failures="" item=""
while [ $printed -lt $n ]; do
    # keep JOBS running: the ones started and not yet ended
    running=0
    i=$printed
    while [ $i -lt $started ]; do
        i=$((i + 1))
        [ -f "$dir/$i.rc" ] || running=$((running + 1))
    done
    while [ $running -lt "$JOBS" ] && [ $started -lt $n ]; do
        started=$((started + 1))
        eval "item=\${$started}"
        start $started "$item"
        running=$((running + 1))
    done
    # print every job that has ended, in order
    progress=0
    while [ $printed -lt $started ] && [ -f "$dir/$((printed + 1)).rc" ]; do
        printed=$((printed + 1))
        eval "item=\${$printed}"
        read -r rc secs <"$dir/$printed.rc"
        echo "== $item (${secs} s)"
        if [ "$rc" -eq 0 ]; then
            [ "$QUIET" = 1 ] || cat "$dir/$printed.out"
            passed=$((passed + 1))
        else
            cat "$dir/$printed.out"
            echo "!! FAILED: $item (exit $rc)"
            failed=$((failed + 1))
            failures="$failures $item"
        fi
        rm -f "$dir/$printed.out"
        progress=1
    done
    [ $progress = 1 ] || sleep 0.2
done
wait
rm -rf "$dir"
[ $failed -eq 0 ] || echo "$LABEL: failed:$failures"
echo "$LABEL: $passed passed, $failed failed"
[ $failed -eq 0 ]
