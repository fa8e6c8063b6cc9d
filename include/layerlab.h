/*
 * layerlab — layered material reflectance (Jakob, d'Eon, Jakob, Marschner,
 * "A Comprehensive Framework for Rendering Layered Materials", SIGGRAPH 2014).
 *
 * The umbrella header: include this one. The headers are plain C99 and
 * usable from C++ (the library itself is C99 with POSIX 2008 and GCC/Clang
 * atomics, for Linux). docs/api.md lists every declaration.
 *   ll_common.h       versions, status codes, error messages, monitor, allocator
 *   ll_quad.h         quadrature rules
 *   ll_layer.h        layers: words (diffuse, media, interfaces) and grammar
 *                     (adding, doubling); threads
 *   ll_bsdf.h         .bsdf files: open, evaluate, sample (the reader library)
 *   ll_bsdf_write.h   .bsdf files: write them from layers
 *   ll_tables.h       tables in the `measured` format (experimental)
 *   ll_material.h     the material language and its compiler
 *   ll_distribution.h one build over several processes (experimental)
 * Experimental declarations, which may change in a minor release, are seen
 * only with LL_EXPERIMENTAL defined before the include.
 */
#ifndef LAYERLAB_H
#define LAYERLAB_H

#include "layerlab/ll_common.h"
#include "layerlab/ll_quad.h"
#include "layerlab/ll_layer.h"
#include "layerlab/ll_bsdf.h"
#include "layerlab/ll_bsdf_write.h"
#include "layerlab/ll_tables.h"
#include "layerlab/ll_material.h"
#include "layerlab/ll_distribution.h"

#endif /* LAYERLAB_H */
