// make_shape: Mitsuba 3 shape parameters, normal conventions and error messages.
#include "scene/bsdf.h"
#include "scene/factory.h"
#include "scene/shape.h"

#include "mesh_test_util.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace penumbra;
using penumbra::test::error_of;
using penumbra::test::ScratchDir;
namespace fs = std::filesystem;

namespace {

const SourceLocation xml{"scene.xml", 7};

// A per-process scratch directory (removed at exit) as the only search path.
LoadContext context() {
    static const ScratchDir dir("penumbra_test_shape_");
    return LoadContext{{dir.path.string()}};
}

void write(const std::string& name, const std::string& contents) {
    test::write_file(context().search_paths[0], name, contents);
}

std::shared_ptr<Shape> build(const Properties& props) {
    auto shape = std::dynamic_pointer_cast<Shape>(make_shape(props, context()));
    props.check_all_queried("shape");
    return shape;
}

// Two triangles folded along the x axis (a "tent"), with texture coordinates and no normals.
const char* tent_obj = "v 0 0 0\nv 1 0 0\nv 0 1 1\nv 0 -1 1\n"
                       "vt 0 0\nvt 1 0\nvt 0 0.25\nvt 0 0.75\n"
                       "f 1/1 2/2 3/3\nf 2/2 1/1 4/4\n";

} // namespace

TEST(ShapeFactory, ObjFlipsTexCoordsByDefaultAndAppliesToWorld) {
    write("tent.obj", tent_obj);
    Properties props("obj", xml);
    props.set("filename", std::string("tent.obj"), xml);
    props.set("to_world", Transform::translate({0, 0, 5}), xml);
    const auto shape = build(props);
    ASSERT_TRUE(shape);
    EXPECT_EQ(shape->mesh.face_count(), 2u);
    EXPECT_FLOAT_EQ(shape->mesh.positions[2].z, 6.f);
    EXPECT_FLOAT_EQ(shape->mesh.uvs[2].y, 0.75f); // 1 - 0.25
    ASSERT_TRUE(shape->bsdf) << "a default diffuse BSDF is expected";
    EXPECT_FALSE(shape->emitter);

    Properties raw("obj", xml);
    raw.set("filename", std::string("tent.obj"), xml);
    raw.set("flip_tex_coords", false, xml);
    EXPECT_FLOAT_EQ(build(raw)->mesh.uvs[2].y, 0.25f);
}

TEST(ShapeFactory, MissingNormalsAreRecomputedUnlessFaceNormals) {
    write("tent.obj", tent_obj);
    Properties props("obj", xml);
    props.set("filename", std::string("tent.obj"), xml);
    const auto smooth = build(props);
    ASSERT_EQ(smooth->mesh.normals.size(), 4u);
    // Vertices on the fold get the angle-weighted mean of both face normals; by symmetry both angles are
    // equal.
    const Vec3f n0 = smooth->face_normal(0), n1 = smooth->face_normal(1);
    const Vec3f mean = normalize(n0 + n1);
    for (int v = 0; v < 2; ++v) {
        EXPECT_NEAR(smooth->mesh.normals[v].x, mean.x, 1e-6f);
        EXPECT_NEAR(smooth->mesh.normals[v].y, mean.y, 1e-6f);
        EXPECT_NEAR(smooth->mesh.normals[v].z, mean.z, 1e-6f);
    }
    EXPECT_NEAR(dot(smooth->mesh.normals[2], n0), 1.f, 1e-6f);

    Properties faceted("obj", xml);
    faceted.set("filename", std::string("tent.obj"), xml);
    faceted.set("face_normals", true, xml);
    const auto flat = build(faceted);
    EXPECT_TRUE(flat->face_normals);
    EXPECT_TRUE(flat->mesh.normals.empty());
}

