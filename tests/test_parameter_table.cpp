// The parameter table (diff/parameter_table.h): entries with Mitsuba traverse() keys and array shapes,
// get/set round trips, poses placing meshes / the camera / lights as the formula says, and the chain rule
// from the estimators' motions to the pose values against finite differences in value space and against
// reverse mode.
#include "core/batch_stats.h"
#include "core/image.h"
#include "core/rng.h"
#include "diff/parameter_table.h"
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "scene/scene.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A cube lit by a directional light in front of a black background (silhouettes and shading change with
// its pose; a convex shape casts no visible shadow), a textured floor far below the view for the array
// shapes, and a point light that lights nothing visible.
std::string cube_scene(int res) {
    return scene(R"(
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective" id="cam">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0.3, 1.2, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value=")" +
                 std::to_string(res) + R"("/><integer name="height" value=")" + std::to_string(res) +
                 R"("/></film>
    </sensor>
    <shape type="cube" id="box">
        <transform name="to_world"><scale value="0.5"/><rotate y="1" angle="20"/><translate value="0.1, 0, 0"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.3"/></bsdf>
    </shape>
    <shape type="rectangle" id="floor">
        <transform name="to_world"><rotate x="1" angle="-90"/><translate value="0, -50, 0"/></transform>
        <bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="tex.exr"/></texture></bsdf>
    </shape>
    <emitter type="directional" id="sun">
        <vector name="direction" value="-1, -2, -1.5"/><rgb name="irradiance" value="3"/>
    </emitter>
    <emitter type="point" id="bulb"><point name="position" value="0, -60, 0"/></emitter>)");
}

std::unique_ptr<Scene> load_cube_scene(const TempDir& dir, int res) {
    write_image(dir.str() + "/tex.exr", Image(5, 4, Color3f(0.5f)));
    return load_scene_string(cube_scene(res), dir.str());
}

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

Vec3d to_vec(const std::vector<float>& v) { return {v[0], v[1], v[2]}; }

// The pose of the derivative tests: t, r (0.4 rad about a tilted axis) and s all non-zero.
const std::vector<float> pose_t = {0.1f, -0.05f, 0.08f};
const std::vector<float> pose_r = {0.4f * 0.4364358f, 0.4f * 0.8728716f, 0.4f * 0.2182179f};
const std::vector<float> pose_s = {0.2f};

void set_pose(ParameterTable& table, const std::string& owner) {
    table.set(table.find(owner + ".translate"), pose_t.data(), 3);
    table.set(table.find(owner + ".rotate"), pose_r.data(), 3);
    table.set(table.find(owner + ".scale"), pose_s.data(), 1);
}

// PENUMBRA_TEST_SEED re-runs the checks with other random numbers (to see that they do not pass by luck).
uint64_t seed_offset() {
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    return env ? 1000 * std::strtoull(env, nullptr, 10) : 0;
}

using Directions = std::vector<std::pair<int, std::vector<float>>>;

// Central differences in value space: renders at x0 ± h·d (apply()'d values, same seeds on both sides,
// stratified film positions) in 16 independent batches; restores x0.
FiniteDifference value_fd(Scene& scene, ParameterTable& table, const Directions& directions, double h,
                          int spp) {
    std::vector<std::vector<float>> x0;
    for (const auto& [entry, d] : directions)
        x0.push_back(table.get(entry));
    const auto place = [&](double sign) {
        for (size_t i = 0; i < directions.size(); ++i) {
            std::vector<float> x = x0[i];
            for (size_t k = 0; k < x.size(); ++k)
                x[k] += float(sign * h * directions[i].second[k]);
            table.set(directions[i].first, x.data(), x.size());
        }
        table.apply();
    };
    ImageBatches estimates;
    for (int b = 0; b < 16; ++b) {
        RenderOptions o;
        o.spp = spp;
        o.seed = 99 + seed_offset() + 7919 * uint64_t(b);
        o.stratified = true;
        place(+1);
        const Image plus = render(scene, o);
        place(-1);
        const Image minus = render(scene, o);
        Image d(plus.width, plus.height);
        for (size_t i = 0; i < d.pixels.size(); ++i)
            d.pixels[i] = (plus.pixels[i] - minus.pixels[i]) / float(2 * h);
        estimates.add(d);
    }
    place(0);
    return {estimates.mean(), estimates.standard_error(), 0.0};
}

