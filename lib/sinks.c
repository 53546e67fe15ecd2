/* sinks.c — the ready-made hooks of sinks.h: printer, JSON Lines,
 * recorder, counters and tee.
 *
 * The printer and the JSON writer share one small output abstraction
 * (sink_out) that either appends to a caller's buffer with snprintf
 * semantics or streams to a FILE.  That way sidx_event_format and the
 * printer produce the very same text from the very same code, and the
 * FILE sinks never truncate a long NOTE text and never allocate.
 *
 * docs/events.md is the reference for what each event carries and for the
 * exact printer and JSON layout; keep the two in step. */
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sinks.h"

/* ---- output: a buffer with snprintf semantics, or a FILE ------------- */

typedef struct sink_out {
    FILE *file;   /* non-NULL: stream here; buf/size unused */
    char *buf;    /* else: write here, always NUL-terminated when size > 0 */
    size_t size;
    size_t len;   /* characters produced so far, truncated or not (what snprintf returns) */
    int error;    /* an encoding / stream error occurred */
    /* Set by the JSON reader: json_key and json_id note which keys the
     * writer would write (bits of json_key_names) and which may be null. */
    int record;
    uint32_t keys, nullable;
} sink_out;

static sink_out out_to_buffer(char *buf, size_t size)
{
    sink_out o = {NULL, buf, size, 0, 0, 0, 0, 0};
    if (buf && size > 0) buf[0] = '\0';
    if (!buf) o.size = 0; /* count only, like snprintf(NULL, 0, ...) */
    return o;
}

static sink_out out_to_file(FILE *f)
{
    sink_out o = {f, NULL, 0, 0, 0, 0, 0, 0};
    return o;
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void out_printf(sink_out *o, const char *fmt, ...)
{
    va_list ap;
    int n;
    va_start(ap, fmt);
    if (o->file) {
        n = vfprintf(o->file, fmt, ap);
    } else {
        /* Once the buffer is full keep counting with a NULL destination, so
         * the final length is what an unbounded buffer would have held. */
        char *dst = NULL;
        size_t room = 0;
        if (o->len < o->size) {
            dst = o->buf + o->len;
            room = o->size - o->len;
        }
        n = vsnprintf(dst, room, fmt, ap);
    }
    va_end(ap);
    if (n < 0)
        o->error = 1;
    else
        o->len += (size_t)n;
}

static void out_puts(sink_out *o, const char *s) { out_printf(o, "%s", s); }

/* The snprintf-style return value of a buffer formatter. */
static int out_result(const sink_out *o)
{
    if (o->error || o->len > (size_t)INT_MAX) return -1;
    return (int)o->len;
}

/* ---- printer ------------------------------------------------------------ */

#define PRINT_MAX_LEVEL 40 /* deeper lines stop indenting: stays readable, bounded */

static const char *axis_name(int32_t axis)
{
    switch (axis) {
    case 0: return "x";
    case 1: return "y";
    case 2: return "z";
    default: return "?";
    }
}

/* An id, or "none" for UINT32_MAX (the blank value). */
static void out_id(sink_out *o, uint32_t id)
{
    if (id == UINT32_MAX)
        out_puts(o, "none");
    else
        out_printf(o, "%" PRIu32, id);
}

static void out_interval(sink_out *o, float a, float b)
{
    out_printf(o, "t=[%g, %g]", (double)a, (double)b);
}

static void out_box(sink_out *o, const sidx_aabb *b)
{
    out_printf(o, "box [(%g, %g, %g), (%g, %g, %g)]", (double)b->min.x, (double)b->min.y, (double)b->min.z,
               (double)b->max.x, (double)b->max.y, (double)b->max.z);
}

static int has_cell(const sidx_event *ev) { return ev->cell[0] >= 0; }

#define PRINT_LEAF_IDS 4 /* a leaf line names this many of its primitives, then "... +k more" */

/* ": 3 17 52 60 ... +9 more" after a leaf's count, when the event lists them. */
static void out_leaf_prims(sink_out *o, const sidx_event *ev)
{
    if (!ev->prims || ev->count == 0 || ev->count == UINT32_MAX) return;
    const uint32_t shown = ev->count < PRINT_LEAF_IDS ? ev->count : PRINT_LEAF_IDS;
    out_puts(o, ":");
    for (uint32_t i = 0; i < shown; ++i) out_printf(o, " %" PRIu32, ev->prims[i]);
    if (ev->count > shown) out_printf(o, " ... +%" PRIu32 " more", ev->count - shown);
}

static int has_extent(const sidx_event *ev) { return ev->extent[0] > 0; }

/* "(4,2,0)", then " 2x2x1" when the event gives the box's extent. */
static void out_coords(sink_out *o, const int32_t c[3], const uint32_t e[3])
{
    out_printf(o, "(%" PRId32 ",%" PRId32 ",%" PRId32 ")", c[0], c[1], c[2]);
    if (e[0] > 0) out_printf(o, " %" PRIu32 "x%" PRIu32 "x%" PRIu32, e[0], e[1], e[2]);
}

static void out_cell(sink_out *o, const sidx_event *ev)
{
    out_puts(o, "cell ");
    out_coords(o, ev->cell, ev->extent);
}

/* A merge: the two boxes that met at finest-level coordinate aux along
 * axis, and the box they became. */
static void out_merge(sink_out *o, const sidx_event *ev)
{
    const int ax = ev->axis >= 0 && ev->axis <= 2 ? ev->axis : 0;
    int32_t c2[3] = {ev->cell[0], ev->cell[1], ev->cell[2]};
    uint32_t e1[3] = {ev->extent[0], ev->extent[1], ev->extent[2]}, e2[3] = {e1[0], e1[1], e1[2]};
    const uint32_t face = ev->aux;
    if (has_cell(ev) && face != UINT32_MAX && face > (uint32_t)ev->cell[ax] && face - (uint32_t)ev->cell[ax] < e1[ax]) {
        e1[ax] = face - (uint32_t)ev->cell[ax];
        e2[ax] = ev->extent[ax] - e1[ax];
        c2[ax] = (int32_t)face;
        out_puts(o, "merge ");
        out_coords(o, ev->cell, e1);
        out_puts(o, " + ");
        out_coords(o, c2, e2);
        out_printf(o, " along %s -> ", axis_name(ev->axis));
    } else {
        out_printf(o, "merge along %s -> ", axis_name(ev->axis));
    }
    out_cell(o, ev);
    out_printf(o, "  prims %" PRIu32, ev->count);
    if (ev->node != UINT32_MAX) out_printf(o, "  (cell %" PRIu32 ")", ev->node);
}

static void out_expand(sink_out *o, const sidx_event *ev)
{
    out_puts(o, "expand cell ");
    out_id(o, ev->node);
    out_printf(o, " %c%s ", ev->aux == 1 ? '+' : '-', axis_name(ev->axis));
    if (ev->result == 1)
        out_printf(o, "by %" PRIu32 " -> ", ev->count);
    else if (ev->reason == 1)
        out_puts(o, "stopped: too many cells in the slab to check  ");
    else
        out_puts(o, "stopped: a neighbour holds other triangles  ");
    out_cell(o, ev);
}

/* Free text on one line: control characters (a stray newline) would break
 * the one-line-per-event promise, so they print as spaces. */
static void out_text_line(sink_out *o, const char *s)
{
    char chunk[64];
    size_t n = 0;
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        chunk[n++] = (c < 0x20 || c == 0x7f) ? ' ' : (char)c;
        if (n == sizeof chunk - 1) {
            chunk[n] = '\0';
            out_puts(o, chunk);
            n = 0;
        }
    }
    chunk[n] = '\0';
    if (n) out_puts(o, chunk);
}

