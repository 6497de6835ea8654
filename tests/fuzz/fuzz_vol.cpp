// Mitsuba .vol grids (read_vol_file).
#include "fuzz_targets.h"

#include "scene/volumes/volume_grid.h"

namespace penumbra::fuzz {

void fuzz_vol(const uint8_t* data, size_t size) {
    const std::string path = write_input("input.vol", data, size);
    reject_with_exceptions([&] { read_vol_file(path); });
}

} // namespace penumbra::fuzz
