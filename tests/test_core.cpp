// Core math: transforms, distributions, RNG streams.
#include "core/distribution.h"
#include "core/sampler.h"
#include "core/transform.h"
#include "core/warp.h"

#include <gtest/gtest.h>

using namespace penumbra;

TEST(Transform, InverseRoundTrip) {
    const Transform t = Transform::translate({1, 2, 3}) * Transform::rotate({0.3f, 1, 0.2f}, 37.f) *
                        Transform::scale({2, 0.5f, 3});
    const Vec3f p(0.3f, -1.2f, 4.f);
    const Vec3f q = t.inverse().apply_point(t.apply_point(p));
    EXPECT_NEAR(norm(q - p), 0.f, 1e-5f);
}

TEST(Transform, LookAtMatchesMitsubaConvention) {
    // Camera at origin looking down +z with up +y: local x is "left" = +x world for this set-up (cross(up, dir)).
    const Transform t = Transform::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0});
    const Vec3f x = t.apply_vector(Vec3f(1, 0, 0));
    EXPECT_NEAR(x.x, 1.f, 1e-6f);
    const Vec3f z = t.apply_vector(Vec3f(0, 0, 1));
    EXPECT_NEAR(z.z, 1.f, 1e-6f);
}

TEST(Transform, NormalsStayPerpendicular) {
    const Transform t = Transform::scale({1, 4, 1}) * Transform::rotate({0, 0, 1}, 30.f);
    const Vec3f tangent = t.apply_vector(Vec3f(1, 1, 0));
    const Vec3f normal = t.apply_normal(Vec3f(1, -1, 0));
    EXPECT_NEAR(dot(tangent, normal), 0.f, 1e-5f);
}

TEST(Distribution, DiscreteMatchesWeights) {
    DiscreteDistribution d({1.f, 0.f, 3.f});
    EXPECT_FLOAT_EQ(d.pmf(0), 0.25f);
    EXPECT_FLOAT_EQ(d.pmf(1), 0.f);
    int counts[3] = {0, 0, 0};
    PCG32 rng;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
        float u = rng.next_float();
        const size_t k = d.sample(u);
        ASSERT_GE(u, 0.f);
        ASSERT_LT(u, 1.f);
        counts[k]++;
    }
    EXPECT_EQ(counts[1], 0);
    // Binomial standard error of the fraction: sqrt(p(1-p)/n) ~ 0.0014; 5 sigma.
    EXPECT_NEAR(counts[0] / double(n), 0.25, 0.007);
}

TEST(Distribution, TwoDimensionalPdfIntegratesToOne) {
    std::vector<float> v = {1, 2, 3, 4, 0, 6};
    Distribution2D d(v, 3, 2);
    double integral = 0;
    const int n = 60;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) integral += d.pdf({(x + 0.5f) / n, (y + 0.5f) / n});
    EXPECT_NEAR(integral / (n * n), 1.0, 1e-5);
    float pdf;
    const Vec2f p = d.sample({0.3f, 0.7f}, pdf);
    EXPECT_NEAR(pdf, d.pdf(p), 1e-5f);
}

TEST(Sampler, StreamsDependOnlyOnSeedPixelAndIndex) {
    Sampler a, b;
    a.start(7, 123, 5);
    b.start(7, 124, 5);
    b.start(7, 123, 5);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(a.next_1d(), b.next_1d());
    a.start(8, 123, 5);
    b.start(7, 123, 5);
    EXPECT_NE(a.next_1d(), b.next_1d());
}

TEST(Warp, CosineHemisphereIsNormalizedAndUpper) {
    PCG32 rng;
    for (int i = 0; i < 1000; ++i) {
        const Vec3f d = warp::square_to_cosine_hemisphere({rng.next_float(), rng.next_float()});
        EXPECT_NEAR(norm(d), 1.f, 1e-5f);
        EXPECT_GE(d.z, 0.f);
    }
}
