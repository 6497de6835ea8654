#include "core/exr_layers.h"

#include "core/error.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>

#include <cstdio>

namespace penumbra {

void write_exr_layers(const std::string& path, const std::vector<std::pair<std::string, const Image*>>& layers) {
    if (layers.empty()) throw Error("write_exr_layers: no layers for '" + path + "'");
    const int w = layers[0].second->width, h = layers[0].second->height;
    Imf::Header header(w, h);
    Imf::FrameBuffer fb;
    const char* channels[3] = {"R", "G", "B"};
    for (const auto& [name, image] : layers) {
        if (image->width != w || image->height != h) throw Error("write_exr_layers: layer sizes differ in '" + path + "'");
        for (int c = 0; c < 3; ++c) {
            const std::string channel = name.empty() ? channels[c] : name + "." + channels[c];
            header.channels().insert(channel, Imf::Channel(Imf::FLOAT));
            char* base = reinterpret_cast<char*>(const_cast<Color3f*>(image->pixels.data())) + c * sizeof(float);
            fb.insert(channel, Imf::Slice(Imf::FLOAT, base, sizeof(Color3f), sizeof(Color3f) * w));
        }
    }
    const std::string tmp = path + ".tmp";
    try {
        Imf::OutputFile file(tmp.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(h);
    } catch (const std::exception& e) {
        std::remove(tmp.c_str());
        throw Error("cannot write '" + path + "': " + e.what());
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw Error("cannot write '" + path + "': rename failed");
    }
}

} // namespace penumbra
