/*
 * textured_grid: a textured .bsdf file from a material template, built basis
 * by basis with the public API (ll_material_build_layers at each point of
 * the grid, then ll_bsdf_write_textured), for the tests and checks of the
 * file's consumers (tests/llplot.sh, shims/pbrt-v3/check/check.sh).
 * llbuild makes such files from a swept material too (`alpha=[0.1 0.2]`,
 * material-language.md, "Sweeps"); this builder stays as an independent
 * one, on the public API only, so that the consumers' checks do not rest on
 * the sweep builder whose files they read.
 *
 *   textured_grid OUT.bsdf TEMPLATE NAME=V1,V2,... [NAME=V1,... ...]
 *
 * TEMPLATE is material text in which {0}, {1}, ... stand for the value of
 * axis 0, 1, ... (e.g. "dielectric eta=1.5 alpha={0}\nconductor eta=Au
 * alpha={1}"; "\n" in the argument is a newline). Each axis's values must
 * be strictly increasing. Every basis is built at one resolution, the
 * largest node and order counts that the resolution heuristic picks over
 * the grid (the sharpest sample's), unless the template sets it (`set
 * nodes= orders=`). The metadata is {"generator": ..., "parameters":
 * [NAME, ...]} in axis order: what ll_bsdf_get_parameter_name reads.
 * Exit status 0 on success, 1 with a message on stderr otherwise.
 */
#include <layerlab.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_AXES 4
#define MAX_VALUES 64

typedef struct axis {
    char name[128];
    double values[MAX_VALUES];
    size_t count;
} axis;

