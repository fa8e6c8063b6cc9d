/*
 * The JSON description that a built .bsdf file carries in its metadata
 * block: the generator, the material text without its comments, and each
 * word with its parameters as they were resolved (its descriptor's
 * metadata writer: a named metal with its per-channel indices, as the
 * original tools stored "eta_cond" / "k_cond").
 *
 * The description is capped at LL_METADATA_MAX_BYTES: a material is a few
 * lines, and the metadata must not outgrow the file it describes (a 3 MB
 * comment line once made a 7.6 MB file 10.7 MB). Past the cap the text is
 * left out (its size is said instead), then the layers too (their count is
 * said).
 */
#include "material/word_table.h"
#include "support/parse_number.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define LL_METADATA_MAX_BYTES 65536

void ll_text_append(ll_text *b, const char *fmt, ...)
{
    va_list ap;
    int need;
    if (b->failed)
        return;
    va_start(ap, fmt);
    need = ll_vformat_c(b->data ? b->data + b->len : NULL, b->data ? b->cap - b->len : 0, fmt,
                        ap);
    va_end(ap);
    if (need < 0) {
        b->failed = 1;
        return;
    }
    if (b->len + (size_t)need + 1 > b->cap) {
        size_t cap = 2 * (b->len + (size_t)need + 1) + 256;
        char *grown = ll_realloc(b->data, cap);
        if (!grown) {
            b->failed = 1;
            return;
        }
        b->data = grown;
        b->cap = cap;
        va_start(ap, fmt);
        ll_vformat_c(b->data + b->len, b->cap - b->len, fmt, ap);
        va_end(ap);
    }
    b->len += (size_t)need;
}

/* [s, s + len) as it is. */
static void append_raw(ll_text *b, const char *s, size_t len)
{
    if (b->failed || len == 0)
        return;
    if (b->len + len + 1 > b->cap) {
        size_t cap = 2 * (b->len + len + 1) + 256;
        char *grown = ll_realloc(b->data, cap);
        if (!grown) {
            b->failed = 1;
            return;
        }
        b->data = grown;
        b->cap = cap;
    }
    memcpy(b->data + b->len, s, len);
    b->len += len;
    b->data[b->len] = '\0';
}

/* A JSON string literal of [s, s + len); runs of plain characters are
 * copied as they are. */
static void append_string_n(ll_text *b, const char *s, size_t len)
{
    size_t i, run = 0;
    ll_text_append(b, "\"");
    for (i = 0; i < len; ++i) {
        unsigned char c = (unsigned char)s[i];
        if (c >= 0x20 && c != '"' && c != '\\')
            continue;
        append_raw(b, s + run, i - run);
        run = i + 1;
        if (c == '"' || c == '\\')
            ll_text_append(b, "\\%c", c);
        else if (c == '\n')
            ll_text_append(b, "\\n");
        else if (c == '\t')
            ll_text_append(b, "\\t");
        else
            ll_text_append(b, "\\u%04x", c);
    }
    append_raw(b, s + run, len - run);
    ll_text_append(b, "\"");
}

void ll_text_string(ll_text *b, const char *s) { append_string_n(b, s, strlen(s)); }

void ll_text_number(ll_text *b, const char *key, const ll_number *x)
{
    if (x->count == 0)
        return;
    if (x->count == 1)
        ll_text_append(b, ", \"%s\": %.17g", key, x->v[0]);
    else
        ll_text_append(b, ", \"%s\": [%.17g, %.17g, %.17g]", key, x->v[0], x->v[1], x->v[2]);
}

/* The material text without comments, trailing blanks and the lines left
 * empty, as the lexer reads it (a `#` inside double quotes is text). */
static char *strip_comments(const char *text)
{
    size_t len = strlen(text), out = 0;
    char *s = ll_malloc(len + 2); /* a newline may be added to the last line */
    const char *at = text;
    if (!s)
        return NULL;
    while (*at) {
        const char *end = strchr(at, '\n'), *p;
        size_t start = out;
        int quoted = 0;
        if (!end)
            end = at + strlen(at);
        for (p = at; p < end; ++p) {
            if (*p == '"')
                quoted = !quoted;
            else if (*p == '#' && !quoted)
                break;
            s[out++] = *p;
        }
        while (out > start && (s[out - 1] == ' ' || s[out - 1] == '\t' || s[out - 1] == '\r'))
            --out;
        if (out > start)
            s[out++] = '\n';
        at = *end ? end + 1 : end;
    }
    s[out] = '\0';
    return s;
}

