// The motion X(p, θ) of points inside participating media (paper 001 §6.1–6.2, diff/volume_motion.h) and its
// tetrahedral meshes (scene/tet_mesh.h): TetGen keeps the input surface and fills its volume exactly; X
// carries the media with the surfaces that bound them (the interior of a moving shape, and a shell around a
// moving shape inside a medium) and is the identity elsewhere; J's derivative is the divergence of dX/dθ; the
// `deform` motion's tape derivative matches finite differences of displace().
#include "core/var.h"
#include "diff/vertex_normals.h"
#include "diff/material_form.h"
#include "diff/parameters.h"
#include "diff/volume_motion.h"
#include "mesh_test_util.h"
#include "scene/mesh.h"
#include "scene/scene.h"
#include "scene/tet_mesh.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// The volume enclosed by a closed, outward-oriented mesh (divergence theorem: Σ p0 · (p1 × p2) / 6).
double enclosed_volume(const TriangleMesh& m) {
    double v = 0.0;
    for (size_t t = 0; t < m.indices.size(); t += 3)
        v += dot(Vec3d(m.positions[m.indices[t]]),
                 cross(Vec3d(m.positions[m.indices[t + 1]]), Vec3d(m.positions[m.indices[t + 2]]))) /
             6.0;
    return v;
}

void write_obj(const std::string& path, const TriangleMesh& m) {
    std::ofstream out(path);
    for (const Vec3f& p : m.positions)
        out << "v " << p.x << " " << p.y << " " << p.z << "\n";
    for (size_t t = 0; t < m.indices.size(); t += 3)
        out << "f " << m.indices[t] + 1 << " " << m.indices[t + 1] + 1 << " " << m.indices[t + 2] + 1 << "\n";
}

// d/dt of x along the enabled direction (the tape's forward mode).
Vec3d tangent(const Vec3<Var>& x, const Parameters& params) {
    std::vector<float> t;
    Tape::current().forward(tape_direction(params).data(), t);
    const auto at = [&](const Var& v) { return v.id < 0 ? 0.0 : double(t[size_t(v.id)]); };
    return Vec3d(at(x.x), at(x.y), at(x.z));
}
double tangent(const Var& x, const Parameters& params) {
    return tangent(Vec3<Var>(x, Var(0.f), Var(0.f)), params).x;
}

// A blob (a coarse sphere mesh, radius 0.5, at `center`) inside a fog box [-3, 3]³ with a floor at y = -1.5.
// With `fog_inside` the blob is a null-bounded pocket of its own medium; otherwise an opaque shape in the
// fog.
std::string scene_xml(const std::string& blob_obj, bool fog_inside, const Vec3f& center = Vec3f(0.f)) {
    const std::string inside = fog_inside ? R"(<bsdf type="null"/><medium type="homogeneous" name="interior">
            <float name="sigma_t" value="2"/></medium><ref name="exterior" id="fog"/>)"
                                          : R"(<bsdf type="diffuse"/>)";
    return scene(R"(<medium type="homogeneous" id="fog"><float name="sigma_t" value="0.3"/></medium>
      <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,8" target="0,0,0" up="0,1,0"/>
        </transform><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
      </sensor>
      <shape type="cube" id="box"><transform name="to_world"><scale value="3"/></transform><bsdf type="null"/>
        <ref name="interior" id="fog"/></shape>
      <shape type="rectangle" id="floor"><transform name="to_world"><scale value="2.5"/><rotate x="1" angle="-90"/>
        <translate value="0,-1.5,0"/></transform><bsdf type="diffuse"/><ref name="exterior" id="fog"/>
        <ref name="interior" id="fog"/></shape>
      <shape type="obj" id="blob"><string name="filename" value=")" +
                 blob_obj + R"("/><transform name="to_world"><translate value=")" + std::to_string(center.x) +
                 "," + std::to_string(center.y) + "," + std::to_string(center.z) + R"("/></transform>)" +
                 inside + "</shape>");
}

