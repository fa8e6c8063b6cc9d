/*
 * The builder's cache of word layers (material_sweep_build.c): LRU over
 * LL_WORD_CACHE_ENTRIES entries keyed by (word index, resolved parameters),
 * every layer written once to a scratch file (tmpfile(): unlinked, gone
 * with the process) and the LL_WORD_CACHE_IN_MEMORY most recently used
 * also kept in memory; a hit on disk reads the layer back (its orders
 * exactly, runs and values), which costs a read of what the layer stores,
 * far less than building it. So with bases built in order (axis 0 fastest)
 * an 8 x 8 coat x gold grid builds 8 + 8 interfaces (each coat read back 7
 * times), and memory holds a few word layers whatever the grid's shape: it
 * does not grow with the number of bases or with the length of an axis.
 * Without a scratch file (tmpfile fails) the cache is the memory part
 * alone, and sharing is what fits there.
 */
#include "material/material.h"
#include "layer/layer.h"
#include "layer/order.h"

#include <stdio.h>
#include <string.h>

typedef struct cache_entry {
    int full;
    size_t word;
    ll_word_params params;
    long long at;             /* offset in the disk file, -1 if not there */
    ll_layer *layer;          /* in memory, or NULL                       */
    unsigned long long used;  /* last use, for LRU                        */
} cache_entry;

struct ll_word_cache {
    cache_entry entry[LL_WORD_CACHE_ENTRIES];
    FILE *disk;               /* tmpfile(); NULL: memory only             */
    int disk_failed;
    ll_layer *shape;          /* a copy of a cached layer: nodes, weights */
    unsigned long long clock;
    size_t built, added, loads;
};

/* The layer's orders appended to the disk file: per order a presence byte,
 * then its runs and values as they are in memory (a private scratch file
 * of this process, read back by load_layer only). 0 on a write error. */
static int save_layer(ll_word_cache *c, const ll_layer *l, long long *at)
{
    size_t k, n = l->n;
    if (!c->disk && !c->disk_failed) {
        c->disk = tmpfile();
        c->disk_failed = c->disk == NULL;
    }
    if (!c->disk || fseeko(c->disk, 0, SEEK_END) != 0 || (*at = (long long)ftello(c->disk)) < 0)
        return 0;
    for (k = 0; k < l->m; ++k) {
        const ll_order *o = l->orders[k];
        unsigned char present = o != NULL;
        if (fwrite(&present, 1, 1, c->disk) != 1 ||
            (o && (fwrite(o->seg, sizeof *o->seg, 2 * n + 1, c->disk) != 2 * n + 1 ||
                   fwrite(o->val, sizeof *o->val, o->seg[2 * n].off, c->disk) !=
                       o->seg[2 * n].off)))
            return 0;
    }
    return 1;
}

/* A layer read back from offset at: the orders as they were saved. */
static ll_status load_layer(ll_word_cache *c, long long at, ll_layer **out)
{
    size_t n = c->shape->n, m = c->shape->m, k;
    ll_order **orders = ll_calloc_array(m, sizeof *orders);
    ll_segment *seg = ll_alloc_array(2 * n + 1, sizeof *seg);
    double *val = NULL;
    ll_layer *l = NULL;
    ll_status s = LL_OK;
    *out = NULL;
    if (!orders || !seg) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading a cached layer");
        goto fail;
    }
    if (fseeko(c->disk, (off_t)at, SEEK_SET) != 0) {
        s = ll_fail(LL_ERROR_IO, "the builder's cache file: cannot seek");
        goto fail;
    }
    for (k = 0; k < m && s == LL_OK; ++k) {
        unsigned char present;
        size_t stored;
        if (fread(&present, 1, 1, c->disk) != 1 ||
            (present && fread(seg, sizeof *seg, 2 * n + 1, c->disk) != 2 * n + 1)) {
            s = ll_fail(LL_ERROR_IO, "the builder's cache file: cannot read a layer back");
            break;
        }
        if (!present)
            continue;
        stored = seg[2 * n].off;
        ll_free(val);
        val = ll_alloc_array(stored ? stored : 1, sizeof *val);
        if (!val) {
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading a cached layer");
            break;
        }
        if (fread(val, sizeof *val, stored, c->disk) != stored) {
            s = ll_fail(LL_ERROR_IO, "the builder's cache file: cannot read a layer back");
            break;
        }
        s = ll_order_from_runs(n, seg, val, &orders[k]);
    }
    /* The nodes and weights of the shape, the orders read (the layer's
     * single commit point). */
    if (s == LL_OK)
        s = ll_layer_clone(c->shape, &l);
    if (s == LL_OK) {
        s = ll_layer_commit_orders(l, orders, LL_OK);
        orders = NULL;
    }
    if (s == LL_OK) {
        *out = l;
        l = NULL;
        c->loads++;
    }
