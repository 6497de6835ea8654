// Differentiable participating media (paper 001) against central finite differences on the validation scenes
// of scenes/validation/media_suite.json (docs/differentiable-media.md): the default psdr derivative, through
// the method front (diff/method.h) as the command line and the optimizer reach it, at each scene's reduced CI
// resolution, against central differences rendered with the scene's own integrator (volpath or bdpt): the
// references that `penumbra ad-suite --fd-only` stored in scenes/validation/media_fd (tens of thousands of
// samples per pixel, too slow for a test), or, when a scene or its settings changed since, computed here at
// the same settings (slow; regenerate the cache as media_suite.json says). Tolerances come from standard
// errors (tests/diff_check.h: z of the image mean, relerr and relerr4 against their noise expectations, 4σ
// outliers of 2 × 2 blocks). Where the parameter moves geometry or a light, the interior term alone (the
// first term of the same run) must fail the same check: the boundary terms carry visible signal. `penumbra
// ad-suite --manifest scenes/validation/media_suite.json --cache scenes/validation/media_fd` reports the
// same.
#include "diff/method.h"
#include "diff/psdr/psdr.h"
#include "diff_cases.h"
#include "diff_check.h"
#include "studies/ad_suite.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const std::string manifest = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/media_suite.json";
const std::string reference_cache = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/media_fd";
// The seed of the stored references (penumbra ad-suite's): independent of the derivative's seeds below.
constexpr uint64_t ReferenceSeed = 2;

// Batches of the derivative: its per-pixel standard errors (t with 15 degrees of freedom, diff_check.h).
constexpr int DerivativeBatches = 16;


// Whether the enabled parameters move a shape, the camera or a light (visibility changes: boundary terms).
bool moves_something(const Parameters& params) {
    for (const auto& [p, index] : params.enabled())
        if (p->kind != Parameter::Kind::Data || p->geometry || p->emitter || p->sensor) return true;
    return false;
}

class MediaScene : public testing::TestWithParam<std::string> {};

TEST_P(MediaScene, MatchesFiniteDifferences) {
    const AdSuite suite = load_ad_suite(manifest);
    const AdSuiteScene* found = nullptr;
    for (const AdSuiteScene& s : suite.scenes)
        found = s.name == GetParam() ? &s : found;
    ASSERT_NE(found, nullptr);
    const AdSuiteScene& s = *found;
    const uint64_t seed = test_seed();
    AdSuiteCase c = load_case(s, s.ci_res);
    const FdSettings ref = fd_settings(suite, s, s.ci_res);
    const std::optional<FiniteDifference> stored =
        read_cached_reference(reference_cache, s, s.ci_res, ref.eps, ref.spp, {}, ReferenceSeed);
    if (!stored)
        std::printf("  %s: no stored reference matches the scene; computing it (slow)\n", s.name.c_str());
    const FiniteDifference fd =
        stored ? *stored
               : suite_reference(*c.scene, *c.params, ref.eps, ref.spp, ReferenceSeed + 1000 * seed, 0);

    MethodRun run;
    run.spp = s.spp;
    run.batches = DerivativeBatches;
    run.seed = 1 + 1000 * seed;
    const DerivativeImage d = make_method("psdr", MethodOptions())->derivative(*c.scene, *c.params, run);
    ASSERT_FALSE(d.terms.empty());
    ASSERT_EQ(d.terms[0].name, "interior");
    const DiffCheck total = check_against(d, fd);
    const DiffCheck interior =
        check_against(d.terms[0].derivative, d.terms[0].stderr_img, fd.derivative, fd.stderr_img);
    std::printf("  %s at %dx%d, psdr %d spp (%.2f s, %s), reference h = %g at %d spp per side (%.0f s%s)\n"
                "  psdr:          %s\n  interior only: %s\n",
                s.name.c_str(), s.ci_res, s.ci_res, s.spp, d.seconds, d.description.c_str(), ref.eps, ref.spp,
                fd.seconds, stored ? ", stored" : "", describe(total).c_str(), describe(interior).c_str());

    EXPECT_TRUE(total.passes()) << describe(total);
    if (moves_something(*c.params)) {
        EXPECT_FALSE(interior.passes())
            << "the interior term alone should miss what the boundary terms add: " << describe(interior);
    }
}

INSTANTIATE_TEST_SUITE_P(MediaValidation, MediaScene, testing::ValuesIn(scene_names(manifest)),
                         [](const testing::TestParamInfo<std::string>& info) { return info.param; });

// Forward and reverse mode on the same samples (psdr_gradient uses the seeds of psdr_derivative's single
// batch): ⟨a, Jv⟩ (adjoint · derivative image) = ⟨Jᵀa, v⟩ (gradient · direction) up to rounding, for every
// term.
void expect_reverse_matches_forward(const std::string& name, int res, int interior_spp, int boundary_spp) {
    const AdSuite suite = load_ad_suite(manifest);
    for (const AdSuiteScene& s : suite.scenes) {
        if (s.name != name) continue;
        AdSuiteCase c = load_case(s, res);
        PsdrOptions o;
        o.interior.spp = interior_spp;
        o.interior.seed = 5;
        o.interior.path = path_settings(*c.scene);
        o.primary_spp = o.direct_spp = o.indirect_spp = boundary_spp;
        o.pixel_spp = 0;
        const DerivativeImage forward = psdr_derivative(*c.scene, *c.params, o);
        Image adjoint(res, res);
        PCG32 rng(3);
        for (auto& a : adjoint.pixels)
            a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
        const Gradient reverse = psdr_gradient(*c.scene, *c.params, adjoint, o);
        const AdjointPair p =
            adjoint_pair(adjoint, forward.derivative, reverse.values, c.params->direction());
        std::printf("  %s: <a, Jv> = %.6g, <J^T a, v> = %.6g (scale %.3g)\n", name.c_str(), p.forward,
                    p.reverse, p.scale);
        EXPECT_GT(p.scale, 0.0) << "a zero derivative tests nothing";
        EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale + 1e-7);
        return;
    }
    FAIL() << "no scene " << name << " in " << manifest;
}

TEST(MediaValidation, ReverseModeMatchesForwardModeHeterogeneousShadows) {
    expect_reverse_matches_forward("branches", 16, 4, 4);
}

TEST(MediaValidation, ReverseModeMatchesForwardModeMediumParameters) {
    expect_reverse_matches_forward("smoke_scale", 16, 4, 0);
    expect_reverse_matches_forward("fog_g", 16, 4, 0);
}

// The bidirectional interior (bdpt scene) and boundary segments ending at a moving point light.
TEST(MediaValidation, ReverseModeMatchesForwardModeLightTranslation) {
    expect_reverse_matches_forward("bumpy_sphere", 8, 4, 4);
}

TEST(MediaValidation, ReverseModeMatchesForwardModeTranslucent) {
    expect_reverse_matches_forward("translucent", 16, 4, 4);
}

} // namespace
