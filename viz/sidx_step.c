/* sidx-step — step through one ray's traversal (or a build) event by event.
 *
 *   sidx-step --accel NAME SCENE --ray ox,oy,oz,dx,dy,dz [--all] [--json] [--build]
 *             [--step K] [--break TYPE] [--panel] [build knobs]
 *   sidx-step --diff A.jsonl B.jsonl [--exact] [--notes]
 *
 * One event per line, indented by depth (sidx_event_format, the printer's
 * layout), or JSON Lines with --json.  When stdin and stdout are both a
 * terminal it is a full-screen stepper: one key per step, forwards and
 * back, jumps to a step number, to the next event of a type or the next
 * leaf, with a Current / Stack column for the tree structures (deck 000,
 * "kD-Tree Traversal (1)-(11)": the node being visited and the subtrees
 * still to traverse, one row per step).  Otherwise, or with --all, it
 * prints the events, up to --step K or the first --break TYPE event.
 * --diff aligns two JSON Lines traces (as --json and sidx-check --trace
 * write them) event by event, prints the first divergence and the count of
 * each event type on both sides.
 * Exit status: 0 ok (--diff: the traces agree), 1 failure (--diff: they
 * part; --break: no such event), 2 usage. */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"
#include "args.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: sidx-step --accel NAME SCENE [--ray ox,oy,oz,dx,dy,dz] [--build] [--all] [--json]\n"
            "                 [--step K] [--break TYPE] [--panel] [build knobs]\n"
            "       sidx-step --diff A.jsonl B.jsonl [--exact] [--notes]\n"
            "\n"
            "Builds structure NAME over SCENE (a .obj/.ply file or a built-in scene such as\n"
            "teapot, flat2d) and prints the ray's traversal one event per line, indented by\n"
            "depth (flat2d, the 2D board, is one triangle per shape, which a ray in the plane\n"
            "z = 0 hits along the shape's longest median).  On a terminal it is a stepper, one\n"
            "key per step:\n"
            "  Enter Space n Right  next step          b Backspace Left  previous step\n"
            "  g K Enter            go to step K       Home End          first, last step\n"
            "  c / C                next / previous event of the --break type (t changes it)\n"
            "  l / L                next / previous leaf entered\n"
            "  a                    run to the end     q                 quit\n"
            "with a Current / Stack column for trees: the node visited and the stack of\n"
            "subtrees still to traverse, top first, each with its t range.  Labelled nodes go by\n"
            "their label: kd-slide with --accel kdtree is deck 000's \"kD-Tree Traversal\" (A, B,\n"
            "L2, ...; try --ray 0,4.2,0,1,0.15,0).\n"
            "\n"
            "  --accel NAME       structure (see --list)\n"
            "  --ray R            the ray: origin ox,oy,oz and direction dx,dy,dz\n"
            "  --build            print the build decisions (before the traversal, if --ray)\n"
            "  --traversal KIND   default, stack, ordered or naive\n"
            "  --bounds           also print node boxes\n"
            "  --step K           start at step K (without a terminal: print steps 1..K)\n"
            "  --break TYPE       run to the first event of TYPE at or after the start\n"
            "                     (without a terminal: print up to it; exit 1 if there is none):\n"
            "                     an event name (stack_push, node_enter, prim_test, ...), the\n"
            "                     part of it after or before '_' if unique (push, pop, enter,\n"
            "                     box, prim, hit, mailbox, terminate), or leaf (a leaf entered)\n"
            "  --panel            add the Current / Stack columns to the printed lines, which\n"
            "                     fit 100 columns: a long event wraps under itself, a deep\n"
            "                     stack shows its top entries and counts the others\n"
            "  --all              do not wait between steps\n"
            "  --json             JSON Lines (one object per event) instead of text\n"
            "  --list             list the registered structures\n"
            "  --diff A B         compare two JSON Lines traces event by event: the first\n"
            "                     divergence and the events of each type on both sides\n"
            "                     (exit 0 agree, 1 they part); floats agree within 1e-5\n"
            "                     relative unless --exact; note events are skipped unless --notes\n"
            "  -h, --help         this help\n"
            "\n%s",
            sidx_viz_build_knobs_help());
}

/* ---- the events to step through ------------------------------------------------------------ */

/* --break's pseudo-type: a NODE_ENTER of a node the build made a leaf. */
#define BREAK_LEAF SIDX_EV_COUNT
#define BREAK_NONE (-1)

typedef struct steps {
    const sidx_event **ev; /* the build events shown (--build), then the traversal */
    size_t n, nbuild;
    uint32_t *leaves;      /* sorted ids of the leaves (BUILD_LEAF) */
    size_t nleaves;
    int json, bounds, panel;
    int columns;           /* --panel printed: the columns name the nodes, the lines carry no label */
    int width;             /* of the event column beside the panel: the longest traversal line */
    const sidx_accel *accel; /* its node labels name the nodes (sidx_accel_node_label) */
} steps;

/* A node as the panel names it: its label (the slide's "A", "L4") or its id. */
static const char *node_name(const steps *s, uint32_t node, char buf[16])
{
    const char *label = sidx_accel_node_label(s->accel, node);
    if (label) return label;
    snprintf(buf, 16, "%u", node);
    return buf;
}

/* Events whose node id a label names (the lines get "  [label]"). */
static int names_node(const sidx_event *e)
{
    switch (e->type) {
    case SIDX_EV_BUILD_NODE: case SIDX_EV_BUILD_SPLIT: case SIDX_EV_BUILD_LEAF: case SIDX_EV_NODE_ENTER:
    case SIDX_EV_BOX_TEST: case SIDX_EV_STACK_PUSH: case SIDX_EV_STACK_POP: case SIDX_EV_TERMINATE:
        return e->node != UINT32_MAX;
    default:
        return 0;
    }
}

