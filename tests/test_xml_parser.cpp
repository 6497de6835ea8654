// The XML layer on its own (transforms, defaults and defines, $substitution, refs, aliases, includes, <path>,
// value parsing) against hand-computed expectations, then the loader that instantiates it.
#include "core/spectrum.h"
#include "render/integrator.h"
#include "scene/scene.h"
#include "scene/xml_parser.h"

#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace penumbra;
using namespace penumbra::test;
namespace fs = std::filesystem;

namespace {

// Float transforms are composed in double and rounded to float: 1e-5 covers a few ulps at magnitudes <= 10.
constexpr float kEps = 1e-5f;

void expect_near(const Vec3f& a, const Vec3f& b) {
    EXPECT_NEAR(a.x, b.x, kEps) << a << " vs " << b;
    EXPECT_NEAR(a.y, b.y, kEps) << a << " vs " << b;
    EXPECT_NEAR(a.z, b.z, kEps) << a << " vs " << b;
}

// The single top-level object of a parsed scene.
const XmlNode& only_object(const XmlScene& s) {
    EXPECT_EQ(s.objects.size(), 1u);
    return *s.objects.at(0).node;
}

Transform to_world(const std::string& ops) {
    const XmlScene s = parse_xml_string(
        scene("<shape type=\"cube\"><transform name=\"to_world\">" + ops + "</transform></shape>"));
    return only_object(s).props.get_transform("to_world");
}

} // namespace

TEST(XmlParser, TransformOpsComposeInDocumentOrder) {
    // translate then scale: T = S * Tr, so the origin goes to (1,0,0) then to (2,0,0).
    expect_near(to_world("<translate x=\"1\"/><scale value=\"2\"/>").apply_point(Vec3f(0.f)), Vec3f(2, 0, 0));
    // scale then translate: the origin only moves by the translation.
    expect_near(to_world("<scale value=\"2\"/><translate x=\"1\"/>").apply_point(Vec3f(0.f)), Vec3f(1, 0, 0));
    // rotate 90 degrees about z, then translate: (1,0,0) -> (0,1,0) -> (1,1,0).
    expect_near(
        to_world("<rotate z=\"1\" angle=\"90\"/><translate value=\"1 0 0\"/>").apply_point(Vec3f(1, 0, 0)),
        Vec3f(1, 1, 0));
    // Per-axis scale with x/y/z (missing axes default to 1) and rotate with a `value` axis.
    expect_near(to_world("<scale x=\"2\" z=\"3\"/>").apply_point(Vec3f(1, 1, 1)), Vec3f(2, 1, 3));
    expect_near(to_world("<rotate value=\"0, 0, 1\" angle=\"180\"/>").apply_point(Vec3f(1, 0, 0)),
                Vec3f(-1, 0, 0));
}

TEST(XmlParser, MatrixIsRowMajorAndComposes) {
    const Transform m = to_world("<matrix value=\"1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1\"/>");
    expect_near(m.apply_point(Vec3f(0.f)), Vec3f(5, 6, 7));
    // A 3x3 matrix is the linear part (Mitsuba), here a swap of x and y.
    expect_near(to_world("<matrix value=\"0 1 0 1 0 0 0 0 1\"/>").apply_point(Vec3f(1, 2, 3)),
                Vec3f(2, 1, 3));
    // matrix then scale: the translation is scaled too.
    expect_near(to_world("<matrix value=\"1 0 0 5 0 1 0 6 0 0 1 7 0 0 0 1\"/><scale value=\"2\"/>")
                    .apply_point(Vec3f(0.f)),
                Vec3f(10, 12, 14));
    // The inverse is kept consistent.
    expect_near(m.inverse().apply_point(Vec3f(5, 6, 7)), Vec3f(0.f));
}

