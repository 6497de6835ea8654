// Infinite emitters: constant and envmap (lat-long convention, sampling density, irradiance, loading).
#include "core/image.h"
#include "core/rng.h"
#include "scene/emitters/emitters.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace penumbra;

namespace {

SourceLocation at(int line) { return {"scene.xml", line}; }

Interaction3f point_at(const Vec3f& p, const Vec3f& n = Vec3f(0.f)) {
    Interaction3f it;
    it.p = p;
    it.n = n;
    return it;
}

struct Stats {
    double sum = 0, sum2 = 0;
    int n = 0;
    void add(double v) { sum += v, sum2 += v * v, ++n; }
    double mean() const { return sum / n; }
    double stderr_() const { return std::sqrt(std::max(0.0, sum2 / n - mean() * mean()) / n); }
};

// Mitsuba's lat-long direction for (u, v) in the emitter's local frame.
Vec3f latlong(float u, float v) {
    const float phi = 2.f * Pi * u, theta = Pi * v;
    return {std::sin(phi) * std::sin(theta), std::cos(theta), -std::cos(phi) * std::sin(theta)};
}

// 8x5 test map: smooth gradient plus a bright pixel, all positive.
Image test_image() {
    Image img(8, 5);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 8; ++x)
            img.at(x, y) = Color3f(1.f + x, 1.f + 2.f * y, 0.5f);
    img.at(2, 2) = Color3f(60.f, 40.f, 20.f);
    return img;
}

// Midpoint quadrature over the sphere in (phi, cos theta): sum f(d) dw on an n_phi x n_z grid.
template <typename F> double sphere_quadrature(int n_phi, int n_z, F&& f) {
    double total = 0;
    const double dw = (2.0 * Pi / n_phi) * (2.0 / n_z);
    for (int j = 0; j < n_z; ++j) {
        const float z = -1.f + (j + 0.5f) * 2.f / n_z;
        const float r = std::sqrt(1.f - z * z);
        for (int i = 0; i < n_phi; ++i) {
            const float phi = (i + 0.5f) * 2.f * Pi / n_phi;
            total += f(Vec3f(r * std::cos(phi), r * std::sin(phi), z)) * dw;
        }
    }
    return total;
}

} // namespace

// ---- constant ---------------------------------------------------------------------------------------------

TEST(EmitterConstant, SampleDirectionIsUniform) {
    Properties props("constant", at(1));
    props.set("radiance", ColorValue{Color3f(2.f, 3.f, 4.f)}, at(2));
    auto e = std::dynamic_pointer_cast<Emitter>(make_emitter(props, LoadContext{}));
    props.check_all_queried("emitter");
    e->set_scene_bounds({Vec3f(1.f), 3.f});
    EXPECT_TRUE(e->is_infinite() && !e->is_delta());
    const Interaction3f ref = point_at(Vec3f(0.f));
    PCG32 rng(1);
    for (int i = 0; i < 100; ++i) {
        auto [ds, w] = e->sample_direction(ref, {rng.next_float(), rng.next_float()});
        EXPECT_NEAR(w.y * ds.pdf, 3.f, 1e-5f);
        EXPECT_FLOAT_EQ(e->pdf_direction(ref, ds), ds.pdf);
        EXPECT_FLOAT_EQ(ds.pdf, Inv4Pi);
        EXPECT_GT(norm(ds.p - Vec3f(1.f)), 3.f); // outside the bounding sphere
        EXPECT_FLOAT_EQ(e->eval_environment(ds.d).z, 4.f);
    }
}

TEST(EmitterConstant, IrradianceOnAPlaneIsPiL) {
    Properties props("constant", at(1));
    props.set("radiance", ColorValue{Color3f(1.5f)}, at(2));
    auto e = std::dynamic_pointer_cast<Emitter>(make_emitter(props, LoadContext{}));
    const Vec3f n = normalize(Vec3f(0.3f, -1.f, 0.2f));
    const Interaction3f ref = point_at(Vec3f(0.f), n);
    PCG32 rng(2);
    Stats s;
    for (int i = 0; i < 100000; ++i) {
        auto [ds, w] = e->sample_direction(ref, {rng.next_float(), rng.next_float()});
        s.add(w.x * std::max(0.f, dot(ds.d, n)));
    }
    // E = pi L for a plane under a uniform sky; 3 standard errors of the estimate.
    EXPECT_NEAR(s.mean(), Pi * 1.5, 3 * s.stderr_());
}

