// The `penumbra` command line as a user runs it: exit codes, outputs, error messages.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
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
