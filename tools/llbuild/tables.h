/*
 * llbuild --format measured (tables.c): the options, the checks made
 * before a build, and the build that writes the table file instead of the
 * .bsdf.
 */
#ifndef LLBUILD_TABLES_H
#define LLBUILD_TABLES_H

#ifndef LL_EXPERIMENTAL
#define LL_EXPERIMENTAL /* ll_tables_options */
#endif
#include <layerlab.h>

typedef struct llbuild_tables {
    int measured;          /* --format measured (else bsdf, the default)  */
    int grid_given;        /* one of --theta-i --vndf --sample given       */
    ll_tables_options opts;
    /* --wavelengths START:END:STEP: a spectral file (opts.format) */
    double wavelengths[LL_TABLES_MAX_WAVELENGTHS];
    /* Filled by llbuild_tables_build for the summary: */
    size_t n_nodes, n_orders, n_channels, bsdf_bytes;
    double albedo[3][4];   /* reflected, at 0, 30, 60, 80 degrees          */
    int transmissive;      /* set by llbuild_tables_check: a set of tables
                              per lobe and side (four times the sets)     */
} llbuild_tables;

/* Take --format, --theta-i, --vndf, --sample and --wavelengths out of argv (the rest is
 * left for llbuild's own parser, argc updated). Returns -1 to go on, else
 * an exit code (the message printed). */
int llbuild_tables_take_args(int *argc, char **argv, llbuild_tables *t);

/* Before building: a textured or transmissive stack is refused for
 * --format measured, saying why. Returns -1 to go on, else an exit code. */
int llbuild_tables_check(llbuild_tables *t, const ll_material *m, const char *input);

/* --dry-run: the table file's size for the grid (nothing for bsdf). */
void llbuild_tables_dry_run(const llbuild_tables *t);

/* Build the layers with options o and write the table file at output
 * (a spectral one through ll_material_write_tables)
 * (atomically: no file, and no temporary, after a failure or a cancel
 * through monitor). Statuses of the library calls; the message is
 * ll_last_error_message(). */
ll_status llbuild_tables_build(llbuild_tables *t, const ll_material *m,
                               const ll_build_options *o, const ll_monitor *monitor,
                               const char *output);

/* The summary after a build: the file read back and the layers' albedo. */
void llbuild_tables_summary(const llbuild_tables *t, const char *input, const char *output,
                            double seconds);

#endif
