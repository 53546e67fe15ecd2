#!/bin/sh
# run_class.sh — sidx-check --class on a synthetic class of 32 students.
#
#   BUILD=build sh tests/run_class.sh        (make test-run does this)
#
# The class is made here from the reference solutions, the stubs, solutions
# with one line changed (mistakes that must fail) and hostile files: a fork
# bomb, an endless loop, sleep(100), an endless printf, writes outside the
# student's directory (../../x and absolute paths into the class), a
# crash, a memory hog, a file that does not build or link.  The checks:
#  - the exit status (1: some submission fails) and the result of every
#    student x exercise in summary.csv, against the expected table below;
#  - a crash names the student's file and line; a capped output is counted
#    and the verdict comes last; each student has a full report;
#  - nothing is written into the class directory outside the report, no
#    student file changes, nothing escapes to the paths the hostile code
#    aims at.
# The time limit (2 s) keeps the hostile cases short; the spam's long
# lines reach the output limit (1 MiB) well within it on a busy machine.  Run from the
# repository root; CC may name the compiler ("ccache gcc").  In a hand-out
# tree without the solutions the test is skipped.  Exit status 1 on failure.

BUILD=${BUILD:-build}
CHECK=$BUILD/bin/sidx-check
# Under the sanitizers the students' code is built with them too: ASan
# catches their crashes itself (exit 1, no signal) and takes no memory
# limit, so the verdicts this class expects do not apply there.
case $BUILD in
*/san | */tsan) echo "class: skipped under the sanitizers (ASan reports the students' crashes itself and takes no memory limit)"; exit 0 ;;
esac
SOL=lessons/exercises/solutions
STUB=lessons/exercises
if [ ! -d "$SOL" ]; then echo "class: skipped (no $SOL: a hand-out tree)"; exit 0; fi
if [ ! -x "$CHECK" ]; then echo "class: no $CHECK"; exit 1; fi

T=$(mktemp -d /tmp/sidx-class-test-XXXXXX) || exit 1
trap 'rm -rf "$T"' EXIT
C=$T/class
mkdir -p "$C"
fail=0
bad() { echo "class: FAIL: $*"; fail=1; }

# student NAME EXERCISE SOURCE: copies SOURCE as NAME's EXERCISE.c
student() { mkdir -p "$C/$1" && cp "$2" "$C/$1/$3.c"; }
# mutate NAME EXERCISE OLD NEW: the solution with the text OLD replaced by
# NEW (fails the test if OLD is not in the solution any more)
mutate() {
    mkdir -p "$C/$1"
    python3 - "$SOL/$2.c" "$C/$1/$2.c" "$3" "$4" <<'EOF' || bad "mutant $1/$2: the line to change is not in $SOL/$2.c"
import sys
src = open(sys.argv[1]).read()
if sys.argv[3] not in src: sys.exit(1)
open(sys.argv[2], "w").write(src.replace(sys.argv[3], sys.argv[4], 1))
EOF
}
# hostile NAME CODE: the 03_ray_box solution with CODE as the first
# statement of ray_box, on a line of its own
hostile() {
    mkdir -p "$C/$1"
    { printf '#include <stdio.h>\n#include <stdlib.h>\n#include <unistd.h>\n'
      sed "0,/^{/s##{\\n    $2#" "$SOL/03_ray_box.c"; } > "$C/$1/03_ray_box.c"
}

for i in 01 02 03; do
    for e in 01_ray_triangle 02_moller_trumbore 03_ray_box; do student s$i-good $SOL/$e.c $e; done
