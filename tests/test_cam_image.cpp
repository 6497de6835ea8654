// Image I/O: EXR and PNG round trips, format variants, sRGB handling, failure behaviour.
#include "core/error.h"
#include "core/image.h"

#include <OpenEXR/ImfRgbaFile.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir() {
    const fs::path dir = fs::temp_directory_path() / ("penumbra_cam_image_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

// Whether `dir` holds a temporary file of an atomic write (core/atomic_file.h: `<name>.tmp.<pid>.<n>`).
bool has_temp_file(const fs::path& dir) {
    if (!fs::exists(dir)) return false;
    for (const auto& entry : fs::directory_iterator(dir))
        if (entry.path().filename().string().find(".tmp.") != std::string::npos) return true;
    return false;
}

Image test_pattern() {
    Image img(3, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x)
            img.at(x, y) = Color3f(0.1f * x, 0.25f + 0.5f * y, 3.5f * (x + 1) * (y + 1));
    return img;
}

struct CamImage : ::testing::Test {
    void TearDown() override { fs::remove_all(temp_dir()); }
};

} // namespace

TEST_F(CamImage, ExrRoundTripIsExact) {
    const std::string path = (temp_dir() / "pattern.exr").string();
    const Image img = test_pattern();
    write_image(path, img);
    const Image back = read_image(path);
    ASSERT_EQ(back.width, 3);
    ASSERT_EQ(back.height, 2);
    // 32-bit float channels: bit-exact, including values > 1.
    for (size_t i = 0; i < img.pixels.size(); ++i)
        EXPECT_EQ(back.pixels[i], img.pixels[i]) << i;
    EXPECT_FALSE(has_temp_file(temp_dir()));
}

TEST_F(CamImage, ExrHalfRgbaAndLuminanceFilesAreRead) {
    const fs::path dir = temp_dir();
    {
        Imf::Rgba px[2] = {Imf::Rgba(0.5f, 0.25f, 2.f, 0.3f), Imf::Rgba(1.f, 0.f, 0.125f, 1.f)};
        Imf::RgbaOutputFile out((dir / "half_rgba.exr").c_str(), 2, 1, Imf::WRITE_RGBA);
        out.setFrameBuffer(px, 1, 2);
        out.writePixels(1);
    }
    {
        Imf::Rgba px[2] = {Imf::Rgba(0.75f, 0.75f, 0.75f, 1.f), Imf::Rgba(4.f, 4.f, 4.f, 1.f)};
        Imf::RgbaOutputFile out((dir / "half_y.exr").c_str(), 2, 1, Imf::WRITE_Y);
        out.setFrameBuffer(px, 1, 2);
        out.writePixels(1);
    }
    // The values are exactly representable as halfs, so the reads are exact.
    const Image rgba = read_image((dir / "half_rgba.exr").string());
    EXPECT_EQ(rgba.at(0, 0), Color3f(0.5f, 0.25f, 2.f));
    EXPECT_EQ(rgba.at(1, 0), Color3f(1.f, 0.f, 0.125f));
    const Image y = read_image((dir / "half_y.exr").string());
    ASSERT_EQ(y.width, 2);
    // RgbaOutputFile converts RGB to luminance Y with its own weights; gray input keeps Y = the gray value.
    EXPECT_NEAR(y.at(0, 0).x, 0.75f, 1e-3f);
    EXPECT_EQ(y.at(0, 0).x, y.at(0, 0).y);
    EXPECT_EQ(y.at(0, 0).x, y.at(0, 0).z);
    EXPECT_NEAR(y.at(1, 0).y, 4.f, 4e-3f); // half precision: relative error <= 2^-11
}

TEST_F(CamImage, PngRoundTripUsesSrgbEncoding) {
    const std::string path = (temp_dir() / "codes.png").string();
    // Linear values whose sRGB encodings are exact 8-bit codes survive the 8-bit quantization.
    const int codes[4] = {0, 10, 128, 255};
    Image img(4, 1);
    for (int i = 0; i < 4; ++i)
        img.at(i, 0) = Color3f(srgb_to_linear(codes[i] / 255.f));
    img.at(3, 0).z = 7.f; // clamped to 1 on output
    write_image(path, img);

    const Image linear = read_image(path, true);
    const Image raw = read_image(path, false);
    for (int i = 0; i < 4; ++i) {
        // Round trip of an exact code: only float roundoff of pow() (~1e-7 relative) remains.
        EXPECT_NEAR(linear.at(i, 0).x, srgb_to_linear(codes[i] / 255.f), 1e-6f) << i;
        EXPECT_FLOAT_EQ(raw.at(i, 0).y, codes[i] / 255.f) << i;
    }
    EXPECT_FLOAT_EQ(linear.at(3, 0).z, 1.f);
    // Mid-gray code 128 is 0.2158605 in linear sRGB (IEC 61966-2-1).
    EXPECT_NEAR(linear.at(2, 0).x, 0.2158605f, 1e-6f);
}

TEST_F(CamImage, SrgbCurveIsInvertible) {
    for (float v : {0.f, 0.001f, 0.0031308f, 0.04f, 0.2f, 0.5f, 1.f})
        EXPECT_NEAR(srgb_to_linear(linear_to_srgb(v)), v, 1e-6f) << v; // float roundoff of pow
}

TEST_F(CamImage, WriteToUnwritablePathThrowsAndLeavesNoFile) {
    const fs::path dir = temp_dir() / "missing_subdir";
    for (const char* name : {"out.png", "out.exr"}) {
        const fs::path path = dir / name;
        try {
            write_image(path.string(), test_pattern());
            FAIL() << "expected an Error";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(path));
        EXPECT_FALSE(has_temp_file(dir));
    }
    EXPECT_THROW(write_image((temp_dir() / "x.tiff").string(), test_pattern()), Error);
}

TEST_F(CamImage, ReadErrorsNameTheFile) {
    const fs::path dir = temp_dir();
    const std::string missing = (dir / "nope.png").string();
    try {
        read_image(missing);
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
    }
    const std::string garbage = (dir / "garbage.exr").string();
    {
        std::FILE* f = std::fopen(garbage.c_str(), "w");
        std::fputs("not an exr", f);
        std::fclose(f);
    }
    EXPECT_THROW(read_image(garbage), Error);
    const std::string garbage_png = (dir / "garbage.png").string();
    fs::copy_file(garbage, garbage_png, fs::copy_options::overwrite_existing);
    EXPECT_THROW(read_image(garbage_png), Error);
}

TEST_F(CamImage, SharedTexturesLoad) {
    const std::string dir = PENUMBRA_SHARED_DIR "/mitsuba-data/common/textures/";
    if (!fs::exists(dir + "museum.exr") || !fs::exists(dir + "wood.jpg"))
        GTEST_SKIP() << "mitsuba-data absent";
    const Image museum = read_image(dir + "museum.exr");
    EXPECT_GT(museum.width, 0);
    EXPECT_EQ(museum.pixels.size(), size_t(museum.width) * museum.height);
    const Image wood = read_image(dir + "wood.jpg");
    EXPECT_GT(wood.width, 0);
    float max_value = 0.f;
    for (const Color3f& c : wood.pixels)
        max_value = std::max(max_value, max_component(c));
    EXPECT_LE(max_value, 1.f);
    EXPECT_GT(max_value, 0.f);
}