static int cmp_u32(const void *a, const void *b)
{
    const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static int is_leaf(const steps *s, uint32_t node)
{
    return s->nleaves && bsearch(&node, s->leaves, s->nleaves, sizeof node, cmp_u32) != NULL;
}

/* Does step i (0-based) stop a run to `type`? */
static int step_is(const steps *s, size_t i, int type)
{
    const sidx_event *e = s->ev[i];
    if (type == BREAK_LEAF)
        return i >= s->nbuild && e->type == SIDX_EV_NODE_ENTER && (e->cell[0] >= 0 || is_leaf(s, e->node));
    return (int)e->type == type;
}

/* "stack_push", "push" or "stack" (if unique), or "leaf": the type, or BREAK_NONE. */
static int parse_break(const char *name)
{
    if (!strcmp(name, "leaf")) return BREAK_LEAF;
    int found = BREAK_NONE, matches = 0;
    for (int t = 0; t < SIDX_EV_COUNT; ++t) {
        const char *full = sidx_event_type_name((sidx_event_type)t), *us = strchr(full, '_');
        if (!strcmp(full, name)) return t;
        const size_t n = strlen(name);
        if ((us && !strcmp(us + 1, name)) || (us && (size_t)(us - full) == n && !strncmp(full, name, n))) {
            found = t;
            ++matches;
        }
    }
    return matches == 1 ? found : BREAK_NONE;
}

static const char *break_name(int type)
{
    return type == BREAK_LEAF ? "leaf" : type == BREAK_NONE ? "(none)" : sidx_event_type_name((sidx_event_type)type);
}

/* The step after (dir +1) or before (dir -1) `from` (0-based) that is `type`; from itself if none. */
static size_t find_step(const steps *s, size_t from, int dir, int type)
{
    for (size_t i = from; dir > 0 ? i + 1 < s->n : i > 0;) {
        i = dir > 0 ? i + 1 : i - 1;
        if (step_is(s, i, type)) return i;
    }
    return from;
}

/* Step i as one line: the printer's (or the JSON) text, plus its box with
 * --bounds.  In buf if it fits, else in a malloc'd copy the caller frees
 * (a build_leaf's JSON lists all its primitives). */
static char *step_text(const steps *s, size_t i, char *buf, size_t size)
{
    const sidx_event *ev = s->ev[i];
    char *out = buf;
    int n = s->json ? sidx_event_to_json(ev, out, size) : sidx_event_format(ev, out, size);
    if (n >= 0 && (size_t)n + 100 >= size && (out = malloc((size_t)n + 101)) != NULL) {
        size = (size_t)n + 101;
        n = s->json ? sidx_event_to_json(ev, out, size) : sidx_event_format(ev, out, size);
    }
    if (!out) out = buf;
    if (n < 0) {
        out[0] = '\0';
        return out;
    }
    if ((size_t)n >= size) n = (int)size - 1;
    const char *label = !s->json && !(s->columns && i >= s->nbuild) && names_node(ev)
                            ? sidx_accel_node_label(s->accel, ev->node) : NULL;
    if (label) {
        const int k = snprintf(out + n, size - (size_t)n, "  [%s]", label);
        if (k > 0) n = (size_t)(n + k) < size ? n + k : (int)size - 1;
    }
    if (!s->json && s->bounds &&
        (ev->type == SIDX_EV_NODE_ENTER || ev->type == SIDX_EV_BUILD_NODE || ev->type == SIDX_EV_BOX_TEST) &&
        !sidx_aabb_is_empty(ev->bounds))
        snprintf(out + n, size - (size_t)n, "  box [(%g, %g, %g), (%g, %g, %g)]", (double)ev->bounds.min.x,
                 (double)ev->bounds.min.y, (double)ev->bounds.min.z, (double)ev->bounds.max.x,
                 (double)ev->bounds.max.y, (double)ev->bounds.max.z);
    return out;
}

static void text_free(char *text, const char *buf)
{
    if (text != buf) free(text);
}

/* ---- Current / Stack (deck 000, "kD-Tree Traversal (1)-(11)") ------------------------------ */

/* What the traversal holds after a step: the node it is at (entered, or
 * just taken off the stack) and the deferred subtrees with their t
 * ranges.  Replayed from the events alone, so it shows what the walk
 * reported, for any structure that reports pushes and pops. */
typedef struct entry {
    uint32_t node;
    float t_near, t_far;
} entry;

typedef struct replay {
    entry cur;
    int has_cur;
    entry *stack;
    size_t n, cap;
} replay;

static void replay_event(replay *r, const sidx_event *e)
{
    switch (e->type) {
    case SIDX_EV_RAY_BEGIN:
    case SIDX_EV_TERMINATE:
    case SIDX_EV_RAY_END:
        r->has_cur = 0;
        if (e->type == SIDX_EV_RAY_BEGIN) r->n = 0;
        break;
    case SIDX_EV_NODE_ENTER:
        r->cur = (entry){e->node, e->t_near, e->t_far};
        r->has_cur = 1;
        break;
    case SIDX_EV_STACK_PUSH:
        if (r->n == r->cap) {
            const size_t nc = r->cap ? 2 * r->cap : 64;
            entry *ns = realloc(r->stack, nc * sizeof *ns);
            if (!ns) break;
            r->stack = ns;
            r->cap = nc;
        }
        r->stack[r->n++] = (entry){e->node, e->t_near, e->t_far};
        break;
    case SIDX_EV_STACK_POP:
        if (r->n) --r->n;
        r->cur = (entry){e->node, e->t_near, e->t_far};
        r->has_cur = e->result != 0; /* 0: dropped (beyond the best hit), nothing current */
        break;
    default:
        break;
    }
}

/* The tree structures report NODE_ENTER of nodes; grids enter cells. */
static int has_panel(const steps *s)
{
    for (size_t i = s->nbuild; i < s->n; ++i)
        if (s->ev[i]->type == SIDX_EV_NODE_ENTER) return s->ev[i]->cell[0] < 0;
    return 0;
}

static void panel_text(const steps *s, const replay *r, char *cur, size_t csize, char *stk, size_t ssize)
{
    char id[16];
    cur[0] = stk[0] = '\0';
    if (r->has_cur)
        snprintf(cur, csize, "%s%s [%g, %g]", node_name(s, r->cur.node, id), is_leaf(s, r->cur.node) ? " leaf" : "",
                 (double)r->cur.t_near, (double)r->cur.t_far);
    size_t off = 0;
    for (size_t k = r->n; k-- > 0 && off < ssize;) {
        const entry *e = &r->stack[k];
        const int w = snprintf(stk + off, ssize - off, "%s%s [%g, %g]", off ? "  " : "", node_name(s, e->node, id),
                               (double)e->t_near, (double)e->t_far);
        if (w < 0) break;
        off += (size_t)w;
    }
}

/* ---- without a terminal: print steps [0, end) -------------------------------------------- */

/* --panel lines fit a terminal of PANEL_COLS columns: the event in a column of at most
 * PANEL_EVENT_COLS, wider when the stack stays narrow (a longer event wraps at its spaces onto
 * lines of its own, the panel beside its first line), the current node in PANEL_CUR_COLS, and the stack with as many entries from
 * the top as fit, the others counted ("+3 more"). */
#define PANEL_COLS 100
#define PANEL_EVENT_COLS 41
#define PANEL_CUR_COLS 20

/* The length of the head of text printed on one line of cols columns: the whole text if it
 * fits, else up to the last gap between two fields in the line's second half, else up to the
 * last space, else cols. */
static size_t wrap_at(const char *text, size_t cols)
{
    const size_t n = strlen(text);
    if (n <= cols) return n;
    for (size_t k = cols; k > cols / 2; --k) /* between two fields (they are two spaces apart) */
        if (text[k] == ' ' && text[k - 1] == ' ') return k - 1;
    for (size_t k = cols; k > 0; --k)
        if (text[k] == ' ') return k;
    return cols;
}

/* The stack entries (top first, separated by two spaces in stk) that fit in cols columns, and
 * "+k more" for the rest. */
static void fit_stack(const char *stk, int cols, char *out, size_t size)
{
    size_t total = 0, kept = 0, len = 0;
    for (const char *p = stk; *p; ++total) { /* entries: "name [a, b]", split at "  " */
        const char *q = strstr(p, "  ");
        const size_t w = q ? (size_t)(q - p) : strlen(p);
        /* the entry, a separator, and room for " +NN more" if entries follow */
        const size_t need = len + (len ? 2 : 0) + w + (q ? 9 : 0);
        if (kept == total && need <= (size_t)cols) {
            len += (len ? 2 : 0) + w;
            kept++;
        }
        p = q ? q + 2 : p + w;
    }
    if (len >= size) len = size - 1;
    memcpy(out, stk, len);
    out[len] = '\0';
    if (kept < total)
        snprintf(out + len, size - len, "%s+%zu more", len ? "  " : "", total - kept);
}

static void print_steps(const steps *s, size_t end)
{
    char buf[512], cur[96], stk[1024], fit[1024];
    replay r = {0};
    const int panel = s->panel && !s->json && has_panel(s);
    /* the event column as wide as the widest stack leaves room for, at least PANEL_EVENT_COLS */
    int ecols = PANEL_EVENT_COLS;
    if (panel) {
        size_t widest = 0;
        for (size_t i = s->nbuild; i < end; ++i) {
            replay_event(&r, s->ev[i]);
            panel_text(s, &r, cur, sizeof cur, stk, sizeof stk);
            if (strlen(stk) > widest) widest = strlen(stk);
        }
        r.n = 0;
        r.has_cur = 0;
        if ((int)widest < PANEL_COLS - PANEL_CUR_COLS - 6 - ecols) ecols = PANEL_COLS - PANEL_CUR_COLS - 6 - (int)widest;
    }
    if (s->width < ecols) ecols = s->width;
    for (size_t i = 0; i < end; ++i) {
        char *line = step_text(s, i, buf, sizeof buf);
        if (panel && i >= s->nbuild) {
            replay_event(&r, s->ev[i]);
            panel_text(s, &r, cur, sizeof cur, stk, sizeof stk);
            const int ccols = (int)strlen(cur) > PANEL_CUR_COLS ? (int)strlen(cur) : PANEL_CUR_COLS;
            fit_stack(stk, PANEL_COLS - ecols - ccols - 6, fit, sizeof fit); /* " | ", " | " */
            /* the event's own indentation, kept on its continuation lines (plus two) */
            size_t indent = strspn(line, " ");
            if (indent + 20 > (size_t)ecols) indent = ecols > 22 ? (size_t)ecols - 22 : 0;
            const char *p = line;
            size_t k = wrap_at(p, (size_t)ecols);
            printf("%-*.*s | %-*s |%s%s\n", ecols, (int)k, p, PANEL_CUR_COLS, cur, fit[0] ? " " : "", fit);
            for (p += k; *p == ' ' || *p; ) {
                while (*p == ' ') ++p;
                if (!*p) break;
                k = wrap_at(p, (size_t)ecols - indent - 2);
                printf("%*s%-*.*s |%*s|\n", (int)indent + 2, "", ecols - (int)indent - 2, (int)k, p,
                       PANEL_CUR_COLS + 2, "");
                p += k;
            }
        } else {
            printf("%s\n", line);
        }
        text_free(line, buf);
    }
    free(r.stack);
}

/* ---- the full-screen stepper ---------------------------------------------------------------- */

static struct termios saved_tty;
static int tty_raw;

static void tty_restore(void)
{
    if (tty_raw) tcsetattr(STDIN_FILENO, TCSAFLUSH, &saved_tty);
    tty_raw = 0;
}

static void on_signal(int sig)
{
    tty_restore();
    signal(sig, SIG_DFL);
    raise(sig);
}

/* Keys without Enter and without echo; restored at exit and on a fatal signal. */
static int tty_enter_raw(void)
{
    if (tcgetattr(STDIN_FILENO, &saved_tty) != 0) return -1;
    struct termios t = saved_tty;
    t.c_lflag &= ~(tcflag_t)(ICANON | ECHO);
    t.c_cc[VMIN] = 1;
    t.c_cc[VTIME] = 0;
    if (tcsetattr(STDIN_FILENO, TCSAFLUSH, &t) != 0) return -1;
    tty_raw = 1;
    atexit(tty_restore);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGHUP, on_signal);
    return 0;
}

