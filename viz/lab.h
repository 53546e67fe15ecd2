/* lab.h — the lab's entry layer: the library as the web page (sidx-lab.html,
 * `make web`) and sidx-lab (the same calls natively) drive it.
 *
 * One scene is open at a time, with up to SIDX_LAB_SLOTS structures built
 * over it side by side (slot 0 and slot 1).  Every answer is JSON text
 * written by the library (viz/json_write.c: the words sidx-view --html
 * uses), owned by this layer and valid until the next call of the same
 * function; integer results are 0 for success or an sidx_status, with the
 * message in sidx_lab_error().  The layer is single-threaded (builds use
 * one thread) and keeps no pointer to what the caller passed.
 *
 * The build and the query are those of sidx-step: sidx_scene_accel_build
 * (kd-slide with kdtree gets the slide's labelled tree) with the knobs of
 * viz/knobs.c, then one closest-hit query with a recorder hook, so a
 * trace here is, event for event, what `sidx-step --json --accel NAME
 * SCENE --ray R [knobs]` prints for the same ray (the trace's "ray_arg").
 *
 * Floats: ray and camera values arrive as doubles and are rounded to
 * float once here; answers echo the ray as those floats printed with 9
 * significant digits, which read back (strtof, sidx-step --ray) to the
 * same floats.  Other floats are printed with 6 significant digits. */
#ifndef SIDX_VIZ_LAB_H
#define SIDX_VIZ_LAB_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define SIDX_LAB_SLOTS 2
/* The page draws every triangle at every step: larger scenes are refused
 * (the same limit as sidx-view --html). */
#define SIDX_LAB_MAX_TRIANGLES 50000u
/* A trace keeps at most this many events ("truncated": true beyond). */
#define SIDX_LAB_MAX_EVENTS 200000u
/* SAH candidate events a build keeps (sidx_lab_build_events_json; sidx-view
 * --html's budget). */
#define SIDX_LAB_MAX_CANDIDATES 20000u
/* The largest heat map, in pixels. */
#define SIDX_LAB_MAX_PIXELS (2048u * 2048u)

/* The last error's message ("" after a success). */
const char *sidx_lab_error(void);

/* {"limit":50000,"scenes":[{"name":"kd-slide","dims":2,"triangles":8},...]}:
 * the built-in scenes at their default detail; dims 2 for a scene flat in z
 * (seen from +z, rays in z = 0), else 3. */
const char *sidx_lab_scenes(void);

/* Opens built-in scene `name` ("teapot", "kd-slide", "name:detail"), or,
 * from memory, an OBJ (or a PLY, by file_name's extension) of len bytes
 * that file_name names in messages.  Either drops every built structure.
 * Errors: the library's (SIDX_ERR_PARSE naming the file, line and what is
 * wrong; SIDX_ERR_BAD_GEOMETRY), SIDX_ERR_LIMIT for a scene over
 * SIDX_LAB_MAX_TRIANGLES ("... has N triangles; the page holds at most
 * 50000"), SIDX_ERR_INVALID_ARG.  On error the open scene is unchanged. */
int sidx_lab_open_scene(const char *name);
int sidx_lab_open_obj(const char *bytes, int len, const char *file_name);

/* The open scene: {"name","dims","vertices","triangles","bounds":[min xyz,
 * max xyz],"pos":[x,y,z,...],"idx":[a,b,c,...]}; "null" when none. */
const char *sidx_lab_scene_json(void);

/* The open scene's triangle count, -1 when none: what the page asks to
 * decide whether a build over it runs in a Web Worker, before it asks
 * for the whole mesh. */
int sidx_lab_scene_triangles(void);

/* The open scene as OBJ text ("v x y z" with 9 significant digits, which
 * read back to the same floats, and "f a b c"), so a program (sidx-step,
 * sidx-view) can open exactly the page's triangles; "" when none. */
const char *sidx_lab_scene_obj(void);

/* {"structures":[{"name","description","suits"},...]}: every registered
 * structure in registration order; suits is false for a structure that
 * does not fit the open scene (quadtree on a 3D scene: it never splits z). */
const char *sidx_lab_structures(void);

/* Builds structure `accel` in `slot` (0 or 1) over the open scene with the
 * knobs of knobs_json (NULL or "" = defaults), an object whose keys are
 *   bins, leaf_size, max_depth          whole numbers (sidx-step --bins ...)
 *   c_trav, c_tri, lambda, optimize     numbers > 0 (optimize = optimize_ms)
 *   empty_bonus                          a number in [0, 1)
 *   mailbox                              false = --no-mailbox (true: default)
 *   traversal                            "default", "stack", "ordered", "naive"
 * and whose values are checked by viz/knobs.c as the programs' flags are
 * (null = the default).  An unknown key, a bad value or a failed build
 * leaves the slot empty.  Errors: SIDX_ERR_INVALID_ARG (no scene, bad
 * slot or knob), SIDX_ERR_UNKNOWN_ACCEL, the build's errors. */
