/*
 * Helpers every test program may use: layers on Gauss-Lobatto nodes,
 * scratch directories (with a cmocka group fixture), files, random numbers.
 */
#ifndef LL_TEST_UTIL_H
#define LL_TEST_UTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <layerlab.h>
#include "layer/layer.h"

/* f(mu_i, mu_o, phi_d) of a layer as a value (0 when ll_layer_eval fails). */
static inline double ll_test_layer_eval(const ll_layer *l, double mu_i, double mu_o,
                                        double phi_d)
{
    double f = 0.0;
    return ll_layer_eval(l, mu_i, mu_o, phi_d, &f) == LL_OK ? f : 0.0;
}

/* ll_layer_set_microfacet of an interface given by its numbers, of a
 * distribution (LL_MICROFACET_BECKMANN, LL_MICROFACET_GGX). */
static inline ll_status ll_test_set_microfacet_dist(ll_layer *l, double eta_re, double eta_im,
                                                    double alpha, int distribution,
                                                    int compensate, size_t n_orders_internal,
                                                    const ll_monitor *monitor)
{
    ll_microfacet mf = LL_MICROFACET_INIT;
    mf.eta_re = eta_re;
    mf.eta_im = eta_im;
    mf.alpha = alpha;
    mf.distribution = distribution;
    mf.compensate = compensate;
    mf.n_orders_internal = n_orders_internal;
    return ll_layer_set_microfacet(l, &mf, monitor);
}

/* The same of a Beckmann interface. */
static inline ll_status ll_test_set_microfacet(ll_layer *l, double eta_re, double eta_im,
                                               double alpha, int compensate,
                                               size_t n_orders_internal,
                                               const ll_monitor *monitor)
{
    return ll_test_set_microfacet_dist(l, eta_re, eta_im, alpha, LL_MICROFACET_BECKMANN,
                                       compensate, n_orders_internal, monitor);
}

/* ll_resolution_search_microfacet of a compensated Beckmann interface (the
 * layer a build makes by default). */
static inline ll_status ll_test_search_microfacet(double alpha, double eta_re, double eta_im,
                                                  double tolerance, double mu_min,
                                                  size_t *n_nodes, size_t *n_orders,
                                                  double *error)
{
    ll_microfacet mf = LL_MICROFACET_INIT;
    mf.eta_re = eta_re;
    mf.eta_im = eta_im;
    mf.alpha = alpha;
    return ll_resolution_search_microfacet(&mf, tolerance, mu_min, NULL, n_nodes, n_orders,
                                           error);
}

/* A clear layer on n Gauss-Lobatto nodes (as files are made: the nodes
 * include +-1, so the file covers every direction) with m orders. */
static inline ll_layer *ll_test_layer(size_t n, size_t m)
{
    double *x = malloc(n * sizeof *x), *w = malloc(n * sizeof *w);
    ll_layer *l = NULL;
    assert_non_null(x);
    assert_non_null(w);
    assert_int_equal(ll_quad_gauss_lobatto(n, x, w, NULL), LL_OK);
    assert_int_equal(ll_layer_create(x, w, n, m, &l), LL_OK);
    free(x);
    free(w);
    return l;
}

/* A clear layer on the nodes of `like`, with as many orders: for a layer
 * made directly to compare with one a build made. */
static inline ll_layer *ll_test_layer_like(const ll_layer *like)
{
    size_t n = ll_layer_node_count(like), m = ll_layer_order_count(like);
    double *x = malloc(n * sizeof *x), *w = malloc(n * sizeof *w);
    ll_layer *l = NULL;
    assert_non_null(x);
    assert_non_null(w);
    assert_int_equal(ll_layer_get_nodes(like, x, w), LL_OK);
    assert_int_equal(ll_layer_create(x, w, n, m, &l), LL_OK);
    free(x);
    free(w);
    return l;
}

/* A scratch directory, removed (with everything in it) by ll_test_rmdir. */
static inline void ll_test_mkdtemp(char *dir, size_t size)
{
    const char *base = getenv("TMPDIR");
    snprintf(dir, size, "%s/ll_test.XXXXXX", base && *base ? base : "/tmp");
    assert_non_null(mkdtemp(dir));
}

static inline size_t ll_test_count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    size_t count = 0;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0)
            ++count;
    closedir(d);
    return count;
}

static inline void ll_test_rmdir(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    struct stat st;
    char path[1024];
    if (!d)
        return;
    while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
            continue;
        if ((size_t)snprintf(path, sizeof path, "%s/%s", dir, e->d_name) >= sizeof path)
            continue;
        if (lstat(path, &st) == 0 && S_ISDIR(st.st_mode))
            ll_test_rmdir(path);
        else
            unlink(path);
    }
    closedir(d);
    rmdir(dir);
}

/* One scratch directory per test program, as a cmocka group fixture:
 * cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown). */
static inline char *ll_test_dir(void)
{
    static char dir[512];
    return dir;
}

static inline int ll_test_dir_setup(void **state)
{
    (void)state;
    ll_test_mkdtemp(ll_test_dir(), 512);
    return 0;
}

static inline int ll_test_dir_teardown(void **state)
{
    (void)state;
    ll_test_rmdir(ll_test_dir());
    return 0;
}

/* The bytes of a file (malloc'ed; *size set). */
static inline unsigned char *ll_test_read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *data;
    long len;
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    len = ftell(f);
    assert_true(len >= 0);
    assert_int_equal(fseek(f, 0, SEEK_SET), 0);
    data = malloc((size_t)len + 1);
    assert_non_null(data);
    assert_int_equal(fread(data, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *size = (size_t)len;
    return data;
}

static inline void ll_test_write_file(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* Deterministic uniform numbers in [0, 1) (xorshift64*). */
static inline double ll_test_uniform(uint64_t *state)
{
    uint64_t x = *state;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    *state = x;
    return (double)((x * 0x2545F4914F6CDD1DULL) >> 11) * (1.0 / 9007199254740992.0);
}

static inline int ll_test_close(double a, double b, double rel, double abs_tol)
{
    return fabs(a - b) <= abs_tol + rel * fabs(b);
}

#endif /* LL_TEST_UTIL_H */
