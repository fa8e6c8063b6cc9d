/*
 * Sweeps: a number parameter written as a bracketed list of values is one
 * axis of a textured file (docs/material-language.md, "Sweeps").
 *
 *     dielectric name=coat eta=1.5 alpha=[0.02 0.05 0.1 0.2]
 *     conductor  eta=Au alpha=[0.05..0.4:8]
 *
 * Each value is one number or an R,G,B triple (all of one kind in a
 * sweep); [A..B:N] is N evenly spaced values from A to B, both included
 * (component by component for triples). Values must be strictly
 * increasing: a scalar by its value, a triple by its luminance
 * (0.212671 R + 0.715160 G + 0.072169 B, the .bsdf Y channel's weights),
 * and that number, the value or the luminance, is the position the file
 * stores for the sample, so a renderer's texture gives a roughness or a
 * luminance and the bases are interpolated in it. Both must also increase
 * once rounded to the file's float. Axes are numbered in order of
 * appearance (top word first, left to right on a line), at most
 * LL_MATERIAL_MAX_AXES; axis 0 runs fastest in the basis index, as the
 * format orders bases. An axis is named LABEL.key when its word carries
 * name=LABEL, else INDEX.key with INDEX the word's 0-based position in the
 * stack from the top (the index of its entry in the metadata's "layers").
 */
#include "material/word_table.h"

#include <float.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* Values one axis may have, and bases a material may have (the product;
 * 16^4, or 256 x 256): every basis is a whole build, and planning and the
 * estimate visit each, in about 10 us a basis. */
#define LL_SWEEP_MAX_VALUES 4096
#define LL_MATERIAL_MAX_BASES 65536

static double luminance(const ll_number *x)
{
    return LL_LUMA_R * x->v[0] + LL_LUMA_G * x->v[1] + LL_LUMA_B * x->v[2];
}

static double position_of(const ll_number *x) { return x->count == 3 ? luminance(x) : x->v[0]; }

ll_status ll_parse_label(const ll_parser *p, ll_word *w, const ll_token *key, const ll_token *v)
{
    size_t i;
    if (w->label[0])
        return ll_parse_error(p, key->begin, "name is given twice");
    if (v->len > LL_WORD_LABEL_MAX)
        return ll_parse_error(p, v->begin, "name: '%.*s' is longer than %d characters",
                              (int)v->len, v->begin, LL_WORD_LABEL_MAX);
    for (i = 0; i < v->len; ++i) {
        char c = v->begin[i];
        int letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
        if (!(letter || c == '_' || (i > 0 && ((c >= '0' && c <= '9') || c == '-'))))
            return ll_parse_error(p, v->begin + i,
                                  "name: '%.*s' is not a label; expected a letter or _ first, "
                                  "then letters, digits, _ or - (such as coat)",
                                  (int)v->len, v->begin);
    }
    memcpy(w->label, v->begin, v->len);
    w->label[v->len] = '\0';
    w->label_line = ll_parser_line(p);
    w->label_column = ll_parser_column(p, v->begin);
    return LL_OK;
}

/* One value of a sweep, checked as a plain value of the parameter is. */
static ll_status parse_value(const ll_parser *p, const ll_word *w, const ll_param_desc *param,
                             const ll_token *key, const ll_token *t, ll_number *out)
{
    ll_status s;
    memset(out, 0, sizeof *out);
    s = ll_parse_number(p, key, t, out);
    if (s == LL_OK)
        s = ll_parse_check_range(p, key, t, out, param->lo, param->lo_closed, param->hi,
                                 param->hi_closed, param->why);
    if (s == LL_OK && param->check)
        s = param->check(p, w, key, t, out);
    return s;
}

