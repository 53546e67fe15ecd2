#!/bin/sh
# mutants.sh — the mutation test of the exercises' batteries.
#
#   sh tests/exercises/mutants.sh [--sample N] [--jobs J] [--keep DIR]
#                                 [--no-mistakes | --mistakes-only] [--ops LIST] [NAME...]
#
# For each exercise NAME (default: every one with a reference solution),
# tests/exercises/mutate.awk writes the systematic mutants of
# lessons/exercises/solutions/NAME.c (one change each: a comparison
# flipped, min and max swapped, a sign swapped, an output replaced by a
# constant or a sibling, a loop bound moved by one, an early return
# removed, an update of the best hit or the interval dropped).  Each runs
# through sidx-check NAME FILE:
#   exit 1                 killed (the battery finds a divergence)
#   exit 2, a crash/loop   killed (the checker caught it)
#   exit 2, BUILD FAILED   invalid (the mutation does not compile): not counted
#   exit 0                 survived
# A survivor listed in tests/exercises/equivalent.txt (with the argument
# why it cannot change behaviour) counts as equivalent; one whose argument
# starts with [memory] is a memory error no trace shows (a write past an
# array), caught only by a sanitizer build (BUILD=build/san after make
# SAN=1), and is counted apart.  The score is killed / (valid - equivalent
# - memory).  Then every planted mistake of tests/exercises/mistakes.txt
# runs and must give its
# exit status and its expect texts (the hint it must get).
# --sample N runs every N-th mutant of each exercise (a deterministic
# sample, for make test).  Exit 1 if a non-equivalent mutant survives, an
# equivalent one is killed (the list is stale), or a mistake is not caught
# as its record says.  --mistakes-only runs the planted mistakes alone,
# --ops LIST (comma-separated operator names, e.g. conj,float) only the
# mutants of those operators; both with NAMEs, the run covers just those
# exercises.  BUILD (default build) names the build directory.
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${BUILD:-build}
case $build in /*) ;; *) build=$root/$build ;; esac
checker=$build/bin/sidx-check
sample=1
jobs=2
keep=
names=
mistakes=1
mutants=1
ops=
while [ $# -gt 0 ]; do
    case $1 in
    --sample) sample=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --keep) keep=$2; shift 2 ;;
    --no-mistakes) mistakes=0; shift ;;
    --mistakes-only) mutants=0; shift ;;
    --ops) ops=$2; shift 2 ;;
    --one)
        # internal: --one NAME FILE RESULT — one mutant, its class in RESULT
        out=$("$checker" "$2" "$3" --timeout 1 2>&1)
        rc=$?
        case $rc in
        0) cls=survived ;;
        1) cls=killed ;;
        *) if printf '%s\n' "$out" | grep -q 'BUILD FAILED'; then cls=invalid; else cls=killed; fi ;;
        esac
        printf '%s %s\n' "$cls" "$rc" >"$4"
        printf '%s\n' "$out" >"$4.out"
        exit 0 ;;
    -h|--help)
        sed -n '2,/^set -u/p' "$0" | sed -e '$d' -e 's/^# \{0,1\}//'
        exit 0 ;;
    -*) echo "mutants.sh: unknown option $1" >&2; exit 2 ;;
    *) names="$names $1"; shift ;;
    esac
done
[ -x "$checker" ] || { echo "mutants.sh: no $checker (make build first)" >&2; exit 2; }
cd "$root" || exit 2
if [ -z "$names" ]; then
    for f in lessons/exercises/solutions/[0-9]*.c; do names="$names $(basename "$f" .c)"; done
fi
if [ -n "$keep" ]; then
    tmp=$keep
    mkdir -p "$tmp"
else
    tmp=$(mktemp -d /tmp/sidx-mutants-XXXXXX) || exit 2
    trap 'rm -rf "$tmp"' EXIT INT TERM
fi
equiv=tests/exercises/equivalent.txt
start=$(date +%s)
fail=0
[ "$mutants" = 0 ] || printf '%-22s %9s %7s %7s %10s %7s %8s %7s\n' exercise generated invalid killed equivalent memory survived score
for name in $names; do
    [ "$mutants" = 1 ] || break
    sol=lessons/exercises/solutions/$name.c
    [ -f "$sol" ] || { echo "mutants.sh: no $sol" >&2; exit 2; }
    d=$tmp/$name
    mkdir -p "$d"
    awk -v out="$d" -v name="$name" -f "$here/mutate.awk" "$sol" >"$d/index" || exit 2
    # --ops: the operator is the description's first word
    awk -F '\t' -v s="$sample" -v ops=",$ops," '
        { split($2, w, " ") }
        (ops == ",," || index(ops, "," w[1] ",")) && ($1 - 1) % s == 0 { print $1 }' "$d/index" >"$d/run"
    # (an empty list runs nothing: xargs would run the script once, with no argument)
    [ -s "$d/run" ] && sed "s|.*|--one $name $d/$name.&.c $d/&.result|" "$d/run" |
        xargs -P "$jobs" -n 4 sh "$0" 2>/dev/null
    # the verdicts, joined with the list of equivalent mutants
    awk -F '\t' -v name="$name" -v d="$d" -v equiv="$equiv" -v sampled="$sample" '
        BEGIN {
            while ((getline line < equiv) > 0) {
                if (line ~ /^#/ || line == "") continue
                n = split(line, f, " :: ")
                if (n >= 3 && f[1] == name) eq[f[2]] = f[3]
            }
        }
        FILENAME ~ /run$/ { run[$1] = 1; next }
        ($1 in run) {
            ++gen
            r = d "/" $1 ".result"
            cls = "missing"
            if ((getline cls < r) <= 0) cls = "missing"
            sub(/ .*/, "", cls)
            close(r)
            if (cls == "invalid") { ++inv; next }
            if (cls == "killed") {
                ++kill
                if (($2 in eq) && eq[$2] !~ /^\[memory\]/) {
                    printf "  stale equivalent (killed): %s :: %s\n", name, $2 > "/dev/stderr"
                    ++bad
                }
                next
            }
            if ($2 in eq) { if (eq[$2] ~ /^\[memory\]/) ++mem; else ++eqv; next }
            ++surv
            printf "  SURVIVED %s.%d: %s :: %s\n", name, $1, name, $2 > "/dev/stderr"
        }
        END {
            valid = kill + eqv + mem + surv
            score = valid - eqv - mem > 0 ? 100 * kill / (valid - eqv - mem) : 100
            printf "%-22s %9d %7d %7d %10d %7d %8d %6.1f%%\n", name, gen, inv, kill, eqv, mem, surv, score
            exit (surv > 0 || bad > 0)
        }' "$d/run" "$d/index" 2>&1 || fail=1