/* A swept material's axes (material_sweep.c), in the file's order:
 * "parameters" the names, "parameter_positions" the positions stored for
 * each, "parameter_values" the values as written (one or three each). */
static void describe_axes(ll_text *b, const ll_material *m)
{
    size_t a, k;
    if (m->n_axes == 0)
        return;
    ll_text_append(b, ",\n  \"parameters\": [");
    for (a = 0; a < m->n_axes; ++a) {
        ll_text_append(b, "%s", a ? ", " : "");
        ll_text_string(b, m->axes[a].name);
    }
    ll_text_append(b, "],\n  \"parameter_positions\": [");
    for (a = 0; a < m->n_axes; ++a) {
        ll_text_append(b, "%s[", a ? ", " : "");
        for (k = 0; k < m->axes[a].count; ++k)
            ll_text_append(b, "%s%.9g", k ? ", " : "", m->axes[a].positions[k]);
        ll_text_append(b, "]");
    }
    ll_text_append(b, "],\n  \"parameter_values\": [");
    for (a = 0; a < m->n_axes; ++a) {
        ll_text_append(b, "%s[", a ? ", " : "");
        for (k = 0; k < m->axes[a].count; ++k) {
            const ll_number *x = &m->axes[a].values[k];
            if (x->count == 3)
                ll_text_append(b, "%s[%.9g, %.9g, %.9g]", k ? ", " : "", x->v[0], x->v[1],
                               x->v[2]);
            else
                ll_text_append(b, "%s%.9g", k ? ", " : "", x->v[0]);
        }
        ll_text_append(b, "]");
    }
    ll_text_append(b, "]");
}

/* level 0: everything; 1: without the text; 2: without the layers too. */
static void describe(ll_text *b, const ll_material *m, const char *stripped, int level)
{
    size_t i;
    ll_text_append(b, "{\n  \"generator\": \"layerlab %s\",\n  \"source\": ",
                   ll_version_string());
    ll_text_string(b, m->source);
    describe_axes(b, m);
    if (level == 0) {
        ll_text_append(b, ",\n  \"material\": ");
        ll_text_string(b, stripped);
    } else {
        ll_text_append(b, ",\n  \"material_omitted\": \"%zu bytes without comments, over the "
                          "%d-byte cap of the metadata\"",
                       strlen(stripped), LL_METADATA_MAX_BYTES);
    }
    if (level == 2) {
        ll_text_append(b, ",\n  \"layer_count\": %zu\n}\n", m->count);
        return;
    }
    ll_text_append(b, ",\n  \"layers\": [");
    for (i = 0; i < m->count; ++i) {
        const ll_word *w = &m->words[i];
        ll_text_append(b, "%s\n    { \"type\": \"%s\"", i ? "," : "", w->desc->name);
        if (w->label[0]) {
            ll_text_append(b, ", \"label\": ");
            ll_text_string(b, w->label);
        }
        w->desc->metadata(b, w);
        ll_text_append(b, " }");
    }
    ll_text_append(b, "\n  ]\n}\n");
}

ll_status ll_material_make_metadata(ll_material *m, const char *text)
{
    ll_text b = { NULL, 0, 0, 0 };
    char *stripped = strip_comments(text);
    int level = 0;
    /* Skip the levels that cannot fit: a text longer than the cap, or more
     * layers than the cap holds at their shortest ({ "type": "x" }). */
    if (stripped && strlen(stripped) > LL_METADATA_MAX_BYTES)
        level = 1;
    if (m->count > LL_METADATA_MAX_BYTES / 16)
        level = 2;
    for (; stripped && level < 3; ++level) {
        ll_free(b.data);
        memset(&b, 0, sizeof b);
        describe(&b, m, stripped, level);
        if (b.failed || b.len <= LL_METADATA_MAX_BYTES)
            break;
    }
    ll_free(stripped);
    if (!stripped || b.failed) {
        ll_free(b.data);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory describing %s", m->source);
    }
    m->metadata = b.data;
    return LL_OK;
}