enum { KEY_EOF = -1, KEY_LEFT = 256, KEY_RIGHT, KEY_UP, KEY_DOWN, KEY_HOME, KEY_END };

static int read_key(void)
{
    unsigned char c;
    if (read(STDIN_FILENO, &c, 1) != 1) return KEY_EOF;
    if (c != 27) return c;
    /* an escape sequence arrives at once; a lone Escape does not */
    struct pollfd p = {STDIN_FILENO, POLLIN, 0};
    unsigned char seq[3];
    if (poll(&p, 1, 50) <= 0 || read(STDIN_FILENO, &seq[0], 1) != 1) return 27;
    if (poll(&p, 1, 50) <= 0 || read(STDIN_FILENO, &seq[1], 1) != 1) return 27;
    if (seq[0] == '[' && seq[1] >= '1' && seq[1] <= '8') { /* ESC [ 1 ~ (Home), ESC [ 4 ~ (End) */
        if (poll(&p, 1, 50) <= 0 || read(STDIN_FILENO, &seq[2], 1) != 1) return 27;
        return seq[1] == '1' || seq[1] == '7' ? KEY_HOME : seq[1] == '4' || seq[1] == '8' ? KEY_END : 27;
    }
    switch (seq[1]) {
    case 'A': return KEY_UP;
    case 'B': return KEY_DOWN;
    case 'C': return KEY_RIGHT;
    case 'D': return KEY_LEFT;
    case 'H': return KEY_HOME;
    case 'F': return KEY_END;
    default: return 27;
    }
}