/* [A..B:N] into values (N of them). */
static ll_status parse_range(const ll_parser *p, const ll_word *w, const ll_param_desc *param,
                             const ll_token *key, const ll_token *inner, const char *dots,
                             ll_number *values, size_t *count, const char **at)
{
    const char *end = inner->begin + inner->len, *colon = memchr(dots, ':', (size_t)(end - dots));
    ll_token a, b;
    ll_number x, y;
    size_t n = 0, i, k;
    ll_status s;
    if (!colon || colon + 1 == end)
        return ll_parse_error(p, dots, "%.*s: a range is [FROM..TO:COUNT], such as [0.05..0.4:8]",
                              (int)key->len, key->begin);
    for (i = 1; colon + i < end; ++i) {
        char c = colon[i];
        if (c < '0' || c > '9' || i > 5)
            return ll_parse_error(p, colon + 1,
                                  "%.*s: the count after ':' must be a whole number from 2 to "
                                  "%d, got '%.*s'",
                                  (int)key->len, key->begin, LL_SWEEP_MAX_VALUES,
                                  (int)(end - colon - 1), colon + 1);
        n = n * 10 + (size_t)(c - '0');
    }
    if (n < 2 || n > LL_SWEEP_MAX_VALUES)
        return ll_parse_error(p, colon + 1, "%.*s: a range of %zu values; expected 2 to %d",
                              (int)key->len, key->begin, n, LL_SWEEP_MAX_VALUES);
    a.begin = inner->begin;
    a.len = (size_t)(dots - inner->begin);
    b.begin = dots + 2;
    b.len = (size_t)(colon - b.begin);
    if (a.len == 0 || b.len == 0)
        return ll_parse_error(p, a.len == 0 ? a.begin : b.begin,
                              "%.*s: a range is [FROM..TO:COUNT], such as [0.05..0.4:8]",
                              (int)key->len, key->begin);
    if ((s = parse_value(p, w, param, key, &a, &x)) != LL_OK ||
        (s = parse_value(p, w, param, key, &b, &y)) != LL_OK)
        return s;
    if (x.count != y.count)
        return ll_parse_error(p, b.begin,
                              "%.*s: the range's ends must both be one value or both R,G,B "
                              "triples",
                              (int)key->len, key->begin);
    for (i = 0; i < n; ++i) {
        double t = (double)i / (double)(n - 1);
        values[i] = x;
        for (k = 0; k < 3; ++k)
            values[i].v[k] = i + 1 == n ? y.v[k] : x.v[k] + t * (y.v[k] - x.v[k]);
    }
    *count = n;
    *at = b.begin; /* an error about increasing points at TO */
    return LL_OK;
}

/* Values separated by spaces. at[k]: where value k is written. */
static ll_status parse_list(const ll_parser *p, const ll_word *w, const ll_param_desc *param,
                            const ll_token *key, const ll_token *inner, ll_number *values,
                            const char **at, size_t *count)
{
    const char *s = inner->begin, *end = inner->begin + inner->len;
    size_t n = 0;
    ll_status st;
    while (1) {
        ll_token t;
        while (s < end && (*s == ' ' || *s == '\t'))
            ++s;
        if (s == end)
            break;
        t.begin = s;
        while (s < end && *s != ' ' && *s != '\t')
            ++s;
        t.len = (size_t)(s - t.begin);
        if (n == LL_SWEEP_MAX_VALUES)
            return ll_parse_error(p, t.begin, "%.*s: more than %d values in a sweep",
                                  (int)key->len, key->begin, LL_SWEEP_MAX_VALUES);
        if ((st = parse_value(p, w, param, key, &t, &values[n])) != LL_OK)
            return st;
        if (n > 0 && values[n].count != values[0].count)
            return ll_parse_error(p, t.begin,
                                  "%.*s: the values of a sweep must all be one value or all "
                                  "R,G,B triples; '%.*s' mixes them",
                                  (int)key->len, key->begin, (int)t.len, t.begin);
        at[n++] = t.begin;
    }
    *count = n;
    return LL_OK;
}

