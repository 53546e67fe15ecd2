/* sidx/mesh.h — triangle meshes, file loaders and built-in scenes.
 *
 * A mesh is two flat arrays: positions (one sidx_vec3 per vertex) and
 * indices (three per triangle).  Triangle i is the i-th triangle in file
 * order after polygons are fan-triangulated (v0 v1 v2, v0 v2 v3, ...); every
 * hit reports that index.  The mesh owns its arrays: free it with
 * sidx_mesh_free.  A structure built over a mesh keeps a pointer to it, so
 * the mesh must outlive the structure (and not change, except through
 * sidx_accel_refit). */
#ifndef SIDX_MESH_H
#define SIDX_MESH_H

#include <stddef.h>
#include <stdint.h>
#include "math.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_mesh {
    sidx_vec3 *positions;
    uint32_t *indices;       /* 3 per triangle */
    uint32_t num_vertices;
    uint32_t num_triangles;
} sidx_mesh;

/* Frees the arrays and zeroes *m.  NULL and a zeroed mesh are fine. */
void sidx_mesh_free(sidx_mesh *m);

/* Takes copies of the given arrays.  Validates as sidx_mesh_validate. */
sidx_status sidx_mesh_from_arrays(sidx_mesh *out, const float *xyz, uint32_t num_vertices, const uint32_t *indices,
                                  uint32_t num_triangles, sidx_error *err);

/* Checks every coordinate is finite and every index < num_vertices.
 * Degenerate (zero-area) triangles are allowed: every test reports them
 * as misses.  Returns SIDX_ERR_BAD_GEOMETRY naming the first bad vertex or
 * triangle. */
sidx_status sidx_mesh_validate(const sidx_mesh *m, sidx_error *err);

/* Wavefront OBJ: `v x y z [w]` and `f` with any of the forms i, i/t, i//n,
 * i/t/n, negative (relative) indices; polygons are fan-triangulated.
 * Other statements (vt, vn, o, g, s, usemtl, mtllib, l, p) are ignored.
 * Malformed numbers, index 0 and faces with fewer than 3 vertices fail
 * with SIDX_ERR_PARSE; out-of-range indices and NaN/Inf coordinates
 * (including literals that overflow a float) with SIDX_ERR_BAD_GEOMETRY;
 * the message reads "file:line: what".  Positive indices may refer to
 * vertices defined later in the file.
 *
 * All loaders: a file with no faces (even an empty file) is not an error
 * but an empty mesh (0 triangles, non-NULL arrays).  On failure *out is
 * left untouched; arrays are allocated with malloc. */
sidx_status sidx_mesh_load_obj(const char *path, sidx_mesh *out, sidx_error *err);
/* PLY, ascii, binary_little_endian and binary_big_endian: vertex x y z
 * (float or double, other properties and elements skipped) and face
 * vertex_indices or vertex_index (list of any int type).  Truncated data
 * fails with SIDX_ERR_PARSE ("file:line: ..." for ascii, "file: byte N:
 * ..." for binary). */
sidx_status sidx_mesh_load_ply(const char *path, sidx_mesh *out, sidx_error *err);
/* Picks the loader by extension (.obj, .ply), else by content. */
sidx_status sidx_mesh_load(const char *path, sidx_mesh *out, sidx_error *err);
/* Same, from memory (for fuzzing and tests); name is used in messages
 * (NULL: "<memory>").  data need not be NUL-terminated. */
sidx_status sidx_mesh_parse_obj(const char *data, size_t size, const char *name, sidx_mesh *out, sidx_error *err);
sidx_status sidx_mesh_parse_ply(const void *data, size_t size, const char *name, sidx_mesh *out, sidx_error *err);

/* Writes an OBJ (used by tests and to export built-in scenes).  Floats
 * are written with 9 significant digits, so loading gives back the same
 * mesh bit for bit.  On failure the partial file is removed. */
sidx_status sidx_mesh_save_obj(const sidx_mesh *m, const char *path, sidx_error *err);

