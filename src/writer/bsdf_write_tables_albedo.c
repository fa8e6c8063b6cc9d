/*
 * ll_tables_albedo (bsdf_write_tables.h): the reflected and transmitted
 * albedo of an opened file for one viewer, by quadrature of ll_bsdf_eval_dir
 * (what a renderer evaluates), the same rule for a .bsdf and a table file.
 *
 * Why not the mean of the sampler's weights: a sampler splits u[0] between
 * the lobes (and a table's refracted sets between two incident elevations),
 * so a lobe that takes a few percent of the light gets a few rows of a
 * stratified grid, and the edges of total internal reflection cut the
 * rows it gets; seen from below rough glass's transmission at 60 degrees
 * took 3% of 256^2 strata and was off by 2-3% for the .bsdf and its table
 * alike, against ll_bsdf_albedo, which integrates the .bsdf's series.
 *
 * Each lobe is an integral over its hemisphere in (theta, phi) about the
 * normal of f cos theta sin theta, phi over [0, pi] and doubled (the files
 * are isotropic: f is even in phi). It starts from cells graded towards
 * the lobe's peak elevation in theta (the caller's) and towards phi = pi
 * (the plane of incidence behind the normal, where the mirror and the
 * refracted peaks lie), each integrated by the 15-point Kronrod rule in
 * both directions, and halves, pass after pass, every cell whose sum
 * changes by more than its area's share of EPS of the lobe's albedo when
 * the 7-point Gauss rule replaces Kronrod's in theta or in phi (along the
 * direction where it changes more). The integrand has kinks a fixed
 * product rule resolves only slowly (with 256 x 128 points per lobe,
 * graded the same way, rough glass's table seen from below at 20 degrees
 * moved by 6e-4 when they were doubled): the edge of total
 * internal reflection seen from the denser side (Fresnel's square root
 * there), a table's cells, the horizon. Each pass is one batch of
 * evaluations, bit-identical for any thread count, so the cells chosen
 * and the sums are too. A lobe under FLOOR of the viewer's R + T is held
 * to EPS of that floor instead, so that a lobe with next to no light
 * (transmission beyond the critical angle) does not drive the refinement;
 * MAX_CELLS bounds the work.
 *
 * The Kronrod-Gauss difference overstates the error by far: with EPS 1e-3
 * a table's R and T over its source's (rough glass and the compensated
 * pane at 64 x 96^2 x 96^2, every viewer of ll_tables_measure) moved by
 * at most 9e-5 against EPS 1e-5 (at 14 times the cost); rough glass's
 * .bsdf is within 1.5e-4 of ll_bsdf_albedo (the part eval clamps at 0,
 * pbrt-v3's max(0, Y), included), the pane's within 9e-5.
 * tests/test_tables_albedo.c holds the .bsdf to ll_bsdf_albedo and a
 * table to a fine product rule, within 0.05%.
 */
#include "writer/bsdf_write_tables.h"

#include <math.h>
#include <string.h>

#define KRONROD 15
#define THETA_START 8  /* theta cells on either side of the peak */
#define PHI_START 4    /* phi cells, graded towards pi           */
#define PASSES 16      /* halvings at most                       */
#define MAX_CELLS 8192 /* 1.8 million evaluations                */
#define EPS 1e-3       /* of the lobe, summed over its cells     */
#define FLOOR 0.01     /* of R + T                               */

/* The 15-point Kronrod rule and its 7-point Gauss rule on [-1, 1]
 * (Piessens et al., QUADPACK, 1983: nodes +-xgk[k], Gauss at the odd k). */
static const double xgk[8] = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.000000000000000000000000000000000
};
static const double wgk[8] = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714
};
static const double wg[4] = { 0.129484966168869693270611432679082,
                              0.279705391489276667901467771423780,
                              0.381830050505118944950369775488975,
                              0.417959183673469387755102040816327 };

/* Node k (0..14) of the Kronrod rule on [-1, 1], its weight, and the Gauss
 * rule's weight there (0 off the Gauss nodes). */
static double kronrod_x(int k) { return k < 7 ? -xgk[k] : (k == 7 ? 0.0 : xgk[14 - k]); }
static double kronrod_w(int k) { return wgk[k < 8 ? k : 14 - k]; }
static double gauss_w(int k)
{
    int j = k < 8 ? k : 14 - k;
    return j % 2 == 1 ? wg[j / 2] : 0.0;
}

