#!/bin/sh
# make_tutorial.sh — rerun the lessons and refresh the output excerpts of
# docs/tutorial.md, so that every number in the tutorial comes from a run
# of the lessons as they are.
#
#   sh docs/make_tutorial.sh [BUILD] [TUTORIAL]   (default build, docs/tutorial.md;
#                                                  `make docs` runs it)
#
# A refreshed block is written between two markers; everything between
# them is replaced by the fenced output, the rest of the file is kept:
#
#   <!-- run: 03_bvh_partitioning [ARGS] [| FILTER] -->
#   ```
#   (the lesson's output, through FILTER)
#   ```
#   <!-- end -->
#
# The lesson runs from $BUILD/lessons/ with ARGS (each distinct command
# line once, however many blocks quote it); FILTER is a shell pipeline
# over its output.  Besides the usual tools (head, grep, sed) FILTER may
# call
#
#   excerpt START END [START END ...]
#
# which prints, for each pair in turn, the lines from the first one
# containing the text START (searched after the previous range) to the
# next one containing END; END may also be "-" (just that line), "+N" (N
# lines more) or "$" (to the end).  Non-adjacent ranges are separated by a
# line "...".  START and END are plain text, not patterns, so a marker
# keeps working when the numbers around them change; a START or END that
# is no longer found fails the run (exit 1) and leaves the tutorial as it
# was.  A run: marker met before the previous block's <!-- end --> fails
# the run too: the missing end would swallow the text up to the next one.
#
# LESSON_OUTPUTS=DIR takes a lesson's output from DIR/LESSON.out instead
# of running it, for a marker with no ARGS (tests/run_lessons.sh saves
# the outputs of its runs there and compares the excerpts this refreshes
# with the tutorial's).  Run from the repository root.
set -u

BUILD=${1:-build}
DOC=${2:-docs/tutorial.md}
LESSONS=$BUILD/lessons

if [ ! -d "$LESSONS" ]; then
    echo "make_tutorial: no lessons in $LESSONS (run make first)" >&2
    exit 1
fi
if [ ! -f "$DOC" ]; then
    echo "make_tutorial: no $DOC" >&2
    exit 1
fi

tmp=$(mktemp -d "${TMPDIR:-/tmp}/sidx_tutorial.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT INT TERM

# The fields are separated by a control character (0x1f) that no excerpt
# text contains.
excerpt() {
    _ex_sep=$(printf '\037')
    _ex_spec=""
    for _ex_a in "$@"; do _ex_spec="$_ex_spec$_ex_a$_ex_sep"; done
    # through the environment: awk -v would expand backslashes in the text
    EX_SPEC=$_ex_spec EX_SEP=$_ex_sep awk '
        { line[NR] = $0 }
        function fail(msg) { print "excerpt: " msg > "/dev/stderr"; exit 1 }
        END {
            n = split(ENVIRON["EX_SPEC"], p, ENVIRON["EX_SEP"]) - 1
            if (n < 2 || n % 2) fail("wants START END pairs")
            i = 1; last = 0
            for (k = 1; k < n; k += 2) {
                s = p[k]; e = p[k + 1]
                while (i <= NR && index(line[i], s) == 0) i++
                if (i > NR) fail("no line containing \"" s "\"")
                if (e == "-") j = i
                else if (e == "$") j = NR
                else if (e ~ /^\+[0-9]+$/) { j = i + substr(e, 2); if (j > NR) j = NR }
                else {
                    j = i + 1
                    while (j <= NR && index(line[j], e) == 0) j++
                    if (j > NR) fail("no line containing \"" e "\" after \"" s "\"")
                }
                if (last && i > last + 1) print "..."
                for (x = i; x <= j; x++) print line[x]
                last = j; i = j + 1
            }
        }'
}

out=$tmp/tutorial.md
: >"$out"
runs=0 blocks=0 status=0
in_block=0
lineno=0
while IFS= read -r line || [ -n "$line" ]; do
    lineno=$((lineno + 1))
    if [ "$in_block" = 1 ]; then
        case $line in
        "<!-- run: "*)
            echo "make_tutorial: $DOC:$lineno: a run: marker before the previous block's <!-- end -->" >&2
            status=1
            break
            ;;
        "<!-- end -->")
            printf '%s\n' "$line" >>"$out"
            in_block=0
            ;;
        esac
        continue
    fi
    printf '%s\n' "$line" >>"$out"
    case $line in
    "<!-- run: "*" -->") ;;
    *) continue ;;
    esac
    spec=${line#"<!-- run: "}
    spec=${spec%" -->"}
    case $spec in
    *"|"*)
        cmd=${spec%%|*}
        filter=${spec#*|}
        ;;
    *)
        cmd=$spec
        filter=cat
        ;;
    esac
    cmd=$(printf '%s' "$cmd" | sed 's/[[:space:]]*$//')
    prog=${cmd%% *}
    args=""
    [ "$prog" != "$cmd" ] && args=${cmd#* }
    if [ ! -x "$LESSONS/$prog" ]; then
        echo "make_tutorial: $DOC:$lineno: no lesson $LESSONS/$prog" >&2
        status=1
        break
    fi
    # one run per distinct command line
    key=$(printf '%s' "$cmd" | cksum | tr ' ' '_')
    if [ ! -f "$tmp/$key.out" ] && [ -z "$args" ] && [ -f "${LESSON_OUTPUTS:-/nonexistent}/$prog.out" ]; then
        cp "$LESSON_OUTPUTS/$prog.out" "$tmp/$key.out"
    fi
    if [ ! -f "$tmp/$key.out" ]; then
        echo "make_tutorial: running $prog $args" >&2
        # shellcheck disable=SC2086 # ARGS are words, as on a command line
        if ! "$LESSONS/$prog" $args >"$tmp/$key.out" 2>"$tmp/$key.err"; then
            echo "make_tutorial: $DOC:$lineno: $prog $args failed:" >&2
            cat "$tmp/$key.err" >&2
            status=1
            break
        fi
        runs=$((runs + 1))
    fi
    if ! eval "$filter" <"$tmp/$key.out" >"$tmp/block" 2>"$tmp/block.err" || [ -s "$tmp/block.err" ]; then
        echo "make_tutorial: $DOC:$lineno: filter '$filter' failed on the output of $cmd:" >&2
        cat "$tmp/block.err" >&2
        status=1
        break
    fi
    if [ ! -s "$tmp/block" ]; then
        echo "make_tutorial: $DOC:$lineno: '$filter' kept nothing of the output of $cmd" >&2
        status=1
        break
    fi
    printf '```\n' >>"$out"
    cat "$tmp/block" >>"$out"
    printf '```\n' >>"$out"
    blocks=$((blocks + 1))
    in_block=1
done <"$DOC"

if [ "$status" = 0 ] && [ "$in_block" = 1 ]; then
    echo "make_tutorial: $DOC: a run: marker without its <!-- end -->" >&2
    status=1
fi
if [ "$status" != 0 ]; then
    echo "make_tutorial: $DOC left unchanged" >&2
    exit 1
fi
if cmp -s "$out" "$DOC"; then
    echo "make_tutorial: $blocks excerpts from $runs lesson runs; $DOC unchanged"
else
    cat "$out" >"$DOC"
    echo "make_tutorial: $blocks excerpts from $runs lesson runs; $DOC updated"
fi
