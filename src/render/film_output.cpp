#include "render/film_output.h"

#include "core/exr_layers.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace penumbra {

namespace {

using PF = Film::PixelFormat;

// The main image's channel letters and values in the film's pixel format: Y = luminance, XYZ = the
// linear-sRGB to XYZ matrix (IEC 61966-2-1), as Mitsuba's film develops its RGB accumulation.
std::string color_letters(PF format) {
    if (format == PF::Luminance || format == PF::LuminanceAlpha) return "Y";
    if (format == PF::XYZ || format == PF::XYZA) return "XYZ";
    return "RGB";
}
Color3f convert(PF format, const Color3f& rgb) {
    if (format == PF::Luminance || format == PF::LuminanceAlpha) return Color3f(luminance(rgb));
    if (format == PF::XYZ || format == PF::XYZA) return srgb_to_xyz(rgb);
    return rgb;
}

const Layer* find_layer(const std::vector<Layer>& layers, const std::string& channels) {
    for (const Layer& l : layers)
        if (l.name.empty() && l.channels == channels) return &l;
    return nullptr;
}

void write_exr(const std::string& path, const Film& film, const std::vector<Layer>& layers, const Layer& main,
               const Layer* alpha) {
    const int w = main.image.width, h = main.image.height;
    const size_t n = main.image.pixels.size();
    std::vector<ExrChannel> channels;
    const std::string letters = color_letters(film.pixel_format);
    for (size_t k = 0; k < letters.size(); ++k) {
        ExrChannel ch{std::string(1, letters[k]), std::vector<float>(n)};
        for (size_t i = 0; i < n; ++i)
            ch.values[i] = convert(film.pixel_format, main.image.pixels[i])[int(k)];
        channels.push_back(std::move(ch));
    }
    if (alpha) {
        ExrChannel ch{"A", std::vector<float>(n)};
        for (size_t i = 0; i < n; ++i)
            ch.values[i] = alpha->image.pixels[i].x;
        channels.push_back(std::move(ch));
    }
    for (const Layer& l : layers) {
        if (&l == &main || (l.name.empty() && l.channels == "A")) continue; // alpha: only as the film's A
        for (size_t k = 0; k < l.channels.size(); ++k) {
            ExrChannel ch{(l.name.empty() ? "" : l.name + ".") + l.channels[k], std::vector<float>(n)};
            for (size_t i = 0; i < n; ++i)
                ch.values[i] = l.image.pixels[i][int(k)];
            channels.push_back(std::move(ch));
        }
    }
    write_exr_channels(path, w, h, channels, film.component_format);
}

void write_png_film(const std::string& path, const Film& film, const Layer& main, const Layer* alpha) {
    const bool gray = film.pixel_format == PF::Luminance || film.pixel_format == PF::LuminanceAlpha;
    const int color = gray ? 1 : 3, channels = color + (alpha ? 1 : 0);
    std::vector<float> values;
    values.reserve(main.image.pixels.size() * channels);
    for (size_t i = 0; i < main.image.pixels.size(); ++i) {
        const Color3f& c = main.image.pixels[i];
        if (gray)
            values.push_back(luminance(c));
        else
            values.insert(values.end(), {c.x, c.y, c.z});
        if (alpha) values.push_back(alpha->image.pixels[i].x);
    }
    write_png(path, main.image.width, main.image.height, channels, values);
}

} // namespace

void write_film(const std::string& path, const Film& film, const std::vector<Layer>& layers) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".exr" && ext != ".png")
        throw Error("output '" + path + "': expected a .exr or .png file name");
    if (layers.empty()) throw Error("write_film: nothing was rendered for '" + path + "'");
    // An integrator without a main image (aov without a nested integrator) leaves it black, as in Mitsuba.
    const Layer black{"", Image(layers.front().image.width, layers.front().image.height)};
    const Layer* main = find_layer(layers, "RGB");
    const Layer* alpha = film.has_alpha() ? find_layer(layers, "A") : nullptr;
    if (film.has_alpha() && !alpha)
        throw Error("write_film: pixel_format with alpha needs a camera-driven integrator (path, direct, "
                    "aov, moment)");
    if (ext == ".exr")
        write_exr(path, film, layers, main ? *main : black, alpha);
    else
        write_png_film(path, film, main ? *main : black, alpha);
}

} // namespace penumbra
