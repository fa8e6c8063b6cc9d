/*
 * llbuild --format measured: the material built as usual, then written as
 * the warped tables that Mitsuba 3's and pbrt-v4's `measured` BSDF read
 * (docs/formats.md) instead of a .bsdf file.
 *
 * With --wavelengths START:END:STEP the file is spectral: the library
 * builds it all (ll_material_write_tables: the warp from the RGB build, the
 * values from the material built again at each wavelength), after checking
 * that every word has a spectrum; the summary's albedo is then the file's,
 * by its own sampler.
 *
 * The tables are made from an opened .bsdf (ll_tables_write_from_bsdf), so
 * the built layers go first to a .bsdf beside the output, which is opened
 * and unlinked at once: the handle holds its data, and the name is gone
 * before the (long) table step starts. The table file itself is written
 * atomically by the library; a failed or cancelled run leaves neither file.
 */
#define LL_EXPERIMENTAL /* ll_tables_write_from_bsdf, ll_material_is_opaque */
#include <layerlab.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "tables.h"

/* A grid size: a whole number in 2..4096 (llconvert's rule). */
static int parse_grid(const char *text, const char *option, size_t *out)
{
    char *end;
    long v;
    if (!text) {
        fprintf(stderr, "llbuild: %s needs a value\n", option);
        return 0;
    }
    v = strtol(text, &end, 10);
    if (*text == '\0' || *end != '\0' || v < 2 || v > 4096) {
        fprintf(stderr, "llbuild: %s wants a whole number in 2..4096, not '%s'\n", option,
                text);
        return 0;
    }
    *out = (size_t)v;
    return 1;
}

/* --wavelengths START:END:STEP in nm: START, START + STEP, ... up to END
 * (included when it falls on the grid), inside the CIE 1931 tables'
 * 360..830 nm, at most LL_TABLES_MAX_WAVELENGTHS of them. */
static int parse_wavelengths(const char *text, llbuild_tables *t)
{
    double v[3], count;
    const char *p = text;
    char *end;
    size_t k, n;
    if (!text) {
        fprintf(stderr, "llbuild: --wavelengths needs a value START:END:STEP (nm)\n");
        return 0;
    }
    for (k = 0; k < 3; ++k) {
        v[k] = strtod(p, &end);
        if (end == p || (k < 2 && *end != ':') || (k == 2 && *end != '\0') || !isfinite(v[k])) {
            fprintf(stderr, "llbuild: --wavelengths wants START:END:STEP in nm (e.g. "
                            "360:830:10), not '%s'\n",
                    text);
            return 0;
        }
        p = end + 1;
    }
    if (v[0] < 360.0 || v[1] > 830.0 || v[0] > v[1]) {
        fprintf(stderr, "llbuild: --wavelengths %s: START and END must lie in 360..830 nm "
                        "(the span of the CIE 1931 tables the file's colour is read with), "
                        "START <= END\n",
                text);
        return 0;
    }
    if (!(v[2] > 0.0)) {
        fprintf(stderr, "llbuild: --wavelengths %s: STEP must be > 0 nm\n", text);
        return 0;
    }
    /* The last node within END (a hair of rounding allowed). */
    count = floor((v[1] - v[0]) / v[2] + 1e-9) + 1.0;
    if (count > (double)LL_TABLES_MAX_WAVELENGTHS) {
        fprintf(stderr, "llbuild: --wavelengths %s gives %.0f wavelengths; at most %d (one "
                        "per nm over 360..830): take a larger STEP\n",
                text, count, LL_TABLES_MAX_WAVELENGTHS);
        return 0;
    }
    n = (size_t)count;
    for (k = 0; k < n; ++k)
        t->wavelengths[k] = v[0] + (double)k * v[2];
    if (t->wavelengths[n - 1] > 830.0)
        t->wavelengths[n - 1] = 830.0;
    t->opts.format = LL_TABLES_SPECTRAL;
    t->opts.wavelengths = t->wavelengths;
    t->opts.n_wavelengths = n;
    return 1;
}