/* Box of the vertices the triangles use (vertices no triangle uses are
 * ignored); the empty box for a mesh without triangles. */
sidx_aabb sidx_mesh_bounds(const sidx_mesh *m);
/* The empty box if tri is out of range. */
sidx_aabb sidx_mesh_triangle_bounds(const sidx_mesh *m, uint32_t tri);
static inline sidx_vec3 sidx_mesh_vertex(const sidx_mesh *m, uint32_t tri, int k)
{
    return m->positions[m->indices[3u * tri + (uint32_t)k]];
}

/* Built-in procedural scenes, so every test and lesson runs without files.
 * detail scales the triangle count (0 = the scene's default).  Y is up
 * except in flat2d.  Closed objects (icosphere, teapot parts, menger cubes)
 * share vertices along edges and face outward.
 *   "icosphere"  closed sphere, subdivided icosahedron (detail = levels, default 3: 1280 tris)
 *   "teapot"     a recognisable closed teapot-like object (body, lid, spout, handle) (~2–4k tris;
 *                detail = segments around the body, default 40: 3412 tris)
 *   "stadium"    teapot in a stadium: a small teapot in the middle of a huge ring + floor
 *                (teapot ~1 unit wide at the origin, stands of radius 800..1000; detail =
 *                segments around the stands, default 128)
 *   "soup"       random triangle soup in the unit cube (detail = count, default 2000; fixed seed;
 *                corners within 0.05 of each triangle's centre)
 *   "menger"     Menger sponge of cubes in [-1,1]^3 (detail = level, default 2: 4800 tris),
 *                many coplanar faces
 *   "flat2d"     the 2D lecture scene, viewed from +z: one triangle per 2D shape, tilted so
 *                the corner opposite its shortest side is at z = 0 and the other two at
 *                +0.05 and -0.05.  From +z it is the drawn shape; a ray in the plane z = 0
 *                (a 2D ray) hits it only where it crosses its "spine", the longest median,
 *                so it misses a shape whose corner it merely clips.  detail = number of
 *                shapes = triangles (default 16 hand-placed; more are random)
 *   "cornell"    the Cornell box (walls, light, two closed blocks: 36 tris), the published
 *                measurements in mm scaled by 0.01; walls face into the room; detail ignored
 *   "grid"       tessellated plane y = 0, x,z in [-1,1], facing +y, detail x detail quads
 *                (default 64)
 *   "kd-slide"   deck 000 "kD-Tree Example": 8 triangles in the xy plane (x in [1, 9.5],
 *                y in [0.5, 7.5]), each tilted about the vertical line through its centroid
 *                (z within ±0.05) so a ray in z = 0 meets it; viewed from +z; with "kdtree",
 *                sidx_scene_accel_build gives the slide's tree; detail ignored
 *   "city"       detail = N buildings (default 1) of sidx_city_make (sidx/instance.h) at
 *                building detail 8 (~530-1100 tris each), flattened into one mesh
 *   "heightfield" rolling terrain: detail x detail quads over x,z in [-1,1], y a sum of two
 *                sine waves (|y| <= 0.1), 2 detail^2 triangles (default 32; 2897: 16.8M),
 *                the surface of `sidx-bench scale --scene heightfield`
 * Unknown names fail with SIDX_ERR_INVALID_ARG, a detail above the scene's
 * maximum (e.g. icosphere 10, menger 5, grid 4096, heightfield 8192) with SIDX_ERR_LIMIT. */
sidx_status sidx_scene_make(const char *name, uint32_t detail, sidx_mesh *out, sidx_error *err);
/* Names of the built-in scenes, NULL-terminated. */
const char *const *sidx_scene_names(void);
/* Loads a file if `spec` names an existing file, else a built-in scene
 * ("name" or "name:detail"). Programs take their SCENE argument this way. */
sidx_status sidx_scene_open(const char *spec, sidx_mesh *out, sidx_error *err);

#ifdef __cplusplus
}
#endif
#endif