static void term_size(int *rows, int *cols)
{
    struct winsize ws;
    *rows = 24;
    *cols = 80;
    if (ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_row > 0 && ws.ws_col > 0) {
        *rows = ws.ws_row;
        *cols = ws.ws_col;
    }
    if (*rows < 10) *rows = 10;
    if (*cols < 40) *cols = 40;
}

/* One screen line: at most cols characters, then clear to its end. */
static void put_line(const char *text, int cols)
{
    printf("%.*s\033[K\n", cols, text);
}

/* The screen for step pos (0-based): a title, the steps up to pos (one
 * row each, the Current / Stack columns for a tree's traversal), the
 * state at pos in the slides' words, a message line and the keys. */
static void draw(const steps *s, size_t pos, int brk, const char *title, const char *msg)
{
    int rows, cols;
    term_size(&rows, &cols);
    const int panel = !s->json && has_panel(s);
    const int window = rows - (panel ? 7 : 5);
    const size_t first = pos + 1 > (size_t)window ? pos + 1 - (size_t)window : 0;
    char buf[512], row[1400], cur[96], stk[1024];
    replay r = {0};
    const int width = s->width < cols / 2 ? s->width : cols / 2;
    printf("\033[H");
    snprintf(row, sizeof row, "%s   step %zu/%zu   break: %s", title, pos + 1, s->n, break_name(brk));
    put_line(row, cols);
    if (panel) snprintf(row, sizeof row, "   step  %-*s | %-20s | %s", width, "event", "current", "stack (top first)");
    else snprintf(row, sizeof row, "   step  event");
    put_line(row, cols);
    for (size_t i = s->nbuild; panel && i < first; ++i) replay_event(&r, s->ev[i]);
    for (size_t i = first; i <= pos; ++i) {
        char *line = step_text(s, i, buf, sizeof buf);
        const char *mark = i == pos ? ">" : " ";
        if (panel && i >= s->nbuild) {
            replay_event(&r, s->ev[i]);
            panel_text(s, &r, cur, sizeof cur, stk, sizeof stk);
            snprintf(row, sizeof row, "%s %5zu  %-*.*s | %-20s | %s", mark, i + 1, width, width, line, cur, stk);
        } else {
            snprintf(row, sizeof row, "%s %5zu  %s", mark, i + 1, line);
        }
        text_free(line, buf);
        if (i == pos) printf("\033[1m");
        printf("%.*s\033[K\033[0m\n", cols, row);
    }
    for (size_t k = pos + 1 - first; k < (size_t)window; ++k) put_line("", cols);
    if (panel) {
        panel_text(s, &r, cur, sizeof cur, stk, sizeof stk);
        snprintf(row, sizeof row, "Current: %s", pos >= s->nbuild ? cur : "");
        put_line(row, cols);
        snprintf(row, sizeof row, "Stack:   %s", pos >= s->nbuild ? stk : "");
        put_line(row, cols);
    }
    put_line(msg ? msg : "", cols);
    put_line("Enter/n next  b back  g go to step  c/C next/prev break  t break type  l/L next/prev leaf  a end  q quit",
             cols);
    fflush(stdout);
    free(r.stack);
}

