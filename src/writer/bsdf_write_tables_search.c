/*
 * ll_tables_write_from_bsdf (ll_tables.h): the grid sizes left at 0 chosen
 * by the tolerance. Each grid tried is written to a scratch file beside
 * path, opened as a renderer would open it and measured against b
 * (ll_tables_measure); the sizes grow along fixed ladders until the
 * figures are met or the ladders end, and the grid reached is written to
 * path once more with its figures in the metadata. path is written only
 * then, so a failed or cancelled search leaves it untouched.
 *
 * Which size grows: a miss of f's percentiles is mostly the sample grid's
 * cells across a lobe (coated gold: 99th percentile 20% at 32 elevations
 * and 15% at 64, 15% with a 128^2 sample grid, no change from a VNDF grid
 * of 64^2 to 256^2), so it grows the sample grid. The albedo misses
 * through both: the interpolation between incident elevations (between two
 * slices its error is several times that at a slice) and the last cells of
 * the sample grid at grazing angles (rough gold's albedo at 85 degrees did
 * not improve from 32 to 192 elevations at a 64^2 sample grid), so an
 * albedo miss grows the elevations and the sample grid in turn. The VNDF
 * grid follows the sample grid (at least 64^2): its side sets how finely a
 * sharp D is followed, and it costs little beside the four tables of the
 * sample grid. From the smallest grid (16 x 64^2 x 32^2) this reaches
 * 24 x 64^2 x 48^2 (1.3 MB) on rough gold (alpha 0.2), 48 x 64^2 x 64^2
 * (3.9 MB) on examples/coated-gold.layers and 64 x 80^2 x 80^2 (16.4 MB,
 * its grids float16) on rough glass (eta 1.5, alpha 0.3, compensate=0),
 * whose f is held closer (TRANSMIT_P99_SHARE).
 */
#include "layerlab/ll_tables.h"
#include "writer/bsdf_write_tables.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#define FN "ll_tables_write_from_bsdf"
#define DEFAULT_TOLERANCE 0.05
/* The other figures' bounds as fractions of the tolerance (the 99th
 * percentile's bound): 2% / 5% for the 95th percentile, 0.2% / 5% for the
 * median, 0.3% / 5% for the albedo. */
#define P95_SHARE 0.4
#define P50_SHARE 0.04
#define ALBEDO_SHARE 0.06
/* The search's f figures are one estimate (its pairs); another
 * (tests/tables_figures.h: other pairs) differs by a few percent of a
 * figure, and the tests' albedo (the samplers' weights, 256^2 strata) by
 * more (coated gold's: 0.293% by the search's former estimate of the same
 * kind, 0.306% by the tests'), so the search aims at 0.9 of each bound. */
#define MARGIN 0.9
/* A transmissive source's f is held closer: its 99th and 95th percentiles
 * to 0.6 and 0.2 of the tolerance (3% and 1% by default), as its four
 * lobes' tables are one file a renderer reads through one warp per lobe.
 * Its figures spread more between pair sets than an opaque one's: rough
 * glass (eta 1.5, alpha 0.3) at 64 x 80^2 x 80^2 has a 99th percentile of
 * 2.35% by the search's pairs and 3.03% by the tests' (a quarter per lobe
 * and side there too, other directions), so the search aims at 0.75 of
 * these bounds. */
#define TRANSMIT_P99_SHARE 0.6
#define TRANSMIT_P95_SHARE 0.2
#define TRANSMIT_MARGIN 0.75

static const size_t theta_ladder[] = { 16, 24, 32, 48, 64, 96, 128, 192 };
static const size_t sample_ladder[] = { 32, 48, 64, 80, 96, 128, 160, 192, 256 };
#define N_THETA (sizeof theta_ladder / sizeof theta_ladder[0])
#define N_SAMPLE (sizeof sample_ladder / sizeof sample_ladder[0])
#define MIN_VNDF 64
/* No grid beyond the larger of the source file's size and SIZE_CAP_FLOOR
 * bytes: where the warp cannot follow a material (a coat over a bright
 * red diffuse base: the plastic example stops at 64 x 96^2 x 96^2, 11.8
 * MB, with its albedo 1.7% off), growing further buys little at a cost no renderer
 * wants, and the file says the figures were not met. */
#define SIZE_CAP_FLOOR 16e6

typedef struct search {
    ll_tables_options o;      /* the caller's options, sizes 0 where chosen */
    double cap;               /* bytes a grid may take (SIZE_CAP)            */
    size_t ti, si;            /* positions on the ladders                    */
    int albedo_grows_sample;  /* whose turn an albedo miss is                */
    double tolerance;
    double sets;              /* table sets: 4 for a transmissive source     */
    int half;                 /* float16 grids (a textured file's basis)    */
} search;

