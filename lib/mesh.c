/* mesh.c — the mesh container, its checks, and the OBJ and PLY loaders.
 *
 * Both loaders work on a byte buffer of known size (the file is read whole
 * first), never past its end and never assuming a terminating NUL, because
 * the parse_* entry points are fuzzed with arbitrary bytes.  They build
 * into local growable arrays and hand them to *out only on success, so a
 * failed call leaves *out exactly as it was.
 *
 * Numbers are converted with strtof/strtod on a NUL-terminated copy of the
 * token: those are correctly rounded (a saved float reloads bit-identical),
 * and fast enough for the 70k-triangle test meshes.  They honour
 * LC_NUMERIC, which is "C" unless the program calls setlocale. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sidx_internal.h"

/* ---- the mesh container ------------------------------------------------ */

void sidx_mesh_free(sidx_mesh *m)
{
    if (!m) return;
    free(m->positions);
    free(m->indices);
    memset(m, 0, sizeof *m);
}

sidx_status sidx_mesh_validate(const sidx_mesh *m, sidx_error *err)
{
    if (!m) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "mesh is NULL");
    if ((m->num_vertices && !m->positions) || (m->num_triangles && !m->indices))
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "mesh has counts but NULL arrays");
    /* 3·tri + k must fit the 32-bit index arithmetic (sidx_mesh_vertex) */
    if (m->num_triangles > UINT32_MAX / 3u)
        return sidx__fail(err, SIDX_ERR_LIMIT, "%u triangles: more than 32-bit indices address (%u)",
                          (unsigned)m->num_triangles, (unsigned)(UINT32_MAX / 3u));
    for (uint32_t i = 0; i < m->num_vertices; ++i) {
        const sidx_vec3 p = m->positions[i];
        if (!sidx_v3_isfinite(p))
            return sidx__fail(err, SIDX_ERR_BAD_GEOMETRY, "vertex %u has a non-finite coordinate (%g, %g, %g)",
                              (unsigned)i, (double)p.x, (double)p.y, (double)p.z);
    }
    const size_t n = 3u * (size_t)m->num_triangles;
    for (size_t i = 0; i < n; ++i) {
        if (m->indices[i] >= m->num_vertices)
            return sidx__fail(err, SIDX_ERR_BAD_GEOMETRY, "triangle %zu: vertex index %u out of range (%u vertices)",
                              i / 3, (unsigned)m->indices[i], (unsigned)m->num_vertices);
    }
    return SIDX_OK;
}

sidx_status sidx_mesh_from_arrays(sidx_mesh *out, const float *xyz, uint32_t num_vertices, const uint32_t *indices,
                                  uint32_t num_triangles, sidx_error *err)
{
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "out is NULL");
    if ((num_vertices && !xyz) || (num_triangles && !indices))
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "counts given with NULL arrays");
    if (num_triangles > UINT32_MAX / 3u)
        return sidx__fail(err, SIDX_ERR_LIMIT, "%u triangles: more than 32-bit indices address (%u)",
                          (unsigned)num_triangles, (unsigned)(UINT32_MAX / 3u));
    /* Only a 32-bit size_t can overflow here. */
    if ((uint64_t)num_triangles * 3u * sizeof(uint32_t) > (uint64_t)SIZE_MAX ||
        (uint64_t)num_vertices * sizeof(sidx_vec3) > (uint64_t)SIZE_MAX)
        return sidx__fail(err, SIDX_ERR_LIMIT, "mesh too large for this address space");

    sidx_mesh m;
    /* malloc(0) may return NULL; allocate at least one element so NULL
     * always means failure. */
    m.positions = malloc(num_vertices ? num_vertices * sizeof(sidx_vec3) : 1);
    m.indices = malloc(num_triangles ? 3u * (size_t)num_triangles * sizeof(uint32_t) : 1);
    m.num_vertices = num_vertices;
    m.num_triangles = num_triangles;
    if (!m.positions || !m.indices) {
        free(m.positions);
        free(m.indices);
        return sidx__fail(err, SIDX_ERR_NOMEM, "out of memory copying a mesh of %u vertices, %u triangles",
                          (unsigned)num_vertices, (unsigned)num_triangles);
    }
    for (uint32_t i = 0; i < num_vertices; ++i)
        m.positions[i] = sidx_v3(xyz[3u * (size_t)i], xyz[3u * (size_t)i + 1], xyz[3u * (size_t)i + 2]);
    if (num_triangles) memcpy(m.indices, indices, 3u * (size_t)num_triangles * sizeof(uint32_t));

    sidx_status s = sidx_mesh_validate(&m, err);
    if (s != SIDX_OK) {
        sidx_mesh_free(&m);
        return s;
    }
    *out = m;
    return SIDX_OK;
}

sidx_aabb sidx_mesh_bounds(const sidx_mesh *m)
{
    /* Over the vertices triangles use: scanned meshes (the bunny) carry
     * unused vertices, and a structure's root box should not include them. */
    sidx_aabb b = sidx_aabb_empty();
    if (!m) return b;
    const size_t n = 3u * (size_t)m->num_triangles;
    for (size_t i = 0; i < n; ++i) b = sidx_aabb_grow(b, m->positions[m->indices[i]]);
    return b;
}

