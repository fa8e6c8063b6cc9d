/*
 * The grammar of layers: adding (Grant and Hunt 1969; Jakob et al. 2014,
 * section 5) and doubling (section 5.2), with the closed-form slab of
 * slab.c as the other way to give a medium its thickness. This is the only
 * code that combines layers.
 *
 * Each Fourier order is independent, so orders run in parallel
 * (ll_parallel_for); inside an order the blocks are expanded to dense
 * column-major h x h matrices and combined with LAPACK (getrf/getrs) and
 * BLAS-3 (gemm), then compressed back.
 */
#include "grammar/grammar.h"
#include "grammar/slab.h"
#include "numerics/lu.h"
#include "support/watch.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Dense blocks of one order; zero[] says which are identically zero. */
typedef struct dense_order {
    double *blk[4]; /* indexed by LL_BLOCK_* */
    int zero[4];
} dense_order;

/* Per-thread scratch: two inputs, one output, the gain matrices and the
 * right-hand sides. Allocated per order (one malloc), so nothing is shared. */
typedef struct workspace {
    size_t h;
    dense_order top, bottom, out;
    double *gain_tb, *gain_bt; /* h x h LU factors, then h x h scratch  */
    double *rhs;               /* h x h: Ra Tb                          */
    lapack_int *piv_tb, *piv_bt;
    void *memory;
    double *slab;              /* slab.c's scratch, made when first needed */
    ll_watch *watch;           /* polled between the BLAS calls (nullable) */
} workspace;

static void workspace_free(workspace *w)
{
    ll_free(w->memory);
    ll_free(w->slab);
}

static ll_status workspace_init(workspace *w, size_t h)
{
    size_t hh, doubles, k;
    double *p;
    memset(w, 0, sizeof *w);
    w->h = h;
    w->watch = NULL;
    /* 12 blocks + 2 x (gain, Z) + rhs = 17 h^2 doubles, plus pivots. */
    if (!ll_size_mul(h, h, &hh) || !ll_size_mul(hh, 17, &doubles) ||
        !ll_size_add(doubles, h, &doubles) || !ll_size_add(doubles, h, &doubles))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "adding: %zu nodes are too many", 2 * h);
    w->memory = ll_alloc_array(doubles, sizeof(double));
    if (!w->memory)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY,
                       "adding: out of memory for the work matrices of %zu nodes", 2 * h);
    p = w->memory;
    for (k = 0; k < 4; ++k) {
        w->top.blk[k] = p; p += hh;
        w->bottom.blk[k] = p; p += hh;
        w->out.blk[k] = p; p += hh;
    }
    w->gain_tb = p; p += 2 * hh;
    w->gain_bt = p; p += 2 * hh;
    w->rhs = p; p += hh;
    w->piv_tb = (lapack_int *)p; p += h;
    w->piv_bt = (lapack_int *)p;
    return LL_OK;
}

/*
 * One workspace per thread, made by the first order a thread runs and
 * reused by its next ones: the work matrices of h = 550 are 40 MB, and
 * fresh ones per order cost a page fault per 4 KiB (the system time of
 * long builds). Orders write every entry they read, so what a slot held
 * before changes nothing: results stay the same for any thread count.
 */
typedef struct workspace_pool {
    size_t count;
    workspace *slot;
} workspace_pool;

static ll_status pool_create(workspace_pool *p, const char *fn)
{
    p->count = ll_get_thread_count();
    p->slot = ll_calloc_array(p->count, sizeof *p->slot);
    return p->slot ? LL_OK : ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
}

static void pool_destroy(workspace_pool *p)
{
    size_t i;
    for (i = 0; p->slot && i < p->count; ++i)
        workspace_free(&p->slot[i]);
    ll_free(p->slot);
    p->slot = NULL;
}

