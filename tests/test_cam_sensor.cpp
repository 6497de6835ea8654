// Perspective and orthographic sensors: ray geometry, fov conventions, projection, importance normalization.
#include "core/rng.h"
#include "core/warp.h"
#include "scene/factory.h"
#include "scene/scene.h"
#include "scene/sensor.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

const SourceLocation Loc{"scene.xml", 1};

struct SensorSpec {
    std::string type = "perspective";
    int width = 64, height = 48;
    Transform to_world;
    std::vector<std::pair<std::string, Properties::Value>> params;
};

std::shared_ptr<Sensor> build(const SensorSpec& spec, Properties* out_props = nullptr) {
    LoadContext ctx;
    Properties film_props("hdrfilm", Loc);
    film_props.set("width", int64_t(spec.width), Loc);
    film_props.set("height", int64_t(spec.height), Loc);
    auto film = make_film(film_props, ctx);
    auto sampler = std::make_shared<SamplerDesc>();
    Properties props(spec.type, Loc);
    props.set("to_world", spec.to_world, Loc);
    for (const auto& [name, value] : spec.params)
        props.set(name, value, {"scene.xml", 20});
    props.add_object("", film, Loc);
    props.add_object("", sampler, Loc);
    auto sensor = std::static_pointer_cast<Sensor>(make_sensor(props, ctx));
    EXPECT_TRUE(props.unqueried().empty());
    if (out_props) *out_props = props;
    return sensor;
}

// Angle (degrees) between the local direction of a film position's ray and the camera axis, per local axis.
Vec3f local_dir(const Sensor& s, const Vec2f& film_pos) {
    const auto [ray, weight] = s.sample_ray(film_pos, Vec2f(0.5f));
    EXPECT_EQ(weight, Color3f(1.f));
    return s.to_world.inverse().apply_vector(ray.d);
}
float half_angle_deg(float tangent) { return degrees(std::atan(tangent)); }

// Float roundoff of transforms and trigonometry on directions of unit length.
constexpr float AngleTol = 1e-3f; // degrees

} // namespace

TEST(CamSensor, CenterRayIsForwardAxis) {
    SensorSpec spec;
    spec.to_world = Transform::look_at(Vec3f(1, 2, 3), Vec3f(4, -1, 0), Vec3f(0, 0, 1));
    spec.params = {{"fov", 45.0}};
    auto s = build(spec);
    const auto [ray, w] = s->sample_ray(Vec2f(32.f, 24.f), Vec2f(0.5f));
    EXPECT_NEAR(norm(ray.o - Vec3f(1, 2, 3)), 0.f, 1e-6f);
    const Vec3f forward = normalize(Vec3f(3, -3, -3));
    EXPECT_NEAR(dot(ray.d, forward), 1.f, 1e-6f); // unit vectors: float roundoff
    // Film x grows to the right of the image = toward local -x (local +x is left).
    const Vec3f right = s->sample_ray(Vec2f(40.f, 24.f), Vec2f(0.5f)).first.d - ray.d;
    const Vec3f left_axis = s->to_world.apply_vector(Vec3f(1, 0, 0));
    EXPECT_LT(dot(right, left_axis), 0.f);
    const Vec3f down = s->sample_ray(Vec2f(32.f, 30.f), Vec2f(0.5f)).first.d - ray.d;
    EXPECT_LT(dot(down, Vec3f(0, 0, 1)), 0.f); // up = +z in world
}

TEST(CamSensor, FovAxisVariants) {
    const float fov = 50.f, t = std::tan(radians(fov / 2));
    const float aspect = 64.f / 48.f;
    struct Case {
        const char* axis;
        Vec2f film_pos;
    };
    // For each axis, the film position whose ray makes exactly fov/2 with the optical axis.
    for (const Case& c : {Case{"x", {0.f, 24.f}}, Case{"y", {32.f, 0.f}}, Case{"diagonal", {0.f, 0.f}},
                          Case{"smaller", {32.f, 0.f}}, Case{"larger", {0.f, 24.f}}}) {
        SensorSpec spec;
        spec.params = {{"fov", double(fov)}, {"fov_axis", std::string(c.axis)}};
        auto s = build(spec);
        const Vec3f d = local_dir(*s, c.film_pos);
        EXPECT_NEAR(degrees(std::acos(d.z)), fov / 2, AngleTol) << c.axis;
        EXPECT_GT(d.z, 0.f);
    }
    // fov along x: the top edge sees tan(half angle) = tan(fov_x / 2) / aspect; the left edge is local +x.
    SensorSpec spec;
    spec.params = {{"fov", double(fov)}};
    auto s = build(spec);
    const Vec3f left = local_dir(*s, {0.f, 24.f}), top = local_dir(*s, {32.f, 0.f});
    EXPECT_NEAR(half_angle_deg(left.x / left.z), fov / 2, AngleTol);
    EXPECT_NEAR(half_angle_deg(top.y / top.z), half_angle_deg(t / aspect), AngleTol);
}

