/*
 * The material language: lexer and parser (docs/material-language.md).
 *
 * A description is a list of lines. Each line is empty, a comment (`#` to
 * the end of the line), a settings line `set key=value ...`, or one word of
 * the stack with its parameters: `dielectric eta=1.5 alpha=0.1`. Words are
 * listed top to bottom. Every error names source:line:column and what was
 * expected there.
 */
#include "material/material.h"
#include "words/merl.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_TOKEN 4096

typedef struct parser {
    const char *source;       /* for messages                          */
    const char *material_dir; /* for names and relative paths; nullable */
    const char *line_start;
    size_t line;
    ll_material *m;
} parser;

/* A token: text [begin, begin + len) of the current line. */
typedef struct token {
    const char *begin;
    size_t len;
} token;

static size_t column_of(const parser *p, const char *at) { return (size_t)(at - p->line_start) + 1; }

static ll_status parse_error(const parser *p, const char *at, const char *fmt, ...)
    LL_PRINTF(3, 4);

static ll_status parse_error(const parser *p, const char *at, const char *fmt, ...)
{
    char what[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return ll_fail(LL_ERROR_PARSE, "%s:%zu:%zu: %s", p->source, p->line, column_of(p, at), what);
}

static int token_is(const token *t, const char *s)
{
    return strlen(s) == t->len && memcmp(t->begin, s, t->len) == 0;
}

/* Copy a token into a NUL-terminated buffer (values are short). */
static int token_copy(const token *t, char *buf, size_t cap)
{
    if (t->len + 1 > cap)
        return 0;
    memcpy(buf, t->begin, t->len);
    buf[t->len] = '\0';
    return 1;
}

/* ------------------------------------------------------------ numbers */

/* One real number, the whole of [s, s + len): digits with an optional sign,
 * point and exponent (no hex, inf or nan). */
static int scan_real(const char *s, size_t len, double *out)
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
    *out = strtod(buf, &end);
    return *end == '\0' && ll_is_finite(*out);
}

/* A complex number n+ki or n-ki (the imaginary part ends in `i`). */
static int scan_complex(const char *s, size_t len, double *re, double *im)
{
    size_t i;
    if (len < 3 || s[len - 1] != 'i')
        return 0;
    /* The sign that starts the imaginary part: not the first character,
     * not right after an exponent's e. */
    for (i = len - 1; i-- > 1;) {
        if ((s[i] == '+' || s[i] == '-') && s[i - 1] != 'e' && s[i - 1] != 'E')
            break;
    }
    if (i == 0)
        return 0;
    return scan_real(s, i, re) && scan_real(s + i, len - 1 - i, im);
}

/* Split a value at commas: up to 3 parts. Returns the part count, or 0 for
 * more than 3 or an empty part. */
