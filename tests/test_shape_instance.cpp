// shapegroup / instance: geometry stored once per group, instance interactions equal to those of the
// flattened shapes, projected areas, Mitsuba's errors, and flattening for derivatives
// (test_shape_instance_diff.cpp checks the derivatives).
#include "diff/parameters.h"
#include "scene/scene.h"

#include "shape_test_util.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

std::string load_error(const std::string& xml) {
    try {
        load_scene_string(xml);
    } catch (const LoadError& e) {
        return e.what();
    }
    return "no error";
}

const char* group_xml = R"(
    <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
    <shape type="shapegroup" id="group">
        <shape type="sphere"><float name="radius" value="0.5"/><ref id="red"/></shape>
        <shape type="rectangle">
            <transform name="to_world"><rotate x="1" angle="30"/><translate x="1"/></transform>
        </shape>
    </shape>)";

// The same placement as an instance and as shapes with the composed to_world.
const char* placement = R"(<scale x="0.7" y="1.3" z="0.9"/><rotate x="0.3" y="1" z="0.2" angle="40"/>
                           <translate x="0.2" y="-0.1" z="0.4"/>)";

} // namespace

TEST(ShapeInstance, HundredInstancesStoreTheGroupOnce) {
    std::string xml = R"(<shape type="shapegroup" id="g"><shape type="sphere"/></shape>)";
    for (int i = 0; i < 100; ++i)
        xml += "<shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\"><translate x=\"" +
               std::to_string(3 * i) + "\"/></transform></shape>";
    const auto scene = load_scene_string(test::scene(xml));
    ASSERT_EQ(scene->instances.size(), 100u);
    EXPECT_TRUE(scene->shapes.empty());
    const size_t sphere = scene->instances[0]->group->triangle_count();
    EXPECT_GT(sphere, 10000u);
    EXPECT_EQ(scene->triangle_count(), sphere);
    EXPECT_EQ(scene->instanced_triangle_count(), 100 * sphere);
    // The last instance is hit where it was placed.
    const SurfaceInteraction3f si = scene->intersect(Ray({297.f, 0.f, 5.f}, {0.f, 0.f, -1.f}));
    ASSERT_TRUE(si.is_valid());
    EXPECT_NEAR(si.p.z, 1.f, 1e-3f);
}

// Interactions on an instance equal those on the flattened shapes (instance to_world after the group shape's
// own to_world): position, normals, uv, shading frame and material, under a rotation and a non-uniform scale.
TEST(ShapeInstance, InteractionsMatchTheFlattenedShapes) {
    const auto instanced = load_scene_string(test::scene(std::string(group_xml) +
                                                         "<shape type=\"instance\"><ref id=\"group\"/>"
                                                         "<transform name=\"to_world\">" +
                                                         placement + "</transform></shape>"));
    const auto flat = load_scene_string(test::scene(
        R"(<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
           <shape type="sphere"><float name="radius" value="0.5"/><ref id="red"/>
               <transform name="to_world">)" +
        std::string(placement) + R"(</transform></shape>
           <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="30"/><translate x="1"/>)" +
        placement + "</transform></shape>"));
    int hits = 0, misses = 0;
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j) {
            const Vec3f o(-1.f + 0.06f * float(i), -5.f, -1.f + 0.05f * float(j));
            const Ray ray(o, normalize(Vec3f(0.05f, 1.f, 0.02f)));
            const SurfaceInteraction3f a = instanced->intersect(ray), b = flat->intersect(ray);
            ASSERT_EQ(a.is_valid(), b.is_valid()) << i << " " << j;
            if (!a.is_valid()) {
                ++misses;
                continue;
            }
            ++hits;
            EXPECT_NEAR(a.t, b.t, 1e-4f);
            EXPECT_NEAR(norm(a.p - b.p), 0.f, 1e-4f);
            EXPECT_NEAR(dot(a.n, b.n), 1.f, 1e-4f);
            EXPECT_NEAR(dot(a.sh_frame.n, b.sh_frame.n), 1.f, 1e-4f);
            EXPECT_NEAR(dot(a.sh_frame.s, b.sh_frame.s), 1.f, 1e-4f);
            EXPECT_NEAR(norm(a.wi - b.wi), 0.f, 1e-4f);
            EXPECT_NEAR(a.uv.x, b.uv.x, 1e-4f);
            EXPECT_NEAR(a.uv.y, b.uv.y, 1e-4f);
            EXPECT_EQ(a.prim_index, b.prim_index);
            ASSERT_TRUE(a.bsdf() && b.bsdf());
            EXPECT_EQ(a.bsdf()->to_string(), b.bsdf()->to_string());
        }
    EXPECT_GT(hits, 200);
    EXPECT_GT(misses, 200);
}

