// Area emitter on a square light facing down: solid-angle sampling, irradiance (Lambert's polygon formula),
// one-sidedness and light-tracing rays.
#include "core/rng.h"
#include "scene/factory.h"
#include "scene/shape.h"

#include <gtest/gtest.h>

using namespace penumbra;

namespace {

SourceLocation at(int line) { return {"scene.xml", line}; }

constexpr float Height = 1.5f, HalfSide = 0.5f;
const Color3f Radiance(2.f, 3.f, 4.f);

// A 1x1 square at z = Height, facing -z, with an area light of radiance (2, 3, 4).
struct SquareLight {
    std::shared_ptr<Shape> shape = std::make_shared<Shape>();
    std::shared_ptr<Emitter> emitter;
    SquareLight() {
        shape->mesh = make_rectangle_mesh();
        shape->mesh.apply_transform(Transform::translate({0.f, 0.f, Height}) * Transform::rotate({1.f, 0.f, 0.f}, 180.f) *
                                    Transform::scale({HalfSide, HalfSide, 1.f}));
        shape->finalize();
        Properties props("area", at(1));
        props.set("radiance", ColorValue{Radiance}, at(2));
        emitter = std::dynamic_pointer_cast<Emitter>(make_emitter(props, LoadContext{}));
        props.check_all_queried("emitter");
        emitter->set_shape(shape.get());
        shape->emitter = emitter;
    }
};

Interaction3f point_at(const Vec3f& p, const Vec3f& n) {
    Interaction3f it;
    it.p = p;
    it.n = n;
    return it;
}

// Lambert's formula: irradiance at p (normal n) from a uniform polygon of radiance L above p's tangent plane,
// E = L/2 |sum_i acos(v_i . v_i+1) n . normalize(v_i x v_i+1)| with v_i unit vectors to the vertices.
double polygon_irradiance(const std::vector<Vec3f>& vertices, const Vec3f& p, const Vec3f& n, double L) {
    double sum = 0;
    for (size_t i = 0; i < vertices.size(); ++i) {
        const Vec3f a = normalize(vertices[i] - p), b = normalize(vertices[(i + 1) % vertices.size()] - p);
        sum += std::acos(std::clamp(double(dot(a, b)), -1.0, 1.0)) * dot(n, normalize(cross(a, b)));
    }
    return 0.5 * L * std::abs(sum);
}

} // namespace

TEST(EmitterArea, SampleDirectionWeightAndPdfAreConsistent) {
    SquareLight light;
    const Interaction3f ref = point_at({0.3f, -0.2f, 0.f}, {0.f, 0.f, 1.f});
    PCG32 rng(1);
    for (int i = 0; i < 1000; ++i) {
        auto [ds, w] = light.emitter->sample_direction(ref, {rng.next_float(), rng.next_float()});
        ASSERT_GT(ds.pdf, 0.f);
        EXPECT_FALSE(ds.delta);
        EXPECT_NEAR(ds.p.z, Height, 1e-5f);
        // weight * pdf = L_e; the pdf is pdf_A dist^2 / cos_e with pdf_A = 1/area.
        EXPECT_NEAR(w.x * ds.pdf, Radiance.x, 1e-5f);
        EXPECT_NEAR(w.z * ds.pdf, Radiance.z, 1e-5f);
        const float expected_pdf = ds.dist * ds.dist / (4.f * HalfSide * HalfSide * ds.d.z);
        EXPECT_NEAR(ds.pdf, expected_pdf, 1e-4f * expected_pdf);
        EXPECT_NEAR(light.emitter->pdf_direction(ref, ds), ds.pdf, 1e-5f * ds.pdf);
    }
}

TEST(EmitterArea, ReferenceBehindTheLightGetsNothing) {
    SquareLight light;
    const Interaction3f ref = point_at({0.f, 0.f, Height + 1.f}, {0.f, 0.f, -1.f});
    auto [ds, w] = light.emitter->sample_direction(ref, {0.4f, 0.6f});
    EXPECT_TRUE(is_black(w));
    EXPECT_EQ(light.emitter->pdf_direction(ref, ds), 0.f);
}