/* "x at 0.25" for an axis-aligned plane; BSP planes (axis -1) keep their
 * normal in bounds.min and their offset in pos. */
static void out_plane(sink_out *o, const sidx_event *ev)
{
    if (ev->axis >= 0 && ev->axis <= 2)
        out_printf(o, "axis %s at %g", axis_name(ev->axis), (double)ev->pos);
    else if (!isfinite(ev->bounds.min.x) || !isfinite(ev->pos))
        out_printf(o, "no plane (equal centroids: index range halved)"); /* BVH edge case */
    else
        out_printf(o, "plane n=(%g, %g, %g) d=%g", (double)ev->bounds.min.x, (double)ev->bounds.min.y,
                   (double)ev->bounds.min.z, (double)ev->pos);
}

static void out_left_right(sink_out *o, const sidx_event *ev)
{
    out_printf(o, "  cost %g  (L %" PRIu32 " | R %" PRIu32 ")", (double)ev->cost, ev->count, ev->aux);
}

/* Indentation level of a line, two spaces each.  Ray and build begin/end
 * sit at column 0; node lines sit one level per tree depth below them;
 * the decisions taken at a node (candidates, split, leaf) and the
 * primitive work one level deeper still.  Emitters that know the depth at
 * a box or primitive test may fill `depth` and get the nesting for free;
 * a blank depth (0) just means "top level".  Push and pop carry the stack
 * size in `depth`, not a tree depth, so they do not indent by it (the line
 * says the size instead). */
static unsigned indent_level(const sidx_event *ev)
{
    unsigned base;
    switch (ev->type) {
    case SIDX_EV_BUILD_BEGIN:
    case SIDX_EV_BUILD_END:
    case SIDX_EV_RAY_BEGIN:
    case SIDX_EV_RAY_END:
    case SIDX_EV_TERMINATE:
        return 0;
    case SIDX_EV_STACK_PUSH:
    case SIDX_EV_STACK_POP:
        return 1;
    case SIDX_EV_BUILD_NODE:
    case SIDX_EV_BUILD_MERGE:
    case SIDX_EV_BUILD_EXPAND:
    case SIDX_EV_BUILD_REINSERT:
    case SIDX_EV_BUILD_LAZY_EXPAND:
    case SIDX_EV_NODE_ENTER:
    case SIDX_EV_BOX_TEST:
    case SIDX_EV_NOTE:
        base = 1;
        break;
    default: /* candidate, split, leaf, prim test, hit update, mailbox */
        base = 2;
        break;
    }
    if (ev->depth == UINT32_MAX) return base;
    uint32_t level = base + (ev->depth < PRINT_MAX_LEVEL ? ev->depth : PRINT_MAX_LEVEL);
    return (unsigned)level;
}

static void format_event(sink_out *o, const sidx_event *ev, int show_bounds)
{
    static const char spaces[] = "                                                                "
                                 "                          "; /* >= 2 * (PRINT_MAX_LEVEL + 2) */
    unsigned level = indent_level(ev);
    out_printf(o, "%.*s", (int)(2 * level), spaces);

    const char *structure = (ev->structure && ev->structure[0]) ? ev->structure : NULL;

    switch (ev->type) {
    case SIDX_EV_BUILD_BEGIN:
        out_puts(o, "build begin");
        if (structure) out_printf(o, " (%s)", structure);
        out_printf(o, ": %" PRIu32 " prims  ", ev->count);
        out_box(o, &ev->bounds); /* the scene box: always worth seeing */
        break;
    case SIDX_EV_BUILD_NODE:
        out_puts(o, "build node ");
        out_id(o, ev->node);
        out_printf(o, "  depth %" PRIu32 "  prims %" PRIu32, ev->depth, ev->count);
        if (ev->parent == UINT32_MAX)
            out_puts(o, "  (root)");
        else
            out_printf(o, "  (parent %" PRIu32 ")", ev->parent);
        if (has_cell(ev)) { out_puts(o, "  "); out_cell(o, ev); }
        if (show_bounds) { out_puts(o, "  "); out_box(o, &ev->bounds); }
        break;
    case SIDX_EV_BUILD_CANDIDATE:
        out_puts(o, "candidate ");
        out_plane(o, ev);
        out_left_right(o, ev);
        break;
    case SIDX_EV_BUILD_SPLIT:
        out_puts(o, "split node ");
        out_id(o, ev->node);
        out_puts(o, " ");
        out_plane(o, ev);
        out_left_right(o, ev);
        break;
    case SIDX_EV_BUILD_LEAF:
        out_puts(o, "leaf node ");
        out_id(o, ev->node);
        out_printf(o, "  prims %" PRIu32, ev->count);
        out_leaf_prims(o, ev);
        if (!isnan(ev->cost)) out_printf(o, "  cost %g", (double)ev->cost);
        out_printf(o, "  (%s)", sidx_leaf_reason_name(ev->reason));
        if (has_cell(ev)) { out_puts(o, "  "); out_cell(o, ev); }
        break;
    case SIDX_EV_BUILD_END:
        out_puts(o, "build end");
        if (structure) out_printf(o, " (%s)", structure);
        out_printf(o, ": %" PRIu32 " nodes  %" PRIu32 " prim refs  max depth %" PRIu32, ev->node, ev->count,
                   ev->depth);
        break;
    case SIDX_EV_RAY_BEGIN:
        out_printf(o, "ray %" PRIu32 " begin", ev->ray_id);
        if (structure) out_printf(o, " (%s)", structure);
        out_puts(o, "  ");
        out_interval(o, ev->t_near, ev->t_far);
        break;
    case SIDX_EV_NODE_ENTER:
        if (has_cell(ev)) {
            /* grids: the coordinates say more than the linear cell id; an
             * irregular grid's cells are numbered, and sized (extent) */
            if (has_extent(ev) && ev->node != UINT32_MAX) {
                out_printf(o, "cell %" PRIu32 " ", ev->node);
                out_coords(o, ev->cell, ev->extent);
            } else {
                out_cell(o, ev);
            }
            out_puts(o, " enter  ");
        } else {
            out_puts(o, "node ");
            out_id(o, ev->node);
            out_printf(o, " enter  depth %" PRIu32 "  ", ev->depth);
        }
        out_interval(o, ev->t_near, ev->t_far);
        if (!has_cell(ev) && ev->axis >= 0 && ev->axis <= 2 && ev->result >= 0 && ev->result <= 2) {
            /* a kd-tree's inner node: t_split and the case taken (sidx_split_case) */
            static const char *const split_case[3] = {"plane before the cell: far child only",
                                                      "plane beyond the cell: near child only",
                                                      "both: near then far"};
            out_printf(o, "  %s=%g at t_split=%g: %s", axis_name(ev->axis), (double)ev->pos, (double)ev->t,
                       split_case[ev->result]);
        }
        break;
    case SIDX_EV_BOX_TEST:
        out_puts(o, "box node ");
        out_id(o, ev->node);
        if (ev->result == 1) {
            out_puts(o, " hit  ");
            out_interval(o, ev->t_near, ev->t_far);
        } else {
            out_puts(o, " miss");
        }
        if (show_bounds) { out_puts(o, "  "); out_box(o, &ev->bounds); }
        break;
    case SIDX_EV_STACK_PUSH:
    case SIDX_EV_STACK_POP: {
        const int push = ev->type == SIDX_EV_STACK_PUSH;
        out_puts(o, push ? "push node " : "pop node ");
        out_id(o, ev->node);
        out_puts(o, "  ");
        out_interval(o, ev->t_near, ev->t_far);
        /* depth is the size after a push and before a pop: show both ends */
        if (ev->depth == UINT32_MAX)
            ;
        else if (push && ev->depth > 0)
            out_printf(o, "  (stack %" PRIu32 " -> %" PRIu32 ")", ev->depth - 1, ev->depth);
        else if (!push && ev->depth > 0)
            out_printf(o, "  (stack %" PRIu32 " -> %" PRIu32 ")", ev->depth, ev->depth - 1);
        else
            out_printf(o, "  (stack %" PRIu32 ")", ev->depth);
        if (!push && ev->result == SIDX_STACK_DROPPED) out_puts(o, "  dropped: t_near beyond the best hit");
        /* a kd-tree ray inside a split plane: the two children overlap, so a
         * hit in the one entered first does not end the walk */
        if (ev->result == SIDX_STACK_IN_PLANE)
            out_puts(o, push ? "  the ray lies in the split plane: both children are near"
                             : "  the ray lies in the split plane: both children are near, so a hit in the other "
                               "does not end the walk");
        break;
    }
    case SIDX_EV_PRIM_TEST:
        out_puts(o, "prim ");
        out_id(o, ev->prim);
        if (ev->result == 1)
            out_printf(o, " test: hit t=%g", (double)ev->t);
        else
            out_puts(o, " test: miss");
        break;
    case SIDX_EV_HIT_UPDATE:
        out_puts(o, "closest hit -> prim ");
        out_id(o, ev->prim);
        out_printf(o, " t=%g", (double)ev->t);
        break;
    case SIDX_EV_MAILBOX_HIT:
        out_puts(o, "mailbox: prim ");
        out_id(o, ev->prim);
        out_puts(o, " already tested, skipped");
        break;
    case SIDX_EV_TERMINATE:
        out_printf(o, "terminate: %s  visited %" PRIu32 "  best t=%g", sidx_term_reason_name(ev->reason), ev->count,
                   (double)ev->t);
        break;
    case SIDX_EV_RAY_END:
        out_printf(o, "ray %" PRIu32 " end: ", ev->ray_id);
        if (ev->prim != UINT32_MAX)
            out_printf(o, "hit prim %" PRIu32 " t=%g", ev->prim, (double)ev->t);
        else if (ev->result == 1) /* an occlusion query: a hit, no closest primitive */
            out_puts(o, "occluded");
        else
            out_puts(o, "miss");
        break;
    case SIDX_EV_NOTE:
        out_puts(o, "note: ");
        if (ev->text) out_text_line(o, ev->text);
        break;
    case SIDX_EV_BUILD_MERGE:
        out_merge(o, ev);
        if (show_bounds) { out_puts(o, "  "); out_box(o, &ev->bounds); }
        break;
    case SIDX_EV_BUILD_EXPAND:
        out_expand(o, ev);
        if (show_bounds) { out_puts(o, "  "); out_box(o, &ev->bounds); }
        break;
    case SIDX_EV_BUILD_REINSERT:
        out_puts(o, "reinsert node ");
        out_id(o, ev->node);
        out_puts(o, " (parent ");
        out_id(o, ev->parent);
        out_puts(o, ") beside node ");
        out_id(o, ev->aux);
        out_printf(o, " at depth %" PRIu32 ": SAH -%g (pass %" PRIu32 ")", ev->depth, (double)ev->cost, ev->count);
        if (show_bounds) { out_puts(o, "  "); out_box(o, &ev->bounds); }
        break;
    case SIDX_EV_BUILD_LAZY_EXPAND:
        out_puts(o, "lazy expand node ");
        out_id(o, ev->node);
        out_printf(o, " at depth %" PRIu32 ": building its subtree of %" PRIu32 " prims", ev->depth, ev->count);
        if (show_bounds) { out_puts(o, "  "); out_box(o, &ev->bounds); }
        break;
    default:
        out_printf(o, "unknown event %d", (int)ev->type);
        break;
    }
}

