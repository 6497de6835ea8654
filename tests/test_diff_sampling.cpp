// Path sampling methods (paper 002) against central finite differences: BSDF and differential sampling, each
// with and without next-event estimation, for GGX and Beckmann roughness and a blend weight, on a scene with
// interreflection (a glossy floor facing a diffuse wall); adaptive pixel sampling of the loss gradient; forward
// against reverse mode; determinism across thread counts; a negative control; rejected parameters.
#include "diff/paths/path_sampling.h"
#include "diff_check.h"
#include "render_stats.h"

#include <gtest/gtest.h>

#include <map>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A floor (the BSDF under test) facing a diffuse wall, lit by a large, dim area light above and out of view:
// paths of up to 3 bounces (max_depth 4) carry floor ↔ wall interreflection; the large light keeps the
// per-sample distribution light-tailed without NEE too.
std::string scene_xml(const std::string& floor_bsdf) {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="4"/></integrator>
      <sensor type="perspective" id="cam"><float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0,1,3.5" target="0,0.3,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="20"/><integer name="height" value="20"/></film></sensor>
      <shape type="rectangle" id="floor"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>)" +
           floor_bsdf + R"(</shape>
      <shape type="rectangle" id="wall"><transform name="to_world"><scale value="3"/><translate value="0,0,-1.5"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6,0.5,0.4"/></bsdf></shape>
      <shape type="rectangle" id="light"><transform name="to_world"><scale value="2.5"/><rotate x="1" angle="90"/>
          <translate value="0,3,0.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="1.2"/></emitter></shape>
    </scene>)";
}

const char* const GGX = R"(<bsdf type="roughconductor" id="mat"><float name="alpha" value="0.25"/>
    <string name="distribution" value="ggx"/></bsdf>)";
const char* const Beckmann = R"(<bsdf type="roughconductor" id="mat"><float name="alpha" value="0.25"/>
    <string name="distribution" value="beckmann"/></bsdf>)";
const char* const Blend = R"(<bsdf type="blendbsdf" id="mix"><float name="weight" value="0.4"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
    <bsdf type="roughconductor"><float name="alpha" value="0.15"/><string name="distribution" value="ggx"/></bsdf></bsdf>)";

uint64_t test_seed() {
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    return env ? std::strtoull(env, nullptr, 10) : 0;
}

// FD references, computed once per (scene, parameter) and shared by the variants.
const FiniteDifference& reference(const std::string& bsdf, const std::string& param) {
    static std::map<std::string, FiniteDifference> cache;
    auto it = cache.find(bsdf + param);
    if (it != cache.end()) return it->second;
    auto scene = load_scene_string(scene_xml(bsdf));
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    RenderOptions ro;
    ro.spp = 192;
    ro.seed = 1234 + 1000 * test_seed();
    return cache[bsdf + param] = finite_difference(*scene, params, 1e-2, ro, 16);
}

PathSamplingOptions options(const Scene& scene, bool differential, bool nee) {
    PathSamplingOptions o;
    o.spp = 32;
    o.batches = 16;
    o.seed = 7 + 1000 * test_seed();
    o.path = path_settings(scene);
    o.differential = differential;
    o.nee = nee;
    return o;
}

void expect_matches_fd(const std::string& bsdf, const std::string& param, bool differential, bool nee) {
    auto scene = load_scene_string(scene_xml(bsdf));
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    const DerivativeImage d = path_sampling_derivative(*scene, params, options(*scene, differential, nee));
    const FiniteDifference& fd = reference(bsdf, param);
    const DiffCheck c = check_against(d, fd);
    const std::string name = param + (differential ? " differential" : " bsdf") + (nee ? " +nee" : " -nee");
    EXPECT_TRUE(c.passes()) << name << ": " << describe(c);
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-4) << name << ": the reference derivative is ~0, a weak test";
    std::printf("  %-28s %s (%.2f s)\n", name.c_str(), describe(c).c_str(), d.seconds);
}

} // namespace

class PathSamplingFD : public testing::TestWithParam<std::tuple<int, bool, bool>> {};

TEST_P(PathSamplingFD, MatchesFiniteDifferences) {
    const auto [which, differential, nee] = GetParam();
    const char* bsdf = which == 0 ? GGX : which == 1 ? Beckmann : Blend;
    expect_matches_fd(bsdf, which == 2 ? "mix.weight" : "mat.alpha", differential, nee);
}

using VariantParam = testing::TestParamInfo<PathSamplingFD::ParamType>;
std::string variant_name(const VariantParam& info) {
    const char* names[] = {"GgxAlpha", "BeckmannAlpha", "BlendWeight"};
    return std::string(names[std::get<0>(info.param)]) + (std::get<1>(info.param) ? "_Differential" : "_Bsdf") +
           (std::get<2>(info.param) ? "_Nee" : "_NoNee");
}

INSTANTIATE_TEST_SUITE_P(Variants, PathSamplingFD, testing::Combine(testing::Values(0, 1, 2), testing::Bool(), testing::Bool()),
                         variant_name);

// The checker must be able to fail: the differential-sampling derivative scaled by 0.8 is rejected.
TEST(PathSampling, CheckerRejectsAWrongDerivative) {
    auto scene = load_scene_string(scene_xml(GGX));
    Parameters params(*scene);
    params.enable({parse_param_selection("mat.alpha")});
    DerivativeImage d = path_sampling_derivative(*scene, params, options(*scene, true, true));
    for (auto& p : d.derivative.pixels) p *= 0.8f;
    for (auto& p : d.stderr_img.pixels) p *= 0.8f;
    const FiniteDifference& fd = reference(GGX, "mat.alpha");
    const DiffCheck c = check_against(d, fd);
    EXPECT_FALSE(c.passes()) << describe(c);
}