done
for i in 04 05 06 07 08; do student s$i-good $SOL/03_ray_box.c 03_ray_box; done
student s05-good $SOL/02_moller_trumbore.c 02_moller_trumbore
for i in 09 10 11 12; do student s$i-stub $STUB/03_ray_box.c 03_ray_box; done
student s09-stub $STUB/01_ray_triangle.c 01_ray_triangle
mutate s13-miss-inverted 03_ray_box 'if (t0 > t1) return 0;' 'if (t0 > t1) return 1;'
mutate s14-edge-strict 02_moller_trumbore 'uu + vv <= 1.0f' 'uu + vv < 1.0f'
mutate s15-backface 02_moller_trumbore 'if (D == 0.0f) return 0;' 'if (D <= 0.0f) return 0;'
mutate s16-plane-t 01_ray_triangle 'if (!(tt >= r->tmin && tt < r->tmax)) return 0;' 'if (!(tt > r->tmin && tt < r->tmax)) return 0;'
mutate s17-tmax 01_ray_triangle 'if (!(tt >= r->tmin && tt < tmax)) return 0;' 'if (!(tt >= r->tmin && tt < r->tmax)) return 0;'
student s17-tmax $SOL/03_ray_box.c 03_ray_box
mutate s18-loop-parallel 02_moller_trumbore 'if (D == 0.0f) return 0;' 'while (D == 0.0f) { }'
mkdir -p "$C/s19-syntax" && printf 'int ray_box(void) { return 0 }\n' > "$C/s19-syntax/03_ray_box.c"
mkdir -p "$C/s20-misnamed" && sed 's/ray_box(/raybox(/' "$SOL/03_ray_box.c" > "$C/s20-misnamed/03_ray_box.c"
hostile s21-forkbomb 'while (1) fork();'
hostile s22-spin 'for (volatile int i = 0;; ++i) { }'
hostile s23-sleep 'sleep(100);'
hostile s24-spam 'for (;;) printf("spam%200s\\n", "");'
hostile s25-escape "{ FILE *f = fopen(\"../../x\", \"w\"); if (f) fclose(f); f = fopen(\"$C/escaped\", \"w\"); if (f) fclose(f); f = fopen(\"$T/escaped\", \"w\"); if (f) fclose(f); f = fopen(\"$C/s01-good/03_ray_box.c\", \"w\"); if (f) fclose(f); }"
hostile s26-crash 'if (r->dir.x == 0.0f) *(volatile int *)0 = 1;'
hostile s27-hog '{ for (;;) { volatile char *p = malloc(1 << 20); p[0] = 1; } }'
hostile s28-chatty 'printf("ray_box called, t in [%g, %g]\\n", (double)tmin, (double)tmax);'
mkdir -p "$C/s29-empty"
student s30-mixed $SOL/01_ray_triangle.c 01_ray_triangle
hostile s30-mixed 'if (r->dir.x == 0.0f) *(volatile int *)0 = 1;'
student s31-good $SOL/02_moller_trumbore.c 02_moller_trumbore
student s32-stubs $STUB/01_ray_triangle.c 01_ray_triangle
student s32-stubs $STUB/02_moller_trumbore.c 02_moller_trumbore
echo "just notes" > "$C/README.txt"

# what the class looks like before: every file and its checksum
(cd "$C" && find . -type f | sort | xargs md5sum) > "$T/before"

start=$(date +%s)
"$CHECK" --class "$C" --jobs 2 --timeout 2 --memory 128 > "$T/stdout" 2> "$T/stderr"
rc=$?
end=$(date +%s)
[ $rc -eq 1 ] || bad "exit status $rc, want 1 (some submissions fail)"
R=$C/sidx-class-report
for f in summary.md summary.csv; do [ -s "$R/$f" ] || bad "no $R/$f"; done

# the expected result of every student x exercise
cat > "$T/want" <<'EOF'
s01-good,01_ray_triangle,pass
s01-good,02_moller_trumbore,pass
s01-good,03_ray_box,pass
s02-good,01_ray_triangle,pass
s02-good,02_moller_trumbore,pass
s02-good,03_ray_box,pass
s03-good,01_ray_triangle,pass
s03-good,02_moller_trumbore,pass
s03-good,03_ray_box,pass
s04-good,03_ray_box,pass
s05-good,02_moller_trumbore,pass
s05-good,03_ray_box,pass
s06-good,03_ray_box,pass
s07-good,03_ray_box,pass
s08-good,03_ray_box,pass
s09-stub,01_ray_triangle,fail
s09-stub,03_ray_box,fail
s10-stub,03_ray_box,fail
s11-stub,03_ray_box,fail
s12-stub,03_ray_box,fail
s13-miss-inverted,03_ray_box,fail
s14-edge-strict,02_moller_trumbore,fail
s15-backface,02_moller_trumbore,fail
s16-plane-t,01_ray_triangle,fail
s17-tmax,01_ray_triangle,fail
s17-tmax,03_ray_box,pass
s18-loop-parallel,02_moller_trumbore,timeout
s19-syntax,03_ray_box,build
s20-misnamed,03_ray_box,build
s21-forkbomb,03_ray_box,timeout
s22-spin,03_ray_box,timeout
s23-sleep,03_ray_box,timeout
s24-spam,03_ray_box,output
s25-escape,03_ray_box,pass
s26-crash,03_ray_box,crash
s27-hog,03_ray_box,memory
s28-chatty,03_ray_box,pass
s30-mixed,01_ray_triangle,pass
s30-mixed,03_ray_box,crash
s31-good,02_moller_trumbore,pass
s32-stubs,01_ray_triangle,fail
s32-stubs,02_moller_trumbore,fail
EOF
tail -n +2 "$R/summary.csv" | cut -d, -f1-3 | tr -d '"' | sort > "$T/got"
if ! diff "$T/want" "$T/got" > "$T/diff"; then
    bad "summary.csv differs from the expected results (< want, > got):"
    cat "$T/diff"
