// What the validation tests of the warped-area methods share (tests/test_diff_war.cpp,
// tests/test_diff_war_bdpt.cpp, tests/test_diff_was.cpp; tests/test_diff_war_scenes.cpp,
// tests/test_diff_was_scenes.cpp): the boundary validation cases of scenes/validation/ with war's stored
// finite-difference references, a case's loader, a method's derivative through the method front
// (diff/method.h), the checks every method passes (reverse mode against forward mode, determinism across
// thread counts, errors naming the way out), and for the paper suites (scenes/war, scenes/was) the method
// table and the check of one scene against its finite differences.
#pragma once
#include "core/error.h"
#include "diff/method.h"
#include "diff_check.h"
#include "studies/ad_suite.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace penumbra::test {

inline uint64_t test_seed() {
    // PENUMBRA_TEST_SEED re-runs the checks with other random numbers (to see that they do not pass by luck).
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    return env ? std::strtoull(env, nullptr, 10) : 0;
}

inline const std::string validation_dir = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/";

// A validation case: scene, its defines, the parameter, the FD step and samples per pixel and side.
struct ValidationCase {
    std::string label, file;
    std::map<std::string, std::string> defines;
    std::string param;
    double h;
    int fd_spp;
};

// The boundary validation scenes with the lights the warped-area methods see (area lights and the
// environment; the shadows of point and directional lights are outside them, diff/war/war.h,
// diff/was/warped_area.h), steps as the psdr tests' (tests/test_diff_boundary.cpp); the camera motion with a
// Gaussian filter (cut at the film's edge) and with a box filter (jumps at every pixel edge).
inline const std::vector<ValidationCase>& validation_cases() {
    static const std::vector<ValidationCase> cases = {
        {"silhouette", "silhouette.xml", {}, "box.rotate=0,1,0", 1e-2, 1024},
        {"shadow", "shadow.xml", {{"light", "area"}}, "occluder.translate=1,0,0", 2e-2, 2048},
        {"sky",
         "shadow.xml",
         {{"light", "sky"}, {"occluder_height", "0.6"}},
         "occluder.translate=1,0,0",
         1e-2,
         2048},
        {"glossy_shadow", "glossy_shadow.xml", {{"light", "area"}}, "cube.translate=1,0,0", 2e-2, 1024},
        {"self_shadow", "self_shadow.xml", {{"light", "area"}}, "lshape.rotate=0,1,0", 1e-2, 1024},
        {"moving_light", "moving_light.xml", {}, "lamp.translate=1,0,0", 2e-2, 1024},
        {"camera", "pixel_edges.xml", {{"filter", "gaussian"}}, "cam.translate=1,0,0", 2e-3, 1024},
        {"camera_box", "pixel_edges.xml", {{"filter", "box"}}, "cam.translate=1,0,0", 2e-3, 1024},
        {"silhouette_box", "silhouette.xml", {{"filter", "box"}}, "box.rotate=0,1,0", 1e-2, 1024},
    };
    return cases;
}

// The cases with the given labels, in that order.
inline std::vector<ValidationCase> validation_cases(const std::vector<std::string>& labels) {
    std::vector<ValidationCase> out;
    for (const std::string& label : labels)
        for (const ValidationCase& c : validation_cases())
            if (c.label == label) out.push_back(c);
    return out;
}

inline void PrintTo(const ValidationCase& c, std::ostream* os) { *os << c.label; }

struct LoadedCase {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Parameters> params;
};

inline LoadedCase load_validation(const ValidationCase& c, int res) {
    std::map<std::string, std::string> defines = c.defines;
    defines["res"] = std::to_string(res);
    LoadedCase l;
    l.scene = load_scene(validation_dir + c.file, defines);
    l.params = std::make_unique<Parameters>(*l.scene);
    l.params->enable({parse_param_selection(c.param)});
    return l;
}

// The finite-difference references of the validation cases that tests/test_diff_war.cpp stores
// (studies/ad_suite.h's cache): their seed and the case's key.
inline const std::string war_reference_cache = validation_dir + "war_fd";
constexpr uint64_t WarReferenceSeed = 99;

inline AdSuiteScene reference_key(const ValidationCase& c, std::vector<std::string>& defines) {
    AdSuiteScene s;
    s.name = c.label;
    s.file = validation_dir + c.file;
    s.params = {c.param};
    for (const auto& [k, v] : c.defines)
        defines.push_back(k + "=" + v);
    return s;
}

