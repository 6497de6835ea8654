// The derivative-method front (diff/method.h): the registry, option checking, and that each method's adapter
// returns exactly what its estimator returns for the same options and seed (forward and reverse mode), so the
// CLI and the Python module, which only go through the front, differentiate like the estimators' own tests.
#include "diff/method.h"
#include "diff/paths/path_sampling.h"
#include "diff/psdr/psdr.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

using namespace penumbra;

namespace {

// A diffuse box on a glossy floor under an area light, 16x16.
std::unique_ptr<Scene> small_scene() {
    return load_scene_string(R"(<scene version="3.0.0">
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,2,4" target="0,0.3,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
      <shape type="rectangle" id="floor"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
        <bsdf type="roughconductor" id="metal"><float name="alpha" value="0.3"/></bsdf></shape>
      <shape type="cube" id="box"><transform name="to_world"><scale value="0.4"/><translate value="0,0.4,0"/></transform>
        <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7,0.6,0.5"/></bsdf></shape>
      <shape type="rectangle" id="light"><transform name="to_world"><rotate x="1" angle="90"/><translate value="0,3,0"/></transform>
        <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
    </scene>)");
}

std::string error_of(const std::string& method, const std::map<std::string, std::string>& given) {
    MethodOptions o;
    for (const auto& [k, v] : given)
        o.set(k, v);
    try {
        make_method(method, o);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

void expect_same(const Image& a, const Image& b) {
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    for (size_t i = 0; i < a.pixels.size(); ++i)
        ASSERT_EQ(a.pixels[i], b.pixels[i]) << "pixel " << i;
}

} // namespace

TEST(Method, RegistryListsTheMethodsWithPsdrFirst) {
    std::vector<std::string> names;
    for (const MethodInfo& m : derivative_methods())
        names.push_back(m.name);
    EXPECT_EQ(names, (std::vector<std::string>{"psdr", "interior", "paths", "was", "war", "war-bdpt", "dpm-c", "dpm-g"}));
    EXPECT_NE(std::string(error_of("nope", {}))
                  .find("unknown method 'nope' (known methods: psdr, interior, paths, was, war, war-bdpt, dpm-c, dpm-g)"),
              std::string::npos);
}

TEST(Method, OptionsAreChecked) {
    EXPECT_EQ(error_of("psdr", {{"primary-spp", "8"}, {"first-vertex", "material"}, {"no-guiding", "true"}}),
              "");
    EXPECT_NE(error_of("psdr", {{"q", "0.3"}})
                  .find("option 'q' is not an option of method psdr (it belongs to method paths)"),
              std::string::npos);
    EXPECT_NE(error_of("paths", {{"q", "1.5"}}).find("'q' = '1.5': expected a value in [0, 0.999]"),
              std::string::npos);
    EXPECT_NE(error_of("psdr", {{"primary-spp", "4.5"}}).find("expected an integer"), std::string::npos);
    EXPECT_NE(error_of("psdr", {{"primary-spp", "-1"}}).find("expected a value in [0, inf]"),
              std::string::npos);
    EXPECT_NE(
        error_of("interior", {{"first-vertex", "camera"}}).find("expected one of auto, image, material"),
        std::string::npos);
    EXPECT_NE(error_of("paths", {{"no-nee", "maybe"}}).find("expected true or false"), std::string::npos);
    EXPECT_NE(error_of("paths", {{"bogus", "1"}}).find("option 'bogus' is not an option of method paths"),
              std::string::npos);
}

// psdr through the front equals psdr_derivative / psdr_gradient with the same budgets and seed.
TEST(Method, PsdrAdapterIsTheEstimator) {
    auto scene = small_scene();
    Parameters params(*scene);
    params.enable({{"box.translate", {1, 0, 0}}});
    MethodOptions given;
    for (const char* term : {"primary-spp", "direct-spp", "indirect-spp", "pixel-spp"})
        given.set(term, "4");
    MethodRun run;
    run.spp = 8;
    run.batches = 2;
    run.seed = 11;
    const DerivativeImage d = make_method("psdr", given)->derivative(*scene, params, run);
    PsdrOptions o;
    o.interior.spp = 4;
    o.interior.batches = 2;
    o.interior.seed = 11;
    o.interior.path = path_settings(*scene);
    o.primary_spp = o.direct_spp = o.indirect_spp = o.pixel_spp = 2;
    const DerivativeImage ref = psdr_derivative(*scene, params, o);
    expect_same(d.derivative, ref.derivative);
    expect_same(d.stderr_img, ref.stderr_img);
    ASSERT_GE(d.terms.size(), 4u);
    EXPECT_EQ(d.terms[1].name, "primary");
    expect_same(d.terms[1].derivative, ref.term("primary").derivative);

    Image adjoint(16, 16);
    for (size_t i = 0; i < adjoint.pixels.size(); ++i)
        adjoint.pixels[i] = Color3f(float(i % 7) - 3.f, 1.f, 0.5f);
    run.batches = 1;
    const Gradient g = make_method("psdr", given)->gradient(*scene, params, adjoint, run);
    o.interior.spp = 8;
    o.interior.batches = 1;
    o.primary_spp = o.direct_spp = o.indirect_spp = o.pixel_spp = 4;
    EXPECT_EQ(g.values, psdr_gradient(*scene, params, adjoint, o).values);
}

// The calibrated psdr split is computed once and reused while film, dimension and spp stay the same.
TEST(Method, PsdrCalibratesOncePerConfiguration) {
    auto scene = small_scene();
    Parameters params(*scene);
    params.enable({{"box.translate", {1, 0, 0}}});
    auto method = make_method("psdr", MethodOptions());
    MethodRun run;
    run.spp = 16;
    const DerivativeImage a = method->derivative(*scene, params, run);
    run.seed = 5;
    const DerivativeImage b = method->derivative(*scene, params, run);
    EXPECT_EQ(a.description, b.description); // same split
    run.seed = 0;
    const DerivativeImage c = method->derivative(*scene, params, run);
    expect_same(a.derivative, c.derivative); // same seed, same split: the same image
}

TEST(Method, PathsAdapterIsTheEstimator) {
    auto scene = small_scene();
    Parameters params(*scene);
    params.enable({{"metal.alpha", {}}, {"white.reflectance", {}}});
    MethodOptions given;
    given.set("sampling", "bsdf");
    given.set("q", "0.3");
    MethodRun run;
    run.spp = 8;
    run.seed = 3;
    Image adjoint(16, 16);
    for (Color3f& c : adjoint.pixels)
        c = Color3f(1.f, -0.5f, 0.25f);
    const Gradient g = make_method("paths", given)->gradient(*scene, params, adjoint, run);
    PathSamplingOptions o;
    o.spp = 8;
    o.seed = 3;
    o.path = path_settings(*scene);
    o.differential = false;
    o.q = 0.3f;
    EXPECT_EQ(g.values, path_sampling_gradient(*scene, params, adjoint, o).values);
    // Geometry is refused by the estimator, with its message.
    params.enable({{"box.translate", {1, 0, 0}}});
    EXPECT_THROW(make_method("paths", MethodOptions())->gradient(*scene, params, adjoint, run), Error);
}

// Media are rendered (volpath, volpathmis, bdpt) but not yet differentiated: every method refuses a scene with
// media, forward and reverse, with one line that says so, rather than differentiating it as if it had none.
// psdr and interior differentiate participating media; the other methods trace surfaces only and say so.
TEST(Method, MethodsWithoutMediaRefuseThemClearly) {
    auto scene = load_scene_string(R"(<scene version="3.0.0">
      <medium type="homogeneous" id="fog"><float name="sigma_t" value="0.5"/></medium>
      <sensor type="perspective"><ref name="medium" id="fog"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
      <shape type="rectangle" id="plane"><bsdf type="diffuse" id="white"/></shape>
      <emitter type="constant"/>
    </scene>)");
    Parameters params(*scene);
    params.enable({{"white.reflectance", {1, 1, 1}}, {"fog.sigma_t", {1, 1, 1}}});
    MethodRun run;
    run.spp = 4;
    run.batches = 2;
    const Image adjoint(8, 8, Color3f(1.f));
    for (const MethodInfo& info : derivative_methods()) {
        const bool differentiates_media = info.name == "psdr" || info.name == "interior";
        for (int reverse = 0; reverse < 2; ++reverse) {
            std::string message;
            try {
                auto method = make_method(info.name, MethodOptions());
                if (reverse) method->gradient(*scene, params, adjoint, run);
                else method->derivative(*scene, params, run);
            } catch (const Error& e) {
                message = e.what();
            }
            if (differentiates_media) {
                EXPECT_EQ(message, "") << info.name << (reverse ? " gradient" : " derivative");
            } else {
                EXPECT_NE(message.find("participating media"), std::string::npos)
                    << info.name << (reverse ? " gradient" : " derivative") << ": '" << message << "'";
                EXPECT_NE(message.find("psdr"), std::string::npos) << message;
            }
        }
    }
}