/* A line typed at the bottom of the screen (Enter ends it, Escape cancels: returns -1). */
static int prompt(const char *what, char *buf, size_t size)
{
    int rows, cols;
    term_size(&rows, &cols);
    size_t n = 0;
    buf[0] = '\0';
    for (;;) {
        printf("\033[%d;1H%s%s\033[K", rows - 1, what, buf);
        fflush(stdout);
        const int k = read_key();
        if (k == '\n' || k == '\r') return 0;
        if (k == 27 || k == KEY_EOF) return -1;
        if ((k == 127 || k == 8) && n) buf[--n] = '\0';
        else if (k >= 32 && k < 127 && n + 1 < size) {
            buf[n++] = (char)k;
            buf[n] = '\0';
        }
    }
}

static void run_stepper(const steps *s, size_t pos, int brk, const char *title)
{
    char msg[160] = "", in[64];
    printf("\033[H\033[2J");
    for (;;) {
        draw(s, pos, brk, title, msg);
        msg[0] = '\0';
        const int k = read_key();
        const size_t was = pos;
        switch (k) {
        case KEY_EOF:
        case 'q':
            return;
        case '\n': case '\r': case ' ': case 'n': case 'j': case KEY_RIGHT: case KEY_DOWN:
            if (pos + 1 < s->n) ++pos;
            else snprintf(msg, sizeof msg, "the last step (q quits)");
            break;
        case 'b': case 'p': case 'k': case 127: case 8: case KEY_LEFT: case KEY_UP:
            if (pos > 0) --pos;
            else snprintf(msg, sizeof msg, "the first step");
            break;
        case KEY_HOME: case '<':
            pos = 0;
            break;
        case KEY_END: case '>': case 'a':
            pos = s->n - 1;
            break;
        case 'g':
            if (prompt("go to step: ", in, sizeof in) == 0 && in[0]) {
                char *end;
                const unsigned long long v = strtoull(in, &end, 10);
                if (*end || v < 1 || v > s->n) snprintf(msg, sizeof msg, "no step '%s' (1 to %zu)", in, s->n);
                else pos = (size_t)v - 1;
            }
            break;
        case 't':
            if (prompt("break on (push, pop, enter, prim, leaf, ...): ", in, sizeof in) == 0 && in[0]) {
                const int t = parse_break(in);
                if (t == BREAK_NONE) snprintf(msg, sizeof msg, "no event type '%s'", in);
                else brk = t;
            }
            break;
        case 'c': case 'C': case 'l': case 'L': {
            const int type = k == 'l' || k == 'L' ? BREAK_LEAF : brk;
            const int dir = k == 'c' || k == 'l' ? 1 : -1;
            if (type == BREAK_NONE) {
                snprintf(msg, sizeof msg, "no break type: t sets one, or --break TYPE");
                break;
            }
            pos = find_step(s, pos, dir, type);
            if (pos == was)
                snprintf(msg, sizeof msg, "no %s %s event", dir > 0 ? "further" : "earlier", break_name(type));
            break;
        }
        default:
            break;
        }
    }
}
/* ---- --diff: two JSON Lines traces side by side ------------------------------- */

/* One trace line, read back into an event (sidx_event_from_json), with
 * the line kept for printing and the keys its JSON object holds. */
typedef struct diff_ev {
    sidx_event ev;
    char *line;     /* the line as read */
    char *store;    /* the event's strings and prims */
    uint32_t keys;  /* bit k: diff_keys[k] is in the line */
    size_t lineno;
} diff_ev;

typedef struct diff_trace {
    diff_ev *ev;
    size_t n, cap;
} diff_trace;

/* The fields compared, as the JSON names them ("structure" and "ray" name
 * the producer, not the step, and are left out). */
typedef enum { DK_ID, DK_I32, DK_FLOAT, DK_REASON, DK_CELL, DK_BOUNDS, DK_TEXT, DK_PRIMS, DK_TYPE } diff_kind;
typedef struct diff_key {
    const char *name;
    diff_kind kind;
    size_t off;
} diff_key;
#define DKEY(name, kind, field) {name, kind, offsetof(sidx_event, field)}
static const diff_key diff_keys[] = {
    DKEY("type", DK_TYPE, type),       DKEY("node", DK_ID, node),         DKEY("parent", DK_ID, parent),
    DKEY("depth", DK_ID, depth),       DKEY("prim", DK_ID, prim),         DKEY("count", DK_ID, count),
    DKEY("aux", DK_ID, aux),           DKEY("axis", DK_I32, axis),        DKEY("result", DK_I32, result),
    DKEY("reason", DK_REASON, reason), DKEY("cell", DK_CELL, cell),       DKEY("pos", DK_FLOAT, pos),
    DKEY("cost", DK_FLOAT, cost),      DKEY("t_near", DK_FLOAT, t_near), DKEY("t_far", DK_FLOAT, t_far),
    DKEY("t", DK_FLOAT, t),            DKEY("bounds", DK_BOUNDS, bounds), DKEY("text", DK_TEXT, text),
    DKEY("prims", DK_PRIMS, prims),
};
#define NDIFF_KEYS ((int)(sizeof diff_keys / sizeof diff_keys[0]))

/* Which of diff_keys the event's JSON holds: the writer decides, so the
 * diff compares exactly the fields the two lines carry. */
static uint32_t event_keys(const sidx_event *ev)
{
    char small[512];
    const int n = sidx_event_to_json(ev, small, sizeof small);
    char *json = n >= 0 && (size_t)n < sizeof small ? small : malloc(n > 0 ? (size_t)n + 1 : 1);
    if (!json) return 0;
    if (json != small) sidx_event_to_json(ev, json, (size_t)n + 1);
    uint32_t keys = 1u; /* type */
    for (int k = 1; k < NDIFF_KEYS; ++k) {
        char pat[32];
        snprintf(pat, sizeof pat, ",\"%s\":", diff_keys[k].name); /* a quote inside a string is escaped */
        if (strstr(json, pat)) keys |= 1u << k;
    }
    if (json != small) free(json);
    return keys;
}

