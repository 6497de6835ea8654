// Derivatives of instanced scenes: Parameters flattens the instances into world-space shapes. The flattened
// scene renders as the instanced one, an instance's motion and a group shape's shared vertex_positions match
// central finite differences (psdr: interior + primary boundary), and `penumbra params` lists them.
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "scene/scene.h"
#include "stored_reference.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// Two instances of a group holding one quad in front of a diffuse wall, lit by a point light at the camera
// (scenes/validation/instanced_quads.xml).
const std::string quads_file = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/instanced_quads.xml";

std::unique_ptr<Scene> quads_scene(int res) { return load_scene(quads_file, {{"res", std::to_string(res)}}); }

// PENUMBRA_TEST_SEED re-runs the checks with other random numbers (to see that they do not pass by luck).
uint64_t seed_offset() {
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    return env ? 1000 * std::strtoull(env, nullptr, 10) : 0;
}

PsdrOptions batched(const Scene& scene, int interior, int primary) {
    PsdrOptions o;
    o.interior.spp = interior;
    o.interior.batches = 16;
    o.interior.seed = 11 + seed_offset();
    o.interior.path = path_settings(scene);
    o.primary_spp = primary;
    return o;
}

// The psdr derivative (interior + primary boundary) of `param` against central differences (step h, with the
// Richardson estimate of the truncation error from 2h), stored as `reference` and `reference`_2h
// (tests/data/fd, scripts/make_test_references.sh) at 4x the samples this test used to render; the interior
// term alone must miss the moving silhouettes.
void expect_matches_fd(const std::string& param, double h, const std::string& reference) {
    const auto start = std::chrono::steady_clock::now();
    auto scene = quads_scene(32);
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    const DerivativeImage d = psdr_derivative(*scene, params, batched(*scene, 16, 16));
    const FiniteDifference fd = stored_reference({reference, {}}, h).fd;
    const Image error =
        with_truncation_error(fd.stderr_img, fd, stored_reference({reference + "_2h", {}}, 2 * h).fd);
    const DiffCheck total = check_against(d.derivative, d.stderr_img, fd.derivative, error);
    const DiffCheck interior =
        check_against(d.term("interior").derivative, d.term("interior").stderr_img, fd.derivative, error);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("  %s: interior+primary %s\n  interior only %s\n  (%.1f s)\n", param.c_str(),
                describe(total).c_str(), describe(interior).c_str(), seconds);
    EXPECT_TRUE(total.passes()) << param << ": " << describe(total);
    EXPECT_FALSE(interior.passes()) << param << ": the interior term alone should miss the silhouettes: "
                                    << describe(interior);
}

} // namespace

// Flattening changes how rays find the geometry (world-space triangles instead of instance rays), not what
// they find: the same image up to float rounding of the hit distances.
TEST(InstanceDerivatives, FlattenedSceneRendersAsTheInstancedOne) {
    auto instanced = quads_scene(48);
    auto flat = quads_scene(48);
    flat->flatten_instances();
    ASSERT_TRUE(flat->instances.empty());
    ASSERT_EQ(flat->shapes.size(), 3u);
    EXPECT_EQ(flat->shapes[1]->id, "left");
    EXPECT_EQ(flat->shapes[2]->id, "right");
    EXPECT_EQ(flat->triangle_count(), instanced->instanced_triangle_count());
    RenderOptions ro;
    ro.spp = 16;
    ro.seed = 5;
    const Image a = render(*instanced, ro), b = render(*flat, ro);
    double diff = 0, sum = 0, largest = 0;
    int identical = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const double d = double(max_component(abs(a.pixels[i] - b.pixels[i])));
        diff += d;
        largest = std::max(largest, d);
        sum += double(max_component(a.pixels[i]));
        identical += d == 0.0;
    }
    RecordProperty("identical_pixels", identical);
    std::printf("  identical pixels %d / %zu, relative L1 difference %.3g, largest %.3g\n", identical,
                a.pixels.size(), diff / sum, largest);
    EXPECT_LT(diff / sum, 1e-5);
    EXPECT_LT(largest, 1e-3);
}

TEST(InstanceDerivatives, ParametersNameTheInstancesAndTheSharedGeometry) {
    auto scene = quads_scene(16);
    Parameters params(*scene);
    for (const char* name : {"left.translate", "left.rotate", "left.scale", "right.translate",
                             "quad.vertex_positions", "quad.bsdf.reflectance"})
        EXPECT_NO_THROW(params.find(name)) << name;
    // The copies do not expose vertex_positions of their own: the group shape's are the parameter.
    EXPECT_THROW(params.find("left.vertex_positions"), Error);
}

