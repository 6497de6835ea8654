// The interior term with participating media (paper 001 §5.1; src/render/volpath_tracer.h) against central
// finite differences of the volpath renderer: derivatives w.r.t. σt, albedo and the HG g of a homogeneous and
// of a heterogeneous medium (its scale and its grid's voxels, `<volume>.data`) (through the free-flight and ratio-tracking re-evaluations of
// render/flight_record.h), and a surface parameter seen through a medium; forward and reverse mode adjoint;
// the float instantiation of the estimator agrees with the renderer.
#include "diff_check.h"
#include "media_test_util.h"
#include "render/volpath_tracer.h"
#include "render_stats.h"
#include "xml_test_util.h"

#include "core/rng.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A fog-filled box (null boundary) over a floor, lit by an area light outside it. `medium` declares id "fog".
// volpathmis renders the FD references: per-path spectral MIS keeps their weights bounded (volpath's
// per-segment MIS compounds over segments, and heavy tails make batch standard errors unreliable).
std::string fog_scene(const std::string& medium, int size = 16) {
    return R"(<scene version="3.0.0">
      <integrator type="volpathmis"><integer name="max_depth" value="6"/></integrator>)" +
           medium + R"(
      <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value=")" +
           std::to_string(size) + R"("/><integer name="height" value=")" + std::to_string(size) + R"("/>
          <rfilter type="gaussian"/></film>
      </sensor>
      <shape type="cube" id="box"><bsdf type="null"/><ref name="interior" id="fog"/></shape>
      <shape type="rectangle" id="floor">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/><translate value="0,-1.2,0"/></transform>
        <bsdf type="diffuse" id="floor_bsdf"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf>
      </shape>
      <shape type="rectangle" id="light">
        <transform name="to_world"><rotate x="1" angle="90"/><scale value="0.5"/><translate value="0.3,1.8,0.2"/></transform>
        <emitter type="area"><rgb name="radiance" value="12, 12, 12"/></emitter>
      </shape>
    </scene>)";
}

const std::string kHomogeneous = R"(<medium type="homogeneous" id="fog">
        <rgb name="sigma_t" value="0.8, 0.6, 0.4"/><rgb name="albedo" value="0.8, 0.7, 0.6"/>
        <phase type="hg"><float name="g" value="0.3"/></phase></medium>)";

const std::string kHeterogeneous = R"(<medium type="heterogeneous" id="fog">
        <volume type="gridvolume" name="sigma_t" id="density"><string name="filename" value="density.vol"/></volume>
        <float name="scale" value="0.8"/><rgb name="albedo" value="0.8, 0.7, 0.6"/>
        <phase type="hg"><float name="g" value="0.3"/></phase></medium>)";

// A smooth blob of density over the box [-1, 1]³.
void write_density(const TempDir& dir) {
    write_bytes(dir.str() + "/density.vol",
                vol_bytes({8, 8, 8}, 1, Vec3f(-1.f), Vec3f(1.f), [](int x, int y, int z, int) {
                    const float u = x / 7.f - 0.5f, v = y / 7.f - 0.4f, w = z / 7.f - 0.5f;
                    return 0.3f + 1.5f * std::exp(-(u * u + v * v + w * w) / 0.08f);
                }));
}

// The interior derivative against FD with 16 batches each; h is the step of the parameter.
DiffCheck media_check(Scene& scene, const std::string& selection, int spp, int spp_fd, double h) {
    Parameters params(scene);
    params.enable({parse_param_selection(selection)});
    const DerivativePair r = derivative_and_fd(scene, params, spp, spp_fd, h);
    return check_against(r.derivative, r.fd);
}

struct MediumParam {
    const char* medium;
    const char* selection;
    double h;   // FD step: wide where the image is smooth in the parameter (its O(h²) error stays small)
    int spp;    // derivative samples per pixel and batch
    int spp_fd; // and FD samples: event probabilities of delta tracking change with σt and the albedo, so
                // that common random numbers flip decisions and the FD's noise is heavy-tailed
};

class MediaInterior : public ::testing::TestWithParam<MediumParam> {};

} // namespace