int sidx_event_format(const sidx_event *ev, char *buf, size_t size)
{
    sink_out o = out_to_buffer(buf, size);
    if (!ev) return -1;
    format_event(&o, ev, 0);
    return out_result(&o);
}

/* Writes one line.  Short lines (nearly all) are formatted on the stack
 * and written with a single call, so lines from several threads sharing a
 * FILE do not interleave mid-line; longer ones stream in pieces. */
static void write_line(FILE *f, const sidx_event *ev, int show_bounds,
                       void (*fmt)(sink_out *, const sidx_event *, int))
{
    char line[512];
    sink_out o = out_to_buffer(line, sizeof line);
    fmt(&o, ev, show_bounds);
    if (!o.error && o.len < sizeof line - 1) {
        line[o.len] = '\n';
        fwrite(line, 1, o.len + 1, f);
    } else {
        sink_out fo = out_to_file(f);
        fmt(&fo, ev, show_bounds);
        fputc('\n', f);
    }
}

static void printer_fn(const sidx_event *ev, void *user)
{
    sidx_printer *p = user;
    if (!p || !p->out || !ev) return;
    /* The emitter already honours the hook's mask; checking p->mask here
     * too lets a caller narrow it on the fly or call the function directly. */
    if (p->mask && ((unsigned)ev->type >= 32u || !(p->mask & SIDX_EVMASK(ev->type)))) return;
    write_line(p->out, ev, p->show_bounds, format_event);
    p->lines++;
}

void sidx_printer_init(sidx_printer *p, FILE *out)
{
    if (!p) return;
    p->out = out;
    p->mask = 0;
    p->show_bounds = 0;
    p->lines = 0;
}

sidx_hook sidx_printer_hook(sidx_printer *p)
{
    sidx_hook h = {printer_fn, p, p ? p->mask : 0};
    return h;
}

/* ---- JSON Lines ----------------------------------------------------------- */

/* A JSON string literal.  Bytes >= 0x80 pass through: event strings are
 * ASCII or UTF-8. */
static void out_json_string(sink_out *o, const char *s)
{
    char chunk[72];
    size_t n = 0;
    chunk[n++] = '"';
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        const char *esc = NULL;
        char uesc[8];
        switch (c) {
        case '"': esc = "\\\""; break;
        case '\\': esc = "\\\\"; break;
        case '\n': esc = "\\n"; break;
        case '\r': esc = "\\r"; break;
        case '\t': esc = "\\t"; break;
        case '\b': esc = "\\b"; break;
        case '\f': esc = "\\f"; break;
        default:
            if (c < 0x20) {
                snprintf(uesc, sizeof uesc, "\\u%04x", (unsigned)c);
                esc = uesc;
            }
            break;
        }
        if (esc) {
            size_t el = strlen(esc);
            memcpy(chunk + n, esc, el);
            n += el;
        } else {
            chunk[n++] = (char)c;
        }
        if (n >= sizeof chunk - 8) { /* room for the longest escape (6) + NUL */
            chunk[n] = '\0';
            out_puts(o, chunk);
            n = 0;
        }
    }
    chunk[n++] = '"';
    chunk[n] = '\0';
    out_puts(o, chunk);
}

/* A float as JSON.  JSON has no inf or NaN, so those become the strings
 * "inf", "-inf" and "nan".  Finite values use the fewest significant
 * digits (6 to 9) that read back as the same float: short for people,
 * exact for tools. */
static void out_json_float(sink_out *o, float f)
{
    if (isnan(f)) { out_puts(o, "\"nan\""); return; }
    if (isinf(f)) { out_puts(o, f > 0 ? "\"inf\"" : "\"-inf\""); return; }
    char tmp[32];
    for (int prec = 6; prec <= 9; ++prec) {
        snprintf(tmp, sizeof tmp, "%.*g", prec, (double)f);
        if (strtof(tmp, NULL) == f) break; /* 9 digits always round-trip a float */
    }
    out_puts(o, tmp);
}

