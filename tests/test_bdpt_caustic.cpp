// bdpt where it matters: a caustic (a glass ball focusing a small area light onto a diffuse floor), which a
// unidirectional path tracer only finds by hitting the small light through the ball with BSDF sampling, and
// bdpt through light tracing and connections of light subpaths. Both must agree (z-scores as in
// test_bdpt_agreement.cpp), and bdpt must be more efficient: per-pixel variance times render time.
// Also: the image is bit-identical for a seed whatever the thread count.
#include "render_stats.h"
#include "test_bdpt_util.h"

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string caustic_scene(const std::string& integrator) {
    return "<scene version=\"3.0.0\">" + integrator +
           bdpt_sensor("perspective", "<lookat origin=\"0,2.2,-2.2\" target=\"0,0.2,0\" up=\"0,1,0\"/>", 35.f,
                       24) +
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/><rotate x=\"1\" "
           "angle=\"-90\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
           "value=\"0.8\"/></bsdf>"
           "</shape><shape type=\"sphere\"><point name=\"center\" value=\"0,0.6,0\"/><float name=\"radius\" "
           "value=\"0.4\"/><bsdf type=\"dielectric\"/></shape>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.05\"/><rotate x=\"1\" "
           "angle=\"90\"/><translate value=\"0,2,0\"/></transform><emitter type=\"area\"><rgb "
           "name=\"radiance\" "
           "value=\"400\"/></emitter></shape></scene>";
}

TEST(BDPTCaustic, AgreesWithPathAndIsMoreEfficient) {
    const auto path = load_scene_string(caustic_scene(integrator_xml("path")));
    const auto bdpt = load_scene_string(caustic_scene(integrator_xml("bdpt")));
    const BlockStats a = block_stats(*bdpt, 12, 4, 1);
    const BlockStats b = block_stats(*path, 12, 256, 100001);
    const std::vector<double> z = z_scores(a, b);
    const double ratio = (a.pixel_variance * a.seconds) / (b.pixel_variance * b.seconds);
    std::printf(
        "[bdpt caustic] mean %.5f vs path %.5f, z = %.2f, max block |z| = %.2f; variance x time: bdpt "
        "%.3g x %.3g s, path %.3g x %.3g s, ratio %.3f\n",
        a.mean[0], b.mean[0], z[0], max_abs(z, 1), a.pixel_variance, a.seconds, b.pixel_variance, b.seconds,
        ratio);
    EXPECT_LT(std::abs(z[0]), 4.0);
    EXPECT_LT(max_abs(z, 1), 4.5);
    EXPECT_LT(ratio, 0.5);
}

TEST(BDPTDeterminism, SameImageWithOneAndTwoThreads) {
    // Every feature at once: light tracing splats, media behind a dielectric, an environment and an area
    // light.
    const auto scene = load_scene_string(
        "<scene version=\"3.0.0\">" + integrator_xml("bdpt") +
        bdpt_sensor("perspective", "<lookat origin=\"0,2.2,-2.2\" target=\"0,0.2,0\" up=\"0,1,0\"/>", 35.f,
                    24, "", "gaussian") +
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/><rotate x=\"1\" "
        "angle=\"-90\"/>"
        "</transform><bsdf type=\"diffuse\"/></shape><shape type=\"sphere\"><point name=\"center\" "
        "value=\"0,0.6,0\"/><float name=\"radius\" value=\"0.4\"/><bsdf type=\"dielectric\"/><medium "
        "type=\"homogeneous\" name=\"interior\"><float name=\"sigma_t\" value=\"2\"/></medium></shape>"
        "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.5\"/></emitter>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.2\"/><rotate x=\"1\" "
        "angle=\"90\"/><translate value=\"0,2,0\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" "
        "value=\"20\"/></emitter></shape></scene>");
    expect_same_image_whatever_the_thread_count(*scene, "bdpt");
}

} // namespace
