// Samplers (core/sampler.h): Mitsuba's sample-count rounding; per-dimension stratification of every pixel's
// set of samples; determinism; loading; unbiasedness and variance against `independent` on a direct-lighting
// image; thread-count independence of a render.
#include "core/sampler.h"
#include "diff_check.h"
#include "render_stats.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <set>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

SamplerSpec spec_of(SamplerType type, int spp) {
    SamplerSpec s;
    s.type = type;
    s.sample_count = s.rounded(spp);
    return s;
}

// The dimensions drawn per sample by the stratification checks: 1D, 2D, 2D, 1D, 2D, 1D, 1D (as a path draws
// them).
const bool kIs2d[] = {false, true, true, false, true, false, false};
constexpr int kCalls = int(sizeof(kIs2d) / sizeof(kIs2d[0]));

// values[call][sample] of one pixel set: sample indices [first, first + n).
std::vector<std::vector<Vec2f>> draw(Sampler& sampler, uint64_t seed, uint64_t pixel, uint32_t first,
                                     uint32_t n) {
    std::vector<std::vector<Vec2f>> v(kCalls, std::vector<Vec2f>(n));
    for (uint32_t i = 0; i < n; ++i) {
        sampler.start(seed, pixel, first + i);
        for (int c = 0; c < kCalls; ++c)
            v[c][i] = kIs2d[c] ? sampler.next_2d() : Vec2f(sampler.next_1d(), 0.f);
    }
    return v;
}

// True if the cells (⌊x·nx⌋, ⌊y·ny⌋) of the points are pairwise distinct (each hit once when nx·ny = points).
bool distinct_cells(const std::vector<Vec2f>& pts, uint32_t nx, uint32_t ny) {
    std::set<std::pair<uint32_t, uint32_t>> cells;
    for (const Vec2f& p : pts)
        cells.insert({uint32_t(p.x * float(nx)), uint32_t(p.y * float(ny))});
    return cells.size() == pts.size();
}

std::vector<Vec2f> pairs_of(const std::vector<float>& a, const std::vector<float>& b) {
    std::vector<Vec2f> out;
    for (size_t i = 0; i < a.size(); ++i)
        out.emplace_back(a[i], b[i]);
    return out;
}

// The 1D values of a sampler set, one vector per dimension (a 2D call gives two dimensions).
std::vector<std::vector<float>> dimensions(const std::vector<std::vector<Vec2f>>& v) {
    std::vector<std::vector<float>> dims;
    for (int c = 0; c < kCalls; ++c) {
        std::vector<float> x, y;
        for (const Vec2f& p : v[c]) {
            x.push_back(p.x);
            y.push_back(p.y);
        }
        dims.push_back(x);
        if (kIs2d[c]) dims.push_back(y);
    }
    return dims;
}

void expect_in_unit_interval(const std::vector<std::vector<Vec2f>>& v) {
    for (const auto& call : v)
        for (const Vec2f& p : call) {
            EXPECT_TRUE(p.x >= 0.f && p.x < 1.f && p.y >= 0.f && p.y < 1.f) << p.x << ", " << p.y;
        }
}

// Every dimension of every set puts one sample in each of the n strata of [0,1) (with `only_1d_calls`, only
// the dimensions drawn by next_1d: the stratified sampler's 2D cells project onto √n strata per axis, as
// Mitsuba's).
void expect_1d_strata(const std::vector<std::vector<Vec2f>>& v, uint32_t n, const char* name,
                      bool only_1d_calls = false) {
    for (int c = 0; c < kCalls; ++c) {
        if (kIs2d[c] && only_1d_calls) continue;
        std::vector<float> x, y;
        for (const Vec2f& p : v[c]) {
            x.push_back(p.x);
            y.push_back(p.y);
        }
        EXPECT_TRUE(distinct_cells(pairs_of(x, x), n, 1)) << name << ": 1D strata, call " << c;
        if (kIs2d[c]) {
            EXPECT_TRUE(distinct_cells(pairs_of(y, y), n, 1)) << name << ": 1D strata, call " << c;
        }
    }
}

} // namespace