struct BlobScene {
    TempDir dir;
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Parameters> params;
    const Shape* blob = nullptr;
    const Medium* fog = nullptr;

    BlobScene(bool fog_inside, const std::string& param, const Vec3f& center = Vec3f(0.f),
              const TriangleMesh& mesh = make_sphere_mesh(Vec3f(0.f), 0.5f, 8, 16)) {
        const std::string obj = dir.str() + "/blob.obj";
        write_obj(obj, mesh);
        scene = load_scene_string(scene_xml(obj, fog_inside, center), dir.str());
        params = std::make_unique<Parameters>(*scene);
        params->enable({parse_param_selection(param)});
        for (const auto& s : scene->shapes)
            if (s->id == "blob")
                blob = s.get();
            else if (s->id == "box")
                fog = s->interior.get();
    }
};

// X at the blob's vertices and at points on its triangles moves as the blob's surface does (MovedVertices).
void expect_follows_surface(const BlobScene& s, const VolumeMotion& motion, const Medium* medium) {
    const MovedVertices moved{*s.blob, s.params->motions(s.blob)};
    const TriangleMesh& m = s.blob->mesh;
    for (size_t t = 0; t < m.indices.size(); t += 3 * 5) {
        Tape::current().clear();
        const uint32_t* i = &m.indices[t];
        const Vec3f b(0.2f, 0.3f, 0.5f);
        const Vec3f p = m.positions[i[0]] * b.x + m.positions[i[1]] * b.y + m.positions[i[2]] * b.z;
        const Vec3d expected = tangent(moved.position(i[0]), *s.params) * double(b.x) +
                               tangent(moved.position(i[1]), *s.params) * double(b.y) +
                               tangent(moved.position(i[2]), *s.params) * double(b.z);
        const Vec3d got = tangent(motion.position(p, medium, nullptr), *s.params);
        ASSERT_LT(norm(got - expected), 1e-3 * std::max(1.0, norm(expected))) << "triangle " << t / 3;
        const Vec3d vertex = tangent(motion.position(m.positions[i[0]], medium, nullptr), *s.params);
        ASSERT_LT(norm(vertex - tangent(moved.position(i[0]), *s.params)), 1e-3) << "vertex " << i[0];
    }
}

} // namespace

TEST(TetMesh, FillsAClosedMeshAndKeepsItsVertices) {
    const TriangleMesh sphere = make_sphere_mesh(Vec3f(0.1f, -0.2f, 0.3f), 1.f, 32, 64);
    const auto start = std::chrono::steady_clock::now();
    const TetMesh mesh = tetrahedralize(sphere.positions, sphere.indices, "sphere");
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    double volume = 0.0;
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
        ASSERT_GT(mesh.volume(t), 0.0);
        volume += mesh.volume(t);
    }
    EXPECT_NEAR(volume, enclosed_volume(sphere), 1e-5 * volume);
    for (size_t i = 0; i < sphere.positions.size(); ++i)
        ASSERT_EQ(mesh.vertices[mesh.input_vertex[i]], sphere.positions[i]) << "input vertex " << i;
    ASSERT_LE(mesh.surface_vertex_count, sphere.positions.size());
    // Point location: barycentrics reproduce the point; points outside are not found.
    const TetLocator locator(mesh);
    const auto located = std::chrono::steady_clock::now();
    int found = 0, queries = 0;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 20; ++j)
            for (int k = 0; k < 20; ++k) {
                const Vec3f p =
                    Vec3f(0.1f, -0.2f, 0.3f) + Vec3f(float(i), float(j), float(k)) * 0.1f - Vec3f(0.95f);
                const bool inside = norm(p - Vec3f(0.1f, -0.2f, 0.3f)) < 0.98f;
                const bool outside = norm(p - Vec3f(0.1f, -0.2f, 0.3f)) > 1.0f;
                const auto at = locator.locate(p);
                ++queries;
                if (inside) {
                    ASSERT_TRUE(at.has_value()) << p;
                    Vec3f q(0.f);
                    for (int v = 0; v < 4; ++v)
                        q += mesh.vertices[mesh.tets[at->tet][v]] * at->bary[v];
                    ASSERT_LT(norm(q - p), 1e-5f);
                    ++found;
                }
                if (outside) {
                    ASSERT_FALSE(at.has_value()) << p;
                }
            }
    const double locate_us =
        1e6 * std::chrono::duration<double>(std::chrono::steady_clock::now() - located).count() / queries;
    std::printf("  %zu triangles -> %zu tets, %zu Steiner points in %.3f s; point location %.2f us\n",
                sphere.indices.size() / 3, mesh.tets.size(), mesh.vertices.size() - mesh.surface_vertex_count,
                seconds, locate_us);
    EXPECT_GT(found, 3000);
}

