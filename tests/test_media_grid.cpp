// Heterogeneous media on .vol grids written by the test: delta tracking (free flights) and ratio tracking
// (transmittance) against exp(-∫ sigma_t) and ∫ Tr sigma_s computed by fine quadrature of the medium's own
// sigma_t along the ray (so that the estimators, not the interpolation, are under test), a purely absorbing
// grid, and the validity of the per-block majorants (>= every channel of sigma_t on each segment).
#include "render/medium_sampling.h"

#include "core/rng.h"
#include "media_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// z-tests of means over N independent samples: |z| < 4.5 fails a correct estimator with probability 7e-6
// per check; each check prints the smallest bias it detects (4.5 standard errors).
constexpr double kMaxZ = 4.5;
constexpr int kSamples = 60000;

// A smooth density over a 24 x 12 x 17 grid (3 x 2 x 3 blocks of maxima) that vanishes for x < 10 (a block
// of zero majorants) and grows with z (blocks with smaller majorants); channel c scaled by (1, 0.6, 1.7)
// (one channel for `channels` 1).
float density(int x, int y, int z, int c) {
    if (x < 10) return 0.f;
    const float v = (0.4f + 1.6f * (0.5f + 0.5f * std::sin(0.7f * float(x) + 0.4f * float(y)))) *
                    (0.1f + 0.9f * float(z * z) / 256.f);
    return v * (c == 0 ? 1.f : (c == 1 ? 0.6f : 1.7f));
}

// The medium: the density grid (scaled by 1.5 and rotated in the world) and a 3-channel albedo grid.
const std::string kRotated =
    "<transform name=\"to_world\"><scale x=\"2\" y=\"1.5\" z=\"1.2\"/>"
    "<rotate y=\"1\" angle=\"30\"/><translate x=\"-1\" y=\"-0.7\" z=\"-0.4\"/></transform>";
const std::string kAxisAligned =
    "<transform name=\"to_world\"><scale x=\"2\" y=\"1.5\" z=\"1.2\"/><translate x=\"-1\" y=\"-0.7\" "
    "z=\"-0.4\"/></transform>";

std::shared_ptr<Medium> grid_medium(const TempDir& dir, int channels, const std::string& albedo_xml,
                                    const std::string& volume_extra = "",
                                    const std::string& placement = kRotated) {
    write_bytes(dir.str() + "/density.vol",
                vol_bytes({24, 12, 17}, channels, Vec3f(0.f), Vec3f(1.f), density));
    write_bytes(dir.str() + "/albedo.vol",
                vol_bytes({5, 4, 3}, 3, Vec3f(0.f), Vec3f(1.f), [](int x, int y, int z, int c) {
                    return 0.2f + 0.15f * float(x) + 0.05f * float(y * z) - 0.1f * float(c);
                }));
    return load_medium(
        "<medium type=\"heterogeneous\" name=\"interior\">\n"
        "<volume type=\"gridvolume\" name=\"sigma_t\"><string name=\"filename\" value=\"density.vol\"/>" +
            placement + volume_extra + "</volume>\n<float name=\"scale\" value=\"1.5\"/>\n" + albedo_xml +
            "\n</medium>",
        dir.str());
}
const std::string kAlbedoGrid =
    "<volume type=\"gridvolume\" name=\"albedo\"><string name=\"filename\" "
    "value=\"albedo.vol\"/><transform name=\"to_world\"><translate x=\"-1\" y=\"-1\" "
    "z=\"-1\"/><scale value=\"2\"/></transform></volume>";

struct Reference {
    Color3f tr, scattered; // exp(-∫_0^tmax sigma_t), ∫_0^tmax Tr(0, t) sigma_s(t) dt
};

// Trapezoid rule on 40000 steps (the trilinear density is piecewise cubic along the ray: the error, O(h²),
// is below 1e-6 here, far under the Monte Carlo errors).
Reference quadrature(const Medium& m, const Vec3f& o, const Vec3f& d, float tmax) {
    constexpr int steps = 40000;
    const double h = double(tmax) / steps;
    Vec3d tau(0.0), scattered(0.0), prev_sigma(0.0), prev_g(0.0);
    for (int i = 0; i <= steps; ++i) {
        const Vec3f p = o + d * float(i * h);
        const Color3f st = m.sigma_t(p), ss = st * m.albedo(p);
        Vec3d sigma(st), g;
        if (i > 0) tau += (sigma + prev_sigma) * (0.5 * h);
        for (int c = 0; c < 3; ++c)
            g[c] = std::exp(-tau[c]) * double(ss[c]);
        if (i > 0) scattered += (g + prev_g) * (0.5 * h);
        prev_sigma = sigma;
        prev_g = g;
    }
    return {Color3f(float(std::exp(-tau.x)), float(std::exp(-tau.y)), float(std::exp(-tau.z))),
            Color3f(scattered)};
}

