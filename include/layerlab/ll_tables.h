/*
 * layerlab — warped tables in the `measured` format that Mitsuba 3 and
 * pbrt-v4 read natively (Dupuy & Jakob 2018, "An Adaptive Parameterization
 * for Efficient Material Acquisition and Rendering"; the format and what a
 * producer computes: docs/formats.md). ll_bsdf_open reads these
 * files too (ll_bsdf.h, LL_BSDF_FORMAT_TABLES). Writing is in liblayerlab
 * only, not in liblayerlab_reader.
 *
 * Experimental: everything here is declared only when LL_EXPERIMENTAL is
 * defined before the include, and may change in a minor release; its
 * symbols are in the version nodes LAYERLAB_EXPERIMENTAL_1.0
 * (ll_tables_write_from_bsdf) and LAYERLAB_EXPERIMENTAL_1.1
 * (ll_material_write_tables).
 */
#include "ll_common.h"
#include "ll_bsdf.h"
#include "ll_material.h"

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
    LL_TABLES_RGB = 0,      /* field "rgb": Mitsuba 3's RGB variants          */
    LL_TABLES_SPECTRAL = 1  /* fields "spectra" and "wavelengths": pbrt-v4 and
                               Mitsuba 3's spectral variants                  */
} ll_tables_format;

/* Where a spectral table file's values come from: the opaque, untextured
 * material at wavelength_nm (the index-th of ll_tables_options.wavelengths),
 * as an opened file (any format; one channel, or three equal ones: its
 * luminance is taken). The writer releases *out after reading it, so one
 * wavelength's file is held at a time. A status other than LL_OK stops the
 * writer, which returns it. */
typedef ll_status (*ll_tables_spectrum_fn)(void *user, size_t index, double wavelength_nm,
                                           ll_bsdf **out);

/* Spectral files: the most wavelengths a file may have (one per nanometre
 * of the CIE 1931 tables, 360..830 nm). */
#define LL_TABLES_MAX_WAVELENGTHS 471

