/* sidx.h — spatial index structures for ray tracing, with trace hooks.
 * Include this one header; see docs/architecture.md for the map. */
#ifndef SIDX_H
#define SIDX_H

#include "status.h"
#include "math.h"
#include "intersect.h"
#include "hook.h"
#include "sinks.h"
#include "mesh.h"
#include "accel.h"

#define SIDX_VERSION_MAJOR 0
#define SIDX_VERSION_MINOR 1
#define SIDX_VERSION_PATCH 0
const char *sidx_version(void);

#endif
