/*
 * llplot — the material being drawn: a .bsdf file opened with ll_bsdf_open,
 * or a material file compiled in memory with ll_material_build_layers.
 */
#include "llplot.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* A material compiled for a picture only needs to look right, not to match
 * a renderer to three digits: unless --nodes/--orders say otherwise, cap
 * the heuristic resolution so that even glossy stacks compile in seconds.
 * (Too few orders blur a narrow highlight; too few nodes make it ripple.) */
#define PREVIEW_MAX_NODES 120
#define PREVIEW_MAX_ORDERS 200

/* A file ll_bsdf_open reads: a .bsdf ("SCATFUN") or a table file of the
 * `measured` format ("tensor_file" and a NUL; docs/formats.md). */
static int is_bsdf_file(const char *path, int *is_bsdf)
{
    char magic[12];
    size_t got;
    FILE *f = fopen(path, "rb");
    if (!f)
        return llplot_fail(LLPLOT_EXIT_IO, "%s: cannot open: %s", path, strerror(errno));
    got = fread(magic, 1, sizeof magic, f);
    *is_bsdf = (got >= 7 && memcmp(magic, "SCATFUN", 7) == 0) ||
               (got == 12 && memcmp(magic, "tensor_file", 12) == 0);
    if (ferror(f)) {
        int err = errno;
        fclose(f);
        return llplot_fail(LLPLOT_EXIT_IO, "%s: cannot read: %s", path, strerror(err));
    }
    fclose(f);
    return LLPLOT_EXIT_OK;
}

/* A textured file is drawn for one basis function: weights one-hot. */
static int choose_basis(const llplot_options *o, llplot_source *s)
{
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    ll_status st = ll_bsdf_get_info(s->bsdf, &info);
    if (st != LL_OK)
        return llplot_fail_ll(st, o->input);
    s->n_channels = info.n_channels;
    if (info.n_bases <= 1) {
        if (o->basis > 0)
            return llplot_fail(LLPLOT_EXIT_INPUT, "%s: --basis %zu given, but the file is not textured",
                               o->input, o->basis);
        return LLPLOT_EXIT_OK;
    }
    if (o->basis >= info.n_bases)
        return llplot_fail(LLPLOT_EXIT_INPUT, "%s: --basis %zu, but the file has %zu basis functions",
                           o->input, o->basis, info.n_bases);
    s->basis_coeffs = calloc(info.n_bases, sizeof(float));
    if (!s->basis_coeffs)
        return llplot_fail(LLPLOT_EXIT_IO, "out of memory");
    s->basis_coeffs[o->basis] = 1.0f;
    return LLPLOT_EXIT_OK;
}

/* Sampling is only reachable through an opened .bsdf: write the compiled
 * layers to a private temporary file, open it, and remove it at once (the
 * opened table lives in memory). */
static int open_compiled_file(const llplot_options *o, llplot_source *s,
                              const ll_bsdf_write_options *header)
{
    const char *tmp = getenv("TMPDIR");
    char dir[4096], path[4200];
    ll_status st;
    int code = LLPLOT_EXIT_OK;
    if (!tmp || !tmp[0])
        tmp = "/tmp";
    if ((size_t)snprintf(dir, sizeof dir, "%s/llplot-XXXXXX", tmp) >= sizeof dir)
        return llplot_fail(LLPLOT_EXIT_IO, "TMPDIR is too long");
    if (!mkdtemp(dir))
        return llplot_fail(LLPLOT_EXIT_IO, "%s: cannot create a temporary directory: %s", dir,
                           strerror(errno));
    snprintf(path, sizeof path, "%s/preview.bsdf", dir);
    st = ll_bsdf_write(path, (const ll_layer *const *)s->layers, s->n_layers, header, NULL);
    if (st == LL_OK)
        st = ll_bsdf_open(path, NULL, &s->bsdf);
    if (st != LL_OK)
        code = llplot_fail_ll(st, o->input);
    unlink(path);
    rmdir(dir);
    return code;
}