// Mitsuba 3's set_sample_count rounding (src/samplers/*.cpp).
TEST(Samplers, SampleCountRoundingFollowsMitsuba) {
    auto r = [](SamplerType t, int spp) { return spec_of(t, spp).sample_count; };
    EXPECT_EQ(r(SamplerType::Independent, 7), 7);
    EXPECT_EQ(r(SamplerType::Stratified, 16), 16);
    EXPECT_EQ(r(SamplerType::Stratified, 5), 9);
    EXPECT_EQ(r(SamplerType::Stratified, 1), 1);
    // multijitter: rows = ⌊∛spp⌋, cols = ⌈spp / rows²⌉, count = cols · rows².
    EXPECT_EQ(r(SamplerType::Multijitter, 16), 16);
    EXPECT_EQ(r(SamplerType::Multijitter, 10), 12);
    EXPECT_EQ(r(SamplerType::Multijitter, 100), 112);
    EXPECT_EQ(r(SamplerType::Multijitter, 27), 27);
    EXPECT_EQ(r(SamplerType::Multijitter, 1), 1);
    // orthogonal: p² for the smallest prime p ≥ 2 with p² ≥ spp.
    EXPECT_EQ(r(SamplerType::Orthogonal, 1), 4);
    EXPECT_EQ(r(SamplerType::Orthogonal, 16), 25);
    EXPECT_EQ(r(SamplerType::Orthogonal, 25), 25);
    EXPECT_EQ(r(SamplerType::Orthogonal, 50), 121);
    // ldsampler: a square power of two, at least 4.
    EXPECT_EQ(r(SamplerType::LowDiscrepancy, 1), 4);
    EXPECT_EQ(r(SamplerType::LowDiscrepancy, 8), 16);
    EXPECT_EQ(r(SamplerType::LowDiscrepancy, 16), 16);
    EXPECT_EQ(r(SamplerType::LowDiscrepancy, 17), 64);
}

TEST(Samplers, StratifiedHitsEveryStratumOnce) {
    const SamplerSpec spec = spec_of(SamplerType::Stratified, 16);
    Sampler s(spec, spec.sample_count);
    for (uint32_t set = 0; set < 2; ++set)
        for (uint64_t pixel : {0ull, 17ull}) {
            const auto v = draw(s, 3, pixel, set * 16, 16);
            expect_in_unit_interval(v);
            expect_1d_strata(v, 16, "stratified", true);
            for (int c = 0; c < kCalls; ++c) {
                if (kIs2d[c]) {
                    EXPECT_TRUE(distinct_cells(v[c], 4, 4)) << "stratified: 4x4 cells, call " << c;
                }
            }
        }
}

TEST(Samplers, MultijitterIsStratifiedIn2dAndAlongEachAxis) {
    for (int spp : {16, 12}) {
        const SamplerSpec spec = spec_of(SamplerType::Multijitter, spp);
        const uint32_t n = uint32_t(spec.sample_count), rows = 4, cols = n / rows; // 4 x 4 and 3 x 4
        Sampler s(spec, spec.sample_count);
        for (uint32_t set = 0; set < 2; ++set) {
            const auto v = draw(s, 5, 3, set * n, n);
            expect_in_unit_interval(v);
            expect_1d_strata(v, n, "multijitter");
            for (int c = 0; c < kCalls; ++c) {
                if (kIs2d[c]) {
                    EXPECT_TRUE(distinct_cells(v[c], cols, rows)) << "multijitter: grid, call " << c;
                }
            }
        }
    }
}

// Strength 2: every dimension is stratified in p² intervals and every pair among the first p + 1 dimensions
// in a p × p grid (the orthogonal array's columns are pairwise orthogonal).
TEST(Samplers, OrthogonalArrayStratifiesEveryPairOfDimensions) {
    const SamplerSpec spec = spec_of(SamplerType::Orthogonal, 25);
    ASSERT_EQ(spec.sample_count, 25);
    Sampler s(spec, spec.sample_count);
    for (uint32_t set = 0; set < 2; ++set) {
        const auto v = draw(s, 7, 11, set * 25, 25);
        expect_in_unit_interval(v);
        expect_1d_strata(v, 25, "orthogonal");
        const auto dims = dimensions(v);
        ASSERT_GE(dims.size(), 6u);
        for (size_t a = 0; a < 6; ++a)
            for (size_t b = a + 1; b < 6; ++b)
                EXPECT_TRUE(distinct_cells(pairs_of(dims[a], dims[b]), 5, 5))
                    << "dimensions " << a << ", " << b;
    }
}

