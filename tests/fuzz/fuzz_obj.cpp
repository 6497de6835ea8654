// Wavefront OBJ meshes (load_obj: tinyobjloader, then fan triangulation and validation).
#include "fuzz_targets.h"

#include "scene/mesh.h"

namespace penumbra::fuzz {

void fuzz_obj(const uint8_t* data, size_t size) {
    const std::string path = write_input("input.obj", data, size);
    reject_with_exceptions([&] { load_obj(path); });
}

} // namespace penumbra::fuzz
