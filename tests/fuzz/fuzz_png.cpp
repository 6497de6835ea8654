// PNG textures (read_image on a .png file). stb_image recognizes the format by content, so the fuzzer also
// reaches its JPEG, BMP, TGA, HDR, ... decoders; the sRGB decoding path is taken.
#include "fuzz_targets.h"

#include "core/image.h"

namespace penumbra::fuzz {

void fuzz_png(const uint8_t* data, size_t size) {
    const std::string path = write_input("input.png", data, size);
    reject_with_exceptions([&] { read_image(path, true, FuzzMaxImagePixels); });
}

} // namespace penumbra::fuzz
