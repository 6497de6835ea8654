// Degenerate input (issue 18): meshes that are non-manifold, inconsistently oriented, with zero-length
// normals or without faces; 1x1 textures and films; 1 sample per pixel; max_depth 0 and 1. Each renders and
// differentiates (psdr, forward and reverse mode) with finite outputs, or is refused with a clear error.
#include "robustness_test_util.h"
#include "xml_test_util.h"

#include "core/image.h"

#include <gtest/gtest.h>

#include <cstdio>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// `xml` with the first occurrence of `from` replaced by `to` (the case must change something).
std::string with(std::string xml, const std::string& from, const std::string& to) {
    const size_t at = xml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? xml : xml.replace(at, from.size(), to);
}

// The box replaced by an OBJ mesh.
std::string mesh_scene(const std::string& obj) {
    return scene_xml(R"(<bsdf type="diffuse"/>)", R"(<bsdf type="diffuse"/>)",
                     R"(<shape type="obj" id="box"><string name="filename" value=")" + obj + R"("/>)");
}

const char* const Diffuse = R"(<bsdf type="diffuse"/>)";

} // namespace

TEST(DegenerateInput, RendersAndDifferentiatesOrIsAClearError) {
    const TempDir dir;
    // Three triangles on one edge (non-manifold) and a fourth wound the other way (inconsistent orientation).
    const std::string fan = dir.write("fan.obj", "v 0 0 -1\nv 0 0 1\nv 1 0.3 0\nv -1 0.3 0\nv 0 1 0\nv 1 0 2\n"
                                                 "f 1 2 3\nf 1 2 4\nf 1 2 5\nf 2 6 3\n");
    const std::string zero_normals =
        dir.write("zero_normals.obj", "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nvn 0 0 0\nvn 0 1 0\nf 1//1 3//2 2//1\n");
    Image texel(1, 1, Color3f(0.3f, 0.6f, 0.9f));
    write_image(dir.str() + "/texel.png", texel);
    const std::string textured = R"(<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value=")" +
                                 dir.str() + "/texel.png" + R"("/></texture></bsdf>)";
    struct Case {
        const char* name;
        std::string xml;
    };
    const Case cases[] = {
        {"a non-manifold, inconsistently oriented mesh", mesh_scene(fan)},
        {"zero-length vertex normals", mesh_scene(zero_normals)},
        {"a 1x1 texture", scene_xml(textured, textured)},
        {"a 1x1 film", with(with(scene_xml(Diffuse), R"(name="width" value="16")", R"(name="width" value="1")"),
                            R"(name="height" value="16")", R"(name="height" value="1")")},
        {"max_depth 0", with(scene_xml(Diffuse), R"(name="max_depth" value="4")", R"(name="max_depth" value="0")")},
        {"max_depth 1", with(scene_xml(Diffuse), R"(name="max_depth" value="4")", R"(name="max_depth" value="1")")},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        std::unique_ptr<Scene> scene;
        try {
            scene = load_scene_string(c.xml);
        } catch (const Error& e) {
            // A refusal must say what is wrong (not crash, not load garbage).
            std::printf("  %s: refused: %s\n", c.name, e.what());
            EXPECT_GT(std::string(e.what()).size(), 20u);
            continue;
        }
        render_and_differentiate(*scene, "box.translate=1,0,0");
        std::printf("  %s: rendered and differentiated\n", c.name);
    }
}

// A mesh without faces is an error naming the file.
TEST(DegenerateInput, AMeshWithoutFacesIsAClearError) {
    const TempDir dir;
    const std::string empty = dir.write("empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    try {
        load_scene_string(mesh_scene(empty));
        FAIL() << "a mesh without faces loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("empty.obj"), std::string::npos) << e.what();
    }
}

// One sample per pixel, for every method that applies to a moving shape.
TEST(DegenerateInput, OneSamplePerPixel) {
    auto scene = load_scene_string(scene_xml(Diffuse));
    for (const char* method : {"psdr", "interior", "was", "war"}) {
        SCOPED_TRACE(method);
        render_and_differentiate(*scene, "box.translate=1,0,0", method, 1, 1);
    }
}