void expect_z(const ChannelStats& s, int c, double expected, const std::string& what) {
    const double z = s.z(c, expected);
    EXPECT_LT(std::abs(z), kMaxZ) << what << " channel " << c << ": mean " << s.mean(c) << " expected "
                                  << expected << " stderr " << s.stderr_(c);
    std::printf("  %-30s c%d  mean %.5f  expected %.5f  z %+.2f  (detects bias > %.2g)\n", what.c_str(), c,
                s.mean(c), expected, z, kMaxZ * s.stderr_(c));
}

void expect_binomial(double count, double p, const std::string& what) {
    const double mean = count / kSamples, se = std::sqrt(p * (1 - p) / kSamples), z = (mean - p) / se;
    EXPECT_LT(std::abs(z), kMaxZ) << what << ": " << mean << " expected " << p;
    std::printf("  %-30s     mean %.5f  expected %.5f  z %+.2f\n", what.c_str(), mean, p, z);
}

struct TestRay {
    Vec3f o, d;
    float tmax;
};
// Through the grid's centre (0.17, 0.05, -0.38) in the world: across the whole grid, ending just past the
// centre, and starting near it.
const Vec3f kCentre(0.166f, 0.05f, -0.38f);
const TestRay kRays[] = {
    {kCentre - normalize(Vec3f(1.f, 0.1f, 0.05f)) * 3.f, normalize(Vec3f(1.f, 0.1f, 0.05f)), 10.f},
    {kCentre - normalize(Vec3f(-0.1f, 1.f, 0.2f)) * 2.f, normalize(Vec3f(-0.1f, 1.f, 0.2f)), 2.3f},
    {kCentre + Vec3f(0.1f), normalize(Vec3f(-0.6f, 0.3f, -0.4f)), 1.5f}};

// Runs both trackers along every test ray; `grey` adds the pass-probability check of delta tracking (for a
// grey medium it is exactly Tr).
void check_trackers(const Medium& medium, bool grey, bool absorbing) {
    Sampler sampler;
    for (const TestRay& ray : kRays) {
        const Reference ref = quadrature(medium, ray.o, ray.d, ray.tmax);
        ASSERT_GT(ref.tr.x, 0.02f);
        ASSERT_LT(ref.tr.x, 0.9f) << "the ray must cross a significant optical depth";
        ChannelStats ratio, passed, scattered;
        double pass_count = 0;
        for (int i = 0; i < kSamples; ++i) {
            sampler.start(5, 0, uint64_t(i));
            ratio.add(transmittance(medium, ray.o, ray.d, ray.tmax, sampler));
            const FreeFlightSample s = sample_free_flight(medium, ray.o, ray.d, ray.tmax, sampler);
            const bool pass = s.event == FreeFlightSample::Event::Passed;
            const bool scatter = s.event == FreeFlightSample::Event::Scattered;
            if (absorbing) {
                ASSERT_FALSE(scatter) << "a purely absorbing medium scattered";
            }
            pass_count += pass;
            passed.add(pass ? s.weight : Color3f(0.f));
            scattered.add(scatter ? s.weight : Color3f(0.f));
        }
        std::printf(" ray o = (%g, %g, %g), tmax = %g\n", ray.o.x, ray.o.y, ray.o.z, ray.tmax);
        for (int c = 0; c < 3; ++c) {
            expect_z(ratio, c, ref.tr[c], "ratio tracking Tr");
            expect_z(passed, c, ref.tr[c], "delta tracking E[w 1(pass)]");
            if (!absorbing) expect_z(scattered, c, ref.scattered[c], "delta tracking E[w 1(scatter)]");
        }
        if (grey) expect_binomial(pass_count, ref.tr.x, "delta tracking P(pass) = Tr");
    }
}

} // namespace

TEST(MediaGrid, ChromaticGridTrackersMatchQuadrature) {
    TempDir dir;
    const auto medium = grid_medium(dir, 3, kAlbedoGrid);
    ASSERT_FALSE(medium->is_homogeneous());
    check_trackers(*medium, false, false);
}

TEST(MediaGrid, GreyGridDeltaTrackingPassesWithProbabilityTr) {
    TempDir dir;
    const auto medium = grid_medium(dir, 1, "<float name=\"albedo\" value=\"0.7\"/>");
    check_trackers(*medium, true, false);
}