sidx_aabb sidx_mesh_triangle_bounds(const sidx_mesh *m, uint32_t tri)
{
    sidx_aabb b = sidx_aabb_empty();
    if (!m || tri >= m->num_triangles) return b;
    for (int k = 0; k < 3; ++k) b = sidx_aabb_grow(b, sidx_mesh_vertex(m, tri, k));
    return b;
}

sidx_status sidx_mesh_save_obj(const sidx_mesh *m, const char *path, sidx_error *err)
{
    if (!m || !path) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "mesh or path is NULL");
    FILE *f = fopen(path, "w");
    if (!f) return sidx__fail(err, SIDX_ERR_IO, "%s: %s", path, strerror(errno));
    int bad = fprintf(f, "# sidx mesh: %u vertices, %u triangles\n", (unsigned)m->num_vertices,
                      (unsigned)m->num_triangles) < 0;
    /* %.9g: nine significant digits always round-trip a float exactly. */
    for (uint32_t i = 0; i < m->num_vertices && !bad; ++i) {
        const sidx_vec3 p = m->positions[i];
        bad = fprintf(f, "v %.9g %.9g %.9g\n", (double)p.x, (double)p.y, (double)p.z) < 0;
    }
    for (uint32_t t = 0; t < m->num_triangles && !bad; ++t) {
        const uint32_t *ix = m->indices + 3u * (size_t)t;
        bad = fprintf(f, "f %lu %lu %lu\n", (unsigned long)ix[0] + 1, (unsigned long)ix[1] + 1,
                      (unsigned long)ix[2] + 1) < 0;
    }
    int saved_errno = errno;
    if (fclose(f) != 0 && !bad) {
        bad = 1;
        saved_errno = errno;
    }
    if (bad) {
        remove(path); /* a half-written mesh is worse than none */
        return sidx__fail(err, SIDX_ERR_IO, "%s: write failed: %s", path, strerror(saved_errno));
    }
    return SIDX_OK;
}

/* ---- growable arrays shared by the loaders ----------------------------- */

typedef struct {
    sidx_vec3 *pos;
    size_t nv, cap_v;
    uint32_t *idx; /* 3 per triangle */
    size_t nt, cap_t;
} mesh_buf;

static void buf_free(mesh_buf *b)
{
    free(b->pos);
    free(b->idx);
    memset(b, 0, sizeof *b);
}

/* Makes room for `need` elements of `size` bytes; 0 on overflow/failure
 * (then *p and *cap are unchanged). */
static int grow_to(void **p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return 1;
    size_t n = *cap ? *cap : 256;
    while (n < need) {
        if (n > SIZE_MAX / 2) return 0;
        n *= 2;
    }
    if (n > SIZE_MAX / size) return 0;
    void *q = realloc(*p, n * size);
    if (!q) return 0;
    *p = q;
    *cap = n;
    return 1;
}

static int buf_push_vertex(mesh_buf *b, sidx_vec3 v)
{
    if (b->nv == b->cap_v && !grow_to((void **)&b->pos, &b->cap_v, b->nv + 1, sizeof *b->pos)) return 0;
    b->pos[b->nv++] = v;
    return 1;
}

static int buf_push_tri(mesh_buf *b, uint32_t i0, uint32_t i1, uint32_t i2)
{
    if (b->nt == b->cap_t && !grow_to((void **)&b->idx, &b->cap_t, b->nt + 1, 3 * sizeof *b->idx)) return 0;
    uint32_t *t = b->idx + 3 * b->nt++;
    t[0] = i0;
    t[1] = i1;
    t[2] = i2;
    return 1;
}

/* Moves the arrays into *out (never NULL arrays, even when empty). */
static sidx_status buf_finish(mesh_buf *b, sidx_mesh *out, const char *name, sidx_error *err)
{
    if (!b->pos && !grow_to((void **)&b->pos, &b->cap_v, 1, sizeof *b->pos)) goto nomem;
    if (!b->idx && !grow_to((void **)&b->idx, &b->cap_t, 1, 3 * sizeof *b->idx)) goto nomem;
    out->positions = b->pos;
    out->indices = b->idx;
    out->num_vertices = (uint32_t)b->nv;
    out->num_triangles = (uint32_t)b->nt;
    memset(b, 0, sizeof *b);
    return SIDX_OK;
nomem:
    buf_free(b);
    return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory", name);
}

/* ---- tokens and numbers ------------------------------------------------- */

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* Longest number token accepted; real files stay far below. */
#define MAX_NUMBER_CHARS 127

/* Parses the whole token [s, s+n) as a float.  0 if it is not a number. */
static int parse_float(const char *s, size_t n, float *out)
{
    char tmp[MAX_NUMBER_CHARS + 1];
    if (n == 0 || n > MAX_NUMBER_CHARS) return 0;
    memcpy(tmp, s, n);
    tmp[n] = '\0';
    /* strtof skips leading space and stops at an embedded NUL: both would
     * make end != tmp + n, so both are rejected. */
    char *end;
    *out = strtof(tmp, &end);
    return end == tmp + n;
}

static int parse_double(const char *s, size_t n, double *out)
{
    char tmp[MAX_NUMBER_CHARS + 1];
    if (n == 0 || n > MAX_NUMBER_CHARS) return 0;
    memcpy(tmp, s, n);
    tmp[n] = '\0';
    char *end;
    *out = strtod(tmp, &end);
    return end == tmp + n;
}

