// Replays the fuzz harnesses' committed inputs without libFuzzer: every file of
// tests/fuzz/regressions/<harness>/ (inputs that once crashed a loader, docs/fuzzing.md) and
// tests/fuzz/seeds/<harness>/ goes through the same body as under the fuzzer. A loader may reject an input
// with a std::exception (the body swallows it); a crash, or any other exception escaping, fails the test.
#include "fuzz/fuzz_targets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

namespace fs = std::filesystem;
using namespace penumbra::fuzz;

namespace {

struct Harness {
    const char* name;
    void (*body)(const uint8_t*, size_t);
};

const Harness harnesses[] = {{"xml", fuzz_xml},
                             {"obj", fuzz_obj},
                             {"ply", fuzz_ply},
                             {"serialized", fuzz_serialized},
                             {"exr", fuzz_exr},
                             {"png", fuzz_png},
                             {"vol", fuzz_vol},
                             {"vdb", fuzz_vdb},
                             {"optimize_config", fuzz_optimize_config}};

// The files of tests/fuzz/<kind>/<harness>/, sorted (empty when the directory does not exist).
std::vector<fs::path> inputs(const std::string& kind, const std::string& harness) {
    std::vector<fs::path> files;
    const fs::path dir = fs::path(PENUMBRA_SOURCE_DIR) / "tests" / "fuzz" / kind / harness;
    if (!fs::is_directory(dir)) return files;
    for (const auto& entry : fs::directory_iterator(dir))
        if (entry.is_regular_file()) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    return files;
}

class FuzzRegressions : public ::testing::TestWithParam<Harness> {};

TEST_P(FuzzRegressions, CommittedInputsDoNotCrash) {
    const Harness& h = GetParam();
    for (const std::string kind : {"seeds", "regressions"})
        for (const fs::path& file : inputs(kind, h.name)) {
            SCOPED_TRACE(file.string());
            std::ifstream in(file, std::ios::binary);
            const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                             std::istreambuf_iterator<char>());
            EXPECT_NO_THROW(h.body(bytes.data(), bytes.size()));
        }
}

// Empty input, as libFuzzer tries first.
TEST_P(FuzzRegressions, EmptyInputDoesNotCrash) {
    const uint8_t none = 0;
    EXPECT_NO_THROW(GetParam().body(&none, 0));
}

INSTANTIATE_TEST_SUITE_P(Harnesses, FuzzRegressions, ::testing::ValuesIn(harnesses),
                         [](const ::testing::TestParamInfo<Harness>& info) {
                             return std::string(info.param.name);
                         });

} // namespace