int sidx_lab_build(int slot, const char *accel, const char *knobs_json);

/* The slot's structure: {"slot","accel","args" (the knobs as sidx-step
 * flags),"stats":{"nodes","leaves","max_depth","sah_cost","bytes",
 * "prim_refs","build_ms"},"build":[the build events in the compact array
 * form of viz/json_write.h, less the SAH candidates],"cand_total",
 * "cand_kept","labels":{"id":"A",...}}; "null" for an empty slot.
 * build_ms is the recorded build's wall time (the only value that differs
 * between runs).  The candidates (a BVH of the teapot proposes over a
 * hundred thousand) are left out: the tree, its counts and labels are all
 * a rebuild after a knob change needs, and they are a fraction of the
 * text to write and parse. */
const char *sidx_lab_build_json(int slot);

/* Every build event of the slot in build order, the SAH candidates in
 * their places (the first cand_kept of cand_total): {"slot","build":[..],
 * "cand_total","cand_kept"}, the events of sidx-view --html's build view
 * and of the page's build mode and SAH curve; "null" for an empty slot. */
const char *sidx_lab_build_events_json(int slot);

/* Traces origin (ox, oy, oz), direction (dx, dy, dz) through the slot's
 * structure (closest hit, the knobs' traversal) and keeps the trace for
 * sidx_lab_trace_json and sidx_lab_diverge_json.  Errors:
 * SIDX_ERR_INVALID_ARG (empty slot, a zero or non-finite direction). */
int sidx_lab_trace(int slot, double ox, double oy, double oz, double dx, double dy, double dz);

/* The slot's last trace: {"slot","accel","ray":{"o":[..],"d":[..]},
 * "ray_arg":"ox,oy,oz,dx,dy,dz","hit":{"prim","t"} or null,
 * "counts":{"nodes" (NODE_ENTER),"boxes" (BOX_TEST),"triangles"
 * (PRIM_TEST),"mailbox" (MAILBOX_HIT),"events"},"truncated":false,
 * "ms" (the recorded query's wall time),
 * "events":[one object per event: sidx_event_to_json's (sidx-step --json)
 * plus "box" on NODE_ENTER and "line", the printer's text with the
 * node's label after it where the structure names its nodes ("  [L4]",
 * as sidx-step prints it)]}; "null" when the slot has no trace. */
const char *sidx_lab_trace_json(int slot);

/* Where the last traces of slot 0 and slot 1 part: {"step":K,"same":K-1,
 * "a":event,"b":event} where step K (1-based, as sidx-step counts) is the
 * first whose events differ in anything but the structure's name, and a
 * and b are the two events there (null past the end of one trace);
 * {"step":0,...} when the walks are the same event for event; "null"
 * unless both slots have a trace. */
const char *sidx_lab_diverge_json(void);

/* The heat map of the slot's structure seen by sidx-view's camera (viz/
 * camera.c: yaw, pitch in radians, zoom) in a w×h image: per pixel the
 * events of the closest-hit query of the ray through its centre, what =
 * 0 steps (nodes entered + triangle tests, as sidx-view's heat mode), 1
 * triangle tests.  The counts, w·h uint32 row by row from the top, are at
 * sidx_lab_heatmap_data() until the next heat map.  Errors:
 * SIDX_ERR_INVALID_ARG (empty slot, w or h < 1, more than
 * SIDX_LAB_MAX_PIXELS, what not 0 or 1), SIDX_ERR_NOMEM. */
int sidx_lab_heatmap(int slot, double yaw, double pitch, double zoom, int w, int h, int what);
const uint32_t *sidx_lab_heatmap_data(void);
/* {"w","h","what","max","total","ms"}: the last heat map's size, its
 * largest and summed counts and its wall time; "null" before the first. */
const char *sidx_lab_heatmap_json(void);

/* The camera ray through image point (px, py) (pixel x's centre is x + 0.5)
 * of a w×h image of the open scene, the heat map's camera:
 * {"o":[..],"d":[..],"ray_arg":"..."}; "null" without a scene. */
const char *sidx_lab_camera_ray(double yaw, double pitch, double zoom, int w, int h, double px, double py);

/* Primary rays without a hook, for speed: the heat map's w×h camera rays
 * traced through the slot's structure (closest hit, default traversal),
 * `repeat` times.  {"rays","hits","prim_sum","ms","cpu_ms","mrays_per_s"}
 * (ms wall time, cpu_ms the process's CPU time where the C library
 * measures it: in the browser it is wall time too): hits
 * and prim_sum (the sum of the hit triangles' ids) let two builds check
 * they found the same hits; "null" on error (sidx_lab_error says why). */
const char *sidx_lab_bench(int slot, double yaw, double pitch, double zoom, int w, int h, int repeat);

/* Frees everything (scene, structures, answers); the layer stays usable. */
void sidx_lab_reset(void);

#ifdef __cplusplus
}
#endif
#endif