/* A cell [a, b] x [c, d] of (theta, phi) with its Kronrod-Kronrod sum k
 * and the sums' changes with the Gauss rule along theta (et) or phi (ep),
 * per channel. */
typedef struct cell {
    double a, b, c, d;
    int lobe; /* 0 reflected, 1 transmitted */
    int open; /* still to be evaluated      */
    double k[3], et[3], ep[3];
} cell;

typedef struct work {
    const ll_bsdf *b;
    double wo[3];
    cell *cells;
    size_t n, cap;
    double *dirs, *wos, *vals; /* one pass's batch */
    size_t batch_cap;
} work;

static ll_status add(work *w, double a, double b, double c, double d, int lobe)
{
    cell *x;
    if (w->n == w->cap) {
        cell *cells = ll_grow_array(w->cells, &w->cap, 128, sizeof *cells);
        if (!cells)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_tables_albedo: out of memory");
        w->cells = cells;
    }
    x = &w->cells[w->n++];
    memset(x, 0, sizeof *x);
    x->a = a;
    x->b = b;
    x->c = c;
    x->d = d;
    x->lobe = lobe;
    x->open = 1;
    return LL_OK;
}

/* Breakpoint j of n on [from, to] graded as from + (to - from) s^2 towards
 * from. */
static double graded(double from, double to, int j, int n)
{
    double s = (double)j / n;
    return from + (to - from) * s * s;
}

/* The lobe's hemisphere, theta cut at the peak and graded towards it on
 * either side, phi in [0, pi] graded towards pi. */
static ll_status start(work *w, double peak, int lobe)
{
    const double ends[2] = { 0.0, LL_PI / 2.0 };
    int side, i, j;
    ll_status s;
    for (side = 0; side < 2; ++side) {
        if (fabs(ends[side] - peak) < 1e-9)
            continue;
        for (i = 0; i < THETA_START; ++i) {
            double t0 = graded(peak, ends[side], i, THETA_START);
            double t1 = graded(peak, ends[side], i + 1, THETA_START);
            for (j = 0; j < PHI_START; ++j) {
                double p0 = graded(LL_PI, 0.0, j + 1, PHI_START);
                double p1 = graded(LL_PI, 0.0, j, PHI_START);
                if ((s = add(w, t0 < t1 ? t0 : t1, t0 < t1 ? t1 : t0, p0, p1, lobe)) != LL_OK)
                    return s;
            }
        }
    }
    return LL_OK;
}

static double mid(double a, double b, int k) { return 0.5 * (a + b) + 0.5 * (b - a) * kronrod_x(k); }

/* Evaluate every open cell's nodes in one batch and close the cells. */
static ll_status pass(work *w)
{
    const size_t per = KRONROD * KRONROD;
    size_t i, open = 0, count, at;
    ll_status s;
    int k, j, c;
    for (i = 0; i < w->n; ++i)
        open += (size_t)w->cells[i].open;
    if (!open)
        return LL_OK;
    count = open * per;
    if (count > w->batch_cap) {
        ll_free(w->dirs);
        ll_free(w->wos);
        ll_free(w->vals);
        w->dirs = ll_alloc_array(count, 3 * sizeof(double));
        w->wos = ll_alloc_array(count, 3 * sizeof(double));
        w->vals = ll_alloc_array(count, 3 * sizeof(double));
        w->batch_cap = w->dirs && w->wos && w->vals ? count : 0;
        if (!w->batch_cap)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_tables_albedo: out of memory");
    }
    at = 0;
    for (i = 0; i < w->n; ++i) {
        const cell *x = &w->cells[i];
        /* A transmitted lobe lies on the far side of the viewer. */
        double z = (w->wo[2] < 0.0) != (x->lobe == 1) ? -1.0 : 1.0;
        if (!x->open)
            continue;
        for (k = 0; k < KRONROD; ++k) {
            double theta = mid(x->a, x->b, k), st = sin(theta), ct = cos(theta);
            for (j = 0; j < KRONROD; ++j, ++at) {
                double phi = mid(x->c, x->d, j);
                w->dirs[3 * at] = st * cos(phi);
                w->dirs[3 * at + 1] = st * sin(phi);
                w->dirs[3 * at + 2] = z * ct;
                memcpy(w->wos + 3 * at, w->wo, sizeof w->wo);
            }
        }
    }
    if ((s = ll_bsdf_eval_dir_batch(w->b, count, w->wos, w->dirs, LL_TRANSPORT_RADIANCE, NULL, 0,
                                    w->vals)) != LL_OK)
        return s;
    at = 0;
    for (i = 0; i < w->n; ++i) {
        cell *x = &w->cells[i];
        /* The phi integral doubled: f is even in phi (isotropic files). */
        double area = 2.0 * 0.25 * (x->b - x->a) * (x->d - x->c);
        double gk[3] = { 0.0, 0.0, 0.0 }, kg[3] = { 0.0, 0.0, 0.0 };
        if (!x->open)
            continue;
        for (c = 0; c < 3; ++c)
            x->k[c] = 0.0;
        for (k = 0; k < KRONROD; ++k) {
            double theta = mid(x->a, x->b, k), jac = cos(theta) * sin(theta);
            for (j = 0; j < KRONROD; ++j, ++at)
                for (c = 0; c < 3; ++c) {
                    double v = area * jac * w->vals[3 * at + c];
                    x->k[c] += kronrod_w(k) * kronrod_w(j) * v;
                    gk[c] += gauss_w(k) * kronrod_w(j) * v;
                    kg[c] += kronrod_w(k) * gauss_w(j) * v;
                }
        }
        for (c = 0; c < 3; ++c) {
            x->et[c] = fabs(x->k[c] - gk[c]);
            x->ep[c] = fabs(x->k[c] - kg[c]);
        }
        x->open = 0;
    }
    return LL_OK;
}

