// Image derivatives with respect to the principled and principledthin parameters against central finite
// differences (tests/diff_check.h), and forward against reverse mode.
#include "diff_check.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cstdio>

using namespace penumbra;
using namespace penumbra::test;

namespace {
// A principled plane filling the view under a point light and a large dim area light out of view (the scene
// of test_diff_interior.cpp): no visibility changes, so the interior term is the whole derivative.
std::string diff_scene(const std::string& bsdf) {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="3"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0.5,3" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
      <shape type="rectangle"><transform name="to_world"><scale value="5"/></transform>)" +
           bsdf + R"(</shape>
      <shape type="rectangle"><transform name="to_world"><scale value="1.2"/><rotate x="1" angle="135"/>
          <translate value="-0.5,2.6,1.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="0.6, 0.45, 0.3"/></emitter></shape>
      <emitter type="point"><point name="position" value="0.5,0.8,1.2"/><rgb name="intensity" value="3"/></emitter>
    </scene>)";
}
const char* kPrincipledPlane =
    R"(<bsdf type="principled" id="mat"><rgb name="base_color" value="0.7,0.5,0.3"/>
    <float name="roughness" value="0.4"/><float name="metallic" value="0.3"/><float name="specular" value="0.6"/>
    <float name="spec_tint" value="0.3"/><float name="sheen" value="0.3"/><float name="clearcoat" value="0.5"/>
    <float name="clearcoat_gloss" value="0.5"/></bsdf>)";

const char* kThinPlane = R"(<bsdf type="principledthin" id="mat"><rgb name="base_color" value="0.7,0.5,0.3"/>
    <float name="roughness" value="0.4"/><float name="spec_trans" value="0.5"/><float name="diff_trans" value="0.6"/>
    <float name="eta" value="1.4"/><float name="sheen" value="0.3"/><float name="spec_tint" value="0.3"/></bsdf>)";

const char* kThinSpecularPlane =
    R"(<bsdf type="principledthin" id="mat"><rgb name="base_color" value="0.7,0.5,0.3"/>
    <float name="roughness" value="0.4"/><float name="spec_trans" value="1"/><float name="eta" value="1.4"/></bsdf>)";

// The derivative along a direction over one or more parameters ("name" or "name=v1,v2,..."), against FD.
void expect_matches_fd(const std::string& xml, const std::vector<std::string>& selection, double h,
                       int spp = 16) {
    auto scene = load_scene_string(xml);
    Parameters params(*scene);
    std::vector<std::pair<std::string, std::vector<float>>> parsed;
    std::string what;
    for (const std::string& s : selection) {
        parsed.push_back(parse_param_selection(s));
        what += (what.empty() ? "" : " + ") + s;
    }
    params.enable(parsed);
    const DerivativePair r = derivative_and_fd(*scene, params, spp, 2 * spp, h);
    const DiffCheck c = check_against(r.derivative, r.fd);
    EXPECT_TRUE(c.passes()) << what << ": " << describe(c);
    std::printf("  %s: %s\n", what.c_str(), describe(c).c_str());
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-4)
        << what << ": the reference derivative is ~0, a weak test";
}
} // namespace

TEST(PrincipledDerivative, BaseColor) {
    expect_matches_fd(diff_scene(kPrincipledPlane), {"mat.base_color=1,0.5,0"}, 1e-2);
}
TEST(PrincipledDerivative, Roughness) {
    expect_matches_fd(diff_scene(kPrincipledPlane), {"mat.roughness"}, 1e-2);
}
TEST(PrincipledDerivative, Metallic) {
    expect_matches_fd(diff_scene(kPrincipledPlane), {"mat.metallic"}, 1e-2);
}
TEST(PrincipledDerivative, Specular) {
    expect_matches_fd(diff_scene(kPrincipledPlane), {"mat.specular"}, 1e-2);
}
TEST(PrincipledDerivative, EtaOfATransmissiveMaterial) {
    expect_matches_fd(
        diff_scene(R"(<bsdf type="principled" id="mat"><rgb name="base_color" value="0.7,0.5,0.3"/>
        <float name="roughness" value="0.3"/><float name="eta" value="1.4"/><float name="spec_trans" value="0.6"/></bsdf>)"),
        {"mat.eta"}, 1e-2);
}
// The roughness of a purely specular sheet. (In the mixed sheet, the specular and retro-reflection parts of
// ∂/∂roughness partly cancel and the image is mostly noise: at 16 spp 2-5% of its 2 × 2 blocks fall beyond
// the 16-batch 4σ, 1% at 64 spp, with |z| < 3 of both signs over seeds: heavy tails, not a bias.)
TEST(PrincipledDerivative, ThinRoughness) {
    expect_matches_fd(diff_scene(kThinSpecularPlane), {"mat.roughness"}, 1e-2);
}
TEST(PrincipledDerivative, ThinSpecTrans) {
    expect_matches_fd(diff_scene(kThinPlane), {"mat.spec_trans"}, 1e-2);
}

// The remaining lobe parameters at once (one directional derivative; the directions make the terms add up
// rather than cancel in the image mean).
TEST(PrincipledDerivative, OtherLobeParameters) {
    expect_matches_fd(diff_scene(kPrincipledPlane),
                      {"mat.clearcoat", "mat.clearcoat_gloss=-1,-1,-1", "mat.sheen", "mat.sheen_tint",
                       "mat.spec_tint", "mat.anisotropic", "mat.flatness", "mat.spec_trans=-1,-1,-1"},
                      1e-2);
}
TEST(PrincipledDerivative, ThinOtherParameters) {
    expect_matches_fd(diff_scene(kThinPlane),
                      {"mat.eta", "mat.diff_trans=-1,-1,-1", "mat.base_color=1,0.5,0", "mat.sheen",
                       "mat.flatness", "mat.anisotropic", "mat.spec_tint"},
                      1e-2);
}

// Forward and reverse mode on the same samples: ⟨a, Jv⟩ = ⟨Jᵀa, v⟩ for the principled parameters.
TEST(PrincipledDerivative, ForwardAndReverseModeAreAdjoint) {
    auto scene = load_scene_string(diff_scene(kPrincipledPlane));
    Parameters params(*scene);
    params.enable({parse_param_selection("mat.base_color=1,0.5,0.25"), parse_param_selection("mat.roughness"),
                   parse_param_selection("mat.metallic"), parse_param_selection("mat.specular"),
                   parse_param_selection("mat.clearcoat"), parse_param_selection("mat.sheen")});
    DiffOptions o;
    o.spp = 4;
    o.seed = 3;
    o.path = path_settings(*scene);
    const DerivativeImage forward = render_derivative(*scene, params, o);
    Image adjoint(24, 24);
    PCG32 rng(5);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    const Gradient reverse = render_gradient(*scene, params, adjoint, o);
    const AdjointPair p = adjoint_pair(adjoint, forward.derivative, reverse.values, params.direction());
    // Both sums are over the same tape products in float: agreement to ~1e-5 of the sum of magnitudes.
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale)
        << "⟨a, Jv⟩ = " << p.forward << ", ⟨Jᵀa, v⟩ = " << p.reverse;
    EXPECT_GT(p.scale, 1e-3);
}