/* Grid sizes, accuracy and text of a table file. Set struct_size =
 * sizeof(ll_tables_options) (the INIT macro does); the library reads only
 * the fields struct_size covers.
 *  n_theta_i: incident elevations over [0, 90] degrees, denser towards
 *    grazing: theta = 90 sin(90 v) degrees for v uniform in [0, 1]
 *    (2..1024); a transmissive file across a net interface packs some of
 *    them around its critical angle instead (docs/formats.md);
 *  vndf_size: side of the visible-normal grid, nodes in u_theta and u_phi
 *    (2..4096);
 *  sample_size: side N of the sample grid at which the values are stored
 *    (2..4096);
 *  format: LL_TABLES_RGB or LL_TABLES_SPECTRAL;
 *  description: text of the file's "description" field (nullable: a
 *    default naming layerlab);
 * and, read for LL_TABLES_SPECTRAL only:
 *  wavelengths, n_wavelengths: the file's wavelengths in nm, strictly
 *    increasing, inside the span of the CIE 1931 tables (360..830 nm),
 *    1..LL_TABLES_MAX_WAVELENGTHS of them (the caller's array, read during
 *    the call);
 *  spectrum, spectrum_user: the material at each wavelength
 *    (ll_tables_write_from_bsdf calls it once per wavelength, in order;
 *    ll_material_write_tables sets its own);
 * and for every format:
 *  tolerance: how close the table must come to the file it is written
 *    from, per channel (0 takes 0.05; 0.005..1): the 99th percentile of
 *    the relative error of f at most tolerance, its 95th percentile at
 *    most 0.4 tolerance and its median at most 0.04 tolerance, where f cos
 *    is above 1% of its largest value (both elevations <= 80 degrees, half
 *    of the pairs near the mirror direction), and the albedo within 0.06
 *    tolerance at viewer elevations 0..85 degrees (so 5%, 2%, 0.2% and
 *    0.3% by default; R and T apart for a transmissive b, from both
 *    sides, each by quadrature of eval, a lobe under 1% of R + T not held
 *    to it); a transmissive b's f over its four lobes is held closer, its
 *    99th percentile to 0.6 and its 95th to 0.2 tolerance (3% and 1% by
 *    default).
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
    const double *wavelengths;
    size_t n_wavelengths;
    ll_tables_spectrum_fn spectrum;
    void *spectrum_user;
    double tolerance;
} ll_tables_options;

#define LL_TABLES_OPTIONS_INIT { sizeof(ll_tables_options), 0, 0, 0, LL_TABLES_RGB, NULL, \
                                 NULL, 0, NULL, NULL, 0.0 }

/* Write the tables of an opened, untextured file b (a .bsdf, or an opaque
 * table file) to path, atomically (a temporary file renamed over path when
 * complete; on failure path is untouched). The microfacet normal
 * distribution is derived from b's retro-reflection (the dominant
 * eigenvector of the operator of docs/formats.md, normalised so
 * that the integral of D cos over the hemisphere is 1), widened by a
 * Beckmann lobe of three times its roughness, one of its peak's width and a
 * uniform floor so that every part of the lobe gets grid cells; the values
 * are f cos stored with the jacobian rule, so that Mitsuba's `measured` plugin, pbrt-v4's reader of
 * the same tables and ll_bsdf_open give f back at the grid's nodes. The
 * file's "layerlab_metadata" field holds b's metadata, the grid sizes and
 * (sizes chosen by the tolerance) the figures measured. opts NULL takes the
 * defaults (every size chosen by the tolerance 0.05); monitor as in
 * ll_common.h (stages "ndf", "tables", "writing" for each grid tried, and
 * "spectra" for the grid chosen; the fraction goes once from 0 to 1 over
 * them all).
 *
 * With format LL_TABLES_SPECTRAL, b gives the warp (D, sigma, the VNDF
 * tables: one for all wavelengths; sizes left at 0 are chosen by measuring
 * b's own tables, which have that warp), and the field "spectra" holds, for
 * each wavelength in turn, f cos of opts->spectrum's file at the same
 * sample nodes (with the jacobian rule as above); the luminance that
 * sampling follows is that of the spectra (lit by D65, seen by the CIE 1931
 * observer, reader/cie.h), with the same floor. One wavelength's file and
 * values are held at a time: the values go to a scratch file and are
 * copied into place when the file is written, so memory holds the warp,
 * the luminance and the sample directions, not n_wavelengths tables.
 *
 * A transmissive b (eta != 1, or light transmitted) gives an extended
 * file, which only layerlab reads (Mitsuba 3's and pbrt-v4's `measured`
 * refuse it: it has no field of the plain names): a set of the tables
 * above per lobe and side, prefixed reflect_top., reflect_bottom.,
 * transmit_top., transmit_bottom. (the side of the fixed direction), the
 * field "layerlab_layout" naming them and "eta" the relative index; the
 * transmitted lobes warped about the refraction half vector (eta != 1) or
 * the z-flipped direction (eta 1); RGB only.
 * A textured b (a .bsdf with parameters) gives a textured table file, also
 * extended: "layerlab_layout" = "textured", the parameter block as the .bsdf
 * holds it ("layerlab_parameter_counts", "layerlab_parameter_positions",
 * float32), b's metadata as "layerlab_metadata", and for each basis k a
 * complete set of the format's fields named "basis<k>." + name, written as
 * the tables of that basis alone (its own grid chosen by the tolerance,
 * measured on the tables as stored), its grids "vndf", "luminance" and
 * "rgb" (or "spectra") as float16 (IEEE binary16), the other fields
 * float32.
 * ll_bsdf_open reads it as a textured handle: the parameters, names and
 * ll_bsdf_basis_coefficients as on b; evaluation blends the bases' tables
 * with the caller's basis weights, sampling picks a basis with probability
 * |w_k| / sum |w_j| (the pdf is that mixture). A spectral textured file
 * takes a textured file of b's parameters from opts->spectrum. A b both
 * textured and transmissive is refused (LL_ERROR_UNSUPPORTED).
 * LL_ERROR_INVALID_ARGUMENT: NULL b or path, bad options, a textured or
 * transmissive table file (write its tables from its .bsdf), all with a
 * message saying why; LL_ERROR_UNSUPPORTED for LL_TABLES_SPECTRAL with a
 * transmissive b;
 * LL_ERROR_IO; LL_ERROR_OUT_OF_MEMORY; LL_ERROR_CANCELLED. Thread-safe (b is
 * only read). */
