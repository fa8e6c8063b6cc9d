/*
 * CI's share of the fuzzing: every input of the seed corpus tests/fuzz/corpus
 * (and the golden file) through the libFuzzer harness's body, and a
 * deterministic pass of byte mutations over the small seeds. `make fuzz`
 * (tests/fuzz/run.sh) does the open-ended search.
 */
#include "test_bsdf_util.h"
#include "fuzz/bsdf_fuzz_body.h"

#define LL_TEST_CORPUS LL_SOURCE_DIR "/tests/fuzz/corpus"

static void replay_corpus(void **state)
{
    DIR *d = opendir(LL_TEST_CORPUS);
    struct dirent *e;
    size_t inputs = 0, opened = 0;
    (void)state;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL) {
        char path[1024];
        unsigned char *data;
        size_t size;
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", LL_TEST_CORPUS, e->d_name);
        data = ll_test_read_file(path, &size);
        opened += (size_t)ll_fuzz_bsdf_one(data, size);
        ++inputs;
        free(data);
    }
    closedir(d);
    /* The seeds are valid files (one per feature: diffuse, RGB, textured,
     * lobed); findings added later need not be. */
    assert_true(inputs >= 4);
    assert_true(opened >= 4);
    {
        size_t size;
        unsigned char *data = ll_test_read_file(LL_TEST_GOLDEN, &size);
        assert_int_equal(ll_fuzz_bsdf_one(data, size), 1);
        free(data);
    }
}

/* Each byte of each small seed replaced by a few values (the header's
 * counts, the table, the CDF and the coefficients all get their turn). */
static void mutate_seeds(void **state)
{
    static const unsigned char values[] = { 0x00, 0xFF, 0x80 };
    DIR *d = opendir(LL_TEST_CORPUS);
    struct dirent *e;
    size_t runs = 0;
    (void)state;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL) {
        char path[1024];
        unsigned char *data;
        size_t size, at, v;
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", LL_TEST_CORPUS, e->d_name);
        data = ll_test_read_file(path, &size);
        if (size <= 4096)
            for (at = 0; at < size; ++at) {
                unsigned char keep = data[at];
                for (v = 0; v < sizeof values; ++v) {
                    if (values[v] == keep)
                        continue;
                    data[at] = values[v];
                    ll_fuzz_bsdf_one(data, size);
                    ++runs;
                }
                data[at] = keep;
            }
        free(data);
    }
    closedir(d);
    assert_true(runs > 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(replay_corpus),
        cmocka_unit_test(mutate_seeds),
    };
    return cmocka_run_group_tests_name("bsdf_fuzz_replay", tests, NULL, NULL);
}
