/* 17_spawn_secondary.c — checker driver: the origin of a secondary ray
 * offset off the surface by the hit point's error bound (deck 001,
 * "Ray-Triangle Intersection": "be careful about the numerical rounding
 * errors"; PBR §3.9.5).  Reference: the library's sidx_ray_spawn_origin
 * and sidx_ray_spawn_to (sidx/spawn.h), the points and their bounds from
 * sidx_triangle_point.  Reported as NOTE events: the status in count, the
 * origin's (or the direction's) bits in cell[] so that the comparison is
 * exact, tmin and tmax of a shadow ray in t_near and t_far. */
#include <string.h>
#include "check.h"

sidx_status spawn_origin(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 dir, sidx_vec3 *out);
sidx_status spawn_to(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 target, sidx_ray *out);

typedef struct sp_case {
    const char *name;
    const char *rules; /* the ids of the rules it tests */
    int rule;          /* the main one: its hint is the case's */
    int to; /* 0: spawn_origin(p, p_err, ng, v); 1: spawn_to(p, p_err, ng, v) */
    sidx_vec3 p, p_err, ng, v;
} sp_case;

#define SP_MAX 96
static sp_case cases[SP_MAX];
static size_t n_cases;

/* The hand-out's rules, in its order. */
enum { R_NONFINITE, R_ZERO_DIR, R_ZERO_NG, R_UNIT, R_OFFSET, R_SIDE, R_TANGENT, R_DOUBLE, R_ROUND, R_ZERO_OFF,
       R_OVERFLOW, R_UNTOUCHED, R_TO_ORIGIN, R_TO_DIR, R_TO_STATUS, NRULES };
static const ex_rule rules[NRULES] = {
    {"refuse-nonfinite", "a NaN or infinite component in p, p_err, ng or dir: SIDX_ERR_INVALID_ARG",
     "refuse with SIDX_ERR_INVALID_ARG a NaN or an infinite component in any of p, p_err, ng and dir (check all "
     "four before computing anything)"},
    {"refuse-zero-dir", "a zero dir (+0 or -0 components): SIDX_ERR_INVALID_ARG",
     "a zero dir (all components +0 or -0) leaves through no side: refuse it with SIDX_ERR_INVALID_ARG"},
    {"refuse-zero-ng", "a zero ng: SIDX_ERR_INVALID_ARG",
     "a zero ng has no direction to offset along: refuse it with SIDX_ERR_INVALID_ARG, *out untouched"},
    {"unit-normal", "n = ng / length(ng): ng may have any length",
     "ng may have any length: offset along the unit normal n = ng/|ng| (in double), or the offset grows with |ng|"},
    {"offset-by-error", "d = abs(n.x)·err.x + abs(n.y)·err.y + abs(n.z)·err.z, the origin moved by d·n",
     "\"be careful about the numerical rounding errors\": p is only known within p_err; offset the origin along the "
     "unit normal n = ng/|ng| by d = |n.x|·err.x + |n.y|·err.y + |n.z|·err.z, so no point of the error box lies "
     "beyond it"},
    {"side-of-dir", "d = -d when n·dir < 0: the origin goes to the side dir leaves through",
     "offset to the side the ray leaves through: d = -d when n·dir < 0 (a ray into the surface, a transmitted "
     "ray); a tangent dir (n·dir = 0) goes to the side of +ng"},
    {"tangent-plus", "a tangent dir (n·dir = 0) goes to the side of +ng",
     "a tangent dir (n·dir = 0, exactly) goes to the side of +ng: only n·dir < 0 flips the offset"},
    {"in-double", "n, d and p_k + off are computed in double, then rounded to float once",
     "compute n = ng/|ng|, d and p_k + d·n_k in double and round to float once, at the end: float arithmetic "
     "rounds at every step and the origin lands a float or two off the reference's"},
    {"round-away", "o_k rounded to float away from the surface, then one more float away (nextafterf)",
     "round the offset origin away from the surface: (float)(p_k + off) may round back towards it, take the next "
     "float away then; and one more float away (nextafterf) so the rounding can only add distance; off = 0 (a ±0 "
     "normal component) leaves p_k as it is"},
    {"zero-off-kept", "off = 0 leaves the component as it is (no nudge on a ±0 normal component)",
     "off = 0 (a ±0 normal component, or a zero error bound) leaves p_k exactly as it is: nudge a component only "
     "when off > 0 (towards +inf) or off < 0 (towards -inf)"},
    {"refuse-overflow", "an origin that is not finite (overflows float): SIDX_ERR_INVALID_ARG",
     "an offset origin that overflows float (any component) is refused with SIDX_ERR_INVALID_ARG, not returned"},
    {"untouched-on-refusal", "*out untouched on every refusal (every input check, an overflow on any axis)",
     "refuse with SIDX_ERR_INVALID_ARG, *out untouched: NaN or Inf in p, p_err, ng or dir, a zero dir, a zero ng, "
     "and an offset origin that overflows float on any axis: compute all three components first, write *out "
     "only on success"},
    {"shadow-origin", "spawn_to's origin is spawn_origin(p, p_err, ng, target - p)",
     "the shadow ray leaves towards the light: its origin is spawn_origin(p, p_err, ng, target - p), with the "
     "direction to the light from p"},
    {"shadow-dir", "spawn_to's direction is target - origin, t in [0, 1) (sidx_ray_init)",
     "the shadow ray: origin = spawn_origin(p, p_err, ng, target - p), direction target - origin (the offset "
     "origin, so the ray still ends at the light), t in [0, 1) with sidx_ray_init"},
    {"shadow-status", "spawn_to returns the status of either step, *out untouched when one refuses",
     "spawn_to returns the status of the step that refuses (spawn_origin's, or sidx_ray_init's), its ray left "
     "untouched"},
};

