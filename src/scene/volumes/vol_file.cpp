// Reader of Mitsuba's binary .vol grids (the format of Mitsuba 0.6 and 3, little endian):
//   bytes 0-2 'V' 'O' 'L', byte 3 version (3), int32 encoding (1 = float32), int32 xres, yres, zres,
//   int32 channels, 6 float32 bounding box (xmin ymin zmin xmax ymax zmax), then xres*yres*zres*channels
//   float32 values, value (x, y, z, c) at index ((z*yres + y)*xres + x)*channels + c.
#include "scene/volumes/volume_grid.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace penumbra {

static_assert(std::endian::native == std::endian::little, "the .vol reader assumes a little-endian host");

namespace {

constexpr size_t HeaderBytes = 48;

template <typename V> V load(const char* bytes) {
    V v;
    std::memcpy(&v, bytes, sizeof(V));
    return v;
}

} // namespace

VolumeGridData read_vol_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw VolumeFileError("cannot open the file");
    const auto file_size = uint64_t(in.tellg());
    in.seekg(0);
    char header[HeaderBytes];
    in.read(header, HeaderBytes);
    if (file_size < 3 || std::memcmp(header, "VOL", 3) != 0)
        throw VolumeFileError("not a Mitsuba .vol file (the first bytes are not 'VOL')");
    if (file_size < HeaderBytes)
        throw VolumeFileError("truncated header (" + std::to_string(file_size) + " of " +
                              std::to_string(HeaderBytes) + " bytes)");
    if (header[3] != 3)
        throw VolumeFileError("unsupported .vol version " + std::to_string(int(header[3])) + " (expected 3)");
    const int32_t encoding = load<int32_t>(header + 4);
    if (encoding != 1)
        throw VolumeFileError("unsupported encoding " + std::to_string(encoding) +
                              " (only 1, float32, is supported)");
    VolumeGridData grid;
    grid.res = Vec3i(load<int32_t>(header + 8), load<int32_t>(header + 12), load<int32_t>(header + 16));
    if (grid.res.x <= 0 || grid.res.y <= 0 || grid.res.z <= 0)
        throw VolumeFileError("invalid resolution " + std::to_string(grid.res.x) + " x " +
                              std::to_string(grid.res.y) + " x " + std::to_string(grid.res.z));
    const int32_t channels = load<int32_t>(header + 20);
    if (channels == 6)
        throw VolumeFileError("6-channel grids are not supported (penumbra's volumes hold 1 or 3 channels)");
    if (channels != 1 && channels != 3)
        throw VolumeFileError("invalid channel count " + std::to_string(channels) + " (expected 1 or 3)");
    grid.channels = channels;

    const uint64_t data_bytes = file_size - HeaderBytes, held = data_bytes / sizeof(float);
    const std::string shape = std::to_string(grid.res.x) + " x " + std::to_string(grid.res.y) + " x " +
                              std::to_string(grid.res.z) + " x " + std::to_string(channels);
    // The declared count in long double: up to 2^93, beyond uint64_t.
    const long double declared = static_cast<long double>(grid.res.x) * grid.res.y * grid.res.z * channels;
    if (declared > static_cast<long double>(held)) {
        char count_text[64];
        std::snprintf(count_text, sizeof(count_text), "%.0Lf", declared);
        throw VolumeFileError("truncated: the header declares " + shape + " = " + count_text +
                              " values, the file holds " + std::to_string(held));
    }
    const uint64_t count = uint64_t(declared);
    if (data_bytes > count * sizeof(float))
        throw VolumeFileError("size mismatch: " + std::to_string(data_bytes - count * sizeof(float)) +
                              " bytes after the " + shape + " values the header declares");
    grid.values.resize(count);
    in.read(reinterpret_cast<char*>(grid.values.data()), std::streamsize(count * sizeof(float)));
    if (!in) throw VolumeFileError("read error in the voxel data");
    for (uint64_t i = 0; i < count; ++i) {
        if (std::isfinite(grid.values[i])) continue;
        const uint64_t voxel = i / uint64_t(channels);
        const uint64_t x = voxel % uint64_t(grid.res.x),
                       y = voxel / uint64_t(grid.res.x) % uint64_t(grid.res.y),
                       z = voxel / (uint64_t(grid.res.x) * uint64_t(grid.res.y));
        throw VolumeFileError("non-finite value " + std::to_string(grid.values[i]) + " at voxel (" +
                              std::to_string(x) + ", " + std::to_string(y) + ", " + std::to_string(z) +
                              ") channel " + std::to_string(i % uint64_t(channels)));
    }

    Vec3f lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = load<float>(header + 24 + 4 * a);
        hi[a] = load<float>(header + 36 + 4 * a);
    }
    const Vec3f extent = hi - lo;
    grid.has_placement = is_finite(lo) && is_finite(hi) && extent.x > 0.f && extent.y > 0.f && extent.z > 0.f;
    if (grid.has_placement) grid.unit_to_file = Transform::translate(lo) * Transform::scale(extent);
    return grid;
}

} // namespace penumbra
