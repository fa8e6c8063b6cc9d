/*
 * measured file=PATH: a MERL measured BRDF as an opaque base
 * (ll_layer_set_matusik, or ll_merl_set_layer for a mix of channels;
 * the file format in docs/material-language.md).
 */
#include "material/word_table.h"
#include "words/merl.h"
#include "search/probe.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The search's first guess (search/merl_probe.c searches from it): 100
 * nodes (about 1.8 degrees between nodes near the horizon, finer near the
 * pole) and 180 orders (azimuthal detail of 1 degree, the database's step
 * in phi_diff), the original's fixed resolution. */
#define MEASURED_NODES 100
#define MEASURED_ORDERS 180

/* Measured on a synthetic MERL file of the database's size (90 x 90 x 180,
 * 35 MB) at 60 x 100, 100 x 90, 100 x 180 and 140 x 180: each of the
 * (n/2)^2 pairs samples 4m azimuths (a lookup each) and sums m cosines
 * over them (the DCT), and each build reads the file once. While it is
 * built the file's raw values and its converted tables are both held. */
#define RATE_MERL 7e8         /* DCT multiply-adds per second, one thread */
#define COST_MERL_SAMPLE 1.8e-7 /* seconds per BRDF lookup               */
#define COST_MERL_LOAD 0.04   /* seconds to read and convert a file      */

#define MAX_PATH_TOKEN 4096

/* path relative to the material's directory unless absolute. */
static char *resolve_path(const char *dir, const char *path)
{
    size_t a, b;
    char *out;
    if (path[0] == '/' || !dir)
        dir = NULL;
    a = dir ? strlen(dir) + 1 : 0;
    b = strlen(path);
    out = ll_malloc(a + b + 1);
    if (!out)
        return NULL;
    if (dir)
        snprintf(out, a + b + 1, "%s/%s", dir, path);
    else
        memcpy(out, path, b + 1);
    return out;
}

static ll_status measured_parse_file(const ll_parser *p, ll_word *w, const ll_token *key,
                                     const ll_token *v)
{
    char path[MAX_PATH_TOKEN];
    struct stat st;
    ll_status s;
    if (w->file)
        return ll_parse_error(p, key->begin, "file is given twice");
    if (v->len + 1 > sizeof path)
        return ll_parse_error(p, v->begin, "file: the path is too long");
    memcpy(path, v->begin, v->len);
    path[v->len] = '\0';
    w->file = resolve_path(ll_parser_dir(p), path);
    if (!w->file)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory parsing the material");
    s = ll_merl_check(w->file);
    if (s != LL_OK)
        return ll_parse_error(p, v->begin, "file: %s", ll_last_error_message());
    if (stat(w->file, &st) == 0)
        w->file_bytes = (double)st.st_size;
    return LL_OK;
}

static ll_status measured_finish(const ll_parser *p, ll_word *w, const char *word_at)
{
    if (!w->file)
        return ll_parse_error(p, word_at, "measured needs file=...; for example: %s",
                              ll_word_measured.example);
    return LL_OK;
}

static int measured_needs_colour(const ll_word *w)
{
    (void)w;
    return 1;
}

static void measured_params(const ll_word *w, size_t c, size_t n_channels, double above,
                            ll_word_params *out)
{
    (void)w;
    (void)above;
    out->v[3] = w->file_bytes;
    out->file = w->file;
    if (n_channels == 3) {
        out->v[c] = 1.0;
    } else {
        out->v[0] = LL_LUMA_R;
        out->v[1] = LL_LUMA_G;
        out->v[2] = LL_LUMA_B;
    }
}

/* The resolution at which the projected table is within the tolerance of
 * twice it (search/merl_probe.c): the file is read once more for
 * the search, which costs what docs/method.md "Resolution" measures (5 to
 * 18 s for a table of the database's size). One search per file, on the
 * luminance mix, for every channel (resolution_reads: the file alone): the
 * channels of a table share its cells, and so its steps, and a relative
 * error does not see their scales; three searches would triple the cost. */
static ll_status measured_resolution(const ll_word_params *p, double tolerance, double mu_min,
                                     ll_watch *watch, size_t *n, size_t *m, double *error)
{
    static const double luma[3] = { LL_LUMA_R, LL_LUMA_G, LL_LUMA_B };
    ll_merl *merl = NULL;
    ll_status s;
    if (!p->file)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "measured: no file");
    s = ll_merl_load(p->file, &merl);
    *n = MEASURED_NODES;
    *m = MEASURED_ORDERS;
    if (s == LL_OK)
        s = ll_merl_resolution(merl, luma, tolerance, mu_min, watch, n, m, error);
    ll_merl_free(merl);
    return s;
}

static void measured_cost(const ll_word_params *p, size_t n, size_t m, ll_word_cost *out)
{
    double h = (double)(n / 2);
    out->parallel_seconds = h * h * 4.0 * (double)m *
                            ((double)m / RATE_MERL + COST_MERL_SAMPLE);
    out->items = n / 2;
    out->serial_seconds = COST_MERL_LOAD;
    out->work.measured_lookups = h * h * 4.0 * (double)m;
    out->work.measured_files = 1.0;
    out->build_bytes = 2.0 * p->v[3];
    out->orders_nonzero = (double)m;
    out->dense_orders = 0.25 * (double)m; /* R^t blocks only */
    out->thread_bytes = 8.0 * 4.0 * (double)m * (double)n;
}

static ll_status measured_build(const ll_word_build_ctx *ctx, const ll_word *w,
                                const ll_word_params *p, ll_layer *layer)
{
    const ll_monitor *monitor = ctx->monitor(ctx->user, 1.0);
    const double *weights = p->v;
    ll_merl *merl = NULL;
    ll_status s;
    int c;
    /* One colour channel of the file: the public call. The luminance mix
     * of a mono build has no public setter and goes through the internal
     * one, with the same monitor. */
    for (c = 0; c < 3; ++c)
        if (weights[c] == 1.0 && weights[(c + 1) % 3] == 0.0 && weights[(c + 2) % 3] == 0.0)
            return ll_layer_set_matusik(layer, w->file, c, 0, monitor);
    s = ll_merl_load(w->file, &merl);
    if (s == LL_OK)
        s = ll_merl_set_layer(layer, merl, weights, 0, monitor);
    ll_merl_free(merl);
    return s;
}

static void measured_metadata(ll_text *b, const ll_word *w)
{
    ll_text_append(b, ", \"file\": ");
    ll_text_string(b, w->file);
}

static void measured_destroy(ll_word *w)
{
    ll_free(w->file);
    w->file = NULL;
}

const ll_word_desc ll_word_measured = {
    "measured", "measured file=gold-metallic-paint.binary", "measured", 1, 0,
    { { "file", 0, -1, 0, 0, 0, 0, NULL, measured_parse_file, NULL } },
    measured_finish, measured_needs_colour, NULL, measured_params, measured_resolution,
    measured_cost, measured_build, measured_metadata, measured_destroy, 1u << 3, 0
};
