/* scale.c — `sidx-bench scale`: build time, the build's peak memory,
 * Mrays/s and traversal steps per ray against triangle count (1k … 4M by
 * default, 16M and more with --max-tris; procedural meshes made on the
 * fly), sidx structures beside Embree (default and HIGH quality), with
 * growth exponents
 * fitted by least squares on log-log axes (n log n build shows as an
 * exponent a little above 1; log n steps as a small exponent, and as the
 * slope per doubling of n; n^(1/3) for uniform grids as about 0.33).
 *
 * --scene stadium is the teapot in a stadium with a growing teapot: a
 * fixed stadium shell (floor and stands of the built-in "stadium", 770
 * triangles, 2200 units across) around a teapot of growing detail scaled
 * to one unit, rays from a camera looking at the teapot (lesson 08's
 * view).  The uniform grid's resolution follows n over the whole stadium
 * volume, so the teapot stays in a few cells and the tests per ray grow
 * about linearly with n (exponent near 1); the nested and irregular grids
 * refine where the triangles are and stay near constant (exponent ~0).
 *
 * --scene FILE sweeps a mesh file by midpoint subdivision: each level
 * splits every triangle into four similar ones (make_subdivided), so a
 * real scene's long thin triangles stay long and thin at every size —
 * Sponza's 66,454 triangles become 17.0M at level 4, a Sponza-like scene
 * at the size of the 16.8M height field.  Its primary rays come from a
 * camera inside the mesh's box looking along its longer horizontal axis
 * (interior_rays: Sponza's atrium seen from one end). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <stdatomic.h>
#include <string.h>

#include "bench.h"

typedef struct scale_pt {
    int accel;     /* index into the structure list */
    double tris, build_ms, steps, prims, mrays;
    double bytes;     /* the structure */
    double peak;      /* resident peak of the build above the loaded mesh; < 0 = not measured */
    double heap;      /* sidx: most bytes live through the build's allocator; < 0 = not sidx */
    double mesh;      /* the mesh's positions and indices */
} scale_pt;

/* Tracing time per structure and size: the cold pass stops after this
 * many ms (the rays it reached are the ones timed warm), and the warm
 * passes stop once they have spent it (bench_time_passes). */
#define SCALE_TRACE_MS 3000.0

typedef struct scale_pass {
    const sidx_accel *a;
    const bench_rays *br;
    size_t n; /* rays per pass: all, or what the cold pass reached */
    sidx_hit *hits;
} scale_pass;

static double scale_pass_run(void *ctx, int cold)
{
    scale_pass *p = ctx;
    double ms = 0;
    const size_t done = bench_trace(p->a, p->br, 0, p->n, NULL, 0, 1, cold ? SCALE_TRACE_MS : 0.0, p->hits, &ms);
    if (cold) p->n = done;
    return ms;
}

static void scale_usage(FILE *out)
{
    fprintf(out,
            "usage: sidx-bench scale [options]\n"
            "\n"
            "Sweeps the triangle count of a procedural scene and reports, per structure, build\n"
            "time (one thread, CPU time), the build's memory, steps per ray (NODE_ENTER events),\n"
            "primitive tests per ray and Mrays/s on primary rays (one thread), then the growth\n"
            "fitted by least squares on log-log axes (y ~ n^k).\n"
            "Memory: MB is the structure; peak_MB the rise of the process's resident set during\n"
            "the build above its level before it (the mesh is loaded then, so it is NOT included:\n"
            "add mesh_MB, printed per size, for \"mesh included\"; Embree's peak includes its own\n"
            "copy of the vertices and indices); heap_MB (sidx only) the most bytes live at once\n"
            "through the build's allocator.  Embree rows (embree: build quality MEDIUM, embree-hq:\n"
            "HIGH) build on a \"threads=1\" device and trace with rtcIntersect1.\n"
            "options:\n"
            "  --scene icosphere|grid|heightfield|soup|stadium|FILE  icosphere: levels (20 x 4^k\n"
            "                     triangles); grid: d x d flat quads (2 d^2); heightfield: the\n"
            "                     built-in scene heightfield:d, the same quads on a rolling surface\n"
            "                     (1024 x 4^k triangles: 16.8M at --max-tris 17e6); soup: random\n"
            "                     triangles of fixed size; stadium: teapot in a stadium, the stadium\n"
            "                     fixed (770 triangles, 2200 units across), the teapot (1 unit)\n"
            "                     growing in detail, rays from a camera looking at the teapot: the\n"
            "                     uniform grid's tests per ray grow ~n, the nested and irregular\n"
            "                     grids' stay flat; FILE (.obj, .ply): the mesh, each level splitting\n"
            "                     every triangle into 4 similar ones at its edge midpoints (T x 4^k\n"
            "                     triangles: Sponza's 66,454 are 17.0M at level 4), primary rays from\n"
            "                     a camera inside its box, a fifth of the way along its longer\n"
            "                     horizontal axis and a fifth of the way up, looking along that axis\n"
            "                     (Sponza's atrium from one end) (default icosphere)\n"
            "  --accel LIST       structures (default: every registered one but brute, and embree,\n"
            "                     embree-hq)\n"
            "  --min-tris N       smallest size (default 1000)\n"
            "  --max-tris N       largest size (default 4200000)\n"
            "  --budget-ms MS     a structure whose build takes longer skips the larger sizes\n"
            "                     (default 20000)\n"
            "  --rays N           rays per size (default 20000; counters on 2000)\n"
            "  --kind primary|diffuse  camera rays, or random origins in the box with uniform\n"
            "                     random directions (default primary; stadium: its camera; FILE:\n"
            "                     primary is the camera inside its box)\n"
            "  --passes N         Mrays/s: the best of up to N warm passes (default %d) after a cold\n"
            "                     one, sidx and Embree alike; the cold pass stops after 3 s (the rays\n"
            "                     it reached are the ones timed), the warm passes once they spent 3 s\n"
            "  --csv FILE  --plot FILE.svg (build ms against triangles, log-log; the build's peak\n"
            "                     memory against triangles goes to FILE-memory.svg)\n",
            BENCH_PASSES);
}

