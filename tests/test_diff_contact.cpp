// Objects resting on each other (issue 35; docs/design.md, "Contacts"): a box resting on a floor slides and
// turns on it. The floor under the box is hidden from everywhere, so the floor's integrand jumps along the
// box's bottom edges (the contact curve, psdr's contact segments and the primary term's silhouettes resting
// on the floor), and the material-form interior is Cauchy-tailed there without the contact flow. psdr
// (default first vertex) against central differences: before the contact term and flow, the translation's
// derivative had the wrong sign (image mean +0.0129 against FD −0.0071 at 32², 4096 spp).
#include "diff/psdr/psdr.h"
#include "diff_check.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

void expect_matches_fd(const std::string& param) {
    auto scene =
        load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/contact/box_on_floor.xml", {{"res", "32"}});
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    PsdrOptions o;
    o.interior.spp = 32;
    o.interior.batches = 16;
    o.interior.seed = 5;
    o.interior.path = path_settings(*scene);
    o.primary_spp = 4;
    o.direct_spp = 16;
    o.indirect_spp = 8;
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 256;
    ro.seed = 77;
    const FiniteDifference fd = finite_difference(*scene, params, 5e-3, ro, 16);
    const DiffCheck c = check_against(d.derivative, d.stderr_img, fd.derivative, fd.stderr_img);
    std::printf("  %s: %s\n", param.c_str(), describe(c).c_str());
    EXPECT_TRUE(c.passes()) << param << ": " << describe(c);
}

} // namespace

TEST(Contact, BoxSlidingOnTheFloorMatchesFiniteDifferences) { expect_matches_fd("box.translate=1,0,0"); }

TEST(Contact, BoxTurningOnTheFloorMatchesFiniteDifferences) { expect_matches_fd("box.rotate@0,0.3,0=0,1,0"); }