TEST(EmitterConstant, SampleRayEntersTheBoundingSphereCosineWeighted) {
    Properties props("constant", at(1));
    auto e = std::dynamic_pointer_cast<Emitter>(make_emitter(props, LoadContext{}));
    const BoundingSphere b{Vec3f(0.f, 1.f, 0.f), 2.f};
    e->set_scene_bounds(b);
    PCG32 rng(4);
    Stats cosines;
    for (int i = 0; i < 50000; ++i) {
        auto [ray, w] =
            e->sample_ray({rng.next_float(), rng.next_float()}, {rng.next_float(), rng.next_float()});
        const Vec3f inward = normalize(b.center - ray.o);
        ASSERT_NEAR(norm(ray.o - b.center), 2.f, 1e-3f);
        ASSERT_GE(dot(ray.d, inward), 0.f);
        EXPECT_FLOAT_EQ(w.x, e->power().x); // constant weight: 4 pi^2 r^2 L
        cosines.add(dot(ray.d, inward));
    }
    // Cosine-weighted hemisphere: E[cos] = 2/3; 3 standard errors.
    EXPECT_NEAR(cosines.mean(), 2.0 / 3.0, 3 * cosines.stderr_());
}

// ---- envmap -----------------------------------------------------------------------------------------------

TEST(EmitterEnvmap, LatLongConventionMatchesMitsuba) {
    const Image img = test_image();
    auto e = make_envmap_emitter(img, 2.f, Transform(), false);
    // Pixel (x, y) sits at u = (x + 1/2) / W, v = y / (H - 1).
    for (int y = 1; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            const Color3f L = e->eval_environment(latlong((x + 0.5f) / 8.f, y / 4.f));
            EXPECT_NEAR(L.x, 2.f * img.at(x, y).x, 1e-3f) << x << "," << y;
            EXPECT_NEAR(L.y, 2.f * img.at(x, y).y, 1e-3f) << x << "," << y;
        }
    // -z is u = 0: halfway between the last and the first column; +x is u = 1/4: between columns 1 and 2.
    EXPECT_NEAR(e->eval_environment(Vec3f(0.f, 0.f, -1.f)).x, 2.f * 0.5f * (8.f + 1.f), 1e-3f);
    EXPECT_NEAR(e->eval_environment(Vec3f(1.f, 0.f, 0.f)).y, 2.f * 0.5f * (5.f + 40.f), 1e-3f);
    EXPECT_NEAR(e->eval_environment(Vec3f(1.f, 0.f, 0.f)).x, 2.f * 0.5f * (60.f + 2.f), 1e-3f);
    // +y is the first row, -y the last row.
    EXPECT_NEAR(e->eval_environment(Vec3f(0.f, 1.f, 0.f)).y, 2.f * 1.f, 1e-3f);
    EXPECT_NEAR(e->eval_environment(Vec3f(0.f, -1.f, 0.f)).y, 2.f * 9.f, 1e-3f);
}

TEST(EmitterEnvmap, ToWorldRotatesTheMap) {
    const Transform r = Transform::rotate({0.3f, 1.f, -0.2f}, 70.f);
    auto plain = make_envmap_emitter(test_image(), 1.f, Transform(), false);
    auto rotated = make_envmap_emitter(test_image(), 1.f, r, false);
    PCG32 rng(5);
    for (int i = 0; i < 100; ++i) {
        const Vec3f d = latlong(rng.next_float(), rng.next_float());
        const Color3f a = plain->eval_environment(d), b = rotated->eval_environment(r.apply_vector(d));
        EXPECT_NEAR(a.x, b.x, 1e-3f * a.x);
    }
}

