/*
 * Names of a textured file's parameters (ll_bsdf_get_parameter_name), read
 * from its metadata when the file is opened.
 *
 * The format itself has no names (docs/formats.md, "Metadata": free
 * text). layerlab's textured builds write a JSON object whose top-level key
 * "parameters" is an array of the axis names as strings, in file order
 * (`["coat.alpha", "base.alpha"]`). The metadata comes from the file, so it
 * is read like the rest of it (docs/style.md item 10): a bounded,
 * non-recursive scan of the bytes that allocates nothing, then one
 * allocation of the size the scan measured. Anything short of a well-formed
 * array of exactly nParameters distinct, non-empty strings of at most
 * LL_BSDF_NAME_MAX bytes (other metadata, no JSON at all, the default
 * writer's `"parameters": 2`, a wrong count, a bad escape, a cut string)
 * gives the documented default names "p0", "p1", ...: a name is a
 * convenience for binding parameters, never a reason to refuse a file whose
 * numbers all passed validation.
 */
#include "reader/bsdf_internal.h"

#include <stdio.h>
#include <string.h>

/* Longest accepted name in bytes (UTF-8, without the terminator). Axis names
 * are word labels and keys ("coat.alpha"); 255 leaves room for any. */
#define LL_BSDF_NAME_MAX 255
/* Names are looked for only in files with at most this many parameters:
 * the duplicate check is quadratic, and the material language makes at
 * most 4 axes. More parameters get the default names. */
#define LL_BSDF_NAMED_MAX 256

typedef struct cursor {
    const char *p, *end;
} cursor;

static void skip_space(cursor *c)
{
    while (c->p < c->end && (*c->p == ' ' || *c->p == '\t' || *c->p == '\n' || *c->p == '\r'))
        ++c->p;
}

static int hex_digit(char ch)
{
    if (ch >= '0' && ch <= '9')
        return ch - '0';
    if (ch >= 'a' && ch <= 'f')
        return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F')
        return ch - 'A' + 10;
    return -1;
}

/* The four hex digits of a \u escape at c->p; -1 if malformed. */
static long read_hex4(cursor *c)
{
    long v = 0;
    int k;
    if (c->end - c->p < 4)
        return -1;
    for (k = 0; k < 4; ++k) {
        int d = hex_digit(c->p[k]);
        if (d < 0)
            return -1;
        v = v * 16 + d;
    }
    c->p += 4;
    return v;
}

/* Append one byte to out (capacity cap) at *len; past cap only counts. */
static void put_byte(char *out, size_t cap, size_t *len, unsigned ch)
{
    if (out && *len < cap)
        out[*len] = (char)ch;
    ++*len;
}

/* The code point of a \u escape (after the "\u"), joining a surrogate pair
 * (RFC 8259, sec. 7); -1 for a lone surrogate or U+0000 (a name is a C
 * string). */
static long read_code_point(cursor *c)
{
    long hi = read_hex4(c), lo;
    if (hi < 0 || hi == 0 || (hi >= 0xDC00 && hi <= 0xDFFF))
        return -1;
    if (hi < 0xD800 || hi > 0xDBFF)
        return hi;
    if (c->end - c->p < 2 || c->p[0] != '\\' || c->p[1] != 'u')
        return -1;
    c->p += 2;
    lo = read_hex4(c);
    if (lo < 0xDC00 || lo > 0xDFFF)
        return -1;
    return 0x10000 + ((hi - 0xD800) << 10) + (lo - 0xDC00);
}

