// Image file I/O: OpenEXR through OpenEXR 3 (linear float data), 8/16-bit and Radiance HDR formats through
// stb_image, PNG output through stb_image_write. Writes are atomic (core/atomic_file.h).
#include "core/image.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>

namespace penumbra {

namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

[[noreturn]] void fail(const std::string& what, const std::string& path, const std::string& reason) {
    throw Error(what + " '" + path + "': " + reason);
}

// Checked before anything is allocated for the pixels: a header may state any size, whatever the data holds.
void check_image_size(int64_t width, int64_t height, int64_t max_pixels, const std::string& path) {
    if (width <= 0 || height <= 0)
        fail("read_image", path,
             "invalid image size " + std::to_string(width) + " x " + std::to_string(height));
    if (width > max_pixels / height)
        fail("read_image", path,
             "the image is " + std::to_string(width) + " x " + std::to_string(height) +
                 " pixels, more than the " + std::to_string(max_pixels) + " that penumbra reads");
}

// EXR: R,G,B channels (any of half/float/uint, converted to float by the library), or a single Y channel.
Image read_exr(const std::string& path, int64_t max_pixels) {
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        check_image_size(int64_t(dw.max.x) - dw.min.x + 1, int64_t(dw.max.y) - dw.min.y + 1, max_pixels, path);
        // Missing pixel data would make readPixels throw anyway; rejecting it here also spares allocating an
        // image of the size that a truncated or corrupt header states.
        if (!file.isComplete()) fail("read_image", path, "incomplete file (pixel data is missing)");
        const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
        const Imf::ChannelList& channels = file.header().channels();
        const bool rgb = channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
        const bool gray = !rgb && channels.findChannel("Y");
        if (!rgb && !gray) {
            std::string names;
            for (auto it = channels.begin(); it != channels.end(); ++it)
                names += std::string(" ") + it.name();
            fail("read_image", path, "expected R,G,B or Y channels, found:" + names);
        }
        Image image(w, h);
        const size_t xs = sizeof(Color3f), ys = sizeof(Color3f) * size_t(w);
        char* base = reinterpret_cast<char*>(image.pixels.data());
        Imf::FrameBuffer fb;
        if (rgb) {
            fb.insert("R", Imf::Slice::Make(Imf::FLOAT, base, dw, xs, ys));
            fb.insert("G", Imf::Slice::Make(Imf::FLOAT, base + sizeof(float), dw, xs, ys));
            fb.insert("B", Imf::Slice::Make(Imf::FLOAT, base + 2 * sizeof(float), dw, xs, ys));
        } else {
            fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, base, dw, xs, ys));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        if (gray)
            for (Color3f& c : image.pixels)
                c = Color3f(c.x);
        return image;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        fail("read_image", path, e.what());
    }
}

std::string stb_reason() {
    const char* reason = stbi_failure_reason();
    return reason ? reason : "unknown stb_image error";
}

// stb_image grows its buffer of a PNG's compressed data to each IDAT chunk's stated length before reading it:
// a chunk claiming gigabytes in a small file must be rejected first.
void check_png_chunks(const std::vector<unsigned char>& file, const std::string& path) {
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (file.size() < 8 || !std::equal(signature, signature + 8, file.begin())) return;
    for (size_t pos = 8; pos + 8 <= file.size();) {
        const uint32_t length = uint32_t(file[pos]) << 24 | uint32_t(file[pos + 1]) << 16 |
                                uint32_t(file[pos + 2]) << 8 | uint32_t(file[pos + 3]);
        const std::string type(file.begin() + long(pos) + 4, file.begin() + long(pos) + 8);
        const size_t left = file.size() - pos - 8;
        if (length > left)
            fail("read_image", path,
                 "corrupt PNG: chunk '" + type + "' states " + std::to_string(length) + " bytes, but only " +
                     std::to_string(left) + " follow");
        if (type == "IEND") return;
        pos += 8 + size_t(length) + 4; // length, type, data, CRC
    }
}

