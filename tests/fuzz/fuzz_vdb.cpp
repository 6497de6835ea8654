// OpenVDB .vdb grids (read_vdb_file: the default float grid, densified).
#include "fuzz_targets.h"

#include "scene/volumes/volume_grid.h"

namespace penumbra::fuzz {

void fuzz_vdb(const uint8_t* data, size_t size) {
    const std::string path = write_input("input.vdb", data, size);
    reject_with_exceptions([&] { read_vdb_file(path, "", FuzzMaxVoxels); });
}

} // namespace penumbra::fuzz