/* Every key an event's JSON object may hold; the reader keeps them as bits. */
static const char *const json_key_names[] = {"type", "structure", "ray", "node", "parent", "depth", "prim",
                                             "count", "aux", "axis", "result", "reason", "cell", "pos",
                                             "cost", "t_near", "t_far", "t", "bounds", "text", "prims", "extent"};
#define JSON_NKEYS ((int)(sizeof json_key_names / sizeof json_key_names[0]))

static int json_key_index(const char *key)
{
    for (int k = 0; k < JSON_NKEYS; ++k)
        if (!strcmp(json_key_names[k], key)) return k;
    return -1;
}

static void json_key(sink_out *o, const char *key)
{
    if (o->record) {
        const int k = json_key_index(key);
        if (k >= 0) o->keys |= 1u << k;
    }
    out_printf(o, ",\"%s\":", key);
}

/* An id field; the blank value UINT32_MAX ("none") is null. */
static void json_id(sink_out *o, const char *key, uint32_t v)
{
    json_key(o, key);
    if (o->record) o->nullable |= 1u << json_key_index(key);
    if (v == UINT32_MAX)
        out_puts(o, "null");
    else
        out_printf(o, "%" PRIu32, v);
}

static void json_u32(sink_out *o, const char *key, uint32_t v)
{
    json_key(o, key);
    out_printf(o, "%" PRIu32, v);
}

static void json_i32(sink_out *o, const char *key, int32_t v)
{
    json_key(o, key);
    out_printf(o, "%" PRId32, v);
}

static void json_float(sink_out *o, const char *key, float v)
{
    json_key(o, key);
    out_json_float(o, v);
}

static void json_vec3(sink_out *o, sidx_vec3 v)
{
    out_puts(o, "[");
    out_json_float(o, v.x);
    out_puts(o, ",");
    out_json_float(o, v.y);
    out_puts(o, ",");
    out_json_float(o, v.z);
    out_puts(o, "]");
}

static void json_bounds(sink_out *o, const sidx_aabb *b)
{
    json_key(o, "bounds");
    out_puts(o, "{\"min\":");
    json_vec3(o, b->min);
    out_puts(o, ",\"max\":");
    json_vec3(o, b->max);
    out_puts(o, "}");
}

static void json_reason(sink_out *o, const char *name)
{
    json_key(o, "reason");
    out_json_string(o, name);
}

/* Which fields each type carries mirrors the comments in hook.h; the table
 * in docs/events.md is the same list. */
static void json_event(sink_out *o, const sidx_event *ev, int unused)
{
    (void)unused;
    out_puts(o, "{\"type\":");
    out_json_string(o, sidx_event_type_name(ev->type));
    out_puts(o, ",\"structure\":");
    if (ev->structure)
        out_json_string(o, ev->structure);
    else
        out_puts(o, "null");
    json_u32(o, "ray", ev->ray_id);

    switch (ev->type) {
    case SIDX_EV_BUILD_BEGIN:
        json_u32(o, "count", ev->count);
        json_bounds(o, &ev->bounds);
        break;
    case SIDX_EV_BUILD_NODE:
    case SIDX_EV_BUILD_REINSERT:
    case SIDX_EV_BUILD_LAZY_EXPAND:
        json_id(o, "node", ev->node);
        json_id(o, "parent", ev->parent);
        json_id(o, "depth", ev->depth);
        json_u32(o, "count", ev->count); /* reinsert: the pass */
        json_bounds(o, &ev->bounds);
        if (ev->type == SIDX_EV_BUILD_REINSERT) {
            json_u32(o, "aux", ev->aux);
            json_float(o, "cost", ev->cost);
        }
        break;
    case SIDX_EV_BUILD_CANDIDATE:
    case SIDX_EV_BUILD_SPLIT:
        json_id(o, "node", ev->node);
        json_i32(o, "axis", ev->axis);
        json_float(o, "pos", ev->pos);
        json_float(o, "cost", ev->cost);
        json_u32(o, "count", ev->count);
        json_u32(o, "aux", ev->aux);
        if (ev->axis < 0) json_bounds(o, &ev->bounds); /* BSP: plane normal in bounds.min */
        break;
    case SIDX_EV_BUILD_LEAF:
        json_id(o, "node", ev->node);
        json_id(o, "depth", ev->depth);
        json_u32(o, "count", ev->count);
        json_float(o, "cost", ev->cost);
        json_reason(o, sidx_leaf_reason_name(ev->reason));
        if (ev->prims && ev->count != UINT32_MAX) { /* all of them: tools want the exact list */
            json_key(o, "prims");
            out_puts(o, "[");
            for (uint32_t i = 0; i < ev->count; ++i) out_printf(o, i ? ",%" PRIu32 : "%" PRIu32, ev->prims[i]);
            out_puts(o, "]");
        }
        break;
    case SIDX_EV_BUILD_END:
        json_u32(o, "node", ev->node); /* a node count here, not an id */
        json_u32(o, "count", ev->count);
        json_u32(o, "depth", ev->depth);
        break;
    case SIDX_EV_RAY_BEGIN:
        json_float(o, "t_near", ev->t_near);
        json_float(o, "t_far", ev->t_far);
        break;
    case SIDX_EV_NODE_ENTER:
        json_id(o, "node", ev->node);
        json_id(o, "depth", ev->depth);
        json_float(o, "t_near", ev->t_near);
        json_float(o, "t_far", ev->t_far);
        if (ev->axis >= 0) { /* a kd-tree's inner node: its plane, t_split, the case taken */
            json_i32(o, "axis", ev->axis);
            json_float(o, "pos", ev->pos);
            json_float(o, "t", ev->t);
            json_i32(o, "result", ev->result);
        }
        break;
    case SIDX_EV_BOX_TEST:
        json_id(o, "node", ev->node);
        json_i32(o, "result", ev->result);
        json_bounds(o, &ev->bounds);
        if (ev->result == 1) { /* a missed box has no interval */
            json_float(o, "t_near", ev->t_near);
            json_float(o, "t_far", ev->t_far);
        }
        break;
    case SIDX_EV_STACK_PUSH:
    case SIDX_EV_STACK_POP:
        json_id(o, "node", ev->node);
        json_id(o, "depth", ev->depth);
        json_float(o, "t_near", ev->t_near);
        json_float(o, "t_far", ev->t_far);
        if (ev->result != -1) json_i32(o, "result", ev->result);
        break;
    case SIDX_EV_PRIM_TEST:
        json_id(o, "prim", ev->prim);
        json_i32(o, "result", ev->result);
        if (ev->result == 1) json_float(o, "t", ev->t);
        break;
    case SIDX_EV_HIT_UPDATE:
        json_id(o, "prim", ev->prim);
        json_float(o, "t", ev->t);
        break;
    case SIDX_EV_MAILBOX_HIT:
        json_id(o, "prim", ev->prim);
        break;
    case SIDX_EV_TERMINATE:
        json_reason(o, sidx_term_reason_name(ev->reason));
        json_float(o, "t", ev->t);
        json_u32(o, "count", ev->count);
        break;
    case SIDX_EV_RAY_END:
        json_id(o, "prim", ev->prim);
        json_float(o, "t", ev->t);
        json_i32(o, "result", ev->result); /* the answer of an occlusion query */
        break;
    case SIDX_EV_NOTE:
        json_key(o, "text");
        if (ev->text)
            out_json_string(o, ev->text);
        else
            out_puts(o, "null");
        break;
    case SIDX_EV_BUILD_MERGE:
    case SIDX_EV_BUILD_EXPAND:
        json_id(o, "node", ev->node);
        json_i32(o, "axis", ev->axis);
        json_u32(o, "aux", ev->aux);
        if (ev->type == SIDX_EV_BUILD_EXPAND) {
            json_i32(o, "result", ev->result);
            if (ev->result == 0) json_i32(o, "reason", ev->reason); /* 1: the slab look-up limit */
        }
        json_u32(o, "count", ev->count);
        json_bounds(o, &ev->bounds);
        break;
    default:
        break;
    }
    /* Grid cells may appear on any event (node_enter above all). */
    if (has_cell(ev)) {
        json_key(o, "cell");
        out_printf(o, "[%" PRId32 ",%" PRId32 ",%" PRId32 "]", ev->cell[0], ev->cell[1], ev->cell[2]);
    }
    if (has_extent(ev)) {
        json_key(o, "extent");
        out_printf(o, "[%" PRIu32 ",%" PRIu32 ",%" PRIu32 "]", ev->extent[0], ev->extent[1], ev->extent[2]);
    }
    out_puts(o, "}");
}

