# mutate.awk — the systematic mutants of one reference solution.
#
#   awk -v out=DIR -v name=NAME -f mutate.awk lessons/exercises/solutions/NAME.c
#
# Writes DIR/NAME.K.c for K = 1, 2, ...: the solution with one line changed
# by one mutation, and prints "K<TAB>DESCRIPTION" for each.  The
# description names the operator, the occurrence and the original line
# (trimmed, without its comment), so it stays the same when lines move.
# The operators (a mutant that does not compile is dropped by the caller):
#   rel      a comparison flipped: < <=, <= <, > >=, >= >
#   minmax   fminf <-> fmaxf, fmin <-> fmax, _min( <-> _max(
#   sign     a binary + <-> -, a unary minus dropped
#   const    an output (*x = E, p->f = E, return E) replaced by a constant
#   sibling  an output replaced by the value of a neighbouring output
#   bound    a loop bound (the for's condition) plus or minus one
#   noreturn an early return (if (...) return ...;) removed
#   noupdate an update of a best / t_max / t_far / t_near / interval dropped
#   field    a write to a struct field (n->bmin[k] = E, node->count = E,
#            a[i].f = E) that is no output above: dropped, or its value
#            replaced by the constant 0
# Comment lines, preprocessor lines and lines holding a string are skipped.

function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }

# The line without a trailing comment (/* ... */ closed on the line, or //).
function code_of(s,    i) {
    i = index(s, "/*")
    if (i > 0 && index(substr(s, i), "*/") > 0) s = substr(s, 1, i - 1)
    i = index(s, "//")
    if (i > 0) s = substr(s, 1, i - 1)
    sub(/[ \t]+$/, "", s)
    return s
}

function emit(ln, newline, desc,    f, k) {
    ++count
    f = out "/" name "." count ".c"
    for (k = 1; k <= nlines; ++k) print (k == ln ? newline : lines[k]) > f
    close(f)
    printf "%d\t%s | %s\n", count, desc, trim(code[ln])
}

# Replaces each occurrence of the literal pat (with the context test ok())
# by rep, one mutant per occurrence.
function each_literal(ln, pat, rep, op,    s, pos, at, occ, pre, post) {
    s = code[ln]
    pos = 1
    occ = 0
    while ((at = index(substr(s, pos), pat)) > 0) {
        at += pos - 1
        pre = substr(s, at - 1, 1)
        post = substr(s, at + length(pat), 1)
        pos = at + length(pat)
        if (!literal_ok(pat, pre, post)) continue
        ++occ
        emit(ln, substr(s, 1, at - 1) rep substr(s, at + length(pat)), op " '" pat "' -> '" rep "' #" occ)
    }
}