PsdrOptions psdr_options(const Scene& scene, int batches) {
    PsdrOptions o;
    o.interior.spp = 32;
    o.interior.batches = batches;
    o.interior.seed = 11 + seed_offset();
    o.interior.path = path_settings(scene);
    o.primary_spp = 64;
    o.direct_spp = 8;
    o.indirect_spp = 0;
    o.pixel_spp = 4;
    return o;
}

// Value-space finite differences along `directions` at the current values, with the truncation error of the
// step (estimated from the difference at 2h) in the reference's standard error.
struct Reference {
    Image derivative, error;
};
Reference value_reference(Scene& scene, ParameterTable& table, const Directions& directions, double h) {
    const FiniteDifference fd = value_fd(scene, table, directions, h, 256);
    const FiniteDifference fd2 = value_fd(scene, table, directions, 2 * h, 256);
    return {fd.derivative, with_truncation_error(fd.stderr_img, fd, fd2)};
}

// The psdr forward derivative along `directions` (16 batches) against a reference.
DiffCheck forward_check(Scene& scene, ParameterTable& table, const Directions& directions,
                        const Reference& ref, const char* label) {
    table.select(directions);
    const DerivativeImage d = psdr_derivative(scene, table.parameters(), psdr_options(scene, 16));
    const DiffCheck c = check_against(d.derivative, d.stderr_img, ref.derivative, ref.error);
    std::printf("  %s: %s\n", label, describe(c).c_str());
    return c;
}

// The value-space direction dr′ whose rotation is ω = dr (J_l(r) dr′ = dr, by fixed-point iteration:
// ‖J_l − I‖ < 0.3 here): a negative control for the J_l map.
std::vector<float> without_left_jacobian(const std::vector<float>& r, const std::vector<float>& dr) {
    const Mat3d j = left_jacobian(to_vec(r));
    Vec3d x = to_vec(dr);
    for (int k = 0; k < 60; ++k)
        x = x + (to_vec(dr) - j * x);
    return {float(x.x), float(x.y), float(x.z)};
}

} // namespace

// Entries carry Mitsuba's traverse() keys and array shapes; motions are 3-vectors (scale: 1 value).
TEST(ParameterTable, EntriesHaveMitsubaKeysAndShapes) {
    TempDir dir;
    auto s = load_cube_scene(dir, 8);
    ParameterTable table(*s);
    const auto shape_of = [&](const std::string& name) {
        return table.entries()[size_t(table.find(name))].shape;
    };
    const int vertices = int(s->shapes[0]->mesh.vertex_count());
    EXPECT_EQ(shape_of("box.vertex_positions"), (std::vector<int>{vertices, 3}));
    EXPECT_EQ(shape_of("box.bsdf.reflectance.value"), (std::vector<int>{3}));
    EXPECT_EQ(shape_of("floor.bsdf.reflectance.data"), (std::vector<int>{4, 5, 3}));
    EXPECT_EQ(shape_of("sun.irradiance.value"), (std::vector<int>{3}));
    EXPECT_EQ(shape_of("box.translate"), (std::vector<int>{3}));
    EXPECT_EQ(shape_of("box.rotate"), (std::vector<int>{3}));
    EXPECT_EQ(shape_of("box.scale"), (std::vector<int>{1}));
    EXPECT_EQ(shape_of("cam.rotate"), (std::vector<int>{3}));
    EXPECT_EQ(shape_of("bulb.translate"), (std::vector<int>{3}));
    EXPECT_EQ(shape_of("sun.rotate"), (std::vector<int>{3}));
    EXPECT_THROW(table.find("sun.translate"), Error);
    EXPECT_THROW(table.find("cam.scale"), Error);
    const ParameterTable::Entry& box = table.entries()[size_t(table.find("box.translate"))];
    EXPECT_TRUE(box.motion && box.geometry);
    const ParameterTable::Entry& cam = table.entries()[size_t(table.find("cam.rotate"))];
    EXPECT_TRUE(cam.motion && !cam.geometry);
    EXPECT_TRUE(table.entries()[size_t(table.find("box.vertex_positions"))].geometry);
    EXPECT_EQ(table.find("box.bsdf.reflectance"), table.find("box.bsdf.reflectance.value"));
    EXPECT_NE(error_of([&] { table.find("box.bsdf.reflectanc"); }).find("did you mean: box.bsdf.reflectance"),
              std::string::npos);

    // An envmap's data is an image too.
    write_image(dir.str() + "/env.exr", Image(6, 3, Color3f(1.f)));
    auto env = load_scene_string(
        scene(R"(<emitter type="envmap" id="sky"><string name="filename" value="env.exr"/></emitter>)"),
        dir.str());
    ParameterTable env_table(*env);
    EXPECT_EQ(env_table.entries()[size_t(env_table.find("sky.data"))].shape, (std::vector<int>{3, 6, 3}));
    EXPECT_EQ(env_table.entries()[size_t(env_table.find("sky.scale"))].shape, (std::vector<int>{1}));
}