/* Least squares slope and intercept of y on x. */
static int fit(const double *x, const double *y, int n, double *slope, double *icpt)
{
    if (n < 2) return 0;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i < n; ++i) {
        sx += x[i];
        sy += y[i];
        sxx += x[i] * x[i];
        sxy += x[i] * y[i];
    }
    const double den = n * sxx - sx * sx;
    if (den == 0) return 0;
    *slope = (n * sxy - sx * sy) / den;
    *icpt = (sy - *slope * sx) / n;
    return 1;
}

/* The stadium sweep's mesh: the floor and stands of "stadium:128" (the
 * triangles after its own teapot) around "teapot:detail" scaled to one
 * unit wide, standing 0.001 above the floor at the origin. */
#define STADIUM_STANDS 128u
static sidx_status make_stadium_sweep(uint32_t detail, sidx_mesh *out, sidx_error *err)
{
    sidx_mesh st = {0}, tp = {0};
    char spec[32];
    snprintf(spec, sizeof spec, "stadium:%u", STADIUM_STANDS);
    sidx_status rc = sidx_scene_open(spec, &st, err);
    if (rc != SIDX_OK) return rc;
    snprintf(spec, sizeof spec, "teapot:%u", detail);
    if ((rc = sidx_scene_open(spec, &tp, err)) != SIDX_OK) {
        sidx_mesh_free(&st);
        return rc;
    }
    const uint32_t shell = 2u + 6u * STADIUM_STANDS; /* floor quad + 3 rings of quads */
    const uint32_t first = st.num_triangles - shell;
    const uint32_t nv = tp.num_vertices + st.num_vertices, nt = tp.num_triangles + shell;
    float *xyz = malloc((size_t)nv * 3 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)nt * 3 * sizeof *idx);
    if (!xyz || !idx) {
        free(xyz);
        free(idx);
        sidx_mesh_free(&st);
        sidx_mesh_free(&tp);
        if (err) {
            err->status = SIDX_ERR_NOMEM;
            snprintf(err->message, sizeof err->message, "out of memory");
        }
        return SIDX_ERR_NOMEM;
    }
    const sidx_aabb tb = sidx_mesh_bounds(&tp);
    const float s = 1.0f / (tb.max.x - tb.min.x), cx = 0.5f * (tb.min.x + tb.max.x), cz = 0.5f * (tb.min.z + tb.max.z);
    for (uint32_t v = 0; v < tp.num_vertices; ++v) {
        const sidx_vec3 p = tp.positions[v];
        xyz[3 * v] = (p.x - cx) * s;
        xyz[3 * v + 1] = (p.y - tb.min.y) * s + 0.001f;
        xyz[3 * v + 2] = (p.z - cz) * s;
    }
    for (uint32_t v = 0; v < st.num_vertices; ++v) {
        const sidx_vec3 p = st.positions[v];
        float *o = xyz + 3 * ((size_t)tp.num_vertices + v);
        o[0] = p.x;
        o[1] = p.y;
        o[2] = p.z;
    }
    memcpy(idx, tp.indices, (size_t)tp.num_triangles * 3 * sizeof *idx);
    for (uint32_t t = 0; t < shell; ++t)
        for (int k = 0; k < 3; ++k)
            idx[3 * ((size_t)tp.num_triangles + t) + (size_t)k] = st.indices[3 * ((size_t)first + t) + (size_t)k] + tp.num_vertices;
    rc = sidx_mesh_from_arrays(out, xyz, nv, idx, nt, err);
    free(xyz);
    free(idx);
    sidx_mesh_free(&st);
    sidx_mesh_free(&tp);
    return rc;
}