/* Decimal integer with optional sign at *p (not past e).  Saturates at
 * ±2^62 so that huge values still read as "out of range", not as garbage.
 * Returns 0 when there is no digit. */
#define INT_SATURATE ((int64_t)1 << 62)
static int scan_int(const char **p, const char *e, int64_t *out)
{
    const char *s = *p;
    int neg = 0;
    if (s < e && (*s == '-' || *s == '+')) neg = *s++ == '-';
    if (s == e || *s < '0' || *s > '9') return 0;
    int64_t v = 0;
    while (s < e && *s >= '0' && *s <= '9') {
        v = v <= (INT_SATURATE - 9) / 10 ? v * 10 + (*s - '0') : INT_SATURATE;
        ++s;
    }
    *out = neg ? -v : v;
    *p = s;
    return 1;
}

/* ---- Wavefront OBJ ------------------------------------------------------- */

/* Next whitespace-separated token of the line [*p, e); a '#' starts a
 * comment that runs to the end of the line. */
static int obj_token(const char **p, const char *e, const char **tok, size_t *len)
{
    const char *s = *p;
    while (s < e && is_blank(*s)) ++s;
    if (s == e || *s == '#') {
        *p = e;
        return 0;
    }
    const char *t = s;
    while (s < e && !is_blank(*s) && *s != '#') ++s;
    *tok = t;
    *len = (size_t)(s - t);
    *p = s;
    return 1;
}

typedef struct {
    const char *name;
    size_t line;
    sidx_error *err;
    /* Positive indices may point forward (some exporters write faces
     * first), so their range is checked once all vertices are known; the
     * largest one and its line are remembered for the message. */
    int64_t max_index;
    size_t max_index_line;
} obj_ctx;

/* Shown tokens are cut short so a huge garbage token cannot flood the message. */
#define TOK_SHOWN 24

static sidx_status obj_vertex(obj_ctx *c, mesh_buf *b, const char *p, const char *e)
{
    float xyz[3];
    int n = 0;
    const char *tok;
    size_t len;
    while (obj_token(&p, e, &tok, &len)) {
        float v;
        if (!parse_float(tok, len, &v))
            return sidx__fail(c->err, SIDX_ERR_PARSE, "%s:%zu: malformed number '%.*s'", c->name, c->line,
                              (int)(len < TOK_SHOWN ? len : TOK_SHOWN), tok);
        /* x y z, then w (or the r g b [a] colour extension), ignored */
        if (n < 3) xyz[n] = v;
        if (++n > 7)
            return sidx__fail(c->err, SIDX_ERR_PARSE, "%s:%zu: too many numbers in a 'v' statement", c->name,
                              c->line);
    }
    if (n < 3)
        return sidx__fail(c->err, SIDX_ERR_PARSE, "%s:%zu: 'v' needs 3 coordinates, got %d", c->name, c->line, n);
    sidx_vec3 v = sidx_v3(xyz[0], xyz[1], xyz[2]);
    if (!sidx_v3_isfinite(v))
        return sidx__fail(c->err, SIDX_ERR_BAD_GEOMETRY, "%s:%zu: vertex %zu has a non-finite coordinate", c->name,
                          c->line, b->nv + 1);
    if (b->nv >= UINT32_MAX)
        return sidx__fail(c->err, SIDX_ERR_LIMIT, "%s:%zu: more than %lu vertices", c->name, c->line,
                          (unsigned long)UINT32_MAX);
    if (!buf_push_vertex(b, v)) return sidx__fail(c->err, SIDX_ERR_NOMEM, "%s:%zu: out of memory", c->name, c->line);
    return SIDX_OK;
}

/* One face corner "i", "i/t", "i//n" or "i/t/n": returns the 0-based
 * position index (provisional for forward references). */
static sidx_status obj_corner(obj_ctx *c, size_t nv, const char *tok, size_t len, uint32_t *out)
{
    const char *p = tok, *e = tok + len;
    int64_t i, unused;
    int ok = scan_int(&p, e, &i);
    if (ok && p < e) {                                   /* "/t", "/t/n" or "//n" */
        ok = *p++ == '/';
        if (ok && p < e && *p != '/') ok = scan_int(&p, e, &unused);
        if (ok && p < e) ok = *p++ == '/' && scan_int(&p, e, &unused) && p == e;
        else if (ok && p == e && p[-1] == '/') ok = 0;   /* "i/" */
    }
    if (!ok)
        return sidx__fail(c->err, SIDX_ERR_PARSE, "%s:%zu: malformed face vertex '%.*s'", c->name, c->line,
                          (int)(len < TOK_SHOWN ? len : TOK_SHOWN), tok);
    if (i == 0)
        return sidx__fail(c->err, SIDX_ERR_PARSE, "%s:%zu: vertex index 0 (OBJ indices start at 1)", c->name,
                          c->line);
    if (i < 0) {
        /* -1 is the latest vertex: resolve against the count so far. */
        if (-i > (int64_t)nv)
            return sidx__fail(c->err, SIDX_ERR_BAD_GEOMETRY,
                              "%s:%zu: relative vertex index %lld out of range (%zu vertices so far)", c->name,
                              c->line, (long long)i, nv);
        *out = (uint32_t)((int64_t)nv + i);
        return SIDX_OK;
    }
    if (i > c->max_index) {
        c->max_index = i;
        c->max_index_line = c->line;
    }
    *out = i - 1 < (int64_t)UINT32_MAX ? (uint32_t)(i - 1) : UINT32_MAX;
    return SIDX_OK;
}

