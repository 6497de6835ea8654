#include "cli.h"

#include "core/colormap.h"
#include "core/error.h"
#include "core/image.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace penumbra::cli {

std::map<std::string, std::string> parse_defines(const std::vector<std::string>& defines) {
    std::map<std::string, std::string> result;
    for (const std::string& d : defines) {
        const size_t eq = d.find('=');
        if (eq == std::string::npos || eq == 0) throw Error("-D expects name=value, got '" + d + "'");
        result[d.substr(0, eq)] = d.substr(eq + 1);
    }
    return result;
}

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

void write_signed(const std::string& path, const Image& image, float scale) {
    if (lower_extension(path) == ".png") write_image(path, diverging_colormap(image, scale));
    else write_image(path, image);
}

void write_z_map(const std::string& path, const Image& a, const Image& b, const Image& sa, const Image& sb) {
    Image z(a.width, a.height);
    for (size_t i = 0; i < z.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const float s = std::hypot(sa.pixels.empty() ? 0.f : sa.pixels[i][k], sb.pixels.empty() ? 0.f : sb.pixels[i][k]);
            const float d = a.pixels[i][k] - b.pixels[i][k];
            z.pixels[i][k] = s > 0.f ? std::clamp(d / s, -4.f, 4.f) : (d == 0.f ? 0.f : std::copysign(4.f, d));
        }
    write_signed(path, z, 4.f);
}

} // namespace penumbra::cli
