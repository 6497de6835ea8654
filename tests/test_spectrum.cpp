// Spectrum tests: spectral -> sRGB conversion (Mitsuba 3 conventions), .spd reading, named conductors.
#include "core/error.h"
#include "core/spectrum.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace penumbra;

namespace {
const std::string IorDir = std::string(PENUMBRA_SHARED_DIR) + "/mitsuba-data/ior/";

// The measured spectra live in ../shared (absent from a user's own clone): skip the tests that read them.
#define SKIP_WITHOUT_IOR_DATA()                                                                              \
    if (!std::filesystem::exists(IorDir)) GTEST_SKIP() << "no Mitsuba ior data at " << IorDir
}

TEST(Spectrum, ConstantReflectanceIsWhiteUnderD65) {
    // A unit reflectance spectrum weighted by D65 is the sRGB white point: (1, 1, 1) up to the 5 nm tables'
    // and the 3-decimal matrix's precision (~1%).
    const Color3f c = spectrum_to_rgb({{360.f, 1.f}, {830.f, 1.f}}, true, true);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(c[i], 1.f, 0.01f) << c;
    // Without D65 a unit spectrum (illuminant E) has luminance 1 but is not white in sRGB: bluish-red clamp.
    const Color3f e = spectrum_to_rgb({{360.f, 1.f}, {830.f, 1.f}}, false, false);
    EXPECT_NEAR(0.212671f * e.x + 0.715160f * e.y + 0.072169f * e.z, 1.f, 0.01f);
    EXPECT_GT(e.x, 1.1f); // E is redder than D65 in sRGB (x = 1.205)
    // Bounded conversion clamps to [0, 1].
    const Color3f b = spectrum_to_rgb({{360.f, 1.f}, {830.f, 1.f}}, true, false);
    EXPECT_LE(max_component(b), 1.f);
}

TEST(Spectrum, SilverMatchesMitsuba) {
    SKIP_WITHOUT_IOR_DATA();
    // Mitsuba 3's ior_from_file("Ag") in RGB mode gives eta = (0.15528, 0.11673, 0.13839), k = (4.8284, 3.1222, 2.1469)
    // (published by a third-party port that reproduces Mitsuba's spectrum_list_to_srgb); 1e-3 covers float rounding.
    const Color3f eta = spectrum_to_rgb(read_spd(IorDir + "Ag.eta.spd"), false, false);
    const Color3f k = spectrum_to_rgb(read_spd(IorDir + "Ag.k.spd"), false, false);
    EXPECT_NEAR(eta.x, 0.155276f, 1e-3f);
    EXPECT_NEAR(eta.y, 0.116728f, 1e-3f);
    EXPECT_NEAR(eta.z, 0.138388f, 1e-3f);
    EXPECT_NEAR(k.x, 4.828354f, 1e-3f);
    EXPECT_NEAR(k.y, 3.122222f, 1e-3f);
    EXPECT_NEAR(k.z, 2.146901f, 1e-3f);
}

TEST(Spectrum, ConductorTableMatchesSpdData) {
    SKIP_WITHOUT_IOR_DATA();
    // The embedded table must be what spectrum_to_rgb gives for the data files; on mismatch, print the
    // regenerated table rows to paste into src/core/spectrum.cpp.
    std::ostringstream rows;
    int checked = 0;
    bool ok = true;
    for (const auto& entry : std::filesystem::directory_iterator(IorDir)) {
        const std::string f = entry.path().filename().string();
        if (f.size() <= 8 || f.substr(f.size() - 8) != ".eta.spd") continue;
        const std::string name = f.substr(0, f.size() - 8);
        const Color3f eta = spectrum_to_rgb(read_spd(IorDir + name + ".eta.spd"), false, false);
        const Color3f k = spectrum_to_rgb(read_spd(IorDir + name + ".k.spd"), false, false);
        Color3f te, tk;
        ASSERT_TRUE(conductor_ior(name, te, tk)) << name;
        for (int i = 0; i < 3; ++i) // the table stores 6 significant digits
            if (std::abs(te[i] - eta[i]) > 1e-5f * std::max(1.f, eta[i]) || std::abs(tk[i] - k[i]) > 1e-5f * std::max(1.f, k[i]))
                ok = false;
        rows << "{\"" << name << "\", {{" << eta.x << "f, " << eta.y << "f, " << eta.z << "f}, {" << k.x << "f, " << k.y
             << "f, " << k.z << "f}}},\n";
        ++checked;
    }
    EXPECT_TRUE(ok) << rows.str();
    EXPECT_GE(checked, 30);
}

TEST(Spectrum, NamedConductors) {
    for (const char* name : {"Cu", "Au", "Ag", "Al", "Cr"}) {
        Color3f eta, k;
        EXPECT_TRUE(conductor_ior(name, eta, k)) << name;
        EXPECT_GT(min_component(k), 0.5f) << name; // metals are strongly absorbing in the visible
    }
    Color3f eta, k;
    ASSERT_TRUE(conductor_ior("Au", eta, k));
    EXPECT_GT(eta.z, eta.x); // gold: low eta in red, high in blue -> red-orange reflectance
    ASSERT_TRUE(conductor_ior("Cu", eta, k));
    EXPECT_GT(eta.z, eta.x);
    EXPECT_FALSE(conductor_ior("Unobtainium", eta, k));
}

TEST(Spectrum, ReadSpdErrorsNameFileAndLine) {
    const std::string path = (std::filesystem::temp_directory_path() / "penumbra_test_bad.spd").string();
    {
        std::ofstream out(path);
        out << "# comment\n400 0.5\n500 0.6\n600 oops\n";
    }
    try {
        read_spd(path);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(path + ":4"), std::string::npos) << e.what();
    }
    {
        std::ofstream out(path);
        out << "400 0.5\n300 0.6\n";
    }
    EXPECT_THROW(read_spd(path), Error);
    std::remove(path.c_str());
    EXPECT_THROW(read_spd(path), Error); // missing file
}

TEST(Spectrum, ReadsMitsubaSpdFiles) {
    SKIP_WITHOUT_IOR_DATA();
    const auto s = read_spd(IorDir + "Au.eta.spd");
    EXPECT_GT(s.size(), 10u);
}