/* The calling thread's workspace for h, made on first use. */
static ll_status pool_get(workspace_pool *p, size_t h, ll_watch *watch, workspace **out)
{
    size_t i = ll_parallel_slot();
    workspace *w;
    ll_status s;
    if (i >= p->count)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "adding: thread %zu of a loop sized for %zu threads", i, p->count);
    w = &p->slot[i];
    if (!w->memory) {
        s = workspace_init(w, h);
        if (s != LL_OK)
            return s;
    }
    w->watch = watch;
    *out = w;
    return LL_OK;
}

static void load_order(const ll_order *o, size_t n, dense_order *d)
{
    int k;
    for (k = 0; k < 4; ++k)
        d->zero[k] = !ll_order_block_to_dense(o, n, k, d->blk[k]);
}

/* C = alpha A B + beta C for h x h (A) times h x cols (B), column-major. */
static void gemm(size_t h, size_t cols, double alpha, const double *A, const double *B,
                 double beta, double *C)
{
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, (blasint)h, (blasint)cols,
                (blasint)h, alpha, A, (blasint)h, B, (blasint)h, beta, C, (blasint)h);
}

/* gain = I - A B, LU-factored in place. */
static ll_status factor_gain(size_t h, const double *A, const double *B, double *gain,
                             lapack_int *piv)
{
    size_t i;
    lapack_int info;
    gemm(h, h, -1.0, A, B, 0.0, gain);
    for (i = 0; i < h; ++i)
        gain[i * h + i] += 1.0;
    info = ll_lu_factor(h, gain, piv);
    if (info != 0)
        return ll_fail(LL_ERROR_NUMERICAL,
                       "adding: the gain matrix I - R R is singular (getrf info %d); a "
                       "non-absorbing stack of two perfect reflectors has no finite solution",
                       (int)info);
    return LL_OK;
}

static int all_zero(const double *x, size_t count)
{
    size_t i;
    for (i = 0; i < count; ++i)
        if (x[i] != 0.0)
            return 0;
    return 1;
}

/*
 * One half of the adding equations (method.md; Grant and Hunt 1969). For
 * light entering through layer a towards layer b:
 *     Z = Tb_through (I - Ra_in Rb_in)^-1
 *     T_out = Z Ta_through,   R_out = Rb_out + Z Ra_in Tb_back
 * which gives T^tb and R^b of the sum for a = top (and, with the roles
 * mirrored, T^bt and R^t). Solving for Z from the right needs h right-hand
 * sides where solving G X = [Ta | Ra Tb] would need 2h; the products are
 * written straight into the output blocks (R_out accumulates onto Rb_out
 * with beta = 1). zero flags skip products with zero operands.
 *
 * Z is where Z is made: Tb_through itself when the caller lets it be
 * overwritten (Z == Tb_through), else a scratch it is copied to; R_out may
 * be Rb_out itself likewise. Adding two layers overwrites its loaded
 * copies that way (no h x h copy per direction); doubling, whose top and
 * bottom are one set of blocks, keeps them.
 */