LL_API ll_status ll_tables_write_from_bsdf(const ll_bsdf *b, const char *path,
                                           const ll_tables_options *opts,
                                           const ll_monitor *monitor);

/* The table file of a material (ll_material.h) at
 * path, atomically. rgb (nullable) is the opened file of its RGB build
 * (ll_material_build_layers, then a .bsdf), from which the warp is made; a
 * NULL rgb makes the library build it (written to a temporary .bsdf beside
 * path, opened, removed). LL_TABLES_RGB: ll_tables_write_from_bsdf(rgb).
 * LL_TABLES_SPECTRAL: the material is built again at each wavelength, one
 * channel at the resolution of its RGB build (ll_material_resolution with
 * build), with:
 *  - a named metal (eta=Au) at its measured n and k at that wavelength
 *    (the spectra of data/ior, interpolated as for the RGB averages);
 *  - a dielectric's eta, a roughness, an optical depth, a phase
 *    parameter: as written, one value for every wavelength;
 *  - an albedo given as R,G,B (diffuse, medium) as a smooth reflectance
 *    spectrum whose colour is that RGB: the sigmoid of a quadratic of
 *    Jakob & Hanika 2019, fitted per colour by Gauss-Newton on the CIELAB
 *    difference under D65 and the CIE 1931 observer in linear sRGB (the
 *    conversion ll_bsdf_open reads the file back with);
 * and refused before anything is built (LL_ERROR_INVALID_ARGUMENT, naming
 * the word and its line) when some other number is given as R,G,B (an
 * index, a roughness, a depth), or a word has no spectrum (a measured MERL
 * table). A word whose parameters are equal
 * at two wavelengths (a clear coat) is built once (a cache of word layers
 * as the builder of ll_material.h keeps). Each wavelength's build goes
 * through a temporary .bsdf beside path, removed at once, and only one is
 * held at a time. build (nullable) as for ll_material_build_layers;
 * tables as for ll_tables_write_from_bsdf (its spectrum fields are not
 * read; wavelengths are). monitor as in ll_common.h: one progress from 0
 * to 1 over the whole call (with rgb NULL, the RGB build takes the first
 * fifth of a spectral file's, the first 0.8 of an RGB file's); a cancel is
 * seen between wavelengths.
 * A swept material (rgb NULL, LL_TABLES_RGB) is built to its textured
 * .bsdf (ll_material_build, a temporary file beside path) and written as a
 * textured table file (ll_tables_write_from_bsdf).
 * Statuses: those of ll_material_build_layers and ll_tables_write_from_bsdf;
 * Statuses: those of ll_material_build_layers and ll_tables_write_from_bsdf;
 * LL_ERROR_INVALID_ARGUMENT for a transmissive material with
 * LL_TABLES_SPECTRAL (its tables are written in RGB only) and for a swept
 * one in LL_TABLES_SPECTRAL. */
LL_API ll_status ll_material_write_tables(const ll_material *material,
                                          const ll_build_options *build, const ll_bsdf *rgb,
                                          const char *path, const ll_tables_options *tables,
                                          const ll_monitor *monitor);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_TABLES_H */
#endif /* LL_EXPERIMENTAL */