static int read_trace(const char *path, diff_trace *t, int notes)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "sidx-step: cannot open %s: %s\n", path, strerror(errno));
        return -1;
    }
    char *line = NULL;
    size_t cap = 0, lineno = 0;
    ssize_t len;
    int rc = 0;
    while ((len = getline(&line, &cap, f)) >= 0) {
        ++lineno;
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = '\0';
        if (len == 0) continue;
        if (t->n == t->cap) {
            const size_t nc = t->cap ? 2 * t->cap : 256;
            diff_ev *ne = realloc(t->ev, nc * sizeof *ne);
            if (!ne) {
                rc = -1;
                break;
            }
            t->ev = ne;
            t->cap = nc;
        }
        diff_ev *e = &t->ev[t->n];
        const size_t store_size = 2 * (size_t)len + 16;
        e->line = strdup(line);
        e->store = malloc(store_size);
        e->lineno = lineno;
        sidx_error err = {SIDX_OK, "out of memory"};
        if (!e->line || !e->store ||
            sidx_event_from_json(line, &e->ev, e->store, store_size, NULL, &err) != SIDX_OK) {
            fprintf(stderr, "sidx-step: %s:%zu: not a sidx event: %s\n", path, lineno, err.message);
            free(e->line);
            free(e->store);
            rc = -1;
            break;
        }
        if (!notes && e->ev.type == SIDX_EV_NOTE) {
            free(e->line);
            free(e->store);
            continue;
        }
        e->keys = event_keys(&e->ev);
        ++t->n;
    }
    free(line);
    fclose(f);
    return rc;
}

static void free_trace(diff_trace *t)
{
    for (size_t i = 0; i < t->n; ++i) {
        free(t->ev[i].line);
        free(t->ev[i].store);
    }
    free(t->ev);
}

static int same_float(float x, float y, int exact)
{
    if (exact || isnan(x) || isnan(y) || isinf(x) || isinf(y))
        return (isnan(x) && isnan(y)) || (x == y && signbit(x) == signbit(y));
    const double m = fabs((double)x) > fabs((double)y) ? fabs((double)x) : fabs((double)y);
    return fabs((double)x - (double)y) <= 1e-5 * m + 1e-7;
}

static int same_field(const diff_key *k, const sidx_event *a, const sidx_event *b, int exact)
{
    const char *pa = (const char *)a + k->off, *pb = (const char *)b + k->off;
    switch (k->kind) {
    case DK_FLOAT: {
        float x, y;
        memcpy(&x, pa, sizeof x);
        memcpy(&y, pb, sizeof y);
        return same_float(x, y, exact);
    }
    case DK_BOUNDS:
        return same_float(a->bounds.min.x, b->bounds.min.x, exact) &&
               same_float(a->bounds.min.y, b->bounds.min.y, exact) &&
               same_float(a->bounds.min.z, b->bounds.min.z, exact) &&
               same_float(a->bounds.max.x, b->bounds.max.x, exact) &&
               same_float(a->bounds.max.y, b->bounds.max.y, exact) && same_float(a->bounds.max.z, b->bounds.max.z, exact);
    case DK_CELL: return !memcmp(a->cell, b->cell, sizeof a->cell);
    case DK_TEXT: return a->text && b->text ? !strcmp(a->text, b->text) : a->text == b->text;
    case DK_PRIMS:
        return a->count == b->count && (!a->count || !memcmp(a->prims, b->prims, a->count * sizeof *a->prims));
    case DK_TYPE: return a->type == b->type;
    default: return !memcmp(pa, pb, sizeof(uint32_t)); /* ids, axis, result, reason */
    }
}

/* A float as the JSON writer spells it: the shortest text that reads back. */
static void put_float(char *buf, size_t size, float f)
{
    if (isnan(f) || isinf(f)) {
        snprintf(buf, size, "%s", isnan(f) ? "\"nan\"" : f > 0 ? "\"inf\"" : "\"-inf\"");
        return;
    }
    for (int prec = 6; prec <= 9; ++prec) {
        snprintf(buf, size, "%.*g", prec, (double)f);
        if (strtof(buf, NULL) == f) break;
    }
}

static void field_text(const diff_key *k, const sidx_event *e, char *buf, size_t size)
{
    const char *p = (const char *)e + k->off;
    uint32_t u;
    int32_t i;
    float f;
    char x[6][32];
    switch (k->kind) {
    case DK_ID:
        memcpy(&u, p, sizeof u);
        if (u == UINT32_MAX) snprintf(buf, size, "null");
        else snprintf(buf, size, "%u", (unsigned)u);
        break;
    case DK_I32:
        memcpy(&i, p, sizeof i);
        snprintf(buf, size, "%d", (int)i);
        break;
    case DK_FLOAT:
        memcpy(&f, p, sizeof f);
        put_float(buf, size, f);
        break;
    case DK_REASON:
        snprintf(buf, size, "\"%s\"", e->type == SIDX_EV_BUILD_LEAF ? sidx_leaf_reason_name(e->reason)
                                                                     : sidx_term_reason_name(e->reason));
        break;
    case DK_CELL: snprintf(buf, size, "[%d,%d,%d]", (int)e->cell[0], (int)e->cell[1], (int)e->cell[2]); break;
    case DK_BOUNDS: {
        const float v[6] = {e->bounds.min.x, e->bounds.min.y, e->bounds.min.z,
                            e->bounds.max.x, e->bounds.max.y, e->bounds.max.z};
        for (int j = 0; j < 6; ++j) put_float(x[j], sizeof x[j], v[j]);
        snprintf(buf, size, "{\"min\":[%s,%s,%s],\"max\":[%s,%s,%s]}", x[0], x[1], x[2], x[3], x[4], x[5]);
        break;
    }
    case DK_TEXT: snprintf(buf, size, e->text ? "\"%s\"" : "null", e->text ? e->text : ""); break;
    case DK_PRIMS: snprintf(buf, size, "[%u ids]", (unsigned)e->count); break;
    case DK_TYPE: snprintf(buf, size, "\"%s\"", sidx_event_type_name(e->type)); break;
    }
}