int sidx_event_to_json(const sidx_event *ev, char *buf, size_t size)
{
    sink_out o = out_to_buffer(buf, size);
    if (!ev) return -1;
    json_event(&o, ev, 0);
    return out_result(&o);
}

static void jsonl_fn(const sidx_event *ev, void *user)
{
    sidx_jsonl *j = user;
    if (!j || !j->out || !ev) return;
    write_line(j->out, ev, 0, json_event);
    j->lines++;
}

void sidx_jsonl_init(sidx_jsonl *j, FILE *out)
{
    if (!j) return;
    j->out = out;
    j->lines = 0;
}

sidx_hook sidx_jsonl_hook(sidx_jsonl *j)
{
    sidx_hook h = {jsonl_fn, j, 0};
    return h;
}

/* ---- reading JSON Lines back ---------------------------------------------- */

/* sidx_event_from_json reads any JSON object (keys in any order, blanks
 * between tokens), then asks json_event which keys it would write for the
 * event read, and accepts the line only if those are exactly the keys
 * given: the writer stays the one description of the format, and a line
 * that is accepted is written back as the same object. */

typedef struct json_in {
    const char *line, *p;  /* the line and the read position */
    char *store;           /* strings and the prims list go here */
    size_t size, used;
    sidx_error *err;
    sidx_status status;
} json_in;

/* Notes the first error (status, and "column N: what" in err); -1. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int jin_fail(json_in *in, sidx_status st, const char *fmt, ...)
{
    if (in->status != SIDX_OK) return -1; /* keep the first message */
    in->status = st;
    if (!in->err) return -1;
    va_list ap;
    int n = snprintf(in->err->message, sizeof in->err->message, "column %zu: ", (size_t)(in->p - in->line) + 1);
    if (n < 0) n = 0;
    va_start(ap, fmt);
    if ((size_t)n < sizeof in->err->message)
        vsnprintf(in->err->message + n, sizeof in->err->message - (size_t)n, fmt, ap);
    va_end(ap);
    in->err->status = st;
    return -1;
}

static void jin_ws(json_in *in)
{
    while (*in->p == ' ' || *in->p == '\t' || *in->p == '\r' || *in->p == '\n') ++in->p;
}

static int jin_char(json_in *in, char c)
{
    jin_ws(in);
    if (*in->p != c) return jin_fail(in, SIDX_ERR_PARSE, "expected '%c'", c);
    ++in->p;
    return 0;
}

/* The literal null (1), or not (0). */
static int jin_null(json_in *in)
{
    jin_ws(in);
    if (strncmp(in->p, "null", 4) != 0) return 0;
    in->p += 4;
    return 1;
}

static void utf8_put(char *dst, size_t *n, uint32_t c)
{
    if (c < 0x80) {
        dst[(*n)++] = (char)c;
    } else if (c < 0x800) {
        dst[(*n)++] = (char)(0xc0 | (c >> 6));
        dst[(*n)++] = (char)(0x80 | (c & 0x3f));
    } else if (c < 0x10000) {
        dst[(*n)++] = (char)(0xe0 | (c >> 12));
        dst[(*n)++] = (char)(0x80 | ((c >> 6) & 0x3f));
        dst[(*n)++] = (char)(0x80 | (c & 0x3f));
    } else {
        dst[(*n)++] = (char)(0xf0 | (c >> 18));
        dst[(*n)++] = (char)(0x80 | ((c >> 12) & 0x3f));
        dst[(*n)++] = (char)(0x80 | ((c >> 6) & 0x3f));
        dst[(*n)++] = (char)(0x80 | (c & 0x3f));
    }
}

static int hex4(const char *s, uint32_t *out)
{
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) {
        const char c = s[i];
        v <<= 4;
        if (c >= '0' && c <= '9') v |= (uint32_t)(c - '0');
        else if (c >= 'a' && c <= 'f') v |= (uint32_t)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F') v |= (uint32_t)(c - 'A' + 10);
        else return -1;
    }
    *out = v;
    return 0;
}

/* A JSON string into dst (cap bytes, NUL-terminated; the decoded text is
 * never longer than the literal).  -1 on bad syntax, or when it does not
 * fit: then status too_long (a store too small, or a name too long to be
 * one of ours). */
static int jin_string(json_in *in, char *dst, size_t cap, sidx_status too_long)
{
    jin_ws(in);
    if (*in->p != '"') return jin_fail(in, SIDX_ERR_PARSE, "expected a string");
    const char *s = ++in->p;
    size_t n = 0;
    for (;;) {
        if (cap - n < 5) { /* room for a 4-byte character and the NUL */
            in->p = s;
            return jin_fail(in, too_long, too_long == SIDX_ERR_LIMIT ? "no room for the string" : "unexpected string");
        }
        unsigned char c = (unsigned char)*s;
        if (c == '"') break;
        if (c == '\0') {
            in->p = s;
            return jin_fail(in, SIDX_ERR_PARSE, "string not closed");
        }
        if (c < 0x20) {
            in->p = s;
            return jin_fail(in, SIDX_ERR_PARSE, "raw control character in a string");
        }
        if (c != '\\') {
            dst[n++] = (char)c;
            ++s;
            continue;
        }
        uint32_t u;
        switch (s[1]) {
        case '"': dst[n++] = '"'; s += 2; continue;
        case '\\': dst[n++] = '\\'; s += 2; continue;
        case '/': dst[n++] = '/'; s += 2; continue;
        case 'b': dst[n++] = '\b'; s += 2; continue;
        case 'f': dst[n++] = '\f'; s += 2; continue;
        case 'n': dst[n++] = '\n'; s += 2; continue;
        case 'r': dst[n++] = '\r'; s += 2; continue;
        case 't': dst[n++] = '\t'; s += 2; continue;
        case 'u':
            if (hex4(s + 2, &u) != 0) break;
            s += 6;
            if (u >= 0xd800 && u < 0xdc00) { /* a surrogate pair: \ud83d\ude00 */
                uint32_t lo;
                if (s[0] != '\\' || s[1] != 'u' || hex4(s + 2, &lo) != 0 || lo < 0xdc00 || lo > 0xdfff) break;
                s += 6;
                u = 0x10000 + ((u - 0xd800) << 10) + (lo - 0xdc00);
            } else if (u >= 0xdc00 && u < 0xe000) {
                break;
            }
            if (u == 0) break; /* would end the C string early */
            utf8_put(dst, &n, u);
            continue;
        default:
            break;
        }
        in->p = s;
        return jin_fail(in, SIDX_ERR_PARSE, "bad escape in a string");
    }
    dst[n] = '\0';
    in->p = s + 1;
    return 0;
}

