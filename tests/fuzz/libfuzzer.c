/* fovea: one fuzz target as a libFuzzer binary (make fuzz builds this file once per target with
 * -DFV_FUZZ_FN=fv_fuzz_NAME, clang -fsanitize=fuzzer,address,undefined). */
#include "targets.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    (void)FV_FUZZ_FN(data, size);
    return 0; /* libFuzzer: 0 keeps the input eligible for the corpus */
}