# A comparison operator, not part of <<, >>, ->, <<=, >>=, <=, >=, ==.
function literal_ok(pat, pre, post) {
    if (pat == "sign[") return pre !~ /[A-Za-z0-9_!]/ || pre == ">" || pre == "."
    if (pat == "<") return pre != "<" && post != "<" && post != "=" && pre != "-"
    if (pat == ">") return pre != ">" && post != ">" && post != "=" && pre != "-"
    if (pat == "==" || pat == "!=") return post != "="
    if (pat == "<=") return pre != "<"
    if (pat == ">=") return pre != ">"
    if (pat == " + " || pat == " - ") return 1
    if (pat ~ /^f(min|max)f?\($/ || pat ~ /^_(min|max)\($/) return pre !~ /[A-Za-z0-9_]/ || pat ~ /^_/
    return 1
}

# Replaces each occurrence of the identifier w (a whole word) by v: the
# siblings a student mixes up (near and far, u and v, lo and hi, ...).
function each_word(ln, w, v,    s, pos, at, occ, pre, post) {
    s = code[ln]
    pos = 1
    occ = 0
    while ((at = index(substr(s, pos), w)) > 0) {
        at += pos - 1
        pre = substr(s, at - 1, 1)
        post = substr(s, at + length(w), 1)
        pos = at + length(w)
        if ((at > 1 && pre ~ /[A-Za-z0-9_]/) || post ~ /[A-Za-z0-9_]/) continue
        ++occ
        emit(ln, substr(s, 1, at - 1) v substr(s, at + length(w)), "sibling '" w "' -> '" v "' #" occ)
    }
}

# Unary minus: a '-' directly before an operand, after '(', '=', ',', '?',
# ':' or 'return' (spaces between allowed).
function unary_minus(ln,    s, k, c, nx, j, p, occ) {
    s = code[ln]
    occ = 0
    for (k = 1; k <= length(s); ++k) {
        c = substr(s, k, 1)
        nx = substr(s, k + 1, 1)
        if (c != "-" || nx !~ /[A-Za-z_(0-9.]/) continue
        j = k - 1
        while (j > 0 && substr(s, j, 1) == " ") --j
        p = substr(s, j, 1)
        if (!(p ~ /[(=,?:]/ || (j >= 6 && substr(s, j - 5, 6) == "return"))) continue
        if (p == "=" && j > 1 && substr(s, j - 1, 1) ~ /[=!<>]/) continue
        ++occ
        emit(ln, substr(s, 1, k - 1) substr(s, k + 1), "sign unary '-' dropped #" occ)
    }
}

# Statements "LHS = E;" on the line: fills st_lhs[], st_rhs[], st_at[] (the
# offset of the LHS), st_end[] (the offset of the ';'); returns their count.
# LHS is an lvalue (*x, x, x->f, x.f, x[i], and chains), not a declaration.
function statements(s,    n, rest, off, m, lhs, eq, semi, pre) {
    n = 0
    off = 0
    rest = s
    while (match(rest, /\*?[A-Za-z_][A-Za-z0-9_]*((->|\.)[A-Za-z_][A-Za-z0-9_]*|\[[^]]*\])* (=|\+=|-=|\*=) [^;]*;/)) {
        lhs = substr(rest, RSTART, RLENGTH)
        eq = index(lhs, " = ")
        if (eq == 0) eq = index(lhs, "= ") - 2
        pre = trim(substr(s, 1, off + RSTART - 1))
        # a declaration (a type before the name) or a for's init is no update
        if (pre ~ /(float|int|double|uint32_t|size_t|sidx_[a-z0-9_]+|const|unsigned|,)$/ || pre ~ /for \($/) {
            off += RSTART + RLENGTH - 1
            rest = substr(rest, RSTART + RLENGTH)
            continue
        }
        ++n
        st_at[n] = off + RSTART
        st_end[n] = off + RSTART + RLENGTH - 1
        semi = RLENGTH
        st_lhs[n] = substr(lhs, 1, eq - 1)
        st_rhs[n] = substr(lhs, eq + 3, semi - eq - 3)
        sub(/^= /, "", st_rhs[n])
        off += RSTART + RLENGTH - 1
        rest = substr(rest, RSTART + RLENGTH)
    }
    return n
}

# A struct field written through -> or . (a node's box, its links, ...).
function is_field(lhs) { return lhs ~ /(->|\.)[A-Za-z_]/ }
function is_output(lhs) { return lhs ~ /^\*[A-Za-z_]/ || lhs ~ /^(best|b|out|res|ex|mb)->/ }
function is_update(lhs) {
    return lhs ~ /best|t_?max|t_far|t_near|^t[01]$|tmax|cost/ && lhs !~ /^(t_split|tt|t)$/
}

{
    lines[NR] = $0
    nlines = NR
}

END {
    npairs = split("near_child far_child lo hi np fp tn tf t0 t1 uu vv t_near t_far left right nl nr n_left n_right cl cr e1 e2", pw, " ") / 2
    for (q = 1; q <= npairs; ++q) {
        pair_a[q] = pw[2 * q - 1]
        pair_b[q] = pw[2 * q]
    }
    count = 0
    in_comment = 0
    for (ln = 1; ln <= nlines; ++ln) {
        s = lines[ln]
        t = trim(s)
        if (in_comment) {
            if (index(s, "*/")) in_comment = 0
            code[ln] = ""
            continue
        }
        if (t ~ /^\/\*/ && !index(t, "*/")) { in_comment = 1; code[ln] = ""; continue }
        if (t ~ /^(\/\*|\/\/|#)/ || t ~ /^\*( |\/|$)/ || index(s, "\"")) { code[ln] = ""; continue }
        code[ln] = code_of(s)
    }
    for (ln = 1; ln <= nlines; ++ln) {
        s = code[ln]
        if (s == "") continue
        # function headers and prototypes are not mutated
        if (s ~ /^[A-Za-z_].*\(/ && s !~ /^[ \t]/) continue
        each_literal(ln, "<=", "<", "rel")
        each_literal(ln, "<", "<=", "rel")
        each_literal(ln, ">=", ">", "rel")
        each_literal(ln, ">", ">=", "rel")
        each_literal(ln, "fminf(", "fmaxf(", "minmax")
        each_literal(ln, "fmaxf(", "fminf(", "minmax")
        each_literal(ln, "_min(", "_max(", "minmax")
        each_literal(ln, "_max(", "_min(", "minmax")
        if (s !~ /for \(/) {
            each_literal(ln, " + ", " - ", "sign")
            each_literal(ln, " - ", " + ", "sign")
        }
        unary_minus(ln)
        each_literal(ln, "==", "!=", "rel")
        each_literal(ln, "!=", "==", "rel")
        each_literal(ln, "sign[", "!sign[", "sign")
        for (q = 1; q <= npairs; ++q) {
            each_word(ln, pair_a[q], pair_b[q])
            each_word(ln, pair_b[q], pair_a[q])
        }
        # loop bounds
        if (match(s, /for \([^;]*; [^;]*;/)) {
            head = substr(s, RSTART, RLENGTH)
            c1 = index(head, ";")
            cond = substr(head, c1 + 2, length(head) - c1 - 2)
            if (cond != "") {
                at = RSTART + c1 + 1
                if (match(cond, / (<|<=|>|>=|!=) /)) {
                    b = substr(cond, RSTART + RLENGTH)
                    a = substr(cond, 1, RSTART + RLENGTH - 1)
                    emit(ln, substr(s, 1, at - 1) a "(" b ") + 1" substr(s, at + length(cond)), "bound +1")
                    emit(ln, substr(s, 1, at - 1) a "(" b ") - 1" substr(s, at + length(cond)), "bound -1")
                }
            }
        }
        # early returns removed
        if (match(s, /if \(.*\) return [^;]*;/) && s !~ /^[ \t]*return/) {
            r = index(s, ") return ")
            rest = substr(s, r + 2)
            semi = index(rest, ";")
            emit(ln, substr(s, 1, r + 1) "{ }" substr(rest, semi + 1), "noreturn")
        }
        # return values
        if (match(s, /return [^;]+;/)) {
            e = substr(s, RSTART + 7, RLENGTH - 8)
            pre = substr(s, 1, RSTART + 6)
            post = substr(s, RSTART + RLENGTH - 1)
            if (e == "0") emit(ln, pre "1" post, "const return 0 -> 1")
            else if (e == "1") emit(ln, pre "0" post, "const return 1 -> 0")
            else if (e !~ /^(SIDX_OK|NULL)$/ && e !~ /^[a-z_]+\(/) emit(ln, pre "0" post, "const return value -> 0")
        }
        # outputs and updates
        n = statements(s)
        for (k = 1; k <= n; ++k) {
            lhs = st_lhs[k]
            rhs = st_rhs[k]
            before = substr(s, 1, st_at[k] - 1)
            after = substr(s, st_end[k] + 1)
            if (is_output(lhs)) {
                if (rhs != "0") emit(ln, before lhs " = 0;" after, "const output " lhs " = 0")
                if (rhs != "1") emit(ln, before lhs " = 1;" after, "const output " lhs " = 1")
            }
            if (is_update(lhs) || is_output(lhs)) emit(ln, before "(void)0;" after, "noupdate " lhs)
            else if (is_field(lhs)) emit(ln, before "(void)0;" after, "field dropped " lhs)
            if (is_field(lhs) && !is_output(lhs) && rhs != "0") emit(ln, before lhs " = 0;" after, "field " lhs " = 0")
        }
    }
    # siblings: an output assignment given the right-hand side of another
    # output assignment of the same type within three lines
    for (ln = 1; ln <= nlines; ++ln) {
        if (code[ln] == "") continue
        n = statements(code[ln])
        for (k = 1; k <= n; ++k) {
            if (!is_output(st_lhs[k])) continue
            l1[ln, k] = st_lhs[k]
            r1[ln, k] = st_rhs[k]
            a1[ln, k] = st_at[k]
            e1[ln, k] = st_end[k]
        }
        ns[ln] = n
    }
    for (ln = 1; ln <= nlines; ++ln) {
        for (k = 1; k <= ns[ln]; ++k) {
            if (!((ln, k) in l1)) continue
            for (m = ln - 3; m <= ln + 3; ++m) {
                if (m < 1 || m > nlines) continue
                for (j = 1; j <= ns[m]; ++j) {
                    if (!((m, j) in l1) || (m == ln && j == k)) continue
                    if (l1[m, j] == l1[ln, k] || r1[m, j] == r1[ln, k]) continue
                    s = code[ln]
                    emit(ln, substr(s, 1, a1[ln, k] - 1) l1[ln, k] " = " r1[m, j] ";" substr(s, e1[ln, k] + 1),
                         "sibling " l1[ln, k] " = " r1[m, j])
                }
            }
        }
    }
}
