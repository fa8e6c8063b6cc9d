/* The calling thread's order split (see split.h). */
#include "layer/split.h"

static __thread const ll_split *tls_split; /* NULL: every order */

const ll_split *ll_split_current(void) { return tls_split; }

const ll_split *ll_split_enter(const ll_split *split)
{
    const ll_split *previous = tls_split;
    tls_split = split;
    return previous;
}

void ll_split_leave(const ll_split *previous) { tls_split = previous; }

int ll_split_owns(const ll_split *split, size_t k)
{
    return !split || k % split->n_ranks == split->rank;
}
