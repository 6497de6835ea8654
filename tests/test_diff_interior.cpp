// The interior term of the material-form differential path integral (paper 001 §5.1) against central finite
// differences, for material, emitter and geometric parameters in scenes without visibility changes; forward
// and reverse mode against each other; the estimator's primal against the renderer.
#include "diff_check.h"
#include "render_stats.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A glossy plane filling the view, lit by a point light and by a large, dim area light above and out of view:
// no silhouette and no shadow in view, so none of the tested motions changes visibility (the interior term is
// the whole derivative; sample_border keeps the pixel filters whole, so that the film's edge does not cut
// them either, a jump under camera motion that the pixel-boundary term handles). A large dim light keeps the
// per-sample distribution light-tailed, which the 16-batch standard errors of the checks need.
std::string scene_xml(const std::string& plane_bsdf = "") {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="3"/></integrator>
      <sensor type="perspective" id="cam"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0.5,3" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
          <boolean name="sample_border" value="true"/></film></sensor>
      <shape type="rectangle" id="plane"><transform name="to_world"><scale value="5"/></transform>)" +
           (plane_bsdf.empty()
                ? std::string(R"(<bsdf type="roughconductor" id="mat"><float name="alpha" value="0.3"/>
          <string name="distribution" value="ggx"/></bsdf>)")
                : plane_bsdf) +
           R"(</shape>
      <shape type="rectangle" id="light"><transform name="to_world"><scale value="1.2"/><rotate x="1" angle="135"/>
          <translate value="-0.5,2.6,1.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="0.6, 0.45, 0.3"/></emitter></shape>
      <emitter type="point" id="bulb"><point name="position" value="0.5,0.8,1.2"/><rgb name="intensity" value="3"/></emitter>
    </scene>)";
}

void expect_matches_fd(const std::string& xml, const std::string& param, double h, int spp = 16) {
    auto scene = load_scene_string(xml);
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    const DerivativePair r = derivative_and_fd(*scene, params, spp, 2 * spp, h);
    const DiffCheck c = check_against(r.derivative, r.fd);
    EXPECT_TRUE(c.passes()) << param << ": " << describe(c);
    std::printf("  %s: %s\n", param.c_str(), describe(c).c_str());
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-4) << param << ": the reference derivative is ~0, a weak test";
}

} // namespace

TEST(InteriorDerivative, RoughnessOfAGlossyPlane) { expect_matches_fd(scene_xml(), "mat.alpha", 1e-2); }

TEST(InteriorDerivative, DiffuseReflectance) {
    expect_matches_fd(scene_xml(R"(<bsdf type="diffuse" id="mat"><rgb name="reflectance" value="0.6,0.5,0.4"/></bsdf>)"),
                      "mat.reflectance=1,0.5,0", 1e-2);
}

TEST(InteriorDerivative, BlendWeight) {
    expect_matches_fd(scene_xml(R"(<bsdf type="blendbsdf" id="mix"><float name="weight" value="0.4"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
        <bsdf type="roughconductor"><float name="alpha" value="0.2"/><string name="distribution" value="ggx"/></bsdf>
        </bsdf>)"),
                      "mix.weight", 1e-2);
}

TEST(InteriorDerivative, IorOfRoughGlass) {
    expect_matches_fd(scene_xml(R"(<bsdf type="roughdielectric" id="glass"><float name="alpha" value="0.3"/>
        <string name="distribution" value="ggx"/></bsdf>)"),
                      "glass.eta", 1e-2);
}

TEST(InteriorDerivative, AreaLightRadiance) { expect_matches_fd(scene_xml(), "light.emitter.radiance", 1e-2); }

TEST(InteriorDerivative, PointLightIntensity) { expect_matches_fd(scene_xml(), "bulb.intensity", 1e-2); }

TEST(InteriorDerivative, PlaneMovingAlongItsNormal) { expect_matches_fd(scene_xml(), "plane.translate=0,0,1", 1e-2); }

TEST(InteriorDerivative, PlaneRotating) { expect_matches_fd(scene_xml(), "plane.rotate=1,0,0", 1e-2); }

TEST(InteriorDerivative, VertexPositions) {
    // All four vertices of the plane move along +z: the same motion as a translation, through the mesh data.
    expect_matches_fd(scene_xml(), "plane.vertex_positions=0,0,1", 1e-2);
}

