// Boundary terms of the differential path integral (paper 001 Eq. 19) against finite differences on the
// validation scenes of scenes/validation/: interior + boundary must match, interior alone must visibly miss.
#include "diff/psdr.h"
#include "diff_check.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const std::string validation = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/";

struct BoundaryRun {
    PsdrDerivative d;
    FiniteDifference fd;
};

BoundaryRun run(const std::string& scene_file, const std::string& param, double h) {
    auto scene = load_scene(validation + scene_file, {{"res", "32"}});
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    PsdrOptions o;
    o.interior.spp = 16;
    o.interior.batches = 16;
    o.interior.seed = 11;
    o.interior.path = path_settings(*scene);
    o.primary_spp = 16;
    BoundaryRun r{psdr_derivative(*scene, params, o), {}};
    RenderOptions ro;
    ro.spp = 64;
    ro.seed = 99;
    r.fd = finite_difference(*scene, params, h, ro, 16);
    return r;
}

void expect_boundary_matters(const std::string& scene_file, const std::string& param, double h) {
    const BoundaryRun r = run(scene_file, param, h);
    const DiffCheck total = check_against(r.d.total, r.d.total_stderr, r.fd.derivative, r.fd.stderr_img);
    const DiffCheck interior = check_against(r.d.interior.derivative, r.d.interior.stderr_img, r.fd.derivative, r.fd.stderr_img);
    std::printf("  %s %s: interior+boundary %s\n  interior only %s\n", scene_file.c_str(), param.c_str(),
                describe(total).c_str(), describe(interior).c_str());
    EXPECT_TRUE(total.passes()) << param << ": " << describe(total);
    EXPECT_FALSE(interior.passes()) << param << ": the interior term alone should miss the silhouettes: " << describe(interior);
}

} // namespace

// Finite-difference steps move the silhouette by ~0.3 px at 32x32: with smaller steps only a few of an edge
// pixel's samples switch sides per batch, and the reference's batch means are too skewed for their standard
// errors; the O(h²) truncation error stays far below the noise.
TEST(PrimaryBoundary, RotatingCubeSilhouette) { expect_boundary_matters("silhouette.xml", "box.rotate=0,1,0", 3e-2); }

TEST(PrimaryBoundary, TranslatingCubeSilhouette) { expect_boundary_matters("silhouette.xml", "box.translate=1,0.5,0", 2e-2); }

// Reverse mode includes the boundary term: ⟨a, (interior + boundary) v⟩ = ⟨gradient, v⟩ on the same samples.
TEST(PrimaryBoundary, ReverseModeIncludesTheBoundaryTerm) {
    auto scene = load_scene(validation + "silhouette.xml", {{"res", "24"}});
    Parameters params(*scene);
    params.enable({parse_param_selection("box.translate=1,0,0")});
    PsdrOptions o;
    o.interior.spp = 4;
    o.interior.seed = 5;
    o.interior.path = path_settings(*scene);
    o.primary_spp = 8;
    // The same seeds as psdr_gradient uses for its single batch.
    const PsdrDerivative forward = psdr_derivative(*scene, params, o);
    Image adjoint(24, 24);
    PCG32 rng(3);
    for (auto& a : adjoint.pixels) a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
    const Gradient reverse = psdr_gradient(*scene, params, adjoint, o);
    double lhs = 0, scale = 0, boundary = 0;
    for (size_t i = 0; i < adjoint.pixels.size(); ++i) {
        lhs += dot(Vec3d(adjoint.pixels[i]), Vec3d(forward.total.pixels[i]));
        scale += std::abs(dot(Vec3d(adjoint.pixels[i]), Vec3d(forward.total.pixels[i])));
        boundary += std::abs(dot(Vec3d(adjoint.pixels[i]), Vec3d(forward.primary.pixels[i])));
    }
    EXPECT_GT(boundary, 0.05 * scale) << "the boundary term should be a sizeable part of this derivative";
    EXPECT_NEAR(lhs, reverse.values[0], 1e-4 * scale + 1e-6) << "⟨a, Jv⟩ = " << lhs << ", ⟨Jᵀa, v⟩ = " << reverse.values[0];
}
