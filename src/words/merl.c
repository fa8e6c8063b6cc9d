/*
 * MERL measured BRDFs (see merl.h): reading and validating the file, the
 * half/difference-angle lookup of MERL's reference reader, and the layer
 * word ll_layer_set_matusik (the original layerlab's Layer::setMatusik,
 * with a direct DCT-I in place of FFTW).
 */
#include "words/merl.h"
#include "support/regular_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MERL_HEADER_BYTES 12
/* Sane maxima for a header that is not trusted: each resolution at most
 * 8x the database's (90, 90, 180) and the samples at most 8x its 1,458,000
 * (a 280 MB file, kept as 280 MB of doubles). A corrupt or sparse file
 * cannot then ask for gigabytes; a finer table would add nothing that the
 * layer's quadrature (a few hundred nodes) could resolve. */
#define MERL_MAX_RESOLUTION_THETA 720u
#define MERL_MAX_RESOLUTION_PHI 1440u
#define MERL_MAX_SAMPLES ((size_t)8 * 90 * 90 * 180)
/* The tables are read in chunks of this many float64 values (1 MiB), so a
 * load peaks at the converted table, not the table plus the raw bytes. */
#define MERL_CHUNK_VALUES 131072
#define MERL_TAIL_GOAL 1e-3

static uint32_t read_u32_le(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static double read_f64_le(const unsigned char *b)
{
    uint64_t bits = 0;
    double value;
    int k;
    for (k = 7; k >= 0; --k)
        bits = bits << 8 | b[k];
    memcpy(&value, &bits, sizeof value);
    return value;
}

/* Open path (a regular file, without blocking on a FIFO), read and
 * validate the header against the sane maxima and the file's real size. */
static ll_status open_and_check(const char *path, FILE **file, size_t res[3], size_t *count)
{
    static const char *const names[3] = { "theta_half", "theta_diff", "phi_diff" };
    static const uint32_t maxima[3] = { MERL_MAX_RESOLUTION_THETA, MERL_MAX_RESOLUTION_THETA,
                                        MERL_MAX_RESOLUTION_PHI };
    unsigned char header[MERL_HEADER_BYTES];
    struct stat st;
    size_t expected, k;
    ll_status s = LL_OK;
    FILE *f = NULL;
    int fd;

    *file = NULL;
    if (ll_open_regular(path, "the MERL file", &fd, &st) != LL_OK)
        return LL_ERROR_IO;
    f = fdopen(fd, "rb");
    if (!f) {
        int err = errno;
        close(fd);
        return ll_fail(LL_ERROR_IO, "the MERL file \"%s\": cannot open: %s", path,
                       strerror(err));
    }
    if (fread(header, 1, sizeof header, f) != sizeof header) {
        s = ll_fail(LL_ERROR_FORMAT,
                    "%s: shorter than the 12-byte MERL header (three int32 resolutions)", path);
        goto fail;
    }
    for (k = 0; k < 3; ++k) {
        uint32_t r = read_u32_le(header + 4 * k);
        if (r == 0 || r > maxima[k]) {
            s = ll_fail(LL_ERROR_FORMAT,
                        "%s: the %s resolution %u is not in [1, %u]; not a MERL .binary file?",
                        path, names[k], (unsigned)r, (unsigned)maxima[k]);
            goto fail;
        }
        res[k] = r;
    }
    /* Cannot overflow: 720 * 720 * 1440 * 24 < 2^35 and size_t holds it on
     * the 64-bit hosts the library supports; checked anyway. */
    if (!ll_size_mul(res[0], res[1], count) || !ll_size_mul(*count, res[2], count) ||
        *count > MERL_MAX_SAMPLES) {
        s = ll_fail(LL_ERROR_FORMAT,
                    "%s: %zu x %zu x %zu samples exceed the supported maximum of %zu (8x the "
                    "database's 90 x 90 x 180)",
                    path, res[0], res[1], res[2], (size_t)MERL_MAX_SAMPLES);
        goto fail;
    }
    if (!ll_size_mul(*count, 3 * 8, &expected) ||
        !ll_size_add(expected, MERL_HEADER_BYTES, &expected)) {
        s = ll_fail(LL_ERROR_FORMAT, "%s: the resolutions %zu x %zu x %zu overflow", path,
                    res[0], res[1], res[2]);
        goto fail;
    }
    if ((uintmax_t)st.st_size != (uintmax_t)expected) {
        s = ll_fail(LL_ERROR_FORMAT,
                    "%s: %jd bytes, but a MERL file of %zu x %zu x %zu samples has %zu "
                    "(12-byte header + 3 channels of float64)",
                    path, (intmax_t)st.st_size, res[0], res[1], res[2], expected);
        goto fail;
    }
    *file = f;
    return LL_OK;
fail:
    fclose(f);
    return s;
}

ll_status ll_merl_check(const char *path)
{
    FILE *f;
    size_t res[3], count;
    ll_status s;
    if (!path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_merl_check: path is NULL");
    s = open_and_check(path, &f, res, &count);
    if (s == LL_OK)
        fclose(f);
    return s;
}

void ll_merl_free(ll_merl *merl)
{
    if (!merl)
        return;
    ll_free(merl->values);
    ll_free(merl);
}

ll_status ll_merl_load(const char *path, ll_merl **out)
{
    static const double scale[3] = { LL_MERL_SCALE_R, LL_MERL_SCALE_G, LL_MERL_SCALE_B };
    FILE *f = NULL;
    size_t res[3], count, total, c, i, chunk = 0;
    unsigned char *raw = NULL;
    ll_merl *m = NULL;
    ll_status s;

    *out = NULL;
    s = open_and_check(path, &f, res, &count);
    if (s != LL_OK)
        return s;
    total = 3 * count; /* no overflow: checked with the byte count */
    m = ll_calloc(1, sizeof *m);
    raw = ll_alloc_array(MERL_CHUNK_VALUES, 8);
    if (!m || !raw || !(m->values = ll_alloc_array(total, sizeof(double)))) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading the MERL file %s", path);
        goto fail;
    }
    m->res_theta_h = res[0];
    m->res_theta_d = res[1];
    m->res_phi_d = res[2];
    /* The header has been read: the tables follow, channel after channel. */
    for (i = 0; i < total; i += chunk) {
        size_t j;
        chunk = total - i < MERL_CHUNK_VALUES ? total - i : MERL_CHUNK_VALUES;
        if (fread(raw, 8, chunk, f) != chunk) {
            s = ll_fail(LL_ERROR_IO, "error reading the tables of %s", path);
            goto fail;
        }
        for (j = 0; j < chunk; ++j) {
            double v = read_f64_le(raw + 8 * j);
            c = (i + j) / count;
            /* The database marks unmeasured configurations with negative
             * values; they carry no light. */
            m->values[i + j] = (v > 0.0 && ll_is_finite(v)) ? v * scale[c] : 0.0;
        }
    }
    ll_free(raw);
    fclose(f);
    *out = m;
    return LL_OK;
fail:
    ll_free(raw);
    ll_merl_free(m);
    fclose(f);
    return s;
}

/* ------------------------------------------------------------- lookup */

static size_t clamp_index(double x, size_t res)
{
    if (!(x > 0.0))
        return 0;
    if (x >= (double)(res - 1))
        return res - 1;
    return (size_t)x;
}

double ll_merl_eval(const ll_merl *m, const double wi[3], const double wo[3],
                    const double weights[3])
{
    double h[3], len, theta_h, phi_h, d[3], t[3], theta_d, phi_d, value = 0.0;
    size_t ih, id, ip, index, count;
    int c;

    if (!(wi[2] > 0.0 && wo[2] > 0.0))
        return 0.0;
    /* Rusinkiewicz's half/difference parametrisation (MERL's reader,
     * std_coords_to_half_diff_coords): the half vector's angles, and wi
     * expressed in the frame where the half vector is the pole. */
    h[0] = wi[0] + wo[0];
    h[1] = wi[1] + wo[1];
    h[2] = wi[2] + wo[2];
    len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (!(len > 0.0))
        return 0.0;
    theta_h = acos(fmin(1.0, fmax(-1.0, h[2] / len)));
    phi_h = atan2(h[1], h[0]);
    /* Rotate wi by -phi_h about z, then by -theta_h about y. */
    t[0] = cos(phi_h) * wi[0] + sin(phi_h) * wi[1];
    t[1] = -sin(phi_h) * wi[0] + cos(phi_h) * wi[1];
    t[2] = wi[2];
    d[0] = cos(theta_h) * t[0] - sin(theta_h) * t[2];
    d[1] = t[1];
    d[2] = sin(theta_h) * t[0] + cos(theta_h) * t[2];
    theta_d = acos(fmin(1.0, fmax(-1.0, d[2])));
    phi_d = atan2(d[1], d[0]);
    /* Reciprocity: phi_d and phi_d + pi are the same configuration. */
    if (phi_d < 0.0)
        phi_d += LL_PI;

    /* MERL's index maps: theta_half non-linearly (finer near the specular
     * direction), the others linearly. */
    ih = clamp_index(sqrt(theta_h / (0.5 * LL_PI)) * (double)m->res_theta_h, m->res_theta_h);
    id = clamp_index(theta_d / (0.5 * LL_PI) * (double)m->res_theta_d, m->res_theta_d);
    ip = clamp_index(phi_d / LL_PI * (double)m->res_phi_d, m->res_phi_d);
    index = ip + m->res_phi_d * (id + m->res_theta_d * ih);
    count = m->res_theta_h * m->res_theta_d * m->res_phi_d;
    for (c = 0; c < 3; ++c)
        if (weights[c] != 0.0)
            value += weights[c] * m->values[(size_t)c * count + index];
    return value;
}

/* ------------------------------------------------------------ the layer */

typedef struct merl_job {
    const ll_layer *layer;
    const ll_merl *merl;
    const double *weights;
    size_t samples;            /* azimuth samples on [0, pi], N          */
    const double *cos_table;   /* cos(pi t / (N - 1)), t < 2 (N - 1)     */
    ll_order_builder **builders;
    ll_watch *watch; /* one unit per column, polled per outgoing node */
} merl_job;

/* The series of one node pair (mu_i > 0 arriving, mu_o > 0 the magnitude
 * of the outgoing cosine): N samples of f over the azimuth into f[], their
 * DCT-I into a[0 .. m), the tail cut where it becomes negligible. The one
 * code path of the layer (below) and of the resolution probes
 * (merl_probe.c). */
void ll_merl_pair_series(const ll_merl *merl, const double weights[3], double mu_i,
                         double mu_o, size_t m, size_t N, const double *cos_table, double *f,
                         double *a)
{
    size_t period = 2 * (N - 1), j, k;
    double sin_i = sqrt(fmax(0.0, 1.0 - mu_i * mu_i)), sin_o = sqrt(fmax(0.0, 1.0 - mu_o * mu_o));
    double wi[3], ref, tail;
    wi[0] = sin_i;
    wi[1] = 0.0;
    wi[2] = mu_i;
    for (j = 0; j < N; ++j) {
        /* The outgoing direction travels up; phi = 0 is the mirror
         * direction of wi, as in the layer convention. */
        double phi = LL_PI * (double)j / (double)(N - 1), wo[3];
        wo[0] = -sin_o * cos(phi);
        wo[1] = -sin_o * sin(phi);
        wo[2] = mu_o;
        f[j] = ll_merl_eval(merl, wi, wo, weights);
    }
    /* DCT-I: a_k = (1/(N-1)) [f_0 + (-1)^k f_{N-1} + 2 sum_j f_j cos(pi j k/(N-1))],
     * halved for k = 0: the coefficients of f(phi) = sum_k a_k cos(k phi)
     * by the trapezoid rule on [0, pi]. */
    for (k = 0; k < m; ++k) {
        double sum = f[0] + ((k & 1) ? -f[N - 1] : f[N - 1]);
        size_t t = 0;
        for (j = 1; j + 1 < N; ++j) {
            t += k;
            if (t >= period)
                t %= period;
            sum += 2.0 * f[j] * cos_table[t];
        }
        a[k] = sum / (double)(N - 1) * (k == 0 ? 0.5 : 1.0);
    }
    /* Truncate the series where its tail becomes negligible. */
    ref = fabs(a[0]);
    tail = 0.0;
    for (k = m; k-- > 1;) {
        tail += fabs(a[k]);
        if (tail > ref * MERL_TAIL_GOAL)
            break;
        a[k] = 0.0;
    }
    if (ref == 0.0)
        for (k = 0; k < m; ++k)
            a[k] = 0.0;
}

ll_status ll_merl_cos_table(size_t orders, size_t *samples, double **table)
{
    size_t N, period, t;
    *table = NULL;
    if (!ll_size_mul(orders, 4, &N) || N > ((size_t)1 << 24))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_set_matusik: %zu internal orders are too many", orders);
    if (N < 4)
        N = 4;
    period = 2 * (N - 1);
    *table = ll_alloc_array(period, sizeof(double));
    if (!*table)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_matusik: out of memory");
    for (t = 0; t < period; ++t)
        (*table)[t] = cos(LL_PI * (double)t / (double)(N - 1));
    *samples = N;
    return LL_OK;
}

/* One incident column (internal index h + col_index, mu_i > 0): for every
 * outgoing node mu_o < 0, sample f over the azimuth and take its cosine
 * series; write the weighted column of every order. */
static ll_status merl_column(size_t col_index, void *ctx)
{
    const merl_job *job = ctx;
    const ll_layer *l = job->layer;
    size_t n = l->n, h = n / 2, m = l->m, N = job->samples;
    size_t col = h + col_index, o, k;
    double mu_i = l->nodes[col];
    double *f = NULL, *coeff = NULL, *column = NULL;
    ll_status s = LL_OK;

    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_matusik: cancelled");
    f = ll_alloc_array(N, sizeof(double));
    coeff = ll_alloc_array(h, m * sizeof(double));
    column = ll_calloc_array(n, sizeof(double));
    if (!f || !coeff || !column) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_matusik: out of memory");
        goto done;
    }
    for (o = 0; o < h; ++o) {
        if (ll_watch_poll(job->watch)) {
            s = ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_matusik: cancelled");
            goto done;
        }
        ll_merl_pair_series(job->merl, job->weights, mu_i, fabs(l->nodes[o]), m, N,
                            job->cos_table, f, coeff + o * m);
    }
    for (k = 0; k < m && s == LL_OK; ++k) {
        double factor = ll_layer_surface_factor(l, col, k);
        /* R^t: rows < h (travelling up) of a column >= h (arriving from above). */
        for (o = 0; o < h; ++o)
            column[o] = coeff[o * m + k] * factor;
        s = ll_order_builder_set_column(job->builders[k], col, column, 0.0);
    }
    ll_watch_advance(job->watch, 1);
done:
    ll_free(f);
    ll_free(coeff);
    ll_free(column);
    return s;
}

