// The equal-time benchmarks of paper 002 on a tiny scene: the variance study produces the eight variants with
// calibrated spp, finite positive variances and means that agree with BSDF sampling; the inverse-rendering race
// writes its CSV and plot; bad inputs are clear Errors. (The measured ratios come from the benchmark runs in
// docs/variance_study.md, not from here.)
#include "core/error.h"
#include "studies/sampling_race.h"
#include "studies/variance_study.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace penumbra;

namespace {

// A glossy/diffuse blend floor facing a diffuse wall under a large area light (interreflection), 8x8 pixels.
const char* const Scene8 = R"(<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0,1,3.5" target="0,0.3,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
  <shape type="rectangle" id="floor"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
    <bsdf type="blendbsdf" id="mix"><float name="weight" value="0.3"/>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
      <bsdf type="roughconductor" id="spec"><float name="alpha" value="0.2"/><string name="distribution" value="ggx"/></bsdf>
    </bsdf></shape>
  <shape type="rectangle" id="wall"><transform name="to_world"><scale value="3"/><translate value="0,0,-1.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6,0.5,0.4"/></bsdf></shape>
  <shape type="rectangle" id="light"><transform name="to_world"><scale value="2.5"/><rotate x="1" angle="90"/>
      <translate value="0,3,0.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="1.2"/></emitter></shape>
</scene>)";

VarianceStudyOptions tiny_study() {
    VarianceStudyOptions o;
    o.runs = 40;
    o.spp = 8;
    o.target_spp = 64;
    o.reference_spp = 4;
    o.calibration_runs = 1;
    o.seed = 3;
    return o;
}

TEST(SamplingStudy, VarianceStudyTableHasTheEightVariants) {
    auto scene = load_scene_string(Scene8);
    Parameters params(*scene);
    params.enable({{"mix.weight", {}}});
    const VarianceStudy study = run_variance_study(*scene, params, tiny_study());
    ASSERT_EQ(study.variants.size(), 8u);
    EXPECT_FLOAT_EQ(study.target_value.at(0), 0.39f);
    EXPECT_FLOAT_EQ(params.values().at(0), 0.3f); // the scene is restored after the target render
    const std::string table = variance_study_markdown(study);
    for (const StudyVariant& v : study_variants()) EXPECT_NE(table.find("| " + v.name() + " |"), std::string::npos) << v.name();
    EXPECT_NE(table.find("| BSDF | "), std::string::npos);
    EXPECT_NE(table.find("| differential + adaptive + NEE | "), std::string::npos);
    EXPECT_NE(variance_study_json(study).find("\"loss_variance\""), std::string::npos);
    for (const VariantStatistics& s : study.variants) {
        SCOPED_TRACE(s.variant.name());
        EXPECT_GE(s.spp_image, 1);
        EXPECT_GE(s.spp_loss, 3);
        EXPECT_GT(s.seconds_image, 0.0);
        EXPECT_TRUE(std::isfinite(s.image_variance) && s.image_variance > 0.0);
        EXPECT_TRUE(std::isfinite(s.loss_variance) && s.loss_variance > 0.0);
        // All variants are unbiased: their means agree with BSDF sampling's (a loose bound: 40 runs give a
        // t-distributed statistic with heavier tails than a normal one; gross bias, e.g. a dropped technique, still fails it).
        EXPECT_LT(std::abs(s.z_image), 6.0);
        EXPECT_LT(std::abs(s.z_loss), 6.0);
    }
}

TEST(SamplingStudy, VarianceStudyRejectsBadParameters) {
    auto scene = load_scene_string(Scene8);
    Parameters params(*scene);
    EXPECT_THROW(params.enable({{"mix.wieght", {}}}), Error);
    params.enable({{"floor.translate", {1.f, 0.f, 0.f}}});
    try {
        run_variance_study(*scene, params, tiny_study());
        FAIL() << "a geometric parameter must be rejected";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("floor.translate"), std::string::npos) << e.what();
    }
    params.enable({{"mix.weight", {}}});
    VarianceStudyOptions o = tiny_study();
    o.runs = 1;
    EXPECT_THROW(run_variance_study(*scene, params, o), Error);
    o = tiny_study();
    o.target_value = {0.1f, 0.2f}; // neither the parameter's 3 values nor one broadcast value
    EXPECT_THROW(run_variance_study(*scene, params, o), Error);
}

TEST(SamplingStudy, RaceWritesHistoriesAndPlot) {
    auto scene = load_scene_string(Scene8);
    const auto dir = std::filesystem::temp_directory_path() / "penumbra_test_sampling_race";
    std::filesystem::remove_all(dir);
    SamplingRaceOptions o;
    o.parameters = {"mix.weight", "spec.alpha"};
    o.initial = {0.6f, 0.4f};
    o.iterations = 5;
    o.spp = 4;
    o.target_spp = 16;
    o.eval_spp = 4;
    o.calibration_runs = 1;
    o.output = dir.string();
    const SamplingRaceResult r = sampling_race(*scene, o);
    ASSERT_EQ(r.methods.size(), 2u);
    for (const RaceMethod& m : r.methods) {
        ASSERT_EQ(m.history.size(), 6u);
        EXPECT_GE(m.spp, 3);
        EXPECT_EQ(m.history.front().seconds, 0.0);
        EXPECT_GT(m.history.back().seconds, 0.0);
        EXPECT_NEAR(m.history.front().parameter_error, std::sqrt((1.0 + 1.0) / 2.0), 1e-6); // (0.6−0.3)/0.3, (0.4−0.2)/0.2
        EXPECT_NE(m.history.back().values, m.history.front().values);
    }
    EXPECT_TRUE(std::filesystem::file_size(r.plot_path) > 1000);
    std::ifstream csv(r.csv_path);
    int lines = 0;
    for (std::string line; std::getline(csv, line);) ++lines;
    EXPECT_EQ(lines, 1 + 2 * 6);
    EXPECT_FLOAT_EQ(Parameters(*scene).find("mix.weight").data[0], 0.3f); // scene left at the truth
    std::filesystem::remove_all(dir);
}

TEST(SamplingStudy, RaceRejectsBadInput) {
    auto scene = load_scene_string(Scene8);
    SamplingRaceOptions o;
    o.iterations = 1;
    o.parameters = {"mix.wieght"};
    o.initial = {0.5f};
    EXPECT_THROW(sampling_race(*scene, o), Error);
    o.parameters = {"floor.translate"};
    EXPECT_THROW(sampling_race(*scene, o), Error);
    o.parameters = {"mix.weight", "spec.alpha"};
    EXPECT_THROW(sampling_race(*scene, o), Error); // one initial value for two parameters
    o.parameters = {"wall.bsdf.reflectance"};
    o.initial = {0.5f};
    EXPECT_THROW(sampling_race(*scene, o), Error); // components differ: not one scalar
}

} // namespace