done
if [ "$mistakes" = 1 ] && [ -f tests/exercises/mistakes.txt ]; then
    # the planted mistakes: files, then the checks
    md=$tmp/mistakes
    mkdir -p "$md"
    awk -v d="$md" -v names=" $names " '
        function flush() {
            if (nm == "" || index(names, " " nm " ") == 0) return
            sol = "lessons/exercises/solutions/" nm ".c"
            src = ""
            while ((getline line < sol) > 0) src = src line "\n"
            close(sol)
            at = index(src, old)
            if (at == 0) { printf "mistake %s--%s: the line to replace is not in %s\n", nm, slug, sol > "/dev/stderr"; return }
            f = d "/" nm "--" slug ".c"
            printf "%s", substr(src, 1, at - 1) new substr(src, at + length(old)) > f
            close(f)
            printf "%s\t%s\t%s\t%d\n", nm, slug, f, ex > (d "/index")
            e = d "/" nm "--" slug ".expect"
            printf "%s", expects > e
            close(e)
        }
        /^#/ { next }
        /^mistake / { flush(); nm = $2; slug = $3; old = new = expects = ""; ex = 1; next }
        /^old / { old = substr($0, 9); next }
        /^new / { new = substr($0, 9); next }
        /^exit / { ex = $2 + 0; next }
        /^expect / { expects = expects substr($0, 9) "\n"; next }
        /^rule / { next }
        END { flush() }' tests/exercises/mistakes.txt
    touch "$md/index"
    [ -s "$md/index" ] && cut -f 3 "$md/index" | sed 's|\(.*/\)\([^/]*\)--\([^/]*\)\.c$|--one \2 & \1\2--\3.result|' |
        xargs -P "$jobs" -n 4 sh "$0" 2>/dev/null
    nm_total=0
    nm_bad=0
    while IFS="$(printf '\t')" read -r nm slug f ex; do
        nm_total=$((nm_total + 1))
        out=${f%.c}.result.out
        rc=$(cut -d ' ' -f 2 "${f%.c}.result")
        ok=1
        [ "$rc" = "$ex" ] || ok=0
        while IFS= read -r e; do
            grep -qF -- "$e" "$out" || { ok=0; echo "  mistake $nm--$slug: the report lacks: $e" >&2; }
        done <"${f%.c}.expect"
        if [ $ok = 0 ]; then
            nm_bad=$((nm_bad + 1))
            echo "  mistake $nm--$slug: exit $rc (want $ex)" >&2
        fi
    done <"$md/index"
    echo "planted mistakes: $nm_total, caught as recorded: $((nm_total - nm_bad))"
    [ $nm_bad = 0 ] || fail=1
fi
echo "mutant run: $(($(date +%s) - start)) s"
exit $fail