static ll_status half_add(size_t h, const double *Ra_in, int zRa_in, const double *Rb_in,
                          int zRb_in, const double *Ta_through, int zTa_through,
                          const double *Tb_back, int zTb_back, const double *Tb_through,
                          int zTb_through, const double *Rb_out, int zRb_out, double *gain,
                          lapack_int *piv, double *rhs, double *Z, double *T_out,
                          double *R_out, ll_watch *watch)
{
    size_t hh = h * h;
    int coupled = !zRa_in && !zRb_in; /* multiple reflections between the layers */
    int reflect_back = !zRa_in && !zTb_back;
    ll_status s;

    if (zTb_through || (zTa_through && !reflect_back)) {
        memset(T_out, 0, hh * sizeof(double));
        if (R_out != Rb_out)
            memcpy(R_out, Rb_out, hh * sizeof(double));
        return LL_OK;
    }
    if (Z != Tb_through)
        memcpy(Z, Tb_through, hh * sizeof(double));
    /* Each BLAS/LAPACK call below is O(h^3): a cancel is seen between them
     * (about 1 s apart at h = 1000 on one loaded core). */
    if (coupled) {
        s = factor_gain(h, Ra_in, Rb_in, gain, piv);
        if (s != LL_OK)
            return s;
        if (ll_watch_poll(watch))
            return ll_fail(LL_ERROR_CANCELLED, "adding: cancelled");
        ll_right_solve_lu(h, gain, piv, Z);
        if (ll_watch_poll(watch))
            return ll_fail(LL_ERROR_CANCELLED, "adding: cancelled");
    }
    /* T_out = Z Ta_through and R_out = Rb_out + Z (Ra_in Tb_back), the
     * products written straight into the output blocks. */
    if (zTa_through)
        memset(T_out, 0, hh * sizeof(double));
    else
        gemm(h, h, 1.0, Z, Ta_through, 0.0, T_out);
    if (R_out != Rb_out)
        memcpy(R_out, Rb_out, hh * sizeof(double));
    if (ll_watch_poll(watch))
        return ll_fail(LL_ERROR_CANCELLED, "adding: cancelled");
    (void)zRb_out; /* a zero block is stored zero-filled */
    if (reflect_back) {
        gemm(h, h, 1.0, Ra_in, Tb_back, 0.0, rhs);
        if (ll_watch_poll(watch))
            return ll_fail(LL_ERROR_CANCELLED, "adding: cancelled");
        gemm(h, h, 1.0, Z, rhs, 1.0, R_out);
    }
    return LL_OK;
}

/* Swap two of the workspace's h x h buffers. */
static void swap_blocks(double **a, double **b)
{
    double *t = *a;
    *a = *b;
    *b = t;
}

/* out = top on bottom, both dense. homogeneous: top == bottom, symmetric
 * (doubling: the blocks are kept); otherwise the loaded blocks are scratch:
 * the downward half reads T^tb and R^b of the bottom last and makes Z and
 * R^b of the sum in them, the upward half likewise with T^bt and R^t of the
 * top (neither half reads what the other overwrites), and the results'
 * buffers trade places with them. */
static ll_status add_dense(workspace *w, int homogeneous)
{
    size_t h = w->h, hh = h * h;
    dense_order *t = &w->top, *b = &w->bottom, *o = &w->out;
    double *Z = homogeneous ? w->gain_tb + hh : b->blk[LL_BLOCK_TTB];
    double *R = homogeneous ? o->blk[LL_BLOCK_RB] : b->blk[LL_BLOCK_RB];
    ll_status s;
    int k;

    /* Downward: through the top into the bottom -> T^tb and R^b. */
    s = half_add(h, t->blk[LL_BLOCK_RB], t->zero[LL_BLOCK_RB], b->blk[LL_BLOCK_RT],
                 b->zero[LL_BLOCK_RT], t->blk[LL_BLOCK_TTB], t->zero[LL_BLOCK_TTB],
                 b->blk[LL_BLOCK_TBT], b->zero[LL_BLOCK_TBT], b->blk[LL_BLOCK_TTB],
                 b->zero[LL_BLOCK_TTB], b->blk[LL_BLOCK_RB], b->zero[LL_BLOCK_RB], w->gain_tb,
                 w->piv_tb, w->rhs, Z, o->blk[LL_BLOCK_TTB], R, w->watch);
    if (s != LL_OK)
        return s;
    if (!homogeneous)
        swap_blocks(&o->blk[LL_BLOCK_RB], &b->blk[LL_BLOCK_RB]);
    if (homogeneous) {
        /* Both sides of a symmetric slab are the same. */
        memcpy(o->blk[LL_BLOCK_TBT], o->blk[LL_BLOCK_TTB], h * h * sizeof(double));
        memcpy(o->blk[LL_BLOCK_RT], o->blk[LL_BLOCK_RB], h * h * sizeof(double));
    } else {
        /* Upward: through the bottom into the top -> T^bt and R^t. */
        s = half_add(h, b->blk[LL_BLOCK_RT], b->zero[LL_BLOCK_RT], t->blk[LL_BLOCK_RB],
                     t->zero[LL_BLOCK_RB], b->blk[LL_BLOCK_TBT], b->zero[LL_BLOCK_TBT],
                     t->blk[LL_BLOCK_TTB], t->zero[LL_BLOCK_TTB], t->blk[LL_BLOCK_TBT],
                     t->zero[LL_BLOCK_TBT], t->blk[LL_BLOCK_RT], t->zero[LL_BLOCK_RT],
                     w->gain_bt, w->piv_bt, w->rhs, t->blk[LL_BLOCK_TBT], o->blk[LL_BLOCK_TBT],
                     t->blk[LL_BLOCK_RT], w->watch);
        if (s != LL_OK)
            return s;
        swap_blocks(&o->blk[LL_BLOCK_RT], &t->blk[LL_BLOCK_RT]);
    }
    for (k = 0; k < 4; ++k)
        o->zero[k] = all_zero(o->blk[k], h * h);
    return LL_OK;
}

