/* sidx.h — spatial index structures for ray tracing, with trace hooks.
 * Include this one header: it brings every public header of the library
 * but sidx/viz.h (the drawing and viewer helpers of libsidxviz.a, which
 * need Graphviz); see docs/architecture.md for the map. */
#ifndef SIDX_H
#define SIDX_H

#include "status.h"
#include "math.h"
#include "intersect.h"
#include "hook.h"
#include "sinks.h"
#include "mesh.h"
#include "accel.h"
#include "beam.h"
#include "bsp.h"
#include "bvh.h"
#include "exercise.h"
#include "grid.h"
#include "instance.h"
#include "kdtree.h"
#include "octree.h"
#include "lightbuffer.h"
#include "packet.h"
#include "parallel.h"
#include "rayclass.h"
#include "spawn.h"

#define SIDX_VERSION_MAJOR 0
#define SIDX_VERSION_MINOR 1
#define SIDX_VERSION_PATCH 0
const char *sidx_version(void);

#endif