static sidx_status obj_face(obj_ctx *c, mesh_buf *b, const char *p, const char *e)
{
    uint32_t first = 0, prev = 0;
    size_t n = 0;
    const char *tok;
    size_t len;
    while (obj_token(&p, e, &tok, &len)) {
        uint32_t v = 0;
        sidx_status s = obj_corner(c, b->nv, tok, len, &v);
        if (s != SIDX_OK) return s;
        if (n == 0) first = v;
        else if (n >= 2) { /* fan: (v0, v1, v2), (v0, v2, v3), ... */
            if (b->nt >= UINT32_MAX)
                return sidx__fail(c->err, SIDX_ERR_LIMIT, "%s:%zu: more than %lu triangles", c->name, c->line,
                                  (unsigned long)UINT32_MAX);
            if (!buf_push_tri(b, first, prev, v))
                return sidx__fail(c->err, SIDX_ERR_NOMEM, "%s:%zu: out of memory", c->name, c->line);
        }
        prev = v;
        ++n;
    }
    if (n < 3)
        return sidx__fail(c->err, SIDX_ERR_PARSE, "%s:%zu: face with %zu vertices (needs at least 3)", c->name,
                          c->line, n);
    return SIDX_OK;
}

sidx_status sidx_mesh_parse_obj(const char *data, size_t size, const char *name, sidx_mesh *out, sidx_error *err)
{
    if (!name) name = "<memory>";
    if (!out || (!data && size)) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: out or data is NULL", name);
    obj_ctx c = {name, 0, err, 0, 0};
    mesh_buf b = {0};
    sidx_status s = SIDX_OK;
    const char *p = data, *end = size ? data + size : data; /* NULL + 0 is undefined */
    while (p < end && s == SIDX_OK) {
        ++c.line;
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        if (!eol) eol = end;
        const char *q = p, *kw;
        size_t kwlen;
        if (obj_token(&q, eol, &kw, &kwlen) && kwlen == 1) {
            if (kw[0] == 'v') s = obj_vertex(&c, &b, q, eol);
            else if (kw[0] == 'f') s = obj_face(&c, &b, q, eol);
        }
        /* Everything else (vt vn vp o g s usemtl mtllib l p, curves...)
         * carries nothing a triangle index needs. */
        p = eol < end ? eol + 1 : end;
    }
    if (s == SIDX_OK && c.max_index > (int64_t)b.nv)
        s = sidx__fail(err, SIDX_ERR_BAD_GEOMETRY, "%s:%zu: vertex index %lld out of range (%zu vertices)", name,
                       c.max_index_line, (long long)c.max_index, b.nv);
    if (s != SIDX_OK) {
        buf_free(&b);
        return s;
    }
    return buf_finish(&b, out, name, err);
}

/* ---- PLY ------------------------------------------------------------------ */

enum ply_type { T_NONE, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 };
static const size_t ply_type_size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};

enum ply_role { R_OTHER, R_X, R_Y, R_Z, R_INDICES };
enum ply_kind { K_OTHER, K_VERTEX, K_FACE };

typedef struct {
    enum ply_type type;       /* scalar type, or list item type */
    enum ply_type count_type; /* T_NONE for a scalar property */
    enum ply_role role;
} ply_prop;

/* Fixed limits keep the header parser allocation-free; real files use a
 * handful of each. */
#define PLY_MAX_ELEMENTS 16
#define PLY_MAX_PROPS 64

typedef struct {
    uint64_t count;
    enum ply_kind kind;
    ply_prop props[PLY_MAX_PROPS];
    int nprops;
    char name[32];
} ply_element;

enum ply_format { F_ASCII, F_LE, F_BE };

typedef struct {
    const char *name;
    sidx_error *err;
    const unsigned char *data, *p, *end;
    enum ply_format format;
    size_t line;      /* ascii: current line (1-based) */
    ply_element el[PLY_MAX_ELEMENTS];
    int nel;
    uint64_t nv;      /* vertices declared */
} ply_ctx;