/* A string value copied into the store; *out points at it. */
static int jin_store_string(json_in *in, const char **out)
{
    char *dst = in->store ? in->store + in->used : NULL;
    const size_t before = in->used;
    if (jin_string(in, dst, in->store ? in->size - in->used : 0, SIDX_ERR_LIMIT) != 0) return -1;
    in->used = before + strlen(dst) + 1;
    *out = dst;
    return 0;
}

/* A JSON number's text (RFC 8259 grammar, at most 63 characters) into tok;
 * *integer says whether it had no fraction and no exponent. */
static int jin_number(json_in *in, char tok[64], int *integer)
{
    jin_ws(in);
    const char *s = in->p, *q = s;
    if (*q == '-') ++q;
    if (*q == '0') ++q;
    else if (*q >= '1' && *q <= '9') while (*q >= '0' && *q <= '9') ++q;
    else return jin_fail(in, SIDX_ERR_PARSE, "expected a number");
    *integer = 1;
    if (*q == '.') {
        ++q;
        if (*q < '0' || *q > '9') return jin_fail(in, SIDX_ERR_PARSE, "bad number");
        while (*q >= '0' && *q <= '9') ++q;
        *integer = 0;
    }
    if (*q == 'e' || *q == 'E') {
        ++q;
        if (*q == '+' || *q == '-') ++q;
        if (*q < '0' || *q > '9') return jin_fail(in, SIDX_ERR_PARSE, "bad number");
        while (*q >= '0' && *q <= '9') ++q;
        *integer = 0;
    }
    if (q - s > 63) return jin_fail(in, SIDX_ERR_PARSE, "number too long");
    memcpy(tok, s, (size_t)(q - s));
    tok[q - s] = '\0';
    in->p = q;
    return 0;
}

static int jin_i64(json_in *in, long long lo, long long hi, long long *out)
{
    char tok[64];
    int integer;
    if (jin_number(in, tok, &integer) != 0) return -1;
    if (!integer) return jin_fail(in, SIDX_ERR_PARSE, "expected a whole number, not %s", tok);
    errno = 0;
    const long long v = strtoll(tok, NULL, 10);
    if (errno == ERANGE || v < lo || v > hi)
        return jin_fail(in, SIDX_ERR_PARSE, "%s is out of range [%lld, %lld]", tok, lo, hi);
    *out = v;
    return 0;
}

static int jin_i32(json_in *in, int32_t *out)
{
    long long v;
    if (jin_i64(in, INT32_MIN, INT32_MAX, &v) != 0) return -1;
    *out = (int32_t)v;
    return 0;
}

static int jin_u32(json_in *in, uint32_t *out)
{
    long long v;
    if (jin_i64(in, 0, UINT32_MAX, &v) != 0) return -1;
    *out = (uint32_t)v;
    return 0;
}

/* A float: a number within float range, or "inf", "-inf", "nan" (the
 * writer's spelling of the values JSON lacks). */
static int jin_float(json_in *in, float *out)
{
    jin_ws(in);
    if (*in->p == '"') {
        char s[16];
        if (jin_string(in, s, sizeof s, SIDX_ERR_PARSE) != 0) return -1;
        if (!strcmp(s, "inf")) *out = INFINITY;
        else if (!strcmp(s, "-inf")) *out = -INFINITY;
        else if (!strcmp(s, "nan")) *out = NAN;
        else return jin_fail(in, SIDX_ERR_PARSE, "expected a number, \"inf\", \"-inf\" or \"nan\"");
        return 0;
    }
    char tok[64];
    int integer;
    if (jin_number(in, tok, &integer) != 0) return -1;
    errno = 0;
    const float f = strtof(tok, NULL);
    if (isinf(f)) return jin_fail(in, SIDX_ERR_PARSE, "%s is beyond the float range", tok);
    *out = f;
    return 0;
}

static int jin_vec3(json_in *in, sidx_vec3 *v)
{
    if (jin_char(in, '[') || jin_float(in, &v->x) || jin_char(in, ',') || jin_float(in, &v->y) ||
        jin_char(in, ',') || jin_float(in, &v->z) || jin_char(in, ']'))
        return -1;
    return 0;
}

static int jin_bounds(json_in *in, sidx_aabb *b)
{
    int have = 0;
    if (jin_char(in, '{') != 0) return -1;
    for (int i = 0; i < 2; ++i) {
        char key[8];
        if (i && jin_char(in, ',') != 0) return -1;
        if (jin_string(in, key, sizeof key, SIDX_ERR_PARSE) != 0 || jin_char(in, ':') != 0) return -1;
        const int k = !strcmp(key, "min") ? 1 : !strcmp(key, "max") ? 2 : 0;
        if (!k || (have & k)) return jin_fail(in, SIDX_ERR_PARSE, "bounds wants \"min\" and \"max\" once each");
        have |= k;
        if (jin_vec3(in, k == 1 ? &b->min : &b->max) != 0) return -1;
    }
    return jin_char(in, '}');
}

/* The prims list, copied into the store (4-byte aligned). */
static int jin_prims(json_in *in, const uint32_t **out, uint32_t *n)
{
    if (jin_char(in, '[') != 0) return -1;
    if (!in->store) return jin_fail(in, SIDX_ERR_LIMIT, "no room for the prims list");
    const uintptr_t at = (uintptr_t)(in->store + in->used);
    const size_t pad = (size_t)((4u - at % 4u) % 4u);
    if (in->size - in->used < pad) return jin_fail(in, SIDX_ERR_LIMIT, "no room for the prims list");
    in->used += pad;
    uint32_t *ids = (uint32_t *)(void *)(in->store + in->used);
    *n = 0;
    jin_ws(in);
    if (*in->p == ']') {
        ++in->p;
        *out = ids;
        return 0;
    }
    for (;;) {
        uint32_t v;
        if (jin_u32(in, &v) != 0) return -1;
        if (in->size - in->used < sizeof v) return jin_fail(in, SIDX_ERR_LIMIT, "no room for the prims list");
        memcpy(in->store + in->used, &v, sizeof v);
        in->used += sizeof v;
        ++*n;
        jin_ws(in);
        if (*in->p == ']') break;
        if (jin_char(in, ',') != 0) return -1;
    }
    ++in->p;
    *out = ids;
    return 0;
}

enum { JK_TYPE = 0, JK_STRUCTURE, JK_RAY, JK_NODE, JK_PARENT, JK_DEPTH, JK_PRIM, JK_COUNT, JK_AUX, JK_AXIS,
       JK_RESULT, JK_REASON, JK_CELL, JK_POS, JK_COST, JK_T_NEAR, JK_T_FAR, JK_T, JK_BOUNDS, JK_TEXT, JK_PRIMS,
       JK_EXTENT };

/* A name of names[0..n) to its index, or -1. */
static int name_index(const char *s, const char *(*name)(int), int n)
{
    for (int i = 0; i < n; ++i)
        if (!strcmp(name(i), s)) return i;
    return -1;
}

static const char *type_name_int(int t) { return sidx_event_type_name((sidx_event_type)t); }

