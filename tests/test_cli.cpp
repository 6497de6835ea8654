// The `penumbra` command line as a user runs it: exit codes, outputs, error messages.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace fs = std::filesystem;

namespace {

struct Result {
    int status;
    std::string output; // stdout and stderr
};

Result run(const std::string& args) {
    const std::string cmd = std::string(PENUMBRA_CLI) + " " + args + " 2>&1";
    Result r{0, {}};
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return {-1, "popen failed"};
    std::array<char, 4096> buf;
    while (fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
    const int status = pclose(pipe);
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

fs::path temp_dir() {
    fs::path dir = fs::temp_directory_path() / ("penumbra_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

const std::string cbox = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cbox/cbox.xml";

} // namespace

TEST(CLI, RendersBundledSceneToPngAndExr) {
    const fs::path dir = temp_dir();
    for (const char* name : {"cbox.png", "cbox.exr"}) {
        const fs::path out = dir / name;
        const Result r = run("render " + cbox + " -o " + out.string() + " -D res=32 --spp 2 --quiet");
        EXPECT_EQ(r.status, 0) << r.output;
        EXPECT_TRUE(fs::exists(out) && fs::file_size(out) > 100) << name;
        EXPECT_NE(r.output.find("samples/s"), std::string::npos) << "summary line missing: " << r.output;
    }
}

TEST(CLI, InfoListsShapesAndEmitters) {
    const Result r = run("info " + cbox);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("triangles"), std::string::npos);
    EXPECT_NE(r.output.find("emitters: 1"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("tall_box"), std::string::npos);
}

TEST(CLI, BadSceneFailsWithOneLineAndNoOutputFile) {
    const fs::path dir = temp_dir();
    const fs::path scene = dir / "bad.xml";
    std::ofstream(scene) << "<scene version=\"3.0.0\">\n  <shape type=\"obj\">\n</scene>\n";
    const fs::path out = dir / "bad.png";
    const Result r = run("render " + scene.string() + " -o " + out.string());
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("bad.xml:"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos) << "uncaught exception: " << r.output;
    EXPECT_FALSE(fs::exists(out));
}

TEST(CLI, UnknownPluginIsNamed) {
    const fs::path dir = temp_dir();
    const fs::path scene = dir / "hair.xml";
    std::ofstream(scene) << "<scene version=\"3.0.0\">\n  <bsdf type=\"hair\"/>\n</scene>\n";
    const Result r = run("render " + scene.string() + " -o " + (dir / "x.exr").string());
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("hair.xml:2"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("'hair'"), std::string::npos) << r.output;
}

TEST(CLI, RejectsUnknownOutputFormatBeforeRendering) {
    const Result r = run("render " + cbox + " -o out.tiff");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find(".exr or .png"), std::string::npos) << r.output;
}

// `ad-suite` on one scene at a tiny resolution: the table row, the pictures, and the reference reused from the
// cache on the second run.
TEST(CLI, AdSuiteWritesItsTableAndPicturesAndReusesTheReference) {
    const fs::path dir = temp_dir() / "ad_suite";
    fs::remove_all(dir);
    const std::string args = "ad-suite --manifest " + std::string(PENUMBRA_SOURCE_DIR) +
                             "/scenes/mitsuba_ad/suite.json --only translate_rectangle_emitter_on_black --res 16 "
                             "--fd-spp-scale 0.25 -q --cache " + dir.string() + " -o " + (dir / "report.md").string();
    const Result first = run(args);
    ASSERT_EQ(first.status, 0) << first.output;
    std::ifstream report(dir / "report.md");
    const std::string table((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    EXPECT_NE(table.find("| translate_rectangle_emitter_on_black | 1024 |"), std::string::npos) << table;
    for (const char* suffix : {"_derivative.png", "_fd.png", "_z.png", "_fd.exr", "_fd_stderr.exr", "_fd.json"})
        EXPECT_TRUE(fs::exists(dir / (std::string("translate_rectangle_emitter_on_black") + suffix))) << suffix;
    const Result second = run(args);
    EXPECT_EQ(second.status, 0) << second.output;
    EXPECT_NE(second.output.find("(cached)"), std::string::npos) << second.output;

    const Result unknown = run("ad-suite --only no_such_scene --manifest " + std::string(PENUMBRA_SOURCE_DIR) +
                               "/scenes/mitsuba_ad/suite.json --cache " + dir.string());
    EXPECT_EQ(unknown.status, 1);
    EXPECT_NE(unknown.output.find("no scene 'no_such_scene'"), std::string::npos) << unknown.output;
}

// Method options come from the method registry (diff/method.h): each is a flag, checked against --method.
TEST(CLI, MethodOptionsAreCheckedAgainstTheMethod) {
    const fs::path dir = temp_dir();
    const std::string out = (dir / "d.exr").string();
    const std::string base =
        "derivative " + cbox + " -D res=16 --param white.reflectance --spp 4 -q -o " + out;
    Result r = run(base + " --method interior --q 0.3");
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("option 'q' is not an option of method interior (it belongs to method paths)"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(out));
    r = run(base + " --method paths --q 0.3 --sampling bsdf");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("derivative (paths: path sampling: bsdf sampling + NEE)"), std::string::npos)
        << r.output;
    r = run("derivative --help");
    EXPECT_NE(r.output.find("--primary-spp"), std::string::npos);
    EXPECT_NE(r.output.find("[method paths]"), std::string::npos);
    fs::remove_all(dir);
}

// --sensor picks one of several sensors by index or id (Mitsuba scenes may declare several).
TEST(CLI, SensorOptionPicksASensor) {
    const fs::path dir = temp_dir();
    std::ofstream(dir / "two.xml") << R"(<scene version="3.0.0">
      <sensor type="perspective" id="wide"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="4"/></film></sensor>
      <sensor type="perspective" id="square"><film type="hdrfilm"><integer name="width" value="6"/><integer name="height" value="6"/></film></sensor>
      <shape type="sphere"><transform name="to_world"><translate value="0,0,4"/></transform></shape>
      <emitter type="constant"/></scene>)";
    const std::string scene = (dir / "two.xml").string(), out = (dir / "s.exr").string();
    Result r = run("render " + scene + " --sensor square --spp 1 -q -o " + out);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("6x6"), std::string::npos) << r.output;
    r = run("render " + scene + " --sensor 2 --spp 1 -q -o " + out);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("unknown sensor '2' (the scene's sensors: 0 (wide), 1 (square))"),
              std::string::npos)
        << r.output;
    fs::remove_all(dir);
}

// The bundled media scene: info lists the medium and who uses it; each media integrator renders it; a surface
// integrator renders it with a warning that it ignores the media; derivatives refuse it in one line.
TEST(CLI, BundledMediaScene) {
    const std::string hazy = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/media/hazy_room.xml";
    const std::string small = " -D width=16 -D height=12 --spp 2 --quiet";
    const Result info = run("info " + hazy);
    EXPECT_EQ(info.status, 0) << info.output;
    EXPECT_NE(info.output.find("media: 1"), std::string::npos) << info.output;
    EXPECT_NE(info.output.find("sensor camera, room (interior)"), std::string::npos) << info.output;
    const fs::path dir = temp_dir();
    for (const char* integrator : {"bdpt", "volpath", "volpathmis"}) {
        const fs::path out = dir / (std::string(integrator) + ".exr");
        const Result r = run("render " + hazy + " --integrator " + integrator + " -o " + out.string() + small);
        EXPECT_EQ(r.status, 0) << r.output;
        EXPECT_TRUE(fs::exists(out)) << integrator;
        EXPECT_EQ(r.output.find("warning"), std::string::npos) << integrator << ": " << r.output;
    }
    const Result path = run("render " + hazy + " --integrator path -o " + (dir / "path.exr").string() + small);
    EXPECT_EQ(path.status, 0) << path.output;
    EXPECT_NE(path.output.find("warning: integrator 'path' ignores the scene's participating media"),
              std::string::npos)
        << path.output;
    const fs::path d = dir / "d.exr";
    const Result deriv = run("derivative " + hazy + " --param haze.sigma_t -o " + d.string() + small);
    EXPECT_EQ(deriv.status, 0) << deriv.output;
    EXPECT_TRUE(fs::exists(d));
    const fs::path p = dir / "p.exr";
    const Result paths = run("derivative " + hazy + " --method paths --param haze.sigma_t -o " + p.string() + small);
    EXPECT_EQ(paths.status, 1) << paths.output;
    EXPECT_NE(paths.output.find("participating media"), std::string::npos) << paths.output;
    EXPECT_FALSE(fs::exists(p));
}