static int split_commas(const token *v, token parts[3])
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
static ll_status parse_number(const parser *p, const token *key, const token *v, ll_number *out)
{
    token parts[3];
    int count = split_commas(v, parts), k;
    if (count == 1 || count == 3) {
        for (k = 0; k < count; ++k)
            if (!scan_real(parts[k].begin, parts[k].len, &out->v[k]))
                return parse_error(p, parts[k].begin,
                                   "%.*s: '%.*s' is not a number; expected a decimal number "
                                   "such as 0.5 or 1e-3",
                                   (int)key->len, key->begin, (int)parts[k].len, parts[k].begin);
    } else {
        return parse_error(p, v->begin,
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
static ll_status check_range(const parser *p, const token *key, const token *v,
                             const ll_number *x, double lo, int lo_closed, double hi,
                             int hi_closed, const char *why)
{
    int k;
    for (k = 0; k < x->count; ++k) {
        double a = x->v[k];
        int ok = (lo_closed ? a >= lo : a > lo) && (hi_closed ? a <= hi : a < hi);
        if (!ok)
            return parse_error(p, v->begin, "%.*s=%g is out of range: %s", (int)key->len,
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
    return parse_error(p, v->begin, "%.*s: expected a whole number, got '%.*s'", (int)key->len,
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
                return parse_error(p, s, "unterminated quote; expected a closing \"");
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
        return parse_error(p, t->begin, "expected key=value, got '%.*s'", (int)t->len,
                           t->begin);
    key->begin = t->begin;
    key->len = (size_t)(eq - t->begin);
    for (i = 0; i < key->len; ++i) {
        char c = key->begin[i];
        if (!((c >= 'a' && c <= 'z') || c == '_'))
            return parse_error(p, t->begin, "'%.*s' is not a parameter name; expected key=value",
                               (int)key->len, key->begin);
    }
    value->begin = eq + 1;
    value->len = t->len - key->len - 1;
    if (value->len >= 2 && value->begin[0] == '"' && value->begin[value->len - 1] == '"') {
        value->begin++;
        value->len -= 2;
    }
    if (value->len == 0)
        return parse_error(p, eq + 1, "%.*s= has no value", (int)key->len, key->begin);
    return LL_OK;
}

/* --------------------------------------------------------------- words */

typedef struct word_syntax {
    const char *name;
    ll_word_kind kind;
    const char *keys;     /* allowed parameters, space separated           */
    const char *required; /* required ones                                 */
    const char *example;
} word_syntax;

static const word_syntax words[] = {
    { "diffuse", LL_WORD_DIFFUSE, "albedo", "albedo", "diffuse albedo=0.5" },
    { "dielectric", LL_WORD_DIELECTRIC, "eta alpha compensate", "eta alpha",
      "dielectric eta=1.5 alpha=0.1" },
    { "conductor", LL_WORD_CONDUCTOR, "eta k alpha compensate", "eta alpha",
      "conductor eta=Au alpha=0.1" },
    { "medium", LL_WORD_MEDIUM, "albedo tau g phase kappa", "albedo tau",
      "medium albedo=0.9 tau=1 g=0.5" },
    { "measured", LL_WORD_MEASURED, "file", "file", "measured file=gold-metallic-paint.binary" },
};

static int key_in_list(const token *key, const char *list)
{
    const char *s = list;
    while (*s) {
        size_t len = strcspn(s, " ");
        if (len == key->len && memcmp(s, key->begin, len) == 0)
            return 1;
        s += len;
        while (*s == ' ')
            ++s;
    }
    return 0;
}

/* Where a parameter goes. */
static ll_number *number_slot(ll_word *w, const token *key)
{
    if (token_is(key, "albedo")) return &w->albedo;
    if (token_is(key, "eta")) return &w->eta;
    if (token_is(key, "k")) return &w->k;
    if (token_is(key, "alpha")) return &w->alpha;
    if (token_is(key, "tau")) return &w->tau;
    if (token_is(key, "g")) return &w->g;
    if (token_is(key, "kappa")) return &w->kappa;
    if (token_is(key, "compensate")) return &w->compensate;
    return NULL;
}

/* path relative to the material's directory unless absolute. */
static char *resolve_path(const char *dir, const char *path)
{
    size_t a, b;
    char *out;
    if (path[0] == '/' || !dir)
        dir = NULL;
    a = dir ? strlen(dir) + 1 : 0;
    b = strlen(path);
    out = malloc(a + b + 1);
    if (!out)
        return NULL;
    if (dir)
        snprintf(out, a + b + 1, "%s/%s", dir, path);
    else
        memcpy(out, path, b + 1);
    return out;
}

/* Only characters of real numbers and commas (no `i` of a complex one). */
static int is_real_list(const token *v)
{
    size_t i;
    for (i = 0; i < v->len; ++i)
        if (!strchr("0123456789+-.eE,", v->begin[i]))
            return 0;
    return 1;
}

/* conductor eta=NAME | n+ki[,n+ki,n+ki] | n[,n,n] (then k=...) */
static ll_status parse_conductor_eta(parser *p, ll_word *w, const token *key, const token *v)
{
    token parts[3];
    int count, k;
    char name[sizeof w->metal];
    ll_status s;
    char c0 = v->begin[0];
    int named = (c0 >= 'A' && c0 <= 'Z') || (c0 >= 'a' && c0 <= 'z');

    if (w->k.count && (named || !is_real_list(v)))
        return parse_error(p, v->begin, "eta: k= is given already; write eta=n with k=k, or "
                                        "eta=n+ki or eta=NAME alone");
    if (named) {
        if (!token_copy(v, name, sizeof name))
            return parse_error(p, v->begin, "eta: the metal name is too long");
        s = ll_metal_ior_lookup(name, p->material_dir, &w->metal_ior);
        if (s != LL_OK)
            return parse_error(p, v->begin, "eta=%s: %s", name, ll_last_error_message());
        memcpy(w->metal, name, sizeof name);
        w->named_metal = 1;
        w->eta.count = 3;
        w->k.count = 3;
        for (k = 0; k < 3; ++k) {
            w->eta.v[k] = w->metal_ior.eta[k];
            w->k.v[k] = w->metal_ior.k[k];
        }
        w->eta.line = w->k.line = p->line;
        w->eta.column = w->k.column = column_of(p, v->begin);
        return LL_OK;
    }
    if (is_real_list(v))
        return parse_number(p, key, v, &w->eta);
    count = split_commas(v, parts);
    if (count != 1 && count != 3)
        return parse_error(p, v->begin,
                           "eta: expected a metal name, one complex index n+ki or three "
                           "(R,G,B), got '%.*s'",
                           (int)v->len, v->begin);
    for (k = 0; k < count; ++k)
        if (!scan_complex(parts[k].begin, parts[k].len, &w->eta.v[k], &w->k.v[k]))
            return parse_error(p, parts[k].begin,
                               "eta: '%.*s' is not a complex index; expected n+ki such as "
                               "0.2+3.9i",
                               (int)parts[k].len, parts[k].begin);
    for (k = count; k < 3; ++k) {
        w->eta.v[k] = w->eta.v[0];
        w->k.v[k] = w->k.v[0];
    }
    w->eta.count = w->k.count = count;
    w->eta.line = w->k.line = p->line;
    w->eta.column = w->k.column = column_of(p, v->begin);
    return LL_OK;
}

/* Range checks of one parameter of a word, right where it was written. */
static ll_status check_parameter(const parser *p, const ll_word *w, const token *key,
                                 const token *v, const ll_number *x)
{
    if (x == &w->albedo)
        return check_range(p, key, v, x, 0.0, 1, 1.0, 1,
                           "an albedo is a fraction of light, in [0, 1]");
    if (x == &w->alpha) {
        ll_status s = check_range(p, key, v, x, 0.0, 0, 1e300, 1,
                                  "the roughness alpha must be > 0 (a perfectly smooth "
                                  "interface cannot be stored as a series)");
        if (s == LL_OK)
            s = check_range(p, key, v, x, LL_MICROFACET_MIN_ALPHA, 1, 1e300, 1,
                            "roughness below 0.001 needs more Fourier orders than a layer "
                            "can hold; use alpha >= 0.001");
        return s;
    }
    if (x == &w->compensate && (x->count != 1 || (x->v[0] != 0.0 && x->v[0] != 1.0)))
        return parse_error(p, v->begin, "compensate is 1 (energy compensation, the default) "
                           "or 0 (single scattering only, as renderers' microfacet BSDFs)");
    if (x == &w->tau)
        return check_range(p, key, v, x, 0.0, 1, 1e12, 1,
                           "the optical thickness tau must be in [0, 1e12]");
    if (x == &w->g)
        return check_range(p, key, v, x, -1.0, 0, 1.0, 0,
                           "the Henyey-Greenstein asymmetry g must be in (-1, 1)");
    if (x == &w->kappa)
        return check_range(p, key, v, x, 0.0, 1, 1e4, 1,
                           "the von Mises-Fisher concentration kappa must be in [0, 10000]");
    if (x == &w->k)
        return check_range(p, key, v, x, 0.0, 0, 1e300, 1,
                           "a conductor absorbs: its extinction k must be > 0 (an interface "
                           "with k = 0 is a dielectric)");
    if (x == &w->eta && w->kind == LL_WORD_DIELECTRIC) {
        int k;
        ll_status s = check_range(p, key, v, x, 0.0, 0, 1e300, 1,
                                  "an index of refraction must be > 0");
        for (k = 0; s == LL_OK && k < x->count; ++k)
            if (x->v[k] == 1.0)
                s = parse_error(p, v->begin,
                                "eta=1 is no interface (nothing reflects or refracts); "
                                "remove the line or use another eta");
        return s;
    }
    if (x == &w->eta)
        return check_range(p, key, v, x, 0.0, 0, 1e300, 1,
                           "the real part of a conductor's index must be > 0");
    return LL_OK;
}

static ll_status parse_word_parameter(parser *p, ll_word *w, const word_syntax *syn,
                                      const token *t)
{
    token key, v;
    ll_number *slot;
    ll_status s = split_key_value(p, t, &key, &v);
    if (s != LL_OK)
        return s;
    if (!key_in_list(&key, syn->keys))
        return parse_error(p, key.begin, "%s has no parameter '%.*s'; expected one of: %s",
                           syn->name, (int)key.len, key.begin, syn->keys);
    if (token_is(&key, "phase")) {
        if (w->phase_given)
            return parse_error(p, key.begin, "phase is given twice");
        if (token_is(&v, "isotropic"))
            w->phase = LL_PHASE_ISOTROPIC;
        else if (token_is(&v, "hg") || token_is(&v, "henyey-greenstein"))
            w->phase = LL_PHASE_HG;
        else if (token_is(&v, "vmf") || token_is(&v, "von-mises-fisher"))
            w->phase = LL_PHASE_VMF;
        else
            return parse_error(p, v.begin,
                               "phase: unknown phase function '%.*s'; expected isotropic, hg "
                               "or vmf",
                               (int)v.len, v.begin);
        w->phase_given = 1;
        return LL_OK;
    }
    if (token_is(&key, "file")) {
        char path[MAX_TOKEN];
        if (w->file)
            return parse_error(p, key.begin, "file is given twice");
        if (!token_copy(&v, path, sizeof path))
            return parse_error(p, v.begin, "file: the path is too long");
        w->file = resolve_path(p->material_dir, path);
        if (!w->file)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory parsing %s", p->source);
        s = ll_merl_check(w->file);
        if (s != LL_OK)
            return parse_error(p, v.begin, "file: %s", ll_last_error_message());
        return LL_OK;
    }
    slot = number_slot(w, &key);
    if (token_is(&key, "k") && w->named_metal)
        return parse_error(p, key.begin, "k: eta=%s already gives the metal's k", w->metal);
    if (token_is(&key, "k") && w->k.count)
        return parse_error(p, key.begin, "k is given already (by k= or by eta=n+ki)");
    if (slot->count != 0)
        return parse_error(p, key.begin, "%.*s is given twice", (int)key.len, key.begin);
    if (w->kind == LL_WORD_CONDUCTOR && token_is(&key, "eta"))
        s = parse_conductor_eta(p, w, &key, &v);
    else
        s = parse_number(p, &key, &v, slot);
    if (s != LL_OK)
        return s;
    /* A conductor's k may come with the complex eta already. */
    if (w->kind == LL_WORD_CONDUCTOR && token_is(&key, "eta") && !w->named_metal &&
        w->k.count)
        s = check_range(p, &key, &v, &w->k, 0.0, 0, 1e300, 1,
                        "a conductor absorbs: the imaginary part k must be > 0 (an "
                        "interface with k = 0 is a dielectric)");
    return s == LL_OK ? check_parameter(p, w, &key, &v, slot) : s;
}

/* What a word still needs once its line is read. */
static ll_status finish_word(const parser *p, ll_word *w, const word_syntax *syn,
                             const char *word_at)
{
    token key;
    const char *s = syn->required;
    while (*s) {
        size_t len = strcspn(s, " ");
        ll_number *slot;
        key.begin = s;
        key.len = len;
        slot = number_slot(w, &key);
        if ((slot && slot->count == 0) || (token_is(&key, "file") && !w->file))
            return parse_error(p, word_at, "%s needs %.*s=...; for example: %s", syn->name,
                               (int)len, s, syn->example);
        s += len;
        while (*s == ' ')
            ++s;
    }
    if (w->kind == LL_WORD_CONDUCTOR && !w->named_metal && w->k.count == 0)
        return parse_error(p, word_at,
                           "conductor needs an absorbing index: eta=NAME (e.g. Au), eta=n+ki "
                           "or eta=n with k=k");
    if (w->kind == LL_WORD_MEDIUM) {
        if (w->g.count && w->phase_given && w->phase != LL_PHASE_HG)
            return parse_error(p, word_at, "g= belongs to phase=hg, not to the phase given");
        if (w->kappa.count && w->phase != LL_PHASE_VMF)
            return parse_error(p, word_at, "kappa= needs phase=vmf");
        if (w->phase == LL_PHASE_VMF && w->kappa.count == 0)
            return parse_error(p, word_at, "phase=vmf needs kappa=... (concentration >= 0)");
        if (w->phase == LL_PHASE_HG && w->g.count == 0)
            return parse_error(p, word_at, "phase=hg needs g=... (asymmetry in (-1, 1))");
        if (w->g.count && !w->phase_given)
            w->phase = LL_PHASE_HG;
    }
    return LL_OK;
}

static ll_status parse_word(parser *p, const word_syntax *syn, const token *name,
                            const char *at, const char *line_end)
{
    ll_word *w, *grown;
    token t;
    int found;
    ll_status s;
    size_t count = p->m->count;

    grown = realloc(p->m->words, (count + 1) * sizeof *grown);
    if (!grown)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory parsing %s", p->source);
    p->m->words = grown;
    w = &grown[count];
    memset(w, 0, sizeof *w);
    p->m->count = count + 1;
    w->kind = syn->kind;
    w->line = p->line;
    w->column = column_of(p, name->begin);
    w->phase = LL_PHASE_ISOTROPIC;
    while (1) {
        s = next_token(p, &at, line_end, &t, &found);
        if (s != LL_OK || !found)
            break;
        s = parse_word_parameter(p, w, syn, &t);
        if (s != LL_OK)
            return s;
    }
    if (s != LL_OK)
        return s;
    return finish_word(p, w, syn, name->begin);
}

/* set nodes=N orders=M channels=1|3 error=E */
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
        if (token_is(&key, "nodes")) {
            if (m->nodes)
                return parse_error(p, key.begin, "nodes is set twice");
            s = parse_count(p, &key, &v, &m->nodes);
            if (s == LL_OK && (m->nodes < 2 || m->nodes % 2))
                s = parse_error(p, v.begin, "nodes=%zu: expected an even count >= 2", m->nodes);
        } else if (token_is(&key, "orders")) {
            if (m->orders)
                return parse_error(p, key.begin, "orders is set twice");
            s = parse_count(p, &key, &v, &m->orders);
            if (s == LL_OK && m->orders < 1)
                s = parse_error(p, v.begin, "orders=0: expected at least 1");
        } else if (token_is(&key, "channels")) {
            if (m->channels)
                return parse_error(p, key.begin, "channels is set twice");
            if (token_is(&v, "1") || token_is(&v, "mono"))
                m->channels = 1;
            else if (token_is(&v, "3") || token_is(&v, "rgb"))
                m->channels = 3;
            else
                s = parse_error(p, v.begin, "channels: expected 1 (mono) or 3 (rgb), got '%.*s'",
                                (int)v.len, v.begin);
        } else if (token_is(&key, "error")) {
            ll_number e;
            if (m->error_goal > 0.0)
                return parse_error(p, key.begin, "error is set twice");
            memset(&e, 0, sizeof e);
            s = parse_number(p, &key, &v, &e);
            if (s == LL_OK && (e.count != 1 || !(e.v[0] > 0.0 && e.v[0] < 1.0)))
                s = parse_error(p, v.begin,
                                "error: expected one relative truncation error in (0, 1), "
                                "such as 1e-3");
            if (s == LL_OK)
                m->error_goal = e.v[0];
        } else {
            s = parse_error(p, key.begin,
                            "set has no setting '%.*s'; expected nodes, orders, channels or "
                            "error",
                            (int)key.len, key.begin);
        }
        if (s != LL_OK)
            return s;
    }
}

static ll_status parse_line(parser *p, const char *at, const char *line_end)
{
    token name;
    int found;
    size_t k;
    char shown[32];
    ll_status s = next_token(p, &at, line_end, &name, &found);
    if (s != LL_OK || !found)
        return s;
    if (token_is(&name, "set"))
        return parse_settings(p, at, line_end);
    for (k = 0; k < sizeof words / sizeof words[0]; ++k)
        if (token_is(&name, words[k].name))
            return parse_word(p, &words[k], &name, at, line_end);
    snprintf(shown, sizeof shown, "%.*s%s", (int)(name.len > 24 ? 24 : name.len), name.begin,
             name.len > 24 ? "..." : "");
    return parse_error(p, name.begin,
                       "unknown word '%s'; expected diffuse, dielectric, conductor, medium, "
                       "measured or set",
                       shown);
}

/* ------------------------------------------------------------ the API */

void ll_material_destroy(ll_material *m)
{
    size_t k;
    if (!m)
        return;
    for (k = 0; k < m->count; ++k)
        free(m->words[k].file);
    free(m->words);
    free(m->source);
    free(m->metadata);
    free(m);
}

static char *copy_string(const char *s)
{
    size_t len = strlen(s) + 1;
    char *c = malloc(len);
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
    ll_material *m = calloc(1, sizeof *m);

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
        /* Point after the last character: the start of the next line when
         * the text ends with a newline (or is empty). */
        if (at == text || at[-1] == '\n') {
            p.line++;
            p.line_start = at;
        }
        s = parse_error(&p, at,
                        "no layers; expected at least one word (diffuse, dielectric, "
                        "conductor, medium, measured), top to bottom, one per line");
    }
    if (s == LL_OK)
        s = ll_material_check_stack(m);
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
    f = fopen(path, "rb");
    if (!f)
        return ll_fail(LL_ERROR_IO, "cannot open the material %s", path);
    do {
        if (cap - len < 4096) {
            char *grown;
            if (cap > ((size_t)64 << 20)) {
                fclose(f);
                free(text);
                return ll_fail(LL_ERROR_PARSE, "%s: larger than 64 MiB; not a material", path);
            }
            cap = cap ? 2 * cap : 8192;
            grown = realloc(text, cap + 1);
            if (!grown) {
                fclose(f);
                free(text);
                return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading %s", path);
            }
            text = grown;
        }
        got = fread(text + len, 1, cap - len, f);
        len += got;
    } while (got > 0);
    if (ferror(f)) {
        fclose(f);
        free(text);
        return ll_fail(LL_ERROR_IO, "error reading the material %s", path);
    }
    fclose(f);
    text[len] = '\0';
    if (strlen(text) != len) {
        free(text);
        return ll_fail(LL_ERROR_PARSE, "%s: contains a NUL byte; not a text file", path);
    }
    dir = copy_string(path);
    if (!dir) {
        free(text);
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
    free(dir);
    free(text);
    return s;
}

size_t ll_material_word_count(const ll_material *m) { return m ? m->count : 0; }