fail:
    if (orders) {
        for (k = 0; k < m; ++k)
            ll_order_release(orders[k]);
        ll_free(orders);
    }
    ll_layer_destroy(l);
    ll_free(seg);
    ll_free(val);
    return s;
}

/* At most LL_WORD_CACHE_IN_MEMORY layers stay in memory: drop the least
 * recently used (it stays on disk; without a disk copy the entry goes). */
static void trim_memory(ll_word_cache *c)
{
    while (1) {
        size_t k, held = 0, victim = LL_WORD_CACHE_ENTRIES;
        for (k = 0; k < LL_WORD_CACHE_ENTRIES; ++k)
            if (c->entry[k].layer) {
                ++held;
                if (victim == LL_WORD_CACHE_ENTRIES || c->entry[k].used < c->entry[victim].used)
                    victim = k;
            }
        if (held <= LL_WORD_CACHE_IN_MEMORY)
            return;
        ll_layer_destroy(c->entry[victim].layer);
        c->entry[victim].layer = NULL;
        if (c->entry[victim].at < 0)
            c->entry[victim].full = 0;
    }
}

ll_status ll_word_cache_get(ll_word_cache *c, size_t word, const ll_word_params *p,
                            ll_layer **out)
{
    size_t k;
    *out = NULL;
    for (k = 0; k < LL_WORD_CACHE_ENTRIES; ++k) {
        cache_entry *e = &c->entry[k];
        if (e->full && e->word == word && ll_word_params_equal(&e->params, p)) {
            ll_status s = LL_OK;
            e->used = ++c->clock;
            if (!e->layer)
                s = load_layer(c, e->at, &e->layer);
            if (s == LL_OK)
                s = ll_layer_clone(e->layer, out);
            trim_memory(c);
            return s;
        }
    }
    return LL_OK;
}

ll_status ll_word_cache_put(ll_word_cache *c, size_t word, const ll_word_params *p,
                            const ll_layer *layer)
{
    size_t k, victim = 0;
    cache_entry *e;
    ll_status s;
    c->built++;
    for (k = 0; k < LL_WORD_CACHE_ENTRIES; ++k) {
        if (!c->entry[k].full) {
            victim = k;
            break;
        }
        if (c->entry[k].used < c->entry[victim].used)
            victim = k;
    }
    e = &c->entry[victim];
    ll_layer_destroy(e->layer);
    memset(e, 0, sizeof *e);
    if (!c->shape && (s = ll_layer_clone(layer, &c->shape)) != LL_OK)
        return s;
    if ((s = ll_layer_clone(layer, &e->layer)) != LL_OK)
        return s;
    if (!save_layer(c, layer, &e->at))
        e->at = -1; /* memory only: the entry lasts while it stays there */
    e->full = 1;
    e->word = word;
    e->params = *p;
    e->used = ++c->clock;
    trim_memory(c);
    return LL_OK;
}

void ll_word_cache_count_addition(ll_word_cache *c) { c->added++; }

static void cache_clear(ll_word_cache *c)
{
    size_t k;
    for (k = 0; k < LL_WORD_CACHE_ENTRIES; ++k) {
        ll_layer_destroy(c->entry[k].layer);
        c->entry[k].layer = NULL;
        c->entry[k].full = 0;
    }
    ll_layer_destroy(c->shape);
    c->shape = NULL;
    if (c->disk)
        fclose(c->disk);
    c->disk = NULL;
}

ll_word_cache *ll_word_cache_create(void) { return ll_calloc(1, sizeof(ll_word_cache)); }

size_t ll_word_cache_built(const ll_word_cache *c) { return c ? c->built : 0; }

size_t ll_word_cache_additions(const ll_word_cache *c) { return c ? c->added : 0; }

void ll_word_cache_destroy(ll_word_cache *c)
{
    if (!c)
        return;
    cache_clear(c);
    ll_free(c);
}
