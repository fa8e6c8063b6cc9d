/*
 * Overflow-checked size arithmetic and allocation.
 */
#include "support/support.h"

#include <stdint.h>
#include <stdlib.h>

int ll_size_mul(size_t a, size_t b, size_t *out)
{
    if (a != 0 && b > SIZE_MAX / a)
        return 0;
    *out = a * b;
    return 1;
}

int ll_size_add(size_t a, size_t b, size_t *out)
{
    if (b > SIZE_MAX - a)
        return 0;
    *out = a + b;
    return 1;
}

void *ll_alloc_array(size_t count, size_t size)
{
    size_t bytes;
    if (!ll_size_mul(count, size, &bytes))
        return NULL;
    return malloc(bytes ? bytes : 1);
}

void *ll_calloc_array(size_t count, size_t size)
{
    size_t bytes;
    if (!ll_size_mul(count, size, &bytes))
        return NULL;
    return calloc(bytes ? count : 1, bytes ? size : 1);
}
