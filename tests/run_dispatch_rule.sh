#!/bin/sh
# run_dispatch_rule.sh — every structure's intersect and occluded entries
# dispatch through its walk table (docs/architecture.md, "Hooks cost
# nothing when unused"; lib/sidx_internal.h): the two functions named in
# each `sidx_accel_vtable` of lib/*.c must call sidx__walk_intersect and
# sidx__walk_occluded.  Exit 0 when the rule holds, 1 naming each entry
# that does not, 2 on a usage error.
#   usage: sh tests/run_dispatch_rule.sh [LIBDIR]    (default: lib)
case "$1" in -h|--help) sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;; esac
LIB=${1:-lib}
[ -d "$LIB" ] || { echo "dispatch rule: no directory $LIB" >&2; exit 2; }
# "FILE ENTRY INTERSECT OCCLUDED" for each vtable: its first three fields
tables=$(for f in "$LIB"/*.c; do
    awk -v f="$f" '/sidx_accel_vtable sidx__[a-z0-9_]+_vtable *= *\{/ {s = ""; on = 1}
        on {s = s $0} on && /\}/ {on = 0; sub(/.*\{/, "", s); gsub(/[ \t]/, "", s); split(s, p, ","); print f, p[2], p[3]}' "$f"
done)
[ -n "$tables" ] || { echo "dispatch rule: no vtable in $LIB" >&2; exit 2; }
# body FUNCTION: the text of its definition in lib/*.c, up to the closing brace in column 0
body() {
    awk -v fn="$1" '$0 ~ "^(static )?(void|int) " fn "\\(" {on = 1} on {print} on && /^}/ {exit}' "$LIB"/*.c
}
bad=0 n=0
while read -r file isect occl; do
    n=$((n + 1))
    body "$isect" | grep -q 'sidx__walk_intersect(' ||
        { echo "dispatch rule: $file: $isect does not call sidx__walk_intersect"; bad=1; }
    body "$occl" | grep -q 'sidx__walk_occluded(' ||
        { echo "dispatch rule: $file: $occl does not call sidx__walk_occluded"; bad=1; }
done <<LIST
$tables
LIST
[ $bad -eq 0 ] && echo "dispatch rule: the intersect and occluded entries of $n structures dispatch through their walk tables"
exit $bad