static enum ply_type ply_type_named(const char *s, size_t n)
{
    static const struct { const char *name; enum ply_type t; } names[] = {
        {"char", T_I8},     {"int8", T_I8},   {"uchar", T_U8},    {"uint8", T_U8},    {"short", T_I16},
        {"int16", T_I16},   {"ushort", T_U16}, {"uint16", T_U16}, {"int", T_I32},     {"int32", T_I32},
        {"uint", T_U32},    {"uint32", T_U32}, {"float", T_F32},  {"float32", T_F32}, {"double", T_F64},
        {"float64", T_F64},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        if (strlen(names[i].name) == n && memcmp(names[i].name, s, n) == 0) return names[i].t;
    return T_NONE;
}

static int is_int_type(enum ply_type t) { return t != T_NONE && t != T_F32 && t != T_F64; }

static int tok_is(const char *tok, size_t len, const char *word)
{
    return strlen(word) == len && memcmp(tok, word, len) == 0;
}

/* Header line tokens: like OBJ's, but without comments. */
static int hdr_token(const char **p, const char *e, const char **tok, size_t *len)
{
    const char *s = *p;
    while (s < e && is_blank(*s)) ++s;
    if (s == e) return 0;
    const char *t = s;
    while (s < e && !is_blank(*s)) ++s;
    *tok = t;
    *len = (size_t)(s - t);
    *p = s;
    return 1;
}

#define PLY_FAIL(c, st, ...) sidx__fail((c)->err, (st), __VA_ARGS__)

/* Reads the header; on success c->p points at the first body byte. */
static sidx_status ply_header(ply_ctx *c)
{
    const char *p = (const char *)c->data, *end = (const char *)c->end;
    int have_format = 0;
    ply_element *cur = NULL;
    for (c->line = 1;; ++c->line) {
        if (p >= end) return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: header ends before end_header", c->name, c->line);
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        if (!eol) return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: header ends before end_header", c->name, c->line);
        const char *q = p, *tok;
        size_t len;
        p = eol + 1;
        if (c->line == 1) {
            if (!(hdr_token(&q, eol, &tok, &len) && tok == (const char *)c->data && tok_is(tok, len, "ply") &&
                  !hdr_token(&q, eol, &tok, &len)))
                return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:1: not a PLY file (no 'ply' magic line)", c->name);
            continue;
        }
        if (!hdr_token(&q, eol, &tok, &len)) continue; /* blank line: tolerated */
        if (tok_is(tok, len, "comment") || tok_is(tok, len, "obj_info")) continue;
        if (tok_is(tok, len, "end_header")) break;
        if (tok_is(tok, len, "format")) {
            const char *f, *v;
            size_t flen, vlen;
            if (!hdr_token(&q, eol, &f, &flen) || !hdr_token(&q, eol, &v, &vlen) || !tok_is(v, vlen, "1.0"))
                return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: expected 'format <type> 1.0'", c->name, c->line);
            if (tok_is(f, flen, "ascii")) c->format = F_ASCII;
            else if (tok_is(f, flen, "binary_little_endian")) c->format = F_LE;
            else if (tok_is(f, flen, "binary_big_endian")) c->format = F_BE;
            else
                return PLY_FAIL(c, SIDX_ERR_UNSUPPORTED, "%s:%zu: unknown PLY format '%.*s'", c->name, c->line,
                                (int)(flen < TOK_SHOWN ? flen : TOK_SHOWN), f);
            have_format = 1;
        } else if (tok_is(tok, len, "element")) {
            const char *n, *cnt;
            size_t nlen, clen;
            int64_t count = -1;
            const char *extra;
            size_t xlen;
            /* scan_int must use the whole count token: then cnt == q. */
            if (!hdr_token(&q, eol, &n, &nlen) || !hdr_token(&q, eol, &cnt, &clen) ||
                !scan_int(&cnt, cnt + clen, &count) || cnt != q || count < 0 || hdr_token(&q, eol, &extra, &xlen))
                return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: expected 'element <name> <count>'", c->name, c->line);
            if (c->nel == PLY_MAX_ELEMENTS)
                return PLY_FAIL(c, SIDX_ERR_UNSUPPORTED, "%s:%zu: more than %d elements", c->name, c->line,
                                PLY_MAX_ELEMENTS);
            cur = &c->el[c->nel++];
            memset(cur, 0, sizeof *cur);
            cur->count = (uint64_t)count;
            size_t shown = nlen < sizeof cur->name - 1 ? nlen : sizeof cur->name - 1;
            memcpy(cur->name, n, shown);
            cur->kind = tok_is(n, nlen, "vertex") ? K_VERTEX : tok_is(n, nlen, "face") ? K_FACE : K_OTHER;
            for (int i = 0; i + 1 < c->nel; ++i)
                if (cur->kind != K_OTHER && c->el[i].kind == cur->kind)
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: second '%s' element", c->name, c->line, cur->name);
            if (cur->kind == K_VERTEX) {
                if ((uint64_t)count > UINT32_MAX)
                    return PLY_FAIL(c, SIDX_ERR_LIMIT, "%s:%zu: more than %lu vertices", c->name, c->line,
                                    (unsigned long)UINT32_MAX);
                c->nv = (uint64_t)count;
            }
        } else if (tok_is(tok, len, "property")) {
            if (!cur) return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: property before any element", c->name, c->line);
            if (cur->nprops == PLY_MAX_PROPS)
                return PLY_FAIL(c, SIDX_ERR_UNSUPPORTED, "%s:%zu: more than %d properties", c->name, c->line,
                                PLY_MAX_PROPS);
            ply_prop *pr = &cur->props[cur->nprops++];
            const char *t1, *t2, *t3, *nm;
            size_t l1, l2, l3, nmlen;
            if (!hdr_token(&q, eol, &t1, &l1))
                return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: property without a type", c->name, c->line);
            if (tok_is(t1, l1, "list")) {
                if (!hdr_token(&q, eol, &t2, &l2) || !hdr_token(&q, eol, &t3, &l3) || !hdr_token(&q, eol, &nm, &nmlen))
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: expected 'property list <count type> <type> <name>'",
                                    c->name, c->line);
                pr->count_type = ply_type_named(t2, l2);
                pr->type = ply_type_named(t3, l3);
                if (!is_int_type(pr->count_type) || pr->type == T_NONE)
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: bad list types", c->name, c->line);
            } else {
                if (!hdr_token(&q, eol, &nm, &nmlen))
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: property without a name", c->name, c->line);
                pr->count_type = T_NONE;
                pr->type = ply_type_named(t1, l1);
                if (pr->type == T_NONE)
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: unknown property type '%.*s'", c->name, c->line,
                                    (int)(l1 < TOK_SHOWN ? l1 : TOK_SHOWN), t1);
            }
            pr->role = R_OTHER;
            if (cur->kind == K_VERTEX && pr->count_type == T_NONE) {
                if (tok_is(nm, nmlen, "x")) pr->role = R_X;
                else if (tok_is(nm, nmlen, "y")) pr->role = R_Y;
                else if (tok_is(nm, nmlen, "z")) pr->role = R_Z;
            } else if (cur->kind == K_FACE && pr->count_type != T_NONE &&
                       (tok_is(nm, nmlen, "vertex_indices") || tok_is(nm, nmlen, "vertex_index"))) {
                if (!is_int_type(pr->type))
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: vertex indices must have an integer type", c->name,
                                    c->line);
                pr->role = R_INDICES;
            }
            for (int i = 0; i + 1 < cur->nprops; ++i)
                if (pr->role != R_OTHER && cur->props[i].role == pr->role)
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: duplicate property '%.*s'", c->name, c->line,
                                    (int)(nmlen < TOK_SHOWN ? nmlen : TOK_SHOWN), nm);
        } else {
            return PLY_FAIL(c, SIDX_ERR_PARSE, "%s:%zu: unknown header keyword '%.*s'", c->name, c->line,
                            (int)(len < TOK_SHOWN ? len : TOK_SHOWN), tok);
        }
    }
    if (!have_format) return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: no 'format' line in the header", c->name);
    int have_vertex = 0;
    for (int i = 0; i < c->nel; ++i) have_vertex |= c->el[i].kind == K_VERTEX;
    if (!have_vertex) return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: no vertex element in the header", c->name);
    c->p = (const unsigned char *)p;
    ++c->line; /* the ascii body starts on the line after end_header */

    /* The vertex element must say where x, y and z are; a face element
     * must carry its index list. */
    for (int i = 0; i < c->nel; ++i) {
        const ply_element *el = &c->el[i];
        int seen[5] = {0};
        for (int k = 0; k < el->nprops; ++k) seen[el->props[k].role] = 1;
        if (el->kind == K_VERTEX && !(seen[R_X] && seen[R_Y] && seen[R_Z]))
            return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: the vertex element lacks scalar x, y or z properties", c->name);
        if (el->kind == K_FACE && !seen[R_INDICES])
            return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: the face element has no vertex_indices list", c->name);
    }
    return SIDX_OK;
}

