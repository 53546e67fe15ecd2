#!/bin/sh
# run_handout.sh — make exercises-handout ships no answer.
#
# Builds the hand-out tarball, unpacks it and checks mechanically that no
# file in it holds a reference solution: no lessons/exercises/solutions/,
# no tests/exercises/ (the planted mistakes quote the solutions), and no
# shipped file under lessons/exercises/ (the stubs, the check drivers),
# docs/ or tests/ holds MIN (3) or more of the body lines of a solution (the lines of lessons/exercises/solutions/NAME.c that are not
# in the stub lessons/exercises/NAME.c, comments, preprocessor lines and
# lines shorter than 24 characters left out, all whitespace removed before comparing).  The
# library (lib/) holds the references the checker compares with
# (sidx/exercise.h), and the lesson programs (lessons/NN_*.c) show the
# library's algorithms at work: both are the course's material.
# Exit 0 clean, 1 a solution was found, 2 the tarball was not built.
set -u
MIN=${MIN:-3}
tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT INT TERM
make --no-print-directory exercises-handout BUILDDIR="$tmp" >"$tmp/make.log" 2>&1 || {
    cat "$tmp/make.log"; echo "run_handout: make exercises-handout failed"; exit 2; }
mkdir "$tmp/x" && tar -xzf "$tmp/sidx-exercises.tar.gz" -C "$tmp/x" || exit 2
root="$tmp/x/sidx-exercises"
[ -d "$root/lessons/exercises/check" ] || { echo "run_handout: no check drivers in the tarball"; exit 2; }
fail=0
for d in lessons/exercises/solutions tests/exercises; do
    if [ -e "$root/$d" ]; then echo "run_handout: the hand-out ships $d/"; fail=1; fi
done
for sol in lessons/exercises/solutions/*.c; do
    name=$(basename "$sol")
    stub="lessons/exercises/$name"
    [ -f "$stub" ] || continue
    # The solution's own lines: not in the stub, not a comment, not short.
    sed -e 's/[[:space:]]//g' "$stub" | sort -u >"$tmp/stub"
    sed -e 's/[[:space:]]//g' "$sol" | grep -v -e '^/\*' -e '^\*' -e '^//' -e '^#' | awk 'length($0) >= 24' | sort -u |
        comm -23 - "$tmp/stub" | sed "s|^|$name	|" >>"$tmp/body"
done
[ -s "$tmp/body" ] || { echo "run_handout: no solution lines to look for"; exit 2; }
# One pass over every shipped file of the scope: count, per file and
# solution, the distinct body lines it holds.
(cd "$root" && find lessons/exercises docs tests -type f | sort | tr '\n' '\0' |
    xargs -0 awk -v MIN="$MIN" -v BODY="$tmp/body" '
    BEGIN { FS = "\t"; while ((getline l < BODY) > 0) { i = index(l, "\t"); sol[substr(l, i + 1)] = sol[substr(l, i + 1)] " " substr(l, 1, i - 1) } FS = " " }
    { x = $0; gsub(/[ \t\r]/, "", x)
      if ((x in sol) && !((FILENAME, x) in seen)) { seen[FILENAME, x] = 1
        n = split(sol[x], names, " ")
        for (k = 1; k <= n; ++k) { c[FILENAME "\t" names[k]]++; ex[FILENAME "\t" names[k]] = ex[FILENAME "\t" names[k]] "\n    " x } } }
    END { bad = 0
      for (key in c) if (c[key] >= MIN) { split(key, p, "\t"); print "run_handout: " p[1] " holds " c[key] " lines of solutions/" p[2] ":" ex[key]; bad = 1 }
      exit bad }') || fail=1
if [ $fail -ne 0 ]; then echo "run_handout: FAIL, the hand-out holds solution code"; exit 1; fi
echo "run_handout: the hand-out holds no solution ($(tar -tzf "$tmp/sidx-exercises.tar.gz" | wc -l) entries)"
exit 0
