/*
 * The JSON description that a built .bsdf file carries in its metadata
 * block: the generator, the material text, and each word with its
 * parameters as they were resolved (a named metal with its per-channel
 * indices, as the original tools stored "eta_cond" / "k_cond").
 */
#include "material/material.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct text_buffer {
    char *data;
    size_t len, cap;
    int failed;
} text_buffer;

static void append(text_buffer *b, const char *fmt, ...) LL_PRINTF(2, 3);

static void append(text_buffer *b, const char *fmt, ...)
{
    va_list ap;
    int need;
    if (b->failed)
        return;
    va_start(ap, fmt);
    need = vsnprintf(b->data ? b->data + b->len : NULL, b->data ? b->cap - b->len : 0, fmt, ap);
    va_end(ap);
    if (need < 0) {
        b->failed = 1;
        return;
    }
    if (b->len + (size_t)need + 1 > b->cap) {
        size_t cap = 2 * (b->len + (size_t)need + 1) + 256;
        char *grown = realloc(b->data, cap);
        if (!grown) {
            b->failed = 1;
            return;
        }
        b->data = grown;
        b->cap = cap;
        va_start(ap, fmt);
        vsnprintf(b->data + b->len, b->cap - b->len, fmt, ap);
        va_end(ap);
    }
    b->len += (size_t)need;
}

/* A JSON string literal. */
static void append_string(text_buffer *b, const char *s)
{
    append(b, "\"");
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            append(b, "\\%c", c);
        else if (c == '\n')
            append(b, "\\n");
        else if (c == '\t')
            append(b, "\\t");
        else if (c < 0x20)
            append(b, "\\u%04x", c);
        else
            append(b, "%c", c);
    }
    append(b, "\"");
}

static void append_number(text_buffer *b, const char *key, const ll_number *x)
{
    if (x->count == 0)
        return;
    if (x->count == 1)
        append(b, ", \"%s\": %.17g", key, x->v[0]);
    else
        append(b, ", \"%s\": [%.17g, %.17g, %.17g]", key, x->v[0], x->v[1], x->v[2]);
}

static const char *phase_name(ll_phase p)
{
    return p == LL_PHASE_HG ? "hg" : p == LL_PHASE_VMF ? "vmf" : "isotropic";
}

ll_status ll_material_make_metadata(ll_material *m, const char *text)
{
    text_buffer b = { NULL, 0, 0, 0 };
    size_t i;
    append(&b, "{\n  \"generator\": \"layerlab %s\",\n  \"source\": ", ll_version_string());
    append_string(&b, m->source);
    append(&b, ",\n  \"material\": ");
    append_string(&b, text);
    append(&b, ",\n  \"layers\": [");
    for (i = 0; i < m->count; ++i) {
        const ll_word *w = &m->words[i];
        append(&b, "%s\n    { \"type\": \"%s\"", i ? "," : "", ll_word_kind_name(w->kind));
        if (w->named_metal) {
            append(&b, ", \"name\": ");
            append_string(&b, w->metal);
            append(&b, ", \"eta_luminance\": %.17g, \"k_luminance\": %.17g",
                   w->metal_ior.eta_y, w->metal_ior.k_y);
        }
        append_number(&b, "albedo", &w->albedo);
        append_number(&b, "eta", &w->eta);
        append_number(&b, "k", &w->k);
        append_number(&b, "alpha", &w->alpha);
        append_number(&b, "compensate", &w->compensate);
        append_number(&b, "tau", &w->tau);
        if (w->kind == LL_WORD_MEDIUM)
            append(&b, ", \"phase\": \"%s\"", phase_name(w->phase));
        append_number(&b, "g", &w->g);
        append_number(&b, "kappa", &w->kappa);
        if (w->file) {
            append(&b, ", \"file\": ");
            append_string(&b, w->file);
        }
        append(&b, " }");
    }
    append(&b, "\n  ]\n}\n");
    if (b.failed) {
        free(b.data);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory describing %s", m->source);
    }
    m->metadata = b.data;
    return LL_OK;
}
