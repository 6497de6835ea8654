// Every malformed scene gives one LoadError "file:line: message" that names what was expected.
#include "scene/scene.h"
#include "scene/xml_parser.h"

#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <map>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string string_error(const std::string& xml, const std::map<std::string, std::string>& defines = {}) {
    return load_error_of([&] { parse_xml_string(xml, ".", defines); });
}

#define EXPECT_CONTAINS(haystack, needle) EXPECT_NE((haystack).find(needle), std::string::npos) << (haystack)

} // namespace

TEST(XmlErrors, MalformedXml) {
    const std::string msg =
        string_error(scene("<bsdf type=\"diffuse\">\n<float name=\"a\" value=\"1\">\n</bsdf>"));
    EXPECT_CONTAINS(msg, "<string>:4: malformed XML");
}

TEST(XmlErrors, UnknownTag) {
    const std::string msg =
        string_error(scene("<bsdf type=\"diffuse\">\n  <colour name=\"a\" value=\"1\"/>\n</bsdf>"));
    EXPECT_CONTAINS(msg, "<string>:3: unexpected tag <colour>");
    EXPECT_CONTAINS(msg, "expected an object");
}

TEST(XmlErrors, BadNumbers) {
    EXPECT_CONTAINS(
        string_error(scene("<bsdf type=\"x\">\n<float name=\"alpha\" value=\"1.0x\"/></bsdf>")),
        "<string>:3: <float name=\"alpha\"> attribute 'value': expected a floating-point number, got '1.0x'");
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\"><integer name=\"n\" value=\"3.5\"/></bsdf>")),
                    "<string>:2: <integer name=\"n\"> attribute 'value': expected an integer, got '3.5'");
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\"><boolean name=\"b\" value=\"yes\"/></bsdf>")),
                    "expected 'true' or 'false', got 'yes'");
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\"><rgb name=\"c\" value=\"0.1 0.2\"/></bsdf>")),
                    "<rgb name=\"c\"> attribute 'value': expected 1 or 3 numbers, got '0.1 0.2'");
    EXPECT_CONTAINS(
        string_error(scene("<shape type=\"x\"><transform name=\"to_world\">\n<translate x=\"one\"/>"
                           "</transform></shape>")),
        "<string>:3: <translate> attribute 'x': expected a floating-point number, got 'one'");
    EXPECT_CONTAINS(string_error(scene("<shape type=\"x\"><transform name=\"t\"><matrix value=\"1 0 0 1\"/>"
                                       "</transform></shape>")),
                    "<matrix> attribute 'value': expected 16 (or 9) numbers, got 4");
    EXPECT_CONTAINS(
        string_error(scene("<bsdf type=\"x\"><spectrum name=\"s\" value=\"500:0.1, 400\"/></bsdf>")),
        "expected wavelength:value pairs, got '400'");
}

TEST(XmlErrors, UnknownReferenceId) {
    const std::string msg =
        string_error(scene("<shape type=\"cube\">\n\n  <ref name=\"bsdf\" id=\"missing_mat\"/>\n</shape>"));
    EXPECT_CONTAINS(msg, "<string>:4: reference to unknown id 'missing_mat'");
    EXPECT_CONTAINS(string_error(scene("<alias id=\"nothing\" as=\"b\"/>")),
                    "<string>:2: <alias> of unknown id 'nothing'");
}

TEST(XmlErrors, UndefinedVariable) {
    const std::string xml =
        scene("<sensor type=\"perspective\">\n<float name=\"fov\" value=\"$fov_deg\"/></sensor>");
    EXPECT_CONTAINS(string_error(xml), "<string>:3: undefined parameter '$fov_deg' in attribute 'value'");
    EXPECT_NO_THROW(parse_xml_string(xml, ".", {{"fov_deg", "45"}}));
    // A default declared after its use does not apply (document order, as in Mitsuba).
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"$t\"/>\n<default name=\"t\" value=\"diffuse\"/>")),
                    "undefined parameter '$t' in attribute 'type'");
}

TEST(XmlErrors, IncludeCycle) {
    TempDir dir;
    dir.write("a.xml", scene("<include filename=\"b.xml\"/>"));
    dir.write("b.xml", scene("\n<include filename=\"a.xml\"/>"));
    const std::string main = dir.write("main.xml", scene("<include filename=\"a.xml\"/>"));
    const std::string msg = load_error_of([&] { parse_xml_file(main); });
    EXPECT_CONTAINS(msg, "b.xml:3: include cycle:");
    EXPECT_CONTAINS(msg, "a.xml -> ");
    // Including the main file from itself is a cycle too.
    EXPECT_CONTAINS(
        load_error_of([&] { parse_xml_file(dir.write("self.xml", scene("<include filename=\"self.xml\"/>"))); }),
        "self.xml:2: include cycle");
}