TEST(ShapeFactory, FlipNormalsFlipsGeometricAndShadingNormals) {
    Properties props("sphere", xml);
    props.set("radius", 2.0, xml);
    props.set("center", Vec3f(0, 0, 1), xml);
    props.set("flip_normals", true, xml);
    const auto sphere = build(props);
    // Tessellation lowers the area by at most 1 - cos^2(g) ~ 0.3% (derivation in test_mesh_shapes.cpp).
    EXPECT_NEAR(sphere->surface_area(), 16.f * Pi, 0.01f * 16.f * Pi);
    // A ray along -x hits the outside near (2, 0, 1); flipped normals point inward, i.e. along -x.
    const Ray ray(Vec3f(5, 0.01f, 1.02f), Vec3f(-1, 0, 0));
    for (uint32_t f = 0; f < sphere->mesh.face_count(); ++f) {
        const uint32_t* i = &sphere->mesh.indices[3 * f];
        const Vec3f p0 = sphere->mesh.positions[i[0]], e1 = sphere->mesh.positions[i[1]] - p0,
                    e2 = sphere->mesh.positions[i[2]] - p0;
        const Vec3f q = cross(ray.d, e2);
        const float det = dot(e1, q);
        if (std::abs(det) < 1e-12f) continue;
        const Vec3f s = ray.o - p0, r = cross(s, e1);
        const float b1 = dot(s, q) / det, b2 = dot(ray.d, r) / det, t = dot(e2, r) / det;
        if (b1 < 0 || b2 < 0 || b1 + b2 > 1 || t <= 0 || t > 4.f) continue;
        const SurfaceInteraction3f si = sphere->compute_surface_interaction(ray, t, f, b1, b2);
        EXPECT_LT(si.n.x, -0.99f);
        EXPECT_LT(si.sh_frame.n.x, -0.99f);
        EXPECT_LT(si.wi.z, 0.f); // the ray arrives from the back side
        return;
    }
    FAIL() << "no hit";
}

TEST(ShapeFactory, RectangleCubeDiskAndSerializedParameters) {
    Properties rect("rectangle", xml);
    rect.set("to_world", Transform::scale({2, 3, 1}), xml);
    EXPECT_FLOAT_EQ(build(rect)->surface_area(), 24.f);
    EXPECT_FLOAT_EQ(build(Properties("cube", xml))->surface_area(), 24.f);
    EXPECT_NEAR(build(Properties("disk", xml))->surface_area(), Pi, 1e-3f); // 256-gon: relative error 1e-4

    const std::string mesh = PENUMBRA_SHARED_DIR "/mitsuba-data/common/meshes/matpreview.serialized";
    if (!fs::exists(mesh)) GTEST_SKIP() << "Mitsuba test meshes not present";
    Properties ser("serialized", xml);
    ser.set("filename", mesh, xml);
    ser.set("shape_index", int64_t(1), xml);
    EXPECT_GT(build(ser)->mesh.face_count(), 0u);
}

TEST(ShapeFactory, ErrorsNameTheLocationAndTheProblem) {
    EXPECT_NE(error_of([] {
                  build(Properties("sdfgrid", xml));
              }).find("scene.xml:7: unsupported shape plugin 'sdfgrid' (penumbra intersects triangle meshes"),
              std::string::npos);

    Properties missing("ply", xml);
    missing.set("filename", std::string("nope.ply"), SourceLocation{"scene.xml", 9});
    std::string msg = error_of([&] { build(missing); });
    EXPECT_NE(msg.find("scene.xml:9"), std::string::npos) << msg;
    EXPECT_NE(msg.find("nope.ply"), std::string::npos) << msg;

    write("broken.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n");
    Properties broken("ply", xml);
    broken.set("filename", std::string("broken.ply"), SourceLocation{"scene.xml", 11});
    msg = error_of([&] { build(broken); });
    EXPECT_NE(msg.find("scene.xml:11"), std::string::npos) << msg;
    EXPECT_NE(msg.find("broken.ply"), std::string::npos) << msg;
    EXPECT_NE(msg.find("x, y, z"), std::string::npos) << msg;

    Properties two_bsdfs("cube", xml);
    two_bsdfs.add_object("", make_bsdf(Properties("diffuse", xml), context()), xml);
    two_bsdfs.add_object("", make_bsdf(Properties("diffuse", xml), context()),
                         SourceLocation{"scene.xml", 20});
    msg = error_of([&] { build(two_bsdfs); });
    EXPECT_NE(msg.find("more than one BSDF"), std::string::npos) << msg;

    Properties bad_radius("sphere", xml);
    bad_radius.set("radius", -1.0, SourceLocation{"scene.xml", 30});
    msg = error_of([&] { build(bad_radius); });
    EXPECT_NE(msg.find("scene.xml:30"), std::string::npos) << msg;

    Properties unknown("rectangle", xml);
    unknown.set("face_normals", true, xml); // Mitsuba's rectangle has no such parameter
    EXPECT_NE(error_of([&] { build(unknown); }).find("face_normals"), std::string::npos);
}

TEST(ShapeFactory, AreaEmitterIsAttached) {
    Properties light("area", xml);
    light.set("radiance", ColorValue{Color3f(1.f, 2.f, 3.f)}, xml);
    Properties props("rectangle", xml);
    props.add_object("", make_emitter(light, context()), xml);
    const auto shape = build(props);
    ASSERT_TRUE(shape->emitter);
    EXPECT_EQ(shape->emitter->shape(), shape.get());
}