// 8/16-bit formats are sRGB-encoded unless `srgb` is false; Radiance HDR is linear. The file is read into
// memory so that its size is checked (stbi_info) before stb_image decodes it.
Image read_stb(const std::string& path, bool srgb, int64_t max_pixels) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<unsigned char> file((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    if (!in.eof() && in.fail()) fail("read_image", path, "cannot read the file");
    if (file.size() > size_t(std::numeric_limits<int>::max())) fail("read_image", path, "file too large");
    const stbi_uc* bytes = file.data();
    const int length = int(file.size());
    int w = 0, h = 0, n = 0;
    if (!stbi_info_from_memory(bytes, length, &w, &h, &n)) fail("read_image", path, stb_reason());
    check_image_size(w, h, max_pixels, path);
    check_png_chunks(file, path);
    auto decode = [&](float v) { return srgb ? srgb_to_linear(v) : v; };
    Image image;
    if (stbi_is_hdr_from_memory(bytes, length)) {
        std::unique_ptr<float, void (*)(void*)> data(stbi_loadf_from_memory(bytes, length, &w, &h, &n, 3),
                                                     stbi_image_free);
        if (!data) fail("read_image", path, stb_reason());
        image = Image(w, h);
        for (size_t i = 0; i < image.pixels.size(); ++i)
            image.pixels[i] = Color3f(data.get()[3 * i], data.get()[3 * i + 1], data.get()[3 * i + 2]);
    } else if (stbi_is_16_bit_from_memory(bytes, length)) {
        std::unique_ptr<stbi_us, void (*)(void*)> data(stbi_load_16_from_memory(bytes, length, &w, &h, &n, 3),
                                                       stbi_image_free);
        if (!data) fail("read_image", path, stb_reason());
        image = Image(w, h);
        for (size_t i = 0; i < image.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c)
                image.pixels[i][c] = decode(data.get()[3 * i + c] / 65535.f);
    } else {
        std::unique_ptr<stbi_uc, void (*)(void*)> data(stbi_load_from_memory(bytes, length, &w, &h, &n, 3),
                                                       stbi_image_free);
        if (!data) fail("read_image", path, stb_reason());
        // Decode through a 256-entry table: the sRGB curve is the expensive part for large textures.
        float table[256];
        for (int v = 0; v < 256; ++v)
            table[v] = decode(v / 255.f);
        image = Image(w, h);
        for (size_t i = 0; i < image.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c)
                image.pixels[i][c] = table[data.get()[3 * i + c]];
    }
    return image;
}

void write_exr(const std::string& path, const Image& image) {
    Imf::Header header(image.width, image.height);
    header.channels().insert("R", Imf::Channel(Imf::FLOAT));
    header.channels().insert("G", Imf::Channel(Imf::FLOAT));
    header.channels().insert("B", Imf::Channel(Imf::FLOAT));
    const size_t xs = sizeof(Color3f), ys = sizeof(Color3f) * size_t(image.width);
    char* base = const_cast<char*>(reinterpret_cast<const char*>(image.pixels.data()));
    Imf::FrameBuffer fb;
    fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
}

// PNG: linear values clamped to [0,1], sRGB-encoded (alpha: linear), rounded to 8 bits.
void write_png_data(const std::string& path, int width, int height, int channels,
                    const std::vector<float>& values) {
    const bool has_alpha = channels == 2 || channels == 4;
    std::vector<unsigned char> bytes(values.size());
    for (size_t i = 0; i < values.size(); ++i) {
        const bool alpha = has_alpha && int(i % channels) == channels - 1;
        const float v = std::clamp(values[i], 0.f, 1.f);
        bytes[i] = (unsigned char)(std::lround((alpha ? v : linear_to_srgb(v)) * 255.f));
    }
    if (!stbi_write_png(path.c_str(), width, height, channels, bytes.data(), width * channels))
        throw std::runtime_error("cannot write PNG data");
}

} // namespace

// IEC 61966-2-1: the linear-sRGB to XYZ matrix (the one Mitsuba 3 uses for its xyz pixel formats).
Color3f srgb_to_xyz(const Color3f& c) {
    return {0.412453f * c.x + 0.357580f * c.y + 0.180423f * c.z,
            0.212671f * c.x + 0.715160f * c.y + 0.072169f * c.z,
            0.019334f * c.x + 0.119193f * c.y + 0.950227f * c.z};
}

// IEC 61966-2-1 sRGB transfer function and its inverse.
float srgb_to_linear(float v) {
    return v <= 0.04045f ? v * (1.f / 12.92f) : std::pow((v + 0.055f) * (1.f / 1.055f), 2.4f);
}
float linear_to_srgb(float v) {
    return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

Image read_image(const std::string& path, bool srgb, int64_t max_pixels) {
    if (!std::filesystem::is_regular_file(path)) fail("read_image", path, "no such file");
    return lower_extension(path) == ".exr" ? read_exr(path, max_pixels) : read_stb(path, srgb, max_pixels);
}

void write_image(const std::string& path, const Image& image) {
    const std::string ext = lower_extension(path);
    if (ext != ".exr" && ext != ".png")
        fail("write_image", path, "unsupported extension (expected .exr or .png)");
    if (image.width <= 0 || image.height <= 0 || image.pixels.size() != size_t(image.width) * image.height)
        fail("write_image", path, "image has invalid dimensions");
    if (ext == ".exr") {
        write_file_atomically(path, [&](const std::string& tmp) { write_exr(tmp, image); });
        return;
    }
    std::vector<float> values(image.pixels.size() * 3);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            values[3 * i + c] = image.pixels[i][c];
    write_png(path, image.width, image.height, 3, values);
}

void write_png(const std::string& path, int width, int height, int channels,
               const std::vector<float>& values) {
    if (width <= 0 || height <= 0 || channels < 1 || channels > 4 ||
        values.size() != size_t(width) * height * channels)
        fail("write_image", path, "image has invalid dimensions");
    write_file_atomically(
        path, [&](const std::string& tmp) { write_png_data(tmp, width, height, channels, values); });
}

namespace {

// Σ (or Σ of squares) of each k × k block, with the block's pixel count.
template <typename F> Image block_reduce(const Image& image, int k, const F& per_pixel, bool root_of_sum) {
    const int w = (image.width + k - 1) / k, h = (image.height + k - 1) / k;
    Image out(w, h);
    for (int by = 0; by < h; ++by)
        for (int bx = 0; bx < w; ++bx) {
            Vec3d sum(0.0);
            int count = 0;
            for (int y = by * k; y < std::min(image.height, (by + 1) * k); ++y)
                for (int x = bx * k; x < std::min(image.width, (bx + 1) * k); ++x, ++count)
                    sum += per_pixel(Vec3d(image.at(x, y)));
            if (root_of_sum) sum = Vec3d(std::sqrt(sum.x), std::sqrt(sum.y), std::sqrt(sum.z));
            out.at(bx, by) = Color3f(sum / double(count));
        }
    return out;
}

} // namespace

Image block_average(const Image& image, int k) {
    if (image.pixels.empty()) return image;
    return block_reduce(
        image, k, [](const Vec3d& v) { return v; }, false);
}

Image block_average_stderr(const Image& stderr_img, int k) {
    if (stderr_img.pixels.empty()) return stderr_img;
    return block_reduce(
        stderr_img, k, [](const Vec3d& s) { return s * s; }, true);
}

} // namespace penumbra