// ⟨a, Jv⟩ = ⟨Jᵀa, v⟩: the forward-mode image and the reverse-mode gradient replay the same paths with the same
// local derivatives, so they agree to rounding — with differential sampling, NEE and adaptive pixel counts.
TEST(PathSampling, ForwardAndReverseModeAreAdjoint) {
    auto scene = load_scene_string(scene_xml(Blend));
    Parameters params(*scene);
    params.enable({parse_param_selection("mix.weight=1"), parse_param_selection("wall.bsdf.reflectance=0.3,0.2,0.1"),
                   parse_param_selection("light.emitter.radiance=0.5,0.5,0.5")});
    const Film& film = *scene->sensor->film;
    Image adjoint(film.width, film.height);
    PCG32 rng(5);
    for (auto& a : adjoint.pixels) a = Color3f(rng.next_float() - 0.5f, rng.next_float() - 0.3f, rng.next_float() - 0.5f);
    PathSamplingOptions o = options(*scene, true, true);
    o.spp = 4;
    o.batches = 1;
    o.adaptive = true;
    const DerivativeImage forward = path_sampling_derivative(*scene, params, o, adjoint);
    const Gradient reverse = path_sampling_gradient(*scene, params, adjoint, o);
    const AdjointPair p = adjoint_pair(adjoint, forward.derivative, reverse.values, params.direction());
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale) << "⟨a, Jv⟩ = " << p.forward << ", ⟨Jᵀa, v⟩ = " << p.reverse;
    EXPECT_GT(p.scale, 1e-4);
}

// Adaptive pixel sampling (Algorithm 2) keeps the loss gradient unbiased: for an L2 loss the adjoint is affine
// in I, so E[dL/dθ] = Σ_j ∂L/∂I_j(I) · ∂I_j/∂θ, compared with the same sum over a high-spp image and the FD
// derivative; the tolerance combines the batch standard error of the estimate with the reference's.
TEST(PathSampling, AdaptiveLossGradientMatchesFiniteDifferences) {
    auto scene = load_scene_string(scene_xml(GGX));
    Parameters params(*scene);
    params.enable({parse_param_selection("mat.alpha")});
    // The target: the same scene with a rougher floor.
    auto target_scene = load_scene_string(scene_xml(GGX));
    Parameters target_params(*target_scene);
    target_params.enable({parse_param_selection("mat.alpha")});
    target_params.set_values(*target_scene, {0.4f, 0.4f, 0.4f});
    const BatchStats target = render_batches(*target_scene, 1, 256, 99);
    const BatchStats image = render_batches(*scene, 8, 64, 17);
    const FiniteDifference& fd = reference(GGX, "mat.alpha");
    const LossResult loss = l2_loss(image.mean, target.mean);
    double expected = 0, var_expected = 0;
    const double n = 3.0 * double(image.mean.pixels.size());
    for (size_t i = 0; i < fd.derivative.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const double a = loss.adjoint.pixels[i][k], d = fd.derivative.pixels[i][k];
            expected += a * d;
            var_expected += sqr(a * fd.stderr_img.pixels[i][k]) + sqr(2.0 / n * image.stderr_img.pixels[i][k] * d);
        }
    for (bool differential : {false, true}) {
        PathSamplingOptions o = options(*scene, differential, true);
        o.spp = 8;
        o.adaptive = true;
        const Gradient g = path_sampling_loss_gradient(*scene, params, target.mean, LossKind::L2, o);
        // dL/dθ along the parameter's direction, per batch (the three scalars come from the same paths).
        std::vector<double> batch;
        for (const auto& values : g.batch_values) {
            double v = 0;
            for (int k = 0; k < params.dimension(); ++k) v += values[k] * params.direction()[k];
            batch.push_back(v);
        }
        double mean = 0, var = 0;
        for (double v : batch) mean += v / double(batch.size());
        for (double v : batch) var += sqr(v - mean) / double(batch.size() - 1);
        const double se = std::sqrt(var / double(batch.size()));
        const double z = (mean - expected) / std::sqrt(se * se + var_expected);
        std::printf("  adaptive loss gradient (%s): %.6g vs %.6g (z %.2f, se %.3g, ref se %.3g)\n",
                    differential ? "differential" : "bsdf", mean, expected, z, se, std::sqrt(var_expected));
        EXPECT_LT(std::abs(z), 4.0);
        EXPECT_GT(std::abs(expected), 4.0 * std::sqrt(var_expected)) << "the reference is not significant: a weak test";
    }
}

TEST(PathSampling, SameResultForAnyThreadCount) {
    auto scene = load_scene_string(scene_xml(Blend));
    Parameters params(*scene);
    params.enable({parse_param_selection("mix.weight")});
    const Film& film = *scene->sensor->film;
    Image adjoint(film.width, film.height, Color3f(0.1f, -0.2f, 0.3f));
    PathSamplingOptions o = options(*scene, true, true);
    o.spp = 2;
    o.batches = 1;
    o.threads = 1;
    const Gradient one = path_sampling_gradient(*scene, params, adjoint, o);
    o.threads = 2;
    const Gradient two = path_sampling_gradient(*scene, params, adjoint, o);
    EXPECT_EQ(one.values, two.values);
}

TEST(PathSampling, RejectsGeometricParameters) {
    auto scene = load_scene_string(scene_xml(GGX));
    Parameters params(*scene);
    params.enable({parse_param_selection("floor.translate=0,1,0")});
    EXPECT_THROW(path_sampling_derivative(*scene, params, options(*scene, true, true)), Error);
    params.enable({parse_param_selection("floor.vertex_positions=0,1,0")});
    EXPECT_THROW(path_sampling_derivative(*scene, params, options(*scene, true, true)), Error);
}