/* The fields of a and b that differ, named as in the JSON; 0 if none. */
static int diff_fields(const diff_ev *a, const diff_ev *b, int exact, char *why, size_t size)
{
    int n = 0;
    size_t off = 0;
    why[0] = '\0';
    for (int k = 0; k < NDIFF_KEYS; ++k) {
        const uint32_t bit = 1u << k;
        const int in_a = (a->keys & bit) != 0, in_b = (b->keys & bit) != 0;
        if (!in_a && !in_b) continue;
        if (in_a && in_b && same_field(&diff_keys[k], &a->ev, &b->ev, exact)) continue;
        char va[256] = "absent", vb[256] = "absent";
        if (in_a) field_text(&diff_keys[k], &a->ev, va, sizeof va);
        if (in_b) field_text(&diff_keys[k], &b->ev, vb, sizeof vb);
        if (off < size)
            off += (size_t)snprintf(why + off, size - off, "%s%s: %s vs %s", n ? ", " : "", diff_keys[k].name, va, vb);
        ++n;
    }
    return n;
}

static int diff_main(int argc, char **argv)
{
    const char *pa = NULL, *pb = NULL;
    int exact = 0, notes = 0;
    for (int i = 2; i < argc; ++i) {
        if (!strcmp(argv[i], "--exact")) exact = 1;
        else if (!strcmp(argv[i], "--notes")) notes = 1;
        else if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "sidx-step: unknown option for --diff: %s\n", argv[i]);
            return 2;
        } else if (!pa) pa = argv[i];
        else if (!pb) pb = argv[i];
        else {
            fprintf(stderr, "sidx-step: --diff takes two files\n");
            return 2;
        }
    }
    if (!pa || !pb) {
        fprintf(stderr, "sidx-step: --diff wants two JSON Lines files: sidx-step --diff A.jsonl B.jsonl\n");
        return 2;
    }
    diff_trace a = {0}, b = {0};
    int rc = 2;
    if (read_trace(pa, &a, notes) != 0 || read_trace(pb, &b, notes) != 0) goto out;
    size_t i = 0;
    char why[1024];
    while (i < a.n && i < b.n && diff_fields(&a.ev[i], &b.ev[i], exact, why, sizeof why) == 0) ++i;
    if (i == a.n && i == b.n) {
        printf("the traces agree: %zu events\n", a.n);
        rc = 0;
    } else {
        printf("the traces part at event %zu", i + 1);
        if (i < a.n && i < b.n) printf(" (%s line %zu, %s line %zu)", pa, a.ev[i].lineno, pb, b.ev[i].lineno);
        printf("\n");
        for (size_t k = i > 3 ? i - 3 : 0; k < i; ++k) printf("  same  %s\n", a.ev[k].line);
        printf("  A     %s\n", i < a.n ? a.ev[i].line : "(the trace ends here)");
        printf("  B     %s\n", i < b.n ? b.ev[i].line : "(the trace ends here)");
        if (i < a.n && i < b.n) printf("  differ: %s\n", why);
        rc = 1;
    }
    /* events of each type on both sides, in the order types first appear */
    int types[SIDX_EV_COUNT];
    size_t ca[SIDX_EV_COUNT] = {0}, cb[SIDX_EV_COUNT] = {0}, nt = 0;
    for (int side = 0; side < 2; ++side) {
        const diff_trace *t = side ? &b : &a;
        for (size_t k = 0; k < t->n; ++k) {
            const int ty = (int)t->ev[k].ev.type;
            size_t j = 0;
            while (j < nt && types[j] != ty) ++j;
            if (j == nt) {
                types[nt] = ty;
                ca[nt] = cb[nt] = 0;
                ++nt;
            }
            ++*(side ? &cb[j] : &ca[j]);
        }
    }
    printf("%-20s %8s %8s\n", "events", "A", "B");
    for (size_t j = 0; j < nt; ++j)
        printf("  %-18s %8zu %8zu%s\n", sidx_event_type_name((sidx_event_type)types[j]), ca[j], cb[j],
               ca[j] != cb[j] ? "  *" : "");
    printf("  %-18s %8zu %8zu\n", "total", a.n, b.n);