static ll_status store_dense(const dense_order *d, size_t h, ll_order **out)
{
    const double *blocks[4];
    int k;
    for (k = 0; k < 4; ++k)
        blocks[k] = d->zero[k] ? NULL : d->blk[k];
    return ll_order_from_blocks(blocks, h, LL_DROP_THRESHOLD, out);
}

/* ----------------------------------------------------------------- adding */

typedef struct add_job {
    const ll_layer *top, *bottom;
    ll_order **result;
    int homogeneous;
    ll_watch *watch;
    workspace_pool pool;
} add_job;

static ll_status add_order(size_t k, add_job *job);

static ll_status add_one_order(size_t k, void *ctx)
{
    add_job *job = ctx;
    ll_status s;
    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "ll_layer_add: cancelled");
    s = add_order(k, job);
    ll_watch_advance(job->watch, 1);
    return s;
}

/*
 * One side only transmits straight through (R = 0, diagonal T: a medium's
 * order beyond its phase function's moments, where only the unscattered
 * light is left): then nothing reflects between the two, and the sum is
 * the other side's matrix scaled by those diagonals,
 *     top straight:    R^t = Du R^t_b Dd, T^tb = T^tb_b Dd, T^bt = Du T^bt_b, R^b = R^b_b,
 *     bottom straight: R^b = Dd R^b_t Du, T^tb = Dd T^tb_t, T^bt = T^bt_t Du, R^t = R^t_t
 * (Dd, Du: the diagonals of T^tb, T^bt), on the compact runs, with the
 * products in the order of the dense path (the same bits, without its
 * O(h^3) work). *done = 0 if neither side is such an order.
 */
static ll_status add_straight_through(const ll_order *ot, const ll_order *ob, size_t n,
                                      ll_order **out, int *done)
{
    size_t h = n / 2, i;
    double *buf = ll_alloc_array(n, 3 * sizeof(double));
    double *down, *up, *left, *right;
    const ll_order *other = NULL;
    ll_status s = LL_OK;

    *done = 0;
    if (!buf)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_add: out of memory");
    down = buf;
    up = down + h;
    left = up + h;
    right = left + n;
    if (ll_order_diagonal(ot, down, up)) {
        for (i = 0; i < h; ++i) {
            left[i] = up[i];
            left[h + i] = 1.0;
            right[i] = 1.0;
            right[h + i] = down[i];
        }
        other = ob;
    } else if (ll_order_diagonal(ob, down, up)) {
        for (i = 0; i < h; ++i) {
            left[i] = 1.0;
            left[h + i] = down[i];
            right[i] = up[i];
            right[h + i] = 1.0;
        }
        other = ot;
    }
    if (other) {
        s = ll_order_scaled(other, left, right, LL_DROP_THRESHOLD, out);
        *done = 1;
    }
    ll_free(buf);
    return s;
}