/* One value of key k into e (ids: null notes the key in *nulls). */
static int jin_field(json_in *in, int k, sidx_event *e, char *reason, size_t reason_size, uint32_t *nulls,
                     uint32_t *nprims)
{
    uint32_t *ids[] = {[JK_RAY] = &e->ray_id, [JK_NODE] = &e->node,   [JK_PARENT] = &e->parent,
                       [JK_DEPTH] = &e->depth, [JK_PRIM] = &e->prim,  [JK_COUNT] = &e->count,
                       [JK_AUX] = &e->aux};
    float *floats[] = {[JK_POS] = &e->pos,       [JK_COST] = &e->cost, [JK_T_NEAR] = &e->t_near,
                       [JK_T_FAR] = &e->t_far,   [JK_T] = &e->t};
    char name[24];
    switch (k) {
    case JK_TYPE: {
        if (jin_string(in, name, sizeof name, SIDX_ERR_PARSE) != 0) return jin_fail(in, SIDX_ERR_PARSE, "\"type\" wants an event name");
        const int t = name_index(name, type_name_int, SIDX_EV_COUNT);
        if (t < 0) return jin_fail(in, SIDX_ERR_PARSE, "unknown event type \"%s\"", name);
        e->type = (sidx_event_type)t;
        return 0;
    }
    case JK_STRUCTURE:
    case JK_TEXT:
        if (jin_null(in)) {
            *(k == JK_TEXT ? &e->text : &e->structure) = NULL;
            return 0;
        }
        return jin_store_string(in, k == JK_TEXT ? &e->text : &e->structure);
    case JK_RAY: case JK_NODE: case JK_PARENT: case JK_DEPTH: case JK_PRIM: case JK_COUNT: case JK_AUX:
        if (jin_null(in)) {
            *ids[k] = UINT32_MAX;
            *nulls |= 1u << k;
            return 0;
        }
        return jin_u32(in, ids[k]);
    case JK_AXIS: return jin_i32(in, &e->axis);
    case JK_RESULT: return jin_i32(in, &e->result);
    case JK_REASON:
        /* a name (leaf and terminate reasons), or build_expand's number */
        jin_ws(in);
        if (*in->p != '"') {
            if (jin_i32(in, &e->reason) != 0) return -1;
            snprintf(reason, reason_size, "#");
            return 0;
        }
        if (jin_string(in, reason, reason_size, SIDX_ERR_PARSE) != 0) return jin_fail(in, SIDX_ERR_PARSE, "\"reason\" wants a name");
        return 0;
    case JK_EXTENT:
        if (jin_char(in, '[') || jin_u32(in, &e->extent[0]) || jin_char(in, ',') || jin_u32(in, &e->extent[1]) ||
            jin_char(in, ',') || jin_u32(in, &e->extent[2]) || jin_char(in, ']'))
            return -1;
        return 0;
    case JK_CELL:
        if (jin_char(in, '[') || jin_i32(in, &e->cell[0]) || jin_char(in, ',') || jin_i32(in, &e->cell[1]) ||
            jin_char(in, ',') || jin_i32(in, &e->cell[2]) || jin_char(in, ']'))
            return -1;
        return 0;
    case JK_POS: case JK_COST: case JK_T_NEAR: case JK_T_FAR: case JK_T:
        return jin_float(in, floats[k]);
    case JK_BOUNDS: return jin_bounds(in, &e->bounds);
    case JK_PRIMS: return jin_prims(in, &e->prims, nprims);
    default: return jin_fail(in, SIDX_ERR_PARSE, "unknown field");
    }
}

static const char *leaf_name_int(int r) { return sidx_leaf_reason_name(r); }
static const char *term_name_int(int r) { return sidx_term_reason_name(r); }

/* One event from in->line into *out; -1 (in->status, in->err) if the line is not one. */
static int jin_event(json_in *in, sidx_event *out)
{
    sidx_event e = sidx_event_blank(SIDX_EV_COUNT);
    char reason[24] = "";
    uint32_t seen = 0, nulls = 0, nprims = 0;
    if (jin_char(in, '{') != 0) return -1;
    jin_ws(in);
    if (*in->p == '}') return jin_fail(in, SIDX_ERR_PARSE, "empty object: an event needs \"type\"");
    for (;;) {
        char key[16];
        const char *at = in->p;
        if (jin_string(in, key, sizeof key, SIDX_ERR_PARSE) != 0) return -1;
        const int k = json_key_index(key);
        if (k < 0) {
            in->p = at;
            return jin_fail(in, SIDX_ERR_PARSE, "unknown field \"%s\"", key);
        }
        if (seen & (1u << k)) {
            in->p = at;
            return jin_fail(in, SIDX_ERR_PARSE, "field \"%s\" given twice", key);
        }
        seen |= 1u << k;
        if (jin_char(in, ':') != 0 || jin_field(in, k, &e, reason, sizeof reason, &nulls, &nprims) != 0)
            return -1;
        jin_ws(in);
        if (*in->p == '}') break;
        if (jin_char(in, ',') != 0) return -1;
    }
    ++in->p;
    jin_ws(in);
    if (*in->p) return jin_fail(in, SIDX_ERR_PARSE, "text after the object");

    in->p = in->line; /* what follows is about the whole line */
    if (!(seen & (1u << JK_TYPE))) return jin_fail(in, SIDX_ERR_PARSE, "no \"type\"");
    const char *tname = sidx_event_type_name(e.type);
    if ((seen & (1u << JK_REASON)) && e.type == SIDX_EV_BUILD_EXPAND) {
        if (strcmp(reason, "#") != 0) return jin_fail(in, SIDX_ERR_PARSE, "a build_expand \"reason\" is a number");
    } else if (seen & (1u << JK_REASON)) {
        if (!strcmp(reason, "#")) return jin_fail(in, SIDX_ERR_PARSE, "\"reason\" wants a name");
        const int leaf = e.type == SIDX_EV_BUILD_LEAF;
        const int r = leaf ? name_index(reason, leaf_name_int, SIDX_LEAF_REASON_COUNT)
                           : name_index(reason, term_name_int, SIDX_TERM_REASON_COUNT);
        if (r < 0) return jin_fail(in, SIDX_ERR_PARSE, "unknown %s reason \"%s\"", tname, reason);
        e.reason = r;
    }
    if ((seen & (1u << JK_PRIMS)) && (e.count == UINT32_MAX || nprims != e.count))
        return jin_fail(in, SIDX_ERR_PARSE, "\"prims\" lists %" PRIu32 " ids, \"count\" says %" PRIu32, nprims,
                        e.count);
    if (!(seen & (1u << JK_PRIMS))) e.prims = NULL;

    /* The keys the writer would write for this event must be the keys read. */
    sink_out keys = out_to_buffer(NULL, 0);
    keys.record = 1;
    json_event(&keys, &e, 0);
    const uint32_t want = keys.keys | (1u << JK_TYPE) | (1u << JK_STRUCTURE);
    for (int k = 0; k < JSON_NKEYS; ++k) {
        const uint32_t bit = 1u << k;
        if ((want & bit) && !(seen & bit))
            return jin_fail(in, SIDX_ERR_PARSE, "a %s event needs \"%s\"", tname, json_key_names[k]);
        if (!(want & bit) && (seen & bit))
            return jin_fail(in, SIDX_ERR_PARSE, "a %s event has no \"%s\" here (docs/events.md)", tname,
                            json_key_names[k]);
        if ((nulls & bit) && !(keys.nullable & bit))
            return jin_fail(in, SIDX_ERR_PARSE, "\"%s\" of a %s event is a number, not null", json_key_names[k],
                            tname);
    }
    *out = e;
    return 0;
}

