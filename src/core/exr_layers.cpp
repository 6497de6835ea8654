#include "core/exr_layers.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace penumbra {

namespace {

// Per-channel storage in the file's component type (the library converts nothing on write).
struct Converted {
    std::vector<half> f16;
    std::vector<uint32_t> u32;
};

} // namespace

void write_exr_channels(const std::string& path, int width, int height,
                        const std::vector<ExrChannel>& channels, ComponentFormat format) {
    if (channels.empty()) throw Error("write_exr_channels: no channels for '" + path + "'");
    const size_t n = size_t(width) * size_t(height);
    const Imf::PixelType type = format == ComponentFormat::Float16   ? Imf::HALF
                                : format == ComponentFormat::Float32 ? Imf::FLOAT
                                                                     : Imf::UINT;
    const size_t bytes = format == ComponentFormat::Float16 ? sizeof(half) : 4;
    Imf::Header header(width, height);
    Imf::FrameBuffer fb;
    std::vector<Converted> storage(channels.size());
    for (size_t c = 0; c < channels.size(); ++c) {
        const ExrChannel& ch = channels[c];
        if (ch.values.size() != n)
            throw Error("write_exr_channels: channel '" + ch.name + "' has the wrong size");
        if (header.channels().findChannel(ch.name))
            throw Error("write_exr_channels: duplicate channel '" + ch.name + "' in '" + path + "'");
        char* base = reinterpret_cast<char*>(const_cast<float*>(ch.values.data()));
        if (format == ComponentFormat::Float16) {
            storage[c].f16.assign(ch.values.begin(), ch.values.end());
            base = reinterpret_cast<char*>(storage[c].f16.data());
        } else if (format == ComponentFormat::UInt32) {
            storage[c].u32.resize(n);
            for (size_t i = 0; i < n; ++i)
                storage[c].u32[i] =
                    uint32_t(std::llround(std::clamp(double(ch.values[i]), 0.0, 1.0) * 4294967295.0));
            base = reinterpret_cast<char*>(storage[c].u32.data());
        }
        header.channels().insert(ch.name, Imf::Channel(type));
        fb.insert(ch.name, Imf::Slice(type, base, bytes, bytes * size_t(width)));
    }
    write_file_atomically(path, [&](const std::string& tmp) {
        Imf::OutputFile file(tmp.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(height);
    });
}

} // namespace penumbra
