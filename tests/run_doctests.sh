#!/bin/sh
# run_doctests.sh — run every command the documentation shows and check
# that its output shows what the text says it does.
#
#   BUILD=build sh tests/run_doctests.sh        (make test-run does this)
#
# The commands are taken from the docs themselves (tests/doc_commands.awk):
# every line of a ```sh block in README.md, docs/tutorial.md,
# docs/exercises.md and docs/programs.md, every command in a table cell
# (a code span starting with build/bin/, build/lessons/, make or sh), every
# code span in prose that runs a program of build/, and every build/...
# line of a lesson's header comment.  Each one
# must be listed, exactly as written, on a "doc:" line of
# tests/doctests.txt, whose entry says how it is run and what is checked:
#
#   doc:    the command as the doc writes it (one or more lines)
#   run:    the shell command run for it (default: the doc command with
#           build/ replaced by $BUILD/); shortened where the doc's command
#           is long, writing into $T (a temporary directory)
#   exit:   its exit status (default 0)
#   expect: a text its output (stdout and stderr) must contain
#   check:  a shell command reading the output on stdin that must exit 0
#
# A command in a doc with no entry fails the run, and so does an entry
# whose doc line is in no doc any more: a new or changed doc line cannot
# go untested.  An entry whose run needs a program that is not built
# (sidx-view without SDL2, sidx-dot without Graphviz, sidx-bench without
# Embree) is reported as skipped.  Besides the commands: README.md stays
# at most 170 lines, and every lesson's header names the library function
# it is about ("Read: lib/FILE.c, FUNCTION", several separated by ";"),
# which must be defined in that file, and every path of the repository a
# comment of lib/, viz/ or lessons/ names (tests/X.sh, docs/Y.md, ...)
# exists.  DOCTEST_ONLY=TEXT runs only the entries whose first doc line
# contains TEXT; DOCTEST_TIMES=1 prints the seconds each run takes.  Run
# from the repository root; exit 1 if anything failed.

BUILD=${BUILD:-build}
LIST=tests/doctests.txt
README_MAX=170

T=$(mktemp -d "${TMPDIR:-/tmp}/sidx_doctests.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
export BUILD T

fail=0
bad() { echo "doc tests: FAIL: $*"; fail=$((fail + 1)); }

# the pages a newcomer follows; the others (architecture, benchmark,
# performance, ...) name maintainers' targets such as `make bench`
docs="README.md docs/tutorial.md docs/exercises.md docs/programs.md"
# shellcheck disable=SC2086 # the file lists are words
awk -f tests/doc_commands.awk $docs lessons/[0-9]*.c >"$T/cmds" || exit 1

# ---- the list: one file per entry ------------------------------------------
n=0
started=0
while IFS= read -r line || [ -n "$line" ]; do
    case $line in
    "#"*) continue ;;
    "") started=0; continue ;;
    esac
    if [ "$started" = 0 ]; then
        n=$((n + 1)); started=1
        : >"$T/e$n.doc"; : >"$T/e$n.expect"; : >"$T/e$n.check"
        echo 0 >"$T/e$n.exit"
    fi
    key=${line%%:*}
    val=${line#*:}
    val=${val# }
    case $key in
    doc) printf '%s\n' "$val" >>"$T/e$n.doc" ;;
    run) printf '%s\n' "$val" >"$T/e$n.run" ;;
    exit) printf '%s\n' "$val" >"$T/e$n.exit" ;;
    expect) printf '%s\n' "$val" >>"$T/e$n.expect" ;;
    check) printf '%s\n' "$val" >>"$T/e$n.check" ;;
    *) bad "$LIST: unknown field '$key' in: $line" ;;
    esac
done <"$LIST"

# ---- coverage: every doc command listed, every listed command in a doc -----
cut -f3 "$T/cmds" | sort -u >"$T/doc_cmds"
cat "$T"/e*.doc | sort -u >"$T/listed"
comm -23 "$T/doc_cmds" "$T/listed" >"$T/missing"
while IFS= read -r c; do
    where=$(awk -F'\t' -v c="$c" '$3 == c { print $1 ":" $2; exit }' "$T/cmds")
    bad "$where: no test for this command (add an entry to $LIST): $c"
done <"$T/missing"
comm -13 "$T/doc_cmds" "$T/listed" >"$T/stale"
while IFS= read -r c; do
    bad "$LIST: this doc line is in no doc any more: $c"
done <"$T/stale"

