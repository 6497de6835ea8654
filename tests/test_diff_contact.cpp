// Objects resting on each other (issue 35; docs/design.md, "Contacts"): a box resting on a floor slides and
// turns on it. The floor under the box is hidden from everywhere, so the floor's integrand jumps along the
// box's bottom edges (the contact curve, psdr's contact segments and the primary term's silhouettes resting
// on the floor), and the material-form interior is Cauchy-tailed there without the contact flow. psdr
// (default first vertex) against central differences: before the contact term and flow, the translation's
// derivative had the wrong sign (image mean +0.0129 against FD −0.0071 at 32², 4096 spp).
#include "diff/psdr/psdr.h"
#include "diff_check.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

using namespace penumbra;
using namespace penumbra::test;

namespace {

void expect_matches_fd(const std::unique_ptr<Scene>& scene, const std::string& param, double h = 5e-3,
                       int fd_spp = 256) {
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
    ro.spp = fd_spp;
    ro.seed = 77;
    const FiniteDifference fd = finite_difference(*scene, params, h, ro, 16);
    const DiffCheck c = check_against(d.derivative, d.stderr_img, fd.derivative, fd.stderr_img);
    std::printf("  %s: %s\n", param.c_str(), describe(c).c_str());
    EXPECT_TRUE(c.passes()) << param << ": " << describe(c);
}

const std::string box_on_floor = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/contact/box_on_floor.xml";

void expect_matches_fd(const std::string& param) {
    expect_matches_fd(load_scene(box_on_floor, {{"res", "32"}}), param);
}

// The scene's film cropped to the window (x, y, w, h) of a res × res frame.
std::unique_ptr<Scene> cropped(int res, int x, int y, int w, int h, const std::string& max_depth,
                               const std::string& height = "0.3") {
    std::ifstream in(box_on_floor);
    std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string film = "<film type=\"hdrfilm\">";
    const size_t at = xml.find(film);
    EXPECT_NE(at, std::string::npos);
    xml.insert(at + film.size(), "<integer name=\"crop_offset_x\" value=\"" + std::to_string(x) +
                                     "\"/><integer name=\"crop_offset_y\" value=\"" + std::to_string(y) +
                                     "\"/><integer name=\"crop_width\" value=\"" + std::to_string(w) +
                                     "\"/><integer name=\"crop_height\" value=\"" + std::to_string(h) +
                                     "\"/>");
    return load_scene_string(xml, std::string(PENUMBRA_SOURCE_DIR) + "/scenes/contact",
                             {{"res", std::to_string(res)}, {"max_depth", max_depth}, {"height", height}});
}

} // namespace

TEST(Contact, BoxSlidingOnTheFloorMatchesFiniteDifferences) { expect_matches_fd("box.translate=1,0,0"); }

TEST(Contact, BoxTurningOnTheFloorMatchesFiniteDifferences) { expect_matches_fd("box.rotate@0,0.3,0=0,1,0"); }

// The contact line at close range (a 128² frame cropped to the box's front bottom edge, leaving out its left
// silhouette, which central differences at this step smear across pixels), three segments (camera → x_D1 →
// x_D0 → light): a contact segment's receiver is probed just outside the curve, and the face rising from the
// curve, which sees the curve edge-on, takes none of its light (BoundarySegment::first_segment_geometry_ratio).
// With the probe's geometry instead, the pixels of the contact line got a spurious share: here z 5.8 (on the
// 64 × 16 crop at (32, 80), 8192 spp: −0.0202 against FD −0.0347, z 11.6).
TEST(Contact, ContactLineAtThreeSegmentsMatchesFiniteDifferences) {
    expect_matches_fd(cropped(128, 40, 80, 56, 16, "3"), "box.translate=1,0,0", 3e-3, 512);
}

// The box hovering 0.05 above the floor, within the contact length: vertices attached to the floor's points
// by fixed directions lie on the box's faces, whose edges move relative to those directions, both where the
// edge is a silhouette (the attached dark side) and where it is a crease seen from the floor (both faces
// visible). Without these terms (128² crop of the front, 4096 spp) the image mean was −0.0382 against FD
// −0.0349 (z −6.7, relerr4 3× its noise); now −0.0352 (z −0.6). At this test's budget, without them: z −5.9.
TEST(Contact, BoxHoveringOverTheFloorMatchesFiniteDifferences) {
    expect_matches_fd(cropped(128, 40, 80, 56, 16, "4", "0.35"), "box.translate=1,0,0", 3e-3, 256);
}
