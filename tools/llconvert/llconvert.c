/*
 * llconvert — convert an existing file to another format.
 *
 *     llconvert [options] IN.bsdf -o OUT [--format measured]
 *
 * A thin program over the public API: ll_bsdf_open, then
 * ll_tables_write_from_bsdf (atomic output), then a summary read back from
 * the written file. The one target format is `measured`, the table files
 * that Mitsuba 3 and pbrt-v4 read natively (docs/formats.md); the
 * source may be transmissive or textured: it then gives our extension of
 * it (a set of tables per lobe and side), which those renderers refuse.
 * Exit codes: 0 done, 1 bad input (including a source the format cannot
 * hold, with the reason), 2 I/O, 3 out of memory.
 */
#define LL_EXPERIMENTAL /* ll_tables_write_from_bsdf */
#include <layerlab.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EXIT_BAD_INPUT 1
#define EXIT_IO 2
#define EXIT_MEMORY 3

static const char usage[] =
    "usage: llconvert [options] IN.bsdf -o OUT [--format measured]\n"
    "Convert a .bsdf (or an opaque, untextured table) file into the tables of\n"
    "the `measured` format that Mitsuba 3 and pbrt-v4 read (docs/formats.md);\n"
    "a transmissive source gives a set of tables per lobe and side, a textured\n"
    "one a set per basis, which only layerlab reads (those renderers refuse them).\n"
    "  -o, --output FILE  the file to write (required unless --dry-run)\n"
    "  --format NAME      the output format: measured (the default and only one)\n"
    "  --theta-i N        incident elevations (default: chosen by the tolerance)\n"
    "  --vndf N           side of the visible-normal grid (default: likewise)\n"
    "  --sample N         side of the sample grid (default: likewise)\n"
    "  --tolerance T      the sizes not given grow until the table agrees with IN:\n"
    "                     99th percentile of f's relative error <= T, 95th <= 0.4 T,\n"
    "                     median <= 0.04 T, albedo within 0.06 T (default 0.05);\n"
    "                     a transmissive IN's 99th and 95th: 0.6 T and 0.2 T\n"
    "  --dry-run          print the table's size (or its range); write nothing\n"
    "  --quiet            no summary (errors only)\n"
    "  --version          print the version\n"
    "  -h, --help         this text\n"
    "Exit codes: 0 done, 1 bad input, 2 I/O, 3 out of memory.\n";

static int exit_code(ll_status s)
{
    if (s == LL_ERROR_IO)
        return EXIT_IO;
    if (s == LL_ERROR_OUT_OF_MEMORY)
        return EXIT_MEMORY;
    return EXIT_BAD_INPUT;
}

/* A grid size: a whole number in 2..4096. */
static int parse_size(const char *text, const char *option, size_t *out)
{
    char *end;
    long v = strtol(text, &end, 10);
    if (*text == '\0' || *end != '\0' || v < 2 || v > 4096) {
        fprintf(stderr, "llconvert: %s wants a whole number in 2..4096, not '%s'\n", option,
                text);
        return 0;
    }
    *out = (size_t)v;
    return 1;
}

/* A tolerance: a number in 0.005..1. */
static int parse_tolerance(const char *text, double *out)
{
    char *end;
    double v = strtod(text, &end);
    if (*text == '\0' || *end != '\0' || !(v >= 0.005 && v <= 1.0)) {
        fprintf(stderr, "llconvert: --tolerance wants a number in 0.005..1, not '%s'\n", text);
        return 0;
    }
    *out = v;
    return 1;
}

/* The grid and figures a written table's metadata holds. */
static void print_written(const char *out, const ll_bsdf_info *info, double source_bytes)
{
    const char *g = info->metadata ? strstr(info->metadata, "\"theta_i\": ") : NULL;
    const char *f = info->metadata ? strstr(info->metadata, "\"figures\": {") : NULL;
    unsigned long n_ti = 0, nv = 0, ns = 0;
    if (info->n_bases > 1) {
        /* A textured file: a set per basis, each with its own grid. */
        printf("%s: textured tables, %zu bases of %zu parameters, %.2f MB (the source: %.2f "
               "MB)\n",
               out, info->n_bases, info->n_parameters, (double)info->file_size / 1e6,
               source_bytes / 1e6);
        return;
    }
    if (g)
        sscanf(g, "\"theta_i\": %lu, \"vndf\": [%lu, %*u], \"sample\": [%lu", &n_ti, &nv, &ns);
    printf("%s: %lu x %lu^2 x %lu^2 tables, %.2f MB (the source: %.2f MB)\n", out, n_ti, nv, ns,
           (double)info->file_size / 1e6, source_bytes / 1e6);
    if (f) {
        const char *end = strchr(f, '}');
        printf("%s: measured against the source: %.*s\n", out,
               end ? (int)(end - f + 1) : 0, f);
    }
}

/* The data the tables hold (the field table and text add a few hundred
 * bytes): ndf and sigma (2 x 256 each), theta_i, vndf, luminance, rgb;
 * a transmissive source's four sets with their grids float16. */
static double table_bytes(size_t n_ti, size_t nv, size_t ns, int transmissive)
{
    double sets = transmissive ? 4.0 : 1.0, grid = transmissive ? 2.0 : 4.0;
    return grid * sets * ((double)n_ti * nv * nv + 4.0 * (double)n_ti * ns * ns) +
           4.0 * (sets * (2.0 * 2 * 256 + (transmissive ? (double)n_ti : 0.0)) +
                  (double)n_ti + 1);
}

/* Whether the source transmits (its tables are then a set per lobe and
 * side): eta differs from 1, or light goes through at some elevation. */
