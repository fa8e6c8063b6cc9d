/*
 * ll_material_write_tables (ll_tables.h): a material's table file. The
 * warp comes from the material's RGB build (as llbuild --format measured
 * has always made it); a spectral file's values come from the material
 * built again at each wavelength (material_spectral.c), one channel at the
 * RGB build's resolution, its word layers shared between wavelengths
 * through the cache the sweep builder uses (material_sweep_cache.c): a
 * clear coat is built once for all wavelengths, the metal under it once
 * per wavelength. Each wavelength's layers are written to a temporary
 * .bsdf beside the output, opened (the handle holds the data) and the name
 * removed at once; the table writer releases the handle before asking for
 * the next wavelength.
 */
#include "material/material_spectral.h"
#include "layerlab/ll_tables.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define FN "ll_material_write_tables"

/* The caller's monitor between the table writer and the wavelengths'
 * builds: the writer's reports pass through (the last fraction kept), and
 * a build polls the caller at that fraction, so that a cancel is seen
 * during a wavelength's build without moving the caller's progress. */
typedef struct relay {
    ll_monitor_fn progress;
    void *user;
    double last;
} relay;

static int relay_report(void *user, double fraction, const char *stage)
{
    relay *r = user;
    r->last = fraction;
    return r->progress ? r->progress(r->user, fraction, stage) : 0;
}

static int relay_poll(void *user, double fraction, const char *stage)
{
    const relay *r = user;
    (void)fraction;
    (void)stage;
    return r->progress ? r->progress(r->user, r->last, "spectra") : 0;
}

typedef struct spectral_source {
    ll_build_options o;          /* fixed resolution, one channel */
    ll_spectral_plan plan;
    ll_word_cache *cache;
    const char *path;
    relay relay;
    ll_monitor poll;             /* a wavelength's build: relay_poll */
} spectral_source;

/* A new empty file beside path, named path + suffix with its XXXXXX made
 * unique, into *name (free with ll_free). */
static ll_status temp_beside(const char *path, const char *suffix, char **name)
{
    size_t n = strlen(path), k = strlen(suffix) + 1, total;
    ll_status s;
    int fd;
    if (!ll_size_add(n, k, &total) || !(*name = ll_malloc(total)))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
    memcpy(*name, path, n);
    memcpy(*name + n, suffix, k);
    fd = mkstemp(*name);
    if (fd < 0) {
        s = ll_fail(LL_ERROR_IO, FN ": cannot create a temporary file beside %s: %s", path,
                    strerror(errno));
        ll_free(*name);
        *name = NULL;
        return s;
    }
    close(fd);
    return LL_OK;
}

/* The file name, written with status s, opened into *out if s is LL_OK;
 * name is unlinked and freed whatever the outcome. */
static ll_status open_temp(char *name, ll_status s, ll_bsdf **out)
{
    if (s == LL_OK)
        s = ll_bsdf_open(name, NULL, out);
    unlink(name);
    ll_free(name);
    return s;
}

/* layers (n_channels) of the material m as an opened file, through a
 * temporary .bsdf beside path that is gone when this returns. */
static ll_status open_layers(const ll_material *m, const ll_build_options *o,
                             ll_layer *const *layers, size_t n_channels, const char *path,
                             ll_bsdf **out)
{
    char *name;
    ll_status s;
    *out = NULL;
    if ((s = temp_beside(path, ".layers-XXXXXX", &name)) != LL_OK)
        return s;
    return open_temp(name, ll_material_write(m, o, layers, n_channels, name, NULL), out);
}

static ll_status build_at(void *user, size_t index, double nm, ll_bsdf **out)
{
    spectral_source *src = user;
    ll_material view;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n_channels = 0, c;
    ll_status s;
    (void)index;
    ll_spectral_view(&src->plan, nm, &view);
    s = ll_material_build_layers_cached(&view, &src->o, src->relay.progress ? &src->poll : NULL,
                                        src->cache, layers, &n_channels, NULL);
    if (s == LL_OK)
        s = open_layers(&view, &src->o, layers, n_channels, src->path, out);
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(layers[c]);
    if (s != LL_OK && s != LL_ERROR_CANCELLED && s != LL_ERROR_OUT_OF_MEMORY)
        return ll_fail(s, FN ": the material at %g nm: %s", nm, ll_last_error_message());
    return s;
}

/* The RGB build, opened: the warp's source. */
static ll_status build_rgb(const ll_material *m, const ll_build_options *build,
                           const ll_monitor *monitor, const char *path, ll_bsdf **out)
{
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n_channels = 0, c;
    ll_status s = ll_material_build_layers(m, build, monitor, layers, &n_channels, NULL);
    if (s == LL_OK)
        s = open_layers(m, build, layers, n_channels, path, out);
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(layers[c]);
    return s;
}

/* A swept material's textured .bsdf, built beside path under a unique
 * name, opened and unlinked. */
static ll_status build_swept(const ll_material *m, const ll_build_options *build,
                             const ll_monitor *monitor, const char *path, ll_bsdf **out)
{
    char *name;
    ll_status s;
    *out = NULL;
    if ((s = temp_beside(path, ".sweep-XXXXXX", &name)) != LL_OK)
        return s;
    return open_temp(name, ll_material_build(m, build, monitor, name), out);
}

/* One step's share [lo, lo + span] of the caller's progress (each library
 * call reports 0..1 for itself). */
typedef struct share {
    ll_monitor_fn progress;
    void *user;
    double lo, span;
} share;

