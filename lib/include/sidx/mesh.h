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
 * Malformed numbers, out-of-range indices, faces with fewer than 3
 * vertices and NaN/Inf coordinates fail with SIDX_ERR_PARSE or
 * SIDX_ERR_BAD_GEOMETRY and a message "file:line: what". */
sidx_status sidx_mesh_load_obj(const char *path, sidx_mesh *out, sidx_error *err);
/* PLY, ascii and binary_little_endian: vertex x y z (float or double, other
 * properties skipped) and face vertex_indices (list of any int type). */
sidx_status sidx_mesh_load_ply(const char *path, sidx_mesh *out, sidx_error *err);
/* Picks the loader by extension (.obj, .ply), else by content. */
sidx_status sidx_mesh_load(const char *path, sidx_mesh *out, sidx_error *err);
/* Same, from memory (for fuzzing and tests); name is used in messages. */
sidx_status sidx_mesh_parse_obj(const char *data, size_t size, const char *name, sidx_mesh *out, sidx_error *err);
sidx_status sidx_mesh_parse_ply(const void *data, size_t size, const char *name, sidx_mesh *out, sidx_error *err);

/* Writes an OBJ (used by tests and to export built-in scenes). */
sidx_status sidx_mesh_save_obj(const sidx_mesh *m, const char *path, sidx_error *err);

sidx_aabb sidx_mesh_bounds(const sidx_mesh *m);
sidx_aabb sidx_mesh_triangle_bounds(const sidx_mesh *m, uint32_t tri);
static inline sidx_vec3 sidx_mesh_vertex(const sidx_mesh *m, uint32_t tri, int k)
{
    return m->positions[m->indices[3u * tri + (uint32_t)k]];
}

/* Built-in procedural scenes, so every test and lesson runs without files.
 * detail scales the triangle count (0 = the scene's default).
 *   "icosphere"  closed sphere, subdivided icosahedron (detail = levels, default 3: 1280 tris)
 *   "teapot"     a recognisable closed teapot-like object (body, lid, spout, handle) (~2–4k tris)
 *   "stadium"    teapot in a stadium: a small teapot in the middle of a huge ring + floor
 *   "soup"       random triangle soup in the unit cube (detail = count, default 2000; fixed seed)
 *   "menger"     Menger sponge of cubes (detail = level, default 2), many coplanar faces
 *   "flat2d"     the 2D lecture scene: 2D triangles in the xy plane extruded along z into
 *                thin prisms (z in [-0.05, 0.05]), viewed from +z
 *   "cornell"    the Cornell box (walls, two blocks)
 *   "grid"       tessellated plane, detail x detail quads (default 64)
 * Unknown names fail with SIDX_ERR_INVALID_ARG. */
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