/* -- body readers: one value at a time, binary or ascii -- */

/* Where we are, for messages: a line in ascii, a byte offset in binary. */
static const char *ply_where(const ply_ctx *c, char *buf, size_t n)
{
    if (c->format == F_ASCII) snprintf(buf, n, "%s:%zu", c->name, c->line);
    else snprintf(buf, n, "%s: byte %zu", c->name, (size_t)(c->p - c->data));
    return buf;
}

static sidx_status ply_truncated(ply_ctx *c, const ply_element *el, uint64_t item)
{
    char w[300];
    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: data ends early (in %s %llu of %llu)", ply_where(c, w, sizeof w),
                    el->name, (unsigned long long)item, (unsigned long long)el->count);
}

/* Next ascii token; tracks line numbers. */
static int ascii_token(ply_ctx *c, const char **tok, size_t *len)
{
    const unsigned char *s = c->p;
    size_t line = c->line;
    while (s < c->end && (is_blank((char)*s) || *s == '\n')) {
        if (*s == '\n') ++line;
        ++s;
    }
    if (s == c->end) { /* keep c->line on the last token: "ends early" points there */
        c->p = s;
        return 0;
    }
    c->line = line;
    const unsigned char *t = s;
    while (s < c->end && !is_blank((char)*s) && *s != '\n') ++s;
    *tok = (const char *)t;
    *len = (size_t)(s - t);
    c->p = s;
    return 1;
}

/* Binary scalar as raw bits in host order. */
static uint64_t bin_raw(ply_ctx *c, size_t size)
{
    uint64_t v = 0;
    const unsigned char *s = c->p;
    if (c->format == F_LE)
        for (size_t i = size; i-- > 0;) v = v << 8 | s[i];
    else
        for (size_t i = 0; i < size; ++i) v = v << 8 | s[i];
    c->p += size;
    return v;
}

/* Reads one scalar of type t.  Integers come back exactly in *i (and as
 * *d), reals in *d.  0 = data ended; -1 = malformed (ascii). */