TEST(CamSensor, FocalLengthDefaultIs50mmOn35mmFilm) {
    SensorSpec spec;
    spec.width = 360;
    spec.height = 240; // 36 x 24 mm proportions: the 50mm diagonal fov spans exactly 36 mm horizontally
    auto s = build(spec);
    const Vec3f left = local_dir(*s, {0.f, 120.f});
    EXPECT_NEAR(left.x / left.z, 18.f / 50.f, 1e-5f); // float roundoff of tan/atan
    SensorSpec both;
    both.params = {{"fov", 30.0}, {"focal_length", std::string("35mm")}};
    EXPECT_THROW(build(both), LoadError);
}

TEST(CamSensor, InvalidParameters) {
    SensorSpec bad_axis;
    bad_axis.params = {{"fov", 30.0}, {"fov_axis", std::string("z")}};
    try {
        build(bad_axis);
        FAIL();
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.xml:20"), std::string::npos) << e.what();
    }
    SensorSpec scaled;
    scaled.to_world = Transform::scale(Vec3f(2.f));
    EXPECT_THROW(build(scaled), LoadError);
    SensorSpec clip;
    clip.params = {{"near_clip", 0.0}};
    EXPECT_THROW(build(clip), LoadError);
    SensorSpec fov;
    fov.params = {{"fov", 180.0}};
    EXPECT_THROW(build(fov), LoadError);
    SensorSpec unknown;
    unknown.type = "thinlens-ish";
    EXPECT_THROW(build(unknown), LoadError);
}

TEST(CamSensor, ProjectInvertsSampleRay) {
    SensorSpec spec;
    spec.to_world = Transform::look_at(Vec3f(0.5f, -1, 2), Vec3f(0, 0, 0), Vec3f(0, 1, 0));
    spec.params = {{"fov", 60.0}, {"principal_point_offset_x", 0.1}, {"principal_point_offset_y", -0.05}};
    auto s = build(spec);
    PCG32 rng(3, 5);
    for (int i = 0; i < 1000; ++i) {
        const Vec2f x(rng.next_float() * 64.f, rng.next_float() * 48.f);
        const float t = 0.1f + 10.f * rng.next_float();
        const auto [ray, w] = s->sample_ray(x, Vec2f(0.5f));
        Vec2f back;
        ASSERT_TRUE(s->project(ray(t), back));
        // Single-precision roundoff of points ~10 units away, magnified by ~W / (2 tan) ~ 55 px per unit
        // angle.
        EXPECT_NEAR(back.x, x.x, 2e-3f);
        EXPECT_NEAR(back.y, x.y, 2e-3f);
        // The light-tracing connection from that point lands on the same film position.
        Interaction3f ref;
        ref.p = ray(t);
        const auto [ds, weight] = s->sample_direction(ref, Vec2f(0.5f));
        EXPECT_NEAR(ds.uv.x, x.x, 2e-3f);
        EXPECT_NEAR(ds.dist, t, 1e-4f * t);
        EXPECT_NEAR(dot(ds.d, ray.d), -1.f, 1e-5f);
        EXPECT_GT(weight.x, 0.f);
    }
    Vec2f dummy;
    EXPECT_FALSE(s->project(s->to_world.apply_point(Vec3f(0, 0, -1)), dummy)); // behind the camera
    EXPECT_FALSE(s->project(s->to_world.apply_point(Vec3f(5, 0, 1)), dummy));  // outside the frustum
    Interaction3f behind;
    behind.p = s->to_world.apply_point(Vec3f(0, 0, -1));
    EXPECT_EQ(s->sample_direction(behind, Vec2f(0.5f)).second, Color3f(0.f));
}