static void totals(const work *w, double sum[2][3])
{
    size_t i;
    int c;
    memset(sum, 0, 2 * sizeof sum[0]);
    for (i = 0; i < w->n; ++i)
        for (c = 0; c < 3; ++c)
            sum[w->cells[i].lobe][c] += w->cells[i].k[c];
}

/* Halve, along the direction of its larger error, every cell whose error
 * is above its area's share of EPS; *split the number halved. */
static ll_status refine(work *w, size_t *split)
{
    const double hemisphere = 0.5 * LL_PI * LL_PI; /* the (theta, phi) area */
    double sum[2][3];
    size_t i, n = w->n;
    int c;
    ll_status s;
    totals(w, sum);
    *split = 0;
    for (i = 0; i < n && w->n < MAX_CELLS; ++i) {
        cell x = w->cells[i];
        double et = 0.0, ep = 0.0;
        int over = 0;
        for (c = 0; c < 3; ++c) {
            double all = fabs(sum[0][c]) + fabs(sum[1][c]);
            double scale = fabs(sum[x.lobe][c]) > FLOOR * all ? fabs(sum[x.lobe][c]) : FLOOR * all;
            double share = EPS * scale * (x.b - x.a) * (x.d - x.c) / hemisphere;
            over |= x.et[c] > share || x.ep[c] > share;
            et += scale > 0.0 ? x.et[c] / scale : 0.0;
            ep += scale > 0.0 ? x.ep[c] / scale : 0.0;
        }
        if (!over)
            continue;
        w->cells[i].open = 1;
        if (et >= ep) {
            w->cells[i].b = 0.5 * (x.a + x.b);
            s = add(w, 0.5 * (x.a + x.b), x.b, x.c, x.d, x.lobe);
        } else {
            w->cells[i].d = 0.5 * (x.c + x.d);
            s = add(w, x.a, x.b, 0.5 * (x.c + x.d), x.d, x.lobe);
        }
        if (s != LL_OK)
            return s;
        ++*split;
    }
    return LL_OK;
}

ll_status ll_tables_albedo(const ll_bsdf *b, const double wo[3], const double peak[2],
                           int transmissive, double r[3], double t[3])
{
    work w;
    double sum[2][3];
    size_t split = 1;
    int p, c;
    ll_status s;
    memset(&w, 0, sizeof w);
    w.b = b;
    memcpy(w.wo, wo, sizeof w.wo);
    if ((s = start(&w, peak[0], 0)) != LL_OK ||
        (transmissive && (s = start(&w, peak[1], 1)) != LL_OK))
        goto done;
    for (p = 0; p < PASSES && split; ++p)
        if ((s = pass(&w)) != LL_OK || (p + 1 < PASSES && (s = refine(&w, &split)) != LL_OK))
            goto done;
    totals(&w, sum);
    for (c = 0; c < 3; ++c) {
        r[c] = sum[0][c];
        t[c] = sum[1][c];
    }
done:
    ll_free(w.cells);
    ll_free(w.dirs);
    ll_free(w.wos);
    ll_free(w.vals);
    return s;
}
