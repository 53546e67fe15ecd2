/* sidx/status.h — errors are values.
 *
 * Every fallible sidx function returns an sidx_status.  Functions that can say
 * more (which file, which line, which triangle) also take an optional
 * sidx_error* that receives a human-readable message; pass NULL if you do not
 * want it.  No global error state exists, so this is thread safe. */
#ifndef SIDX_STATUS_H
#define SIDX_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sidx_status {
    SIDX_OK = 0,
    SIDX_ERR_INVALID_ARG,   /* NULL pointer, zero direction, bad option value */
    SIDX_ERR_NOMEM,         /* an allocation failed; nothing leaked, outputs untouched */
    SIDX_ERR_IO,            /* a file could not be opened, read or written */
    SIDX_ERR_PARSE,         /* a file is malformed (message names file and line) */
    SIDX_ERR_BAD_GEOMETRY,  /* NaN/Inf coordinates, index out of range */
    SIDX_ERR_UNKNOWN_ACCEL, /* no structure registered under that name */
    SIDX_ERR_LIMIT,         /* input exceeds what the structure can address */
    SIDX_ERR_UNSUPPORTED,   /* the structure does not implement this operation */
    SIDX_STATUS_COUNT
} sidx_status;

/* A short, static, English description of a status ("out of memory"). Never NULL. */
const char *sidx_status_str(sidx_status s);

/* Optional detail for a failed call. */
typedef struct sidx_error {
    sidx_status status;
    char message[256];
} sidx_error;

#ifdef __cplusplus
}
#endif
#endif
