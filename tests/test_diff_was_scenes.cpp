// The validation scenes of paper 004 (warped-area sampling, docs/warped-area-sampling.md) against central
// finite differences: a cube's silhouette, a rotating corkscrew's soft shadow and a dense hedge (220k
// triangles) seen in a glossy floor (scenes/was/suite.json). Each derivative method of `methods` below,
// through the method front (diff/method.h) as the command line and the optimizer reach it, at each scene's CI
// resolution, against the references that `penumbra ad-suite --fd-only` stored in scenes/was/fd (or, when a
// scene changed since, computed here at the same settings: slow; regenerate the cache as suite.json says).
// Tolerances come from standard errors (tests/diff_check.h: z of the image mean, relerr and relerr4 against
// their noise expectations, 4σ outliers of 2 × 2 blocks). Every parameter moves geometry, so psdr's interior
// term alone (the method's first term) must fail the same check: the boundary contribution carries visible
// signal.
#include "diff_cases.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const PaperSuite paper = paper_suite("was", "suite.json");

// The derivative methods checked on every scene. psdr's automatic first vertex picks the image-space form on
// the cube and the corkscrew; the material form is checked too (they differ on the corkscrew).
const std::vector<MethodCase> methods = {
    {"psdr", "psdr", {}},
    {"psdr_material", "psdr", {{"first-vertex", "material"}}},
    {"was", "was", {}},
    {"was_unbiased", "was", {{"was-unbiased", "true"}}},
};

class WasScene : public testing::TestWithParam<std::tuple<std::string, std::string>> {};

// Cases a method does not pass (reported as skipped, never as passed).
//
// psdr on hedge passed no test before the indirect term's camera technique (diff/psdr/indirect_boundary.cpp,
// diff/psdr/edge_tree.h): Algorithm 1 alone samples the hedge's ~440k edges by length and uniform directions,
// which almost never fall in the glossy floor's narrow lobe toward the camera, and its estimate was fireflies
// (256 spp: relerr4 7.6 against a noise expectation of 3.9, 61% of the pixels beyond 3σ, image mean −0.86
// against −0.12). Drawn from the camera side through an edge tree weighed by the floor's lobe, seeds 0–5
// pass (relerr4 0.92–1.50 against 1.13–1.33, |z| ≤ 2.0; the blocks' errors from the batches' block means).
//
// psdr on corkscrew passed no test before the primary term took the horizon creases of smooth shading
// (diff/psdr/primary_boundary.cpp, lune_may_be_lit): with the image-space first vertex (auto's choice here)
// every interior edge of the turning tube is an image discontinuity, the two faces hiding different
// half-spaces from the light. Before (4096 spp, seed 1): relerr4 0.082 against a noise expectation of 0.033,
// mean −0.00042 against FD +0.00001 (z −11.5); with them 0.038 and 0.034 against 0.032–0.033 (seeds 1, 2),
// means −0.00004 and +0.00002. At the CI budget seeds 0–3 pass (relerr4 0.086–0.130 against 0.091–0.095).
// was on hedge: the consistent estimate (N' = 32) is half the reference (256 spp: mean −0.058 against
// −0.123, z +7.6) and takes 175 s at 32 × 32 on two cores (auxiliary rays at every vertex among 220k
// triangles): measured in the study (docs/warped-area-sampling.md), not in CI.
// was on corkscrew: the paper's κ = 1e4 leaves the consistent estimate biased (1024 spp: relerr4 0.45 against
// a noise expectation of 0.32, z −3.4, 2.3% of the 2 × 2 blocks beyond 4σ; it was 0.63 against 0.37 before
// the boundary test took creases and the film warp the jackknife); its OPTIM-CORKSCREW used κ = 5e5 for that
// reason (§6). With κ = 1e5 the bias goes (before those changes: 1024 spp, relerr4 0.64 against 0.44, z −0.5)
// and heavier tails come: 3.9% of the 2 × 2 blocks beyond their batch standard errors' 4σ.
// The unbiased variant is checked on the corkscrew too.
const char* open_problem(const std::string& label, const std::string& scene) {
    if (label == "was_unbiased" && scene == "hedge")
        return "the unbiased warped-area estimate is too slow and heavy-tailed on the hedge at test budgets";
    if (label == "was" && scene == "corkscrew")
        return "the consistent warped-area estimate is biased on the corkscrew at kappa 1e4 (heavy-tailed above)";
    if (label == "was" && scene == "hedge")
        return "the consistent warped-area estimate is biased on the hedge at N' = 32, and slow at test "
               "budgets";
    return nullptr;
}

TEST_P(WasScene, MatchesFiniteDifferences) {
    const auto& [label, name] = GetParam();
    if (const char* why = open_problem(label, name)) GTEST_SKIP() << "open: " << why;
    const MethodCase* method = find_method_case(methods, label);
    ASSERT_NE(method, nullptr);
    const AdSuite suite = load_ad_suite(paper.manifest);
    const AdSuiteScene* found = find_suite_scene(suite, name);
    ASSERT_NE(found, nullptr);
    const AdSuiteScene& s = *found;
    ASSERT_TRUE(missing_files(s).empty()) << s.file << " needs " << missing_files(s).front()
                                          << " (the build writes it: scripts/make_was_meshes.py)";
    // was at 4 × the budget: its batches of 16 samples understate its heavy-tailed standard errors (4σ
    // outliers in 4% of the cube's blocks at 256 spp).
    const int spp = method->name == "was" ? 4 * s.spp : s.spp;
    check_suite_scene(paper, *method, suite, s, spp, {});
}

INSTANTIATE_TEST_SUITE_P(WasValidation, WasScene,
                         testing::Combine(testing::ValuesIn(method_labels(methods)),
                                          testing::ValuesIn(scene_names(paper.manifest))),
                         [](const testing::TestParamInfo<WasScene::ParamType>& info) {
                             return std::get<0>(info.param) + "_" + std::get<1>(info.param);
                         });

} // namespace
