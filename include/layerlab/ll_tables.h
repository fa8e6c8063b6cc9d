/*
 * layerlab — warped tables in the `measured` format that Mitsuba 3 and
 * pbrt-v4 read natively (Dupuy & Jakob 2018, "An Adaptive Parameterization
 * for Efficient Material Acquisition and Rendering"; the format and what a
 * producer computes: docs/measured-format.md). ll_bsdf_open reads these
 * files too (ll_bsdf.h, LL_BSDF_FORMAT_TABLES). Writing is in liblayerlab
 * only, not in liblayerlab_reader.
 *
 * Experimental: everything here is declared only when LL_EXPERIMENTAL is
 * defined before the include, and may change in a minor release (spectral
 * files); its symbols are in the version node LAYERLAB_EXPERIMENTAL_1.0.
 */
#include "ll_common.h"
#include "ll_bsdf.h"

/* (The include guard sits inside the LL_EXPERIMENTAL block, so that a file
 * included once without LL_EXPERIMENTAL and then again with it gets the
 * declarations.) */
#ifdef LL_EXPERIMENTAL
#ifndef LAYERLAB_LL_TABLES_H
#define LAYERLAB_LL_TABLES_H

#ifdef __cplusplus
extern "C" {
#endif

/* What the table file stores per direction pair. */
typedef enum {
    LL_TABLES_RGB = 0   /* field "rgb": Mitsuba 3's RGB variants */
} ll_tables_format;

/* Grid sizes, accuracy and text of a table file. Set struct_size =
 * sizeof(ll_tables_options) (the INIT macro does); the library reads only
 * the fields struct_size covers.
 *  n_theta_i: incident elevations over [0, 90] degrees, denser towards
 *    grazing: theta = 90 sin(90 v) degrees for v uniform in [0, 1]
 *    (2..1024);
 *  vndf_size: side of the visible-normal grid, nodes in u_theta and u_phi
 *    (2..4096);
 *  sample_size: side N of the sample grid at which the values are stored
 *    (2..4096);
 *  format: LL_TABLES_RGB;
 *  description: text of the file's "description" field (nullable: a
 *    default naming layerlab);
 *  tolerance: how close the table must come to the file it is written
 *    from, per channel (0 takes 0.05; 0.005..1): the 99th percentile of
 *    the relative error of f at most tolerance, its 95th percentile at
 *    most 0.4 tolerance and its median at most 0.04 tolerance, where f cos
 *    is above 1% of its largest value (both elevations <= 80 degrees, half
 *    of the pairs near the mirror direction), and the albedo within 0.06
 *    tolerance at viewer elevations 0..85 degrees (so 5%, 2%, 0.2% and
 *    0.3% by default).
 * A size of 0 is chosen by the tolerance: the writer measures each table
 * it makes against b and grows the sizes left at 0 (the elevations when
 * the albedo misses, the VNDF and sample grids when f misses) until the
 * figures are met, the ladders end (192 elevations, VNDF and sample grids
 * of 256^2) or the next grid would take more than the larger of b's file
 * size and 16 MB; the figures reached are in the file's
 * "layerlab_metadata" ("figures", with "met" false if they fall short).
 * When all three sizes are given, the table is written at that grid and
 * nothing is measured. */
typedef struct ll_tables_options {
    size_t struct_size;
    size_t n_theta_i;
    size_t vndf_size;
    size_t sample_size;
    ll_tables_format format;
    const char *description;
    double tolerance;
} ll_tables_options;

#define LL_TABLES_OPTIONS_INIT { sizeof(ll_tables_options), 0, 0, 0, LL_TABLES_RGB, NULL, 0.0 }

/* Write the tables of an opened, untextured, opaque file b (a .bsdf, or a
 * table file) to path, atomically (a temporary file renamed over path when
 * complete; on failure path is untouched). The microfacet normal
 * distribution is derived from b's retro-reflection (the dominant
 * eigenvector of the operator of docs/measured-format.md, normalised so
 * that the integral of D cos over the hemisphere is 1), widened by a
 * Beckmann lobe of three times its roughness, one of its peak's width and a
 * uniform floor so that every part of the lobe gets grid cells; the values are f cos stored with the
 * jacobian rule, so that Mitsuba's `measured` plugin, pbrt-v4's reader of
 * the same tables and ll_bsdf_open give f back at the grid's nodes. The
 * file's "layerlab_metadata" field holds b's metadata, the grid sizes and
 * (sizes chosen by the tolerance) the figures measured. opts NULL takes the
 * defaults (every size chosen by the tolerance 0.05); monitor as in
 * ll_common.h (stages "ndf", "tables", "writing" for each grid tried; the
 * fraction goes once from 0 to 1 over them all).
 * LL_ERROR_INVALID_ARGUMENT: NULL b or path, bad options, a textured file
 * (several basis functions) or a transmissive one (eta != 1, or light
 * transmitted), all with a message saying why the format cannot hold it;
 * LL_ERROR_IO; LL_ERROR_OUT_OF_MEMORY; LL_ERROR_CANCELLED. Thread-safe (b is
 * only read). */
LL_API ll_status ll_tables_write_from_bsdf(const ll_bsdf *b, const char *path,
                                           const ll_tables_options *opts,
                                           const ll_monitor *monitor);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_TABLES_H */
#endif /* LL_EXPERIMENTAL */
