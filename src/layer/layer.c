/*
 * ll_layer: life cycle, reading (eval, matrix, albedo), the clear layer
 * and the reversal (top and bottom swapped).
 */
#include "layer/layer.h"
#include "numerics/spline.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ life cycle */

static void layer_free(ll_layer *l)
{
    size_t k;
    if (!l)
        return;
    if (l->orders)
        for (k = 0; k < l->m; ++k)
            ll_order_release(l->orders[k]);
    ll_free(l->orders);
    ll_free(l->nodes);
    ll_free(l->weights);
    ll_free(l);
}

void ll_layer_destroy(ll_layer *layer) { layer_free(layer); }

/* All orders of a clear layer share one identity order. */
static ll_status fill_clear(ll_order **orders, size_t n, size_t m)
{
    ll_order *id;
    size_t k;
    ll_status s = ll_order_identity(n, &id);
    if (s != LL_OK)
        return s;
    for (k = 0; k < m; ++k)
        orders[k] = ll_order_retain(id);
    ll_order_release(id);
    return LL_OK;
}

ll_status ll_layer_create(const double *nodes, const double *weights, size_t n_nodes,
                          size_t n_orders, ll_layer **out)
{
    ll_layer *l = NULL;
    size_t i, h = n_nodes / 2;
    int ascending;
    ll_status s;

    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_create: out is NULL");
    *out = NULL;
    if (!nodes || !weights)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_create: nodes or weights is NULL");
    if (n_nodes < 2 || n_nodes % 2 != 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_create: the node count must be even and at least 2 (got %zu)",
                       n_nodes);
    if (n_nodes > (size_t)UINT32_MAX / 2)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_create: %zu nodes are too many",
                       n_nodes);
    if (n_orders < 1)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_create: at least one Fourier order is needed");
    for (i = 0; i < n_nodes; ++i) {
        if (!ll_is_finite(nodes[i]) || nodes[i] < -1.0 || nodes[i] > 1.0)
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_layer_create: node %zu (%g) is not a cosine in [-1, 1]", i,
                           nodes[i]);
        if (nodes[i] == 0.0)
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_layer_create: node %zu is mu = 0, which layers cannot use "
                           "(take an even-sized Gauss-Legendre or Gauss-Lobatto rule)",
                           i);
        if (!ll_is_finite(weights[i]) || !(weights[i] > 0.0))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_layer_create: weight %zu (%g) is not positive and finite", i,
                           weights[i]);
    }
    ascending = nodes[0] < nodes[1];

    l = ll_calloc(1, sizeof *l);
    if (!l)
        goto oom;
    l->n = n_nodes;
    l->m = n_orders;
    l->nodes = ll_alloc_array(n_nodes, sizeof(double));
    l->weights = ll_alloc_array(n_nodes, sizeof(double));
    l->orders = ll_calloc_array(n_orders, sizeof(ll_order *));
    if (!l->nodes || !l->weights || !l->orders)
        goto oom;

    /* Adding-doubling order: reverse the negative half of an ascending rule
     * so that index j and j + h are -x and +x of the same magnitude. */
    for (i = 0; i < n_nodes; ++i) {
        size_t src = (ascending && i < h) ? h - 1 - i : i;
        l->nodes[i] = nodes[src];
        l->weights[i] = weights[src];
    }
    for (i = 0; i < h; ++i) {
        double a = l->nodes[i], b = l->nodes[i + h];
        if (!(a < 0.0 && b > 0.0 && fabs(a + b) <= 1e-12 * fabs(b)))
            return layer_free(l),
                   ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_layer_create: the nodes must be symmetric about 0 (%g and %g "
                           "should have the same magnitude)",
                           a, b);
        if (i > 0 && !(b > l->nodes[i + h - 1]))
            return layer_free(l),
                   ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_layer_create: the nodes must be sorted and distinct");
    }
    s = fill_clear(l->orders, n_nodes, n_orders);
    if (s != LL_OK) {
        layer_free(l);
        return s;
    }
    *out = l;
    return LL_OK;
oom:
    layer_free(l);
    return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_create: out of memory for %zu nodes, %zu orders",
                   n_nodes, n_orders);
}