static ll_status add_order(size_t k, add_job *job)
{
    ll_order *ot = job->top->orders[k], *ob = job->bottom->orders[k];
    size_t n = job->top->n;
    workspace *w;
    ll_status s;

    if (!ot && !ob)
        return LL_OK; /* nothing reflects or transmits in this order */
    /* An order that is all zero absorbs everything that enters it, so only
     * the other layer's reflection from its outer side survives: R^t of the
     * top over an absorbing bottom, R^b of the bottom under an absorbing top.
     * (A diffuse base has only order 0: this spares a coat over it all the
     * dense work of its other orders.) */
    if (!ob)
        return ll_order_keep_block(ot, LL_BLOCK_RT, &job->result[k]);
    if (!ot)
        return ll_order_keep_block(ob, LL_BLOCK_RB, &job->result[k]);
    {
        int done;
        s = add_straight_through(ot, ob, n, &job->result[k], &done);
        if (s != LL_OK || done)
            return s;
    }
    s = pool_get(&job->pool, n / 2, job->watch, &w);
    if (s != LL_OK)
        return s;
    load_order(ot, n, &w->top);
    load_order(ob, n, &w->bottom);
    s = add_dense(w, job->homogeneous);
    if (s == LL_OK)
        s = store_dense(&w->out, n / 2, &job->result[k]);
    return s;
}

ll_status ll_layer_add(const ll_layer *top, const ll_layer *bottom, ll_layer *out,
                       int homogeneous, const ll_monitor *monitor)
{
    static const char fn[] = "ll_layer_add";
    add_job job;
    ll_watch watch;
    ll_status s;

    s = ll_layer_check_compatible(top, bottom, fn);
    if (s == LL_OK)
        s = ll_layer_check_compatible(top, out, "ll_layer_add (output)");
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, fn);
    if (s != LL_OK)
        return s;
    job.top = top;
    job.bottom = bottom;
    job.homogeneous = homogeneous != 0;
    job.watch = &watch;
    job.result = ll_calloc_array(top->m, sizeof(ll_order *));
    if (!job.result)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_add: out of memory");
    s = pool_create(&job.pool, fn);
    if (s != LL_OK) {
        ll_free(job.result);
        return s;
    }
    /* An order is one unit (they cost about the same). */
    s = ll_watch_stage(&watch, "adding", 0.0, 1.0, top->m) ? ll_watch_check(&watch, fn) : LL_OK;
    if (s == LL_OK)
        s = ll_parallel_for_watched(top->m, add_one_order, &job, &watch);
    pool_destroy(&job.pool);
    s = ll_watch_finish(&watch, s, fn);
    return ll_layer_commit_orders(out, job.result, s);
}

ll_status ll_layer_add_to_top(ll_layer *layer, const ll_layer *top)
{
    return ll_layer_add(top, layer, layer, 0, NULL);
}

ll_status ll_layer_add_to_bottom(ll_layer *layer, const ll_layer *bottom)
{
    return ll_layer_add(layer, bottom, layer, 0, NULL);
}

/* --------------------------------------------------------------- doubling */

/* Progress: an order is doublings + 1 units (the steps, then storing). */
typedef struct expand_job {
    const ll_layer *layer;
    double tau0;
    size_t doublings;
    int slab;       /* the closed form of slab.c instead of doubling */
    double tau;
    ll_order **result;
    ll_watch *watch;
    const ll_split *split; /* the calling thread's (layer/split.h) */
    workspace_pool pool;
} expand_job;

int ll_block_is_diagonal(const double *x, size_t h)
{
    size_t r, c;
    for (c = 0; c < h; ++c)
        for (r = 0; r < h; ++r)
            if (r != c && x[c * h + r] != 0.0)
                return 0;
    return 1;
}