static int fail(const char *what, const char *detail)
{
    fprintf(stderr, "textured_grid: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    return 1;
}

static int parse_axis(const char *arg, axis *a)
{
    const char *eq = strchr(arg, '=');
    const char *p;
    size_t len;
    if (!eq || eq == arg)
        return 0;
    len = (size_t)(eq - arg);
    if (len >= sizeof a->name || strpbrk(arg, "\"\\") != NULL)
        return 0;
    memcpy(a->name, arg, len);
    a->name[len] = '\0';
    a->count = 0;
    for (p = eq + 1; *p;) {
        char *end;
        double v = strtod(p, &end);
        if (end == p || a->count == MAX_VALUES || (a->count > 0 && v <= a->values[a->count - 1]))
            return 0;
        a->values[a->count++] = v;
        if (*end == ',')
            ++end;
        else if (*end != '\0')
            return 0;
        p = end;
    }
    return a->count > 0;
}

/* The template with {k} replaced by the axis values of this grid point and
 * "\n" by newlines; NULL if it does not fit. */
static char *instantiate(const char *tmpl, const double *point, size_t n_axes)
{
    size_t cap = strlen(tmpl) + 64 * MAX_AXES + 1, at = 0;
    char *out = malloc(cap);
    const char *p;
    if (!out)
        return NULL;
    for (p = tmpl; *p; ++p) {
        if (p[0] == '{' && p[1] >= '0' && p[1] < (char)('0' + n_axes) && p[2] == '}') {
            at += (size_t)snprintf(out + at, cap - at, "%.9g", point[p[1] - '0']);
            p += 2;
        } else if (p[0] == '\\' && p[1] == 'n') {
            out[at++] = '\n';
            ++p;
        } else {
            out[at++] = *p;
        }
        if (at + 32 >= cap) {
            free(out);
            return NULL;
        }
    }
    out[at] = '\0';
    return out;
}

/* The axis values of basis b (axis 0 fastest, the format's order). */
static void grid_point(const axis *axes, size_t n_axes, size_t b, double *point)
{
    size_t k;
    for (k = 0; k < n_axes; ++k) {
        point[k] = axes[k].values[b % axes[k].count];
        b /= axes[k].count;
    }
}

static ll_material *parse_point(const char *tmpl, const axis *axes, size_t n_axes, size_t b)
{
    double point[MAX_AXES];
    char *text;
    ll_material *m = NULL;
    grid_point(axes, n_axes, b, point);
    text = instantiate(tmpl, point, n_axes);
    if (!text || ll_material_parse(text, "template", &m) != LL_OK)
        m = NULL;
    free(text);
    return m;
}

int main(int argc, char **argv)
{
    axis axes[MAX_AXES];
    size_t n_axes = (size_t)argc - 3, n_bases = 1, k, b, ch, nodes = 0, orders = 0;
    size_t n_channels = 0, counts[MAX_AXES];
    double positions[MAX_AXES * MAX_VALUES];
    size_t n_positions = 0;
    ll_layer **layers = NULL;
    ll_build_options opts = LL_BUILD_OPTIONS_INIT;
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    char metadata[1024];
    size_t at;
    int status = 1;
    if (argc < 4 || n_axes > MAX_AXES)
        return fail("usage: textured_grid OUT.bsdf TEMPLATE NAME=V1,V2,... (1 to 4 axes)", NULL);
    for (k = 0; k < n_axes; ++k) {
        if (!parse_axis(argv[3 + k], &axes[k]))
            return fail("bad axis (NAME=V1,V2,... strictly increasing)", argv[3 + k]);
        n_bases *= axes[k].count;
        counts[k] = axes[k].count;
        memcpy(positions + n_positions, axes[k].values, axes[k].count * sizeof(double));
        n_positions += axes[k].count;
    }
    /* One resolution for every basis: the largest the heuristic picks. */
    for (b = 0; b < n_bases; ++b) {
        size_t n, m, c;
        ll_material *mat = parse_point(argv[2], axes, n_axes, b);
        if (!mat)
            return fail("the template does not parse", ll_last_error_message());
        if (ll_material_resolution(mat, NULL, NULL, &n, &m, &c) != LL_OK) {
            ll_material_destroy(mat);
            return fail("resolution", ll_last_error_message());
        }
        ll_material_destroy(mat);
        nodes = n > nodes ? n : nodes;
        orders = m > orders ? m : orders;
        n_channels = c;
    }
    opts.n_nodes = nodes;
    opts.n_orders = orders;
    layers = calloc(n_bases * 3, sizeof *layers);
    if (!layers)
        return fail("out of memory", NULL);
    for (b = 0; b < n_bases; ++b) {
        size_t c = 0;
        ll_material *mat = parse_point(argv[2], axes, n_axes, b);
        ll_layer *out[3] = { NULL, NULL, NULL };
        ll_status s = mat ? ll_material_build_layers(mat, &opts, NULL, out, &c,
                                                     b == 0 ? &header : NULL)
                          : LL_ERROR_INVALID_ARGUMENT;
        ll_material_destroy(mat);
        if (s != LL_OK || c != n_channels) {
            fail("build", ll_last_error_message());
            goto done;
        }
        for (ch = 0; ch < c; ++ch)
            layers[b * n_channels + ch] = out[ch];
    }
    at = (size_t)snprintf(metadata, sizeof metadata,
                          "{\"generator\": \"layerlab tests/textured_grid\", \"nodes\": %zu, "
                          "\"orders\": %zu, \"parameters\": [",
                          nodes, orders);
    for (k = 0; k < n_axes && at < sizeof metadata; ++k)
        at += (size_t)snprintf(metadata + at, sizeof metadata - at, "%s\"%s\"", k ? ", " : "",
                               axes[k].name);
    if (at + 3 >= sizeof metadata) {
        fail("metadata too long", NULL);
        goto done;
    }
    memcpy(metadata + at, "]}", 3);
    header.metadata = metadata;
    if (ll_bsdf_write_textured(argv[1], (const ll_layer *const *)layers, n_channels, n_axes,
                               counts, positions, &header, NULL) != LL_OK) {
        fail("write", ll_last_error_message());
        goto done;
    }
    printf("textured_grid: %s: %zu bases, %zu nodes x %zu orders, %zu channel(s)\n", argv[1],
           n_bases, nodes, orders, n_channels);
    status = 0;
done:
    for (b = 0; b < n_bases * 3; ++b)
        ll_layer_destroy(layers[b]);
    free(layers);
    return status;
}