TEST(EmitterEnvmap, SampleDirectionMatchesEvalAndPdf) {
    auto e = make_envmap_emitter(test_image(), 1.f, Transform::rotate({1.f, 0.f, 0.f}, 30.f), false);
    e->set_scene_bounds({Vec3f(0.f), 1.f});
    const Interaction3f ref = point_at({5.f, 0.f, 0.f}); // outside the bounds (e.g. a camera)
    PCG32 rng(6);
    for (int i = 0; i < 2000; ++i) {
        auto [ds, w] = e->sample_direction(ref, {rng.next_float(), rng.next_float()});
        ASSERT_GT(ds.pdf, 0.f);
        const Color3f L = e->eval_environment(ds.d);
        EXPECT_NEAR(w.x * ds.pdf, L.x, 1e-3f * L.x);
        EXPECT_NEAR(e->pdf_direction(ref, ds), ds.pdf, 1e-3f * ds.pdf);
        EXPECT_GT(ds.dist, 5.f);
    }
}

TEST(EmitterEnvmap, PdfIntegratesToOne) {
    auto e = make_envmap_emitter(test_image(), 1.f, Transform(), false);
    const Interaction3f ref = point_at(Vec3f(0.f));
    DirectionSample3f ds;
    const double integral = sphere_quadrature(1024, 512, [&](const Vec3f& d) {
        ds.d = d;
        return e->pdf_direction(ref, ds);
    });
    // Midpoint rule on a density that is piecewise constant in (u, v): cells cut by the grid give O(1/512).
    EXPECT_NEAR(integral, 1.0, 5e-3);
}

TEST(EmitterEnvmap, SampledDirectionsFollowThePdf) {
    auto e = make_envmap_emitter(test_image(), 1.f, Transform(), false);
    const Interaction3f ref = point_at(Vec3f(0.f));
    // Bins in (phi, cos theta) about the world z axis, unrelated to the map's cells.
    const int n_phi = 10, n_z = 7, n = 200000;
    auto bin_of = [&](const Vec3f& d) {
        float phi = std::atan2(d.y, d.x);
        if (phi < 0.f) phi += 2.f * Pi;
        const int i = std::min(int(phi / (2.f * Pi) * n_phi), n_phi - 1);
        const int j = std::clamp(int((d.z + 1.f) * 0.5f * n_z), 0, n_z - 1);
        return j * n_phi + i;
    };
    std::vector<double> expected(n_phi * n_z, 0.0), observed(n_phi * n_z, 0.0);
    DirectionSample3f probe;
    sphere_quadrature(1000, 700, [&](const Vec3f& d) {
        probe.d = d;
        const double p = e->pdf_direction(ref, probe);
        expected[bin_of(d)] += p * (2.0 * Pi / 1000) * (2.0 / 700) * n;
        return 0.0;
    });
    PCG32 rng(8);
    for (int k = 0; k < n; ++k)
        observed[bin_of(e->sample_direction(ref, {rng.next_float(), rng.next_float()}).first.d)]++;
    double chi2 = 0;
    for (size_t b = 0; b < expected.size(); ++b) {
        ASSERT_GT(expected[b], 20.0);
        chi2 += sqr(observed[b] - expected[b]) / expected[b];
    }
    // chi^2 with k-1 = 69 degrees of freedom has mean 69 and sd sqrt(2*69) ~ 11.7: reject beyond mean + 5 sd.
    const double dof = double(expected.size() - 1);
    EXPECT_LT(chi2, dof + 5.0 * std::sqrt(2.0 * dof));
}

TEST(EmitterEnvmap, IrradianceMatchesQuadrature) {
    auto e = make_envmap_emitter(test_image(), 1.f, Transform(), false);
    const Vec3f n = normalize(Vec3f(0.4f, 0.6f, -0.3f));
    const Interaction3f ref = point_at(Vec3f(0.f), n);
    const double reference = sphere_quadrature(
        1024, 512, [&](const Vec3f& d) { return e->eval_environment(d).x * std::max(0.f, dot(d, n)); });
    PCG32 rng(9);
    Stats s;
    for (int i = 0; i < 100000; ++i) {
        auto [ds, w] = e->sample_direction(ref, {rng.next_float(), rng.next_float()});
        s.add(w.x * std::max(0.f, dot(ds.d, n)));
    }
    // 3 standard errors (the quadrature of a continuous integrand is accurate to ~1e-5 relative).
    EXPECT_NEAR(s.mean(), reference, 3 * s.stderr_());
}