/*
 * One order by the closed form (slab.c) into w->out's R^t and T^tb; the
 * phase blocks are w->top's. An order whose only content is the diagonal
 * of T (no sideways scattering: beyond the kept moments of the phase
 * function only the unscattered and truncated-forward light) is the
 * exponential of its extinction, exactly.
 */
static ll_status slab_order(const expand_job *job, workspace *w, int *solved)
{
    const ll_layer *l = job->layer;
    size_t h = l->n / 2, c;
    const double *PT = w->top.blk[LL_BLOCK_TTB], *PR = w->top.blk[LL_BLOCK_RT];
    double *R = w->out.blk[LL_BLOCK_RT], *T = w->out.blk[LL_BLOCK_TTB], *scratch;
    size_t doubles;

    *solved = 0;
    if (w->top.zero[LL_BLOCK_RT] && ll_block_is_diagonal(PT, h)) {
        memset(R, 0, h * h * sizeof(double));
        memset(T, 0, h * h * sizeof(double));
        for (c = 0; c < h; ++c)
            T[c * h + c] = exp(-job->tau * (1.0 - PT[c * h + c]) / l->nodes[h + c]);
        *solved = 1;
        return LL_OK;
    }
    if (!w->slab) {
        doubles = ll_slab_scratch_doubles(h);
        w->slab = doubles ? ll_alloc_array(doubles, sizeof(double)) : NULL;
        if (!w->slab)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY,
                           "ll_layer_expand: out of memory for the slab of %zu nodes", l->n);
    }
    scratch = w->slab;
    *solved = ll_slab_solve(h, PT, PR, l->nodes + h, l->weights + h, job->tau, scratch, R, T);
    return LL_OK;
}

/*
 * An order of the medium that only transmits straight through (no sideways
 * scattering: beyond the kept moments of the phase function only the
 * unscattered and the truncated-forward light) stays one, built from its
 * diagonal without dense work: doubling squares the thin layer's diagonal
 * once per doubling, the slab takes the exponential of the extinction.
 * *done = 0 for any other order.
 */
static ll_status expand_straight_through(const expand_job *job, size_t k, int *done)
{
    const ll_layer *l = job->layer;
    size_t n = l->n, h = n / 2, c, d;
    double *down = ll_alloc_array(n, sizeof(double)), *up = down ? down + h : NULL;
    ll_status s = LL_OK;

    *done = 0;
    if (!down)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_expand: out of memory");
    if (!l->orders[k])
        memset(down, 0, n * sizeof(double)); /* a pure absorber */
    else if (!ll_order_diagonal(l->orders[k], down, up))
        goto done;
    /* The slab is the same from both sides: T^tb (the phase matrix's
     * down-from-down diagonal) on both, as the dense path does. */
    for (c = 0; c < h; ++c) {
        double x = l->nodes[h + c];
        if (job->slab) {
            down[c] = exp(-job->tau * (1.0 - down[c]) / x);
        } else {
            double t = 1.0 + (job->tau0 / x) * (down[c] - 1.0);
            for (d = 0; d < job->doublings; ++d)
                t *= t;
            down[c] = t;
        }
    }
    s = ll_order_from_diagonals(n, down, down, LL_DROP_THRESHOLD, &job->result[k]);
    ll_watch_advance(job->watch, job->doublings + 1);
    *done = 1;
done:
    ll_free(down);
    return s;
}