// Values read back as set (staged, then applied into the scene); bad values are refused by name.
TEST(ParameterTable, GetSetRoundTripsAndErrors) {
    TempDir dir;
    auto s = load_cube_scene(dir, 8);
    ParameterTable table(*s);
    const int albedo = table.find("box.bsdf.reflectance");
    EXPECT_EQ(table.get(albedo), (std::vector<float>{0.7f, 0.5f, 0.3f}));
    const std::vector<float> v = {0.1f, 0.2f, 0.3f};
    table.set(albedo, v.data(), 3);
    EXPECT_EQ(table.get(albedo), v);
    table.apply();
    EXPECT_EQ(table.get(albedo), v);
    const Parameter& p = table.parameters().find("box.bsdf.reflectance");
    EXPECT_EQ(std::vector<float>(p.data, p.data + 3), v);
    const int texels = table.find("floor.bsdf.reflectance.data");
    std::vector<float> image(60);
    for (size_t k = 0; k < image.size(); ++k)
        image[k] = 0.01f * float(k);
    table.set(texels, image.data(), image.size());
    table.apply();
    EXPECT_EQ(table.get(texels), image);
    const int rotate = table.find("box.rotate");
    EXPECT_EQ(table.get(rotate), (std::vector<float>{0, 0, 0}));
    table.set(rotate, pose_r.data(), 3);
    table.apply();
    EXPECT_EQ(table.get(rotate), pose_r);

    EXPECT_EQ(error_of([&] { table.set(albedo, v.data(), 2); }),
              "parameter 'box.bsdf.reflectance.value': expected 3 values, got 2");
    const std::vector<float> nan = {0.1f, NAN, 0.f}, inf = {INFINITY};
    EXPECT_EQ(error_of([&] { table.set(albedo, nan.data(), 3); }),
              "parameter 'box.bsdf.reflectance.value': value 1 is not finite");
    EXPECT_NE(error_of([&] { table.set(table.find("box.scale"), inf.data(), 1); }).find("not finite"),
              std::string::npos);
    const std::vector<float> flat = {-1.f};
    EXPECT_NE(error_of([&] { table.set(table.find("box.scale"), flat.data(), 1); }).find("must be positive"),
              std::string::npos);
    EXPECT_EQ(error_of([&] { table.get(int(table.entries().size())); }).find("parameter table: no entry"),
              0u);
    EXPECT_EQ(error_of([&] {
                  table.select(std::vector<int>{albedo, albedo});
              }),
              "parameter 'box.bsdf.reflectance.value' is selected twice");
    // vertex_positions with a pose of the same shape: refused whether the pose is non-zero or selected.
    const int vertices = table.find("box.vertex_positions");
    EXPECT_EQ(error_of([&] { table.select(std::vector<int>{vertices}); }),
              "parameter 'box': vertex_positions and a pose of the same shape cannot be combined");
    const std::vector<float> zero = {0, 0, 0};
    table.set(rotate, zero.data(), 3);
    table.apply();
    EXPECT_EQ(error_of([&] {
                  table.select(std::vector<int>{vertices, table.find("box.translate")});
              }),
              "parameter 'box': vertex_positions and a pose of the same shape cannot be combined");
    EXPECT_NO_THROW(table.select(std::vector<int>{vertices}));
    // A pose back at 0 and new vertex positions in one apply(): the vertices are those given.
    std::vector<float> x = table.get(vertices);
    x[0] += 0.01f;
    table.select(std::vector<int>{});
    table.set(rotate, pose_r.data(), 3);
    table.apply();
    table.set(rotate, zero.data(), 3);
    table.set(vertices, x.data(), x.size());
    table.apply();
    EXPECT_EQ(table.get(vertices), x);
    EXPECT_EQ(s->shapes[0]->mesh.positions[0].x, x[0]);
    table.set(rotate, pose_r.data(), 3);
    EXPECT_EQ(error_of([&] { table.apply(); }),
              "parameter 'box': vertex_positions and a pose of the same shape cannot be combined");
    EXPECT_NE(error_of([&] { table.select(std::vector<int>{albedo}); }).find("call apply() first"),
              std::string::npos);
}