ll_status ll_layer_clone(const ll_layer *src, ll_layer **out)
{
    ll_layer *l;
    size_t k;
    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_clone: out is NULL");
    *out = NULL;
    if (!src)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_clone: layer is NULL");
    l = ll_calloc(1, sizeof *l);
    if (!l)
        goto oom;
    l->n = src->n;
    l->m = src->m;
    l->nodes = ll_alloc_array(src->n, sizeof(double));
    l->weights = ll_alloc_array(src->n, sizeof(double));
    l->orders = ll_calloc_array(src->m, sizeof(ll_order *));
    if (!l->nodes || !l->weights || !l->orders)
        goto oom;
    memcpy(l->nodes, src->nodes, src->n * sizeof(double));
    memcpy(l->weights, src->weights, src->n * sizeof(double));
    for (k = 0; k < src->m; ++k)
        l->orders[k] = ll_order_retain(src->orders[k]);
    *out = l;
    return LL_OK;
oom:
    layer_free(l);
    return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_clone: out of memory");
}

size_t ll_layer_node_count(const ll_layer *layer) { return layer ? layer->n : 0; }
size_t ll_layer_order_count(const ll_layer *layer) { return layer ? layer->m : 0; }

ll_status ll_layer_get_nodes(const ll_layer *layer, double *nodes, double *weights)
{
    size_t a, h;
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_get_nodes: layer is NULL");
    h = layer->n / 2;
    for (a = 0; a < layer->n; ++a) {
        size_t src = a < h ? h - 1 - a : a;
        if (nodes)
            nodes[a] = layer->nodes[src];
        if (weights)
            weights[a] = layer->weights[src];
    }
    return LL_OK;
}

size_t ll_layer_stored_count(const ll_layer *layer)
{
    size_t k, total = 0;
    if (!layer)
        return 0;
    for (k = 0; k < layer->m; ++k)
        total += ll_order_stored(layer->orders[k]);
    return total;
}

/* ------------------------------------------------------------ internals */

void ll_layer_replace_orders(ll_layer *layer, ll_order **new_orders)
{
    const ll_split *split = ll_split_current();
    size_t k;
    for (k = 0; k < layer->m; ++k) {
        ll_order_release(layer->orders[k]);
        layer->orders[k] = new_orders[k];
        if (!ll_split_owns(split, k)) {
            /* A distributed build keeps only this rank's orders (a clear
             * layer's identity, a diffuse order 0 of another rank). */
            ll_order_release(layer->orders[k]);
            layer->orders[k] = NULL;
        }
    }
}

ll_status ll_layer_commit_orders(ll_layer *layer, ll_order **new_orders, ll_status status)
{
    size_t k;
    if (status == LL_OK) {
        ll_layer_replace_orders(layer, new_orders);
    } else {
        for (k = 0; k < layer->m; ++k)
            ll_order_release(new_orders[k]);
    }
    ll_free(new_orders);
    return status;
}