/* One level of midpoint subdivision of in: every triangle (a b c) becomes
 * (a ab ca), (ab b bc), (ca bc c) and (ab bc ca), each similar to it at
 * half the size (Loop 1987's split without the smoothing), so the shapes
 * of the triangles — Sponza's long thin ones too — are the same at every
 * level.  A midpoint is shared by the triangles on both sides of its edge
 * (an open-addressing table keyed by the edge's two vertex ids), so the
 * mesh stays connected where the file's was; (p + q) / 2 is the same
 * float whichever way round the edge is met. */
static sidx_status subdivide_once(const sidx_mesh *in, sidx_mesh *out, sidx_error *err)
{
    const uint64_t nt = 4ull * in->num_triangles, max_nv = (uint64_t)in->num_vertices + 3ull * in->num_triangles;
    if (nt > UINT32_MAX / 3u || max_nv > UINT32_MAX) {
        if (err) {
            err->status = SIDX_ERR_LIMIT;
            snprintf(err->message, sizeof err->message, "%llu triangles: more than 32-bit indices address",
                     (unsigned long long)nt);
        }
        return SIDX_ERR_LIMIT;
    }
    size_t cap = 64;
    while (cap < 3u * (size_t)in->num_triangles + (size_t)in->num_triangles / 2u) cap *= 2;
    uint64_t *key = malloc(cap * sizeof *key);
    uint32_t *val = malloc(cap * sizeof *val);
    sidx_vec3 *pos = malloc((size_t)max_nv * sizeof *pos);
    uint32_t *idx = malloc((size_t)nt * 3 * sizeof *idx);
    if (!key || !val || !pos || !idx) {
        free(key);
        free(val);
        free(pos);
        free(idx);
        if (err) {
            err->status = SIDX_ERR_NOMEM;
            snprintf(err->message, sizeof err->message, "out of memory subdividing %u triangles", in->num_triangles);
        }
        return SIDX_ERR_NOMEM;
    }
    memset(key, 0xff, cap * sizeof *key); /* no edge has both ids UINT32_MAX */
    memcpy(pos, in->positions, (size_t)in->num_vertices * sizeof *pos);
    uint32_t nv = in->num_vertices;
    uint32_t *o = idx;
    for (uint32_t t = 0; t < in->num_triangles; ++t) {
        const uint32_t *c = in->indices + 3 * (size_t)t;
        uint32_t mid[3]; /* mid[k]: the midpoint of edge c[k] c[k+1] */
        for (int k = 0; k < 3; ++k) {
            const uint32_t p = c[k], q = c[(k + 1) % 3], lo = p < q ? p : q, hi = p < q ? q : p;
            const uint64_t e = (uint64_t)lo << 32 | hi;
            size_t h = (size_t)((e * 0x9E3779B97F4A7C15ull) >> 20) & (cap - 1);
            while (key[h] != e && key[h] != UINT64_MAX) h = (h + 1) & (cap - 1);
            if (key[h] == UINT64_MAX) {
                key[h] = e;
                val[h] = nv;
                pos[nv++] = sidx_v3_scale(sidx_v3_add(in->positions[lo], in->positions[hi]), 0.5f);
            }
            mid[k] = val[h];
        }
        const uint32_t q[12] = {c[0], mid[0], mid[2], mid[0], c[1], mid[1], mid[2], mid[1], c[2], mid[0], mid[1], mid[2]};
        memcpy(o, q, sizeof q);
        o += 12;
    }
    free(key);
    free(val);
    sidx_vec3 *fit_pos = realloc(pos, (size_t)nv * sizeof *pos); /* give back the unused midpoints' room */
    sidx_mesh m = {fit_pos ? fit_pos : pos, idx, nv, (uint32_t)nt};
    const sidx_status rc = sidx_mesh_validate(&m, err);
    if (rc != SIDX_OK) {
        sidx_mesh_free(&m);
        return rc;
    }
    *out = m;
    return SIDX_OK;
}

/* base subdivided `levels` times into *out (levels 0: a copy). */
static sidx_status make_subdivided(const sidx_mesh *base, uint32_t levels, sidx_mesh *out, sidx_error *err)
{
    sidx_mesh cur = {0};
    sidx_status rc = SIDX_OK;
    cur.positions = malloc((size_t)base->num_vertices * sizeof *cur.positions + 1);
    cur.indices = malloc((size_t)base->num_triangles * 3 * sizeof *cur.indices + 1);
    if (!cur.positions || !cur.indices) {
        sidx_mesh_free(&cur);
        if (err) {
            err->status = SIDX_ERR_NOMEM;
            snprintf(err->message, sizeof err->message, "out of memory");
        }
        return SIDX_ERR_NOMEM;
    }
    memcpy(cur.positions, base->positions, (size_t)base->num_vertices * sizeof *cur.positions);
    memcpy(cur.indices, base->indices, (size_t)base->num_triangles * 3 * sizeof *cur.indices);
    cur.num_vertices = base->num_vertices;
    cur.num_triangles = base->num_triangles;
    for (uint32_t l = 0; l < levels && rc == SIDX_OK; ++l) {
        sidx_mesh next = {0};
        rc = subdivide_once(&cur, &next, err);
        sidx_mesh_free(&cur);
        cur = next;
    }
    if (rc == SIDX_OK) *out = cur;
    return rc;
}

