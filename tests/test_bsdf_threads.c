/*
 * One opened file shared by many threads: evaluation, pdf and sampling give
 * exactly (bit for bit) what one thread gets, and retain/release from many
 * threads at once keeps the object alive until the last release.
 */
#include "test_bsdf_util.h"

#include <pthread.h>

enum { N_QUERIES = 4000, N_THREADS = 6 };

typedef struct query {
    double wo[3], wi[3], u[2];
} query;

typedef struct answer {
    double f[3], pdf, sampled_wi[3], sampled_pdf, sampled_f[3];
    double layer_f[3], layer_pdf, mu_o, phi, sampled_layer_f[3], pdf_s;
} answer;

typedef struct job {
    ll_bsdf *b;
    const query *q;
    answer *a;
    int retain_release;
} job;

static void run_queries(ll_bsdf *b, const query *q, answer *a)
{
    size_t k;
    memset(a, 0, N_QUERIES * sizeof *a);
    for (k = 0; k < N_QUERIES; ++k) {
        const query *x = &q[k];
        answer *y = &a[k];
        ll_bsdf_eval_dir(b, x->wo, x->wi, LL_TRANSPORT_RADIANCE, NULL, y->f);
        ll_bsdf_pdf_dir(b, x->wo, x->wi, NULL, &y->pdf);
        ll_bsdf_sample_dir(b, x->wo, x->u, LL_TRANSPORT_IMPORTANCE, NULL, y->sampled_wi,
                           &y->sampled_pdf, y->sampled_f);
        ll_bsdf_eval(b, x->wo[2], x->wi[2], 1.0, NULL, y->layer_f);
        ll_bsdf_pdf(b, x->wo[2], x->wi[2], 1.0, NULL, &y->layer_pdf);
        ll_bsdf_sample(b, x->wi[2], x->u, NULL, &y->mu_o, &y->phi, &y->pdf_s, y->sampled_layer_f);
    }
}

static void *worker(void *arg)
{
    job *j = arg;
    int k;
    if (j->retain_release)
        for (k = 0; k < 10000; ++k)
            ll_bsdf_release(ll_bsdf_retain(j->b));
    run_queries(j->b, j->q, j->a);
    return NULL;
}

static void same_results_from_many_threads(void **state)
{
    ll_bsdf *b = NULL;
    query *q = malloc(N_QUERIES * sizeof *q);
    answer *reference = malloc(N_QUERIES * sizeof *reference);
    answer *results[N_THREADS];
    pthread_t threads[N_THREADS];
    job jobs[N_THREADS];
    uint64_t rng = 4242;
    size_t k;
    int t;
    (void)state;
    assert_non_null(q);
    assert_non_null(reference);
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &b), LL_OK);
    for (k = 0; k < N_QUERIES; ++k) {
        double zo = 2.0 * ll_test_uniform(&rng) - 1.0, po = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        double zi = 2.0 * ll_test_uniform(&rng) - 1.0, pi_ = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        q[k].wo[0] = sqrt(1.0 - zo * zo) * cos(po);
        q[k].wo[1] = sqrt(1.0 - zo * zo) * sin(po);
        q[k].wo[2] = zo;
        q[k].wi[0] = sqrt(1.0 - zi * zi) * cos(pi_);
        q[k].wi[1] = sqrt(1.0 - zi * zi) * sin(pi_);
        q[k].wi[2] = zi;
        q[k].u[0] = ll_test_uniform(&rng);
        q[k].u[1] = ll_test_uniform(&rng);
    }
    run_queries(b, q, reference);
    for (t = 0; t < N_THREADS; ++t) {
        results[t] = malloc(N_QUERIES * sizeof *results[t]);
        assert_non_null(results[t]);
        jobs[t].b = b;
        jobs[t].q = q;
        jobs[t].a = results[t];
        jobs[t].retain_release = t % 2;
        assert_int_equal(pthread_create(&threads[t], NULL, worker, &jobs[t]), 0);
    }
    for (t = 0; t < N_THREADS; ++t) {
        assert_int_equal(pthread_join(threads[t], NULL), 0);
        assert_memory_equal(results[t], reference, N_QUERIES * sizeof *reference);
        free(results[t]);
    }
    ll_bsdf_release(b);
    free(q);
    free(reference);
}

/* The last of many concurrent releases frees (LeakSanitizer would report
 * a lost object, AddressSanitizer a use after free). */
static void *releaser(void *arg)
{
    ll_bsdf *b = arg;
    double rgb[3], wo[3] = { 0, 0, 1 };
    ll_bsdf_eval_dir(b, wo, wo, LL_TRANSPORT_RADIANCE, NULL, rgb);
    ll_bsdf_release(b);
    return NULL;
}

static void concurrent_release(void **state)
{
    ll_bsdf *b = NULL;
    pthread_t threads[N_THREADS];
    int t;
    (void)state;
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &b), LL_OK);
    for (t = 1; t < N_THREADS; ++t)
        ll_bsdf_retain(b);
    for (t = 0; t < N_THREADS; ++t)
        assert_int_equal(pthread_create(&threads[t], NULL, releaser, b), 0);
    for (t = 0; t < N_THREADS; ++t)
        assert_int_equal(pthread_join(threads[t], NULL), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(same_results_from_many_threads),
        cmocka_unit_test(concurrent_release),
    };
    return cmocka_run_group_tests_name("bsdf_threads", tests, NULL, NULL);
}
