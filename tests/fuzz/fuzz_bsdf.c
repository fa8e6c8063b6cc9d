/* libFuzzer entry point for the .bsdf reader (built by tests/fuzz/run.sh
 * with clang -fsanitize=fuzzer,address,undefined). */
#include "bsdf_fuzz_body.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ll_fuzz_bsdf_one(data, size);
    return 0;
}
