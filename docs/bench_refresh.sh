#!/bin/sh
# bench_refresh.sh GENERATED.md DOC.md... — refreshes the benchmark figures
# in the documents.
#
# GENERATED.md is what `sidx-bench run --markdown GENERATED.md` wrote: blocks
# between <!-- bench:NAME begin --> and <!-- bench:NAME end --> lines.  In
# each DOC.md, the text between the same two lines is replaced by that
# block; everything else in DOC.md stays as it is.  A block DOC.md has but
# GENERATED.md lacks (a part the run skipped, e.g. --no-targets) keeps its
# old figures, and the script says so.  `make bench` runs
#   sh docs/bench_refresh.sh build/bench/table.md docs/benchmark.md README.md
set -e
if [ $# -lt 2 ]; then
    echo "usage: sh docs/bench_refresh.sh GENERATED.md DOC.md..." >&2
    exit 2
fi
gen=$1
shift
if [ ! -r "$gen" ]; then
    echo "bench_refresh: cannot read $gen" >&2
    exit 1
fi
for doc in "$@"; do
    tmp="$doc.refresh.$$"
    if ! awk -v gen="$gen" -v doc="$doc" '
        # "<!-- bench:NAME begin -->" -> NAME ("<!-- bench:" is 11 characters)
        function block_name(line, tail) { return substr(line, 12, length(line) - 11 - length(tail)) }
        BEGIN {
            inside = 0
            while ((getline line < gen) > 0) {
                if (line ~ /^<!-- bench:[a-z0-9_-]+ begin -->$/) {
                    name = block_name(line, " begin -->"); have[name] = 1; body[name] = ""; inside = 1
                } else if (line ~ /^<!-- bench:[a-z0-9_-]+ end -->$/) {
                    inside = 0
                } else if (inside) {
                    body[name] = body[name] line "\n"
                }
            }
            skip = 0
        }
        /^<!-- bench:[a-z0-9_-]+ begin -->$/ {
            print
            name = block_name($0, " begin -->")
            if (name in have) { printf "%s", body[name]; skip = 1; done = done " " name }
            else kept = kept " " name
            open = name
            next
        }
        /^<!-- bench:[a-z0-9_-]+ end -->$/ { skip = 0; open = ""; print; next }
        !skip { print }
        END {
            if (open != "") { printf "bench_refresh: %s: block %s has no end marker\n", doc, open > "/dev/stderr"; exit 1 }
            printf "bench_refresh: %s: refreshed:%s\n", doc, (done == "" ? " nothing" : done) > "/dev/stderr"
            if (kept != "") printf "bench_refresh: %s: not in %s, figures kept:%s\n", doc, gen, kept > "/dev/stderr"
        }
    ' "$doc" >"$tmp"; then
        rm -f "$tmp"
        exit 1
    fi
    if cmp -s "$tmp" "$doc"; then rm -f "$tmp"; else mv "$tmp" "$doc"; fi
done
