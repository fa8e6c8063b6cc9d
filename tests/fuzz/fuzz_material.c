/* libFuzzer entry point for the material language (built by
 * tests/fuzz/run.sh with clang -fsanitize=fuzzer,address,undefined). */
#include "material_fuzz_body.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* At a given resolution: the resolution search takes seconds per word
     * under the sanitizers, beyond the fuzzer's 5 s per input; the corpus
     * replay (tests/test_material_fuzz_replay.c) and the convergence test
     * run it. */
    ll_fuzz_material_run(data, size, 0);
    return 0;
}
