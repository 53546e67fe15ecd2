# doc_commands.awk — print FILE<TAB>LINE<TAB>COMMAND for every command a
# doc shows: the lines of its ```sh blocks, the commands in its table
# cells and code spans in its prose, the build/... lines of a C file's
# header comment (tests/run_doctests.sh reads them).
function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }
function emit(c) { c = trim(c); if (c != "") printf "%s\t%d\t%s\n", FILENAME, FNR, c }
FNR == 1 { fence = 0; sh = 0; incomment = (FILENAME ~ /\.c$/) }
FILENAME ~ /\.c$/ {
    if (!incomment) next
    line = $0
    if (line ~ /\*\//) incomment = 0
    sub(/^ \*[ \t]*/, "", line); sub(/^Run:[ \t]*/, "", line)
    if (line ~ /^([A-Z_]+=[^ ]+ )*build\//) { sub(/[ \t]*\*\/.*$/, "", line); emit(line) }
    next
}
/^[ \t]*```/ {
    if (!fence) { fence = 1; sh = ($0 ~ /```(sh|bash|console)[ \t]*$/) } else { fence = 0; sh = 0 }
    next
}
fence { if (sh && $0 !~ /^[ \t]*#/) { l = $0; sub(/[ \t]+#.*$/, "", l); emit(l) } next }
/^\|/ {
    # table cells: every code span that is a command
    s = $0
    while (match(s, /`[^`]+`/)) {
        c = substr(s, RSTART + 1, RLENGTH - 2); s = substr(s, RSTART + RLENGTH)
        if (c ~ /^([A-Z_]+=[^ ]+ )*(build\/(bin|lessons)\/|make |sh )/) emit(c)
    }
    next
}
{
    # prose: a code span running a program of build/ (the make targets
    # named in prose are the maintainers': make bench, make docs, ...)
    s = $0
    while (match(s, /`[^`]+`/)) {
        c = substr(s, RSTART + 1, RLENGTH - 2); s = substr(s, RSTART + RLENGTH)
        if (c ~ /^([A-Z_]+=[^ ]+ )*build\/(bin|lessons)\/[^ \/]+( |$)/) emit(c)
    }
}
