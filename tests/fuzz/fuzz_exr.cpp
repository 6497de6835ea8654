// OpenEXR textures (read_image on a .exr file: OpenEXR's reader, RGB or Y channels).
#include "fuzz_targets.h"

#include "core/image.h"

namespace penumbra::fuzz {

void fuzz_exr(const uint8_t* data, size_t size) {
    const std::string path = write_input("input.exr", data, size);
    reject_with_exceptions([&] { read_image(path, false, FuzzMaxImagePixels); });
}

} // namespace penumbra::fuzz