static int ply_read(ply_ctx *c, enum ply_type t, int64_t *i, double *d)
{
    if (c->format != F_ASCII) {
        const size_t sz = ply_type_size[t];
        if ((size_t)(c->end - c->p) < sz) return 0;
        const uint64_t raw = bin_raw(c, sz);
        switch (t) {
        case T_I8: *i = (int8_t)(uint8_t)raw; break;
        case T_U8: *i = (uint8_t)raw; break;
        case T_I16: *i = (int16_t)(uint16_t)raw; break;
        case T_U16: *i = (uint16_t)raw; break;
        case T_I32: *i = (int32_t)(uint32_t)raw; break;
        case T_U32: *i = (uint32_t)raw; break;
        case T_F32: {
            uint32_t r32 = (uint32_t)raw;
            float f;
            memcpy(&f, &r32, sizeof f);
            *d = f;
            *i = 0;
            return 1;
        }
        default: {
            double f;
            memcpy(&f, &raw, sizeof f);
            *d = f;
            *i = 0;
            return 1;
        }
        }
        *d = (double)*i;
        return 1;
    }
    const char *tok;
    size_t len;
    if (!ascii_token(c, &tok, &len)) return 0;
    if (is_int_type(t)) {
        const char *q = tok;
        if (!scan_int(&q, tok + len, i) || q != tok + len) return -1;
        *d = (double)*i;
        return 1;
    }
    *i = 0;
    if (t == T_F32) {
        float f;
        if (!parse_float(tok, len, &f)) return -1;
        *d = f;
        return 1;
    }
    return parse_double(tok, len, d) ? 1 : -1;
}

static sidx_status ply_bad_value(ply_ctx *c, const ply_element *el, uint64_t item, int r)
{
    if (r == 0) return ply_truncated(c, el, item);
    char w[300];
    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: malformed number in %s %llu", ply_where(c, w, sizeof w), el->name,
                    (unsigned long long)item);
}

/* Skips `n` values of type t. */
static int ply_skip(ply_ctx *c, enum ply_type t, uint64_t n)
{
    if (c->format != F_ASCII) {
        const uint64_t avail = (uint64_t)(c->end - c->p) / ply_type_size[t];
        if (n > avail) return 0;
        c->p += n * ply_type_size[t];
        return 1;
    }
    int64_t i;
    double d;
    for (uint64_t k = 0; k < n; ++k) {
        int r = ply_read(c, t, &i, &d);
        if (r <= 0) return r;
    }
    return 1;
}

static sidx_status ply_body(ply_ctx *c, mesh_buf *b)
{
    for (int e = 0; e < c->nel; ++e) {
        const ply_element *el = &c->el[e];
        /* An element without properties has zero-length instances; do not
         * spin through a fuzzed count of 2^62 of them. */
        if (el->nprops == 0) continue;
        if (el->kind == K_VERTEX) {
            /* The header's count is trusted for one allocation only after a
             * plausibility check: every property needs at least one byte. */
            if (el->count > (uint64_t)(c->end - c->p) / (uint64_t)el->nprops) return ply_truncated(c, el, 0);
            if (!grow_to((void **)&b->pos, &b->cap_v, (size_t)el->count, sizeof *b->pos))
                return PLY_FAIL(c, SIDX_ERR_NOMEM, "%s: out of memory for %llu vertices", c->name,
                                (unsigned long long)el->count);
        }
        for (uint64_t item = 0; item < el->count; ++item) {
            float xyz[3] = {0, 0, 0};
            uint32_t first = 0, prev = 0;
            for (int k = 0; k < el->nprops; ++k) {
                const ply_prop *pr = &el->props[k];
                int64_t iv;
                double dv;
                int r;
                if (pr->count_type == T_NONE) {
                    if (pr->role == R_OTHER) r = ply_skip(c, pr->type, 1);
                    else r = ply_read(c, pr->type, &iv, &dv);
                    if (r <= 0) return ply_bad_value(c, el, item, r);
                    if (pr->role != R_OTHER) xyz[pr->role - R_X] = (float)dv;
                    continue;
                }
                int64_t n;
                r = ply_read(c, pr->count_type, &n, &dv);
                if (r <= 0) return ply_bad_value(c, el, item, r);
                if (n < 0) {
                    char w[300];
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: negative list length in %s %llu",
                                    ply_where(c, w, sizeof w), el->name, (unsigned long long)item);
                }
                if (pr->role != R_INDICES) {
                    r = ply_skip(c, pr->type, (uint64_t)n);
                    if (r <= 0) return ply_bad_value(c, el, item, r);
                    continue;
                }
                if (n < 3) {
                    char w[300];
                    return PLY_FAIL(c, SIDX_ERR_PARSE, "%s: face %llu has %lld vertices (needs at least 3)",
                                    ply_where(c, w, sizeof w), (unsigned long long)item, (long long)n);
                }
                for (int64_t j = 0; j < n; ++j) {
                    r = ply_read(c, pr->type, &iv, &dv);
                    if (r <= 0) return ply_bad_value(c, el, item, r);
                    if (iv < 0 || (uint64_t)iv >= c->nv) {
                        char w[300];
                        return PLY_FAIL(c, SIDX_ERR_BAD_GEOMETRY,
                                        "%s: face %llu: vertex index %lld out of range (%llu vertices)",
                                        ply_where(c, w, sizeof w), (unsigned long long)item, (long long)iv,
                                        (unsigned long long)c->nv);
                    }
                    const uint32_t v = (uint32_t)iv;
                    if (j == 0) first = v;
                    else if (j >= 2) {
                        if (b->nt >= UINT32_MAX)
                            return PLY_FAIL(c, SIDX_ERR_LIMIT, "%s: more than %lu triangles", c->name,
                                            (unsigned long)UINT32_MAX);
                        if (!buf_push_tri(b, first, prev, v))
                            return PLY_FAIL(c, SIDX_ERR_NOMEM, "%s: out of memory", c->name);
                    }
                    prev = v;
                }
            }
            if (el->kind == K_VERTEX) {
                const sidx_vec3 v = sidx_v3(xyz[0], xyz[1], xyz[2]);
                if (!sidx_v3_isfinite(v)) {
                    char w[300];
                    return PLY_FAIL(c, SIDX_ERR_BAD_GEOMETRY, "%s: vertex %llu has a non-finite coordinate",
                                    ply_where(c, w, sizeof w), (unsigned long long)item);
                }
                b->pos[b->nv++] = v; /* capacity reserved above */
            }
        }
    }
    return SIDX_OK;
}