fi

# the student reports: one per student with a file, the empty one said so
n=$(ls "$R"/s*.txt 2>/dev/null | wc -l)
[ "$n" -eq 32 ] || bad "$n student reports, want 32"
grep -q 'no exercise file' "$R/s29-empty.txt" || bad "the empty folder's report does not say it is empty"
# a crash names the student's file and line (the line of the NULL write)
line=$(grep -n 'volatile int \*)0' "$C/s26-crash/03_ray_box.c" | cut -d: -f1)
grep -q "at $C/s26-crash/03_ray_box.c:$line, in ray_box()" "$R/s26-crash.txt" ||
    bad "the crash does not name s26-crash/03_ray_box.c:$line"
grep -q "crash at 03_ray_box.c:$line" "$R/summary.md" || bad "summary.md does not name the crash's line"
# a failing case as a page, linked from the summary; none for a pass
[ -s "$R/s13-miss-inverted--03_ray_box.html" ] || bad "no page for s13-miss-inverted's failing case"
grep -q "(\[report\](s13-miss-inverted.txt), \[page\](s13-miss-inverted--03_ray_box.html))" "$R/summary.md" ||
    bad "summary.md does not link s13-miss-inverted's page"
[ ! -e "$R/s01-good--03_ray_box.html" ] || bad "a page for a submission that passes"
# a capped output: the first lines, the rest counted, the verdict last
grep -q 'more lines of your output not shown' "$R/s24-spam.txt" || bad "the endless printf's output is not counted"
[ "$(grep -c '^  | spam' "$R/s24-spam.txt")" -eq 20 ] || bad "the endless printf shows other than 20 lines"
[ "$(tail -n 2 "$R/s24-spam.txt" | head -n 1)" = "CRASH (exit 2)" ] || bad "the verdict is not the last line of s24-spam's report"
grep -q 'more than 1 MiB of output' "$R/s24-spam.txt" || bad "too much output is not said"
grep -q 'ray_box called' "$R/s28-chatty.txt" || bad "a passing student's output is not shown"
grep -Eq 'all [0-9]+ cases pass' "$R/s28-chatty.txt" || bad "the chatty student does not pass"
grep -q 'it kept computing' "$R/s22-spin.txt" || bad "the endless loop is not named"
grep -q 'it was waiting' "$R/s23-sleep.txt" || bad "the sleep is not named"
grep -q 'ran out of memory' "$R/s27-hog.txt" || bad "the memory hog is not named"
grep -q 'BUILD FAILED' "$R/s19-syntax.txt" || bad "the build failure's report has no BUILD FAILED"
grep -q 'leaves the reference at step 1' "$R/s10-stub.txt" || bad "a stub does not fail at step 1"

# nothing written outside the students' temporary directories
(cd "$C" && find . -path ./sidx-class-report -prune -o -type f -print | sort | xargs md5sum) > "$T/after"
if ! diff "$T/before" "$T/after" > "$T/diff"; then
    bad "the class directory changed (< before, > after):"
    cat "$T/diff"
fi
[ ! -e "$T/escaped" ] || bad "a student wrote $T/escaped"
[ ! -e "$C/escaped" ] || bad "a student wrote $C/escaped"

if [ $fail -ne 0 ]; then
    echo "class: stdout:"; cat "$T/stdout"; echo "class: stderr:"; cat "$T/stderr"
    exit 1
fi
echo "class: 32 students, $(wc -l < "$T/want") files: summary as expected, nothing escaped ($((end - start)) s)"
