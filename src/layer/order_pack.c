/*
 * An order as bytes, for a distributed build (layerlab/ll_distribution.h):
 * rank 0 gathers the orders of the finished stack from their owners. The
 * segments and values are copied as stored, so the gathered order is the
 * one its owner computed, bit for bit, and the file written from it is the
 * single-process one.
 *
 * Layout: uint64 flag (0: a NULL order, nothing follows); uint64 n; uint64
 * values stored; 2n + 1 segments of uint32 lo, uint32 len, uint64 off;
 * the values. memcpy throughout: the bytes sit in a receive buffer with
 * no alignment.
 */
#include "layer/order.h"

#include <string.h>

#define SEGMENT_BYTES (2 * sizeof(uint32_t) + sizeof(uint64_t))

size_t ll_order_packed_bytes(const ll_order *o)
{
    if (!o)
        return sizeof(uint64_t);
    return 3 * sizeof(uint64_t) + (2 * o->n + 1) * SEGMENT_BYTES +
           o->seg[2 * o->n].off * sizeof(double);
}

static unsigned char *put_u64(unsigned char *dst, size_t v)
{
    uint64_t x = (uint64_t)v;
    memcpy(dst, &x, sizeof x);
    return dst + sizeof x;
}

unsigned char *ll_order_pack(const ll_order *o, unsigned char *dst)
{
    size_t s, total;
    dst = put_u64(dst, o ? 1 : 0);
    if (!o)
        return dst;
    total = o->seg[2 * o->n].off;
    dst = put_u64(dst, o->n);
    dst = put_u64(dst, total);
    for (s = 0; s <= 2 * o->n; ++s) {
        memcpy(dst, &o->seg[s].lo, sizeof(uint32_t));
        memcpy(dst + sizeof(uint32_t), &o->seg[s].len, sizeof(uint32_t));
        dst = put_u64(dst + 2 * sizeof(uint32_t), o->seg[s].off);
    }
    memcpy(dst, o->val, total * sizeof(double));
    return dst + total * sizeof(double);
}

static int get_u64(const unsigned char **p, const unsigned char *end, uint64_t *v)
{
    if ((size_t)(end - *p) < sizeof *v)
        return 0;
    memcpy(v, *p, sizeof *v);
    *p += sizeof *v;
    return 1;
}

ll_status ll_order_unpack(size_t n, const unsigned char **src, const unsigned char *end,
                          ll_order **out)
{
    const unsigned char *p = *src;
    uint64_t flag, n_sent, total;
    size_t s, segs = 2 * n + 1, h = n / 2;
    ll_order *o = NULL;

    *out = NULL;
    if (!get_u64(&p, end, &flag) || flag > 1)
        goto malformed;
    if (flag == 1) {
        /* Validate before allocating: counts must fit what arrived. */
        if (!get_u64(&p, end, &n_sent) || n_sent != n || !get_u64(&p, end, &total) ||
            (size_t)(end - p) / SEGMENT_BYTES < segs ||
            total > ((size_t)(end - p) - segs * SEGMENT_BYTES) / sizeof(double))
            goto malformed;
        o = ll_calloc(1, sizeof *o);
        if (o) {
            o->refcount = 1;
            o->n = n;
            o->seg = ll_calloc_array(segs, sizeof *o->seg);
            o->val = ll_alloc_array(total ? (size_t)total : 1, sizeof *o->val);
        }
        if (!o || !o->seg || !o->val) {
            ll_order_release(o);
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory receiving a %zu-node order",
                           n);
        }
        for (s = 0; s < segs; ++s) {
            uint64_t off;
            memcpy(&o->seg[s].lo, p, sizeof(uint32_t));
            memcpy(&o->seg[s].len, p + sizeof(uint32_t), sizeof(uint32_t));
            memcpy(&off, p + 2 * sizeof(uint32_t), sizeof off);
            p += SEGMENT_BYTES;
            o->seg[s].off = (size_t)off;
            if (off > total || (s < segs - 1 && ((size_t)o->seg[s].lo + o->seg[s].len > h ||
                                                 o->seg[s].len > total - off)))
                goto malformed;
        }
        if (o->seg[segs - 1].off != total)
            goto malformed;
        memcpy(o->val, p, (size_t)total * sizeof(double));
        p += (size_t)total * sizeof(double);
    }
    *src = p;
    *out = o;
    return LL_OK;
malformed:
    ll_order_release(o);
    return ll_fail(LL_ERROR_FORMAT, "a received order of a layer is malformed");
}