// x = c0 + t + (1 + s) R(r) (x0 − c0) with c0 the reference bounding-box center; back to the scene at 0.
TEST(ParameterTable, ShapePoseMovesTheMeshAsTheFormulaSays) {
    TempDir dir;
    auto s = load_cube_scene(dir, 8);
    const std::vector<Vec3f> x0 = s->shapes[0]->mesh.positions;
    ParameterTable table(*s);
    const Vec3d c0(bbox_center({s->shapes[0].get()}));
    set_pose(table, "box");
    table.apply();
    const Mat3d r = rotation_from_vector(to_vec(pose_r));
    for (size_t i = 0; i < x0.size(); ++i) {
        const Vec3d expected = c0 + to_vec(pose_t) + r * (Vec3d(x0[i]) - c0) * (1.0 + pose_s[0]);
        EXPECT_LT(norm(Vec3d(s->shapes[0]->mesh.positions[i]) - expected), 1e-6) << i;
    }
    // The BVH follows: a ray through the moved center hits the cube.
    const std::vector<float> zero = {0, 0, 0}, none = {0};
    table.set(table.find("box.translate"), zero.data(), 3);
    table.set(table.find("box.rotate"), zero.data(), 3);
    table.set(table.find("box.scale"), none.data(), 1);
    table.apply();
    for (size_t i = 0; i < x0.size(); ++i)
        EXPECT_LT(norm(s->shapes[0]->mesh.positions[i] - x0[i]), 1e-6f) << i;
}

// The camera and a point light move about their own positions; a directional light turns.
TEST(ParameterTable, SensorAndEmitterPosesMoveThem) {
    TempDir dir;
    auto s = load_cube_scene(dir, 8);
    ParameterTable table(*s);
    const Transform cam0 = s->sensor->to_world;
    const Vec3d p0(cam0.apply_point(Vec3f(0.f))), forward0(cam0.apply_vector(Vec3f(0, 0, 1)));
    table.set(table.find("cam.translate"), pose_t.data(), 3);
    table.set(table.find("cam.rotate"), pose_r.data(), 3);
    const std::vector<float> up = {0, 1, 0}, turn = {0, 0, 0.5f};
    table.set(table.find("bulb.translate"), up.data(), 3);
    table.set(table.find("sun.rotate"), turn.data(), 3);
    Emitter* sun = s->emitters[0].get();
    Emitter* bulb = s->emitters[1].get();
    const Vec3d sun0(sun->to_world().apply_vector(Vec3f(0, 0, 1)));
    table.apply();
    const Mat3d r = rotation_from_vector(to_vec(pose_r));
    EXPECT_LT(norm(Vec3d(s->sensor->to_world.apply_point(Vec3f(0.f))) - (p0 + to_vec(pose_t))), 1e-5);
    EXPECT_LT(norm(Vec3d(s->sensor->to_world.apply_vector(Vec3f(0, 0, 1))) - r * forward0), 1e-5);
    EXPECT_LT(norm(Vec3d(bulb->to_world().apply_point(Vec3f(0.f))) - Vec3d(0, -59, 0)), 1e-5);
    EXPECT_LT(norm(Vec3d(sun->to_world().apply_vector(Vec3f(0, 0, 1))) -
                   rotation_from_vector(Vec3d(0, 0, 0.5)) * sun0),
              1e-5);
    EXPECT_EQ(table.get(table.find("cam.rotate")), pose_r);
}