// The first 4^k points of a (0,2)-sequence form a (0, 2k, 2)-net: each elementary interval of area 4^-k, of
// any shape 2^-a × 2^-(2k-a), holds exactly one point.
TEST(Samplers, LowDiscrepancyIsA02Net) {
    for (int spp : {16, 64}) {
        const SamplerSpec spec = spec_of(SamplerType::LowDiscrepancy, spp);
        const uint32_t n = uint32_t(spec.sample_count);
        const int m = int(std::log2(double(n)));
        Sampler s(spec, spec.sample_count);
        for (uint32_t set = 0; set < 2; ++set) {
            const auto v = draw(s, 9, 2, set * n, n);
            expect_in_unit_interval(v);
            expect_1d_strata(v, n, "ldsampler");
            for (int c = 0; c < kCalls; ++c) {
                if (!kIs2d[c]) continue;
                for (int a = 0; a <= m; ++a) {
                    EXPECT_TRUE(distinct_cells(v[c], 1u << a, 1u << (m - a)))
                        << "ldsampler " << n << ": interval 2^-" << a << " x 2^-" << (m - a) << ", call "
                        << c;
                }
            }
        }
    }
}

// Values are a pure function of (seed, pixel, sample index, dimension): the order in which samples are drawn
// does not matter, and another seed, pixel or set gives other values.
TEST(Samplers, ValuesArePureFunctionsOfSeedPixelIndexDimension) {
    for (SamplerType t : {SamplerType::Independent, SamplerType::Stratified, SamplerType::Multijitter,
                          SamplerType::Orthogonal, SamplerType::LowDiscrepancy}) {
        const SamplerSpec spec = spec_of(t, 16);
        const uint32_t n = uint32_t(spec.sample_count);
        Sampler a(spec, spec.sample_count), b(spec, spec.sample_count);
        const auto forward = draw(a, 1, 5, 0, n);
        for (uint32_t i = n; i-- > 0;) { // reverse order, on another sampler object
            b.start(1, 5, i);
            for (int c = 0; c < kCalls; ++c) {
                const Vec2f p = kIs2d[c] ? b.next_2d() : Vec2f(b.next_1d(), 0.f);
                EXPECT_EQ(std::memcmp(&p, &forward[c][i], sizeof(Vec2f)), 0) << sampler_type_name(t);
            }
        }
        const auto other_seed = draw(a, 2, 5, 0, n), other_pixel = draw(a, 1, 6, 0, n),
                   next_set = draw(a, 1, 5, n, n);
        for (const auto* other : {&other_seed, &other_pixel, &next_set}) {
            int same = 0;
            for (int c = 0; c < kCalls; ++c)
                for (uint32_t i = 0; i < n; ++i)
                    same += (*other)[c][i].x == forward[c][i].x;
            EXPECT_LT(same, kCalls * int(n) / 4)
                << sampler_type_name(t) << ": values repeat across sequences";
        }
    }
}

// Unbiasedness at the level of one sample: across seeds, a given sample's values are uniform in every
// dimension and jointly in pairs of dimensions (what makes any estimator using them unbiased). Chi-square
// over 5 × 5 cells of 20000 seeds (24 dof): above 24 + 6·√48 ≈ 66 is a non-uniform pattern (a permutation
// whose π(i) favours some strata), not chance (p < 1e-6).
TEST(Samplers, EachSampleIsUniformAcrossSeeds) {
    constexpr int seeds = 20000, bins = 5;
    for (const auto& [type, spp] :
         std::vector<std::pair<SamplerType, int>>{{SamplerType::Stratified, 9},
                                                  {SamplerType::Multijitter, 12},
                                                  {SamplerType::Orthogonal, 25},
                                                  {SamplerType::LowDiscrepancy, 16}}) {
        const SamplerSpec spec = spec_of(type, spp);
        Sampler s(spec, spec.sample_count);
        for (uint64_t index : {0ull, 5ull}) {
            std::vector<std::vector<float>> dims; // dims[seed][dimension]
            for (int k = 0; k < seeds; ++k) {
                s.start(uint64_t(k), 3, index);
                std::vector<float> d;
                for (int c = 0; c < kCalls; ++c) {
                    const Vec2f p = kIs2d[c] ? s.next_2d() : Vec2f(s.next_1d(), 0.f);
                    d.push_back(p.x);
                    if (kIs2d[c]) d.push_back(p.y);
                }
                dims.push_back(d);
            }
            for (size_t a = 0; a < dims[0].size(); ++a)
                for (size_t b = a + 1; b < dims[0].size(); ++b) {
                    std::vector<int> h(bins * bins, 0);
                    for (const auto& d : dims)
                        ++h[int(d[a] * bins) * bins + int(d[b] * bins)];
                    double chi2 = 0;
                    const double e = double(seeds) / (bins * bins);
                    for (int v : h)
                        chi2 += (v - e) * (v - e) / e;
                    EXPECT_LT(chi2, 66.0) << sampler_type_name(type) << " sample " << index << ": dimensions "
                                          << a << ", " << b;
                }
        }
    }
}