TEST(EmitterArea, IrradianceMatchesLambertPolygonFormula) {
    SquareLight light;
    const Vec3f p(0.3f, -0.2f, 0.f), n = normalize(Vec3f(0.1f, 0.2f, 1.f));
    const std::vector<Vec3f> square = {{-HalfSide, -HalfSide, Height},
                                       {HalfSide, -HalfSide, Height},
                                       {HalfSide, HalfSide, Height},
                                       {-HalfSide, HalfSide, Height}};
    const double reference = polygon_irradiance(square, p, n, Radiance.y);
    PCG32 rng(2);
    double sum = 0, sum2 = 0;
    const int count = 100000;
    for (int i = 0; i < count; ++i) {
        auto [ds, w] = light.emitter->sample_direction(point_at(p, n), {rng.next_float(), rng.next_float()});
        const double v = w.y * std::max(0.f, dot(ds.d, n));
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / count, stderr_ = std::sqrt((sum2 / count - mean * mean) / count);
    // Monte Carlo estimate vs the exact value: 3 standard errors.
    EXPECT_NEAR(mean, reference, 3 * stderr_);
}

TEST(EmitterArea, EvalIsOneSidedOnTheGeometricNormal) {
    SquareLight light;
    // From below (front side: the light faces -z) and from above (back side).
    const Ray up(Vec3f(0.1f, 0.1f, 0.f), Vec3f(0.f, 0.f, 1.f)), down(Vec3f(0.1f, 0.1f, 3.f), Vec3f(0.f, 0.f, -1.f));
    const SurfaceInteraction3f front = light.shape->compute_surface_interaction(up, Height, 0, 0.2f, 0.3f);
    const SurfaceInteraction3f back = light.shape->compute_surface_interaction(down, 3.f - Height, 0, 0.2f, 0.3f);
    EXPECT_EQ(light.emitter->eval(front), Radiance);
    EXPECT_TRUE(is_black(light.emitter->eval(back)));
    EXPECT_TRUE(is_black(light.emitter->eval_environment(Vec3f(0.f, 0.f, 1.f))));
}

TEST(EmitterArea, SampleRayEmitsCosineWeightedFromTheFront) {
    SquareLight light;
    const float area = 4.f * HalfSide * HalfSide;
    EXPECT_FLOAT_EQ(light.emitter->power().x, Pi * Radiance.x * area);
    PCG32 rng(3);
    double sum_w = 0, sum_cos = 0, sum_cos2 = 0;
    const int count = 50000;
    for (int i = 0; i < count; ++i) {
        auto [ray, w] = light.emitter->sample_ray({rng.next_float(), rng.next_float()}, {rng.next_float(), rng.next_float()});
        ASSERT_NEAR(ray.o.z, Height, 1e-3f);
        ASSERT_LE(std::abs(ray.o.x), HalfSide + 1e-5f);
        ASSERT_LE(ray.d.z, 0.f); // front side only
        sum_w += w.x;
        const double c = -ray.d.z;
        sum_cos += c;
        sum_cos2 += c * c;
    }
    // Mean power estimate pi L A (the weight is constant for a uniform light, so only float rounding remains).
    EXPECT_NEAR(sum_w / count, Pi * Radiance.x * area, 1e-4 * Pi * Radiance.x * area);
    // Cosine-weighted directions: E[cos] = 2/3; 3 standard errors.
    const double mean = sum_cos / count, stderr_ = std::sqrt((sum_cos2 / count - mean * mean) / count);
    EXPECT_NEAR(mean, 2.0 / 3.0, 3 * stderr_);
}

TEST(EmitterArea, ToWorldAndNegativeRadianceAreRejected) {
    Properties with_transform("area", at(1));
    with_transform.set("to_world", Transform(), at(3));
    try {
        make_emitter(with_transform, LoadContext{});
        ADD_FAILURE() << "to_world must be rejected";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.xml:3"), std::string::npos) << e.what();
    }
    Properties negative("area", at(1));
    negative.set("radiance", ColorValue{Color3f(-1.f)}, at(4));
    try {
        make_emitter(negative, LoadContext{});
        ADD_FAILURE() << "negative radiance must be rejected";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.xml:4"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("radiance"), std::string::npos) << e.what();
    }
}