inline std::optional<FiniteDifference> stored_war_reference(const ValidationCase& c, int res) {
    std::vector<std::string> defines;
    const AdSuiteScene s = reference_key(c, defines);
    return read_cached_reference(war_reference_cache, s, res, c.h, c.fd_spp, defines, WarReferenceSeed);
}

// The stored reference, for the tests that only read it (tests/test_diff_war.cpp owns them: it computes and
// stores a missing or stale one).
inline FiniteDifference stored_war_reference_or_throw(const ValidationCase& c, int res) {
    auto stored = stored_war_reference(c, res);
    if (!stored) throw Error("no stored reference for " + c.label + ": run tests/test_diff_war.cpp's case");
    return *stored;
}

// A method's derivative through the method front, with the given options.
inline DerivativeImage method_derivative(const std::string& method,
                                         const std::map<std::string, std::string>& given, const LoadedCase& l,
                                         int spp, uint64_t seed, int batches) {
    MethodOptions o;
    for (const auto& [k, v] : given)
        o.set(k, v);
    MethodRun run;
    run.spp = spp;
    run.batches = batches;
    run.seed = seed;
    return make_method(method, o)->derivative(*l.scene, *l.params, run);
}

// Reverse mode runs the same samples through the same tape: ⟨adjoint, dI/dθ⟩ of forward mode (one batch, so
// that the seeds agree) equals the gradient along the direction.
inline void expect_reverse_matches_forward(const std::string& method, const MethodOptions& options,
                                           const LoadedCase& l) {
    auto m = make_method(method, options);
    MethodRun run;
    run.spp = 16;
    run.batches = 1;
    run.seed = 41;
    const DerivativeImage d = m->derivative(*l.scene, *l.params, run);
    const int w = d.derivative.width, h = d.derivative.height;
    Image adjoint(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            adjoint.at(x, y) = Color3f(0.3f + 0.05f * float(x), 1.f - 0.04f * float(y), 0.5f);
    const Gradient g = m->gradient(*l.scene, *l.params, adjoint, run);
    double forward = 0, reverse = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < 3; ++k)
                forward += double(adjoint.at(x, y)[k]) * double(d.derivative.at(x, y)[k]);
    const std::vector<float>& direction = l.params->direction();
    for (size_t k = 0; k < g.values.size(); ++k)
        reverse += g.values[k] * double(direction[k]);
    std::printf("  <a, Jv> = %.6f, <J^T a, v> = %.6f\n", forward, reverse);
    EXPECT_GT(std::abs(forward), 1e-3);
    EXPECT_NEAR(reverse, forward, 1e-4 * std::abs(forward) + 1e-6);
}

// Same seed, same image, whatever the thread count.
inline void expect_thread_count_invariant(const std::string& method, const LoadedCase& l) {
    MethodRun run;
    run.spp = 8;
    run.batches = 2;
    run.seed = 5;
    auto m = make_method(method, MethodOptions());
    run.threads = 1;
    const DerivativeImage one = m->derivative(*l.scene, *l.params, run);
    run.threads = 2;
    const DerivativeImage two = m->derivative(*l.scene, *l.params, run);
    EXPECT_EQ(one.derivative.pixels, two.derivative.pixels);
}

// A 4 × 4 scene in fog: what methods that trace surfaces only refuse.
inline const std::string fog_scene = R"(<scene version="3.0.0">
      <medium type="homogeneous" id="fog"><float name="sigma_t" value="0.5"/></medium>
      <sensor type="perspective"><ref name="medium" id="fog"/>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
      <shape type="rectangle" id="plane"><bsdf type="diffuse"/></shape><emitter type="constant"/>
    </scene>)";

// The error a method's derivative throws on the scene (empty if none), the plane translating.
inline std::string derivative_error(const std::string& method, const std::string& xml) {
    auto scene = load_scene_string(xml);
    Parameters params(*scene);
    params.enable({parse_param_selection("plane.translate=1,0,0")});
    MethodRun run;
    run.spp = 1;
    try {
        make_method(method, MethodOptions())->derivative(*scene, params, run);
    } catch (const Error& e) {
        return std::string(e.what());
    }
    return std::string();
}

// A paper suite's derivative methods: a label (the test's name), the method's name in derivative_methods()
// and its options as on the command line.
struct MethodCase {
    std::string label, name;
    std::map<std::string, std::string> options;
};

