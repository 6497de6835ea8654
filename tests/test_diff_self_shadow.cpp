// Validation scene (d) of the boundary terms (paper 001 Eq. 19): a vertex-position perturbation of a closed,
// concave mesh with self-shadowing (scenes/validation/self_shadow.xml). Interior + boundary terms must match
// central finite differences; the interior term alone must visibly miss the silhouettes and the moving shadow.
#include "diff/psdr/psdr.h"
#include "diff_check.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const std::string validation = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/";

// The non-rigid field of scene (d): every vertex p of the L-prism moves along d(p) = (0.3 y, 0.2 x, 0.15)
// (world coordinates). It shears and stretches the faces (their areas and normals change to first order).
std::vector<float> deformation_field(const Parameter& positions) {
    std::vector<float> d(size_t(positions.size));
    for (int v = 0; v < positions.size / 3; ++v) {
        const float* p = positions.data + 3 * v;
        d[3 * v] = 0.3f * p[1];
        d[3 * v + 1] = 0.2f * p[0];
        d[3 * v + 2] = 0.15f;
    }
    return d;
}

struct SelfShadowRun {
    DerivativeImage d;
    FiniteDifference fd;
    Image fd_error; // the reference's per-pixel standard error, with its detection limit and truncation error (diff_check.h)
};

SelfShadowRun run(const std::string& light, int interior_spp, int primary_spp, int direct_spp, int fd_spp, double h) {
    // PENUMBRA_TEST_SEED re-runs the checks with other random numbers (to see that they do not pass by luck).
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    const uint64_t seed = env ? std::strtoull(env, nullptr, 10) : 0;
    auto scene = load_scene(validation + "self_shadow.xml", {{"res", "32"}, {"light", light}});
    Parameters params(*scene);
    params.enable({{"lshape.vertex_positions", deformation_field(params.find("lshape.vertex_positions"))}});
    PsdrOptions o;
    o.interior.spp = interior_spp;
    o.interior.batches = 16;
    o.interior.seed = 11 + 1000 * seed;
    o.interior.path = path_settings(*scene);
    o.primary_spp = primary_spp;
    o.direct_spp = direct_spp;
    o.indirect_spp = 0; // max_depth 2: every boundary segment is a camera or an emitter segment
    SelfShadowRun r{psdr_derivative(*scene, params, o), {}, {}};
    RenderOptions ro;
    ro.spp = fd_spp;
    ro.seed = 99 + 1000 * seed;
    r.fd = finite_difference(*scene, params, h, ro, 16);
    r.fd_error = with_truncation_error(
        with_detection_limit(r.fd, r.d.primal, h, fd_spp * 16, scene->sensor->film->rfilter->radius()), r.fd,
        finite_difference(*scene, params, 2 * h, ro, 16));
    return r;
}

// interior + s × (boundary terms)
Image with_boundary_scaled(const DerivativeImage& d, float s) {
    const Image& interior = d.term("interior").derivative;
    Image out = interior;
    for (size_t i = 0; i < out.pixels.size(); ++i)
        out.pixels[i] += (d.derivative.pixels[i] - interior.pixels[i]) * s;
    return out;
}

} // namespace

// (d) The area light up left makes the vertical arm of the L shadow its horizontal arm and the floor; the field
// moves silhouettes (primary boundary term) and shadow edges (direct boundary term), and deforms the faces
// (interior term: moving points, normals and area Jacobians).
TEST(SelfShadow, VertexPerturbationOfAConcaveMesh) {
    const SelfShadowRun r = run("area", 16, 16, 64, 256, 2e-2);
    const DiffCheck total = check_against(r.d.derivative, r.d.stderr_img, r.fd.derivative, r.fd_error);
    const DiffCheck interior = check_against(r.d.term("interior").derivative, r.d.term("interior").stderr_img,
                                             r.fd.derivative, r.fd_error);
    const DiffCheck scaled =
        check_against(with_boundary_scaled(r.d, 0.8f), r.d.stderr_img, r.fd.derivative, r.fd_error);
    std::printf("  self_shadow.xml (area light): interior+boundary %s\n  interior only %s\n  boundary x0.8 %s\n",
                describe(total).c_str(), describe(interior).c_str(), describe(scaled).c_str());
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_GT(std::abs(interior.comparison.mean_z), 8.0) << "the interior term alone must miss the edges: " << describe(interior);
    EXPECT_GT(interior.comparison.relerr, 2.0 * interior.noise_relerr) << describe(interior);
    EXPECT_FALSE(scaled.passes()) << "negative control: boundary terms scaled by 0.8 must be rejected: " << describe(scaled);
}

// Regression: primary visibility alone under the same non-rigid field (a point light at the camera hides every
// shadow behind its caster; no direct boundary term). The background radiance next to a silhouette used to be
// probed 1e-3 px from the edge, closer than the ray offsets of the background point: its shadow ray back to the
// light at the camera clipped the occluder, L_bg read 0 on much of the floor and the image mean was off by z ~ 8.
TEST(SelfShadow, PrimaryBoundaryOfANonRigidFieldWithTheLightAtTheCamera) {
    const SelfShadowRun r = run("camera", 32, 32, 0, 256, 2e-2);
    const DiffCheck total = check_against(r.d.derivative, r.d.stderr_img, r.fd.derivative, r.fd_error);
    const DiffCheck interior = check_against(r.d.term("interior").derivative, r.d.term("interior").stderr_img,
                                             r.fd.derivative, r.fd_error);
    std::printf("  self_shadow.xml (light at the camera): interior+primary %s\n  interior only %s\n", describe(total).c_str(),
                describe(interior).c_str());
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(interior.passes()) << "the interior term alone must miss the silhouettes: " << describe(interior);
}