static void grid_at(const search *s, ll_tables_options *g)
{
    *g = s->o;
    if (!g->n_theta_i)
        g->n_theta_i = theta_ladder[s->ti];
    if (!g->sample_size)
        g->sample_size = sample_ladder[s->si];
    if (!g->vndf_size) {
        size_t ns = g->sample_size;
        g->vndf_size = ns > MIN_VNDF ? ns : MIN_VNDF;
    }
}

static int albedo_met(const search *s, const ll_tables_figures *f)
{
    return f->albedo <= MARGIN * ALBEDO_SHARE * s->tolerance;
}

static int f_met(const search *s, const ll_tables_figures *f)
{
    double t = MARGIN * s->tolerance;
    if (s->sets > 1.0) {
        double tt = TRANSMIT_MARGIN * s->tolerance;
        return f->p99 <= TRANSMIT_P99_SHARE * tt && f->p95 <= TRANSMIT_P95_SHARE * tt &&
               f->p50 <= P50_SHARE * t;
    }
    return f->p99 <= t && f->p95 <= P95_SHARE * t && f->p50 <= P50_SHARE * t;
}

/* One step up the ladders the misses point to; 0 if none can grow. */
static int grow_ladders(search *s, const ll_tables_figures *f)
{
    int theta_free = !s->o.n_theta_i && s->ti + 1 < N_THETA;
    int sample_free = !s->o.sample_size && s->si + 1 < N_SAMPLE;
    int grow_theta = 0, grow_sample = 0;
    if (!f_met(s, f))
        grow_sample = 1;
    if (!albedo_met(s, f)) {
        /* A transmissive file whose f is met misses its albedo between
         * incident elevations (the transmission from below, whose lobe
         * sweeps to the horizon near the critical angle), which a finer
         * sample grid hardly moves (docs/benchmarks.md, "Incident elevations
         * of transmissive files"): so the elevations
         * grow. */
        if (s->sets > 1.0 && !grow_sample)
            grow_theta = 1;
        else if (s->albedo_grows_sample && !grow_sample)
            grow_sample = 1;
        else
            grow_theta = 1;
        s->albedo_grows_sample = !s->albedo_grows_sample;
    }
    /* A miss whose size is fixed (or at its ladder's end) grows whatever
     * is still free. */
    grow_theta = grow_theta && theta_free;
    grow_sample = grow_sample && sample_free;
    if (!grow_theta && !grow_sample) {
        grow_theta = theta_free;
        grow_sample = !theta_free && sample_free;
    }
    s->ti += (size_t)grow_theta;
    s->si += (size_t)grow_sample;
    return grow_theta || grow_sample;
}

/* The tables' bytes at grid g as float32 grids (the small tables and text
 * aside). A transmissive file's grids are float16 and take half, but the
 * cap stays on this count: it is what a renderer holds in memory (the
 * Mitsuba plugin keeps them as float32), and the search stops at the grids
 * it did before. */
static double grid_bytes(const ll_tables_options *g)
{
    double n_ti = (double)g->n_theta_i, nv = (double)g->vndf_size, ns = (double)g->sample_size;
    return 4.0 * n_ti * (nv * nv + 4.0 * ns * ns);
}

/* One step up the ladders the misses point to; 0 if none can grow, or if
 * the grown grid would pass the cap (the last grid is then kept). */
static int grow(search *s, const ll_tables_figures *f)
{
    search next = *s;
    ll_tables_options g;
    if (!grow_ladders(&next, f))
        return 0;
    grid_at(&next, &g);
    if (s->sets * grid_bytes(&g) > s->cap)
        return 0;
    *s = next;
    return 1;
}

/* The caller's monitor seen through one step of the search: the step
 * reports 0..1 for itself and the caller sees [lo, hi] of the whole. The
 * number of grids is not known in advance, so grid i gets the half of
 * what is left ([1 - 2^-i, 1 - 2^-(i+1)] of 0.9), and the final write the
 * last tenth. */
static ll_monitor monitor_of(ll_tables_share *st, double lo, double hi)
{
    return ll_tables_share_of(st, lo, hi - lo);
}

/* Write the grid g to at, open it, measure it against b. */
/* A trial grid is written and measured as b's own RGB tables, also for a
 * spectral file: its spectra share that warp, and measuring them would
 * build every wavelength again for each grid tried. */
static ll_status try_grid(const ll_bsdf *b, const ll_tables_source *ref, const char *at,
                          const ll_tables_options *g, int half, const ll_monitor *monitor,
                          ll_tables_figures *f)
{
    ll_bsdf *t = NULL;
    ll_tables_options rgb = *g;
    ll_status s;
    rgb.format = LL_TABLES_RGB;
    s = ll_tables_write_grid(b, at, &rgb, NULL, half, monitor);
    if (s != LL_OK)
        return s;
    if ((s = ll_bsdf_open(at, NULL, &t)) != LL_OK)
        return s;
    s = ll_tables_measure(b, ref, t, f);
    ll_bsdf_release(t);
    return s;
}

