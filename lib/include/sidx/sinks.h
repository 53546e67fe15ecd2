/* sidx/sinks.h — ready-made hooks: printer, JSON Lines, recorder, counters, tee.
 *
 * Each sink is a small struct you own; sidx_*_hook() returns the sidx_hook
 * to pass to a build or query.  None allocates except the recorder. */
#ifndef SIDX_SINKS_H
#define SIDX_SINKS_H

#include <stdio.h>
#include "hook.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Human-readable, one line per event, indented by depth — the way the
 * lessons print:  "  node 3 [d=2] t=[0.50, 1.25]". */
typedef struct sidx_printer {
    FILE *out;
    uint32_t mask;      /* which events to print; 0 = all */
    int show_bounds;    /* also print node boxes */
    uint64_t lines;     /* lines printed so far */
} sidx_printer;
void sidx_printer_init(sidx_printer *p, FILE *out);
sidx_hook sidx_printer_hook(sidx_printer *p);
/* Formats one event as the printer would (no newline); returns snprintf's count. */
int sidx_event_format(const sidx_event *ev, char *buf, size_t size);

/* JSON Lines: one object per event with the fields named as in sidx_event
 * ("type", "structure", "ray", "node", ...); fields that do not apply to
 * the event type are omitted.  docs/events.md lists them. */
typedef struct sidx_jsonl {
    FILE *out;
    uint64_t lines;
} sidx_jsonl;
void sidx_jsonl_init(sidx_jsonl *j, FILE *out);
sidx_hook sidx_jsonl_hook(sidx_jsonl *j);
int sidx_event_to_json(const sidx_event *ev, char *buf, size_t size);
/* The inverse of sidx_event_to_json: reads one JSON Lines line (a trailing
 * newline is allowed) back into *ev, so that writing *ev again gives the
 * same object.  Fields the type does not carry are blank (sidx_event_blank).
 * The line must hold exactly the keys sidx_event_to_json writes for the
 * event it describes, in any order; floats are JSON numbers within float
 * range or "inf", "-inf", "nan"; ids fit in 32 bits.
 * The strings (structure, text) and a build_leaf's prims list are copied
 * into store (store_size bytes) and *ev points into it, so ev stays valid
 * while store does; 2 * strlen(line) + 16 bytes always suffice.  If
 * store_used is not NULL it receives the bytes taken.
 * Returns SIDX_OK; SIDX_ERR_PARSE for a line that is not such an event
 * (err->message names the column and what is wrong: bad JSON, an unknown
 * event type or reason, a missing, extra or repeated field, a value of
 * the wrong type or out of range); SIDX_ERR_LIMIT when store is too small;
 * SIDX_ERR_INVALID_ARG for a NULL line or ev.  *ev is untouched on error. */
sidx_status sidx_event_from_json(const char *line, sidx_event *ev, char *store, size_t store_size, size_t *store_used,
                                 sidx_error *err);

/* Keeps every event in memory, for stepping forward and back.  If an
 * allocation fails the recorder stops recording and sets overflow.  A
 * BUILD_LEAF's prims list is copied into memory the recorder owns, so the
 * recorded events' prims stay valid until clear or free. */
typedef struct sidx_recorder {
    sidx_event *events;
    size_t count, capacity;
    size_t limit;       /* stop after this many events; 0 = no limit */
    int overflow;       /* 1 if events were dropped (limit or out of memory) */
    void *prim_store;   /* internal: the copied prims lists (chunks that never move) */
} sidx_recorder;
void sidx_recorder_init(sidx_recorder *r);
void sidx_recorder_clear(sidx_recorder *r);   /* forget events (and their prims lists), keep the event array */
void sidx_recorder_free(sidx_recorder *r);
sidx_hook sidx_recorder_hook(sidx_recorder *r);

/* Counts events of each type (and primitive-test hits). */
typedef struct sidx_counters {
    uint64_t n[SIDX_EV_COUNT];
    uint64_t prim_hits;   /* PRIM_TEST events with result 1 */
    uint64_t box_hits;    /* BOX_TEST events with result 1 */
    uint64_t rays;        /* RAY_BEGIN events */
} sidx_counters;
void sidx_counters_init(sidx_counters *c);
sidx_hook sidx_counters_hook(sidx_counters *c);
/* Prints "event: count" lines for the non-zero counters. */
void sidx_counters_print(const sidx_counters *c, FILE *out);

/* Forwards every event to up to 4 hooks. */
typedef struct sidx_tee { sidx_hook hooks[4]; int n; } sidx_tee;
sidx_hook sidx_tee_hook(sidx_tee *t);

#ifdef __cplusplus
}
#endif
#endif