TEST(EmitterEnvmap, SampleRayPowerMatchesPower) {
    auto e = make_envmap_emitter(test_image(), 1.f, Transform(), false);
    const BoundingSphere b{Vec3f(1.f, 0.f, 0.f), 2.f};
    e->set_scene_bounds(b);
    PCG32 rng(10);
    Stats s;
    for (int i = 0; i < 100000; ++i) {
        auto [ray, w] =
            e->sample_ray({rng.next_float(), rng.next_float()}, {rng.next_float(), rng.next_float()});
        ASSERT_LT(dot(ray.o - b.center, ray.d), 0.f); // starts outside, heading into the sphere
        s.add(w.x);
    }
    // pi r^2 int L dw: the power estimate uses a midpoint rule over the bilinear cells (error well below the
    // 3 stderr).
    EXPECT_NEAR(s.mean(), e->power().x, 3 * s.stderr_() + 1e-3 * e->power().x);
}

TEST(EmitterEnvmap, BlackMapIsNeverSampled) {
    auto e = make_envmap_emitter(Image(4, 3), 1.f, Transform(), false);
    auto [ds, w] = e->sample_direction(point_at(Vec3f(0.f)), {0.5f, 0.5f});
    EXPECT_TRUE(is_black(w));
    EXPECT_EQ(e->pdf_direction(point_at(Vec3f(0.f)), ds), 0.f);
}

TEST(EmitterEnvmap, MisCompensationKeepsSamplingConsistent) {
    auto e = make_envmap_emitter(test_image(), 1.f, Transform(), true);
    const Interaction3f ref = point_at(Vec3f(0.f));
    PCG32 rng(11);
    for (int i = 0; i < 500; ++i) {
        auto [ds, w] = e->sample_direction(ref, {rng.next_float(), rng.next_float()});
        ASSERT_GT(ds.pdf, 0.f);
        EXPECT_NEAR(e->pdf_direction(ref, ds), ds.pdf, 1e-3f * ds.pdf);
    }
}

TEST(EmitterEnvmap, LoadsFromFileThroughTheFactory) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "penumbra_test_emitter_env";
    std::filesystem::create_directories(dir);
    write_image((dir / "sky.exr").string(), test_image());
    Properties props("envmap", at(1));
    props.set("filename", std::string("sky.exr"), at(2));
    props.set("scale", 0.5, at(3));
    auto e = std::dynamic_pointer_cast<Emitter>(make_emitter(props, LoadContext{{dir.string()}}));
    props.check_all_queried("emitter");
    auto reference = make_envmap_emitter(test_image(), 0.5f, Transform(), false);
    const Vec3f d = normalize(Vec3f(0.2f, 0.5f, -0.7f));
    EXPECT_NEAR(e->eval_environment(d).x, reference->eval_environment(d).x, 1e-4f);

    Image tiny(1, 1, Color3f(1.f));
    write_image((dir / "tiny.exr").string(), tiny);
    Properties bad("envmap", at(1));
    bad.set("filename", std::string("tiny.exr"), at(4));
    try {
        make_emitter(bad, LoadContext{{dir.string()}});
        ADD_FAILURE() << "a 1x1 environment map must be rejected";
    } catch (const LoadError& err) {
        EXPECT_NE(std::string(err.what()).find("scene.xml:4"), std::string::npos) << err.what();
    }
    std::filesystem::remove_all(dir);
}

TEST(EmitterEnvmap, MissingFileAndNegativeScaleAreLoadErrors) {
    Properties missing("envmap", at(1));
    missing.set("filename", std::string("does_not_exist.exr"), at(5));
    EXPECT_THROW(make_emitter(missing, LoadContext{{"."}}), LoadError);

    Properties negative("envmap", at(1));
    negative.set("filename", std::string("does_not_exist.exr"), at(5));
    negative.set("scale", -1.0, at(6));
    try {
        make_emitter(negative, LoadContext{{"."}});
        ADD_FAILURE() << "a negative scale must be rejected";
    } catch (const LoadError& err) {
        EXPECT_NE(std::string(err.what()).find("scene.xml:6"), std::string::npos) << err.what();
    }
}
