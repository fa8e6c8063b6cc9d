/*
 * CI's share of fuzzing the material language: every input of the seed
 * corpus tests/fuzz/material_corpus (the examples and hand-made edge cases,
 * and findings once fixed) through the libFuzzer harness's body, then a
 * deterministic pass of character substitutions over each seed. `make fuzz`
 * (tests/fuzz/run.sh) does the open-ended search.
 *
 * The fuzzer limits one input to 5 s; here an input that takes more than
 * LL_TEST_INPUT_SECONDS (generous for a loaded CI machine) is killed by
 * SIGALRM, so a regression fails the suite instead of hanging it.
 */
#include "test_util.h"
#include "fuzz/material_fuzz_body.h"

#include <dirent.h>
#include <signal.h>
#include <sys/time.h>
#include <unistd.h>

#define LL_TEST_CORPUS LL_SOURCE_DIR "/tests/fuzz/material_corpus"
#define LL_TEST_INPUT_SECONDS 30
/* The corpus replay chooses each material's resolution (a second or more
 * of CPU per word; media build their phase matrices repeatedly), so its
 * limit is on CPU time (SIGPROF, all threads), which a busy machine does
 * not stretch (on a shared machine an input's wall time can be ten times
 * its CPU time). A hang without CPU still meets the wall alarm.
 * Since the interface search probes the energy compensation (O(n^2)
 * order-0 series per node count, docs/method.md "Resolution"),
 * edge-alpha-0.01 (eta 1.33, alpha 0.01: 3682 x 2847) takes 30 s of CPU on
 * one thread, 4.2 s with compensate=0, so the limit is 90 s. */
#define LL_TEST_CHOOSE_CPU_SECONDS 90
#define LL_TEST_CHOOSE_WALL_SECONDS 300

static void cpu_limit(long seconds)
{
    struct itimerval t;
    memset(&t, 0, sizeof t);
    t.it_value.tv_sec = seconds;
    assert_int_equal(setitimer(ITIMER_PROF, &t, NULL), 0);
}

static unsigned char *read_input(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *data;
    long len;
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    len = ftell(f);
    assert_true(len >= 0);
    rewind(f);
    data = malloc((size_t)len + 1);
    assert_non_null(data);
    assert_int_equal(fread(data, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *size = (size_t)len;
    return data;
}

/* Run fn on every corpus input; returns how many there were. */
static size_t for_each_input(void (*fn)(const char *name, unsigned char *data, size_t size,
                                        size_t *count),
                             size_t *count)
{
    DIR *d = opendir(LL_TEST_CORPUS);
    struct dirent *e;
    size_t inputs = 0;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL) {
        char path[1024];
        unsigned char *data;
        size_t size;
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", LL_TEST_CORPUS, e->d_name);
        data = read_input(path, &size);
        fn(e->d_name, data, size, count);
        free(data);
        ++inputs;
    }
    closedir(d);
    return inputs;
}

static void replay_one(const char *name, unsigned char *data, size_t size, size_t *parsed)
{
    alarm(LL_TEST_CHOOSE_WALL_SECONDS);
    cpu_limit(LL_TEST_CHOOSE_CPU_SECONDS);
    *parsed += (size_t)ll_fuzz_material_one(data, size);
    cpu_limit(0);
    alarm(0);
    /* The examples are valid materials. */
    if (strncmp(name, "example-", 8) == 0 && ll_fuzz_material_run(data, size, 0) != 1)
        fail_msg("%s does not parse: %s", name, ll_last_error_message());
}

static void replay_corpus(void **state)
{
    size_t parsed = 0, inputs;
    (void)state;
    inputs = for_each_input(replay_one, &parsed);
    assert_true(inputs >= 50);
    assert_true(parsed >= 20);
}

/* Each character of each seed replaced by a few that matter to the
 * grammar: separators, a digit, a sign, an exponent, a quote. */
static void mutate_one(const char *name, unsigned char *data, size_t size, size_t *runs)
{
    static const char values[] = { '=', ',', ' ', '\n', '9', '-', 'e', '"', '#' };
    size_t at, v;
    (void)name;
    if (size > 600)
        return;
    for (at = 0; at < size; ++at) {
        unsigned char keep = data[at];
        for (v = 0; v < sizeof values; ++v) {
            if ((unsigned char)values[v] == keep)
                continue;
            data[at] = (unsigned char)values[v];
            alarm(LL_TEST_INPUT_SECONDS);
            /* At a given resolution: the substitutions exercise the parser
             * and the cost model, and the corpus replay above the
             * resolution search (a second per word; thousands of
             * substitutions here). */
            ll_fuzz_material_run(data, size, 0);
            alarm(0);
            ++*runs;
        }
        data[at] = keep;
    }
}

static void mutate_seeds(void **state)
{
    size_t runs = 0;
    (void)state;
    for_each_input(mutate_one, &runs);
    assert_true(runs > 5000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(replay_corpus),
        cmocka_unit_test(mutate_seeds),
    };
    /* One thread: the estimate does not depend on it, and CI shares cores. */
    ll_set_thread_count(1);
    return cmocka_run_group_tests_name("material_fuzz_replay", tests, NULL, NULL);
}