static sidx_vec3 V(float x, float y, float z) { return sidx_v3(x, y, z); }

static void add(const char *name, const char *ids, int rule, int to, sidx_vec3 p, sidx_vec3 e, sidx_vec3 ng,
                sidx_vec3 v)
{
    sp_case *c = &cases[n_cases++];
    c->name = name;
    c->rules = ids;
    c->rule = rule;
    c->to = to;
    c->p = p;
    c->p_err = e;
    c->ng = ng;
    c->v = v;
}

/* A point of triangle (a, b, c) at (u, v) with its bound, as a hit has it. */
static void on_tri(const char *name, const char *ids, int rule, int to, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float u, float w,
                   sidx_vec3 v)
{
    sidx_vec3 p = V(0, 0, 0), e = V(0, 0, 0);
    (void)sidx_triangle_point(a, b, c, u, w, &p, &e);
    add(name, ids, rule, to, p, e, sidx_v3_cross(sidx_v3_sub(b, a), sidx_v3_sub(c, a)), v);
}

static int setup(void)
{
    const float inf = INFINITY, nan = NAN;
    n_cases = 0;
    const sidx_vec3 A = V(0, 0, 0), B = V(1, 0, 0), C = V(0, 1, 0);          /* normal +z */
    const sidx_vec3 sa = V(0.3f, 0.1f, 0.7f), sb = V(1.9f, 0.4f, 0.2f), sc = V(0.6f, 1.7f, 1.1f); /* slanted */
    const sidx_vec3 fa = V(1e6f, 2e6f, -5e5f), fb = V(1e6f + 3, 2e6f + 1, -5e5f + 2), fc = V(1e6f - 1, 2e6f + 4, -5e5f + 1);
    on_tri("leaving up the normal, axis-aligned triangle (x, y untouched)", "offset-by-error round-away zero-off-kept", R_OFFSET, 0, A, B, C, 0.25f, 0.25f,
           V(0.3f, 0.2f, 1));
    on_tri("leaving into the surface (n·dir < 0), axis-aligned triangle", "side-of-dir zero-off-kept", R_SIDE, 0, A, B, C, 0.25f, 0.25f,
           V(0.3f, 0.2f, -1));
    on_tri("tangent dir (n·dir = 0): the side of +ng", "tangent-plus", R_TANGENT, 0, A, B, C, 0.25f, 0.25f, V(1, 1, 0));
    on_tri("slanted triangle, reflected ray", "offset-by-error unit-normal in-double round-away", R_OFFSET, 0, sa, sb, sc, 0.2f, 0.3f, V(-0.5f, 0.8f, 1));
    on_tri("slanted triangle, transmitted ray", "side-of-dir in-double round-away", R_SIDE, 0, sa, sb, sc, 0.2f, 0.3f, V(0.5f, -0.8f, -1));
    on_tri("slanted triangle at a vertex (u = v = 0)", "offset-by-error in-double round-away", R_OFFSET, 0, sa, sb, sc, 0, 0, V(-0.5f, 0.8f, 1));
    on_tri("slanted triangle on an edge (u + v = 1)", "offset-by-error side-of-dir in-double", R_OFFSET, 0, sa, sb, sc, 0.5f, 0.5f, V(0.5f, -0.8f, -1));
    on_tri("a point a million units out (a large error bound)", "offset-by-error in-double round-away", R_OFFSET, 0, fa, fb, fc, 0.3f, 0.3f,
           V(0.1f, 0.2f, 1));
    on_tri("a point a million units out, leaving the other side", "side-of-dir in-double", R_SIDE, 0, fa, fb, fc, 0.3f, 0.3f,
           V(-0.1f, -0.2f, -1));
    add("normal not unit length (|ng| = 7)", "unit-normal zero-off-kept", R_UNIT, 0, V(1, 2, 3), V(1e-6f, 2e-6f, 4e-6f), V(0, 7, 0),
        V(0, 1, 0));
    add("normal not unit length, oblique (|ng| = 9)", "unit-normal in-double", R_UNIT, 0, V(1, 2, 3), V(1e-6f, 2e-6f, 4e-6f),
        V(1, 4, 8), V(1, 1, 1));
    add("normal with -0 components (-y)", "zero-off-kept", R_ZERO_OFF, 0, V(0.5f, 0.25f, 2), V(1e-6f, 1e-6f, 1e-6f),
        V(-0.0f, -3, -0.0f), V(0, -1, 0));
    add("normal with -0 components, leaving into the surface", "side-of-dir zero-off-kept", R_SIDE, 0, V(0.5f, 0.25f, 2),
        V(1e-6f, 1e-6f, 1e-6f), V(-0.0f, -3, 0), V(0, 1, 0));
    add("offset below half an ulp of p (the rounding goes back to p)", "round-away", R_ROUND, 0, V(1, 1, 1),
        V(1e-9f, 1e-9f, 1e-9f), V(1, 1, 1), V(1, 1, 1));
    add("offset below half an ulp of p, negative side", "round-away side-of-dir", R_ROUND, 0, V(1, 1, 1), V(1e-9f, 1e-9f, 1e-9f),
        V(1, 1, 1), V(-1, -1, -1));
    add("zero error bound (d = 0: the origin is p)", "zero-off-kept", R_ZERO_OFF, 0, V(1, 2, 3), V(0, 0, 0), V(0, 0, 1), V(0, 0, 1));
    add("error bound along an axis the normal does not have", "offset-by-error zero-off-kept", R_OFFSET, 0, V(1, 2, 3), V(5e-5f, 0, 0), V(0, 0, 1),
        V(0, 0, 1));
    add("point at 0 (offset into denormals)", "round-away in-double", R_ROUND, 0, V(0, 0, 0), V(1e-30f, 1e-30f, 1e-30f), V(1, 2, 2),
        V(1, 0, 0));
    add("NaN in p", "refuse-nonfinite untouched-on-refusal", R_NONFINITE, 0, V(nan, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, 1), V(0, 0, 1));
    add("Inf in p_err", "refuse-nonfinite untouched-on-refusal", R_NONFINITE, 0, V(0, 0, 0), V(1e-6f, inf, 1e-6f), V(0, 0, 1), V(0, 0, 1));
    add("NaN in ng", "refuse-nonfinite untouched-on-refusal", R_NONFINITE, 0, V(0, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, nan), V(0, 0, 1));
    add("-Inf in dir", "refuse-nonfinite untouched-on-refusal", R_NONFINITE, 0, V(0, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, 1), V(0, -inf, 1));
    add("zero dir", "refuse-zero-dir untouched-on-refusal", R_ZERO_DIR, 0, V(0, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, 1), V(0, 0, 0));
    add("zero dir of -0 components", "refuse-zero-dir untouched-on-refusal", R_ZERO_DIR, 0, V(0, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, 1),
        V(-0.0f, -0.0f, -0.0f));
    add("zero normal", "refuse-zero-ng untouched-on-refusal", R_ZERO_NG, 0, V(0, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, 0), V(0, 0, 1));
    add("origin overflows float", "refuse-overflow untouched-on-refusal", R_OVERFLOW, 0, V(3.4028e38f, 0, 0), V(1e35f, 0, 0), V(1, 0, 0), V(1, 0, 0));
    add("near FLT_MAX, leaving towards 0 (no overflow)", "refuse-overflow offset-by-error", R_OVERFLOW, 0, V(3.4e38f, 0, 0), V(1e32f, 0, 0),
        V(1, 0, 0), V(-1, 0, 0));
    /* *out untouched on an overflow in y or z too: a component written
     * before the last one is checked shows */
    add("origin overflows float in y (x, z fine)", "refuse-overflow untouched-on-refusal", R_UNTOUCHED, 0,
        V(1, 3.4028e38f, 2), V(1e-6f, 1e35f, 1e-6f), V(0.1f, 1, 0.1f), V(0, 1, 0));
    add("origin overflows float in z, towards -inf (x, y fine)", "refuse-overflow untouched-on-refusal", R_UNTOUCHED, 0,
        V(1, 2, -3.4028e38f), V(1e-6f, 1e-6f, 1e35f), V(0.1f, 0.1f, -1), V(0, 0, -1));
    /* shadow rays */
    on_tri("shadow ray to a light above", "shadow-origin shadow-dir", R_TO_DIR, 1, sa, sb, sc, 0.2f, 0.3f, V(-2, 5, 6));
    on_tri("shadow ray to a light below (n·dir < 0)", "shadow-origin shadow-dir", R_TO_ORIGIN, 1, sa, sb, sc, 0.2f, 0.3f, V(3, -4, -2));
    on_tri("shadow ray from a million units out", "shadow-origin shadow-dir", R_TO_DIR, 1, fa, fb, fc, 0.3f, 0.3f, V(0, 0, 1e6f));
    add("shadow ray to a light at infinity", "shadow-status", R_TO_STATUS, 1, V(0, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, 1),
        V(0, 0, inf));
    add("shadow ray from a point with a zero normal", "shadow-status", R_TO_STATUS, 1, V(0, 0, 0), V(1e-6f, 1e-6f, 1e-6f), V(0, 0, 0),
        V(0, 0, 1));
    add("shadow ray from an origin that overflows float", "shadow-status", R_TO_STATUS, 1, V(3.4028e38f, 0, 0), V(1e35f, 0, 0),
        V(1, 0, 0), V(0, 0, 0));
    uint32_t st = 1717u;
    for (int i = 0; i < 30; ++i) {
        sidx_vec3 t[3];
        for (int j = 0; j < 3; ++j) t[j] = V(ex_rand(&st) * 20 - 10, ex_rand(&st) * 20 - 10, ex_rand(&st) * 20 - 10);
        const float u = ex_rand(&st) * 0.5f, w = ex_rand(&st) * 0.5f;
        const sidx_vec3 v = V(ex_rand(&st) * 2 - 1, ex_rand(&st) * 2 - 1, ex_rand(&st) * 2 - 1);
        if (i % 3 == 2)
            on_tri("random triangle, shadow ray", "shadow-origin shadow-dir", R_TO_DIR, 1, t[0], t[1], t[2], u, w, sidx_v3_scale(v, 30));
        else
            on_tri("random triangle, random dir", "offset-by-error side-of-dir in-double round-away", R_OFFSET, 0, t[0], t[1], t[2], u, w, v);
    }
    return 0;
}