TEST(XmlErrors, MissingIncludeFile) {
    TempDir dir;
    const std::string main = dir.write("main.xml", scene("\n<include filename=\"nowhere/parts.xml\"/>"));
    EXPECT_CONTAINS(load_error_of([&] { parse_xml_file(main); }),
                    "main.xml:3: included file 'nowhere/parts.xml' not found");
}

TEST(XmlErrors, ErrorsInsideIncludedFilesNameThatFile) {
    TempDir dir;
    dir.write("part.xml", scene("<bsdf type=\"diffuse\">\n\n<float name=\"x\" value=\"bad\"/></bsdf>"));
    const std::string main = dir.write("main.xml", scene("<include filename=\"part.xml\"/>"));
    EXPECT_CONTAINS(load_error_of([&] { parse_xml_file(main); }), "part.xml:4: <float name=\"x\">");
}

TEST(XmlErrors, DuplicateParameterAndId) {
    const std::string msg =
        string_error(scene("<bsdf type=\"diffuse\">\n  <float name=\"alpha\" value=\"1\"/>\n  <float "
                           "name=\"alpha\" value=\"2\"/>\n</bsdf>"));
    EXPECT_CONTAINS(msg, "<string>:4: ");
    EXPECT_CONTAINS(msg, "'alpha'");
    EXPECT_CONTAINS(msg, "<string>:3"); // the first declaration
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"a\" id=\"m\"/>\n<bsdf type=\"b\" id=\"m\"/>")),
                    "<string>:3: duplicate id 'm' (first declared at <string>:2)");
}

TEST(XmlErrors, MissingOrUnexpectedAttributes) {
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\"><float name=\"a\"/></bsdf>")),
                    "<string>:2: missing attribute 'value' in <float>");
    EXPECT_CONTAINS(string_error(scene("<bsdf id=\"a\"/>")),
                    "<string>:2: missing attribute 'type' in <bsdf>");
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\"><float name=\"a\" value=\"1\" unit=\"m\"/></bsdf>")),
                    "unexpected attribute 'unit' in <float> (expected name, value)");
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\"><spectrum name=\"s\"/></bsdf>")),
                    "expected exactly one of the attributes 'value' and 'filename'");
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\" name=\"_arg_0\"/>")),
                    "leading underscore is reserved");
}

TEST(XmlErrors, VersionAndRoot) {
    EXPECT_CONTAINS(string_error("<scene version=\"0.6.0\">\n<shape type=\"obj\"/>\n</scene>"),
                    "<string>:1: scene version 0.6.0 is a Mitsuba 0.6 scene");
    EXPECT_CONTAINS(string_error("<scene>\n</scene>"), "<string>:1: missing attribute 'version' in <scene>");
    EXPECT_CONTAINS(string_error("<scene version=\"three\"/>"), "could not parse scene version 'three'");
    EXPECT_CONTAINS(string_error("<bsdf type=\"diffuse\" version=\"3.0.0\"/>"),
                    "expected the root element <scene>");
}

TEST(XmlErrors, MisplacedElements) {
    // Values directly in <scene> are the scene's parameters (Mitsuba 3 has one).
    EXPECT_CONTAINS(load_error_of([] { load_scene_string(scene("<float name=\"a\" value=\"1\"/>")); }),
                    "<string>:2: unknown parameter 'a' of <scene>");
    EXPECT_CONTAINS(string_error(scene("<shape type=\"x\"><translate x=\"1\"/></shape>")),
                    "<translate> may only appear inside <transform>");
    EXPECT_CONTAINS(
        string_error(scene("<shape type=\"x\"><transform name=\"t\"><float name=\"a\" value=\"1\"/>"
                           "</transform></shape>")),
        "<transform> may only contain translate, rotate, scale, matrix and lookat (got <float>)");
    EXPECT_CONTAINS(string_error(scene("<bsdf type=\"x\"><path value=\".\"/></bsdf>")),
                    "<path> may only appear directly inside <scene>");
    EXPECT_CONTAINS(string_error(scene("<path value=\"no/such/folder\"/>")),
                    "<path>: folder 'no/such/folder' not found");
    EXPECT_CONTAINS(string_error(scene("<shape type=\"x\">some text</shape>")),
                    "unexpected text 'some text'");
}

