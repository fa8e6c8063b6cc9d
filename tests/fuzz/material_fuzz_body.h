/*
 * One fuzz input for the material language: parse it as a material file,
 * then ask for the resolution and the estimate of its build, as
 * `llbuild --dry-run` does. Shared by the libFuzzer harness
 * (fuzz_material.c) and the corpus replay that CI runs
 * (tests/test_material_fuzz_replay.c).
 *
 * Whatever the text, parsing either fails with a message and no material or
 * succeeds; a parsed material has a resolution (or a refusal with a
 * message) and an estimate that is finite and non-negative (at the
 * resolution it has). Any violation
 * aborts, which the fuzzer reports as a finding; so do a crash, a
 * sanitizer report, more than 5 s for one input or more than 2 GB of
 * memory (tests/fuzz/run.sh).
 */
#ifndef LL_MATERIAL_FUZZ_BODY_H
#define LL_MATERIAL_FUZZ_BODY_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <layerlab.h>

static void ll_fuzz_material_require(int ok)
{
    if (!ok)
        abort();
}

/* Returns 1 if the input parsed. choose != 0: the resolution is chosen
 * by the tolerance, as llbuild --dry-run does (the resolution search probes
 * every word: about a second each on a loaded machine); 0: it is given
 * (12 nodes x 4 orders), so that only the parser, the stack and the cost
 * model run (thousands of inputs a second: the mutations, the fuzzer). */
static int ll_fuzz_material_run(const uint8_t *data, size_t size, int choose)
{
    ll_build_options opts = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate est = LL_BUILD_ESTIMATE_INIT;
    ll_material *m = (ll_material *)&opts; /* must be reset to NULL on failure */
    size_t n_nodes = 0, n_orders = 0, n_channels = 0;
    char *text = malloc(size + 1);
    ll_status s;

    ll_fuzz_material_require(text != NULL);
    memcpy(text, data, size);
    text[size] = '\0'; /* an embedded NUL ends the text, as for any C string */
    s = ll_material_parse(text, "fuzz.layers", &m);
    free(text);
    if (s != LL_OK) {
        ll_fuzz_material_require(m == NULL && ll_last_error_message()[0] != '\0');
        return 0;
    }
    ll_fuzz_material_require(m != NULL && ll_material_word_count(m) >= 1);
    opts.threads = 1;
    if (!choose) {
        opts.n_nodes = 12;
        opts.n_orders = 4;
    }
    s = ll_material_resolution(m, &opts, NULL, &n_nodes, &n_orders, &n_channels);
    if (s == LL_OK)
        ll_fuzz_material_require(n_nodes >= 2 && n_orders >= 1 &&
                                 (n_channels == 1 || n_channels == 3));
    else
        ll_fuzz_material_require(ll_last_error_message()[0] != '\0');
    if (s == LL_OK) {
        /* The estimate at that resolution (choosing it again would double
         * the time). */
        opts.n_nodes = n_nodes;
        opts.n_orders = n_orders;
    }
    s = ll_material_estimate(m, &opts, &est, NULL);
    if (s == LL_OK)
        ll_fuzz_material_require(isfinite(est.peak_bytes) && est.peak_bytes >= 0.0 &&
                                 isfinite(est.add_entries) && est.add_entries >= 0.0 &&
                                 isfinite(est.stored_values) && est.stored_values >= 0.0 &&
                                 (est.n_channels == 1 || est.n_channels == 3));
    else
        ll_fuzz_material_require(ll_last_error_message()[0] != '\0');
    ll_material_destroy(m);
    return 1;
}

/* The corpus replay's input: the resolution chosen. */
static int ll_fuzz_material_one(const uint8_t *data, size_t size)
{
    return ll_fuzz_material_run(data, size, 1);
}

#endif /* LL_MATERIAL_FUZZ_BODY_H */