out:
    free_trace(&a);
    free_trace(&b);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "--diff")) return diff_main(argc, argv);
    int all = 0, json = 0, build = 0, bounds = 0, panel = 0, brk = BREAK_NONE;
    unsigned long long start = 0;
    sidx_traversal trav = SIDX_TRAVERSE_DEFAULT;
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    viz_args args = {.prog = "sidx-step", .usage = usage, .build = &bo, .scene_operand = 1};
    for (int i = 1; i < argc; ++i) {
        const int took = viz_arg(&args, argc, argv, &i);
        if (took == VIZ_ARG_TAKEN) continue;
        if (took != VIZ_ARG_OWN) return took;
        const char *a = argv[i];
        const int has_val = i + 1 < argc;
        if (!strcmp(a, "--all")) {
            all = 1;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--build")) {
            build = 1;
        } else if (!strcmp(a, "--bounds")) {
            bounds = 1;
        } else if (!strcmp(a, "--panel")) {
            panel = 1;
        } else if (!strcmp(a, "--traversal") && has_val) {
            if (sidx_traversal_parse(argv[++i], &trav) != SIDX_OK) {
                fprintf(stderr, "sidx-step: --traversal wants default, stack, ordered or naive, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--step") && has_val) {
            char *end;
            const char *v = argv[++i];
            start = v[0] >= '0' && v[0] <= '9' ? strtoull(v, &end, 10) : 0;
            if (!start || *end) {
                fprintf(stderr, "sidx-step: --step wants a step number >= 1, not '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--break") && has_val) {
            brk = parse_break(argv[++i]);
            if (brk == BREAK_NONE) {
                fprintf(stderr,
                        "sidx-step: --break wants an event type (stack_push, push, pop, enter, box, prim, hit, "
                        "mailbox, terminate, leaf, ...), not '%s'\n",
                        argv[i]);
                return 2;
            }
        } else {
            return viz_arg_unknown(&args, a);
        }
    }
    const char *accel = args.accel, *scene = args.scene, *ray_text = args.ray_text;
    const int has_ray = ray_text != NULL;
    const sidx_vec3 org = args.org, dir = args.dir;
    if (!accel || !scene || (!has_ray && !build)) {
        fprintf(stderr, "sidx-step: --accel, SCENE and --ray (or --build) are required\n");
        usage(stderr);
        return 2;
    }
    const int bad_accel = viz_arg_check_accel(&args);
    if (bad_accel) return bad_accel;

    sidx_mesh mesh;
    sidx_error err;
    memset(&mesh, 0, sizeof mesh);
    if (sidx_scene_open(scene, &mesh, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-step: %s\n", err.message);
        return 1;
    }
    sidx_recorder brec, trec;
    sidx_recorder_init(&brec);
    sidx_recorder_init(&trec);
    /* the build's leaves are always recorded: "next leaf" and the panel's "leaf" */
    sidx_hook bh = sidx_recorder_hook(&brec);
    bh.mask = build ? SIDX_EVMASK_BUILD | SIDX_EVMASK(SIDX_EV_NOTE) : SIDX_EVMASK(SIDX_EV_BUILD_LEAF);
    bo.hook = &bh;
    sidx_accel *acc = NULL;
    steps s;
    memset(&s, 0, sizeof s);
    int rc = 0;
    /* the scene's own tree where it has one (kd-slide: the slide's, labelled) */
    if (sidx_scene_accel_build(scene, accel, &mesh, &bo, &acc, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-step: building %s: %s\n", accel, err.message);
        rc = 1;
        goto done;
    }
    if (has_ray) {
        sidx_ray ray;
        if (sidx_ray_init(&ray, org, dir, 0.0f, INFINITY) != SIDX_OK) {
            fprintf(stderr, "sidx-step: invalid ray\n");
            rc = 2;
            goto done;
        }
        sidx_hook th = sidx_recorder_hook(&trec);
        /* a lazy tree builds the subtrees the ray enters: build_lazy_expand
         * and the subtree's build events arrive among the ray's */
        th.mask = SIDX_EVMASK_TRAVERSAL | (bo.lazy ? SIDX_EVMASK_BUILD : 0u);
        sidx_query q;
        memset(&q, 0, sizeof q);
        q.traversal = trav;
        q.hook = &th;
        sidx_hit hit;
        sidx_accel_intersect(acc, &ray, &q, &hit);
    }
    s.nbuild = build ? brec.count : 0;
    s.n = s.nbuild + trec.count;
    s.ev = malloc((s.n ? s.n : 1) * sizeof *s.ev);
    s.leaves = malloc((brec.count + trec.count ? brec.count + trec.count : 1) * sizeof *s.leaves);
    if (brec.overflow || trec.overflow || !s.ev || !s.leaves) {
        fprintf(stderr, "sidx-step: out of memory recording the events\n");
        rc = 1;
        goto done;
    }
    for (size_t i = 0; i < brec.count; ++i) {
        if (i < s.nbuild) s.ev[i] = &brec.events[i];
        if (brec.events[i].type == SIDX_EV_BUILD_LEAF) s.leaves[s.nleaves++] = brec.events[i].node;
    }
    for (size_t i = 0; i < trec.count; ++i) /* leaves a lazy tree built for the ray */
        if (trec.events[i].type == SIDX_EV_BUILD_LEAF) s.leaves[s.nleaves++] = trec.events[i].node;
    qsort(s.leaves, s.nleaves, sizeof *s.leaves, cmp_u32);
    for (size_t i = 0; i < trec.count; ++i) s.ev[s.nbuild + i] = &trec.events[i];
    s.json = json;
    s.bounds = bounds;
    s.panel = panel;
    s.accel = acc;
    s.columns = panel && !json && has_panel(&s);
    if (s.n == 0) goto done;
    for (size_t i = s.nbuild; i < s.n; ++i) {
        char buf[512], *line = step_text(&s, i, buf, sizeof buf);
        if ((int)strlen(line) > s.width) s.width = (int)strlen(line);
        text_free(line, buf);
    }

    /* where to stop: --step K, then the first --break event from there */
    size_t pos = start ? (start <= s.n ? (size_t)start - 1 : s.n - 1) : 0;
    if (brk != BREAK_NONE && !step_is(&s, pos, brk)) {
        const size_t at = find_step(&s, pos, 1, brk);
        if (at == pos) {
            fprintf(stderr, "sidx-step: no %s event from step %zu on\n", break_name(brk), pos + 1);
            rc = 1;
        }
        pos = at == pos ? s.n - 1 : at;
    }
    if (!all && isatty(STDIN_FILENO) && isatty(STDOUT_FILENO) && tty_enter_raw() == 0) {
        char title[256];
        snprintf(title, sizeof title, "sidx-step  %s  %s%s%s", accel, scene, ray_text ? "  ray " : "",
                 ray_text ? ray_text : "");
        run_stepper(&s, pos, brk, title);
        tty_restore();
        rc = 0;
    } else {
        print_steps(&s, start || brk != BREAK_NONE ? pos + 1 : s.n);
    }
    if (fflush(stdout) != 0 || ferror(stdout)) rc = 1;
done:
    free(s.ev);
    free(s.leaves);
    sidx_accel_destroy(acc);
    sidx_recorder_free(&brec);
    sidx_recorder_free(&trec);
    sidx_mesh_free(&mesh);
    return rc;
}
