// Mitsuba .serialized meshes (zlib records). Every input is read as shape_index 0 and 1, so that the offset
// table of multi-mesh files is exercised.
#include "fuzz_targets.h"

#include "scene/mesh.h"

namespace penumbra::fuzz {

void fuzz_serialized(const uint8_t* data, size_t size) {
    const std::string path = write_input("input.serialized", data, size);
    for (int shape_index : {0, 1})
        reject_with_exceptions([&] { load_serialized(path, shape_index); });
}

} // namespace penumbra::fuzz
