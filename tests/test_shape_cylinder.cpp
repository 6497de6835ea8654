// cylinder: Mitsuba 3's parameterization, its silhouette (2 r h seen from the side), its area and the power
// of a cylinder area emitter.
#include "diff/edges.h"
#include "diff/parameters.h"
#include "diff/psdr/psdr.h"
#include "scene/emitter.h"
#include "scene/factory.h"
#include "scene/shape.h"

#include "diff_check.h"
#include "shape_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

const SourceLocation xml{"scene.xml", 3};

std::shared_ptr<Shape> cylinder(const Vec3f& p0, const Vec3f& p1, float radius, bool flip = false) {
    Properties props("cylinder", xml);
    props.set("p0", p0, xml);
    props.set("p1", p1, xml);
    props.set("radius", double(radius), xml);
    if (flip) props.set("flip_normals", true, xml);
    auto shape = std::dynamic_pointer_cast<Shape>(make_shape(props, LoadContext{}));
    props.check_all_queried("shape");
    return shape;
}

} // namespace

TEST(ShapeCylinder, AreaWithinTessellationError) {
    const auto s = cylinder({1.f, 2.f, 3.f}, {1.f, 2.f + 3.f, 3.f + 4.f}, 0.5f); // axis length 5
    const double exact = 2.0 * Pi * 0.5 * 5.0;
    EXPECT_NEAR(s->surface_area(), exact, 1.1e-4 * exact); // a 128-gon's perimeter: 1 - sin(x)/x, x = pi/128
    EXPECT_LT(s->surface_area(), exact);
}

TEST(ShapeCylinder, ParameterizationFollowsMitsuba) {
    // Default frame: axis +z, u = phi / 2pi from +x toward +y, v = z / length, normal outward.
    const auto s = cylinder({0.f, 0.f, 0.f}, {0.f, 0.f, 2.f}, 0.5f);
    const TriangleMesh& m = s->mesh;
    for (size_t i = 0; i < m.vertex_count(); ++i) {
        const Vec3f p = m.positions[i];
        EXPECT_NEAR(std::hypot(p.x, p.y), 0.5f, 1e-6f);
        EXPECT_NEAR(m.uvs[i].y, p.z / 2.f, 1e-6f);
        const float phi = std::atan2(p.y, p.x);
        const float u = phi < 0.f ? phi / (2.f * Pi) + 1.f : phi / (2.f * Pi);
        if (m.uvs[i].x > 1e-4f && m.uvs[i].x < 1.f - 1e-4f) {
            EXPECT_NEAR(m.uvs[i].x, u, 1e-5f);
        }
        EXPECT_NEAR(dot(m.normals[i], Vec3f(p.x, p.y, 0.f) / 0.5f), 1.f, 1e-5f);
    }
    for (uint32_t f = 0; f < m.face_count(); ++f) {
        const Vec3f c = m.positions[m.indices[3 * f]];
        EXPECT_GT(dot(s->face_normal(f), Vec3f(c.x, c.y, 0.f)), 0.f) << "face " << f << " points inward";
    }
    const auto flipped = cylinder({0.f, 0.f, 0.f}, {0.f, 0.f, 2.f}, 0.5f, true);
    EXPECT_LT(dot(flipped->face_normal(0), flipped->mesh.positions[flipped->mesh.indices[0]]), 0.f);
}

TEST(ShapeCylinder, ZeroLengthAxisAndBadRadiusAreErrors) {
    Properties props("cylinder", xml);
    props.set("p0", Vec3f(1.f), xml);
    props.set("p1", Vec3f(1.f), SourceLocation{"scene.xml", 9});
    try {
        make_shape(props, LoadContext{});
        ADD_FAILURE() << "a zero-length axis was accepted";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.xml:9"), std::string::npos) << e.what();
    }
    Properties radius("cylinder", xml);
    radius.set("radius", 0.0, xml);
    EXPECT_THROW(make_shape(radius, LoadContext{}), LoadError);
}