sidx_status sidx_mesh_parse_ply(const void *data, size_t size, const char *name, sidx_mesh *out, sidx_error *err)
{
    if (!name) name = "<memory>";
    if (!out || (!data && size)) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: out or data is NULL", name);
    /* ~70 KB of element tables: keep them off the stack of fuzzers. */
    ply_ctx *c = calloc(1, sizeof *c);
    if (!c) return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory", name);
    c->name = name;
    c->err = err;
    c->data = data;
    c->p = data;
    c->end = size ? c->data + size : c->data;
    mesh_buf b = {0};
    sidx_status s = ply_header(c);
    if (s == SIDX_OK) s = ply_body(c, &b);
    free(c);
    if (s != SIDX_OK) {
        buf_free(&b);
        return s;
    }
    return buf_finish(&b, out, name, err);
}

/* ---- files ----------------------------------------------------------------- */

/* Reads a whole file into a malloc'd buffer (NUL-terminated for safety;
 * *size excludes the NUL). */
static sidx_status read_file(const char *path, char **data, size_t *size, sidx_error *err)
{
    if (!path) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "path is NULL");
    FILE *f = fopen(path, "rb");
    if (!f) return sidx__fail(err, SIDX_ERR_IO, "%s: %s", path, strerror(errno));
    char *buf = NULL;
    size_t n = 0, cap = 0;
    /* Chunked reads rather than fseek/ftell: works for pipes too. */
    for (;;) {
        if (cap - n < 65536 + 1) {
            size_t ncap = cap ? cap * 2 : 1 << 20;
            if (ncap < cap) {
                free(buf);
                fclose(f);
                return sidx__fail(err, SIDX_ERR_LIMIT, "%s: file too large", path);
            }
            char *q = realloc(buf, ncap);
            if (!q) {
                free(buf);
                fclose(f);
                return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory reading the file", path);
            }
            buf = q;
            cap = ncap;
        }
        size_t got = fread(buf + n, 1, cap - n - 1, f);
        n += got;
        if (got == 0) break;
    }
    if (ferror(f)) {
        int e = errno;
        free(buf);
        fclose(f);
        return sidx__fail(err, SIDX_ERR_IO, "%s: %s", path, e ? strerror(e) : "read error");
    }
    fclose(f);
    buf[n] = '\0';
    *data = buf;
    *size = n;
    return SIDX_OK;
}

sidx_status sidx_mesh_load_obj(const char *path, sidx_mesh *out, sidx_error *err)
{
    char *data;
    size_t size;
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "out is NULL");
    sidx_status s = read_file(path, &data, &size, err);
    if (s != SIDX_OK) return s;
    s = sidx_mesh_parse_obj(data, size, path, out, err);
    free(data);
    return s;
}

sidx_status sidx_mesh_load_ply(const char *path, sidx_mesh *out, sidx_error *err)
{
    char *data;
    size_t size;
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "out is NULL");
    sidx_status s = read_file(path, &data, &size, err);
    if (s != SIDX_OK) return s;
    s = sidx_mesh_parse_ply(data, size, path, out, err);
    free(data);
    return s;
}

static int has_extension(const char *path, const char *ext)
{
    const size_t n = strlen(path), m = strlen(ext);
    if (n < m) return 0;
    for (size_t i = 0; i < m; ++i) {
        char ch = path[n - m + i];
        if (ch >= 'A' && ch <= 'Z') ch = (char)(ch - 'A' + 'a');
        if (ch != ext[i]) return 0;
    }
    return 1;
}

sidx_status sidx_mesh_load(const char *path, sidx_mesh *out, sidx_error *err)
{
    if (!path || !out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "path or out is NULL");
    if (has_extension(path, ".obj")) return sidx_mesh_load_obj(path, out, err);
    if (has_extension(path, ".ply")) return sidx_mesh_load_ply(path, out, err);
    char *data;
    size_t size;
    sidx_status s = read_file(path, &data, &size, err);
    if (s != SIDX_OK) return s;
    /* PLY files start with the line "ply"; anything else is tried as OBJ. */
    if (size >= 4 && memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r'))
        s = sidx_mesh_parse_ply(data, size, path, out, err);
    else
        s = sidx_mesh_parse_obj(data, size, path, out, err);
    free(data);
    return s;
}