TEST(XmlParser, LookAtFollowsMitsubaConvention) {
    // Mitsuba's look_at: local +z forward, +x left (cross(up, forward)), +y up; origin at `origin`.
    const Transform t = to_world("<lookat origin=\"0, 0, 5\" target=\"0 0 0\" up=\"0 1 0\"/>");
    expect_near(t.apply_point(Vec3f(0.f)), Vec3f(0, 0, 5));
    expect_near(t.apply_vector(Vec3f(0, 0, 1)), Vec3f(0, 0, -1));
    expect_near(t.apply_vector(Vec3f(0, 1, 0)), Vec3f(0, 1, 0));
    expect_near(t.apply_vector(Vec3f(1, 0, 0)), Vec3f(-1, 0, 0));
    // lookat after a translation moves the whole frame (T = lookat * translate).
    const Transform u =
        to_world("<translate z=\"1\"/><lookat origin=\"0 0 5\" target=\"0 0 0\" up=\"0 1 0\"/>");
    expect_near(u.apply_point(Vec3f(0.f)), Vec3f(0, 0, 4));
    // Without `up` a perpendicular up vector is chosen: the frame stays orthonormal and looks at the target.
    const Transform v = to_world("<lookat origin=\"1 2 3\" target=\"1 2 0\"/>");
    expect_near(v.apply_vector(Vec3f(0, 0, 1)), Vec3f(0, 0, -1));
    EXPECT_NEAR(dot(v.apply_vector(Vec3f(1, 0, 0)), v.apply_vector(Vec3f(0, 1, 0))), 0.f, kEps);
    EXPECT_NEAR(norm(v.apply_vector(Vec3f(0, 1, 0))), 1.f, kEps);
}