// Seen from the side (along +y) a cylinder of radius r and height h covers 2 r h, whatever its tilt in the
// image plane. Tolerance: 4 standard errors of the rendered estimate plus the 128-gon's width deficit
// (at most 1 - cos(pi/128) = 3e-4 relative).
TEST(ShapeCylinder, SilhouetteAreaSeenFromTheSide) {
    const auto scene = load_scene_string(test::projected_area_scene(R"(
    <shape type="cylinder">
        <point name="p0" x="-0.5" y="0" z="-1"/> <point name="p1" x="0.3" y="0" z="1.2"/>
        <float name="radius" value="0.4"/> <ref id="black"/>
    </shape>)"));
    const double h = std::hypot(0.8, 2.2), exact = 2.0 * 0.4 * h;
    const test::ProjectedArea a = test::projected_area(*scene, 16, 32);
    RecordProperty("area", std::to_string(a.value) + " +- " + std::to_string(a.stderr_value) + " (exact " +
                               std::to_string(exact) + ")");
    EXPECT_NEAR(a.value, exact, 4.0 * a.stderr_value + 3e-4 * exact) << "stderr " << a.stderr_value;
    EXPECT_LT(a.stderr_value, 0.01 * exact); // the test can resolve a 4% error
}

// Power of a one-sided Lambertian area emitter: pi L A. The light-tracing weight L cos / (pdf_A pdf_dir) of
// every sampled ray equals it (cosine-weighted directions), so its mean over rays estimates the power.
TEST(ShapeCylinder, AreaEmitterPower) {
    const auto scene = load_scene_string(R"(<scene version="3.0.0">
    <shape type="cylinder">
        <float name="radius" value="0.25"/> <point name="p1" x="0" y="0" z="3"/>
        <emitter type="area"><rgb name="radiance" value="2"/></emitter>
    </shape></scene>)");
    ASSERT_EQ(scene->emitters.size(), 1u);
    const Emitter& e = *scene->emitters[0];
    const double exact = Pi * 2.0 * (2.0 * Pi * 0.25 * 3.0);
    EXPECT_NEAR(e.power().x, exact, 1.1e-4 * exact);
    double sum = 0.0;
    const int n = 4096;
    for (int i = 0; i < n; ++i) {
        const float a = (float(i) + 0.5f) / float(n), b = std::fmod(0.618034f * float(i), 1.f);
        auto [ray, w] = e.sample_ray({a, b}, {b, a});
        // Rays leave the outside of the tube: away from the axis.
        EXPECT_GT(dot(ray.d, Vec3f(ray.o.x, ray.o.y, 0.f)), 0.f);
        sum += w.x;
    }
    EXPECT_NEAR(sum / n, exact, 1.1e-4 * exact);
}

// The cylinder is a mesh like the sphere, so its motions are differentiated by the same estimators: a tube
// moving in front of an emitting panel (max_depth 1: the primary boundary term of its silhouette and open
// ends) against central differences (diff_check.h tolerances).
TEST(ShapeCylinder, TranslateDerivativeMatchesFiniteDifferences) {
    const auto scene = load_scene_string(R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="1"/></integrator>
      <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film></sensor>
      <shape type="cylinder" id="tube"><float name="radius" value="0.25"/>
        <point name="p0" x="-0.6" y="-0.2" z="0"/><point name="p1" x="-0.3" y="0.1" z="0.3"/></shape>
      <shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform>
        <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>
    </scene>)");
    Parameters params(*scene);
    params.enable({parse_param_selection("tube.translate=1,0.5,0")});
    PsdrOptions o;
    o.interior.spp = 4;
    o.interior.batches = 16;
    o.interior.seed = 3;
    o.interior.path = path_settings(*scene);
    o.primary_spp = 16;
    o.direct_spp = o.indirect_spp = o.pixel_spp = 0; // max_depth 1: no light paths; the camera does not move
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 256;
    ro.seed = 5;
    const FiniteDifference fd = finite_difference(*scene, params, 2e-3, ro, 16);
    const test::DiffCheck c = test::check_against(d, fd);
    RecordProperty("check", test::describe(c));
    EXPECT_TRUE(c.passes()) << test::describe(c);
}

// The uv seams of the tessellated primitives are welded: their duplicated vertices sit at exactly the same
// positions, so the seam is an interior edge and not a pair of boundary edges (which the boundary estimators
// take for silhouettes wherever they are). Boundary edges remain only where the surface ends.
TEST(ShapeCylinder, SeamsOfTessellatedPrimitivesAreWelded) {
    auto boundary_edges = [](const TriangleMesh& m) {
        int n = 0;
        for (const Edge& e : discontinuity_edges(m))
            n += e.f1 < 0 ? 1 : 0;
        return n;
    };
    EXPECT_EQ(boundary_edges(make_sphere_mesh(Vec3f(0.f), 1.f, 16, 32)), 0);
    EXPECT_EQ(boundary_edges(make_disk_mesh(64)), 64);
    EXPECT_EQ(boundary_edges(cylinder({0.f, 0.f, 0.f}, {1.f, 2.f, 3.f}, 0.5f)->mesh), 2 * 128);
}