# ---- run each entry ----------------------------------------------------------
ran=0 skipped=0 i=0
while [ $i -lt $n ]; do
    i=$((i + 1))
    first=$(head -n 1 "$T/e$i.doc")
    if [ -f "$T/e$i.run" ]; then
        run=$(cat "$T/e$i.run")
    else
        run=$(printf '%s\n' "$first" | sed 's|^build/|$BUILD/|; s| build/| $BUILD/|g')
    fi
    case $first in *"${DOCTEST_ONLY:-}"*) ;; *) continue ;; esac
    # a program of build/bin/ that this build does not have: skipped
    need=$(printf '%s\n' "$run" | grep -o '\$BUILD/bin/[a-z-]*' | sed 's|\$BUILD/||' | sort -u)
    missing=""
    for p in $need; do [ -x "$BUILD/$p" ] || missing="$missing $p"; done
    if [ -n "$missing" ]; then
        echo "doc tests: skipped (not built:$missing): $first"
        skipped=$((skipped + 1))
        continue
    fi
    want=$(cat "$T/e$i.exit")
    t0=$(date +%s)
    timeout 300 sh -c "$run" </dev/null >"$T/out" 2>&1
    got=$?
    [ -n "${DOCTEST_TIMES:-}" ] && echo "doc tests: $(($(date +%s) - t0)) s: $first"
    ran=$((ran + 1))
    if [ "$got" != "$want" ]; then
        bad "'$first' (run: $run) exits $got, the doc promises $want; its output ends:"
        tail -n 5 "$T/out" | sed 's/^/    /'
        continue
    fi
    while IFS= read -r e; do
        grep -qF -e "$e" "$T/out" || bad "'$first' (run: $run): no \"$e\" in its output"
    done <"$T/e$i.expect"
    while IFS= read -r c; do
        sh -c "$c" <"$T/out" >"$T/check.out" 2>&1 ||
            bad "'$first' (run: $run): check fails: $c $(head -c 300 "$T/check.out")"
    done <"$T/e$i.check"
done

# ---- code fences: every block closed where it should be ------------------------
# A block that is never closed turns the rest of the page into code (the
# next headings included).  As Markdown reads them: a line opening with
# ``` opens a block, a bare ``` closes it; an opening fence with a
# language (```sh), a run:/end marker of docs/make_tutorial.sh or a
# heading met inside a block means the block before was left open.
for d in $docs; do
    awk -v f="$d" '
        /^```/ && !open { open = FNR; next }
        /^```[ \t]*$/ && open { open = 0; next }
        open && (/^```/ || /^<!-- (run: |end -->)/ || /^##+ /) {
            printf "%s:%d: the code block opened at line %d is not closed before: %s\n", f, FNR, open, $0
            open = 0; bad = 1 }
        END { if (open) { printf "%s: the code block opened at line %d is never closed\n", f, open; bad = 1 }
              exit bad }' "$d" >"$T/fences" || while IFS= read -r l; do bad "$l"; done <"$T/fences"
done

# ---- README length, lessons' Read: lines --------------------------------------
lines=$(wc -l <README.md)
[ "$lines" -le $README_MAX ] || bad "README.md has $lines lines, at most $README_MAX (move details to docs/)"

# ---- paths named in the sources' comments exist --------------------------------
# A comment that sends the reader to tests/X.sh or docs/Y.md must name a
# file that is there; placeholders in capitals (lessons/exercises/NAME.c)
# and wildcards are not files.
paths=0
for p in $(grep -ohE '(^|[^A-Za-z0-9_./])(tests|docs|lib|viz|lessons)/[A-Za-z0-9_./*-]+\.(sh|c|h|md|awk|txt|def|html|js)\b' \
               lib/*.[ch] lib/include/sidx/*.h viz/*.[ch] lessons/*.[ch] | sed 's/^[^a-z]//' | sort -u); do
    case $p in *"*"* | *[A-Z][A-Z]*) continue ;; esac
    paths=$((paths + 1))
    [ -e "$p" ] || bad "a comment in lib/, viz/ or lessons/ names $p, which does not exist: $(grep -lF "$p" lib/*.[ch] lib/include/sidx/*.h viz/*.[ch] lessons/*.[ch] | tr '\n' ' ')"
done

reads=0
for f in lessons/[0-9]*.c; do
    r=$(awk 'NR == 1, /\*\// {
                 if (sub(/^ \* Read:[ \t]*/, "")) { printf "%s", $0; more = 1 }
                 else if (more && sub(/^ \*[ \t]+lib\//, "lib/")) printf " %s", $0
                 else more = 0 }' "$f")
    if [ -z "$r" ]; then
        bad "$f: its header names no library function (a line \" * Read: lib/FILE.c, FUNCTION\")"
        continue
    fi
    printf '%s\n' "$r" | tr ';' '\n' >"$T/reads"
    while IFS= read -r item; do
        file=$(printf '%s' "$item" | sed 's/^[ \t]*//; s/,.*//')
        func=$(printf '%s' "$item" | sed 's/^[^,]*,[ \t]*//; s/[ \t.]*$//')
        if [ ! -f "$file" ]; then
            bad "$f: Read: names $file, which does not exist"
        elif ! grep -E "^([A-Za-z_].*[^A-Za-z0-9_])?$func\(" "$file" | grep -vq ';[[:space:]]*$'; then
            # a definition starts at the line's beginning (not a call, which
            # is indented) and is not a declaration (which ends with ';')
            bad "$f: Read: names $func, which $file does not define"
        else
            reads=$((reads + 1))
        fi
    done <"$T/reads"
done

summary=$(cut -f1 "$T/cmds" | sed 's|^lessons/.*|lessons/*.c|' | sort | uniq -c |
          awk '{ printf "%s%d %s%s", sep, $1, (NR == 1 ? "commands from " : "from "), $2; sep = ", " }')
echo "doc tests: $summary checked ($ran runs, $skipped skipped);" \
     "README.md $lines lines (at most $README_MAX); $reads lesson Read: functions defined;" \
     "$paths paths named in comments exist"
if [ $fail -ne 0 ]; then
    echo "doc tests: $fail failed"
    exit 1
fi
echo "doc tests: all passed"
