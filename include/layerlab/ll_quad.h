/*
 * layerlab — quadrature rules on [-1, 1].
 *
 * All rules write n nodes in ascending order and their weights into caller
 * buffers of length n. They are pure functions: thread-safe, no allocation
 * that outlives the call. Nodes and weights are accurate to about 1e-14 for
 * every n up to at least 4096 (the Gauss rules use Newton iteration on
 * Legendre recurrences started from asymptotic estimates, so they do not
 * degrade at large n as tabulated or eigenvalue-based rules do).
 */
#ifndef LAYERLAB_LL_QUAD_H
#define LAYERLAB_LL_QUAD_H

#include "ll_common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The Gauss rules cost O(n) per node, O(n^2) in all, so they
 * take a monitor (ll_common.h; nullable): stage "quadrature", one unit per
 * node pair, polled once per node (per Newton sweep), on the calling
 * thread (the rules use no other). With a monitor the rule is computed
 * into scratch memory (16 n bytes, so LL_ERROR_OUT_OF_MEMORY is possible)
 * and copied out at the end: LL_ERROR_CANCELLED leaves both buffers
 * exactly as they were.
 *
 * Gauss-Legendre: n >= 1 nodes, exact for polynomials of degree 2n-1.
 * No node is at +-1; for odd n one node is 0 (not usable for layers).
 * Returns LL_ERROR_INVALID_ARGUMENT for n == 0 or NULL buffers. */
LL_API ll_status ll_quad_gauss_legendre(size_t n, double *nodes, double *weights,
                                        const ll_monitor *monitor);

/* Gauss-Lobatto: n >= 2 nodes including both end points -1 and 1, exact
 * for polynomials of degree 2n-3. ll_quad_gauss_lobatto(10, ...) gives
 * -1, -0.91953391, -0.73877387, -0.47792495, -0.16527896, 0.16527896, ...
 * with weights 0.02222222, 0.13330599, 0.22488934, 0.29204268, 0.32753976, ...
 * LL_ERROR_INVALID_ARGUMENT for n < 2 or NULL buffers; with a monitor also
 * LL_ERROR_OUT_OF_MEMORY and LL_ERROR_CANCELLED (above). Both Gauss rules
 * return LL_ERROR_NUMERICAL should Newton's iteration not settle on a
 * node. */
LL_API ll_status ll_quad_gauss_lobatto(size_t n, double *nodes, double *weights,
                                       const ll_monitor *monitor);

/* Composite Simpson: odd n >= 3 equidistant nodes (n-1 even intervals),
 * exact for cubics. LL_ERROR_INVALID_ARGUMENT for another n or NULL
 * buffers. */
LL_API ll_status ll_quad_composite_simpson(size_t n, double *nodes, double *weights);

/* Composite Simpson 3/8: n >= 4 equidistant nodes with n-1 divisible by 3,
 * exact for cubics. LL_ERROR_INVALID_ARGUMENT for another n or NULL
 * buffers. */
LL_API ll_status ll_quad_composite_simpson38(size_t n, double *nodes, double *weights);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_QUAD_H */