TEST(InteriorDerivative, CameraTranslation) { expect_matches_fd(scene_xml(), "cam.translate=1,0,0", 1e-2); }

// The checker must be able to fail: the correct derivative scaled by 0.8 (a missing 20% term) is rejected.
TEST(InteriorDerivative, CheckerRejectsAWrongDerivative) {
    auto scene = load_scene_string(scene_xml());
    Parameters params(*scene);
    params.enable({parse_param_selection("plane.translate=0,0,1")});
    DerivativePair r = derivative_and_fd(*scene, params, 16, 32, 1e-2);
    for (auto& p : r.derivative.derivative.pixels) p *= 0.8f;
    for (auto& p : r.derivative.stderr_img.pixels) p *= 0.8f;
    const DiffCheck c = check_against(r.derivative, r.fd);
    EXPECT_FALSE(c.passes()) << describe(c);
}

// ⟨a, J v⟩ = ⟨Jᵀ a, v⟩: forward and reverse mode on the same samples agree to rounding.
TEST(InteriorDerivative, ForwardAndReverseModeAreAdjoint) {
    auto scene = load_scene_string(scene_xml());
    Parameters params(*scene);
    params.enable({parse_param_selection("mat.alpha=1,0.5,0.25"), parse_param_selection("bulb.intensity=0.3,0.2,0.1"),
                   parse_param_selection("plane.translate=0,0,1"), parse_param_selection("plane.vertex_positions=0.1,0.2,0.3")});
    DiffOptions o;
    o.spp = 4;
    o.seed = 3;
    o.path = path_settings(*scene);
    const DerivativeImage forward = render_derivative(*scene, params, o);
    Image adjoint(24, 24);
    PCG32 rng(5);
    for (auto& a : adjoint.pixels) a = Color3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    const Gradient reverse = render_gradient(*scene, params, adjoint, o);
    const AdjointPair p = adjoint_pair(adjoint, forward.derivative, reverse.values, params.direction());
    // Both sums are over the same tape products in float: agreement to ~1e-5 of the sum of magnitudes.
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale) << "⟨a, Jv⟩ = " << p.forward << ", ⟨Jᵀa, v⟩ = " << p.reverse;
    EXPECT_GT(p.scale, 1e-3);
}

// The derivative estimator's own primal (same samples, detached) is an unbiased estimate of the image.
TEST(InteriorDerivative, PrimalOfTheEstimatorMatchesTheRenderer) {
    auto scene = load_scene_string(scene_xml());
    Parameters params(*scene);
    params.enable({parse_param_selection("mat.alpha")});
    DiffOptions o;
    o.spp = 8;
    o.batches = 16;
    o.path = path_settings(*scene);
    const DerivativeImage d = render_derivative(*scene, params, o);
    const BatchStats s = render_batches(*scene, 16, 8);
    double mean = 0;
    for (const auto& p : d.primal.pixels) mean += (p.x + p.y + p.z) / 3.0;
    mean /= d.primal.pixels.size();
    // The primal's batch spread is not recorded; its variance is comparable to the renderer's: use √2 × stderr.
    EXPECT_LT(std::abs(mean - s.image_mean), 4.0 * std::sqrt(2.0) * s.image_mean_stderr)
        << "estimator primal " << mean << " vs renderer " << s.image_mean;
}

// Pixel-level antithetic sampling (paper 001 Fig. 6) cancels the odd filter-derivative term of a motion.
TEST(InteriorDerivative, AntitheticSamplingReducesVariance) {
    auto scene = load_scene_string(scene_xml());
    Parameters params(*scene);
    params.enable({parse_param_selection("cam.translate=1,0,0")});
    DiffOptions o;
    o.spp = 8;
    o.batches = 16;
    o.path = path_settings(*scene);
    const DerivativeImage with = render_derivative(*scene, params, o);
    o.antithetic = false;
    const DerivativeImage without = render_derivative(*scene, params, o);
    double v_with = 0, v_without = 0;
    for (size_t i = 0; i < with.stderr_img.pixels.size(); ++i) {
        v_with += squared_norm(with.stderr_img.pixels[i]);
        v_without += squared_norm(without.stderr_img.pixels[i]);
    }
    // Each variance estimate has ~15 dof per pixel over 1728 pixel channels: a factor 2 is far beyond noise.
    EXPECT_LT(v_with, 0.5 * v_without) << "variance with antithetic " << v_with << ", without " << v_without;
}