/* A swept material (material-language.md, "Sweeps") compiled to its textured
 * file in a private temporary directory, opened, and removed at once; the
 * source then is that file, drawn like a textured .bsdf. */
static int build_swept_file(const llplot_options *o, const ll_material *material,
                            const ll_build_options *opts, const ll_monitor *shown,
                            llplot_source *s)
{
    const char *tmp = getenv("TMPDIR");
    char dir[4096], path[4200];
    ll_status st;
    int code;
    if (!tmp || !tmp[0])
        tmp = "/tmp";
    if ((size_t)snprintf(dir, sizeof dir, "%s/llplot-XXXXXX", tmp) >= sizeof dir)
        return llplot_fail(LLPLOT_EXIT_IO, "TMPDIR is too long");
    if (!mkdtemp(dir))
        return llplot_fail(LLPLOT_EXIT_IO, "%s: cannot create a temporary directory: %s", dir,
                           strerror(errno));
    snprintf(path, sizeof path, "%s/swept.bsdf", dir);
    st = ll_material_build(material, opts, shown, path);
    if (shown)
        fputc('\n', stderr);
    if (st == LL_OK)
        st = ll_bsdf_open(path, NULL, &s->bsdf);
    code = st == LL_OK ? choose_basis(o, s) : llplot_fail_ll(st, o->input);
    unlink(path);
    rmdir(dir);
    return code;
}

/* Compiling a glossy stack takes seconds: show how far it got when stderr
 * is a terminal (one line, rewritten in place). */
/* What show_progress prints: the monitor's user pointer is not const, the
 * input name is, so it travels inside this. */
typedef struct progress_label {
    const char *input;
} progress_label;

static int show_progress(void *user, double fraction, const char *stage)
{
    const progress_label *label = user;
    fprintf(stderr, "\rllplot: compiling %s: %3.0f%% %-24s", label->input,
            100.0 * fraction, stage ? stage : "");
    fflush(stderr);
    return 0;
}

/* The material's own setting of one part of the resolution (its `set
 * nodes=` or `orders=`), found without a search: asked with the other part
 * given, the resolution is chosen by no search exactly when the material
 * sets this part. 0 when it does not. */
static size_t material_setting(const ll_material *material, const ll_build_options *opts,
                               int nodes)
{
    ll_build_options other = *opts;
    size_t n = 0, m = 0, c = 0;
    int chosen = 1;
    if (nodes) {
        other.n_nodes = 0;
        other.n_orders = 1;
    } else {
        other.n_nodes = LL_BUILD_MIN_NODES;
        other.n_orders = 0;
    }
    if (ll_material_goal(material, &other, NULL, NULL, &chosen) != LL_OK || chosen ||
        ll_material_resolution(material, &other, NULL, &n, &m, &c) != LL_OK)
        return 0;
    return nodes ? n : m;
}

/* The resolution a picture is drawn at, with no resolution search (whose
 * answer, for a glossy stack hundreds of nodes, the preview's cap would
 * throw away): each part from --nodes/--orders, else the material's `set`
 * line, at most the preview's cap, else the cap. Says it on stderr. */
static void preview_resolution(const llplot_options *o, const ll_material *material,
                               ll_build_options *opts)
{
    size_t set_nodes = o->nodes ? 0 : material_setting(material, opts, 1);
    size_t set_orders = o->orders ? 0 : material_setting(material, opts, 0);
    if (!o->nodes)
        opts->n_nodes = set_nodes && set_nodes < PREVIEW_MAX_NODES ? set_nodes
                                                                   : PREVIEW_MAX_NODES;
    if (!o->orders)
        opts->n_orders = set_orders && set_orders < PREVIEW_MAX_ORDERS ? set_orders
                                                                      : PREVIEW_MAX_ORDERS;
    if (!o->nodes || !o->orders)
        fprintf(stderr,
                "llplot: %s: drawing at %zu nodes x %zu orders (a preview: the material's "
                "`set` or --nodes/--orders, at most %d x %d; no resolution search; a .bsdf "
                "from llbuild shows the chosen resolution)\n",
                o->input, opts->n_nodes, opts->n_orders, PREVIEW_MAX_NODES,
                PREVIEW_MAX_ORDERS);
}