ll_status ll_parse_sweep(const ll_parser *p, ll_material *m, ll_word *w,
                         const ll_param_desc *param, const ll_token *key, const ll_token *v)
{
    ll_token inner;
    ll_sweep *axis;
    ll_number *values = NULL;
    const char **at = NULL, *dots;
    size_t count = 0, k;
    ll_status s = LL_OK;

    if (param->parse || param->slot < 0)
        return ll_parse_error(p, v->begin,
                              "%.*s cannot be swept: only number parameters can (such as "
                              "alpha=[0.05 0.1 0.2])",
                              (int)key->len, key->begin);
    if (w->number[param->slot].count != 0)
        return ll_parse_error(p, key->begin, "%.*s is given twice", (int)key->len, key->begin);
    if (v->len < 2 || v->begin[v->len - 1] != ']')
        return ll_parse_error(p, v->begin, "%.*s: a sweep is [v1 v2 ...] or [FROM..TO:COUNT]",
                              (int)key->len, key->begin);
    if (m->n_axes == LL_MATERIAL_MAX_AXES)
        return ll_parse_error(p, v->begin,
                              "%.*s: a sweep beyond the %d a material may have (one axis each)",
                              (int)key->len, key->begin, LL_MATERIAL_MAX_AXES);
    inner.begin = v->begin + 1;
    inner.len = v->len - 2;
    values = ll_alloc_array(LL_SWEEP_MAX_VALUES, sizeof *values);
    at = ll_alloc_array(LL_SWEEP_MAX_VALUES, sizeof *at);
    if (!values || !at) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory parsing a sweep");
        goto fail;
    }
    dots = NULL;
    for (k = 0; k + 1 < inner.len; ++k)
        if (inner.begin[k] == '.' && inner.begin[k + 1] == '.') {
            dots = inner.begin + k;
            break;
        }
    if (dots) {
        const char *to;
        s = parse_range(p, w, param, key, &inner, dots, values, &count, &to);
        for (k = 0; k < count; ++k)
            at[k] = to;
    } else {
        s = parse_list(p, w, param, key, &inner, values, at, &count);
    }
    if (s != LL_OK)
        goto fail;
    if (count < 2) {
        s = ll_parse_error(p, v->begin,
                           "%.*s: a sweep needs at least two values (write one value "
                           "without brackets)",
                           (int)key->len, key->begin);
        goto fail;
    }
    for (k = 1; k < count; ++k) {
        double a = position_of(&values[k - 1]), b = position_of(&values[k]);
        if (!(b > a) || !((float)b > (float)a)) {
            s = ll_parse_error(p, at[k],
                               "%.*s: the values of a sweep must be strictly increasing%s: "
                               "%.9g after %.9g%s",
                               (int)key->len, key->begin,
                               values[k].count == 3 ? " in luminance (0.2127 R + 0.7152 G + "
                                                      "0.0722 B)"
                                                    : "",
                               b, a, b > a ? " (equal once rounded to the file's float)" : "");
            goto fail;
        }
    }
    axis = &m->axes[m->n_axes];
    memset(axis, 0, sizeof *axis);
    axis->values = ll_alloc_array(count, sizeof *axis->values);
    axis->positions = ll_alloc_array(count, sizeof *axis->positions);
    if (!axis->values || !axis->positions) {
        ll_free(axis->values);
        ll_free(axis->positions);
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory parsing a sweep");
        goto fail;
    }
    for (k = 0; k < count; ++k) {
        axis->values[k] = values[k];
        axis->values[k].line = ll_parser_line(p);
        axis->values[k].column = ll_parser_column(p, v->begin);
        axis->positions[k] = position_of(&values[k]);
    }
    axis->word = (size_t)(w - m->words);
    axis->slot = param->slot;
    axis->count = count;
    snprintf(axis->name, sizeof axis->name, "%.*s", (int)key->len, key->begin);
    m->n_axes++;
    w->number[param->slot] = axis->values[0];
fail:
    ll_free(values);
    ll_free(at);
    return s;
}

ll_status ll_material_finish_axes(ll_material *m)
{
    size_t i, j, a, bases = 1;
    for (i = 0; i < m->count; ++i)
        for (j = 0; j < i && m->words[i].label[0]; ++j)
            if (!strcmp(m->words[i].label, m->words[j].label))
                return ll_fail(LL_ERROR_PARSE,
                               "%s:%zu:%zu: name=%s is given to line %zu's %s already; "
                               "expected a name of its own",
                               m->source, m->words[i].label_line, m->words[i].label_column,
                               m->words[i].label, m->words[j].line,
                               ll_word_name(&m->words[j]));
    for (a = 0; a < m->n_axes; ++a) {
        ll_sweep *x = &m->axes[a];
        const ll_word *w = &m->words[x->word];
        char key[24];
        snprintf(key, sizeof key, "%s", x->name);
        if (w->label[0])
            snprintf(x->name, sizeof x->name, "%s.%s", w->label, key);
        else
            snprintf(x->name, sizeof x->name, "%zu.%s", x->word, key);
        if (!ll_size_mul(bases, x->count, &bases) || bases > LL_MATERIAL_MAX_BASES)
            return ll_fail(LL_ERROR_PARSE,
                           "%s:%zu:%zu: the sweeps make more than %d bases, the most a "
                           "material may have (every basis is a whole build; the planning "
                           "and the estimate visit each)",
                           m->source, x->values[0].line, x->values[0].column,
                           LL_MATERIAL_MAX_BASES);
    }
    return LL_OK;
}

