/* "Did you mean": the closest of a list of names to a mistyped one. */
#ifndef LL_MATERIAL_WORD_SUGGEST_H
#define LL_MATERIAL_WORD_SUGGEST_H

#include "support/support.h"

#include <stddef.h>

/* The name of names[0 .. count) closest to text[0 .. len) in edit distance
 * (insertions, deletions, substitutions and swaps of neighbours, each 1,
 * case ignored), if it is close enough to be a typing mistake: at most 1
 * edit for names of up to 4 letters, 2 up to 8, else 3. NULL otherwise
 * (also for a text longer than 64 bytes). */
LL_INTERNAL const char *ll_closest_name(const char *text, size_t len, const char *const *names,
                                        size_t count);

#endif
