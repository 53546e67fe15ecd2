/* borrowed.h — no borrowed answers: what a student's object may call.
 *
 * Decided on the compiled object, not on its source text: its ELF symbol
 * table (what nm -P lists; read in process, nm only if NM is set or the
 * object is not ELF) names every symbol the object calls or takes the
 * address of (a call through a macro, inline assembly, a weak declaration
 * all name it), and every global it defines.  symbols.def lists per exercise what of the library the
 * student's code may call and the library's own versions of what the
 * exercise asks it to write. */
#ifndef SIDX_CK_BORROWED_H
#define SIDX_CK_BORROWED_H

#include <stddef.h>
#include <stdio.h>

/* The exercise's lists (symbols.def): words separated by blanks. */
typedef struct ck_symbols {
    const char *name, *may_call, *writes;
} ck_symbols;
/* The lists of exercise NAME, or NULL if symbols.def has none. */
const ck_symbols *ck_symbols_of(const char *name);

/* Reads the symbols of OBJ (the student's object, compiled for exercise
 * NAME) and writes to out one line per symbol it may not use or define
 * ("uses sidx_intersect_triangle, which this exercise asks you to
 * write"), the first of them also to first (size bytes; "" if none).
 * Returns the number of such symbols, or -1 if nm could not be run (the
 * message on stderr). */
int ck_borrowed(const char *name, const char *obj, FILE *out, char *first, size_t size);

#endif
