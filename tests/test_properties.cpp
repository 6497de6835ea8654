// Properties: value types, typed getters and their errors, query tracking (check_all_queried).
#include "scene/factory.h"
#include "scene/properties.h"
#include "scene/texture.h"

#include <gtest/gtest.h>

#include <string>

using namespace penumbra;

namespace {

const SourceLocation object_at{"scene.xml", 3};
SourceLocation at(int line) { return {"scene.xml", line}; }

// The message of the LoadError thrown by `fn` (fails the test if nothing or something else is thrown).
template <typename Fn> std::string load_error(Fn&& fn) {
    try {
        fn();
    } catch (const LoadError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no LoadError thrown";
    return {};
}

#define EXPECT_CONTAINS(haystack, needle) EXPECT_NE((haystack).find(needle), std::string::npos) << (haystack)

class TestObject final : public Object {
  public:
    explicit TestObject(ObjectKind kind) : kind_(kind) {}
    ObjectKind kind() const override { return kind_; }

  private:
    ObjectKind kind_;
};

// One value of every type, each on its own line (4 to 11).
Properties every_type() {
    Properties props("test", object_at);
    props.set("f", 1.5, at(4));
    props.set("i", int64_t(2), at(5));
    props.set("b", true, at(6));
    props.set("s", std::string("bk7"), at(7));
    props.set("c", ColorValue{Color3f(0.1f, 0.2f, 0.3f)}, at(8));
    props.set("v", Vec3f(1.f, 2.f, 3.f), at(9));
    props.set("t", Transform::translate({1, 0, 0}), at(10));
    props.add_object("o", std::make_shared<TestObject>(ObjectKind::BSDF), at(11));
    return props;
}

} // namespace

TEST(Properties, TypeNamesTheTagOfEveryValue) {
    using Tag = Properties::Tag;
    const Properties props = every_type();
    EXPECT_EQ(props.type("f"), Tag::Float);
    EXPECT_EQ(props.type("i"), Tag::Integer);
    EXPECT_EQ(props.type("b"), Tag::Boolean);
    EXPECT_EQ(props.type("s"), Tag::String);
    EXPECT_EQ(props.type("c"), Tag::Color);
    EXPECT_EQ(props.type("v"), Tag::Vector);
    EXPECT_EQ(props.type("t"), Tag::Transform);
    EXPECT_EQ(props.type("o"), Tag::Object);
}

TEST(Properties, TypeDoesNotMarkQueried) {
    const Properties props = every_type();
    for (const char* name : {"f", "i", "b", "s", "c", "v", "t", "o"})
        props.type(name);
    EXPECT_EQ(props.unqueried(), (std::vector<std::string>{"f", "i", "b", "s", "c", "v", "t", "o"}));
}

TEST(Properties, TypeOfAMissingValueIsALoadError) {
    const Properties props = every_type();
    EXPECT_EQ(load_error([&] { props.type("nothing"); }),
              "scene.xml:3: test: missing required parameter 'nothing'");
}

TEST(Properties, GettersConvertCompatibleTypes) {
    const Properties props = every_type();
    EXPECT_FLOAT_EQ(props.get_float("i"), 2.f);     // integer -> float
    EXPECT_EQ(props.get_color("f"), Color3f(1.5f)); // float -> gray
    EXPECT_EQ(props.get_color("i"), Color3f(2.f));
    EXPECT_EQ(props.get_texture("c")->mean(), Color3f(0.1f, 0.2f, 0.3f)); // rgb -> constant texture
    EXPECT_EQ(props.get_string("s"), "bk7");
    EXPECT_TRUE(props.get_bool("b", false));
    EXPECT_EQ(props.get_vector("v"), Vec3f(1.f, 2.f, 3.f));
    EXPECT_EQ(props.get_transform("t").apply_point(Vec3f(0.f)), Vec3f(1.f, 0.f, 0.f));
    EXPECT_EQ(props.get_object("o", ObjectKind::BSDF)->kind(), ObjectKind::BSDF);
    // Defaults apply only to absent values.
    EXPECT_FLOAT_EQ(props.get_float("absent", 4.f), 4.f);
    EXPECT_EQ(props.get_string("absent", "air"), "air");
}

// A value of the wrong type is reported at the value's own line, with the expected and the actual type.
TEST(Properties, GettersReportTypeErrorsAtTheValue) {
    const Properties props = every_type();
    EXPECT_EQ(load_error([&] { props.get_float("s"); }),
              "scene.xml:7: parameter 's' of test: expected float, got string");
    EXPECT_EQ(load_error([&] { props.get_int("f"); }),
              "scene.xml:4: parameter 'f' of test: expected integer, got float");
    EXPECT_EQ(load_error([&] { props.get_bool("i", false); }),
              "scene.xml:5: parameter 'i' of test: expected boolean, got integer");
    EXPECT_EQ(load_error([&] { props.get_string("c"); }),
              "scene.xml:8: parameter 'c' of test: expected string, got rgb");
    EXPECT_EQ(load_error([&] { props.get_color("v"); }),
              "scene.xml:9: parameter 'v' of test: expected rgb, spectrum or float, got point/vector");
    EXPECT_EQ(load_error([&] { props.get_vector("t"); }),
              "scene.xml:10: parameter 't' of test: expected point or vector, got transform");
    EXPECT_EQ(load_error([&] { props.get_transform("b"); }),
              "scene.xml:6: parameter 'b' of test: expected transform, got boolean");
    EXPECT_EQ(load_error([&] { props.get_texture("o"); }),
              "scene.xml:11: parameter 'o' of test: expected texture, got object");
    // A missing required value is reported at the object.
    EXPECT_EQ(load_error([&] { props.get_float("absent"); }),
              "scene.xml:3: test: missing required parameter 'absent'");
}

TEST(Properties, CheckAllQueriedNamesTheFirstUnqueriedValue) {
    Properties props("diffuse", object_at);
    props.set("reflectance", 0.5, at(4));
    props.set("roughness", 0.1, at(5));
    props.set("alpha", 0.2, at(6));
    props.get_color("reflectance");
    EXPECT_EQ(props.unqueried(), (std::vector<std::string>{"roughness", "alpha"}));
    EXPECT_EQ(load_error([&] { props.check_all_queried("bsdf 'diffuse'"); }),
              "scene.xml:5: unknown parameter 'roughness' of bsdf 'diffuse'");
    props.get_float("roughness");
    props.get_float("alpha");
    EXPECT_NO_THROW(props.check_all_queried("bsdf 'diffuse'"));
}

TEST(Properties, CheckAllQueriedNamesNestedObjects) {
    Properties named("diffuse", object_at);
    named.add_object("base", std::make_shared<TestObject>(ObjectKind::Texture), at(4));
    EXPECT_EQ(load_error([&] { named.check_all_queried("bsdf 'diffuse'"); }),
              "scene.xml:4: bsdf 'diffuse' does not accept a nested texture named 'base'");

    // An unnamed child gets a generated name, which the message leaves out.
    Properties unnamed("diffuse", object_at);
    unnamed.add_object("", std::make_shared<TestObject>(ObjectKind::Emitter), at(5));
    EXPECT_EQ(load_error([&] { unnamed.check_all_queried("bsdf 'diffuse'"); }),
              "scene.xml:5: bsdf 'diffuse' does not accept a nested emitter");

    // objects(kind) marks the children of that kind as queried.
    EXPECT_EQ(unnamed.objects(ObjectKind::Emitter).size(), 1u);
    EXPECT_NO_THROW(unnamed.check_all_queried("bsdf 'diffuse'"));
}

// The BSDF loaders read an IOR as a float, an integer or a material name (Properties::type decides).
TEST(Properties, IorIsAFloatAnIntegerOrAName) {
    const LoadContext ctx;
    Properties by_int("dielectric", object_at);
    by_int.set("int_ior", int64_t(2), at(4));
    EXPECT_NO_THROW(make_bsdf(by_int, ctx));
    EXPECT_TRUE(by_int.unqueried().empty());

    Properties by_name("dielectric", object_at);
    by_name.set("int_ior", std::string("Diamond"), at(4));
    EXPECT_NO_THROW(make_bsdf(by_name, ctx));

    Properties by_color("dielectric", object_at);
    by_color.set("int_ior", ColorValue{Color3f(1.5f)}, at(4));
    EXPECT_EQ(load_error([&] { make_bsdf(by_color, ctx); }),
              "scene.xml:4: parameter 'int_ior' of dielectric: expected string, got rgb");
}