static ll_status expand_one_order(size_t k, void *ctx)
{
    expand_job *job = ctx;
    const ll_layer *l = job->layer;
    size_t n = l->n, h = n / 2, r, c, d;
    workspace *w;
    dense_order own_bottom; /* the doubling points the bottom at the top */
    double *R, *T;
    int solved = 0;
    ll_status s;

    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "ll_layer_expand: cancelled");
    if (!ll_split_owns(job->split, k)) {
        /* Another rank's order of a distributed build: not computed, NULL. */
        ll_watch_advance(job->watch, job->doublings + 1);
        return LL_OK;
    }
    s = expand_straight_through(job, k, &solved);
    if (s != LL_OK || solved)
        return s;
    s = pool_get(&job->pool, h, job->watch, &w);
    if (s != LL_OK)
        return s;
    own_bottom = w->bottom;
    /* The phase matrices of a medium are the same seen from either side, so
     * R^t and T^tb describe the slab. Initial thin slab (Grant and Hunt 1969,
     * first order in tau0): R = (tau0 / mu_o) P_R and T = I + (tau0 / mu_o)
     * (P_T - I). With phase matrices that conserve energy exactly this
     * conserves energy exactly too, and adding preserves it. */
    load_order(l->orders[k], n, &w->top);
    R = w->top.blk[LL_BLOCK_RT];
    T = w->top.blk[LL_BLOCK_TTB];
    if (job->slab) {
        /* An order the closed form does not take (not reciprocal) is
         * doubled instead. */
        s = slab_order(job, w, &solved);
        if (s != LL_OK)
            goto done;
        if (solved) {
            ll_watch_advance(job->watch, job->doublings);
            goto store;
        }
    }
    for (c = 0; c < h; ++c)
        for (r = 0; r < h; ++r) {
            double scale = job->tau0 / l->nodes[h + r];
            R[c * h + r] *= scale;
            T[c * h + r] = (r == c ? 1.0 : 0.0) + scale * (T[c * h + r] - (r == c ? 1.0 : 0.0));
        }

    if (w->top.zero[LL_BLOCK_RT] && ll_block_is_diagonal(T, h)) {
        /* Nothing scatters sideways in this order (only the unscattered and
         * exactly-forward part): each doubling squares the diagonal. */
        for (c = 0; c < h; ++c)
            for (d = 0; d < job->doublings; ++d)
                T[c * h + c] *= T[c * h + c];
        memset(w->out.blk[LL_BLOCK_RT], 0, h * h * sizeof(double));
        memcpy(w->out.blk[LL_BLOCK_TTB], T, h * h * sizeof(double));
        ll_watch_advance(job->watch, job->doublings);
    } else {
        for (d = 0; d < job->doublings; ++d) {
            if (ll_watch_poll(job->watch)) {
                s = ll_fail(LL_ERROR_CANCELLED, "ll_layer_expand: cancelled");
                goto done;
            }
            /* The slab added to itself: its top is the bottom's copy. */
            memcpy(w->top.blk[LL_BLOCK_RB], R, h * h * sizeof(double));
            memcpy(w->top.blk[LL_BLOCK_TBT], T, h * h * sizeof(double));
            w->top.zero[LL_BLOCK_RT] = w->top.zero[LL_BLOCK_RB] = all_zero(R, h * h);
            w->top.zero[LL_BLOCK_TTB] = w->top.zero[LL_BLOCK_TBT] = 0;
            memcpy(w->bottom.blk, w->top.blk, sizeof w->top.blk);
            memcpy(w->bottom.zero, w->top.zero, sizeof w->top.zero);
            s = add_dense(w, 1);
            if (s != LL_OK)
                goto done;
            memcpy(R, w->out.blk[LL_BLOCK_RT], h * h * sizeof(double));
            memcpy(T, w->out.blk[LL_BLOCK_TTB], h * h * sizeof(double));
            ll_watch_advance(job->watch, 1);
        }
        memcpy(w->out.blk[LL_BLOCK_RT], R, h * h * sizeof(double));
        memcpy(w->out.blk[LL_BLOCK_TTB], T, h * h * sizeof(double));
    }
store:
    memcpy(w->out.blk[LL_BLOCK_RB], w->out.blk[LL_BLOCK_RT], h * h * sizeof(double));
    memcpy(w->out.blk[LL_BLOCK_TBT], w->out.blk[LL_BLOCK_TTB], h * h * sizeof(double));
    w->out.zero[LL_BLOCK_RT] = w->out.zero[LL_BLOCK_RB] = all_zero(w->out.blk[LL_BLOCK_RT], h * h);
    w->out.zero[LL_BLOCK_TTB] = w->out.zero[LL_BLOCK_TBT] =
        all_zero(w->out.blk[LL_BLOCK_TTB], h * h);
    s = store_dense(&w->out, h, &job->result[k]);
    ll_watch_advance(job->watch, 1);