int llbuild_tables_take_args(int *argc, char **argv, llbuild_tables *t)
{
    int i, kept = 1;
    ll_tables_options defaults = LL_TABLES_OPTIONS_INIT;
    memset(t, 0, sizeof *t);
    t->opts = defaults;
    for (i = 1; i < *argc; ++i) {
        const char *o = argv[i], *next = i + 1 < *argc ? argv[i + 1] : NULL;
        size_t *grid = !strcmp(o, "--theta-i") ? &t->opts.n_theta_i
                       : !strcmp(o, "--vndf") ? &t->opts.vndf_size
                       : !strcmp(o, "--sample") ? &t->opts.sample_size
                                                : NULL;
        if (!strcmp(o, "--table-tolerance")) {
            char *end;
            t->opts.tolerance = next ? strtod(next, &end) : 0.0;
            if (!next || *next == '\0' || *end != '\0' ||
                !(t->opts.tolerance >= 0.005 && t->opts.tolerance <= 1.0)) {
                fprintf(stderr, "llbuild: --table-tolerance wants a number in 0.005..1, not "
                                "'%s'\n",
                        next ? next : "(missing)");
                return 1;
            }
            t->grid_given = 1;
            ++i;
        } else if (!strcmp(o, "--format")) {
            if (next && !strcmp(next, "measured")) {
                t->measured = 1;
            } else if (next && !strcmp(next, "bsdf")) {
                t->measured = 0;
            } else {
                fprintf(stderr, "llbuild: --format: expected bsdf or measured, not '%s'\n",
                        next ? next : "(missing)");
                return 1;
            }
            ++i;
        } else if (!strcmp(o, "--wavelengths")) {
            if (!parse_wavelengths(next, t))
                return 1;
            ++i;
        } else if (grid) {
            if (!parse_grid(next, o, grid))
                return 1;
            t->grid_given = 1;
            ++i;
        } else {
            argv[kept++] = argv[i];
        }
    }
    argv[kept] = NULL;
    *argc = kept;
    if (t->grid_given && !t->measured) {
        fprintf(stderr, "llbuild: --theta-i, --vndf, --sample and --table-tolerance size the "
                        "tables of --format measured; a .bsdf file has no such grid\n");
        return 1;
    }
    if (t->opts.format == LL_TABLES_SPECTRAL && !t->measured) {
        fprintf(stderr, "llbuild: --wavelengths makes a spectral table file of --format "
                        "measured; a .bsdf file is RGB or monochrome\n");
        return 1;
    }
    return -1;
}

int llbuild_tables_check(llbuild_tables *t, const ll_material *m, const char *input)
{
    if (!t->measured)
        return -1;
    if (ll_material_axis_count(m) > 0 && t->opts.format == LL_TABLES_SPECTRAL) {
        fprintf(stderr,
                "llbuild: %s: a swept (textured) material is written as RGB tables (a set "
                "per basis); spectral textured tables are not made by this version: leave out "
                "--wavelengths, or build it as a .bsdf (--format bsdf)\n",
                input);
        return 1;
    }
    t->transmissive = !ll_material_is_opaque(m);
    if (t->transmissive && t->opts.format == LL_TABLES_SPECTRAL) {
        fprintf(stderr,
                "llbuild: %s: a transmissive stack (its bottom word lets light through) is "
                "written as RGB tables only (its tables of every lobe are not written "
                "spectral by this version; the `measured` format itself stores reflection only); "
                "leave out --wavelengths or build it as a .bsdf (--format bsdf)\n",
                input);
        return 1;
    }
    return -1;
}

/* The data the tables hold (the field table and text add a few hundred
 * bytes): ndf and sigma (2 x 256 each), theta_i, vndf, luminance, rgb (or
 * spectra and wavelengths). */
static double table_bytes(const ll_tables_options *o, int transmissive)
{
    double n_ti = (double)o->n_theta_i, nv = (double)o->vndf_size,
           ns = (double)o->sample_size;
    double values = o->format == LL_TABLES_SPECTRAL ? (double)o->n_wavelengths : 3.0;
    /* A transmissive stack: a set per lobe and side, each with its
     * albedo per elevation, and its grids float16. */
    double sets = transmissive ? 4.0 : 1.0, grid = transmissive ? 2.0 : 4.0;
    return grid * sets * (n_ti * nv * nv + (1.0 + values) * n_ti * ns * ns) +
           4.0 * (sets * (2.0 * 2 * 256 + (transmissive ? n_ti : 0.0)) + n_ti + 1 +
                  (o->format == LL_TABLES_SPECTRAL ? values : 0.0));
}

