// Central-difference references stored once at a higher budget (tests/data/fd/suite.json, in the format and
// cache of studies/ad_suite.h; scripts/make_test_references.sh writes them): a test reads the reference of
// its scene, parameter and step instead of rendering it. A reference whose key no longer matches (the scene
// file changed, or the test asks for another step or other defines) is an error naming the command that
// regenerates it.
#pragma once
#include "core/error.h"
#include "studies/ad_suite.h"

#include <string>
#include <vector>

namespace penumbra::test {

inline const std::string stored_reference_dir = std::string(PENUMBRA_SOURCE_DIR) + "/tests/data/fd";
// The seed of the stored references (penumbra ad-suite's): independent of the tests' derivative seeds.
constexpr uint64_t StoredReferenceSeed = 2;

// A reference of the manifest: its name and the -D defines it was rendered with (in the script's order).
struct StoredKey {
    std::string name;
    std::vector<std::string> defines;
};

struct StoredReference {
    FiniteDifference fd;
    double h = 0;    // the step
    int samples = 0; // samples per pixel and side, over all batches
};

// The stored reference of `key` at step `h` (which must be the manifest's: a test states the step it checks).
inline StoredReference stored_reference(const StoredKey& key, double h) {
    const AdSuite suite = load_ad_suite(stored_reference_dir + "/suite.json");
    for (const AdSuiteScene& s : suite.scenes) {
        if (s.name != key.name) continue;
        const FdSettings settings = fd_settings(suite, s, s.ci_res);
        if (settings.eps != h)
            throw Error("stored reference '" + key.name + "' has the step " + std::to_string(settings.eps) +
                        ", the test asks for " + std::to_string(h));
        const auto fd = read_cached_reference(stored_reference_dir, s, s.ci_res, settings.eps, settings.spp,
                                              key.defines, StoredReferenceSeed);
        if (!fd)
            throw Error("no stored reference '" + key.name +
                        "' matches its scene: regenerate it with scripts/make_test_references.sh " +
                        key.name);
        return {*fd, settings.eps, settings.spp};
    }
    throw Error("no reference '" + key.name + "' in tests/data/fd/suite.json");
}

} // namespace penumbra::test