sidx_status sidx_event_from_json(const char *line, sidx_event *ev, char *store, size_t store_size, size_t *store_used,
                                 sidx_error *err)
{
    json_in in = {line, line, store, store ? store_size : 0, 0, err, SIDX_OK};
    if (store_used) *store_used = 0;
    if (!line || !ev) {
        if (err) {
            err->status = SIDX_ERR_INVALID_ARG;
            snprintf(err->message, sizeof err->message, "sidx_event_from_json: line and ev must not be NULL");
        }
        return SIDX_ERR_INVALID_ARG;
    }
    sidx_event e;
    if (jin_event(&in, &e) != 0) return in.status;
    *ev = e;
    if (store_used) *store_used = in.used;
    return SIDX_OK;
}

/* ---- recorder ------------------------------------------------------------- */

#define RECORDER_FIRST_CAPACITY 256
#define PRIM_CHUNK_MIN 4096 /* ids per chunk of the prims store, at least */

/* The prims lists are copied into a list of chunks that are never moved
 * or resized, so the pointers handed out stay valid while more leaves are
 * recorded (a realloc'd pool would leave the earlier events dangling). */
typedef struct prim_chunk {
    struct prim_chunk *next;
    size_t used, cap;
    uint32_t ids[];
} prim_chunk;

static void prim_store_free(sidx_recorder *r)
{
    prim_chunk *c = r->prim_store;
    while (c) {
        prim_chunk *next = c->next;
        free(c);
        c = next;
    }
    r->prim_store = NULL;
}

/* A copy of ids[0..n) owned by the recorder, or NULL when out of memory. */
static const uint32_t *prim_store_copy(sidx_recorder *r, const uint32_t *ids, uint32_t n)
{
    prim_chunk *c = r->prim_store; /* the newest chunk is first */
    if (!c || c->cap - c->used < n) {
        size_t cap = n > PRIM_CHUNK_MIN ? n : PRIM_CHUNK_MIN;
        if (c && c->cap <= (SIZE_MAX / 2) && 2 * c->cap > cap) cap = 2 * c->cap; /* fewer chunks on big builds */
        if (cap > (SIZE_MAX - sizeof(prim_chunk)) / sizeof(uint32_t)) return NULL;
        prim_chunk *fresh = malloc(sizeof(prim_chunk) + cap * sizeof(uint32_t));
        if (!fresh) return NULL;
        fresh->next = c;
        fresh->used = 0;
        fresh->cap = cap;
        r->prim_store = c = fresh;
    }
    uint32_t *dst = c->ids + c->used;
    memcpy(dst, ids, (size_t)n * sizeof *ids);
    c->used += n;
    return dst;
}

static void recorder_fn(const sidx_event *ev, void *user)
{
    sidx_recorder *r = user;
    if (!r || !ev) return;
    /* After the first drop the recording has a hole; keeping later events
     * would make a stepper show a history that never happened. */
    if (r->overflow) return;
    if (r->limit && r->count >= r->limit) {
        r->overflow = 1;
        return;
    }
    if (r->count == r->capacity) {
        const size_t max_cap = SIZE_MAX / sizeof(sidx_event);
        size_t cap = r->capacity ? r->capacity : RECORDER_FIRST_CAPACITY;
        if (r->capacity) cap = r->capacity <= max_cap / 2 ? r->capacity * 2 : max_cap;
        if (cap <= r->capacity) { /* cannot grow any further */
            r->overflow = 1;
            return;
        }
        sidx_event *grown = realloc(r->events, cap * sizeof(sidx_event));
        if (!grown) { /* the old array is still valid and still ours */
            r->overflow = 1;
            return;
        }
        r->events = grown;
        r->capacity = cap;
    }
    sidx_event copy = *ev;
    if (ev->prims) {
        /* The emitter's list lives only during this call: keep our own. */
        copy.prims = NULL;
        if (ev->count && ev->count != UINT32_MAX) {
            copy.prims = prim_store_copy(r, ev->prims, ev->count);
            if (!copy.prims) {
                r->overflow = 1;
                return;
            }
        }
    }
    r->events[r->count++] = copy;
}

void sidx_recorder_init(sidx_recorder *r)
{
    if (!r) return;
    r->events = NULL;
    r->count = 0;
    r->capacity = 0;
    r->limit = 0;
    r->overflow = 0;
    r->prim_store = NULL;
}

void sidx_recorder_clear(sidx_recorder *r)
{
    if (!r) return;
    r->count = 0;
    r->overflow = 0;
    prim_store_free(r);
}

void sidx_recorder_free(sidx_recorder *r)
{
    if (!r) return;
    free(r->events);
    prim_store_free(r);
    r->events = NULL;
    r->count = 0;
    r->capacity = 0;
    r->overflow = 0; /* limit is a setting, not contents: kept */
}

sidx_hook sidx_recorder_hook(sidx_recorder *r)
{
    sidx_hook h = {recorder_fn, r, 0};
    return h;
}

/* ---- counters ------------------------------------------------------------- */

static void counters_fn(const sidx_event *ev, void *user)
{
    sidx_counters *c = user;
    if (!c || !ev || (unsigned)ev->type >= SIDX_EV_COUNT) return;
    c->n[ev->type]++;
    if (ev->type == SIDX_EV_PRIM_TEST && ev->result == 1) c->prim_hits++;
    if (ev->type == SIDX_EV_BOX_TEST && ev->result == 1) c->box_hits++;
    if (ev->type == SIDX_EV_RAY_BEGIN) c->rays++;
}

void sidx_counters_init(sidx_counters *c)
{
    if (c) memset(c, 0, sizeof *c);
}

sidx_hook sidx_counters_hook(sidx_counters *c)
{
    sidx_hook h = {counters_fn, c, 0};
    return h;
}

void sidx_counters_print(const sidx_counters *c, FILE *out)
{
    if (!c || !out) return;
    for (int t = 0; t < SIDX_EV_COUNT; ++t)
        if (c->n[t]) fprintf(out, "%s: %" PRIu64 "\n", sidx_event_type_name((sidx_event_type)t), c->n[t]);
    if (c->prim_hits) fprintf(out, "prim_hits: %" PRIu64 "\n", c->prim_hits);
    if (c->box_hits) fprintf(out, "box_hits: %" PRIu64 "\n", c->box_hits);
    if (c->rays) fprintf(out, "rays: %" PRIu64 "\n", c->rays);
}

/* ---- tee ------------------------------------------------------------------ */

#define TEE_MAX ((int)(sizeof(((sidx_tee *)0)->hooks) / sizeof(sidx_hook)))

static int tee_size(const sidx_tee *t)
{
    if (t->n < 0) return 0;
    return t->n < TEE_MAX ? t->n : TEE_MAX;
}

static int hook_wants(const sidx_hook *h, sidx_event_type type)
{
    return h->fn && (h->mask == 0 || ((unsigned)type < 32u && (h->mask & SIDX_EVMASK(type))));
}

static void tee_fn(const sidx_event *ev, void *user)
{
    const sidx_tee *t = user;
    if (!t || !ev) return;
    const int n = tee_size(t);
    for (int i = 0; i < n; ++i)
        if (hook_wants(&t->hooks[i], ev->type)) t->hooks[i].fn(ev, t->hooks[i].user);
}

/* The tee's own mask is the union of its hooks' masks, so emitters skip
 * events nobody downstream wants.  It is computed now: fill t->hooks and
 * t->n before asking for the hook. */
sidx_hook sidx_tee_hook(sidx_tee *t)
{
    sidx_hook h = {tee_fn, t, 0};
    if (!t) return h;
    uint32_t mask = 0;
    const int n = tee_size(t);
    for (int i = 0; i < n; ++i) {
        if (!t->hooks[i].fn) continue;
        if (t->hooks[i].mask == 0) { /* one hook wants everything */
            mask = 0;
            break;
        }
        mask |= t->hooks[i].mask;
    }
    h.mask = mask;
    return h;
}