/* " x N wavelengths (A..B nm)" of a spectral file, nothing otherwise. */
static void spectral_suffix(const llbuild_tables *t)
{
    if (t->opts.format == LL_TABLES_SPECTRAL)
        printf(" x %zu wavelengths (%g..%g nm)", t->opts.n_wavelengths, t->wavelengths[0],
               t->wavelengths[t->opts.n_wavelengths - 1]);
}

void llbuild_tables_dry_run(const llbuild_tables *t)
{
    const ll_tables_options *o = &t->opts;
    ll_tables_options lo = *o, hi = *o;
    if (!t->measured)
        return;
    if (o->n_theta_i && o->vndf_size && o->sample_size) {
        printf("tables       %zu incident elevations x %zu^2 visible-normal x %zu^2 sample grid",
               o->n_theta_i, o->vndf_size, o->sample_size);
        spectral_suffix(t);
        printf(": about %.2f MiB (the `measured` file written instead of the .bsdf above)\n",
               table_bytes(o, t->transmissive) / 1048576.0);
        return;
    }
    /* The library's ladders (ll_tables.h): 16..192 elevations, sample
     * grids 32..256, the VNDF grid the sample grid's but at least 64. */
    if (!o->n_theta_i) {
        lo.n_theta_i = 16;
        hi.n_theta_i = 192;
    }
    if (!o->sample_size) {
        lo.sample_size = 32;
        hi.sample_size = 256;
    }
    if (!o->vndf_size) {
        lo.vndf_size = lo.sample_size > 64 ? lo.sample_size : 64;
        hi.vndf_size = hi.sample_size > 64 ? hi.sample_size : 64;
    }
    printf("tables       sized by the tolerance %g, known once measured: from %zu x %zu^2 x "
           "%zu^2 (about %.2f MiB) up to %zu x %zu^2 x %zu^2 (about %.2f MiB)",
           o->tolerance != 0.0 ? o->tolerance : 0.05, lo.n_theta_i, lo.vndf_size,
           lo.sample_size, table_bytes(&lo, t->transmissive) / 1048576.0, hi.n_theta_i, hi.vndf_size,
           hi.sample_size, table_bytes(&hi, t->transmissive) / 1048576.0);
    spectral_suffix(t);
    printf(" (the `measured` file written instead of the .bsdf above)\n");
}

static const double summary_degrees[4] = { 0.0, 30.0, 60.0, 80.0 };

/* What the summary shows of the built layers, taken before they are freed. */
static void remember_layers(llbuild_tables *t, ll_layer *const *layers, size_t n_channels)
{
    size_t a, c;
    t->n_nodes = ll_layer_node_count(layers[0]);
    t->n_orders = ll_layer_order_count(layers[0]);
    t->n_channels = n_channels;
    for (c = 0; c < n_channels && c < 3; ++c)
        for (a = 0; a < 4; ++a) {
            double transmitted = 0.0;
            ll_layer_albedo(layers[c], cos(summary_degrees[a] * 3.14159265358979323846 / 180.0),
                            &t->albedo[c][a], &transmitted);
        }
}

/* Albedo per channel for light seen along cos theta = mu, by the file's
 * own sampler: the mean of the weights f cos / pdf over 64 x 64 strata
 * (the tables sample nearly in proportion to f cos). */
static void file_albedo(const ll_bsdf *b, double mu, double out[3])
{
    const int n = 64;
    double wo[3];
    int i, j, c;
    wo[0] = sqrt(1.0 - mu * mu);
    wo[1] = 0.0;
    wo[2] = mu;
    out[0] = out[1] = out[2] = 0.0;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            double u[2], wi[3], pdf = 0.0, f[3];
            u[0] = (i + 0.5) / n;
            u[1] = (j + 0.5) / n;
            if (ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, f) == LL_OK &&
                pdf > 0.0)
                for (c = 0; c < 3; ++c)
                    out[c] += f[c] * fabs(wi[2]) / pdf / ((double)n * n);
        }
}

