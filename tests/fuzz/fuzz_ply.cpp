// PLY meshes, ascii and binary (load_ply).
#include "fuzz_targets.h"

#include "scene/mesh.h"

namespace penumbra::fuzz {

void fuzz_ply(const uint8_t* data, size_t size) {
    const std::string path = write_input("input.ply", data, size);
    reject_with_exceptions([&] { load_ply(path); });
}

} // namespace penumbra::fuzz