TEST(XmlParser, ValuesOfEveryType) {
    const XmlScene s = parse_xml_string(scene(R"(<bsdf type="test">
        <float name="f" value="-1.5e-1"/>
        <integer name="i" value=" 42 "/>
        <boolean name="b" value="TRUE"/>
        <string name="s" value="hello world"/>
        <rgb name="c3" value="0.1,0.2 , 0.3"/>
        <rgb name="c1" value="0.5"/>
        <spectrum name="gray" value="0.25"/>
        <point name="p" value="1 2 3"/>
        <vector name="v" x="4" z="6"/>
    </bsdf>)"));
    const Properties& p = only_object(s).props;
    EXPECT_FLOAT_EQ(p.get_float("f"), -0.15f);
    EXPECT_EQ(p.get_int("i"), 42);
    EXPECT_TRUE(p.get_bool("b", false));
    EXPECT_EQ(p.get_string("s"), "hello world");
    EXPECT_EQ(p.get_color("c3"), Color3f(0.1f, 0.2f, 0.3f));
    EXPECT_EQ(p.get_color("c1"), Color3f(0.5f));
    EXPECT_EQ(p.get_color("gray"), Color3f(0.25f));
    EXPECT_EQ(p.get_vector("p"), Vec3f(1, 2, 3));
    EXPECT_EQ(p.get_vector("v"), Vec3f(4, 0, 6));
    EXPECT_TRUE(p.unqueried().empty());
}

TEST(XmlParser, SpectrumListsUseMitsubasBoundedAndIlluminantRules) {
    const std::vector<std::pair<float, float>> samples = {
        {400.f, 0.2f}, {500.f, 0.9f}, {600.f, 0.4f}, {700.f, 0.7f}};
    const std::string list = "400:0.2, 500:0.9 600:0.4,700:0.7";
    const XmlScene s = parse_xml_string(scene(R"(<shape type="cube">
        <bsdf type="roughconductor">
            <spectrum name="specular_reflectance" value=")" +
                                              list + R"("/>
            <spectrum name="eta" value=")" + list +
                                              R"("/>
        </bsdf>
        <emitter type="area"><spectrum name="radiance" value=")" +
                                              list + R"("/></emitter>
    </shape>)"));
    const XmlNode& shape = only_object(s);
    ASSERT_EQ(shape.children.size(), 2u);
    const Properties& bsdf = shape.children[0].node->props;
    const Properties& emitter = shape.children[1].node->props;
    // Mitsuba 3 xml.cpp: reflectances are bounded, IOR and emission spectra are not; everything but emission
    // is integrated against D65 (bounded = !(emitter || unbounded), d65 = !(emitter && !unbounded)).
    EXPECT_EQ(bsdf.get_color("specular_reflectance"), spectrum_to_rgb(samples, true, true));
    EXPECT_EQ(bsdf.get_color("eta"), spectrum_to_rgb(samples, false, true));
    EXPECT_EQ(emitter.get_color("radiance"), spectrum_to_rgb(samples, false, false));
}

TEST(XmlParser, SpectrumFromSpdFileOnSearchPath) {
    TempDir dir;
    dir.write("spectra/flat.spd", "# flat\n400 0.5\n550 0.5\n700 0.5\n");
    const std::string path = dir.write("main.xml", scene(R"(<path value="spectra"/>
        <bsdf type="diffuse"><spectrum name="reflectance" filename="flat.spd"/></bsdf>)"));
    const XmlScene s = parse_xml_file(path);
    const std::vector<std::pair<float, float>> samples = {{400.f, 0.5f}, {550.f, 0.5f}, {700.f, 0.5f}};
    EXPECT_EQ(only_object(s).props.get_color("reflectance"), spectrum_to_rgb(samples, true, true));
}

TEST(XmlParser, DefaultsDefinesAndSubstitution) {
    const std::string xml = scene(R"(<default name="spp" value="4"/>
        <default name="spp" value="99"/>
        <default name="res" value="64"/>
        <default name="kind" value="independent"/>
        <sampler type="$kind">
            <integer name="sample_count" value="$spp"/>
            <string name="label" value="$res x $res px"/>
        </sampler>)");
    {
        const XmlScene s = parse_xml_string(xml);
        const XmlNode& n = only_object(s);
        EXPECT_EQ(n.type, "independent");
        EXPECT_EQ(n.props.get_int("sample_count"), 4); // the first <default> wins
        EXPECT_EQ(n.props.get_string("label"), "64 x 64 px");
    }
    {
        const XmlScene s = parse_xml_string(xml, ".", {{"spp", "16"}, {"res", "8"}});
        const XmlNode& n = only_object(s);
        EXPECT_EQ(n.props.get_int("sample_count"), 16); // -D beats <default>
        EXPECT_EQ(n.props.get_string("label"), "8 x 8 px");
    }
}

TEST(XmlParser, RefsAndAliasesShareOneDeclaration) {
    const XmlScene s = parse_xml_string(scene(R"(<shape type="sphere" id="ball">
            <ref id="white"/>
        </shape>
        <bsdf type="diffuse" id="white"/>
        <alias id="white" as="snow"/>
        <shape type="cube"><ref name="bsdf" id="snow"/></shape>)"));
    ASSERT_EQ(s.objects.size(), 3u);
    const auto& white = s.ids.at("white");
    EXPECT_EQ(white->kind, ObjectKind::BSDF);
    EXPECT_EQ(s.ids.at("snow"), white);
    // A forward reference without a name, and a named reference through the alias.
    const XmlChild& first = s.objects[0].node->children.at(0);
    EXPECT_EQ(first.node, white);
    EXPECT_EQ(first.name, "");
    const XmlChild& second = s.objects[2].node->children.at(0);
    EXPECT_EQ(second.node, white);
    EXPECT_EQ(second.name, "bsdf");
    EXPECT_EQ(second.ref_id, "snow");
    EXPECT_EQ(s.ids.at("ball")->type, "sphere");
}

TEST(XmlParser, NestedObjectsKeepOrderNamesAndLocations) {
    const XmlScene s = parse_xml_string(scene(R"(<sensor type="perspective">
    <film type="hdrfilm" name="film">
        <rfilter type="tent"/>
    </film>
    <sampler type="independent"/>
</sensor>)"));
    const XmlNode& sensor = only_object(s);
    EXPECT_EQ(sensor.kind, ObjectKind::Sensor);
    EXPECT_EQ(sensor.location.str(), "<string>:2");
    ASSERT_EQ(sensor.children.size(), 2u);
    EXPECT_EQ(sensor.children[0].name, "film");
    EXPECT_EQ(sensor.children[0].node->kind, ObjectKind::Film);
    EXPECT_EQ(sensor.children[0].location.line, 3);
    EXPECT_EQ(sensor.children[0].node->children.at(0).node->kind, ObjectKind::RFilter);
    EXPECT_EQ(sensor.children[1].node->kind, ObjectKind::Sampler);
    EXPECT_EQ(sensor.children[1].location.line, 6);
}

TEST(XmlParser, IncludesAndPaths) {
    TempDir dir;
    // An included <scene> is spliced in; it includes a file found through a <path> of the main file, whose
    // root is a single object. Defaults declared in included files apply to later elements.
    dir.write("parts/materials.xml", scene(R"(<default name="albedo" value="0.3"/>
        <bsdf type="diffuse" id="mat"><rgb name="reflectance" value="$albedo"/></bsdf>
        <include filename="light.xml"/>)"));
    dir.write("lib/light.xml", "<emitter type=\"constant\" id=\"sky\"/>\n");
    const std::string main = dir.write("main.xml", scene(R"(<path value="lib"/>
        <include filename="parts/materials.xml"/>
        <shape type="cube"><ref id="mat"/></shape>)"));
    const XmlScene s = parse_xml_file(main);
    ASSERT_EQ(s.objects.size(), 3u);
    EXPECT_EQ(s.objects[0].node->id, "mat");
    EXPECT_EQ(s.objects[0].node->props.get_color("reflectance"), Color3f(0.3f));
    EXPECT_EQ(s.objects[0].node->location.file, (fs::path(dir.str()) / "parts/materials.xml").string());
    EXPECT_EQ(s.objects[0].node->location.line, 3);
    EXPECT_EQ(s.objects[1].node->id, "sky");
    EXPECT_EQ(s.objects[2].node->children.at(0).node, s.objects[0].node);
    ASSERT_EQ(s.search_paths.size(), 2u);
    EXPECT_EQ(s.search_paths[0], dir.str());
    EXPECT_EQ(s.search_paths[1], (fs::path(dir.str()) / "lib").string());
}

TEST(XmlParser, IncludeInsideAnObjectAddsToThatObject) {
    TempDir dir;
    dir.write("params.xml", scene(R"(<float name="alpha" value="0.2"/>)"));
    const std::string main = dir.write("main.xml", scene(R"(<bsdf type="roughconductor">
        <include filename="params.xml"/>
    </bsdf>)"));
    EXPECT_FLOAT_EQ(only_object(parse_xml_file(main)).props.get_float("alpha"), 0.2f);
}

// ---- The loader on top of the parser: instantiation, sharing, defaults and scene lists.

TEST(XmlLoader, RefsShareOneInstanceAndDefaultsAreMitsubas) {
    const auto s = load_scene_string(scene(R"(<bsdf type="diffuse" id="white"/>
        <alias id="white" as="snow"/>
        <shape type="cube" id="box"><ref id="white"/></shape>
        <shape type="sphere"><ref name="bsdf" id="white"/></shape>)"));
    ASSERT_EQ(s->shapes.size(), 2u);
    const Object* white = s->named_objects.at("white").get();
    EXPECT_EQ(static_cast<const Object*>(s->shapes[0]->bsdf.get()), white);
    EXPECT_EQ(static_cast<const Object*>(s->shapes[1]->bsdf.get()), white);
    EXPECT_EQ(white->plugin, "diffuse");
    EXPECT_EQ(white->location.str(), "<string>:2");
    EXPECT_EQ(s->named_objects.at("snow").get(), white);
    EXPECT_EQ(s->named_objects.at("box").get(), static_cast<const Object*>(s->shapes[0].get()));
    EXPECT_EQ(s->shapes[0]->id, "box");
    // No sensor or integrator declared: a perspective sensor with its default film, and the path tracer.
    ASSERT_TRUE(s->sensor && s->sensor->film && s->integrator);
    EXPECT_EQ(s->sensor->plugin, "perspective");
    EXPECT_EQ(s->sensor->film->width, 768);
    EXPECT_EQ(s->sensor->film->height, 576);
    EXPECT_EQ(s->integrator->plugin, "path");
    EXPECT_TRUE(s->emitters.empty());
}

TEST(XmlLoader, AreaEmittersJoinTheEmitterListWithTheirShape) {
    const auto s =
        load_scene_string(scene(R"(<emitter type="point"><rgb name="intensity" value="1"/></emitter>
        <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
        <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="32"/>
            <integer name="height" value="16"/></film></sensor>)"));
    ASSERT_EQ(s->emitters.size(), 2u);
    EXPECT_EQ(s->emitters[0]->plugin, "point");
    EXPECT_EQ(s->emitters[1]->plugin, "area");
    EXPECT_EQ(s->emitters[1]->shape(), s->shapes.at(0).get());
    EXPECT_EQ(s->emitters[1].get(), s->shapes[0]->emitter.get());
    EXPECT_EQ(s->sensor->film->width, 32);
    EXPECT_EQ(s->sensor->film->height, 16);
}
