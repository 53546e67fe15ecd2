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
#   conj     one conjunct of a condition dropped: a && b -> a, and -> b
#   swapret  two adjacent early returns (if (...) return ...;) swapped:
#            the checks in the other order
#   early    an output written before a refusal: the assignment (*x = E,
#            best->f = E, ...) moved above the nearest early return before it
#   float    a line that computes in double computed in float (double ->
#            float, and pow, floor, sqrt, cbrt, fabs to their float forms)
#   acc0     an accumulation started at 0: a variable that a later line
#            updates from itself (v = f(v, ...), v += ...) initialised to 0
#            instead of its first element, +-INFINITY or the empty box
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

# Like emit, with two lines changed (a statement moved, two lines swapped).
function emit2(ln1, new1, ln2, new2, desc,    f, k) {
    ++count
    f = out "/" name "." count ".c"
    for (k = 1; k <= nlines; ++k) print (k == ln1 ? new1 : k == ln2 ? new2 : lines[k]) > f
    close(f)
    printf "%d\t%s | %s\n", count, desc, trim(code[ln1])
}

# The operand of a && that ends before offset at (scanning left) or starts
# after it (scanning right): its first and last offsets in s, at the same
# parenthesis depth, bounded by an unmatched parenthesis, a ',', '?', ':',
# ';', an assignment, || or &&.
function operand_left(s, at,    k, depth, c, c2) {
    depth = 0
    for (k = at - 1; k >= 1; --k) {
        c = substr(s, k, 1)
        c2 = substr(s, k - 1, 2)
        if (c == ")") { ++depth; continue }
        if (c == "(") { if (depth == 0) break; --depth; continue }
        if (depth > 0) continue
        if (c2 == "&&" || c2 == "||") break
        if (c == "," || c == "?" || c == ":" || c == ";") break
        if (c == "=" && substr(s, k - 1, 1) !~ /[=!<>]/ && substr(s, k + 1, 1) != "=") break
    }
    return k + 1
}
function operand_right(s, at,    k, depth, c, c2, n) {
    depth = 0
    n = length(s)
    for (k = at; k <= n; ++k) {
        c = substr(s, k, 1)
        c2 = substr(s, k, 2)
        if (c == "(") { ++depth; continue }
        if (c == ")") { if (depth == 0) break; --depth; continue }
        if (depth > 0) continue
        if (c2 == "&&" || c2 == "||") break
        if (c == "," || c == "?" || c == ":" || c == ";") break
    }
    return k - 1
}

# conj: each "A && B" on the line becomes A, and B (a duplicate of an
# earlier mutant of the line is skipped).
function conjuncts(ln,    s, pos, at, l0, r1, left, right, a, b, nw, seen) {
    s = code[ln]
    if (s ~ /for \(/) return # a loop's bound and its allocation checks: the bound operator's
    pos = 1
    split("", seen)
    while ((at = index(substr(s, pos), " && ")) > 0) {
        at += pos - 1
        pos = at + 4
        l0 = operand_left(s, at)
        r1 = operand_right(s, at + 4)
        left = substr(s, l0, at - l0)
        right = substr(s, at + 4, r1 - at - 3)
        a = trim(left)
        b = trim(right)
        if (a == "" || b == "") continue
        nw = substr(s, 1, l0 - 1) left substr(s, r1 + 1)
        if (!(("b" b) in seen)) { seen["b" b] = 1; emit(ln, nw, "conj drop '" b "'") }
        nw = substr(s, 1, l0 - 1) (substr(left, 1, 1) == " " ? " " : "") b substr(s, r1 + 1)
        if (!(("b" a) in seen)) { seen["b" a] = 1; emit(ln, nw, "conj drop '" a "'") }
    }
}

function is_early_return(s) { return s ~ /^[ \t]*if \(.*\) return [^;]*;[ \t]*$/ }

# Every whole-word occurrence of w in s replaced by v.
function subst_word(s, w, v,    out, at, pre, post) {
    out = ""
    while ((at = index(s, w)) > 0) {
        pre = at > 1 ? substr(s, at - 1, 1) : ""
        post = substr(s, at + length(w), 1)
        if (pre ~ /[A-Za-z0-9_]/ || post ~ /[A-Za-z0-9_]/) {
            out = out substr(s, 1, at + length(w) - 1)
        } else {
            out = out substr(s, 1, at - 1) v
        }
        s = substr(s, at + length(w))
    }
    return out s
}

# float: the line's double arithmetic in float.
function to_float(s,    t) {
    t = subst_word(s, "double", "float")
    t = subst_word(t, "pow", "powf")
    t = subst_word(t, "floor", "floorf")
    t = subst_word(t, "sqrt", "sqrtf")
    t = subst_word(t, "cbrt", "cbrtf")
    t = subst_word(t, "fabs", "fabsf")
    return t
}

# 1 if a statement after line ln (within 25 lines; a loop header is
# none, the loop's body on its line is) updates v from itself: v += / -= / *= / |= ..., or v = ...v....
function accumulates(v, ln,    m, t, lead) {
    lead = "(^|[;{)][ \t]*|^[ \t]*)\\*?"
    for (m = ln + 1; m <= nlines && m <= ln + 25; ++m) {
        t = code[m]
        # a loop's header is no update; its body on the same line may be
        if (match(t, /for \([^;]*;[^;]*;[^)]*\)/)) t = substr(t, RSTART + RLENGTH)
        if (t == "") continue
        if (t ~ (lead v " (\\+|-|\\*|\\|)= ")) return 1
        if (t ~ (lead v " = [^;]*[^A-Za-z0-9_.>]" v "[^A-Za-z0-9_]")) return 1
    }
    return 0
}

