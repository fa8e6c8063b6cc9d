/*
 * llplot — the parameter space of a textured .bsdf file: its parameters'
 * names and sample positions, the point a picture is drawn at (--param or
 * the middle of each range), and the basis weights of a point
 * (ll_bsdf_basis_coefficients: linear in each parameter, clamped to its
 * range).
 */
#include "llplot.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void llplot_axes_close(llplot_axes *a)
{
    free((void *)a->names);
    free((void *)a->positions);
    free(a->counts);
    free(a->point);
    memset(a, 0, sizeof *a);
}

/* The file's names as "a, b, c" for messages (truncated to size). */
static void list_names(const llplot_axes *a, char *buf, size_t size)
{
    size_t k, at = 0;
    buf[0] = '\0';
    for (k = 0; k < a->n && at + 1 < size; ++k) {
        int n = snprintf(buf + at, size - at, "%s%s", k ? ", " : "", a->names[k]);
        if (n < 0)
            break;
        at += (size_t)n;
    }
}

int llplot_axes_find(const llplot_axes *a, const char *name, size_t len, const char *what,
                     const char *input, size_t *index)
{
    char names[512];
    size_t k;
    for (k = 0; k < a->n; ++k)
        if (strlen(a->names[k]) == len && memcmp(a->names[k], name, len) == 0) {
            *index = k;
            return LLPLOT_EXIT_OK;
        }
    list_names(a, names, sizeof names);
    return llplot_fail(LLPLOT_EXIT_INPUT, "%s: %s '%.*s': the file has no such parameter (it has %s)",
                       input, what, (int)len, name, names);
}

int llplot_axes_open(const llplot_options *o, const llplot_source *s, const char *what,
                     llplot_axes *a)
{
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    size_t k;
    int code = LLPLOT_EXIT_OK;
    memset(a, 0, sizeof *a);
    if (!s->bsdf || s->n_layers > 0 || ll_bsdf_get_info(s->bsdf, &info) != LL_OK ||
        info.n_parameters == 0)
        return llplot_fail(LLPLOT_EXIT_INPUT,
                           "%s: %s needs a textured .bsdf file or a swept material (this one "
                           "has no parameters)",
                           o->input, what);
    a->n = info.n_parameters;
    a->n_bases = info.n_bases;
    a->names = calloc(a->n, sizeof *a->names);
    a->positions = calloc(a->n, sizeof *a->positions);
    a->counts = calloc(a->n, sizeof *a->counts);
    a->point = calloc(a->n, sizeof *a->point);
    if (!a->names || !a->positions || !a->counts || !a->point) {
        llplot_axes_close(a);
        return llplot_fail(LLPLOT_EXIT_IO, "out of memory");
    }
    for (k = 0; k < a->n; ++k) {
        ll_status st = ll_bsdf_get_parameter_name(s->bsdf, k, &a->names[k]);
        if (st == LL_OK)
            st = ll_bsdf_get_parameter(s->bsdf, k, &a->counts[k], &a->positions[k]);
        if (st != LL_OK) {
            llplot_axes_close(a);
            return llplot_fail_ll(st, o->input);
        }
        a->point[k] = 0.5 * ((double)a->positions[k][0] + (double)a->positions[k][a->counts[k] - 1]);
    }
    for (k = 0; k < o->n_params && code == LLPLOT_EXIT_OK; ++k) {
        size_t index;
        code = llplot_axes_find(a, o->params[k].name, o->params[k].name_len, "--param", o->input,
                                &index);
        if (code == LLPLOT_EXIT_OK)
            a->point[index] = o->params[k].value;
    }
    if (code != LLPLOT_EXIT_OK)
        llplot_axes_close(a);
    return code;
}

int llplot_axes_weights(const llplot_source *s, const double *point, float *coeffs)
{
    ll_status st = ll_bsdf_basis_coefficients(s->bsdf, point, coeffs);
    return st == LL_OK ? LLPLOT_EXIT_OK : llplot_fail_ll(st, s->label);
}

void llplot_format_value(double v, char *buf, size_t size)
{
    snprintf(buf, size, "%.4g", v);
}

int llplot_source_set_point(const llplot_options *o, llplot_source *s)
{
    llplot_axes a;
    int code = llplot_axes_open(o, s, "--param", &a);
    if (code != LLPLOT_EXIT_OK)
        return code;
    /* A textured source of several bases has its one-hot weights allocated
     * (source.c); with one basis its weight is 1 whatever the point. */
    if (s->basis_coeffs)
        code = llplot_axes_weights(s, a.point, s->basis_coeffs);
    llplot_axes_close(&a);
    return code;
}
