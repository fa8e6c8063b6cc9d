/*
 * The material language: lexer and parser (docs/material-language.md).
 *
 * A description is a list of lines. Each line is empty, a comment (`#` to
 * the end of the line), a settings line `set key=value ...`, or one word of
 * the stack with its parameters: `dielectric eta=1.5 alpha=0.1`. Words are
 * listed top to bottom. Every error names source:line:column and what was
 * expected there.
 */
#include "material/word_table.h"
#include "material/word_suggest.h"
#include "support/parse_number.h"
#include "support/regular_file.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct ll_parser {
    const char *source;       /* for messages                          */
    const char *material_dir; /* for names and relative paths; nullable */
    const char *line_start;
    size_t line;
    ll_material *m;
};
typedef struct ll_parser parser;
typedef ll_token token;

static size_t column_of(const parser *p, const char *at) { return (size_t)(at - p->line_start) + 1; }

size_t ll_parser_line(const ll_parser *p) { return p->line; }
size_t ll_parser_column(const ll_parser *p, const char *at) { return column_of(p, at); }
const char *ll_parser_dir(const ll_parser *p) { return p->material_dir; }

ll_status ll_parse_error(const parser *p, const char *at, const char *fmt, ...)
{
    char what[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return ll_fail(LL_ERROR_PARSE, "%s:%zu:%zu: %s", p->source, p->line, column_of(p, at), what);
}

int ll_token_is(const token *t, const char *s)
{
    return strlen(s) == t->len && memcmp(t->begin, s, t->len) == 0;
}

/* ------------------------------------------------------------ numbers */

/* One real number, the whole of [s, s + len): digits with an optional sign,
 * point and exponent (no hex, inf or nan). */
int ll_scan_real(const char *s, size_t len, double *out)
{
    char buf[64], *end;
    size_t i;
    int digits = 0;
    if (len == 0 || len >= sizeof buf)
        return 0;
    for (i = 0; i < len; ++i) {
        char c = s[i];
        if (c >= '0' && c <= '9')
            digits = 1;
        else if (!(c == '+' || c == '-' || c == '.' || c == 'e' || c == 'E'))
            return 0;
    }
    if (!digits)
        return 0;
    memcpy(buf, s, len);
    buf[len] = '\0';
    *out = ll_parse_double(buf, &end);
    return *end == '\0' && ll_is_finite(*out);
}

int ll_split_commas(const token *v, token parts[3])
{
    int count = 0;
    const char *p = v->begin, *end = v->begin + v->len;
    while (1) {
        const char *comma = memchr(p, ',', (size_t)(end - p));
        const char *stop = comma ? comma : end;
        if (count == 3 || stop == p)
            return 0;
        parts[count].begin = p;
        parts[count].len = (size_t)(stop - p);
        ++count;
        if (!comma)
            return count;
        p = comma + 1;
    }
}

/* A number as one value or three. */
ll_status ll_parse_number(const parser *p, const token *key, const token *v, ll_number *out)
{
    token parts[3];
    int count = ll_split_commas(v, parts), k;
    if (count == 1 || count == 3) {
        for (k = 0; k < count; ++k)
            if (!ll_scan_real(parts[k].begin, parts[k].len, &out->v[k]))
                return ll_parse_error(p, parts[k].begin,
                                   "%.*s: '%.*s' is not a number; expected a decimal number "
                                   "such as 0.5 or 1e-3",
                                   (int)key->len, key->begin, (int)parts[k].len, parts[k].begin);
    } else {
        return ll_parse_error(p, v->begin,
                           "%.*s: expected one value or three comma-separated values (R,G,B), "
                           "got '%.*s'",
                           (int)key->len, key->begin, (int)v->len, v->begin);
    }
    if (count == 1)
        out->v[1] = out->v[2] = out->v[0];
    out->count = count;
    out->line = p->line;
    out->column = column_of(p, v->begin);
    return LL_OK;
}

/* Every channel value of x within [lo, hi] (bounds included when the
 * matching flag is set); else an error naming the value. */
ll_status ll_parse_check_range(const parser *p, const token *key, const token *v,
                               const ll_number *x, double lo, int lo_closed, double hi,
                               int hi_closed, const char *why)
{
    int k;
    for (k = 0; k < x->count; ++k) {
        double a = x->v[k];
        int ok = (lo_closed ? a >= lo : a > lo) && (hi_closed ? a <= hi : a < hi);
        if (!ok)
            return ll_parse_error(p, v->begin, "%.*s=%g is out of range: %s", (int)key->len,
                               key->begin, a, why);
    }
    return LL_OK;
}

/* Unsigned integer setting. */
static ll_status parse_count(const parser *p, const token *key, const token *v, size_t *out)
{
    size_t i, value = 0;
    if (v->len == 0 || v->len > 9)
        goto bad;
    for (i = 0; i < v->len; ++i) {
        if (v->begin[i] < '0' || v->begin[i] > '9')
            goto bad;
        value = value * 10 + (size_t)(v->begin[i] - '0');
    }
    *out = value;
    return LL_OK;
bad:
    return ll_parse_error(p, v->begin, "%.*s: expected a whole number, got '%.*s'", (int)key->len,
                       key->begin, (int)v->len, v->begin);
}

/* ---------------------------------------------------------------- lexer */

/* Next token of the line at *at: a run up to whitespace or `#`; a double
 * quote starts a quoted run (for paths with spaces) that ends at the next
 * quote. Returns 0 at the end of the line (or a comment). */
static ll_status next_token(const parser *p, const char **at, const char *line_end, token *t,
                            int *found)
{
    const char *s = *at;
    *found = 0;
    while (s < line_end && (*s == ' ' || *s == '\t' || *s == '\r'))
        ++s;
    if (s == line_end || *s == '#') {
        *at = line_end;
        return LL_OK;
    }
    t->begin = s;
    while (s < line_end && *s != ' ' && *s != '\t' && *s != '\r' && *s != '#') {
        if (*s == '"') {
            const char *close = memchr(s + 1, '"', (size_t)(line_end - s - 1));
            if (!close)
                return ll_parse_error(p, s, "unterminated quote; expected a closing \"");
            s = close;
        } else if (*s == '[') {
            /* A sweep, alpha=[0.02 0.05 0.1]: its spaces are inside the value. */
            const char *close = memchr(s + 1, ']', (size_t)(line_end - s - 1));
            if (!close)
                return ll_parse_error(p, s, "unterminated sweep; expected a closing ]");
            s = close;
        }
        ++s;
    }
    t->len = (size_t)(s - t->begin);
    *at = s;
    *found = 1;
    return LL_OK;
}

/* Split key=value; the value loses its quotes. */
static ll_status split_key_value(const parser *p, const token *t, token *key, token *value)
{
    const char *eq = memchr(t->begin, '=', t->len);
    size_t i;
    if (!eq || eq == t->begin)
        return ll_parse_error(p, t->begin, "expected key=value, got '%.*s'", (int)t->len,
                           t->begin);
    key->begin = t->begin;
    key->len = (size_t)(eq - t->begin);
    for (i = 0; i < key->len; ++i) {
        char c = key->begin[i];
        if (!((c >= 'a' && c <= 'z') || c == '_'))
            return ll_parse_error(p, t->begin, "'%.*s' is not a parameter name; expected key=value",
                               (int)key->len, key->begin);
    }
    value->begin = eq + 1;
    value->len = t->len - key->len - 1;
    if (value->len >= 2 && value->begin[0] == '"' && value->begin[value->len - 1] == '"') {
        value->begin++;
        value->len -= 2;
    }
    if (value->len == 0)
        return ll_parse_error(p, eq + 1, "%.*s= has no value", (int)key->len, key->begin);
    return LL_OK;
}

/* --------------------------------------------------------------- words */

static const ll_param_desc *find_param(const ll_word_desc *d, const token *key)
{
    size_t i;
    for (i = 0; i < LL_WORD_MAX_PARAMS && d->params[i].key; ++i)
        if (ll_token_is(key, d->params[i].key))
            return &d->params[i];
    return NULL;
}

/* "albedo tau g phase kappa": the keys of a word, for messages. */
static void list_keys(const ll_word_desc *d, char *buf, size_t cap)
{
    size_t i, len = 0;
    buf[0] = '\0';
    for (i = 0; i < LL_WORD_MAX_PARAMS && d->params[i].key; ++i) {
        int k = snprintf(buf + len, cap - len, "%s%s", i ? " " : "", d->params[i].key);
        if (k < 0 || (size_t)k >= cap - len)
            return;
        len += (size_t)k;
    }
}

static ll_status parse_word_parameter(parser *p, ll_word *w, const token *t)
{
    token key, v;
    const ll_word_desc *d = w->desc;
    const ll_param_desc *param;
    ll_number *slot;
    ll_status s = split_key_value(p, t, &key, &v);
    if (s != LL_OK)
        return s;
    param = find_param(d, &key);
    if (!param && ll_token_is(&key, "name"))
        return ll_parse_label(p, w, &key, &v);
    if (!param) {
        char keys[256];
        list_keys(d, keys, sizeof keys);
        return ll_parse_error(p, key.begin, "%s has no parameter '%.*s'; expected one of: %s",
                              d->name, (int)key.len, key.begin, keys);
    }
    if (v.begin[0] == '[')
        return ll_parse_sweep(p, p->m, w, param, &key, &v);
    if (param->parse)
        return param->parse(p, w, &key, &v);
    slot = &w->number[param->slot];
    if (slot->count != 0)
        return ll_parse_error(p, key.begin, "%.*s is given twice", (int)key.len, key.begin);
    s = ll_parse_number(p, &key, &v, slot);
    if (s == LL_OK)
        s = ll_parse_check_range(p, &key, &v, slot, param->lo, param->lo_closed, param->hi,
                                 param->hi_closed, param->why);
    if (s == LL_OK && param->check)
        s = param->check(p, w, &key, &v, slot);
    return s;
}

/* What a word still needs once its line is read. */
static ll_status finish_word(const parser *p, ll_word *w, const char *word_at)
{
    const ll_word_desc *d = w->desc;
    size_t i;
    for (i = 0; i < LL_WORD_MAX_PARAMS && d->params[i].key; ++i) {
        const ll_param_desc *param = &d->params[i];
        if (param->required && param->slot >= 0 && w->number[param->slot].count == 0)
            return ll_parse_error(p, word_at, "%s needs %s=...; for example: %s", d->name,
                                  param->key, d->example);
    }
    return d->finish ? d->finish(p, w, word_at) : LL_OK;
}

static ll_status parse_word(parser *p, const ll_word_desc *desc, const token *name,
                            const char *at, const char *line_end)
{
    ll_word *w, *grown;
    token t;
    int found;
    ll_status s;
    size_t count = p->m->count;

    if (count == p->m->capacity) {
        /* Geometric growth: a text of millions of words parses in linear
         * time. */
        grown = ll_grow_array(p->m->words, &p->m->capacity, 8, sizeof *grown);
        if (!grown)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory parsing %s", p->source);
        p->m->words = grown;
    }
    w = &p->m->words[count];
    memset(w, 0, sizeof *w);
    p->m->count = count + 1;
    w->desc = desc;
    w->line = p->line;
    w->column = column_of(p, name->begin);
    while (1) {
        s = next_token(p, &at, line_end, &t, &found);
        if (s != LL_OK || !found)
            break;
        s = parse_word_parameter(p, w, &t);
        if (s != LL_OK)
            return s;
    }
    if (s != LL_OK)
        return s;
    return finish_word(p, w, name->begin);
}

/* "diffuse, dielectric, conductor, medium, measured": the table's words. */
static void list_words(char *buf, size_t cap)
{
    size_t i, len = 0;
    buf[0] = '\0';
    for (i = 0; i < ll_word_table_size; ++i) {
        int k = snprintf(buf + len, cap - len, "%s%s", i ? ", " : "", ll_word_table[i]->name);
        if (k < 0 || (size_t)k >= cap - len)
            return;
        len += (size_t)k;
    }
}

/* set tolerance=T or mu_min=C: one number in [lo, hi) or (lo, hi] (the
 * open end as named by `range`), stored once in *slot. */
static ll_status parse_goal(parser *p, const token *key, const token *v, double *slot,
                            double lo, int lo_closed, double hi, int hi_closed,
                            const char *range)
{
    ll_number x;
    ll_status s;
    if (*slot > 0.0)
        return ll_parse_error(p, key->begin, "%.*s is set twice", (int)key->len, key->begin);
    memset(&x, 0, sizeof x);
    s = ll_parse_number(p, key, v, &x);
    if (s == LL_OK && (x.count != 1 || !(lo_closed ? x.v[0] >= lo : x.v[0] > lo) ||
                       !(hi_closed ? x.v[0] <= hi : x.v[0] < hi)))
        s = ll_parse_error(p, v->begin, "%.*s: expected one value in %s", (int)key->len,
                           key->begin, range);
    if (s == LL_OK)
        *slot = x.v[0];
    return s;
}

/* set nodes=N orders=M channels=1|3 error=E tolerance=T mu_min=C */
static ll_status parse_settings(parser *p, const char *at, const char *line_end)
{
    token t, key, v;
    int found;
    ll_material *m = p->m;
    ll_status s;
    while (1) {
        s = next_token(p, &at, line_end, &t, &found);
        if (s != LL_OK || !found)
            return s;
        s = split_key_value(p, &t, &key, &v);
        if (s != LL_OK)
            return s;
        if (ll_token_is(&key, "nodes")) {
            if (m->nodes)
                return ll_parse_error(p, key.begin, "nodes is set twice");
            s = parse_count(p, &key, &v, &m->nodes);
            if (s == LL_OK && (m->nodes < 2 || m->nodes % 2))
                s = ll_parse_error(p, v.begin,
                                   "nodes=%zu: a build needs an even count of at least %d",
                                   m->nodes, LL_MATERIAL_MIN_NODES);
            else if (s == LL_OK && m->nodes > LL_MATERIAL_MAX_RESOLUTION)
                s = ll_parse_error(p, v.begin, "nodes=%zu is beyond the %d supported", m->nodes,
                                   LL_MATERIAL_MAX_RESOLUTION);
        } else if (ll_token_is(&key, "orders")) {
            if (m->orders)
                return ll_parse_error(p, key.begin, "orders is set twice");
            s = parse_count(p, &key, &v, &m->orders);
            if (s == LL_OK && m->orders < 1)
                s = ll_parse_error(p, v.begin, "orders=0: expected at least 1");
            else if (s == LL_OK && m->orders > LL_MATERIAL_MAX_RESOLUTION)
                s = ll_parse_error(p, v.begin, "orders=%zu is beyond the %d supported",
                                   m->orders, LL_MATERIAL_MAX_RESOLUTION);
        } else if (ll_token_is(&key, "channels")) {
            if (m->channels)
                return ll_parse_error(p, key.begin, "channels is set twice");
            if (ll_token_is(&v, "1") || ll_token_is(&v, "mono"))
                m->channels = 1;
            else if (ll_token_is(&v, "3") || ll_token_is(&v, "rgb"))
                m->channels = 3;
            else
                s = ll_parse_error(p, v.begin, "channels: expected 1 (mono) or 3 (rgb), got '%.*s'",
                                (int)v.len, v.begin);
        } else if (ll_token_is(&key, "error")) {
            ll_number e;
            if (m->error_goal > 0.0)
                return ll_parse_error(p, key.begin, "error is set twice");
            memset(&e, 0, sizeof e);
            s = ll_parse_number(p, &key, &v, &e);
            if (s == LL_OK && (e.count != 1 || !(e.v[0] > 0.0 && e.v[0] < 1.0)))
                s = ll_parse_error(p, v.begin,
                                "error: expected one relative truncation error in (0, 1), "
                                "such as 1e-3");
            if (s == LL_OK)
                m->error_goal = e.v[0];
        } else if (ll_token_is(&key, "tolerance")) {
            s = parse_goal(p, &key, &v, &m->tolerance, LL_MIN_TOLERANCE, 1, 1.0, 0,
                           "[0.001, 1): the relative error the resolution is chosen for, "
                           "such as 0.01");
        } else if (ll_token_is(&key, "mu_min")) {
            s = parse_goal(p, &key, &v, &m->mu_min, 0.0, 0, 1.0, 1,
                           "(0, 1]: the smallest cosine the tolerance holds at, such as 0.1");
        } else {
            s = ll_parse_error(p, key.begin,
                            "set has no setting '%.*s'; expected nodes, orders, channels, "
                            "error, tolerance or mu_min",
                            (int)key.len, key.begin);
        }
        if (s != LL_OK)
            return s;
    }
}

/* More words than the language has, for the suggestion's list. */
#define LL_SUGGEST_WORDS 32

static ll_status parse_line(parser *p, const char *at, const char *line_end)
{
    token name;
    int found;
    size_t k;
    char shown[32], names[512];
    ll_status s = next_token(p, &at, line_end, &name, &found);
    if (s != LL_OK || !found)
        return s;
    if (ll_token_is(&name, "set"))
        return parse_settings(p, at, line_end);
    for (k = 0; k < ll_word_table_size; ++k)
        if (ll_token_is(&name, ll_word_table[k]->name))
            return parse_word(p, ll_word_table[k], &name, at, line_end);
    snprintf(shown, sizeof shown, "%.*s%s", (int)(name.len > 24 ? 24 : name.len), name.begin,
             name.len > 24 ? "..." : "");
    list_words(names, sizeof names);
    {
        /* The words and "set": a typing mistake gets its likely meaning. */
        const char *candidates[LL_SUGGEST_WORDS + 1], *closest;
        size_t n = ll_word_table_size < LL_SUGGEST_WORDS ? ll_word_table_size : LL_SUGGEST_WORDS;
        for (k = 0; k < n; ++k)
            candidates[k] = ll_word_table[k]->name;
        candidates[n] = "set";
        closest = ll_closest_name(name.begin, name.len, candidates, n + 1);
        if (closest)
            return ll_parse_error(p, name.begin,
                                  "unknown word '%s'; did you mean '%s'? (expected %s or set)",
                                  shown, closest, names);
    }
    return ll_parse_error(p, name.begin, "unknown word '%s'; expected %s or set", shown, names);
}

/* ------------------------------------------------------------ the API */

void ll_material_destroy(ll_material *m)
{
    size_t k;
    if (!m)
        return;
    for (k = 0; k < m->count; ++k)
        if (m->words[k].desc && m->words[k].desc->destroy)
            m->words[k].desc->destroy(&m->words[k]);
    ll_material_free_axes(m);
    ll_free(m->words);
    ll_free(m->source);
    ll_free(m->metadata);
    ll_free(m);
}

static char *copy_string(const char *s)
{
    size_t len = strlen(s) + 1;
    char *c = ll_malloc(len);
    if (c)
        memcpy(c, s, len);
    return c;
}

/* Parse text; material_dir (nullable) anchors names and relative paths. */
static ll_status parse_text(const char *text, const char *source, const char *material_dir,
                            ll_material **out)
{
    parser p;
    const char *at = text;
    ll_status s = LL_OK;
    ll_material *m = ll_calloc(1, sizeof *m);

    if (!m || !(m->source = copy_string(source))) {
        ll_material_destroy(m);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory parsing %s", source);
    }
    p.source = source;
    p.material_dir = material_dir;
    p.m = m;
    p.line = 0;
    while (*at && s == LL_OK) {
        const char *end = strchr(at, '\n');
        if (!end)
            end = at + strlen(at);
        p.line++;
        p.line_start = at;
        s = parse_line(&p, at, end);
        at = *end ? end + 1 : end;
    }
    if (s == LL_OK && m->count == 0) {
        char names[512];
        /* Point after the last character: the start of the next line when
         * the text ends with a newline (or is empty). */
        if (at == text || at[-1] == '\n') {
            p.line++;
            p.line_start = at;
        }
        list_words(names, sizeof names);
        s = ll_parse_error(&p, at,
                           "no layers; expected at least one word (%s), top to bottom, one "
                           "per line",
                           names);
    }
    if (s == LL_OK)
        s = ll_material_check_stack(m);
    if (s == LL_OK)
        s = ll_material_finish_axes(m);
    if (s == LL_OK)
        s = ll_material_make_metadata(m, text);
    if (s != LL_OK) {
        ll_material_destroy(m);
        return s;
    }
    *out = m;
    return LL_OK;
}

ll_status ll_material_parse(const char *text, const char *source_name, ll_material **out)
{
    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_parse: out is NULL");
    *out = NULL;
    if (!text)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_parse: text is NULL");
    return parse_text(text, source_name ? source_name : "<material>", NULL, out);
}

ll_status ll_material_parse_file(const char *path, ll_material **out)
{
    FILE *f;
    char *text = NULL, *dir = NULL, *slash;
    size_t len = 0, cap = 0, got;
    ll_status s;

    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_parse_file: out is NULL");
    *out = NULL;
    if (!path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_parse_file: path is NULL");
    f = ll_fopen_regular(path, "the material");
    if (!f)
        return LL_ERROR_IO;
    do {
        if (cap - len < 4096) {
            char *grown;
            if (cap > ((size_t)64 << 20)) {
                fclose(f);
                ll_free(text);
                return ll_fail(LL_ERROR_PARSE, "%s: larger than 64 MiB; not a material", path);
            }
            cap = cap ? 2 * cap : 8192;
            grown = ll_realloc(text, cap + 1);
            if (!grown) {
                fclose(f);
                ll_free(text);
                return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading %s", path);
            }
            text = grown;
        }
        got = fread(text + len, 1, cap - len, f);
        len += got;
    } while (got > 0);
    if (ferror(f)) {
        fclose(f);
        ll_free(text);
        return ll_fail(LL_ERROR_IO, "error reading the material %s", path);
    }
    fclose(f);
    text[len] = '\0';
    if (strlen(text) != len) {
        ll_free(text);
        return ll_fail(LL_ERROR_PARSE, "%s: contains a NUL byte; not a text file", path);
    }
    dir = copy_string(path);
    if (!dir) {
        ll_free(text);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading %s", path);
    }
    slash = strrchr(dir, '/');
    if (slash == dir)
        slash[1] = '\0';
    else if (slash)
        *slash = '\0';
    else
        strcpy(dir, ".");
    s = parse_text(text, path, dir, out);
    ll_free(dir);
    ll_free(text);
    return s;
}

size_t ll_material_word_count(const ll_material *m) { return m ? m->count : 0; }

int ll_material_transmits(const ll_material *m) { return m && !ll_material_is_opaque(m); }
