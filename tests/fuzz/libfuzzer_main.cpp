// libFuzzer's entry point for one harness, chosen at compile time (-DPENUMBRA_FUZZ_TARGET=fuzz_<name>).
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    penumbra::fuzz::PENUMBRA_FUZZ_TARGET(data, size);
    return 0;
}