TEST(XmlErrors, InvalidTransforms) {
    EXPECT_CONTAINS(string_error(scene(
                        "<shape type=\"x\"><transform name=\"t\">\n<lookat origin=\"0 0 0\" target=\"0 0 1\""
                        " up=\"0 0 1\"/></transform></shape>")),
                    "<string>:3: <lookat>: ");
    EXPECT_CONTAINS(
        string_error(scene("<shape type=\"x\"><transform name=\"t\"><lookat origin=\"0 0 0\" target=\"0 1\"/>"
                           "</transform></shape>")),
        "<lookat> attribute 'target': expected 3 numbers, got '0 1'");
    EXPECT_CONTAINS(string_error(scene("<shape type=\"x\"><transform name=\"t\"><rotate angle=\"30\"/>"
                                       "</transform></shape>")),
                    "<rotate>: expected a non-zero rotation axis");
    EXPECT_CONTAINS(string_error(scene("<shape type=\"x\"><transform name=\"t\"><rotate x=\"1\"/>"
                                       "</transform></shape>")),
                    "missing attribute 'angle' in <rotate>");
    EXPECT_CONTAINS(
        string_error(scene("<shape type=\"x\"><transform name=\"t\"><matrix value=\"0 0 0 0 0 0 0 0 0\"/>"
                           "</transform></shape>")),
        "<matrix>: expected an invertible matrix");
}

TEST(XmlErrors, LoaderRejectsWhatPenumbraCannotRender) {
    const auto load_error = [](const std::string& xml) { return load_error_of([&] { load_scene_string(xml); }); };
    // Unsupported plugin: exactly one line at the declaration.
    EXPECT_EQ(
        load_error(scene("<shape type=\"cube\">\n  <bsdf type=\"hair\"/>\n</shape>")),
        "<string>:3: unsupported bsdf plugin 'hair': it is meant for curve shapes, which penumbra does not "
        "have");
    // A parameter the plugin does not know.
    const std::string unknown =
        load_error(scene("<bsdf type=\"diffuse\">\n<float name=\"roughness\" value=\"1\"/></bsdf>"));
    EXPECT_CONTAINS(unknown, "<string>:3: ");
    EXPECT_CONTAINS(unknown, "'roughness'");
    // Mitsuba allows one integrator.
    EXPECT_CONTAINS(load_error(scene("<integrator type=\"path\"/>\n<integrator type=\"direct\"/>")),
                    "<string>:3: only one <integrator>");
    EXPECT_CONTAINS(
        load_error(scene("<medium type=\"homogeneous\">\n<phase type=\"hg\"><float name=\"g\" value=\"1.5\"/>"
                         "</phase></medium>")),
        "<string>:3: hg: the asymmetry parameter 'g' must lie in (-1, 1)");
    EXPECT_CONTAINS(load_error(scene("<bsdf type=\"twosided\" id=\"loop\">\n<ref id=\"loop\"/></bsdf>")),
                    "<string>:2: circular reference: bsdf 'loop'");
    EXPECT_EQ(load_error(scene("<sensor type=\"perspective\"><sampler type=\"halton\"/></sensor>")),
              "<string>:2: unsupported sampler plugin 'halton'");
    // An area emitter only makes sense attached to the shape that emits.
    EXPECT_EQ(load_error(scene("<emitter type=\"area\"/>")),
              "<string>:2: an area emitter must be attached to a shape (nest it in the <shape>, or <ref> it from one)");
    // ... but declaring it at the top level for a shape to <ref> (as Mitsuba's own scenes do) is fine.
    const auto s = load_scene_string(scene("<shape type=\"rectangle\"><ref id=\"lamp\"/></shape>\n"
                                           "<emitter type=\"area\" id=\"lamp\"/>"));
    ASSERT_EQ(s->emitters.size(), 1u);
    EXPECT_EQ(s->emitters[0]->shape(), s->shapes[0].get());
}

// Mitsuba 3's scene parameter embree_use_robust_intersections (default false, as there).
TEST(XmlScene, RobustIntersectionsParameter) {
    const std::string sphere = "<shape type=\"sphere\"/>";
    EXPECT_FALSE(load_scene_string(scene(sphere))->robust_intersections);
    EXPECT_TRUE(load_scene_string(scene("<boolean name=\"embree_use_robust_intersections\" value=\"true\"/>" +
                                        sphere))
                    ->robust_intersections);
}