static int compile_material(const llplot_options *o, int need_sampling, llplot_source *s)
{
    ll_material *material = NULL;
    ll_build_options opts = LL_BUILD_OPTIONS_INIT;
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    progress_label label;
    ll_monitor monitor = LL_MONITOR_INIT;
    const ll_monitor *shown = NULL;
    ll_status st = ll_material_parse_file(o->input, &material);
    int code = LLPLOT_EXIT_OK;
    if (st != LL_OK)
        return llplot_fail_ll(st, o->input);
    opts.n_nodes = o->nodes;
    opts.n_orders = o->orders;
    opts.threads = o->threads;
    if (isatty(STDERR_FILENO)) {
        label.input = o->input;
        monitor.progress = show_progress;
        monitor.user = &label;
        shown = &monitor;
    }
    preview_resolution(o, material, &opts);
    if (ll_material_basis_count(material) > 1) {
        /* A swept material is one textured file, not one set of layers:
         * build it and draw the file (its bases at the resolution above). */
        code = build_swept_file(o, material, &opts, shown, s);
        goto done;
    }
    st = ll_material_build_layers(material, &opts, shown, s->layers, &s->n_layers, &header);
    if (shown)
        fputc('\n', stderr);
    if (st != LL_OK) {
        code = llplot_fail_ll(st, o->input);
        goto done;
    }
    s->n_channels = s->n_layers;
    if (need_sampling)
        code = open_compiled_file(o, s, &header);
done:
    ll_material_destroy(material);
    return code;
}

int llplot_source_open(const llplot_options *o, int need_sampling, llplot_source *s)
{
    const char *slash = strrchr(o->input, '/');
    int is_bsdf = 0, code;
    ll_status st;
    memset(s, 0, sizeof *s);
    snprintf(s->label, sizeof s->label, "%s", slash ? slash + 1 : o->input);
    code = is_bsdf_file(o->input, &is_bsdf);
    if (code != LLPLOT_EXIT_OK)
        return code;
    if (!is_bsdf) {
        if (o->basis > 0)
            return llplot_fail(LLPLOT_EXIT_INPUT, "%s: --basis applies to textured .bsdf files only",
                               o->input);
        code = compile_material(o, need_sampling, s);
    } else {
        st = ll_bsdf_open(o->input, NULL, &s->bsdf);
        code = st == LL_OK ? choose_basis(o, s) : llplot_fail_ll(st, o->input);
    }
    if (code != LLPLOT_EXIT_OK)
        llplot_source_close(s);
    return code;
}

void llplot_source_close(llplot_source *s)
{
    size_t c;
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(s->layers[c]);
    ll_bsdf_release(s->bsdf);
    free(s->basis_coeffs);
    memset(s, 0, sizeof *s);
}

void llplot_source_eval(const llplot_source *s, double mu_i, double mu_o, double phi_d,
                        double rgb[3])
{
    size_t c;
    if (s->n_layers > 0) {
        /* The layers themselves: exact node values, no series truncation. */
        for (c = 0; c < 3; ++c)
            if (ll_layer_eval(s->layers[c < s->n_layers ? c : 0], mu_i, mu_o, phi_d, &rgb[c]) !=
                LL_OK)
                rgb[c] = 0.0;
        return;
    }
    if (ll_bsdf_eval(s->bsdf, mu_i, mu_o, phi_d, s->basis_coeffs, rgb) != LL_OK)
        rgb[0] = rgb[1] = rgb[2] = 0.0;
}
