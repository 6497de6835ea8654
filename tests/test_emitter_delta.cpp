// Point, spot and directional emitters: delta sampling, Mitsuba's parameters and their errors.
#include "core/rng.h"
#include "scene/emitter.h"
#include "scene/factory.h"

#include <gtest/gtest.h>

using namespace penumbra;

namespace {

SourceLocation at(int line) { return {"scene.xml", line}; }

std::shared_ptr<Emitter> make(const Properties& props) {
    auto e = std::dynamic_pointer_cast<Emitter>(make_emitter(props, LoadContext{}));
    props.check_all_queried("emitter");
    return e;
}

Interaction3f point_at(const Vec3f& p) {
    Interaction3f it;
    it.p = p;
    return it;
}

std::string load_error(const Properties& props) {
    try {
        make(props);
    } catch (const LoadError& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST(EmitterPoint, SampleDirectionIsInverseSquare) {
    Properties props("point", at(1));
    props.set("position", Vec3f(1.f, 2.f, 3.f), at(2));
    props.set("intensity", ColorValue{Color3f(2.f, 3.f, 4.f)}, at(3));
    auto e = make(props);
    EXPECT_TRUE(e->is_delta());
    const Interaction3f ref = point_at({1.f, 2.f, 0.f});
    auto [ds, w] = e->sample_direction(ref, {0.3f, 0.7f});
    EXPECT_TRUE(ds.delta);
    EXPECT_FLOAT_EQ(ds.dist, 3.f);
    EXPECT_NEAR(ds.d.z, 1.f, 1e-6f);
    // weight * pdf * dist^2 = I (pdf is the discrete probability 1).
    EXPECT_FLOAT_EQ(w.x * ds.pdf * 9.f, 2.f);
    EXPECT_FLOAT_EQ(w.z * ds.pdf * 9.f, 4.f);
    EXPECT_EQ(e->pdf_direction(ref, ds), 0.f);
    EXPECT_TRUE(is_black(e->eval_environment(Vec3f(0.f, 0.f, 1.f))));
    EXPECT_FLOAT_EQ(e->power().y, 3.f * 4.f * Pi);
}

TEST(EmitterPoint, ToWorldPlacesTheLightAtItsOrigin) {
    Properties props("point", at(1));
    props.set("to_world", Transform::translate({0.f, 5.f, 0.f}), at(2));
    auto e = make(props);
    auto [ds, w] = e->sample_direction(point_at(Vec3f(0.f)), {0.5f, 0.5f});
    EXPECT_NEAR(ds.p.y, 5.f, 1e-6f);
    EXPECT_FLOAT_EQ(w.x, 1.f / 25.f); // default intensity 1
}

TEST(EmitterPoint, RejectsBadParameters) {
    Properties both("point", at(1));
    both.set("position", Vec3f(0.f), at(2));
    both.set("to_world", Transform(), at(3));
    EXPECT_NE(load_error(both).find("scene.xml:2"), std::string::npos);

    Properties negative("point", at(1));
    negative.set("intensity", ColorValue{Color3f(1.f, -1.f, 1.f)}, at(4));
    const std::string msg = load_error(negative);
    EXPECT_NE(msg.find("scene.xml:4"), std::string::npos) << msg;
    EXPECT_NE(msg.find("intensity"), std::string::npos) << msg;
}

TEST(EmitterFactory, UnknownTypeIsALoadError) {
    Properties props("laser", at(9));
    const std::string msg = load_error(props);
    EXPECT_NE(msg.find("scene.xml:9"), std::string::npos) << msg;
    EXPECT_NE(msg.find("laser"), std::string::npos) << msg;
}

namespace {

// Spot at the origin pointing along +x (look_at), cutoff 30 deg, beam width 10 deg, intensity 2.
std::shared_ptr<Emitter> make_spot() {
    Properties props("spot", at(1));
    props.set("to_world", Transform::look_at({0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 0.f, 1.f}), at(2));
    props.set("cutoff_angle", 30.0, at(3));
    props.set("beam_width", 10.0, at(4));
    props.set("intensity", ColorValue{Color3f(2.f)}, at(5));
    return make(props);
}

// weight * dist^2 / I at angle theta (degrees) off the spot axis, at distance 2.
float spot_falloff(const Emitter& e, float theta_deg) {
    const float t = radians(theta_deg);
    auto [ds, w] = e.sample_direction(point_at(Vec3f(std::cos(t), std::sin(t), 0.f) * 2.f), {0.5f, 0.5f});
    return w.x * ds.dist * ds.dist / 2.f;
}

} // namespace

TEST(EmitterSpot, FalloffMatchesMitsubaProfile) {
    auto e = make_spot();
    EXPECT_FLOAT_EQ(spot_falloff(*e, 0.f), 1.f);
    EXPECT_NEAR(spot_falloff(*e, 9.99f), 1.f, 1e-6f);     // inside the beam
    EXPECT_NEAR(spot_falloff(*e, 10.f), 1.f, 1e-4f);      // at the beam width (continuous there)
    EXPECT_NEAR(spot_falloff(*e, 20.f), 0.5f, 1e-4f);     // linear in angle: (30 - 20) / (30 - 10)
    EXPECT_NEAR(spot_falloff(*e, 29.9f), 0.005f, 1e-4f);  // -> 0 at the cutoff
    EXPECT_EQ(spot_falloff(*e, 30.1f), 0.f);
    EXPECT_EQ(spot_falloff(*e, 120.f), 0.f);
}

TEST(EmitterSpot, DefaultBeamWidthIsThreeQuartersOfTheCutoff) {
    Properties props("spot", at(1));
    props.set("cutoff_angle", 40.0, at(2));
    auto e = make(props); // points along +z, beam width 30 deg
    auto falloff = [&](float deg) {
        const float t = radians(deg);
        auto [ds, w] = e->sample_direction(point_at(Vec3f(std::sin(t), 0.f, std::cos(t))), {0.f, 0.f});
        return w.x;
    };
    EXPECT_NEAR(falloff(29.9f), 1.f, 1e-5f);
    EXPECT_NEAR(falloff(35.f), 0.5f, 1e-4f);
}

TEST(EmitterSpot, SampleRayPowerMatchesAnalyticPower) {
    auto e = make_spot();
    PCG32 rng(7);
    const int n = 200000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        auto [ray, w] = e->sample_ray({rng.next_float(), rng.next_float()}, {rng.next_float(), rng.next_float()});
        ASSERT_GT(ray.d.x, std::cos(radians(30.f)) - 1e-5f); // inside the cone around +x
        sum += w.x;
        sum2 += double(w.x) * w.x;
    }
    const double mean = sum / n, stderr_ = std::sqrt((sum2 / n - mean * mean) / n);
    // Monte Carlo estimate of int I falloff dw: 3 standard errors.
    EXPECT_NEAR(mean, e->power().x, 3 * stderr_);
}

// Mitsuba applies a spot's texture only when it is spatially varying: a constant one changes nothing.
TEST(EmitterSpot, ConstantTextureIsIgnoredAsInMitsuba) {
    Properties plain("spot", at(1)), textured("spot", at(1));
    textured.set("texture", ColorValue{Color3f(2.f)}, at(6));
    const Interaction3f ref = point_at({0.1f, 0.05f, 3.f});
    const Color3f a = make(plain)->sample_direction(ref, {0.5f, 0.5f}).second;
    const Color3f b = make(textured)->sample_direction(ref, {0.5f, 0.5f}).second;
    EXPECT_GT(a.x, 0.f);
    EXPECT_EQ(a.x, b.x);
}

TEST(EmitterSpot, BeamWiderThanCutoffIsRejected) {
    Properties props("spot", at(1));
    props.set("cutoff_angle", 10.0, at(2));
    props.set("beam_width", 20.0, at(3));
    EXPECT_NE(load_error(props).find("scene.xml:3"), std::string::npos);
}

TEST(EmitterDirectional, SampleDirectionComesFromMinusDirection) {
    Properties props("directional", at(1));
    props.set("direction", Vec3f(0.f, 0.f, -2.f), at(2));
    props.set("irradiance", ColorValue{Color3f(3.f)}, at(3));
    auto e = make(props);
    e->set_scene_bounds({Vec3f(0.f), 2.f});
    EXPECT_TRUE(e->is_delta() && e->is_infinite());
    const Interaction3f ref = point_at({0.5f, 0.f, 0.f});
    auto [ds, w] = e->sample_direction(ref, {0.1f, 0.9f});
    EXPECT_NEAR(ds.d.z, 1.f, 1e-6f); // toward the light, against the propagation direction
    EXPECT_FLOAT_EQ(w.x * ds.pdf, 3.f);
    EXPECT_GT(ds.dist, 4.f); // beyond the bounding sphere
    EXPECT_EQ(e->pdf_direction(ref, ds), 0.f);
    EXPECT_TRUE(is_black(e->eval_environment(Vec3f(0.f, 0.f, 1.f))));
}

TEST(EmitterDirectional, ToWorldUsesLocalZ) {
    Properties props("directional", at(1));
    props.set("to_world", Transform::rotate({1.f, 0.f, 0.f}, 90.f), at(2)); // local +z -> world -y
    auto e = make(props);
    auto [ds, w] = e->sample_direction(point_at(Vec3f(0.f)), {0.f, 0.f});
    EXPECT_NEAR(ds.d.y, 1.f, 1e-6f);
    EXPECT_FLOAT_EQ(w.x, 1.f);
}

TEST(EmitterDirectional, SampleRayCoversTheBoundingDisk) {
    Properties props("directional", at(1));
    props.set("direction", Vec3f(1.f, 1.f, 0.f), at(2));
    auto e = make(props);
    const BoundingSphere b{Vec3f(1.f, 2.f, 3.f), 2.f};
    e->set_scene_bounds(b);
    const Vec3f d = normalize(Vec3f(1.f, 1.f, 0.f));
    const float r = 2.f * (1.f + RayEpsilon); // Mitsuba enlarges the scene's bounding sphere
    PCG32 rng(3);
    for (int i = 0; i < 1000; ++i) {
        auto [ray, w] = e->sample_ray({rng.next_float(), rng.next_float()}, {rng.next_float(), rng.next_float()});
        const Vec3f rel = ray.o - b.center;
        EXPECT_NEAR(dot(ray.d, d), 1.f, 1e-6f);
        EXPECT_NEAR(dot(rel, d), -r, 1e-5f);             // upstream by one radius
        EXPECT_LE(norm(rel - d * dot(rel, d)), r + 1e-5f); // within the disk
        EXPECT_FLOAT_EQ(w.x, Pi * r * r);                  // E * pi r^2
    }
}

TEST(EmitterDirectional, DirectionAndToWorldAreExclusive) {
    Properties props("directional", at(1));
    props.set("direction", Vec3f(1.f, 0.f, 0.f), at(2));
    props.set("to_world", Transform(), at(3));
    EXPECT_NE(load_error(props).find("scene.xml:2"), std::string::npos);
}
