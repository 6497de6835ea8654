// Multi-channel OpenEXR output: the film's pixel formats and AOV layers (channel <layer>.<letter>).
#pragma once
#include "core/image.h"

#include <string>
#include <vector>

namespace penumbra {

// Mitsuba's hdrfilm `component_format`: how the channels are stored in the file.
enum class ComponentFormat { Float16, Float32, UInt32 };

// One named channel: width * height values, row-major, top row first.
struct ExrChannel {
    std::string name;
    std::vector<float> values;
};

// All channels must hold width * height values. UInt32 stores round(clamp(v, 0, 1) (2^32 - 1))
// (Mitsuba's Bitmap marks integer components as normalized). Written atomically (core/atomic_file.h); throws
// Error on failure.
void write_exr_channels(const std::string& path, int width, int height,
                        const std::vector<ExrChannel>& channels, ComponentFormat format);

} // namespace penumbra