static void put_utf8(char *out, size_t cap, size_t *len, long cp)
{
    if (cp < 0x80) {
        put_byte(out, cap, len, (unsigned)cp);
    } else if (cp < 0x800) {
        put_byte(out, cap, len, 0xC0u | (unsigned)(cp >> 6));
        put_byte(out, cap, len, 0x80u | (unsigned)(cp & 0x3F));
    } else if (cp < 0x10000) {
        put_byte(out, cap, len, 0xE0u | (unsigned)(cp >> 12));
        put_byte(out, cap, len, 0x80u | (unsigned)((cp >> 6) & 0x3F));
        put_byte(out, cap, len, 0x80u | (unsigned)(cp & 0x3F));
    } else {
        put_byte(out, cap, len, 0xF0u | (unsigned)(cp >> 18));
        put_byte(out, cap, len, 0x80u | (unsigned)((cp >> 12) & 0x3F));
        put_byte(out, cap, len, 0x80u | (unsigned)((cp >> 6) & 0x3F));
        put_byte(out, cap, len, 0x80u | (unsigned)(cp & 0x3F));
    }
}

/* A JSON string at c->p (which is '"'), decoded into out[0 .. cap) when out
 * is not NULL; *len receives the decoded length even beyond cap. 0 if the
 * string is malformed (cut, a raw control character, a bad escape). */
static int scan_string(cursor *c, char *out, size_t cap, size_t *len)
{
    *len = 0;
    ++c->p;
    while (c->p < c->end) {
        unsigned char ch = (unsigned char)*c->p++;
        if (ch == '"')
            return 1;
        if (ch < 0x20)
            return 0;
        if (ch != '\\') {
            put_byte(out, cap, len, ch);
            continue;
        }
        if (c->p >= c->end)
            return 0;
        ch = (unsigned char)*c->p++;
        switch (ch) {
        case '"': case '\\': case '/': put_byte(out, cap, len, ch); break;
        case 'b': put_byte(out, cap, len, '\b'); break;
        case 'f': put_byte(out, cap, len, '\f'); break;
        case 'n': put_byte(out, cap, len, '\n'); break;
        case 'r': put_byte(out, cap, len, '\r'); break;
        case 't': put_byte(out, cap, len, '\t'); break;
        case 'u': {
            long cp = read_code_point(c);
            if (cp < 0)
                return 0;
            put_utf8(out, cap, len, cp);
            break;
        }
        default: return 0;
        }
    }
    return 0;
}

/* Skip one value of any kind. Objects and arrays are skipped by counting
 * brackets (strings skipped whole), not by recursion, so nesting depth costs
 * nothing; the scan only has to find the top-level keys, not to judge the
 * rest of the text. 0 if the value is cut or empty. */
static int skip_value(cursor *c)
{
    size_t depth = 0, len;
    const char *start = c->p;
    while (c->p < c->end) {
        char ch = *c->p;
        if (ch == '"') {
            if (!scan_string(c, NULL, 0, &len))
                return 0;
        } else if (ch == '{' || ch == '[') {
            ++depth;
            ++c->p;
        } else if (ch == '}' || ch == ']') {
            if (depth == 0)
                break; /* the end of the enclosing object: a scalar ends here */
            --depth;
            ++c->p;
        } else if (depth == 0 && (ch == ',' || ch == ' ' || ch == '\t' || ch == '\n' ||
                                  ch == '\r')) {
            break;
        } else {
            ++c->p;
        }
        if (depth == 0 && (ch == '"' || ch == '}' || ch == ']'))
            return 1; /* a string, object or array just ended */
    }
    return depth == 0 && c->p > start;
}

/* The array of names at c->p (which is '['): count names, their bytes with
 * terminators in *bytes; with block not NULL, the names are written there and
 * names[k] points at each. 0 unless it is an array of exactly want strings of
 * 1 .. LL_BSDF_NAME_MAX bytes. */
static int scan_names(cursor *c, size_t want, char *block, const char **names, size_t *bytes)
{
    size_t count = 0, len;
    *bytes = 0;
    ++c->p;
    skip_space(c);
    if (c->p < c->end && *c->p == ']')
        return want == 0;
    for (;;) {
        char *out = block ? block + *bytes : NULL;
        skip_space(c);
        if (c->p >= c->end || *c->p != '"' || count == want)
            return 0;
        if (!scan_string(c, out, LL_BSDF_NAME_MAX, &len) || len == 0 || len > LL_BSDF_NAME_MAX)
            return 0;
        if (block) {
            out[len] = '\0';
            names[count] = out;
        }
        *bytes += len + 1;
        ++count;
        skip_space(c);
        if (c->p >= c->end)
            return 0;
        if (*c->p == ']')
            return count == want;
        if (*c->p++ != ',')
            return 0;
    }
}