ll_status ll_merl_set_layer(ll_layer *layer, const ll_merl *merl, const double weights[3],
                               size_t n_orders_internal, const ll_monitor *monitor)
{
    ll_watch watch;
    ll_status s = ll_watch_begin(&watch, monitor, "ll_layer_set_matusik");
    if (s != LL_OK)
        return s;
    ll_watch_stage(&watch, "measured", 0.0, 0.0, 0);
    return ll_merl_set_layer_watched(layer, merl, weights, n_orders_internal, &watch);
}

ll_status ll_merl_set_layer_watched(ll_layer *layer, const ll_merl *merl,
                                    const double weights[3], size_t n_orders_internal,
                                    ll_watch *watch)
{
    static const char fn[] = "ll_layer_set_matusik";
    merl_job job;
    size_t m, orders, N = 0;
    double *cos_table = NULL;
    ll_status s;

    if (!layer || !merl || !weights)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_merl_set_layer: a pointer is NULL");
    m = layer->m;
    orders = n_orders_internal > m ? n_orders_internal : m;
    s = ll_merl_cos_table(orders, &N, &cos_table);
    if (s != LL_OK)
        return s;
    job.layer = layer;
    job.merl = merl;
    job.weights = weights;
    job.samples = N;
    job.cos_table = cos_table;
    job.builders = NULL;
    job.watch = watch;
    /* (The file was read in the first tenth of the progress.) Incident
     * columns from above only: h + 0 .. h + h - 1. */
    s = ll_watch_stage(watch, "measured", 0.1, 0.9, layer->n / 2) ? ll_watch_check(watch, fn)
                                                                   : LL_OK;
    if (s == LL_OK)
        s = ll_layer_build_by_columns(layer, layer->n / 2, layer->n / 2, merl_column, NULL,
                                         &job, &job.builders, NULL, 0, watch, fn);
    ll_free(cos_table);
    return s;
}

ll_status ll_layer_set_matusik(ll_layer *layer, const char *path, int channel,
                               size_t n_orders_internal, const ll_monitor *monitor)
{
    double weights[3] = { 0.0, 0.0, 0.0 };
    ll_merl *merl;
    ll_watch watch;
    ll_status s;
    if (!layer || !path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_set_matusik: layer or path is NULL");
    if (channel < 0 || channel > 2)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_set_matusik: channel %d is not 0, 1 or 2 (R, G, B)", channel);
    s = ll_watch_begin(&watch, monitor, "ll_layer_set_matusik");
    if (s != LL_OK)
        return s;
    if (ll_watch_stage(&watch, "measured", 0.0, 0.1, 1))
        return ll_watch_check(&watch, "ll_layer_set_matusik");
    s = ll_merl_load(path, &merl);
    if (s != LL_OK)
        return s;
    weights[channel] = 1.0;
    s = ll_merl_set_layer_watched(layer, merl, weights, n_orders_internal, &watch);
    ll_merl_free(merl);
    return s;
}