ll_status ll_layer_check_compatible(const ll_layer *a, const ll_layer *b, const char *fn)
{
    if (!a || !b)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: a layer is NULL", fn);
    if (a->n != b->n || a->m != b->m)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the layers do not match (%zu nodes x %zu orders vs %zu x %zu)", fn,
                       a->n, a->m, b->n, b->m);
    if (a != b && (memcmp(a->nodes, b->nodes, a->n * sizeof(double)) != 0 ||
                   memcmp(a->weights, b->weights, a->n * sizeof(double)) != 0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the layers use different nodes or weights", fn);
    return LL_OK;
}

double ll_layer_surface_factor(const ll_layer *l, size_t col, size_t order)
{
    return l->weights[col] * fabs(l->nodes[col]) * LL_PI * (order == 0 ? 2.0 : 1.0);
}

ll_status ll_layer_set_from_builders(ll_layer *layer, ll_order_builder **builders)
{
    size_t k, m = layer->m;
    ll_status s = LL_OK;
    ll_order **orders = ll_calloc_array(m, sizeof *orders);
    if (!orders) {
        for (k = 0; k < m; ++k)
            ll_order_builder_destroy(builders[k]);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory setting a layer");
    }
    for (k = 0; k < m; ++k) {
        if (s == LL_OK && builders[k])
            s = ll_order_builder_finish(builders[k], &orders[k]);
        else
            ll_order_builder_destroy(builders[k]);
        builders[k] = NULL;
    }
    return ll_layer_commit_orders(layer, orders, s);
}

/* ---------------------------------------------------------------- words */

ll_status ll_layer_clear(ll_layer *layer)
{
    ll_order **orders;
    ll_status s;
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_clear: layer is NULL");
    orders = ll_calloc_array(layer->m, sizeof *orders);
    if (!orders)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_clear: out of memory");
    s = fill_clear(orders, layer->n, layer->m);
    if (s == LL_OK)
        ll_layer_replace_orders(layer, orders);
    ll_free(orders);
    return s;
}

ll_status ll_layer_reverse(ll_layer *layer)
{
    size_t k, m;
    ll_order **orders;
    ll_status s = LL_OK;
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_reverse: layer is NULL");
    m = layer->m;
    orders = ll_calloc_array(m, sizeof *orders);
    if (!orders)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_reverse: out of memory");
    for (k = 0; k < m && s == LL_OK; ++k) {
        /* Orders shared within the layer (a clear layer's identity) are
         * reversed once. */
        if (k > 0 && layer->orders[k] == layer->orders[k - 1])
            orders[k] = ll_order_retain(orders[k - 1]);
        else
            s = ll_order_reversed(layer->orders[k], &orders[k]);
    }
    return ll_layer_commit_orders(layer, orders, s);
}

/* -------------------------------------------------------------- reading */

/* Spline weights for a direction cosine mu against the positive half of the
 * nodes; returns the internal index of the first of the four nodes. The
 * side is chosen by the sign of mu (and of `other` when mu == 0, as the
 * original does for grazing directions). */
static ptrdiff_t direction_weights(const ll_layer *l, double mu, double other, double w[4])
{
    size_t h = l->n / 2;
    ptrdiff_t offset = 0;
    int negative = mu < 0.0 || (mu == 0.0 && other > 0.0);
    if (h < 2) {
        /* One node per hemisphere: the BSDF is constant in mu. */
        w[0] = w[2] = w[3] = 0.0;
        w[1] = 1.0;
        offset = -1;
    } else {
        ll_spline_weights(l->nodes + h, h, fabs(mu), &offset, w, 1);
    }
    return negative ? offset : offset + (ptrdiff_t)h;
}

/* The interpolated BSDF: for each Fourier order, the 4 x 4 spline stencil
 * of weighted matrix entries around (mu_o, mu_i), summed with cos(k phi).
 * The stencil's rows lie in one half of a column, so each of the four
 * columns contributes through one stored run. */
static double eval_point(const ll_layer *l, double mu_o, double mu_i, double phi_d)
{
    double wo[4], wi[4], scale[4], result = 0.0;
    ptrdiff_t oo, oi, row0;
    size_t h = l->n / 2, k;
    int a, b, half_o, half_i;
    double c1, cos_prev, cos_cur;

    oo = direction_weights(l, mu_o, mu_i, wo);
    oi = direction_weights(l, mu_i, mu_o, wi);
    /* Which half each stencil lies in; a weight of a node beyond the end
     * of the half is 0 by construction and is skipped. */
    half_o = oo >= (ptrdiff_t)h - 1;
    half_i = oi >= (ptrdiff_t)h - 1;
    row0 = oo - (half_o ? (ptrdiff_t)h : 0);
    for (b = 0; b < 4; ++b) {
        ptrdiff_t col = oi + b, c = col - (half_i ? (ptrdiff_t)h : 0);
        if (wi[b] == 0.0 || c < 0 || c >= (ptrdiff_t)h)
            scale[b] = 0.0;
        else
            scale[b] = wi[b] / (fabs(l->nodes[col]) * l->weights[col]);
    }
    c1 = cos(phi_d);
    cos_prev = c1; /* cos(-phi) */
    cos_cur = 1.0;
    for (k = 0; k < l->m; ++k) {
        const ll_order *o = l->orders[k];
        double next;
        if (o) {
            double sum = 0.0;
            for (b = 0; b < 4; ++b) {
                size_t seg;
                ptrdiff_t lo, len;
                const double *val;
                if (scale[b] == 0.0)
                    continue;
                seg = 2 * (size_t)(oi + b) + (size_t)half_o;
                lo = (ptrdiff_t)o->seg[seg].lo;
                len = (ptrdiff_t)o->seg[seg].len;
                val = o->val + o->seg[seg].off;
                for (a = 0; a < 4; ++a) {
                    ptrdiff_t r = row0 + a;
                    if (wo[a] != 0.0 && r >= lo && r < lo + len)
                        sum += wo[a] * scale[b] * val[r - lo];
                }
            }
            result += sum * cos_cur * (k == 0 ? 0.5 : 1.0);
        }
        /* cos((k+1) phi) = 2 cos(phi) cos(k phi) - cos((k-1) phi) */
        next = 2.0 * c1 * cos_cur - cos_prev;
        cos_prev = cos_cur;
        cos_cur = next;
    }
    result *= LL_INV_PI;
    return result > 0.0 ? result : 0.0;
}

/* f at one point, arguments clamped; 0 for a NaN argument. */
static double eval_clamped(const ll_layer *layer, double mu_i, double mu_o, double phi_d)
{
    if (mu_o != mu_o || mu_i != mu_i || phi_d != phi_d)
        return 0.0;
    if (mu_o > 1.0) mu_o = 1.0;
    if (mu_o < -1.0) mu_o = -1.0;
    if (mu_i > 1.0) mu_i = 1.0;
    if (mu_i < -1.0) mu_i = -1.0;
    return eval_point(layer, mu_o, mu_i, phi_d);
}

ll_status ll_layer_eval(const ll_layer *layer, double mu_i, double mu_o, double phi_d,
                        double *f)
{
    static const char fn[] = "ll_layer_eval";
    if (!f)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: f is NULL", fn);
    *f = 0.0;
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layer is NULL", fn);
    if (mu_o != mu_o || mu_i != mu_i || phi_d != phi_d)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: an argument is NaN (mu_i %g, mu_o %g, phi_d %g)", fn, mu_i, mu_o,
                       phi_d);
    *f = eval_clamped(layer, mu_i, mu_o, phi_d);
    return LL_OK;
}