// Unbiased for every medium parameter: the closed-form transmittance of a homogeneous medium, and delta and
// ratio tracking re-evaluated with the null-collision weights of a heterogeneous one.
TEST_P(MediaInterior, MatchesFiniteDifferences) {
    const MediumParam& p = GetParam();
    TempDir dir;
    write_density(dir);
    auto scene = load_scene_string(fog_scene(p.medium == std::string("het") ? kHeterogeneous : kHomogeneous),
                                   dir.str());
    const DiffCheck c = media_check(*scene, p.selection, p.spp, p.spp_fd, p.h);
    EXPECT_TRUE(c.passes()) << describe(c);
}

INSTANTIATE_TEST_SUITE_P(Parameters, MediaInterior,
                         ::testing::Values(MediumParam{"hom", "fog.sigma_t", 0.04, 32, 256},
                                           MediumParam{"hom", "fog.albedo", 0.02, 32, 256},
                                           MediumParam{"hom", "fog.phase_function.g", 0.05, 32, 256},
                                           MediumParam{"het", "fog.scale", 0.05, 32, 1024},
                                           MediumParam{"het", "density.data", 0.05, 32, 1024},
                                           MediumParam{"het", "fog.albedo", 0.04, 64, 1024},
                                           MediumParam{"het", "fog.phase_function.g", 0.08, 64, 1024},
                                           MediumParam{"het", "floor_bsdf.reflectance", 0.02, 64, 1024}),
                         [](const auto& info) {
                             std::string name = std::string(info.param.medium) + "_" + info.param.selection;
                             for (char& ch : name)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return name;
                         });

// A test that can fail: the derivative of σt scaled by 0.8 is rejected.
TEST(MediaInterior, DetectsAScaledDerivative) {
    auto scene = load_scene_string(fog_scene(kHomogeneous));
    Parameters params(*scene);
    params.enable({parse_param_selection("fog.albedo")});
    DerivativePair r = derivative_and_fd(*scene, params, 32, 256, 0.02);
    for (auto& d : r.derivative.derivative.pixels)
        d *= 0.8f;
    const DiffCheck c = check_against(r.derivative, r.fd);
    EXPECT_FALSE(c.passes()) << describe(c);
}

// ⟨a, J v⟩ = ⟨Jᵀ a, v⟩ with medium and surface parameters together.
TEST(MediaInterior, ForwardAndReverseModeAreAdjoint) {
    TempDir dir;
    write_density(dir);
    auto scene = load_scene_string(fog_scene(kHeterogeneous), dir.str());
    Parameters params(*scene);
    params.enable({parse_param_selection("fog.scale=0.7"), parse_param_selection("fog.albedo=0.2,0.3,0.1"),
                   parse_param_selection("fog.phase_function.g=0.5"),
                   parse_param_selection("floor_bsdf.reflectance=0.3,0.2,0.1")});
    DiffOptions o;
    o.spp = 4;
    o.seed = 3;
    o.path = path_settings(*scene);
    const DerivativeImage forward = render_derivative(*scene, params, o);
    Image adjoint(16, 16);
    PCG32 rng(5);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    const Gradient reverse = render_gradient(*scene, params, adjoint, o);
    const AdjointPair p = adjoint_pair(adjoint, forward.derivative, reverse.values, params.direction());
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale)
        << "⟨a, Jv⟩ = " << p.forward << ", ⟨Jᵀa, v⟩ = " << p.reverse;
    EXPECT_GT(p.scale, 1e-3);
}

// The estimator's own primal (the float weights of the same samples) is an unbiased image of the scene.
TEST(MediaInterior, PrimalOfTheEstimatorMatchesTheRenderer) {
    TempDir dir;
    write_density(dir);
    auto scene = load_scene_string(fog_scene(kHeterogeneous), dir.str());
    Parameters params(*scene);
    params.enable({parse_param_selection("fog.scale")});
    DiffOptions o;
    o.spp = 16;
    o.batches = 16;
    o.path = path_settings(*scene);
    const DerivativeImage d = render_derivative(*scene, params, o);
    const BatchStats s = render_batches(*scene, 16, 16);
    double mean = 0;
    for (const auto& p : d.primal.pixels)
        mean += (p.x + p.y + p.z) / 3.0;
    mean /= d.primal.pixels.size();
    // The primal's batch spread is not recorded; its variance is comparable to the renderer's: √2 × stderr.
    EXPECT_NEAR(mean, s.image_mean, 4.0 * std::sqrt(2.0) * s.image_mean_stderr)
        << "renderer " << s.image_mean;
}