/* A pinhole camera's rays, a square image of about n pixels: from eye
 * towards look, up the world's +y; u and v span [-1, 1] times half_u and
 * half_v (a negative half_v turns the image's rows over). */
static void camera_rays(sidx_vec3 eye, sidx_vec3 look, float half_u, float half_v, size_t n, tk_rayrec *out)
{
    sidx_vec3 fwd = sidx_v3_sub(look, eye);
    fwd = sidx_v3_scale(fwd, 1.0f / sidx_v3_length(fwd));
    sidx_vec3 right = sidx_v3_cross(fwd, sidx_v3(0, 1, 0));
    right = sidx_v3_scale(right, 1.0f / sidx_v3_length(right));
    const sidx_vec3 up = sidx_v3_cross(right, fwd);
    size_t w = 1;
    while ((w + 1) * (w + 1) <= n) ++w;
    for (size_t i = 0; i < n; ++i) {
        const float u = (((float)(i % w) + 0.5f) / (float)w * 2.0f - 1.0f) * half_u;
        const float v = (((float)((i / w) % w) + 0.5f) / (float)w * 2.0f - 1.0f) * half_v;
        const sidx_vec3 d = sidx_v3_add(fwd, sidx_v3_add(sidx_v3_scale(right, u), sidx_v3_scale(up, v)));
        out[i] = (tk_rayrec){{eye.x, eye.y, eye.z}, {d.x, d.y, d.z}, 0.0f, INFINITY};
    }
}

/* Camera rays inside a mesh's box b (an interior: Sponza's atrium): the
 * eye a fifth of the way along the longer horizontal axis (x or z; y is
 * up) and a fifth of the way up, centred across, looking along that axis
 * at the far wall three tenths of the way up; a square image of about n
 * pixels, 64 degrees across (tan 0.625).  On Sponza (x in [-17.4, 17.4],
 * y in [-0.9, 15.7]) the eye stands at (-10.4, 2.4, 0) on the ground
 * floor of one end, seeing the floor, both arcades and the far end. */
static void interior_rays(sidx_aabb b, size_t n, tk_rayrec *out)
{
    const sidx_vec3 e = sidx_aabb_extent(b), c = sidx_aabb_centroid(b);
    const int along_x = e.x >= e.z;
    const float y_eye = b.min.y + 0.2f * e.y, y_at = b.min.y + 0.3f * e.y;
    const sidx_vec3 eye = along_x ? sidx_v3(b.min.x + 0.2f * e.x, y_eye, c.z) : sidx_v3(c.x, y_eye, b.min.z + 0.2f * e.z);
    const sidx_vec3 look = along_x ? sidx_v3(b.max.x, y_at, c.z) : sidx_v3(c.x, y_at, b.max.z);
    camera_rays(eye, look, 0.625f, -0.625f, n, out); /* rows top down: (1 - x) 0.625 = (x - 1) (-0.625) exactly */
}

/* Camera rays at the teapot (lesson 08's view): eye 2.3 units away, a
 * square image of about n pixels covering the teapot and some floor. */
static void teapot_rays(size_t n, tk_rayrec *out)
{
    camera_rays(sidx_v3(0.66f, 1.07f, 2.2f), sidx_v3(0.0f, 0.3f, 0.0f), 0.35f, 0.35f, n, out);
}

/* v / scale printed with fmt, "-" when v < 0 (not measured). */
static void num_cell(char *buf, size_t size, double v, double scale, const char *fmt)
{
    if (v >= 0) snprintf(buf, size, fmt, v / scale);
    else snprintf(buf, size, "-");
}

/* --plot FILE.svg: build ms against triangles; FILE-memory.svg: the
 * build's resident peak (MB, mesh not included) against triangles. */
static int write_plots(const char *plot, const char *scene, const scale_pt *pts, int npts, const char *const *names,
                       int na)
{
    bench_point *bp = calloc((size_t)npts + 1, sizeof *bp);
    if (!bp) return 0;
    int ok = 1;
    char title[128], path[1024];
    for (int pass = 0; pass < 2 && ok; ++pass) {
        size_t n = 0;
        for (int i = 0; i < npts; ++i) {
            const double y = pass ? pts[i].peak / 1048576.0 : pts[i].build_ms;
            if (!(y > 0)) continue;
            bp[n].x = pts[i].tris;
            bp[n].y = y;
            bp[n].label = names[pts[i].accel];
            bp[n].series = pts[i].accel;
            ++n;
        }
        if (pass == 0) {
            snprintf(path, sizeof path, "%s", plot);
            snprintf(title, sizeof title, "build time against triangle count (%s)", scene);
        } else {
            const size_t len = strlen(plot);
            const size_t stem = len >= 4 && !strcmp(plot + len - 4, ".svg") ? len - 4 : len;
            snprintf(path, sizeof path, "%.*s-memory.svg", (int)stem, plot);
            snprintf(title, sizeof title, "build peak memory against triangle count (%s)", scene);
        }
        ok = bench_svg_lines(path, title, "triangles",
                             pass ? "build peak, MB resident (mesh not included)" : "build ms (one thread)", bp, n,
                             names, na);
    }
    free(bp);
    return ok;
}

