/*
 * "Did you mean": optimal-string-alignment distance (Levenshtein with
 * swaps of neighbouring letters, the commonest typing mistake:
 * "dielectirc") between a mistyped word and the names it could have meant.
 */
#include "material/word_suggest.h"

#include <ctype.h>
#include <string.h>

#define LL_SUGGEST_MAX 64

static size_t min3(size_t a, size_t b, size_t c)
{
    size_t m = a < b ? a : b;
    return m < c ? m : c;
}

static int same(char a, char b)
{
    return tolower((unsigned char)a) == tolower((unsigned char)b);
}

/* Distance between a[0 .. n) and b[0 .. m), both at most LL_SUGGEST_MAX. */
static size_t distance(const char *a, size_t n, const char *b, size_t m)
{
    /* Distances are at most 2 * LL_SUGGEST_MAX: a byte each (4 KiB). */
    unsigned char d[LL_SUGGEST_MAX + 1][LL_SUGGEST_MAX + 1];
    size_t i, j;
    for (i = 0; i <= n; ++i)
        d[i][0] = (unsigned char)i;
    for (j = 0; j <= m; ++j)
        d[0][j] = (unsigned char)j;
    for (i = 1; i <= n; ++i)
        for (j = 1; j <= m; ++j) {
            d[i][j] = (unsigned char)min3((size_t)d[i - 1][j] + 1, (size_t)d[i][j - 1] + 1,
                                          (size_t)d[i - 1][j - 1] +
                                              (same(a[i - 1], b[j - 1]) ? 0 : 1));
            if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]) &&
                d[i - 2][j - 2] + 1 < d[i][j])
                d[i][j] = (unsigned char)(d[i - 2][j - 2] + 1);
        }
    return d[n][m];
}

const char *ll_closest_name(const char *text, size_t len, const char *const *names,
                            size_t count)
{
    const char *best = NULL;
    size_t best_d = (size_t)-1, k;
    if (len == 0 || len > LL_SUGGEST_MAX)
        return NULL;
    for (k = 0; k < count; ++k) {
        size_t m = strlen(names[k]), d, allowed;
        if (m > LL_SUGGEST_MAX)
            continue;
        d = distance(text, len, names[k], m);
        allowed = m <= 4 ? 1 : m <= 8 ? 2 : 3;
        if (d <= allowed && d < best_d) {
            best = names[k];
            best_d = d;
        }
    }
    return best;
}