// An instance of a group with two shapes moves both copies about their common center.
TEST(ParameterTable, InstancePoseMovesItsCopies) {
    auto s = load_scene_string(scene(R"(
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
    <shape type="shapegroup" id="pair">
        <shape type="rectangle"><transform name="to_world"><scale value="0.2"/><translate x="-0.5"/></transform></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="0.2"/><translate x="0.5"/></transform></shape>
    </shape>
    <shape type="instance" id="both"><ref id="pair"/><transform name="to_world"><translate y="0.3"/></transform></shape>)"));
    ParameterTable table(*s);
    const std::vector<Shape*> copies = s->instance_shapes.at("both");
    ASSERT_EQ(copies.size(), 2u);
    std::vector<std::vector<Vec3f>> x0;
    for (Shape* c : copies)
        x0.push_back(c->mesh.positions);
    const Vec3d c0(bbox_center(copies));
    set_pose(table, "both");
    table.apply();
    const Mat3d r = rotation_from_vector(to_vec(pose_r));
    for (size_t k = 0; k < copies.size(); ++k)
        for (size_t i = 0; i < x0[k].size(); ++i) {
            const Vec3d expected = c0 + to_vec(pose_t) + r * (Vec3d(x0[k][i]) - c0) * (1.0 + pose_s[0]);
            EXPECT_LT(norm(Vec3d(copies[k]->mesh.positions[i]) - expected), 1e-6);
        }
    // A copy's own pose cannot move it at the same time, nor be selected while the instance is posed.
    const std::string copy = copies[0]->id + ".translate"; // both.0.translate
    EXPECT_NE(error_of([&] {
                  table.select(std::vector<int>{table.find(copy)});
              }).find("which poses the same shape"),
              std::string::npos);
    table.set(table.find(copy), pose_t.data(), 3);
    EXPECT_NE(error_of([&] { table.apply(); }).find("pose the same shape"), std::string::npos);
}

// J_l(φ) δ is the world-frame rotation that a change δ of the rotation vector makes:
// exp(φ + hδ) exp(φ)ᵀ ≈ exp(h J_l(φ) δ), checked by central differences (error O(h²)).
TEST(ParameterTable, LeftJacobianIsTheDerivativeOfTheExponential) {
    const Vec3d phi = to_vec(pose_r) * 5.0, delta(0.3, -0.7, 0.2);
    const double h = 1e-5;
    const Mat3d r0 = rotation_from_vector(phi).transpose();
    const Vec3d fd = (rotation_vector(rotation_from_vector(phi + delta * h) * r0) -
                      rotation_vector(rotation_from_vector(phi - delta * h) * r0)) /
                     (2 * h);
    EXPECT_LT(norm(fd - left_jacobian(phi) * delta), 1e-8);
    EXPECT_GT(norm(fd - delta), 0.1) << "the check must tell J_l from the identity";
    EXPECT_LT(norm(left_jacobian(Vec3d(1e-4, 0, 0)) * delta - delta), 1e-4);
}

// The forward derivative along a value-space direction at a non-zero pose (t, r, s) equals central
// differences of renders at the apply()'d values ± h·direction: a rotation direction not parallel to r
// (J_l(r) ≠ I matters), a scale direction, and all three together. Tolerances from the standard errors
// (tests/diff_check.h). Negative control: the rotation direction mapped without J_l (ω = dr) must be
// rejected.
TEST(ParameterTable, ForwardDerivativeMatchesValueSpaceFiniteDifferences) {
    TempDir dir;
    auto s = load_cube_scene(dir, 24);
    ParameterTable table(*s);
    set_pose(table, "box");
    table.apply();
    const int t = table.find("box.translate"), r = table.find("box.rotate"), sc = table.find("box.scale");
    const std::vector<float> dr = {0.6f, -0.2f, -0.77f};
    const Reference rotate = value_reference(*s, table, {{r, dr}}, 1e-2);
    EXPECT_TRUE(forward_check(*s, table, {{r, dr}}, rotate, "box.rotate").passes());
    const Reference scale = value_reference(*s, table, {{sc, {1.f}}}, 1e-2);
    EXPECT_TRUE(forward_check(*s, table, {{sc, {1.f}}}, scale, "box.scale").passes());
    const Directions all = {{t, {0.3f, 0.5f, -0.2f}}, {r, dr}, {sc, {0.5f}}};
    EXPECT_TRUE(forward_check(*s, table, all, value_reference(*s, table, all, 1e-2), "all three").passes());
    // Negative controls: ω = dr, and a scale motion of ds instead of ds / (1 + s).
    EXPECT_FALSE(forward_check(*s, table, {{r, without_left_jacobian(pose_r, dr)}}, rotate,
                               "control: box.rotate without J_l")
                     .passes());
    EXPECT_FALSE(
        forward_check(*s, table, {{sc, {1.f + pose_s[0]}}}, scale, "control: box.scale without 1 / (1 + s)")
            .passes());
}

// The camera's pose the same way: at a non-zero translation and rotation, the derivative along a rotation
// direction (about the camera's current position, ω = J_l(r) dr) and a translation direction matches
// value-space central differences (the whole image moves: interior, silhouettes and the pixel filter's
// boundary).
TEST(ParameterTable, CameraPoseDerivativeMatchesValueSpaceFiniteDifferences) {
    TempDir dir;
    auto s = load_cube_scene(dir, 24);
    ParameterTable table(*s);
    // r: a roll of 0.8 rad about the viewing axis (the cube stays in view); dr: a tilt across it, so that
    // J_l(r) dr differs from dr by ~0.4 |dr|.
    const std::vector<float> cam_t = {0.2f, -0.1f, 0.3f}, cam_r = {-0.0573f, -0.2293f, -0.7642f};
    const int t = table.find("cam.translate"), r = table.find("cam.rotate");
    table.set(t, cam_t.data(), 3);
    table.set(r, cam_r.data(), 3);
    table.apply();
    const std::vector<float> dr = {0.3f, 0.f, -0.0225f};
    const Reference reference = value_reference(*s, table, {{r, dr}}, 5e-3);
    EXPECT_TRUE(forward_check(*s, table, {{r, dr}}, reference, "cam.rotate").passes());
    EXPECT_FALSE(forward_check(*s, table, {{r, without_left_jacobian(cam_r, dr)}}, reference,
                               "control: cam.rotate without J_l")
                     .passes());
    const Directions both = {{t, {0.5f, 0.2f, -0.3f}}, {r, {0.3f, -0.1f, 0.4f}}};
    const DiffCheck d =
        forward_check(*s, table, both, value_reference(*s, table, both, 5e-3), "cam.translate+rotate");
    EXPECT_TRUE(d.passes()) << describe(d);
}

// Reverse mode: chain() of the gradient equals forward mode on the same samples, ⟨Jᵀa, v⟩ = ⟨a, Jv⟩, for a
// Data entry and the translate / rotate / scale of a shape and the camera's motions, at non-zero poses. Both
// sums are over the same samples in float: agreement to ~1e-5 of the sum of magnitudes (as in
// test_diff_interior.cpp).
TEST(ParameterTable, ReverseModeChainIsTheAdjointOfForwardMode) {
    TempDir dir;
    auto s = load_cube_scene(dir, 16);
    ParameterTable table(*s);
    set_pose(table, "box");
    table.set(table.find("cam.translate"), pose_t.data(), 3);
    const std::vector<float> cam_r = {0.02f, -0.05f, 0.03f};
    table.set(table.find("cam.rotate"), cam_r.data(), 3);
    table.apply();
    const Directions v = {{table.find("box.bsdf.reflectance"), {0.5f, -0.3f, 0.2f}},
                          {table.find("box.translate"), {0.3f, 0.5f, -0.2f}},
                          {table.find("box.rotate"), {0.6f, -0.2f, -0.77f}},
                          {table.find("box.scale"), {0.5f}},
                          {table.find("cam.translate"), {0.1f, 0.2f, 0.3f}},
                          {table.find("cam.rotate"), {-0.2f, 0.1f, 0.3f}}};
    const PsdrOptions o = psdr_options(*s, 1);
    table.select(v);
    const DerivativeImage forward = psdr_derivative(*s, table.parameters(), o);
    std::vector<int> entries;
    for (const auto& [entry, d] : v)
        entries.push_back(entry);
    table.select(entries);
    Image adjoint(16, 16);
    PCG32 rng(3);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
    const Gradient reverse = psdr_gradient(*s, table.parameters(), adjoint, o);
    const std::vector<std::vector<double>> g = table.chain(reverse.values);
    ASSERT_EQ(g.size(), v.size());
    std::vector<double> flat, contributions;
    std::vector<float> direction;
    for (size_t i = 0; i < v.size(); ++i) {
        ASSERT_EQ(g[i].size(), v[i].second.size());
        flat.insert(flat.end(), g[i].begin(), g[i].end());
        double contribution = 0;
        for (size_t k = 0; k < g[i].size(); ++k)
            contribution += g[i][k] * v[i].second[k];
        std::printf("  %s: <J^T a, v> part %.6g\n", table.entries()[size_t(v[i].first)].name.c_str(),
                    contribution);
        contributions.push_back(contribution);
        direction.insert(direction.end(), v[i].second.begin(), v[i].second.end());
    }
    const AdjointPair p = adjoint_pair(adjoint, forward.derivative, flat, direction);
    std::printf("  <a, Jv> = %.7g, <J^T a, v> = %.7g (scale %.6g)\n", p.forward, p.reverse, p.scale);
    EXPECT_GT(std::abs(p.forward), 0.05 * p.scale);
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale);
    // Every entry's part is far above that tolerance, so that a wrong map of any one of them would show.
    for (double c : contributions)
        EXPECT_GT(std::abs(c), 1e-2 * p.scale);
}