/* Move c to the value of the metadata's top-level key "parameters" if that
 * value is an array; 0 otherwise (no JSON object, no such key, another kind
 * of value, or text that stops being an object before the key). */
static int find_parameters(cursor *c)
{
    char key[16];
    size_t len;
    skip_space(c);
    if (c->p >= c->end || *c->p++ != '{')
        return 0;
    for (;;) {
        skip_space(c);
        if (c->p >= c->end || *c->p != '"' || !scan_string(c, key, sizeof key, &len))
            return 0;
        skip_space(c);
        if (c->p >= c->end || *c->p++ != ':')
            return 0;
        skip_space(c);
        if (len == 10 && memcmp(key, "parameters", 10) == 0)
            return c->p < c->end && *c->p == '[';
        if (!skip_value(c))
            return 0;
        skip_space(c);
        if (c->p >= c->end || *c->p++ != ',')
            return 0;
    }
}

static int all_distinct(const char *const *names, size_t n)
{
    size_t i, j;
    for (i = 0; i < n; ++i)
        for (j = 0; j < i; ++j)
            if (strcmp(names[i], names[j]) == 0)
                return 0;
    return 1;
}

/* Bytes of the default names "p0" .. "p<n-1>" with their terminators. */
static size_t default_bytes(size_t n)
{
    size_t bytes = 0, p, digits = 1, next = 10;
    for (p = 0; p < n; ++p) {
        if (p == next) {
            ++digits;
            next = next > (size_t)-1 / 10 ? (size_t)-1 : next * 10;
        }
        bytes += 2 + digits;
    }
    return bytes;
}

static void write_default_names(char *block, const char **names, size_t n)
{
    size_t p, at = 0;
    for (p = 0; p < n; ++p) {
        names[p] = block + at;
        at += (size_t)sprintf(block + at, "p%zu", p) + 1;
    }
}

int ll_bsdf_read_parameter_names(ll_bsdf *b)
{
    cursor c;
    size_t named = 0, bytes, total;
    int have_names = 0;
    char *block;
    if (b->n_parameters == 0)
        return 1;
    /* 1. Validate and measure, allocating nothing. */
    c.p = b->metadata;
    c.end = b->metadata + b->metadata_size;
    if (b->n_parameters <= LL_BSDF_NAMED_MAX && find_parameters(&c)) {
        cursor at = c;
        have_names = scan_names(&at, b->n_parameters, NULL, NULL, &named);
    }
    bytes = default_bytes(b->n_parameters);
    if (have_names && named > bytes)
        bytes = named;
    /* 2. One block: the pointers, then the names (room for the default
     * names too, which replace duplicates found once they are decoded). */
    if (!ll_size_mul(b->n_parameters, sizeof(char *), &total) ||
        !ll_size_add(total, bytes, &total))
        return 0;
    b->param_names = ll_malloc(total);
    if (!b->param_names)
        return 0;
    block = (char *)(b->param_names + b->n_parameters);
    if (have_names) {
        (void)scan_names(&c, b->n_parameters, block, b->param_names, &named);
        have_names = all_distinct(b->param_names, b->n_parameters);
    }
    if (!have_names)
        write_default_names(block, b->param_names, b->n_parameters);
    return 1;
}

ll_status ll_bsdf_get_parameter_name(const ll_bsdf *b, size_t p, const char **name)
{
    if (!b || !name)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_get_parameter_name: bsdf or name is NULL");
    if (p >= b->n_parameters)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_get_parameter_name: parameter %zu does not exist (the file "
                       "has %zu)",
                       p, b->n_parameters);
    *name = b->param_names[p];
    return LL_OK;
}