void llbuild_tables_summary(const llbuild_tables *t, const char *input, const char *output,
                            double seconds)
{
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    size_t a, c;
    if (ll_bsdf_open(output, NULL, &b) != LL_OK || ll_bsdf_get_info(b, &info) != LL_OK) {
        fprintf(stderr, "llbuild: cannot read back %s: %s\n", output, ll_last_error_message());
        ll_bsdf_release(b);
        return;
    }
    printf("%s -> %s (format measured)\n", input, output);
    if (info.n_bases > 1) {
        printf("tables       textured: a set per basis, %zu bases of %zu parameters, each "
               "grid chosen by the tolerance\n",
               info.n_bases, info.n_parameters);
        printf("file         %zu bytes (the textured .bsdf: %zu bytes)\n", info.file_size,
               t->bsdf_bytes);
        printf("wall time    %.2f s\n", seconds);
        ll_bsdf_release(b);
        return;
    }
    if (info.n_wavelengths > 0)
        printf("resolution   %zu nodes x %zu Fourier orders (the layers of the warp, 3 "
               "channels, and of each wavelength, 1)\n",
               t->n_nodes, t->n_orders);
    else
        printf("resolution   %zu nodes x %zu Fourier orders, %zu channel%s (the layers the "
               "tables are made from)\n",
               t->n_nodes, t->n_orders, t->n_channels, t->n_channels == 1 ? "" : "s");
    {
        /* The grid the file holds (chosen by the tolerance, or given). */
        const char *g = info.metadata ? strstr(info.metadata, "\"theta_i\": ") : NULL;
        const char *f = info.metadata ? strstr(info.metadata, "\"figures\": {") : NULL;
        unsigned long n_ti = 0, nv = 0, ns = 0;
        if (g)
            sscanf(g, "\"theta_i\": %lu, \"vndf\": [%lu, %*u], \"sample\": [%lu", &n_ti, &nv,
                   &ns);
        printf("tables       %lu incident elevations x %lu^2 visible-normal x %lu^2 sample "
               "grid\n",
               n_ti, nv, ns);
        if (f) {
            const char *end = strchr(f, '}');
            printf("measured     %.*s\n", end ? (int)(end - f + 1) : 0, f);
        }
    }
    if (info.n_wavelengths > 0) {
        printf("spectra      %zu wavelengths, %g..%g nm (read back as linear sRGB: D65, CIE "
               "1931)\n",
               info.n_wavelengths, t->wavelengths[0], t->wavelengths[info.n_wavelengths - 1]);
        printf("file         %zu bytes\n", info.file_size);
        printf("albedo       (R G B) reflected, of the file (its sampler; linear sRGB)\n");
        for (a = 0; a < 4; ++a) {
            double alb[3];
            file_albedo(b, cos(summary_degrees[a] * 3.14159265358979323846 / 180.0), alb);
            printf("  %4.0f deg   %.4f %.4f %.4f\n", summary_degrees[a], alb[0], alb[1],
                   alb[2]);
        }
        printf("wall time    %.2f s\n", seconds);
        ll_bsdf_release(b);
        return;
    }
    printf("file         %zu bytes (the .bsdf of these layers: %zu bytes)\n", info.file_size,
           t->bsdf_bytes);
    printf("albedo       %sreflected, of the layers\n", t->n_channels == 3 ? "(R G B) " : "");
    for (a = 0; a < 4; ++a) {
        printf("  %4.0f deg  ", summary_degrees[a]);
        for (c = 0; c < t->n_channels; ++c)
            printf(" %.4f", t->albedo[c][a]);
        printf("\n");
    }
    printf("wall time    %.2f s\n", seconds);
    ll_bsdf_release(b);
}

/* A new empty file beside output (where the user chose to have room)
 * under a unique name, into *name (free with free). */
static ll_status temp_beside(const char *output, char **name)
{
    static const char suffix[] = ".llbuild-XXXXXX";
    size_t n = strlen(output);
    int fd;
    if (!(*name = malloc(n + sizeof suffix)))
        return LL_ERROR_OUT_OF_MEMORY;
    memcpy(*name, output, n);
    memcpy(*name + n, suffix, sizeof suffix);
    fd = mkstemp(*name);
    if (fd < 0) {
        fprintf(stderr, "llbuild: cannot create a file beside %s: %s\n", output,
                strerror(errno));
        free(*name);
        *name = NULL;
        return LL_ERROR_IO;
    }
    close(fd);
    return LL_OK;
}