TEST(Samplers, LoadRoundsAndRejectsBadParameters) {
    auto load = [](const std::string& sampler) {
        return load_scene_string("<scene version=\"3.0.0\"><sensor type=\"perspective\">" + sampler +
                                 "<film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/>"
                                 "<integer name=\"height\" value=\"4\"/></film></sensor></scene>");
    };
    auto scene =
        load("<sampler type=\"orthogonal\"><integer name=\"sample_count\" value=\"16\"/>"
             "<boolean name=\"jitter\" value=\"false\"/><integer name=\"seed\" value=\"3\"/></sampler>");
    EXPECT_EQ(scene->sensor->sampler->type, SamplerType::Orthogonal);
    EXPECT_EQ(scene->sensor->sampler->sample_count, 25);
    EXPECT_FALSE(scene->sensor->sampler->jitter);
    EXPECT_EQ(scene->sensor->sampler->seed, 3u);
    EXPECT_EQ(load("<sampler type=\"ldsampler\"><integer name=\"sample_count\" value=\"8\"/></sampler>")
                  ->sensor->sampler->sample_count,
              16);
    auto expect_error = [&](const std::string& sampler, const std::string& words) {
        try {
            load(sampler);
            ADD_FAILURE() << sampler << " loaded";
        } catch (const LoadError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(words), std::string::npos) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        }
    };
    expect_error("<sampler type=\"orthogonal\"><integer name=\"strength\" value=\"3\"/></sampler>",
                 "strength");
    expect_error("<sampler type=\"ldsampler\"><boolean name=\"jitter\" value=\"false\"/></sampler>",
                 "jitter");
    expect_error("<sampler type=\"stratified\"><integer name=\"sample_count\" value=\"0\"/></sampler>",
                 "sample_count");
    expect_error("<sampler type=\"sobol\"/>", "unsupported sampler plugin 'sobol'");
}

namespace {

// Direct lighting of a diffuse floor by a rectangular area light, half of it in the soft shadow of a square
// occluder: the integrand varies smoothly within pixels, over the light and across the penumbra.
std::unique_ptr<Scene> penumbra_scene(const std::string& sampler, int spp) {
    return load_scene_string(R"(<scene version="3.0.0">
      <integrator type="direct"/>
      <sensor type="perspective"><float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0,3,0.01" target="0,0,0" up="0,1,0"/></transform>
        <sampler type=")" + sampler +
                             R"("><integer name="sample_count" value=")" + std::to_string(spp) +
                             R"("/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
      <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>
      <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="0.4"/>
          <translate value="0.4,0.8,0"/></transform><bsdf type="diffuse"/></shape>
      <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><scale value="0.5"/>
          <translate value="0.5,1.6,0"/></transform>
        <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
    </scene>)");
}

// Per-pixel variance over the batches, averaged over pixels and channels.
double mean_pixel_variance(const BatchStats& s, int batches) {
    double v = 0;
    for (const Color3f& e : s.stderr_img.pixels)
        v += (e.x * e.x + e.y * e.y + e.z * e.z) * batches;
    return v / (3.0 * s.stderr_img.pixels.size());
}

} // namespace