/* The point of structure name at the largest size it reached; NULL if none. */
static const scale_pt *largest_of(const scale_pt *pts, int npts, const char *const *names, int na, const char *name)
{
    const scale_pt *best = NULL;
    for (int i = 0; i < npts; ++i)
        if (pts[i].accel < na && !strcmp(names[pts[i].accel], name) && (!best || pts[i].tris > best->tris))
            best = &pts[i];
    return best;
}

/* The targets of `sidx-bench run` that concern scale, at the largest size
 * both sides reached: bvh build vs Embree's, bvh8 build, peak memory (mesh
 * included in both: peak above the loaded mesh + the mesh's bytes) and
 * Mrays/s vs Embree HQ's.  One run, no rounds: indicative only. */
static void largest_ratios(FILE *f, const scale_pt *pts, int npts, const char *const *names, int na)
{
    static const struct { const char *a, *b, *what; double goal; } pairs[] = {
        {"bvh", "embree", "build ms", 1.0},       {"bvh8", "embree-hq", "build ms", 1.0},
        {"bvh8", "embree-hq", "peak MB", 1.2},    {"bvh8", "embree-hq", "Mrays/s", 1.1},
    };
    int header = 0;
    for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; ++i) {
        const scale_pt *a = largest_of(pts, npts, names, na, pairs[i].a);
        const scale_pt *b = largest_of(pts, npts, names, na, pairs[i].b);
        if (!a || !b || a->tris != b->tris) continue;
        double va, vb;
        const int mem = pairs[i].what[0] == 'p', speed = pairs[i].what[0] == 'M';
        if (mem) {
            if (a->peak < 0 || b->peak < 0) continue;
            va = (a->peak + a->mesh) / 1048576.0;
            vb = (b->peak + b->mesh) / 1048576.0;
        } else if (speed) {
            va = a->mrays;
            vb = b->mrays;
        } else {
            va = a->build_ms;
            vb = b->build_ms;
        }
        if (!(vb > 0)) continue;
        if (!header) {
            fprintf(f, "\n== at the largest size (one run, no rounds: indicative; peak MB includes the mesh)\n");
            header = 1;
        }
        const double r = va / vb;
        const int pass = speed ? r >= pairs[i].goal : r <= pairs[i].goal;
        fprintf(f, "%-5s %-9s vs %-10s %9.0f tris: %10.2f vs %10.2f = %5.2fx (target %s %.1fx: %s)\n", pairs[i].a,
                pairs[i].what, pairs[i].b, a->tris, va, vb, r, speed ? ">=" : "<=", pairs[i].goal,
                pass ? "PASS" : "FAIL");
    }
}