static size_t num_cases(void) { return n_cases; }

static void describe(size_t i, ex_case_info *out)
{
    const sp_case *c = &cases[i];
    snprintf(out->name, sizeof out->name, "%s", c->name);
    snprintf(out->what, sizeof out->what,
             "%s(p=(%.9g, %.9g, %.9g), p_err=(%.9g, %.9g, %.9g), ng=(%.9g, %.9g, %.9g), %s=(%.9g, %.9g, %.9g))",
             c->to ? "spawn_to" : "spawn_origin", (double)c->p.x, (double)c->p.y, (double)c->p.z, (double)c->p_err.x,
             (double)c->p_err.y, (double)c->p_err.z, (double)c->ng.x, (double)c->ng.y, (double)c->ng.z,
             c->to ? "target" : "dir", (double)c->v.x, (double)c->v.y, (double)c->v.z);
    out->hint = rules[c->rule].hint;
    out->rules = c->rules;
}

static int32_t bits(float f)
{
    int32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

static float unbits(int32_t b)
{
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

/* node 0: the origin (count = status); node 1: the direction, [tmin, tmax). */
static void note(const sidx_hook *h, uint32_t what, sidx_status s, sidx_vec3 v, float t0, float t1)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "spawn";
    e.node = what;
    e.count = (uint32_t)s;
    e.cell[0] = bits(v.x);
    e.cell[1] = bits(v.y);
    e.cell[2] = bits(v.z);
    e.t_near = t0;
    e.t_far = t1;
    sidx_hook_emit(h, &e);
}

/* What the student's function left in *out when it refused: the marker. */
static const float MARK = -7.0f;

static void report(const sidx_hook *h, const sp_case *c, sidx_status s, sidx_vec3 o, const sidx_ray *r)
{
    if (!c->to) {
        note(h, 0, s, o, 0, 0);
        return;
    }
    note(h, 0, s, r->org, 0, 0);
    note(h, 1, s, r->dir, r->tmin, r->tmax);
}

static void run(size_t i, const sidx_hook *h, int ref)
{
    const sp_case *c = &cases[i];
    sidx_vec3 o = V(MARK, MARK, MARK);
    sidx_ray r;
    memset(&r, 0, sizeof r);
    r.org = r.dir = o;
    r.tmin = r.tmax = MARK;
    sidx_status s;
    if (!c->to) {
        s = ref ? sidx_ray_spawn_origin(c->p, c->p_err, c->ng, c->v, &o) : spawn_origin(c->p, c->p_err, c->ng, c->v, &o);
    } else if (ref) {
        sidx_hit hit = sidx_hit_none();
        hit.prim = 0;
        hit.p = c->p;
        hit.p_err = c->p_err;
        hit.ng = c->ng;
        s = sidx_ray_spawn_to(&hit, c->v, &r);
    } else {
        s = spawn_to(c->p, c->p_err, c->ng, c->v, &r);
    }
    report(h, c, s, o, &r);
}

static void reference(size_t i, const sidx_hook *h) { run(i, h, 1); }
static void student(size_t i, const sidx_hook *h) { run(i, h, 0); }

/* The hint by what differs: the status (the case's refusal rule, or
 * *out written on a refusal); the shadow ray's direction; the origin left
 * at p; on the other side of p (a tangent: +ng); a ±0 normal component
 * nudged; every component one float closer to p (the rounding away);
 * a float or two off (float arithmetic); the offset's size (|ng|). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const sp_case *c = &cases[i];
    if (!ref || !stu || ref->type != SIDX_EV_NOTE || stu->type != SIDX_EV_NOTE) return NULL;
    if (ref->count != stu->count) return c->to ? rules[R_TO_STATUS].hint : rules[c->rule].hint;
    if (ref->count != SIDX_OK) return c->to ? rules[R_TO_STATUS].hint : rules[R_UNTOUCHED].hint;
    if (ref->node == 1) return rules[R_TO_DIR].hint;
    sidx_vec3 dir = c->v;
    if (c->to) dir = sidx_v3_sub(c->v, c->p);
    const float p[3] = {c->p.x, c->p.y, c->p.z}, n[3] = {c->ng.x, c->ng.y, c->ng.z};
    float so = 0, ro = 0;
    /* closer: every moved component one or two floats nearer p than the
     * reference's (the rounding not taken away); near: within two floats
     * either way, some not (rounded more than once, in float) */
    int at_p = 1, near = 1, closer = 1, zero_moved = 0;
    for (int k = 0; k < 3; ++k) {
        const float r = unbits(ref->cell[k]), s = unbits(stu->cell[k]);
        if (s != p[k]) at_p = 0;
        if (r == p[k] && s != p[k] && n[k] == 0.0f) zero_moved = 1;
        const float up = r > p[k] ? INFINITY : -INFINITY, down = -up;
        const float r1 = nextafterf(r, down), r2 = nextafterf(r1, down);
        if (r != p[k] && s != r1 && s != r2) closer = 0;
        if (s != r && s != r1 && s != r2 && s != nextafterf(r, up) && s != nextafterf(nextafterf(r, up), up)) near = 0;
        ro += (r - p[k]) * n[k];
        so += (s - p[k]) * n[k];
    }
    if (at_p || (unbits(stu->cell[0]) == MARK && unbits(stu->cell[1]) == MARK && unbits(stu->cell[2]) == MARK))
        return c->to ? rules[R_TO_ORIGIN].hint : rules[R_OFFSET].hint;
    if ((ro > 0 && so < 0) || (ro < 0 && so > 0)) {
        if (c->to) return rules[R_TO_ORIGIN].hint;
        const double nd = (double)n[0] * dir.x + (double)n[1] * dir.y + (double)n[2] * dir.z;
        return nd == 0.0 ? rules[R_TANGENT].hint : rules[R_SIDE].hint;
    }
    if (zero_moved) return rules[R_ZERO_OFF].hint;
    if (closer) return rules[R_ROUND].hint;
    if (near) return rules[R_DOUBLE].hint;
    const float len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (len2 != 1.0f) return rules[R_UNIT].hint;
    return c->to ? rules[R_TO_ORIGIN].hint : rules[R_OFFSET].hint;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    const char *st = sidx_status_str((sidx_status)e->count);
    if (e->node == 1)
        snprintf(buf, size, "shadow ray dir=(%.9g, %.9g, %.9g) t in [%g, %g)", (double)unbits(e->cell[0]),
                 (double)unbits(e->cell[1]), (double)unbits(e->cell[2]), (double)e->t_near, (double)e->t_far);
    else
        snprintf(buf, size, "%s origin=(%.9g, %.9g, %.9g)", st ? st : "status ?", (double)unbits(e->cell[0]),
                 (double)unbits(e->cell[1]), (double)unbits(e->cell[2]));
    return 1;
}

const ex_driver ex_driver_this = {
    "17_spawn_secondary",
    "a secondary ray's origin offset by the hit point's error bound, and the shadow ray to a light",
    "deck 001, \"Ray-Triangle Intersection\" (\"be careful about the numerical rounding errors\"); PBR 3.9.5",
    setup, num_cases, describe, reference, student, hint, NULL, format, rules, NRULES,
};