// An instance of a group with several shapes: its motions move all of them together, about their common
// center.
TEST(InstanceDerivatives, InstanceMotionsMoveAllItsShapes) {
    auto scene = load_scene_string(test::scene(R"(
    <shape type="shapegroup" id="pair">
        <shape type="rectangle" id="a"/>
        <shape type="rectangle"><transform name="to_world"><translate x="4"/></transform></shape>
    </shape>
    <shape type="instance" id="two"><ref id="pair"/><transform name="to_world"><translate y="1"/></transform></shape>)"));
    Parameters params(*scene);
    ASSERT_EQ(scene->shapes.size(), 2u);
    EXPECT_EQ(scene->shapes[0]->id, "two.a");
    EXPECT_EQ(scene->shapes[1]->id, "two.1");
    params.enable({parse_param_selection("two.scale")});
    for (const auto& shape : scene->shapes) {
        ASSERT_EQ(params.motions(shape.get()).size(), 1u);
        EXPECT_EQ(params.motions(shape.get())[0].center, Vec3f(2.f, 1.f, 0.f));
    }
    params.displace(*scene, 0.5);
    EXPECT_EQ(scene->shapes[0]->mesh.positions[0], Vec3f(-2.5f, -0.5f, 0.f));
    EXPECT_EQ(scene->shapes[1]->mesh.positions[1], Vec3f(6.5f, -0.5f, 0.f));
    params.displace(*scene, 0.0);
    EXPECT_EQ(scene->shapes[1]->mesh.positions[1], Vec3f(5.f, 0.f, 0.f));
}

// Displacing a group shape's vertex_positions moves every copy by its own instance's to_world.
TEST(InstanceDerivatives, SharedVerticesMoveEveryCopy) {
    auto scene = quads_scene(16);
    Parameters params(*scene);
    const Vec3f left0 = scene->shapes[1]->mesh.positions[2], right0 = scene->shapes[2]->mesh.positions[2];
    params.enable({parse_param_selection("quad.vertex_positions=0,0,0,0,0,0,0.1,0,0,0,0,0")});
    params.displace(*scene, 1.0);
    const Vec3f left = scene->shapes[1]->mesh.positions[2] - left0,
                right = scene->shapes[2]->mesh.positions[2] - right0;
    EXPECT_NEAR(norm(left - Vec3f(0.1f, 0.f, 0.f)), 0.f, 1e-6f);
    const Vec3f expected = scene->shapes[2]->instance_to_world.apply_vector(Vec3f(0.1f, 0.f, 0.f));
    EXPECT_NEAR(norm(right - expected), 0.f, 1e-6f);
    EXPECT_EQ(scene->shapes[1]->mesh.positions[0],
              scene->shapes[1]->group_shape->mesh.positions[0] + Vec3f(-0.5f, 0.1f, 0.f));
    params.displace(*scene, 0.0);
    EXPECT_EQ(scene->shapes[2]->mesh.positions[2], right0);
}

TEST(InstanceDerivatives, InstanceTranslationMatchesFiniteDifferences) {
    expect_matches_fd("left.translate=1,0.5,0", 1e-2, "instance_translate");
}

// A non-rigid change of the shared quad (one corner pulled outwards, one pushed along the edge): both
// silhouettes move, each by its own instance's linear map.
TEST(InstanceDerivatives, SharedVertexPositionsMatchFiniteDifferences) {
    expect_matches_fd("quad.vertex_positions=0,0,0,1,-0.5,0,0,0,0,0,0.6,0", 1e-2, "instance_vertices");
}

// Reverse mode sees the shared vertices too: ⟨a, Jv⟩ = ⟨Jᵀa, v⟩ on the same samples (psdr_gradient uses the
// seeds of psdr_derivative's single batch), the gradient reaching the group-space vertices through both
// copies.
TEST(InstanceDerivatives, ReverseModeOfSharedVerticesIsTheAdjoint) {
    auto scene = quads_scene(24);
    Parameters params(*scene);
    params.enable({parse_param_selection("quad.vertex_positions=0,0,0,1,-0.5,0,0,0,0,0,0.6,0")});
    PsdrOptions o;
    o.interior.spp = 4;
    o.interior.seed = 5;
    o.interior.path = path_settings(*scene);
    o.primary_spp = 8;
    const DerivativeImage forward = psdr_derivative(*scene, params, o);
    Image adjoint(scene->sensor->film->width, scene->sensor->film->height);
    PCG32 rng(3);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
    const Gradient reverse = psdr_gradient(*scene, params, adjoint, o);
    const AdjointPair p = adjoint_pair(adjoint, forward.derivative, reverse.values, params.direction());
    std::printf("  <a, Jv> = %.6g, <J^T a, v> = %.6g (scale %.6g)\n", p.forward, p.reverse, p.scale);
    EXPECT_GT(std::abs(p.forward), 0.1 * p.scale);
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale + 1e-6);
}

TEST(InstanceDerivatives, ParamsCommandListsTheInstanceMotions) {
    FILE* pipe = popen((std::string(PENUMBRA_CLI) + " params " + quads_file + " 2>&1").c_str(), "r");
    ASSERT_TRUE(pipe);
    std::string out;
    std::array<char, 4096> buf;
    while (fgets(buf.data(), buf.size(), pipe))
        out += buf.data();
    EXPECT_EQ(pclose(pipe), 0) << out;
    for (const char* name : {"left.translate", "right.rotate", "right.scale", "quad.vertex_positions"})
        EXPECT_NE(out.find(name), std::string::npos) << name << " missing from:\n" << out;
}