static int report_share(void *user, double fraction, const char *stage)
{
    const share *sh = user;
    return sh->progress ? sh->progress(sh->user, sh->lo + fraction * sh->span, stage) : 0;
}

static ll_monitor monitor_share(share *sh, const ll_monitor *caller, double lo, double span)
{
    ll_monitor m = LL_MONITOR_INIT;
    ll_monitor c = LL_MONITOR_INIT;
    if (caller)
        ll_struct_read(&c, sizeof c, caller, FN, "ll_monitor");
    sh->progress = c.progress;
    sh->user = c.user;
    sh->lo = lo;
    sh->span = span;
    m.progress = report_share;
    m.user = sh;
    return m;
}

/* plan: checked and fitted (ll_spectral_plan_init), owned from here. */
static ll_status write_spectral(const ll_material *m, const ll_build_options *build,
                                const ll_bsdf *rgb, const char *path,
                                const ll_tables_options *tables, const ll_monitor *monitor,
                                ll_spectral_plan *plan)
{
    spectral_source src;
    ll_tables_options t = *tables;
    ll_monitor writer = LL_MONITOR_INIT, caller = LL_MONITOR_INIT;
    size_t n, orders, nch;
    ll_status s;
    memset(&src, 0, sizeof src);
    src.path = path;
    src.plan = *plan;
    if (monitor)
        ll_struct_read(&caller, sizeof caller, monitor, FN, "ll_monitor");
    src.relay.progress = caller.progress;
    src.relay.user = caller.user;
    src.poll = writer;
    src.poll.progress = relay_poll;
    src.poll.user = &src.relay;
    writer.progress = relay_report;
    writer.user = &src.relay;
    if ((s = ll_build_options_read(build, &src.o, FN)) != LL_OK) {
        ll_spectral_plan_free(&src.plan);
        return s;
    }
    /* Every wavelength at the resolution of the RGB build. */
    s = ll_material_plan(m, &src.o, NULL, &n, &orders, &nch);
    if (s == LL_OK) {
        src.o.n_nodes = n;
        src.o.n_orders = orders;
        src.o.n_channels = 1;
        src.cache = ll_word_cache_create();
        if (!src.cache)
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
    }
    if (s == LL_OK) {
        t.spectrum = build_at;
        t.spectrum_user = &src;
        s = ll_tables_write_from_bsdf(rgb, path, &t, monitor ? &writer : NULL);
    }
    ll_word_cache_destroy(src.cache);
    ll_spectral_plan_free(&src.plan);
    return s;
}

ll_status ll_material_write_tables(const ll_material *m, const ll_build_options *build,
                                   const ll_bsdf *rgb, const char *path,
                                   const ll_tables_options *tables, const ll_monitor *monitor)
{
    ll_tables_options t = LL_TABLES_OPTIONS_INIT;
    ll_bsdf *own = NULL;
    ll_spectral_plan plan;
    ll_monitor part = LL_MONITOR_INIT;
    share sh;
    double split = 0.0;
    ll_status s;
    if (!m || !path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": material or path is NULL");
    if (tables && (s = ll_struct_read(&t, sizeof t, tables, FN, "ll_tables_options")) != LL_OK)
        return s;
    if (m->n_axes > 0 && t.format == LL_TABLES_SPECTRAL)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": %s is swept (textured): its tables are written in RGB (a set per "
                       "basis); spectral textured tables are not made by this version",
                       m->source);
    /* A transmissive stack's tables (a set per lobe and side) are written
     * in RGB only. */
    if (!ll_material_is_opaque(m) && t.format == LL_TABLES_SPECTRAL)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": %s transmits light (its bottom word is not opaque): its tables "
                       "of every lobe are written in RGB only (LL_TABLES_RGB); the `measured` "
                       "format itself stores reflection only",
                       m->source);
    if (monitor && (s = ll_struct_check(monitor, FN, "ll_monitor")) != LL_OK)
        return s;
    /* A word without a spectrum is refused before anything is built. */
    if (t.format == LL_TABLES_SPECTRAL && (s = ll_spectral_plan_init(m, &plan, FN)) != LL_OK)
        return s;
    if (!rgb && m->n_axes > 0) {
        /* A sweep: its textured .bsdf, then a table set per basis. */
        part = monitor_share(&sh, monitor, 0.0, 0.8);
        s = build_swept(m, build, monitor ? &part : NULL, path, &own);
        if (s != LL_OK)
            return s;
        part = monitor_share(&sh, monitor, 0.8, 0.2);
        s = ll_tables_write_from_bsdf(own, path, &t, monitor ? &part : NULL);
        ll_bsdf_release(own);
        return s;
    }
    if (!rgb) {
        /* The progress: the RGB build a share, the tables (for a spectral
         * file: a build per wavelength) the rest. */
        split = t.format == LL_TABLES_SPECTRAL ? 0.2 : 0.8;
        part = monitor_share(&sh, monitor, 0.0, split);
        s = build_rgb(m, build, monitor ? &part : NULL, path, &own);
        if (s != LL_OK) {
            if (t.format == LL_TABLES_SPECTRAL)
                ll_spectral_plan_free(&plan);
            return s;
        }
        rgb = own;
        part = monitor_share(&sh, monitor, split, 1.0 - split);
        if (monitor)
            monitor = &part;
    }
    if (t.format == LL_TABLES_SPECTRAL)
        s = write_spectral(m, build, rgb, path, &t, monitor, &plan);
    else
        s = ll_tables_write_from_bsdf(rgb, path, &t, monitor);
    ll_bsdf_release(own);
    return s;
}
