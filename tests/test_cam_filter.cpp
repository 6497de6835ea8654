// Reconstruction filters (normalization, sampling) and the hdrfilm factory.
#include "core/rng.h"
#include "scene/factory.h"
#include "scene/film.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

std::shared_ptr<ReconstructionFilter> make_filter(const std::string& type) {
    LoadContext ctx;
    Properties props(type, {"scene.xml", 2});
    auto filter = std::static_pointer_cast<ReconstructionFilter>(make_rfilter(props, ctx));
    filter->plugin = type;
    return filter;
}

// Integral of the normalized 1D profile f(x) / ∫f over [a, b] (midpoint rule, 4096 points).
double profile_mass(const ReconstructionFilter& f, double a, double b) {
    const int n = 4096;
    const double r = f.radius(), h_all = 2.0 * r / n;
    double total = 0.0, part = 0.0;
    for (int i = 0; i < n; ++i) {
        const double x = -r + (i + 0.5) * h_all;
        total += f.eval(float(x));
    }
    const double h = (b - a) / n;
    for (int i = 0; i < n; ++i)
        part += f.eval(float(a + (i + 0.5) * h)) * h;
    return part / (total * h_all);
}

} // namespace

TEST(CamFilter, Profiles) {
    auto box = make_filter("box"), tent = make_filter("tent"), gauss = make_filter("gaussian");
    EXPECT_EQ(box->radius(), 0.5f);
    EXPECT_EQ(tent->radius(), 1.f);
    EXPECT_EQ(gauss->radius(), 2.f);
    EXPECT_EQ(box->eval(0.49f), 1.f);
    EXPECT_EQ(box->eval(0.51f), 0.f);
    EXPECT_FLOAT_EQ(tent->eval(0.25f), 0.75f);
    // Mitsuba's gaussian with stddev 0.5: exp(-2 x^2) minus its value at the radius 2, exp(-8).
    EXPECT_FLOAT_EQ(gauss->eval(0.5f), std::exp(-0.5f) - std::exp(-8.f));
    EXPECT_EQ(gauss->eval(2.5f), 0.f);
}

TEST(CamFilter, NormalizedEvalIntegratesToOne) {
    for (const char* type : {"box", "tent", "gaussian"}) {
        auto f = make_filter(type);
        // 2D midpoint rule on a 600^2 grid over [-r, r]^2; the filter's own normalization uses a 1024-bin
        // midpoint rule. Both are exact for box/tent (kinks on bin edges) and O(h^2) ~ 1e-5 for the gaussian.
        const int n = 600;
        const double r = f->radius(), h = 2.0 * r / n;
        double sum = 0.0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                sum += f->eval_normalized(Vec2f(float(-r + (i + 0.5) * h), float(-r + (j + 0.5) * h)));
        EXPECT_NEAR(sum * h * h, 1.0, 2e-4) << type;
    }
}

TEST(CamFilter, SampleHistogramMatchesEval) {
    for (const char* type : {"box", "tent", "gaussian"}) {
        auto f = make_filter(type);
        const int bins = 8, n = 400000;
        const double r = f->radius();
        std::vector<int> hist(bins * bins, 0);
        PCG32 rng(7, 11);
        for (int k = 0; k < n; ++k) {
            const Vec2f s = f->sample(Vec2f(rng.next_float(), rng.next_float()));
            ASSERT_LE(std::abs(s.x), r) << type;
            ASSERT_LE(std::abs(s.y), r) << type;
            const int bx = std::min(bins - 1, int((s.x + r) / (2 * r) * bins));
            const int by = std::min(bins - 1, int((s.y + r) / (2 * r) * bins));
            ++hist[by * bins + bx];
        }
        std::vector<double> marginal(bins);
        for (int b = 0; b < bins; ++b)
            marginal[b] = profile_mass(*f, -r + 2 * r * b / bins, -r + 2 * r * (b + 1) / bins);
        for (int by = 0; by < bins; ++by)
            for (int bx = 0; bx < bins; ++bx) {
                const double p = marginal[bx] * marginal[by];
                const double observed = hist[by * bins + bx] / double(n);
                // Binomial standard error of a bin frequency; 5 sigma over 192 bins: false alarm rate ~1e-4.
                const double sigma = std::sqrt(p * (1 - p) / n);
                EXPECT_NEAR(observed, p, 5 * sigma + 1e-6) << type << " bin " << bx << "," << by;
            }
    }
}

TEST(CamFilter, TentAndGaussianParameters) {
    LoadContext ctx;
    Properties tent("tent", {"scene.xml", 2});
    tent.set("radius", 2.0, {"scene.xml", 3});
    EXPECT_EQ(std::static_pointer_cast<ReconstructionFilter>(make_rfilter(tent, ctx))->radius(), 2.f);
    Properties gauss("gaussian", {"scene.xml", 2});
    gauss.set("stddev", 0.25, {"scene.xml", 3});
    EXPECT_EQ(std::static_pointer_cast<ReconstructionFilter>(make_rfilter(gauss, ctx))->radius(), 1.f);
    EXPECT_THROW(make_rfilter(Properties("lanczos-ish", {"scene.xml", 2}), ctx), LoadError);
}

TEST(CamFilm, DefaultsAndValidation) {
    LoadContext ctx;
    Properties props("hdrfilm", {"scene.xml", 4});
    auto film = std::static_pointer_cast<Film>(make_film(props, ctx));
    EXPECT_EQ(film->width, 768);
    EXPECT_EQ(film->height, 576);
    ASSERT_TRUE(film->rfilter);
    EXPECT_EQ(film->rfilter->radius(), 2.f); // gaussian, stddev 0.5

    Properties custom("hdrfilm", {"scene.xml", 4});
    custom.set("width", int64_t(32), {"scene.xml", 5});
    custom.set("height", int64_t(16), {"scene.xml", 6});
    custom.set("pixel_format", std::string("rgba"), {"scene.xml", 7});
    custom.set("component_format", std::string("float32"), {"scene.xml", 8});
    custom.add_object("", make_filter("box"), {"scene.xml", 9});
    film = std::static_pointer_cast<Film>(make_film(custom, ctx));
    EXPECT_TRUE(custom.unqueried().empty());
    EXPECT_EQ(film->width, 32);
    EXPECT_EQ(film->rfilter->radius(), 0.5f);

    Properties crop("hdrfilm", {"scene.xml", 4});
    crop.set("crop_offset_x", int64_t(700), {"scene.xml", 11});
    crop.set("crop_width", int64_t(100), {"scene.xml", 12}); // 700 + 100 > 768
    try {
        make_film(crop, ctx);
        FAIL();
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.xml:12"), std::string::npos) << e.what();
    }
    Properties bad_format("hdrfilm", {"scene.xml", 4});
    bad_format.set("pixel_format", std::string("xyzw"), {"scene.xml", 13});
    EXPECT_THROW(make_film(bad_format, ctx), LoadError);
    EXPECT_THROW(make_film(Properties("specfilm", {"scene.xml", 4}), ctx), LoadError);
}