// The absorbing grid: never scatters; the transmittance is exp(-∫ density) along the ray.
TEST(MediaGrid, AbsorbingGridTransmittanceIsExpOfIntegratedDensity) {
    TempDir dir;
    const auto medium = grid_medium(dir, 1, "<float name=\"albedo\" value=\"0\"/>");
    check_trackers(*medium, true, true);
}

// Majorants: segments cover [tmin, tmax) in order, and each bounds every channel of sigma_t at points drawn
// in it (including its start and points a hair before its end). Exact comparisons up to float rounding of
// the trilinear sum (relative 1e-5): a majorant that is too low by any amount at any point fails.
TEST(MediaGrid, MajorantsBoundSigmaTAlongRandomRays) {
    struct Config {
        const char* name;
        std::string extra;
        bool axis_aligned; // unrotated grid, rays along the axes, often exactly on block or voxel planes
    };
    const Config configs[] = {
        {"trilinear clamp", "", false},
        {"nearest repeat",
         "<string name=\"filter_type\" value=\"nearest\"/><string name=\"wrap_mode\" value=\"repeat\"/>",
         false},
        {"trilinear mirror", "<string name=\"wrap_mode\" value=\"mirror\"/>", false},
        {"axis-aligned rays", "", true}};
    for (const auto& [name, extra, axis_aligned] : configs) {
        TempDir dir;
        const auto medium = grid_medium(dir, 3, kAlbedoGrid, extra, axis_aligned ? kAxisAligned : kRotated);
        PCG32 rng(11);
        int segments = 0, points = 0;
        std::vector<float> bounds;
        const Vec3f lo(-1.f, -0.7f, -0.4f), size(2.f, 1.5f, 1.2f), res(24.f, 12.f, 17.f);
        for (int r = 0; r < 3000; ++r) {
            auto u = [&] { return rng.next_float(); };
            Vec3f o(-3.f + 6.f * u(), -3.f + 6.f * u(), -3.f + 6.f * u());
            const float z = 1.f - 2.f * u(), phi = 2.f * Pi * u(), s = std::sqrt(std::max(0.f, 1.f - z * z));
            Vec3f d(s * std::cos(phi), s * std::sin(phi), z);
            if (axis_aligned) {
                const int axis = int(3.f * u()) % 3;
                d = Vec3f(0.f);
                d[axis] = u() < 0.5f ? 1.f : -1.f;
                for (int a = 0; a < 3; ++a) {
                    const float which = u();
                    if (a == axis || which < 0.2f) continue;
                    // A block plane (every 8 voxels) or a voxel-centre plane.
                    const float k = std::floor(u() * res[a]);
                    const float voxel = which < 0.6f ? 8.f * std::floor(k / 8.f) : k + 0.5f;
                    o[a] = lo[a] + size[a] * voxel / res[a];
                }
            }
            const float tmin = u() < 0.3f ? 0.f : 2.f * u();
            const float tmax = u() < 0.2f ? Infinity : tmin + 8.f * u();
            float expected_start = tmin;
            medium->majorants(o, d, tmin, tmax, [&](float t0, float t1, float m) {
                ++segments;
                EXPECT_EQ(t0, expected_start) << name << ": segments must be contiguous";
                EXPECT_LE(t0, t1);
                EXPECT_GE(m, 0.f);
                expected_start = t1;
                bounds.push_back(m);
                const float end = std::min(t1, t0 + 10.f);
                for (int k = 0; k < 10; ++k) {
                    const float t = k == 0 ? t0 : (k == 1 ? std::nextafter(end, t0) : t0 + (end - t0) * u());
                    const Color3f sigma = medium->sigma_t(o + d * t);
                    ++points;
                    EXPECT_LE(max_component(sigma), m * (1.f + 1e-5f))
                        << name << ": majorant " << m << " below sigma_t " << sigma << " at t = " << t
                        << " in [" << t0 << ", " << t1 << ")";
                }
                return true;
            });
            EXPECT_EQ(expected_start, tmax) << name << ": segments must end at tmax";
        }
        const float global = *std::max_element(bounds.begin(), bounds.end());
        const auto inside = std::count_if(bounds.begin(), bounds.end(), [](float m) { return m > 0.f; });
        const auto refined = std::count_if(bounds.begin(), bounds.end(),
                                           [&](float m) { return m > 0.f && m < 0.5f * global; });
        std::printf("  %-17s %d segments (%d non-zero, %d below half the largest), %d points checked\n", name,
                    segments, int(inside), int(refined), points);
        // The block structure is used: many segments are much tighter than the global bound (not with
        // `repeat`, whose stencils wrap the densest top layer into the bottom blocks).
        if (std::string(name).find("repeat") == std::string::npos) {
            EXPECT_GT(refined, inside / 10) << name;
        }
    }
}
