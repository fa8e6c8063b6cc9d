/* libFuzzer entry point for the material language (built by
 * tests/fuzz/run.sh with clang -fsanitize=fuzzer,address,undefined). */
#include "material_fuzz_body.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ll_fuzz_material_one(data, size);
    return 0;
}