static int transmits(const ll_bsdf *b, const ll_bsdf_info *info)
{
    static const double mu[3] = { 1.0, 0.5, -0.5 };
    int k;
    if (info->eta < 1.0 - 1e-6 || info->eta > 1.0 + 1e-6)
        return 1;
    for (k = 0; k < 3; ++k) {
        double r[3], t[3];
        if (ll_bsdf_albedo(b, mu[k], NULL, r, t) == LL_OK &&
            t[0] + t[1] + t[2] > 1e-6 * (r[0] + r[1] + r[2]))
            return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    ll_tables_options opts = LL_TABLES_OPTIONS_INIT;
    const char *in = NULL, *out = NULL;
    int dry_run = 0, quiet = 0, k;
    ll_bsdf *b = NULL, *written = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT, out_info = LL_BSDF_INFO_INIT;
    ll_status s;
    for (k = 1; k < argc; ++k) {
        const char *a = argv[k];
        int has_value = k + 1 < argc;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage, stdout);
            return 0;
        } else if (!strcmp(a, "--version")) {
            printf("llconvert (layerlab) %s\n", ll_version_string());
            return 0;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_value) {
            out = argv[++k];
        } else if (!strcmp(a, "--format") && has_value) {
            if (strcmp(argv[++k], "measured") != 0) {
                fprintf(stderr, "llconvert: unknown format '%s' (measured)\n", argv[k]);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--theta-i") && has_value) {
            if (!parse_size(argv[++k], a, &opts.n_theta_i))
                return EXIT_BAD_INPUT;
        } else if (!strcmp(a, "--vndf") && has_value) {
            if (!parse_size(argv[++k], a, &opts.vndf_size))
                return EXIT_BAD_INPUT;
        } else if (!strcmp(a, "--sample") && has_value) {
            if (!parse_size(argv[++k], a, &opts.sample_size))
                return EXIT_BAD_INPUT;
        } else if (!strcmp(a, "--tolerance") && has_value) {
            if (!parse_tolerance(argv[++k], &opts.tolerance))
                return EXIT_BAD_INPUT;
        } else if (!strcmp(a, "--dry-run")) {
            dry_run = 1;
        } else if (!strcmp(a, "--quiet")) {
            quiet = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "llconvert: unknown option or missing value: %s\n%s", a, usage);
            return EXIT_BAD_INPUT;
        } else if (!in) {
            in = a;
        } else {
            fprintf(stderr, "llconvert: more than one input (%s, %s)\n", in, a);
            return EXIT_BAD_INPUT;
        }
    }
    if (!in || (!out && !dry_run)) {
        fprintf(stderr, "llconvert: %s\n%s", in ? "no output (-o FILE)" : "no input file",
                usage);
        return EXIT_BAD_INPUT;
    }
    if ((s = ll_bsdf_open(in, NULL, &b)) != LL_OK) {
        fprintf(stderr, "llconvert: %s\n", ll_last_error_message());
        return exit_code(s);
    }
    ll_bsdf_get_info(b, &info);
    if (dry_run && opts.n_theta_i && opts.vndf_size && opts.sample_size) {
        printf("%s: %s%zu x %zu^2 x %zu^2 tables, about %.2f MB (the source: %.2f MB)\n", in,
               info.n_bases > 1 ? "per basis " : "", opts.n_theta_i, opts.vndf_size,
               opts.sample_size,
               (double)info.n_bases *
                   table_bytes(opts.n_theta_i, opts.vndf_size, opts.sample_size,
                               transmits(b, &info)) / 1e6,
               (double)info.file_size / 1e6);
        ll_bsdf_release(b);
        return 0;
    }
    if (dry_run) {
        /* The library's ladders (ll_tables.h): 16..192 elevations, sample
         * grids 32..256, the VNDF grid the sample grid's but at least 64. */
        size_t lo_ti = opts.n_theta_i ? opts.n_theta_i : 16, hi_ti = opts.n_theta_i ? opts.n_theta_i : 192;
        size_t lo_ns = opts.sample_size ? opts.sample_size : 32, hi_ns = opts.sample_size ? opts.sample_size : 256;
        size_t lo_nv = opts.vndf_size ? opts.vndf_size : (lo_ns > 64 ? lo_ns : 64);
        size_t hi_nv = opts.vndf_size ? opts.vndf_size : (hi_ns > 64 ? hi_ns : 64);
        printf("%s: tables sized by the tolerance %g: from %zu x %zu^2 x %zu^2 per basis (about "
               "%.2f MB) "
               "up to %zu x %zu^2 x %zu^2 (about %.2f MB), known once measured (the source: "
               "%.2f MB)\n",
               in, opts.tolerance != 0.0 ? opts.tolerance : 0.05, lo_ti, lo_nv, lo_ns,
               (double)info.n_bases * table_bytes(lo_ti, lo_nv, lo_ns, transmits(b, &info)) / 1e6,
               hi_ti, hi_nv, hi_ns,
               (double)info.n_bases * table_bytes(hi_ti, hi_nv, hi_ns, transmits(b, &info)) / 1e6,
               (double)info.file_size / 1e6);
        ll_bsdf_release(b);
        return 0;
    }
    s = ll_tables_write_from_bsdf(b, out, &opts, NULL);
    ll_bsdf_release(b);
    if (s != LL_OK) {
        fprintf(stderr, "llconvert: %s\n", ll_last_error_message());
        return exit_code(s);
    }
    if (!quiet) {
        if ((s = ll_bsdf_open(out, NULL, &written)) != LL_OK) {
            fprintf(stderr, "llconvert: the written file does not open: %s\n",
                    ll_last_error_message());
            return exit_code(s);
        }
        ll_bsdf_get_info(written, &out_info);
        print_written(out, &out_info, (double)info.file_size);
        ll_bsdf_release(written);
    }
    return 0;
}