TEST(TetMesh, SelfIntersectingInputIsAnErrorNamingTheShape) {
    TriangleMesh a = make_sphere_mesh(Vec3f(0.f), 1.f, 8, 16),
                 b = make_sphere_mesh(Vec3f(0.5f, 0.f, 0.f), 1.f, 8, 16);
    const uint32_t offset = uint32_t(a.positions.size());
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    for (uint32_t i : b.indices)
        a.indices.push_back(i + offset);
    try {
        tetrahedralize(a.positions, a.indices, "shape 'twins'");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("shape 'twins'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("intersect"), std::string::npos) << e.what();
    }
}

TEST(VolumeMotion, IdentityWithoutMovingShapesInMedia) {
    BlobScene s(false, "floor.bsdf.reflectance.value");
    EXPECT_TRUE(VolumeMotion(*s.scene, *s.params).identity());
    s.params->enable({parse_param_selection("blob.translate=0,1,0")});
    EXPECT_FALSE(VolumeMotion(*s.scene, *s.params).identity());
}

class InteriorAndShell : public ::testing::TestWithParam<std::tuple<bool, const char*>> {};

// Both cases, every motion kind: the medium next to the surface moves with it (assumption A.4).
TEST_P(InteriorAndShell, MediumFollowsTheSurface) {
    const auto [fog_inside, param] = GetParam();
    BlobScene s(fog_inside, param);
    const VolumeMotion motion(*s.scene, *s.params);
    ASSERT_FALSE(motion.identity());
    expect_follows_surface(s, motion, fog_inside ? s.blob->interior.get() : s.fog);
    if (fog_inside) return;
    // The shell: the identity beyond its box (at most twice the blob's bounding box), and in other media.
    EXPECT_EQ(norm(tangent(motion.position(Vec3f(0.f, 1.3f, 0.f), s.fog, nullptr), *s.params)), 0.0);
    EXPECT_EQ(norm(tangent(motion.position(Vec3f(1.2f, -1.2f, 0.f), s.fog, nullptr), *s.params)), 0.0);
    EXPECT_EQ(norm(tangent(motion.position(Vec3f(0.6f, 0.f, 0.f), nullptr, nullptr), *s.params)), 0.0);
    // Inside the box, between the blob and the box: a blend (nonzero, smaller than on the surface).
    const double between = norm(tangent(motion.position(Vec3f(0.f, 0.f, 0.75f), s.fog, nullptr), *s.params));
    EXPECT_GT(between, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Motions, InteriorAndShell,
                         ::testing::Combine(::testing::Bool(),
                                            ::testing::Values("blob.translate=0.3,1,0", "blob.rotate=1,1,0",
                                                              "blob.scale", "blob.deform=0,1,0.5",
                                                              "blob.deform@0.3,0.2,0=1,0,0",
                                                              "blob.vertex_positions=0.2,1,0")));

// An open mesh (a thin sheet, like a leaf) moves the medium around it on both sides; it has no interior.
TEST(VolumeMotion, SheetInAMedium) {
    TriangleMesh sheet = make_rectangle_mesh();
    for (Vec3f& p : sheet.positions)
        p = Vec3f(0.5f * p.x, 0.1f * p.x + 0.2f * p.y, 0.4f * p.y);
    for (const char* param : {"blob.rotate=0,0,1", "blob.deform=0,1,0"}) {
        BlobScene s(false, param, Vec3f(0.f), sheet);
        const VolumeMotion motion(*s.scene, *s.params);
        expect_follows_surface(s, motion, s.fog);
        EXPECT_EQ(norm(tangent(motion.position(Vec3f(0.f, 1.3f, 0.f), s.fog, nullptr), *s.params)), 0.0);
    }
    const std::string error = error_of([&] {
        BlobScene s(true, "blob.deform", Vec3f(0.f), sheet);
        VolumeMotion m(*s.scene, *s.params);
    });
    EXPECT_NE(error.find("shape 'blob' is not closed"), std::string::npos) << error;
}

// J = dV(x)/dV(p): scaling by 1 + θ multiplies volumes by (1 + θ)³, so dJ/dθ = 3; a deformation's dJ/dθ is
// the divergence of its field, d · ∇φ, up to the piecewise-linear interpolation's error on the tets.
TEST(VolumeMotion, JacobianDerivativeIsTheDivergence) {
    {
        BlobScene s(true, "blob.scale");
        const VolumeMotion motion(*s.scene, *s.params);
        Var j;
        motion.position(Vec3f(0.1f, 0.05f, 0.f), s.blob->interior.get(), &j);
        EXPECT_FLOAT_EQ(j.v, 1.f);
        EXPECT_NEAR(tangent(j, *s.params), 3.0, 1e-6);
    }
    BlobScene s(true, "blob.deform@0.2,0,0=0.5,1,0");
    const VolumeMotion motion(*s.scene, *s.params);
    const Motion& m = s.params->motions(s.blob).at(0);
    double worst = 0.0, largest = 0.0;
    for (int i = 0; i < 40; ++i) {
        Tape::current().clear();
        const float a = 0.7f * float(i), r = 0.1f + 0.0075f * float(i);
        const Vec3f p(r * std::cos(a), r * std::sin(a), 0.1f * std::sin(3.f * a));
        Var j;
        const Vec3<Var> x = motion.position(p, s.blob->interior.get(), &j);
        const double div = double(dot(m.vector, deform_weight_gradient(m, p)));
        worst = std::max(worst, std::abs(tangent(j, *s.params) - div));
        largest = std::max(largest, std::abs(div));
        // Inside, X is the field interpolated on the tets: close to p + θ d φ(p).
        ASSERT_LT(norm(tangent(x, *s.params) - Vec3d(m.vector * deform_weight(m, p))), 0.02) << p;
    }
    std::printf("  deform: max |dJ/dθ - div| = %.4f (max |div| = %.3f)\n", worst, largest);
    EXPECT_LT(worst, 0.25 * largest);
}

// Translating every vertex by vertex_positions translates the interior medium: dX = d, dJ = 0 (the
// interpolation weights sum to 1 inside).
TEST(VolumeMotion, VertexPositionsMoveTheInterior) {
    BlobScene s(true, "blob.vertex_positions=0,1,0");
    const VolumeMotion motion(*s.scene, *s.params);
    expect_follows_surface(s, motion, s.blob->interior.get());
    for (const Vec3f& p : {Vec3f(0.f), Vec3f(0.2f, 0.1f, -0.1f), Vec3f(-0.3f, 0.f, 0.2f)}) {
        Var j;
        const Vec3d dx = tangent(motion.position(p, s.blob->interior.get(), &j), *s.params);
        EXPECT_LT(norm(dx - Vec3d(0, 1, 0)), 1e-4) << p;
        EXPECT_NEAR(tangent(j, *s.params), 0.0, 1e-4) << p;
    }
}

// A shape that touches another leaves no room for a shell: a clear error.
TEST(VolumeMotion, ShellThatCannotFitIsAnError) {
    BlobScene s(false, "blob.translate", Vec3f(0.f, -1.2f, 0.f));
    try {
        VolumeMotion motion(*s.scene, *s.params);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("shape 'blob' touches another shape (shape 'floor')"),
                  std::string::npos)
            << e.what();
    }
    // Every vertex_positions enabled (reverse mode): reported, not fatal.
    s.params->enable_all_data();
    const VolumeMotion all(*s.scene, *s.params);
    std::string omitted;
    for (const std::string& why : all.omitted())
        omitted += why + "\n";
    EXPECT_NE(omitted.find("shape 'blob' touches another shape"), std::string::npos) << omitted;
    EXPECT_NE(omitted.find("shape 'box' moves its interior medium"), std::string::npos) << omitted;
}

// Moving a medium's container with shapes inside: refused (they bound the medium but would not move).
TEST(VolumeMotion, ContainerWithContentsIsAnError) {
    BlobScene s(false, "box.translate");
    const std::string error = error_of([&] { VolumeMotion m(*s.scene, *s.params); });
    EXPECT_NE(error.find("shape 'box' moves its interior medium, which holds shape '"), std::string::npos)
        << error;
}

// displace() moves the mesh exactly (x + θ d φ(x)); its central differences match the tape's derivative of
// positions and (normalized) normals.
// Two selections are two control variables, both moved by the direction (1, 1).
TEST(DeformMotion, DisplaceMatchesTheTape) {
    BlobScene s(false, "blob.deform@0.1,0.2,0=0.3,1,-0.2");
    s.params->enable({parse_param_selection("blob.deform@0.1,0.2,0=0.3,1,-0.2"),
                      parse_param_selection("blob.deform@-0.3,0,0.2=1,0,0")});
    ASSERT_EQ(s.params->dimension(), 2);
    Shape& blob = const_cast<Shape&>(*s.blob);
    ASSERT_FALSE(blob.mesh.normals.empty());
    const MovedVertices moved{blob, s.params->motions(&blob)};
    std::vector<Vec3d> dx, dn;
    for (uint32_t v = 0; v < blob.mesh.positions.size(); ++v) {
        Tape::current().clear();
        dx.push_back(tangent(moved.position(v), *s.params));
        // d/dθ normalize(n) = (I - n nᵀ) dn/dθ.
        const Vec3d n(blob.mesh.normals[v]), d = tangent(moved.normal(v), *s.params);
        dn.push_back(d - n * dot(n, d));
    }
    const double h = 1e-2;
    s.params->displace(*s.scene, h);
    const std::vector<Vec3f> xp = blob.mesh.positions, np = blob.mesh.normals;
    s.params->displace(*s.scene, -h);
    const std::vector<Vec3f> xm = blob.mesh.positions, nm = blob.mesh.normals;
    s.params->displace(*s.scene, 0.0);
    for (size_t v = 0; v < xp.size(); ++v) {
        ASSERT_LT(norm((Vec3d(xp[v]) - Vec3d(xm[v])) / (2 * h) - dx[v]), 1e-3) << "vertex " << v;
        ASSERT_LT(norm((Vec3d(np[v]) - Vec3d(nm[v])) / (2 * h) - dn[v]), 2e-3) << "normal " << v;
    }
    const std::string listed = s.params->find("blob.deform").name;
    EXPECT_EQ(listed, "blob.deform");
}

// An instance's deform moves all its flattened shapes by one world-space field (center and radius from their
// common bounding box).
TEST(DeformMotion, InstanceDeformsAllItsShapes) {
    auto scene = load_scene_string(test::scene(R"(
    <shape type="shapegroup" id="pair">
        <shape type="rectangle" id="a"/>
        <shape type="rectangle"><transform name="to_world"><translate x="4"/></transform></shape>
    </shape>
    <shape type="instance" id="two"><ref id="pair"/><transform name="to_world"><translate y="1"/></transform></shape>)"));
    Parameters params(*scene);
    params.enable({parse_param_selection("two.deform=0,0,1")});
    for (const auto& shape : scene->shapes) {
        ASSERT_EQ(params.motions(shape.get()).size(), 1u);
        EXPECT_EQ(params.motions(shape.get())[0].center, Vec3f(2.f, 1.f, 0.f));
        EXPECT_FLOAT_EQ(params.motions(shape.get())[0].radius, 0.25f * std::sqrt(36.f + 4.f));
    }
    const Motion m = params.motions(scene->shapes[1].get())[0];
    const Vec3f p = scene->shapes[1]->mesh.positions[1];
    params.displace(*scene, 0.5);
    EXPECT_NEAR(scene->shapes[1]->mesh.positions[1].z, 0.5f * deform_weight(m, p), 1e-6f);
    params.displace(*scene, 0.0);
    EXPECT_EQ(scene->shapes[1]->mesh.positions[1], p);
}

// J is the Jacobian of X: dJ/dθ equals the divergence of dX/dθ (central differences of the tape's tangents,
// at points whose stencil stays in one tet: nearly all of them, the rest crossing a face of the
// piecewise-linear field), in the interior and in the shell.
TEST(VolumeMotion, JacobianIsConsistentWithX) {
    for (const auto& [fog_inside, param] :
         {std::pair{true, "blob.deform=0.3,1,0"}, std::pair{true, "blob.vertex_positions"},
          std::pair{false, "blob.translate=1,0.5,0"}, std::pair{false, "blob.deform=0,1,0"}}) {
        BlobScene s(fog_inside, param);
        // vertex_positions: a non-uniform direction (a uniform one translates: dJ/dθ = 0).
        if (s.params->dimension() > 1) {
            std::vector<float> direction(size_t(s.params->dimension()));
            for (size_t i = 0; i < direction.size(); ++i)
                direction[i] = std::sin(1.7f * float(i));
            s.params->set_direction(direction);
        }
        const VolumeMotion motion(*s.scene, *s.params);
        const Medium* medium = fog_inside ? s.blob->interior.get() : s.fog;
        int consistent = 0, n = 0;
        double largest = 0.0;
        for (int i = 0; i < 60; ++i, ++n) {
            Tape::current().clear();
            const float a = 0.9f * float(i),
                        r = fog_inside ? 0.05f + 0.006f * float(i) : 0.58f + 0.006f * float(i);
            const Vec3f p(r * std::cos(a) * std::cos(0.3f * a), r * std::sin(a) * std::cos(0.3f * a),
                          r * std::sin(0.3f * a));
            Var j;
            motion.position(p, medium, &j);
            const double dj = tangent(j, *s.params);
            largest = std::max(largest, std::abs(dj));
            const float h = 1e-4f;
            double div = 0.0;
            for (int k = 0; k < 3; ++k) {
                Vec3f e(0.f);
                e[k] = h;
                div += (tangent(motion.position(p + e, medium, nullptr), *s.params)[k] -
                        tangent(motion.position(p - e, medium, nullptr), *s.params)[k]) /
                       (2.0 * h);
            }
            consistent += std::abs(dj - div) < 2e-2 * std::max(1.0, std::abs(dj));
        }
        std::printf("  %s: %d of %d consistent (largest |dJ/dθ| %.3f)\n", param, consistent, n, largest);
        EXPECT_GT(largest, 0.05);
        EXPECT_GE(consistent, n * 9 / 10) << param << (fog_inside ? " (interior)" : " (shell)");
    }
}

// A point light translated inside the fog carries the medium near it (the shell around an octahedron at the
// light, radius a quarter of its distance to the floor): X moves with the light there, is the identity beyond
// the shell's box and in other media, and J's derivative stays bounded. Rotating the light moves no medium.
TEST(VolumeMotion, TranslatedPointLightCarriesTheMediumNearIt) {
    const Vec3f light(0.3f, 0.f, 0.2f); // 1.5 above the floor: the octahedron's radius is 0.375
    const auto load = [&](const std::string& param) {
        auto scene = load_scene_string(
            test::scene(R"(<medium type="homogeneous" id="fog"><float name="sigma_t" value="0.3"/></medium>
      <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,8" target="0,0,0" up="0,1,0"/>
        </transform><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
      </sensor>
      <shape type="cube" id="box"><transform name="to_world"><scale value="3"/></transform><bsdf type="null"/>
        <ref name="interior" id="fog"/></shape>
      <shape type="rectangle" id="floor"><transform name="to_world"><scale value="2.5"/><rotate x="1" angle="-90"/>
        <translate value="0,-1.5,0"/></transform><bsdf type="diffuse"/></shape>
      <emitter type="point" id="bulb"><point name="position" value="0.3,0,0.2"/>
        <rgb name="intensity" value="1"/></emitter>)"),
            ".");
        auto params = std::make_unique<Parameters>(*scene);
        params->enable({parse_param_selection(param)});
        return std::pair{std::move(scene), std::move(params)};
    };
    EXPECT_TRUE(VolumeMotion(*load("bulb.rotate=0,1,0").first, *load("bulb.rotate=0,1,0").second).identity());
    const auto [scene, params] = load("bulb.translate=1,0.5,0");
    const VolumeMotion motion(*scene, *params);
    ASSERT_FALSE(motion.identity());
    const Medium* fog = scene->shapes[0]->interior.get();
    const Vec3d d(1, 0.5, 0);
    for (const Vec3f& offset : {Vec3f(0.f), Vec3f(0.1f, 0.f, 0.f), Vec3f(-0.05f, 0.08f, 0.1f)}) {
        Tape::current().clear();
        Var j;
        const Vec3d dx = tangent(motion.position(light + offset, fog, &j), *params);
        EXPECT_LT(norm(dx - d), 1e-3) << offset;
        EXPECT_NEAR(tangent(j, *params), 0.0, 1e-3) << offset;
    }
    for (const Vec3f& offset : {Vec3f(0.f, 0.f, 1.f), Vec3f(-0.9f, 0.3f, 0.f), Vec3f(0.f, -1.f, 0.f)})
        EXPECT_EQ(norm(tangent(motion.position(light + offset, fog, nullptr), *params)), 0.0) << offset;
    EXPECT_EQ(norm(tangent(motion.position(light, nullptr, nullptr), *params)), 0.0);
    // Between the octahedron and the box: a blend, and J's derivative is the field's divergence, of the order
    // of the light's speed over the shell's width.
    double largest = 0.0, blend = 0.0;
    for (int i = 0; i < 60; ++i) {
        Tape::current().clear();
        const float a = 0.9f * float(i), r = 0.4f + 0.005f * float(i);
        const Vec3f p = light + Vec3f(r * std::cos(a) * std::cos(0.3f * a),
                                      r * std::sin(a) * std::cos(0.3f * a), r * std::sin(0.3f * a));
        Var j;
        blend = std::max(blend, norm(tangent(motion.position(p, fog, &j), *params)));
        largest = std::max(largest, std::abs(tangent(j, *params)));
    }
    std::printf("  light shell: largest |dX/dθ| %.3f, largest |dJ/dθ| %.3f\n", blend, largest);
    EXPECT_GT(blend, 0.05);
    EXPECT_LT(blend, norm(d));
    EXPECT_LT(largest, 4.0 * norm(d) / 0.375);
}