static ll_status run(const ll_bsdf *b, const char *path, search *s, const char *scratch,
                     ll_tables_share *progress)
{
    ll_tables_options g;
    ll_tables_figures f;
    ll_tables_source *ref = ll_malloc(sizeof *ref);
    ll_monitor m;
    char figures[400];
    double left = 0.9;
    int met;
    ll_status st;
    if (!ref)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
    /* The source's albedos once: every grid is measured against them. */
    if ((st = ll_tables_reference(b, ref)) != LL_OK) {
        ll_free(ref);
        return st;
    }
    for (;;) {
        grid_at(s, &g);
        m = monitor_of(progress, 0.9 - left, 0.9 - 0.5 * left);
        if ((st = try_grid(b, ref, scratch, &g, s->half, &m, &f)) != LL_OK) {
            ll_free(ref);
            return st;
        }
        left *= 0.5;
        met = albedo_met(s, &f) && f_met(s, &f);
        if (met || !grow(s, &f))
            break;
    }
    ll_free(ref);
    unlink(scratch);
    snprintf(figures, sizeof figures,
             "\"tolerance\": %.6g, \"figures\": {\"met\": %s, \"albedo\": %.3g, "
             "\"f_median\": %.3g, \"f_p95\": %.3g, \"f_p99\": %.3g}, ",
             s->tolerance, met ? "true" : "false", f.albedo, f.p50, f.p95, f.p99);
    m = monitor_of(progress, 0.9, 1.0);
    return ll_tables_write_grid(b, path, &g, figures, s->half, &m);
}

/* ll_tables_write_from_bsdf, its grids rounded to float16 if half. */
static ll_status write_tables(const ll_bsdf *b, const char *path, const ll_tables_options *opts,
                              int half, const ll_monitor *monitor)
{
    ll_tables_options defaults = LL_TABLES_OPTIONS_INIT;
    ll_monitor none = LL_MONITOR_INIT;
    search s;
    ll_tables_share progress;
    char *scratch = NULL;
    size_t len;
    ll_status st;
    if (!b || !path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": bsdf or path is NULL");
    memset(&s, 0, sizeof s);
    s.o = defaults;
    if (opts && (st = ll_struct_read(&s.o, sizeof s.o, opts, FN, "ll_tables_options")) != LL_OK)
        return st;
    /* A textured file: the search for each basis (its own grid). A
     * textured table file is made from its .bsdf, whose bases it holds. */
    if (b->n_parameters > 0 && b->measured)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": the file is a textured table file; convert the textured .bsdf it "
                       "was made from");
    if (b->n_parameters > 0)
        return half ? ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": a basis is untextured")
                    : ll_tables_write_textured(b, path, &s.o, monitor);
    if (s.o.format == LL_TABLES_SPECTRAL && ll_tables_transmits(b))
        return ll_fail(LL_ERROR_UNSUPPORTED,
                       FN ": spectral tables of a transmissive file are not written by this "
                       "version (LL_TABLES_RGB writes them)");
    if (s.o.n_theta_i && s.o.vndf_size && s.o.sample_size)
        return ll_tables_write_grid(b, path, &s.o, NULL, half, monitor);
    s.tolerance = s.o.tolerance != 0.0 ? s.o.tolerance : DEFAULT_TOLERANCE;
    s.sets = ll_tables_transmits(b) ? 4.0 : 1.0;
    s.half = half;
    /* The floor per set: a transmissive file holds four. */
    s.cap = (double)b->file_size > s.sets * SIZE_CAP_FLOOR ? (double)b->file_size
                                                          : s.sets * SIZE_CAP_FLOOR;

    if (!(s.tolerance >= 0.005 && s.tolerance <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": tolerance %g out of range (0.005..1)",
                       s.o.tolerance);
    /* The scratch file: path with the process id and a suffix of its own,
     * so that concurrent searches for different paths (or processes) do
     * not meet. */
    len = strlen(path) + 48;
    if (!(scratch = ll_malloc(len)))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
    snprintf(scratch, len, "%s.%ld.measuring", path, (long)getpid());
    progress.whole = none;
    if (monitor &&
        (st = ll_struct_read(&progress.whole, sizeof progress.whole, monitor, FN, "ll_monitor")) !=
            LL_OK) {
        ll_free(scratch);
        return st;
    }
    st = run(b, path, &s, scratch, &progress);
    unlink(scratch);
    ll_free(scratch);
    return st;
}

ll_status ll_tables_write_from_bsdf(const ll_bsdf *b, const char *path,
                                    const ll_tables_options *opts, const ll_monitor *monitor)
{
    return write_tables(b, path, opts, 0, monitor);
}

ll_status ll_tables_write_half(const ll_bsdf *b, const char *path, const ll_tables_options *opts,
                               const ll_monitor *monitor)
{
    return write_tables(b, path, opts, 1, monitor);
}