int bench_cmd_scale(int argc, char **argv)
{
    const char *scene = "icosphere", *accel_list = NULL, *csv = NULL, *plot = NULL;
    double min_tris = 1000, max_tris = 4200000, budget = 20000;
    int passes = BENCH_PASSES;
    size_t nrays = 20000;
    int diffuse = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            scale_usage(stdout);
            return BENCH_OK;
        }
        if (!val) {
            fprintf(stderr, "sidx-bench scale: unexpected '%s'\n", a);
            scale_usage(stderr);
            return BENCH_USAGE;
        }
        ++i;
        char *end = NULL;
        if (!strcmp(a, "--scene")) scene = val;
        else if (!strcmp(a, "--accel")) accel_list = val;
        else if (!strcmp(a, "--csv")) csv = val;
        else if (!strcmp(a, "--plot")) plot = val;
        else if (!strcmp(a, "--kind")) {
            if (strcmp(val, "primary") && strcmp(val, "diffuse")) goto bad;
            diffuse = !strcmp(val, "diffuse");
        }
        else if (!strcmp(a, "--min-tris")) { min_tris = strtod(val, &end); if (*end || !(min_tris > 0)) goto bad; }
        else if (!strcmp(a, "--max-tris")) { max_tris = strtod(val, &end); if (*end || !(max_tris > 0)) goto bad; }
        else if (!strcmp(a, "--budget-ms")) { budget = strtod(val, &end); if (*end || !(budget > 0)) goto bad; }
        else if (!strcmp(a, "--passes")) {
            const long v = strtol(val, &end, 10);
            if (*end || end == val || v < 1 || v > 1000) goto bad;
            passes = (int)v;
        }
        else if (!strcmp(a, "--rays")) {
            nrays = (size_t)strtoull(val, &end, 10);
            if (*end || nrays == 0 || nrays > 10000000) goto bad;
        } else {
            fprintf(stderr, "sidx-bench scale: unknown option '%s'\n", a);
            return BENCH_USAGE;
        }
        continue;
    bad:
        fprintf(stderr, "sidx-bench scale: bad value '%s' for %s\n", val, a);
        return BENCH_USAGE;
    }
    const int stadium = !strcmp(scene, "stadium"), hfield = !strcmp(scene, "heightfield");
    /* any other name is a mesh file, swept by subdivision */
    const int file = strcmp(scene, "icosphere") && strcmp(scene, "grid") && strcmp(scene, "soup") && !stadium && !hfield;
    sidx_mesh base = {0};
    sidx_aabb base_box = {{0, 0, 0}, {0, 0, 0}};
    if (file) {
        sidx_error lerr = {SIDX_OK, ""};
        if (sidx_mesh_load(scene, &base, &lerr) != SIDX_OK) {
            fprintf(stderr,
                    "sidx-bench scale: --scene %s: %s\n(--scene is icosphere, grid, heightfield, soup, stadium or a "
                    "mesh file)\n",
                    scene, lerr.message);
            return BENCH_USAGE;
        }
        if (base.num_triangles == 0) {
            fprintf(stderr, "sidx-bench scale: --scene %s: the file has no triangles\n", scene);
            sidx_mesh_free(&base);
            return BENCH_USAGE;
        }
        base_box = sidx_mesh_bounds(&base);
    }
    /* the sizes: details of the scene */
    uint32_t details[32];
    int nsizes = 0;
    for (int k = 0; k < 32 && nsizes < 32; ++k) {
        double tris;
        uint32_t d;
        if (!strcmp(scene, "icosphere")) {
            d = (uint32_t)k;
            tris = 20.0 * pow(4.0, k);
        } else if (file) {
            d = (uint32_t)k; /* subdivision levels */
            tris = base.num_triangles * pow(4.0, k);
        } else if (stadium) {
            /* teapot detail 8·2^(k/2): about twice the triangles per size
             * (a teapot of detail d has about 8.3 d^2 triangles) */
            d = (uint32_t)lround(8.0 * pow(2.0, 0.5 * k));
            if (d > 1024) break;
            tris = 8.3 * d * d + 2.0 + 6.0 * STADIUM_STANDS;
        } else {
            tris = 1024.0 * pow(4.0, k);
            const int quads = !strcmp(scene, "grid") || hfield;
            d = quads ? (uint32_t)lround(sqrt(tris / 2)) : (uint32_t)tris;
            if (quads) tris = 2.0 * d * d;
        }
        if (tris > max_tris) break;
        if (tris < min_tris) continue;
        details[nsizes] = d;
        ++nsizes;
    }
    /* sidx structures, then Embree's default (MEDIUM) and HIGH builds */
    const char *names[64];
    int is_embree[64] = {0};
    int na = 0;
    for (size_t i = 0; i < sidx_accel_registered_count() && na < 62; ++i) {
        const char *nm = sidx_accel_registered_name(i);
        if (accel_list ? bench_list_has(accel_list, nm) : strcmp(nm, "brute") != 0) names[na++] = nm;
    }
    static const char *const embree_names[2] = {"embree", "embree-hq"};
    for (int e = 0; e < 2; ++e)
        if (bench_list_has(accel_list, embree_names[e])) {
            is_embree[na] = 1;
            names[na++] = embree_names[e];
        }
    if (na == 0) {
        fprintf(stderr, "sidx-bench scale: no structure selected\n");
        sidx_mesh_free(&base);
        return BENCH_USAGE;
    }
    scale_pt *pts = calloc((size_t)na * (size_t)(nsizes ? nsizes : 1), sizeof *pts);
    int npts = 0;
    int skip[64] = {0};
    sidx_hit *hits = malloc(nrays * sizeof *hits);
    tk_rayrec *rec = malloc(nrays * sizeof *rec);
    if (!pts || !hits || !rec) {
        fprintf(stderr, "sidx-bench scale: out of memory\n");
        free(pts);
        free(hits);
        free(rec);
        sidx_mesh_free(&base);
        return BENCH_FAIL;
    }
    bench_cpu_time = 1;
    FILE *f = stdout;
    fprintf(f, "sidx-bench scale: scene %s, %zu %s rays per size, build budget %.0f ms; one thread; Embree %s\n"
               "Mrays/s: the best of up to %d warm passes after a cold one (thread CPU time)\n"
               "MB: the structure; peak_MB: resident peak of the build above the loaded mesh (mesh not\n"
               "included; Embree's includes its copy of vertices and indices); heap_MB: sidx allocator peak\n",
            scene, nrays,
            stadium    ? "camera-at-the-teapot"
            : diffuse  ? "diffuse"
            : file     ? "primary (inside the box)"
                       : "primary",
            budget, bench_embree_version(), passes);
    fprintf(f, "%-14s %10s %10s %9s %8s %8s %9s %9s %9s\n", "accel", "tris", "build_ms", "Mrays/s", "steps", "prims",
            "MB", "peak_MB", "heap_MB");
    int rc = BENCH_OK;
    for (int si = 0; si < nsizes; ++si) {
        char spec[1100];
        if (file) snprintf(spec, sizeof spec, "%s level %u", scene, details[si]);
        else snprintf(spec, sizeof spec, "%s:%u", scene, details[si]);
        sidx_mesh m = {0};
        sidx_error err = {SIDX_OK, ""};
        bench_progress("scale: making %s", spec);
        const sidx_status made = stadium ? make_stadium_sweep(details[si], &m, &err)
                                 : file  ? make_subdivided(&base, details[si], &m, &err)
                                         : sidx_scene_open(spec, &m, &err);
        if (made != SIDX_OK) {
            bench_progress_done();
            fprintf(stderr, "sidx-bench scale: %s: %s\n", spec, err.message);
            rc = BENCH_FAIL;
            break;
        }
        const double mesh_bytes = (double)bench_mesh_bytes(&m);
        bench_progress_done();
        fprintf(f, "-- %s: %u triangles, %u vertices, mesh_MB %.2f\n", spec, m.num_triangles, m.num_vertices,
                mesh_bytes / 1048576.0);
        if (stadium) teapot_rays(nrays, rec);
        else if (file && !diffuse) interior_rays(base_box, nrays, rec);
        else tk_make_rays(&m, diffuse ? TK_RAYS_DIFFUSE : TK_RAYS_PRIMARY, nrays, 7, rec);
        bench_rays br;
        if (!bench_rays_prepare(rec, nrays, &br)) {
            sidx_mesh_free(&m);
            rc = BENCH_FAIL;
            break;
        }
        /* The counters run on 2000 rays spread over the whole image: the first
         * rows of a camera's rays miss the scene and would count nothing. */
        const size_t nc = nrays < 2000 ? nrays : 2000;
        sidx_ray *sample_r = malloc(nc * sizeof *sample_r);
        uint8_t *sample_valid = malloc(nc);
        if (!sample_r || !sample_valid) {
            free(sample_r);
            free(sample_valid);
            bench_rays_free(&br);
            sidx_mesh_free(&m);
            rc = BENCH_FAIL;
            break;
        }
        for (size_t i = 0; i < nc; ++i) {
            sample_r[i] = br.r[i * nrays / nc];
            sample_valid[i] = br.valid[i * nrays / nc];
        }
        const bench_rays sample = {sample_r, sample_valid, nc};
        for (int ai = 0; ai < na; ++ai) {
            if (skip[ai]) continue;
            bench_progress("scale: %s on %u triangles", names[ai], m.num_triangles);
            scale_pt *p = &pts[npts];
            memset(p, 0, sizeof *p);
            p->accel = ai;
            p->tris = m.num_triangles;
            p->mesh = mesh_bytes;
            p->steps = p->prims = -1;
            p->heap = -1;
            bench_mem mem;
            if (is_embree[ai]) {
                bench_embree_cfg cfg;
                bench_embree_parse(names[ai], &cfg);
                bench_embree *e = NULL;
                char msg[256];
                bench_mem_begin(&mem);
                const int ok = bench_embree_build(&m, cfg, &e, &p->build_ms, msg, sizeof msg);
                p->peak = (double)bench_mem_end(&mem);
                if (!ok) {
                    bench_progress_done();
                    fprintf(stderr, "sidx-bench scale: %s on %s: %s\n", names[ai], spec, msg);
                    skip[ai] = 1;
                    continue;
                }
                p->bytes = (double)bench_embree_bytes(e);
                bench_timing tm;
                bench_embree_trace_timed(e, rec, nrays, 0, 1, passes, SCALE_TRACE_MS, hits, &tm);
                p->mrays = bench_mrays(nrays, tm.best_ms);
                bench_embree_free(e);
            } else {
                bench_heap heap;
                const sidx_allocator al = bench_heap_allocator(&heap);
                sidx_build_options bo;
                memset(&bo, 0, sizeof bo);
                bo.alloc = &al;
                sidx_accel *a = NULL;
                bench_mem_begin(&mem);
                const double t0 = bench_build_clock_ms();
                const sidx_status bs = sidx_accel_build(names[ai], &m, &bo, &a, &err);
                p->build_ms = bench_build_clock_ms() - t0;
                p->peak = (double)bench_mem_end(&mem);
                if (bs != SIDX_OK) {
                    bench_progress_done();
                    fprintf(stderr, "sidx-bench scale: %s on %s: %s\n", names[ai], spec, err.message);
                    skip[ai] = 1;
                    continue;
                }
                p->heap = (double)atomic_load(&heap.peak);
                scale_pass sp = {a, &br, nrays, hits};
                const bench_buf bufs[3] = {{hits, nrays * sizeof *hits, 1},
                                           {br.r, nrays * sizeof *br.r, 0},
                                           {br.valid, nrays, 0}};
                bench_timing tm;
                bench_time_passes(scale_pass_run, &sp, bufs, 3, passes, SCALE_TRACE_MS, &tm);
                p->mrays = bench_mrays(sp.n, tm.best_ms);
                sidx_counters c;
                sidx_counters_init(&c);
                sidx_hook h = sidx_counters_hook(&c);
                sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &h, 0};
                bench_trace(a, &sample, 0, nc, &q, 0, 1, 0.0, hits, NULL);
                p->steps = (double)c.n[SIDX_EV_NODE_ENTER] / (double)nc;
                p->prims = (double)c.n[SIDX_EV_PRIM_TEST] / (double)nc;
                sidx_accel_stats st;
                sidx_accel_stats_get(a, &st);
                p->bytes = (double)st.bytes;
                sidx_accel_destroy(a);
            }
            ++npts;
            bench_progress_done();
            char steps[16], prims[16], peak[16], heap[16];
            num_cell(steps, sizeof steps, p->steps, 1.0, "%.1f");
            num_cell(prims, sizeof prims, p->prims, 1.0, "%.1f");
            num_cell(peak, sizeof peak, p->peak, 1048576.0, "%.2f");
            num_cell(heap, sizeof heap, p->heap, 1048576.0, "%.2f");
            fprintf(f, "%-14s %10.0f %10.2f %9.3f %8s %8s %9.2f %9s %9s\n", names[ai], p->tris, p->build_ms, p->mrays,
                    steps, prims, p->bytes / 1048576.0, peak, heap);
            fflush(f);
            if (p->build_ms > budget) {
                fprintf(f, "%-14s build over budget: larger sizes skipped\n", names[ai]);
                skip[ai] = 1;
            }
        }
        free(sample_r);
        free(sample_valid);
        bench_rays_free(&br);
        sidx_mesh_free(&m);
    }
    bench_progress_done();
    fprintf(f, "\n== growth (least squares on log-log: y ~ n^k; steps also as a + b log2 n)\n");
    fprintf(f, "%-14s %6s %10s %10s %10s %10s %14s %10s\n", "accel", "sizes", "build k", "peak k", "Mrays k",
            "steps k", "steps b/log2n", "prims k");
    for (int ai = 0; ai < na; ++ai) {
        double lx[32], lb[32], ls[32], lp[32], l2[32], st[32], lmx[32], lm[32], lrx[32], lr[32];
        int n = 0, ns = 0, np = 0, nm = 0, nr = 0;
        for (int i = 0; i < npts; ++i)
            if (pts[i].accel == ai && n < 32) {
                lx[n] = log(pts[i].tris);
                lb[n] = log(fmax(pts[i].build_ms, 1e-3));
                if (pts[i].steps > 0) { l2[ns] = log2(pts[i].tris); st[ns] = pts[i].steps; ls[ns++] = log(pts[i].steps); }
                if (pts[i].prims > 0) lp[np++] = log(pts[i].prims);
                /* memory below 1 MB is page and allocator noise: fitted from 1 MB up */
                if (pts[i].peak >= 1048576.0) { lmx[nm] = lx[n]; lm[nm++] = log(pts[i].peak); }
                if (pts[i].mrays > 0) { lrx[nr] = lx[n]; lr[nr++] = log(pts[i].mrays); }
                ++n;
            }
        double kb = NAN, ks = NAN, kp = NAN, bs = NAN, km = NAN, kr = NAN, c;
        fit(lx, lb, n, &kb, &c);
        if (ns == n) fit(lx, ls, ns, &ks, &c);
        if (ns >= 2) fit(l2, st, ns, &bs, &c);
        if (np == n) fit(lx, lp, np, &kp, &c);
        fit(lmx, lm, nm, &km, &c);
        fit(lrx, lr, nr, &kr, &c);
        fprintf(f, "%-14s %6d %10.3f %10.3f %10.3f %10.3f %14.3f %10.3f\n", names[ai], n, kb, km, kr, ks, bs, kp);
    }
    largest_ratios(f, pts, npts, names, na);
    if (csv) {
        FILE *cf = fopen(csv, "w");
        if (!cf) {
            fprintf(stderr, "sidx-bench scale: %s: %s\n", csv, strerror(errno));
            rc = BENCH_FAIL;
        } else {
            fprintf(cf, "scene,accel,tris,build_ms,mrays_per_s,steps_per_ray,prims_per_ray,bytes,build_peak_bytes,"
                        "build_heap_peak_bytes,mesh_bytes\n");
            for (int i = 0; i < npts; ++i)
                fprintf(cf, "%s,%s,%.0f,%.3f,%.4f,%.3f,%.3f,%.0f,%.0f,%.0f,%.0f\n", scene, names[pts[i].accel],
                        pts[i].tris, pts[i].build_ms, pts[i].mrays, pts[i].steps, pts[i].prims, pts[i].bytes,
                        pts[i].peak, pts[i].heap, pts[i].mesh);
            if (fclose(cf) != 0) rc = BENCH_FAIL;
        }
    }
    if (plot && !write_plots(plot, scene, pts, npts, names, na)) {
        fprintf(stderr, "sidx-bench scale: cannot write %s\n", plot);
        rc = BENCH_FAIL;
    }
    free(pts);
    free(hits);
    free(rec);
    sidx_mesh_free(&base);
    return rc;
}