done:
    w->bottom = own_bottom;
    return s;
}

void ll_expand_schedule(double tau, double min_mu, double *tau0, size_t *doublings)
{
    /* Initial thickness: Grant and Hunt's bound tau0 <= 2 min|mu| keeps the
     * first-order slab non-negative; 2^-15 keeps its error small. Round so
     * that tau0 2^k hits tau exactly. */
    double t0 = fmin(2.0 * min_mu, ldexp(1.0, -15));
    size_t k = tau > t0 ? (size_t)ceil(log2(tau / t0)) : 0;
    *doublings = k;
    *tau0 = ldexp(tau, -(int)k);
}

/* Doubling on a begun watch: one code path for every entry point. */
static ll_status expand_watched(ll_layer *layer, double tau, ll_expand_method method,
                                ll_watch *watch)
{
    static const char fn[] = "ll_layer_expand";
    expand_job job;
    double min_mu = 1.0;
    size_t i, units;
    ll_status s;

    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_expand: layer is NULL");
    if (!(tau >= 0.0) || !ll_is_finite(tau))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_expand: optical thickness %g is not a finite number >= 0", tau);
    if (tau > 1e12)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_expand: optical thickness %g is beyond 1e12", tau);
    if (tau == 0.0) {
        ll_watch_stage(watch, "doubling", 0.0, 1.0, 0);
        s = ll_watch_finish(watch, LL_OK, fn);
        return s == LL_OK ? ll_layer_clear(layer) : s;
    }

    for (i = 0; i < layer->n; ++i)
        if (fabs(layer->nodes[i]) < min_mu)
            min_mu = fabs(layer->nodes[i]);
    job.layer = layer;
    job.split = ll_split_current();
    ll_expand_schedule(tau, min_mu, &job.tau0, &job.doublings);
    job.tau = tau;
    /* The cost model depends on n and the doublings alone: the same pick
     * for any data and any thread count. */
    job.slab = method == LL_EXPAND_SLAB ||
               (method == LL_EXPAND_CHEAPEST &&
                ll_slab_order_steps(layer->n / 2) < (double)job.doublings);
    job.watch = watch;
    if (!ll_size_mul(layer->m, job.doublings + 1, &units))
        units = SIZE_MAX;
    job.result = ll_calloc_array(layer->m, sizeof(ll_order *));
    if (!job.result)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_expand: out of memory");
    s = pool_create(&job.pool, fn);
    if (s != LL_OK) {
        ll_free(job.result);
        return s;
    }
    s = ll_watch_stage(watch, "doubling", 0.0, 1.0, units) ? ll_watch_check(watch, fn) : LL_OK;
    if (s == LL_OK)
        s = ll_parallel_for_watched(layer->m, expand_one_order, &job, watch);
    pool_destroy(&job.pool);
    s = ll_watch_finish(watch, s, fn);
    return ll_layer_commit_orders(layer, job.result, s);
}

ll_status ll_layer_expand(ll_layer *layer, double tau, const ll_monitor *monitor)
{
    ll_watch watch;
    ll_status s = ll_watch_begin(&watch, monitor, "ll_layer_expand");
    return s == LL_OK ? expand_watched(layer, tau, LL_EXPAND_CHEAPEST, &watch) : s;
}

ll_status ll_layer_expand_by(ll_layer *layer, double tau, ll_expand_method method)
{
    ll_watch watch;
    ll_status s = ll_watch_begin(&watch, NULL, "ll_layer_expand");
    return s == LL_OK ? expand_watched(layer, tau, method, &watch) : s;
}