# acc0: each initialiser NAME = RHS on line ln (a declaration's, or an
# assignment) of an accumulation, RHS replaced by the start at 0.
function acc_zero(ln,    s, rest, off, v, rhs, at, end, depth, k, c, zero, head, decl_re) {
    s = code[ln]
    decl_re = "^[ \t]*(const )?(float|double|int|uint32_t|uint64_t|size_t|unsigned|sidx_[a-z0-9_]+) "
    if (s ~ /for \(/) return
    off = 0
    rest = s
    while (match(rest, /[A-Za-z_][A-Za-z0-9_]* = /)) {
        v = substr(rest, RSTART, RLENGTH - 3)
        at = off + RSTART + RLENGTH       # the RHS's first offset in s
        head = substr(s, 1, off + RSTART - 1)
        # the RHS ends at a ',' or ';' outside parentheses
        depth = 0
        for (k = at; k <= length(s); ++k) {
            c = substr(s, k, 1)
            if (c == "(" || c == "{") ++depth
            else if (c == ")" || c == "}") --depth
            else if ((c == "," || c == ";") && depth == 0) break
        }
        end = k - 1
        rhs = substr(s, at, end - at + 1)
        off = end
        rest = substr(s, end + 1)
        if (head ~ /(->|\.)$/ || substr(s, off + 1 - length(rhs) - 4, 1) ~ /[=!<>]/) continue
        if ((" " rhs " ") ~ ("[^A-Za-z0-9_.>]" v "[^A-Za-z0-9_]")) continue # an update, not a start
        # a start: a statement of its own, or a declaration
        if (head !~ /^[ \t]*\*?$/ && s !~ decl_re) continue
        if (!accumulates(v, ln)) continue
        if (rhs == "sidx_aabb_empty()") zero = "(sidx_aabb){{0, 0, 0}, {0, 0, 0}}"
        else if (rhs ~ /^(0|0\.0f?|0u|NULL)$/ || rhs ~ /[{]/) continue
        else zero = "0"
        emit(ln, substr(s, 1, at - 1) zero substr(s, end + 1), "acc0 " v " from 0 (not " rhs ")")
    }
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
    # the operators of the rules: a conjunct dropped, the float arithmetic,
    # an accumulation's start, two checks swapped, an output written early
    for (ln = 1; ln <= nlines; ++ln) {
        s = code[ln]
        if (s == "" || (s ~ /^[A-Za-z_].*\(/ && s !~ /^[ \t]/)) continue
        conjuncts(ln)
        t = to_float(s)
        if (t != s) emit(ln, t, "float")
        acc_zero(ln)
        if (ln < nlines && is_early_return(s) && is_early_return(code[ln + 1]))
            emit2(ln, code[ln + 1], ln + 1, s, "swapret with '" trim(code[ln + 1]) "'")
    }
    for (ln = 1; ln <= nlines; ++ln) {
        if (code[ln] == "") continue
        n = statements(code[ln])
        for (k = 1; k <= n; ++k) {
            if (!is_output(st_lhs[k])) continue
            # the nearest early return above, in the same function
            for (m = ln - 1; m >= 1 && m >= ln - 12; --m) {
                if (lines[m] ~ /^[A-Za-z_{}]/) { m = 0; break }
                if (code[m] != "" && is_early_return(code[m])) break
            }
            if (m < 1 || m < ln - 12) continue
            stmt = substr(code[ln], st_at[k], st_end[k] - st_at[k] + 1)
            rest = substr(code[ln], 1, st_at[k] - 1) substr(code[ln], st_end[k] + 1)
            if (trim(rest) == "") rest = ""
            match(code[m], /^[ \t]*/)
            emit2(m, substr(code[m], 1, RLENGTH) stmt " " substr(code[m], RLENGTH + 1), ln, rest,
                  "early " trim(stmt) " above '" trim(code[m]) "'")
        }
    }
}