/* The file name, written with status s, opened into *out and its size
 * into *bytes if s is LL_OK; name is unlinked and freed before returning
 * whatever the outcome. */
static ll_status open_temp(char *name, ll_status s, ll_bsdf **out, size_t *bytes)
{
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    if (s == LL_OK)
        s = ll_bsdf_open(name, NULL, out);
    unlink(name);
    free(name);
    if (s != LL_OK)
        return s;
    ll_bsdf_get_info(*out, &info);
    *bytes = info.file_size;
    return LL_OK;
}

/* The built layers as an opened .bsdf, through a temporary beside output. */
static ll_status open_as_bsdf(const ll_material *m, const ll_build_options *o,
                              ll_layer *const *layers, size_t n_channels, const char *output,
                              const ll_monitor *monitor, ll_bsdf **out, size_t *bytes)
{
    char *name;
    ll_status s;
    *out = NULL;
    if ((s = temp_beside(output, &name)) != LL_OK)
        return s;
    return open_temp(name, ll_material_write(m, o, layers, n_channels, name, monitor), out,
                     bytes);
}

/* A swept material built to its textured .bsdf beside output (as
 * open_as_bsdf), opened and unlinked. */
static ll_status open_swept(const ll_material *m, const ll_build_options *o, const char *output,
                            const ll_monitor *monitor, ll_bsdf **out, size_t *bytes)
{
    char *name;
    ll_status s;
    *out = NULL;
    if ((s = temp_beside(output, &name)) != LL_OK)
        return s;
    return open_temp(name, ll_material_build(m, o, monitor, name), out, bytes);
}

/* One step's share [lo, hi] of the whole run's progress: each library
 * call reports 0..1 for itself, and the bar should go once from 0 to 1. */
typedef struct step {
    const ll_monitor *whole;
    double lo, hi;
} step;

static int report_step(void *user, double fraction, const char *stage)
{
    const step *st = user;
    if (!st->whole || !st->whole->progress)
        return 0;
    return st->whole->progress(st->whole->user, st->lo + fraction * (st->hi - st->lo), stage);
}

static ll_monitor monitor_of(step *st, const ll_monitor *whole, double lo, double hi)
{
    ll_monitor m = LL_MONITOR_INIT;
    st->whole = whole;
    st->lo = lo;
    st->hi = hi;
    m.progress = report_step;
    m.user = st;
    return m;
}

ll_status llbuild_tables_build(llbuild_tables *t, const ll_material *m,
                               const ll_build_options *o, const ll_monitor *monitor,
                               const char *output)
{
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n_channels = 0, c;
    ll_bsdf *b = NULL;
    step st;
    /* Shares of the bar: the build most, the .bsdf a little, the tables
     * (a few seconds: each grid the tolerance tries is written and
     * measured) the rest. */
    ll_monitor building = monitor_of(&st, monitor, 0.0, 0.8);
    ll_status s;
    if (t->opts.format == LL_TABLES_SPECTRAL) {
        t->n_nodes = o->n_nodes;
        t->n_orders = o->n_orders;
        t->n_channels = 3;
        return ll_material_write_tables(m, o, NULL, output, &t->opts, monitor);
    }
    if (ll_material_axis_count(m) > 0) {
        /* A swept material: its textured .bsdf, then a table set per basis. */
        s = open_swept(m, o, output, &building, &b, &t->bsdf_bytes);
        building = monitor_of(&st, monitor, 0.8, 1.0);
        if (s == LL_OK)
            s = ll_tables_write_from_bsdf(b, output, &t->opts, &building);
        ll_bsdf_release(b);
        return s;
    }
    s = ll_material_build_layers(m, o, &building, layers, &n_channels, NULL);
    if (s != LL_OK)
        return s;
    remember_layers(t, layers, n_channels);
    building = monitor_of(&st, monitor, 0.8, 0.85);
    s = open_as_bsdf(m, o, layers, n_channels, output, &building, &b, &t->bsdf_bytes);
    for (c = 0; c < n_channels; ++c)
        ll_layer_destroy(layers[c]);
    building = monitor_of(&st, monitor, 0.85, 1.0);
    if (s == LL_OK)
        s = ll_tables_write_from_bsdf(b, output, &t->opts, &building);
    ll_bsdf_release(b);
    return s;
}