inline std::vector<std::string> method_labels(const std::vector<MethodCase>& methods) {
    std::vector<std::string> labels;
    for (const MethodCase& m : methods)
        labels.push_back(m.label);
    return labels;
}

// The suite's scenes (one "manifest" placeholder when it does not load, so that the test reports why).
inline std::vector<std::string> scene_names(const std::string& manifest) {
    try {
        std::vector<std::string> names;
        for (const AdSuiteScene& s : load_ad_suite(manifest).scenes)
            names.push_back(s.name);
        return names;
    } catch (const Error&) {
        return {"manifest"};
    }
}

// A paper suite: scenes/<dir>/<manifest>, with the references that `penumbra ad-suite --fd-only` stored in
// scenes/<dir>/fd.
struct PaperSuite {
    std::string manifest, reference_cache;
    // The seed of the stored references (penumbra ad-suite's): independent of the derivative's seeds.
    uint64_t reference_seed = 2;
    // Batches of the derivative: its per-pixel standard errors (t with 15 degrees of freedom, diff_check.h).
    int batches = 16;
};

inline PaperSuite paper_suite(const std::string& dir, const std::string& manifest) {
    const std::string root = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/" + dir + "/";
    return {root + manifest, root + "fd"};
}

// The method's derivative at `spp` per pixel (seed 1 + 1000 · test_seed()) against the suite's finite
// differences at the scene's CI resolution: stored (key: the scene with `defines`), or computed with them.
// psdr's first term is the interior alone, which must miss the boundary contribution.
inline void check_suite_scene(const PaperSuite& paper, const MethodCase& method, const AdSuite& suite,
                              const AdSuiteScene& s, int spp, const std::vector<std::string>& defines) {
    const uint64_t seed = test_seed();
    const FdSettings ref = fd_settings(suite, s, s.ci_res);
    const std::optional<FiniteDifference> stored = read_cached_reference(
        paper.reference_cache, s, s.ci_res, ref.eps, ref.spp, defines, paper.reference_seed);
    if (!stored)
        std::printf("  %s: no stored reference matches the scene; computing it (slow)\n", s.name.c_str());
    std::map<std::string, std::string> reference_scene;
    for (const std::string& d : defines)
        reference_scene[d.substr(0, d.find('='))] = d.substr(d.find('=') + 1);
    const FiniteDifference fd = [&] {
        if (stored) return *stored;
        AdSuiteCase r = load_case(s, s.ci_res, reference_scene);
        return suite_reference(*r.scene, *r.params, ref.eps, ref.spp, paper.reference_seed + 1000 * seed, 0);
    }();

    AdSuiteCase c = load_case(s, s.ci_res);
    MethodRun run;
    run.spp = spp;
    run.batches = paper.batches;
    run.seed = 1 + 1000 * seed;
    MethodOptions options;
    for (const auto& [key, value] : method.options)
        options.set(key, value);
    const DerivativeImage d = make_method(method.name, options)->derivative(*c.scene, *c.params, run);
    ASSERT_FALSE(d.terms.empty());
    const DiffCheck total = check_against(d, fd);
    std::printf("  %s at %dx%d, %s %d spp (%.2f s, %s), reference h = %g at %d spp per side (%.0f s%s)\n"
                "  %s: %s\n",
                s.name.c_str(), s.ci_res, s.ci_res, method.label.c_str(), run.spp, d.seconds,
                d.description.c_str(), ref.eps, ref.spp, fd.seconds, stored ? ", stored" : "",
                method.label.c_str(), describe(total).c_str());
    EXPECT_TRUE(total.passes()) << describe(total);
    if (d.terms[0].name == "interior") {
        const DiffCheck interior = check_against(d.terms[0].derivative, d.terms[0].stderr_img, fd.derivative,
                                                 fd.stderr_img, d.terms[0].block_stderr, fd.block_stderr);
        std::printf("  interior only: %s\n", describe(interior).c_str());
        EXPECT_FALSE(interior.passes())
            << "the interior term alone should miss the boundary contribution: " << describe(interior);
    }
}

// The method and scene of a suite test's parameter, or null.
inline const MethodCase* find_method_case(const std::vector<MethodCase>& methods, const std::string& label) {
    for (const MethodCase& m : methods)
        if (m.label == label) return &m;
    return nullptr;
}
inline const AdSuiteScene* find_suite_scene(const AdSuite& suite, const std::string& name) {
    for (const AdSuiteScene& s : suite.scenes)
        if (s.name == name) return &s;
    return nullptr;
}

} // namespace penumbra::test
