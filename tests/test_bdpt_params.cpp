// bdpt's parameters: invalid values are one-line LoadErrors at the integrator's location naming the
// parameter.
#include "test_bdpt_util.h"
#include "xml_test_util.h"

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string load_error(const std::string& params) {
    const std::string xml =
        "<scene version=\"3.0.0\">\n" + integrator_xml("bdpt", params) + "\n" +
        bdpt_sensor("perspective", "<lookat origin=\"0,0,0\" target=\"0,0,1\" up=\"0,1,0\"/>", 40.f, 4) +
        "\n</scene>";
    const std::string msg = load_error_of([&] { load_scene_string(xml); });
    EXPECT_NE(msg.find(":2"), std::string::npos) << "the integrator is on line 2 (" << params << "): " << msg;
    return msg;
}

TEST(BDPTParameters, InvalidValuesAreLoadErrors) {
    EXPECT_NE(load_error("<string name=\"heuristic\" value=\"cubic\"/>").find("heuristic"),
              std::string::npos);
    EXPECT_NE(load_error("<integer name=\"max_depth\" value=\"-2\"/>").find("max_depth"), std::string::npos);
    EXPECT_NE(load_error("<integer name=\"rr_depth\" value=\"0\"/>").find("rr_depth"), std::string::npos);
    EXPECT_NE(load_error("<integer name=\"strategy_s\" value=\"1\"/>").find("strategy_t"), std::string::npos);
    EXPECT_NE(
        load_error("<integer name=\"strategy_s\" value=\"1\"/><integer name=\"strategy_t\" value=\"0\"/>")
            .find("strategy_t"),
        std::string::npos);
}

TEST(BDPTParameters, MaxDepthZeroIsBlack) {
    const auto scene = load_scene_string(
        "<scene version=\"3.0.0\">" + integrator_xml("bdpt", "<integer name=\"max_depth\" value=\"0\"/>") +
        bdpt_sensor("perspective", "<lookat origin=\"0,0,0\" target=\"0,0,1\" up=\"0,1,0\"/>", 40.f, 4) +
        "<emitter type=\"constant\"/></scene>");
    RenderOptions opt;
    opt.spp = 2;
    for (const Color3f& p : render(*scene, opt).pixels)
        EXPECT_EQ(p.x + p.y + p.z, 0.f);
}

} // namespace
