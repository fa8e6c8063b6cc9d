/*
 * A layer as bytes (layerlab/ll_distribution.h: ll_layer_pack_size,
 * ll_layer_pack, ll_layer_unpack), for moving built layers between the
 * ranks of a distributed build.
 *
 * Layout: "LLLAYER1"; uint64 n, m; the n nodes and n weights in the
 * layer's own (adding-doubling) order; the m orders as order_pack.c packs
 * them. Unpacking checks every count against the bytes that are there
 * before it allocates, as the .bsdf reader does with a file.
 */
#include "layer/layer.h"
#include "layerlab/ll_distribution.h"

#include <string.h>

static const char magic[8] = { 'L', 'L', 'L', 'A', 'Y', 'E', 'R', '1' };
#define HEADER_BYTES (sizeof magic + 2 * sizeof(uint64_t))

size_t ll_layer_pack_size(const ll_layer *layer)
{
    size_t k, total;
    if (!layer)
        return 0;
    total = HEADER_BYTES + 2 * layer->n * sizeof(double);
    for (k = 0; k < layer->m; ++k)
        total += ll_order_packed_bytes(layer->orders[k]);
    return total;
}

ll_status ll_layer_pack(const ll_layer *layer, void *buffer, size_t size)
{
    unsigned char *p = buffer;
    uint64_t counts[2];
    size_t k;
    if (!layer || !buffer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_pack: layer or buffer is NULL");
    if (size < ll_layer_pack_size(layer))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_pack: the buffer holds %zu bytes; the layer needs %zu", size,
                       ll_layer_pack_size(layer));
    counts[0] = (uint64_t)layer->n;
    counts[1] = (uint64_t)layer->m;
    memcpy(p, magic, sizeof magic);
    memcpy(p + sizeof magic, counts, sizeof counts);
    p += HEADER_BYTES;
    memcpy(p, layer->nodes, layer->n * sizeof(double));
    p += layer->n * sizeof(double);
    memcpy(p, layer->weights, layer->n * sizeof(double));
    p += layer->n * sizeof(double);
    for (k = 0; k < layer->m; ++k)
        p = ll_order_pack(layer->orders[k], p);
    return LL_OK;
}

ll_status ll_layer_unpack(const void *buffer, size_t size, ll_layer **out)
{
    static const char fn[] = "ll_layer_unpack";
    const unsigned char *p = buffer, *end;
    double *nodes = NULL, *weights = NULL;
    ll_layer *l = NULL;
    uint64_t counts[2];
    size_t n, m, k;
    ll_status s;

    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: out is NULL", fn);
    *out = NULL;
    if (!buffer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: buffer is NULL", fn);
    end = p + size;
    if (size < HEADER_BYTES || memcmp(p, magic, sizeof magic) != 0)
        return ll_fail(LL_ERROR_FORMAT, "%s: %zu bytes that do not start a packed layer", fn,
                       size);
    memcpy(counts, p + sizeof magic, sizeof counts);
    p += HEADER_BYTES;
    /* Every order takes at least 8 bytes, each node 16. */
    if (counts[0] < 2 || counts[0] % 2 || counts[0] > UINT32_MAX / 2 ||
        counts[0] > (uint64_t)(size - HEADER_BYTES) / (2 * sizeof(double)) || counts[1] < 1 ||
        counts[1] > (uint64_t)(size - HEADER_BYTES - 2 * counts[0] * sizeof(double)) /
                        sizeof(uint64_t))
        return ll_fail(LL_ERROR_FORMAT,
                       "%s: %llu nodes and %llu orders do not fit the %zu bytes given", fn,
                       (unsigned long long)counts[0], (unsigned long long)counts[1], size);
    n = (size_t)counts[0];
    m = (size_t)counts[1];
    nodes = ll_alloc_array(n, sizeof *nodes);
    weights = ll_alloc_array(n, sizeof *weights);
    if (!nodes || !weights) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory for %zu nodes", fn, n);
        goto done;
    }
    memcpy(nodes, p, n * sizeof(double));
    memcpy(weights, p + n * sizeof(double), n * sizeof(double));
    p += 2 * n * sizeof(double);
    /* (The layer's own order: create checks the nodes and keeps it.) */
    s = ll_layer_create(nodes, weights, n, m, &l);
    for (k = 0; k < m && s == LL_OK; ++k) {
        ll_order *o;
        s = ll_order_unpack(n, &p, end, &o);
        if (s == LL_OK) {
            ll_order_release(l->orders[k]);
            l->orders[k] = o;
        }
    }
    if (s == LL_OK && p != end)
        s = ll_fail(LL_ERROR_FORMAT, "%s: %zu bytes follow the layer", fn, (size_t)(end - p));
    else if (s == LL_ERROR_FORMAT)
        s = ll_fail(LL_ERROR_FORMAT, "%s: order %zu: %s", fn, k - 1, ll_last_error_message());
done:
    ll_free(nodes);
    ll_free(weights);
    if (s != LL_OK) {
        ll_layer_destroy(l);
        return s;
    }
    *out = l;
    return LL_OK;
}
