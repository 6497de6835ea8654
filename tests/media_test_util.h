// Helpers of the participating-media tests (tests/test_media_*.cpp): Mitsuba .vol files written from a
// function, media loaded from XML snippets, and per-channel Monte Carlo means with their standard errors.
#pragma once
#include "scene/scene.h"

#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace penumbra::test {

// The bytes of a version-3 float32 .vol file; `value(x, y, z, c)` gives the data.
inline std::string vol_bytes(Vec3i res, int channels, const Vec3f& lo, const Vec3f& hi,
                             const std::function<float(int, int, int, int)>& value) {
    std::string out = "VOL";
    out.push_back(char(3));
    auto put = [&](auto v) { out.append(reinterpret_cast<const char*>(&v), sizeof(v)); };
    put(int32_t(1));
    put(int32_t(res.x)), put(int32_t(res.y)), put(int32_t(res.z)), put(int32_t(channels));
    put(lo.x), put(lo.y), put(lo.z), put(hi.x), put(hi.y), put(hi.z);
    for (int z = 0; z < res.z; ++z)
        for (int y = 0; y < res.y; ++y)
            for (int x = 0; x < res.x; ++x)
                for (int c = 0; c < channels; ++c)
                    put(value(x, y, z, c));
    return out;
}

inline void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// Loads `medium_xml` (a <medium ...> element whose name attribute is "interior") inside a cube and returns
// the medium. `dir` is the scene directory (relative file names resolve against it).
inline std::shared_ptr<Medium> load_medium(const std::string& medium_xml, const std::string& dir) {
    const std::string xml = scene("<shape type=\"cube\">\n" + medium_xml + "\n</shape>");
    std::ofstream(dir + "/scene.xml") << xml;
    auto loaded = load_scene(dir + "/scene.xml");
    return loaded->shapes.at(0)->interior;
}

// Running per-channel mean and standard error of a vector-valued estimator.
struct ChannelStats {
    double n = 0;
    Vec3d sum{0.0, 0.0, 0.0}, sum2{0.0, 0.0, 0.0};
    void add(const Color3f& v) {
        n += 1;
        for (int c = 0; c < 3; ++c) {
            sum[c] += double(v[c]);
            sum2[c] += double(v[c]) * double(v[c]);
        }
    }
    double mean(int c) const { return sum[c] / n; }
    double stderr_(int c) const {
        const double m = mean(c);
        return std::sqrt(std::max(0.0, sum2[c] / n - m * m) / (n - 1));
    }
    // z-score of the mean against `expected` (0 when both the error and the deviation vanish).
    double z(int c, double expected) const {
        const double dev = mean(c) - expected, se = stderr_(c);
        if (se == 0.0) return std::abs(dev) < 1e-9 ? 0.0 : Infinity;
        return dev / se;
    }
};

} // namespace penumbra::test