// Two instances of a group holding a square (2 x 2 rectangle facing the camera) and a cylinder seen from the
// side (2 r h = 2 * 0.25 * 1): each instance scaled by s covers s^2 (4 + 0.5).
TEST(ShapeInstance, ProjectedAreaOfInstances) {
    const auto scene = load_scene_string(test::projected_area_scene(R"(
    <shape type="shapegroup" id="g">
        <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/></transform><ref id="black"/></shape>
        <shape type="cylinder"><float name="radius" value="0.25"/><point name="p0" x="3" y="0" z="-0.5"/>
            <point name="p1" x="3" y="0" z="0.5"/><ref id="black"/></shape>
    </shape>
    <shape type="instance"><ref id="g"/>
        <transform name="to_world"><scale value="0.3"/><rotate y="1" angle="20"/><translate x="-1" z="1"/></transform>
    </shape>
    <shape type="instance"><ref id="g"/>
        <transform name="to_world"><scale value="0.4"/><translate x="-1" z="-1"/></transform>
    </shape>)"));
    const double exact = (0.09 + 0.16) * 4.5;
    const test::ProjectedArea a = test::projected_area(*scene, 16, 32);
    RecordProperty("area", std::to_string(a.value) + " +- " + std::to_string(a.stderr_value) + " (exact " +
                               std::to_string(exact) + ")");
    EXPECT_NEAR(a.value, exact, 4.0 * a.stderr_value + 3e-4 * 0.125) << a.stderr_value; // cylinder: 128-gon
}

TEST(ShapeInstance, ErrorsMirrorMitsuba) {
    EXPECT_NE(load_error(test::scene(R"(<shape type="shapegroup"><shape type="sphere">
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></shape>)"))
                  .find("<string>:2: a shape inside a shapegroup cannot carry an emitter"),
              std::string::npos);
    EXPECT_NE(load_error(test::scene(R"(<shape type="shapegroup" id="a"><shape type="sphere"/></shape>
        <shape type="shapegroup"><shape type="instance"><ref id="a"/></shape></shape>)"))
                  .find("nested instancing is not supported"),
              std::string::npos);
    EXPECT_NE(load_error(test::scene(R"(<shape type="instance"/>)"))
                  .find("<string>:2: an instance needs a shapegroup"),
              std::string::npos);
    EXPECT_NE(load_error(test::scene(R"(<shape type="instance"><shape type="sphere"/></shape>)"))
                  .find("an instance references a shapegroup, not a 'sphere'"),
              std::string::npos);
}

// Parameters flattens the instances (Scene::flatten_instances): their geometry reaches the estimators.
TEST(ShapeInstance, DerivativesFlattenTheInstances) {
    const auto scene = load_scene_string(test::scene(
        std::string(group_xml) + R"(<shape type="instance" id="inst"><ref id="group"/></shape>)"));
    const size_t triangles = scene->instanced_triangle_count();
    Parameters params(*scene);
    EXPECT_TRUE(scene->instances.empty());
    ASSERT_EQ(scene->shapes.size(), 2u);
    EXPECT_EQ(scene->shapes[0]->id, "inst.0");
    EXPECT_EQ(scene->shapes[1]->id, "inst.1");
    EXPECT_EQ(scene->triangle_count(), triangles);
    EXPECT_NO_THROW(params.find("inst.translate"));
    EXPECT_NO_THROW(params.find("group.0.vertex_positions"));
}
