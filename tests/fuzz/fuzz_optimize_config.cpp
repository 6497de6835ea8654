// The JSON configuration of `penumbra optimize` (load_optimize_config). The file sits in the fixture
// directory, so that relative mesh paths ("init": "mesh.ply") are loaded.
#include "fuzz_targets.h"

#include "optim/optimize.h"

namespace penumbra::fuzz {

void fuzz_optimize_config(const uint8_t* data, size_t size) {
    fixture_dir();
    const std::string path = write_input("config.json", data, size);
    reject_with_exceptions([&] { load_optimize_config(path); });
}

} // namespace penumbra::fuzz