ll_status ll_layer_eval_many(const ll_layer *layer, size_t count, const double *mu_i,
                             const double *mu_o, const double *phi_d, double *out)
{
    long long k, n = (long long)count;
    if (!layer || (count && (!mu_o || !mu_i || !out)))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_eval_many: a required pointer is NULL");
#pragma omp parallel for schedule(static) num_threads((int)ll_get_thread_count()) if (count > 4096)
    for (k = 0; k < n; ++k)
        out[k] = eval_clamped(layer, mu_i[k], mu_o[k], phi_d ? phi_d[k] : 0.0);
    return LL_OK;
}

ll_status ll_layer_matrix(const ll_layer *layer, size_t order, double *out)
{
    size_t n, h, r, c;
    if (!layer || !out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_matrix: layer or out is NULL");
    if (order >= layer->m)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_matrix: order %zu is beyond the layer's %zu orders", order,
                       layer->m);
    n = layer->n;
    h = n / 2;
    for (r = 0; r < n; ++r) {
        size_t ir = r < h ? h - 1 - r : r;
        for (c = 0; c < n; ++c) {
            size_t ic = c < h ? h - 1 - c : c;
            out[r * n + c] = ll_order_get(layer->orders[order], ir, ic) /
                             ll_layer_surface_factor(layer, ic, order);
        }
    }
    return LL_OK;
}

ll_status ll_layer_albedo(const ll_layer *layer, double mu_i, double *reflectance,
                          double *transmittance)
{
    size_t h, r;
    double wi[4], R = 0.0, T = 0.0;
    ptrdiff_t oi;
    int b;
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_albedo: layer is NULL");
    if (!(fabs(mu_i) > 0.0 && fabs(mu_i) <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_albedo: mu_i = %g is not a cosine in [-1, 0) or (0, 1]", mu_i);
    h = layer->n / 2;
    oi = direction_weights(layer, mu_i, 0.0, wi);
    /* Flux ratio of incident column i: sum_o M0(o, i) |mu_o| w_o / (|mu_i| w_i),
     * interpolated over the incident nodes with the spline weights. */
    for (b = 0; b < 4; ++b) {
        ptrdiff_t col = oi + b;
        ptrdiff_t half0 = mu_i < 0.0 ? 0 : (ptrdiff_t)h;
        double scale;
        if (wi[b] == 0.0 || col < half0 || col >= half0 + (ptrdiff_t)h)
            continue;
        scale = wi[b] / (fabs(layer->nodes[col]) * layer->weights[col]);
        for (r = 0; r < layer->n; ++r) {
            double v = ll_order_get(layer->orders[0], r, (size_t)col) * fabs(layer->nodes[r]) *
                       layer->weights[r] * scale;
            /* Reflection leaves into the other half: up (rows < h) for light
             * travelling down (mu_i > 0). */
            if ((r < h) == (mu_i > 0.0))
                R += v;
            else
                T += v;
        }
    }
    if (reflectance)
        *reflectance = R;
    if (transmittance)
        *transmittance = T;
    return LL_OK;
}