TEST(CamSensor, ImportanceIntegratesToOneOverFilm) {
    SensorSpec spec;
    spec.to_world = Transform::look_at(Vec3f(0, 0, 0), Vec3f(0, 0, 1), Vec3f(0, 1, 0));
    spec.params = {{"fov", 70.0}};
    auto s = build(spec);
    // MC over directions, uniform in a cone that contains the whole film: E[W(w) / p(w)] = ∫ W dω.
    const float tan_x = std::tan(radians(35.f)), tan_y = tan_x * 48.f / 64.f;
    const float cos_cut = 1.f / std::sqrt(1.f + tan_x * tan_x + tan_y * tan_y) - 0.01f;
    const float pdf = warp::square_to_uniform_cone_pdf(cos_cut);
    PCG32 rng(1, 2);
    const int n = 200000;
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        const Vec3f d = warp::square_to_uniform_cone(Vec2f(rng.next_float(), rng.next_float()), cos_cut);
        const float dist = 0.5f + 4.f * rng.next_float();
        Interaction3f ref;
        ref.p = s->to_world.apply_point(d * dist);
        const auto [ds, weight] = s->sample_direction(ref, Vec2f(0.5f));
        // weight = W(w) / dist^2.
        const double value = double(weight.x) * dist * dist / pdf;
        sum += value;
        sum2 += value * value;
    }
    const double mean = sum / n, stderr_ = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, 1.0, 5 * stderr_) << "stderr " << stderr_; // 5 standard errors
    EXPECT_LT(stderr_, 0.01);                                    // the test has power
}

TEST(CamSensor, OrthographicExtentAndImportance) {
    SensorSpec spec;
    spec.type = "orthographic";
    spec.width = 100;
    spec.height = 50;
    // Camera at z = -1 looking along +z, view scaled by 2: the film spans x in [-2, 2], y in [-1, 1].
    spec.to_world = Transform::translate(Vec3f(0, 0, -1)) * Transform::scale(Vec3f(2.f, 2.f, 1.f));
    auto s = build(spec);
    const auto [top_left, w] = s->sample_ray(Vec2f(0.f, 0.f), Vec2f(0.5f));
    EXPECT_NEAR(norm(top_left.o - Vec3f(2.f, 1.f, -1.f + 0.01f)), 0.f,
                1e-5f); // +x is left; origin on the near plane
    EXPECT_NEAR(norm(top_left.d - Vec3f(0, 0, 1)), 0.f, 1e-6f);
    const auto [bottom_right, w2] = s->sample_ray(Vec2f(100.f, 50.f), Vec2f(0.5f));
    EXPECT_NEAR(norm(bottom_right.o - Vec3f(-2.f, -1.f, -1.f + 0.01f)), 0.f, 1e-5f);
    Vec2f fp;
    ASSERT_TRUE(s->project(Vec3f(1.f, -0.5f, 3.f), fp));
    EXPECT_NEAR(fp.x, 25.f, 1e-4f);
    EXPECT_NEAR(fp.y, 37.5f, 1e-4f);
    EXPECT_FALSE(s->project(Vec3f(2.5f, 0.f, 3.f), fp));
    Interaction3f ref;
    ref.p = Vec3f(1.f, -0.5f, 3.f);
    const auto [ds, weight] = s->sample_direction(ref, Vec2f(0.5f));
    EXPECT_NEAR(weight.x * 8.f, 1.f, 1e-6f); // 1 / film area (4 x 2)
    EXPECT_NEAR(norm(ds.d - Vec3f(0, 0, -1)), 0.f, 1e-6f);
    EXPECT_NEAR(ds.dist, 4.f - 0.01f, 1e-5f);
}

// Several sensors load in declaration order (a sensor nested in a shape counts where the shape is); the first
// is rendered unless another is selected (Mitsuba's scene.sensors()).
TEST(CamSensor, SeveralSensorsLoadInOrder) {
    auto scene = load_scene_string(R"(<scene version="3.0.0">
      <sensor type="perspective" id="front"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>
      <sensor type="orthographic" id="top"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
      <shape type="sphere"><sensor type="irradiancemeter" id="probe"><film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film></sensor></shape>
    </scene>)");
    ASSERT_EQ(scene->sensors.size(), 3u);
    EXPECT_EQ(scene->sensors[0]->id, "front");
    EXPECT_EQ(scene->sensors[1]->id, "top");
    EXPECT_EQ(scene->sensors[2]->id, "probe");
    EXPECT_EQ(scene->sensor, scene->sensors[0]);
    EXPECT_EQ(scene->sensors[1]->film->width, 4);
    scene->select_sensor("top");
    EXPECT_EQ(scene->sensor, scene->sensors[1]);
    scene->select_sensor("2");
    EXPECT_EQ(scene->sensor, scene->sensors[2]);
    try {
        scene->select_sensor("side");
        FAIL();
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "unknown sensor 'side' (the scene's sensors: 0 (front), 1 (top), 2 (probe))");
    }
}