void ll_material_free_axes(ll_material *m)
{
    size_t a;
    for (a = 0; a < m->n_axes; ++a) {
        ll_free(m->axes[a].values);
        ll_free(m->axes[a].positions);
    }
    m->n_axes = 0;
}

void ll_basis_indices(const ll_material *m, size_t basis, size_t *index)
{
    size_t a;
    for (a = 0; a < m->n_axes; ++a) {
        index[a] = basis % m->axes[a].count;
        basis /= m->axes[a].count;
    }
}

void ll_material_basis_view(const ll_material *m, size_t basis, ll_word *words,
                            ll_material *out)
{
    size_t index[LL_MATERIAL_MAX_AXES], a;
    ll_basis_indices(m, basis, index);
    memcpy(words, m->words, m->count * sizeof *words);
    for (a = 0; a < m->n_axes; ++a)
        words[m->axes[a].word].number[m->axes[a].slot] = m->axes[a].values[index[a]];
    *out = *m;
    out->words = words;
    out->capacity = m->count;
    out->n_axes = 0;
}

ll_status ll_material_plan_bases(const ll_material *m, const ll_build_options *o,
                                 ll_watch *watch, size_t *n_nodes, size_t *n_orders,
                                 size_t *n_channels, double *error)
{
    size_t bases = ll_material_basis_count(m), b, n = 0, orders = 0, nch = 0;
    ll_resolution_memo memo = LL_RESOLUTION_MEMO_INIT;
    ll_word *words;
    ll_status s = LL_OK;
    double worst = -1.0;
    memo.watch = watch;
    if (m->n_axes == 0) {
        s = ll_material_plan_memo(m, o, &memo, n_nodes, n_orders, n_channels, error);
        ll_resolution_memo_free(&memo);
        return s;
    }
    words = ll_alloc_array(m->count, sizeof *words);
    if (!words)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", m->source);
    /* Every basis: a word's heuristic depends on its own values and on the
     * indices above it, so the largest need may be at any corner. */
    for (b = 0; b < bases && s == LL_OK; ++b) {
        ll_material view;
        size_t bn, bm, bc;
        double be;
        ll_material_basis_view(m, b, words, &view);
        s = ll_material_plan_memo(&view, o, &memo, &bn, &bm, &bc, &be);
        if (s == LL_OK) {
            n = bn > n ? bn : n;
            orders = bm > orders ? bm : orders;
            nch = bc;
            if (b == 0 || !(be <= worst) || be < 0.0)
                worst = be;
        }
    }
    ll_free(words);
    ll_resolution_memo_free(&memo);
    if (s == LL_OK) {
        *n_nodes = n;
        *n_orders = orders;
        *n_channels = nch;
        if (error)
            *error = worst;
    }
    return s;
}

/* ------------------------------------------------------------ the API */

size_t ll_material_axis_count(const ll_material *m) { return m ? m->n_axes : 0; }

size_t ll_material_basis_count(const ll_material *m)
{
    size_t a, bases = 1;
    if (!m)
        return 0;
    /* (At most 2^32 - 1: checked when parsed.) */
    for (a = 0; a < m->n_axes; ++a)
        bases *= m->axes[a].count;
    return bases;
}

ll_status ll_material_get_axis(const ll_material *m, size_t axis, ll_material_axis *out)
{
    ll_material_axis full = LL_MATERIAL_AXIS_INIT;
    if (!m || !out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_get_axis: material or out is NULL");
    if (axis >= m->n_axes)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_get_axis: axis %zu, but the material has %zu", axis,
                       m->n_axes);
    full.name = m->axes[axis].name;
    full.n_values = m->axes[axis].count;
    full.positions = m->axes[axis].positions;
    return ll_struct_write(out, &full, sizeof full, "ll_material_get_axis", "ll_material_axis");
}