// (b) Each sampler's mean image matches `independent` within the standard errors, and (c) the stratified and
// low-discrepancy samplers lower the per-pixel variance at equal spp. 16 seeds: with 15 degrees of freedom
// P(|t| > 4) ~ 1e-3, so more than 3% of pixels beyond 4 standard errors, or an image-mean |z| > 4, is bias.
TEST(Samplers, UnbiasedAndLowerVarianceThanIndependent) {
    constexpr int batches = 16;
    for (const auto& [name, spp] : std::vector<std::pair<std::string, int>>{
             {"stratified", 16}, {"multijitter", 16}, {"ldsampler", 16}, {"orthogonal", 25}}) {
        const BatchStats ind = render_batches(*penumbra_scene("independent", spp), batches, 0, 1);
        const BatchStats st = render_batches(*penumbra_scene(name, spp), batches, 0, 1);
        const double z =
            (st.image_mean - ind.image_mean) / std::sqrt(st.image_mean_stderr * st.image_mean_stderr +
                                                         ind.image_mean_stderr * ind.image_mean_stderr);
        int outliers = 0, n = 0;
        for (size_t i = 0; i < st.mean.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                const double d = st.mean.pixels[i][c] - ind.mean.pixels[i][c];
                const double se = std::hypot(st.stderr_img.pixels[i][c], ind.stderr_img.pixels[i][c]);
                outliers += se > 0 ? std::abs(d) > 4 * se : d != 0;
                ++n;
            }
        const double ratio = mean_pixel_variance(st, batches) / mean_pixel_variance(ind, batches);
        std::printf("  %-11s %2d spp: image mean %.5f vs independent %.5f (z = %+.2f), pixels beyond 4 se: "
                    "%d/%d, var ratio %.3f\n",
                    name.c_str(), spp, st.image_mean, ind.image_mean, z, outliers, n, ratio);
        EXPECT_LT(std::abs(z), 4.0) << name;
        EXPECT_LT(outliers, n * 3 / 100) << name;
        // Each sampler stratifies the film and light-sample dimensions; measured ratios are far below 0.7.
        EXPECT_LT(ratio, 0.7) << name;
    }
}

// (d) The image is bit-identical whatever the thread count.
TEST(Samplers, RenderIsIndependentOfThreadCount) {
    for (const char* name : {"multijitter", "ldsampler", "orthogonal"}) {
        auto scene = penumbra_scene(name, 16);
        RenderOptions o;
        o.seed = 4;
        o.threads = 1;
        const Image one = render(*scene, o);
        o.threads = 2;
        const Image two = render(*scene, o);
        ASSERT_EQ(one.pixels.size(), two.pixels.size());
        EXPECT_EQ(std::memcmp(one.pixels.data(), two.pixels.data(), one.pixels.size() * sizeof(Color3f)), 0)
            << name;
    }
}

// The interior derivative estimator draws its per-pixel numbers from the scene's sampler: with a stratified
// or low-discrepancy sampler its derivative still matches central finite differences (same checks and
// tolerances as tests/test_diff_interior.cpp; the glossy plane and lights of that file's scene, no visibility
// change).
TEST(Samplers, InteriorDerivativeMatchesFiniteDifferences) {
    for (const char* name : {"multijitter", "ldsampler"}) {
        auto scene = load_scene_string(std::string(R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="3"/></integrator>
      <sensor type="perspective" id="cam"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0.5,3" target="0,0,0" up="0,1,0"/></transform>
        <sampler type=")") + name + R"("/>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
      <shape type="rectangle" id="plane"><transform name="to_world"><scale value="5"/></transform>
        <bsdf type="roughconductor" id="mat"><float name="alpha" value="0.3"/>
          <string name="distribution" value="ggx"/></bsdf></shape>
      <shape type="rectangle" id="light"><transform name="to_world"><scale value="1.2"/><rotate x="1" angle="135"/>
          <translate value="-0.5,2.6,1.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="0.6, 0.45, 0.3"/></emitter></shape>
      <emitter type="point" id="bulb"><point name="position" value="0.5,0.8,1.2"/><rgb name="intensity" value="3"/></emitter>
    </scene>)");
        Parameters params(*scene);
        params.enable({parse_param_selection("mat.alpha")});
        const DerivativePair r = derivative_and_fd(*scene, params, 16, 64, 1e-2);
        const DiffCheck c = check_against(r.derivative, r.fd);
        std::printf("  %s: %s\n", name, describe(c).c_str());
        EXPECT_TRUE(c.passes()) << name << ": " << describe(c);
        EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-4)
            << name << ": the reference derivative is ~0, a weak test";
    }
}
