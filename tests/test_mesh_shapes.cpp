// Shapes on triangle meshes: tessellated primitives, area sampling, surface interactions, finalize() errors.
#include "core/rng.h"
#include "scene/shape.h"
#include "scene/shape_interaction.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

Shape make(TriangleMesh mesh, const Transform& to_world = Transform()) {
    Shape s;
    s.plugin = "test";
    s.mesh = std::move(mesh);
    s.mesh.apply_transform(to_world);
    s.finalize();
    return s;
}

struct Hit {
    uint32_t prim = 0;
    float t = Infinity, b1 = 0, b2 = 0;
};

// Brute-force Moller-Trumbore over all triangles (test oracle independent of the shape code).
Hit intersect(const TriangleMesh& m, const Ray& ray) {
    Hit best;
    for (uint32_t f = 0; f < m.face_count(); ++f) {
        const Vec3f p0 = m.positions[m.indices[3 * f]], p1 = m.positions[m.indices[3 * f + 1]],
                    p2 = m.positions[m.indices[3 * f + 2]];
        const Vec3f e1 = p1 - p0, e2 = p2 - p0, q = cross(ray.d, e2);
        const float det = dot(e1, q);
        if (std::abs(det) < 1e-12f) continue;
        const Vec3f s = ray.o - p0;
        const float b1 = dot(s, q) / det;
        const Vec3f r = cross(s, e1);
        const float b2 = dot(ray.d, r) / det, t = dot(e2, r) / det;
        if (b1 < 0 || b2 < 0 || b1 + b2 > 1 || t <= 0 || t >= best.t) continue;
        best = {f, t, b1, b2};
    }
    return best;
}

void expect_near(const Vec3f& a, const Vec3f& b, float tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

} // namespace

TEST(MeshPrimitives, RectangleAndCubeAreasAreExact) {
    EXPECT_FLOAT_EQ(make(make_rectangle_mesh()).surface_area(), 4.f);
    const Shape cube = make(make_cube_mesh());
    EXPECT_FLOAT_EQ(cube.surface_area(), 24.f);
    ASSERT_EQ(cube.mesh.vertex_count(), 24u);
    // Outward: every face normal points away from the origin and agrees with its vertex normals.
    for (uint32_t f = 0; f < cube.mesh.face_count(); ++f) {
        const Vec3f n = cube.face_normal(f);
        const Vec3f c = cube.mesh.positions[cube.mesh.indices[3 * f]];
        EXPECT_GT(dot(n, c), 0.f);
        expect_near(cube.mesh.normals[cube.mesh.indices[3 * f]], n, 1e-6f);
    }
}

TEST(MeshPrimitives, CubeUvLayoutMatchesMitsuba) {
    // Mitsuba 3's cube: the -y face has uv = ((z+1)/2, (x+1)/2), the +z face uv = ((y+1)/2, (x+1)/2).
    const TriangleMesh m = make_cube_mesh();
    for (size_t i = 0; i < m.vertex_count(); ++i) {
        const Vec3f p = m.positions[i], n = m.normals[i];
        if (n.y < -0.5f) {
            EXPECT_FLOAT_EQ(m.uvs[i].x, 0.5f * (p.z + 1.f));
            EXPECT_FLOAT_EQ(m.uvs[i].y, 0.5f * (p.x + 1.f));
        }
        if (n.z > 0.5f) {
            EXPECT_FLOAT_EQ(m.uvs[i].x, 0.5f * (p.y + 1.f));
            EXPECT_FLOAT_EQ(m.uvs[i].y, 0.5f * (p.x + 1.f));
        }
    }
}

TEST(MeshPrimitives, DiskAreaWithinTessellationError) {
    const int n = 256;
    const float area = make(make_disk_mesh(n)).surface_area();
    // Inscribed n-gon: area = (n/2) sin(2 pi/n) and sin x >= x - x^3/6, so pi (1 - (2 pi/n)^2/6) <= area <=
    // pi; 1e-5 relative slack covers float summation.
    const float x = 2.f * Pi / n;
    EXPECT_LE(area, Pi * (1.f + 1e-5f));
    EXPECT_GE(area, Pi * (1.f - x * x / 6.f - 1e-5f));
}

TEST(MeshPrimitives, SphereAreaWithinTessellationError) {
    const int rings = 64, segments = 128;
    const float r = 2.f;
    const Shape s = make(make_sphere_mesh(Vec3f(1, 2, 3), r, rings, segments));
    // Inscribed polyhedron: area <= 4 pi r^2. Central projection of a facet at distance h from the center
    // onto the sphere magnifies area by at most (r/h)^2, and h >= r cos(g) with g the largest angular size of
    // a grid cell, g <= sqrt(dtheta^2 + dphi^2). Hence area >= 4 pi r^2 cos^2(g); 1e-5 slack for float sums.
    const float g = std::hypot(Pi / rings, 2.f * Pi / segments);
    const float exact = 4.f * Pi * r * r;
    EXPECT_LE(s.surface_area(), exact * (1.f + 1e-5f));
    EXPECT_GE(s.surface_area(), exact * (std::cos(g) * std::cos(g) - 1e-5f));
    EXPECT_EQ(s.degenerate_count(), 0u);
    for (uint32_t f = 0; f < s.mesh.face_count(); f += 97)
        EXPECT_GT(dot(s.face_normal(f), s.mesh.positions[s.mesh.indices[3 * f]] - Vec3f(1, 2, 3)), 0.f);
}

TEST(MeshShape, SampledPositionsHaveTheAreaWeightedCentroid) {
    // A rectangle scaled to [-2,2]x[-1,1] (area 8, centroid 0), a triangle of area 3 with centroid (32/3, 1,
    // 0) and a degenerate triangle far away that must never be sampled.
    TriangleMesh m = make_rectangle_mesh();
    m.apply_transform(Transform::scale({2, 1, 1}));
    m.uvs.clear();
    for (const Vec3f& p : {Vec3f(10, 0, 0), Vec3f(12, 0, 0), Vec3f(10, 3, 0), Vec3f(100, 0, 0),
                           Vec3f(101, 0, 0), Vec3f(102, 0, 0)})
        m.positions.push_back(p);
    m.indices.insert(m.indices.end(), {4, 5, 6, 7, 8, 9});
    const Shape s = make(m);
    EXPECT_EQ(s.degenerate_count(), 1u);
    EXPECT_FLOAT_EQ(s.surface_area(), 11.f);

    PCG32 rng;
    const int n = 200000;
    double sum[2] = {0, 0}, sum2[2] = {0, 0};
    for (int i = 0; i < n; ++i) {
        const float u = rng.next_float();
        const PositionSample3f ps = s.sample_position(Vec2f(u, rng.next_float()));
        ASSERT_LT(ps.p.x, 50.f);
        ASSERT_FLOAT_EQ(ps.pdf, 1.f / 11.f);
        ASSERT_FLOAT_EQ(ps.n.z, 1.f);
        for (int k = 0; k < 2; ++k) {
            sum[k] += ps.p[k];
            sum2[k] += double(ps.p[k]) * ps.p[k];
        }
    }
    const double expected[2] = {32.0 / 11.0, 3.0 / 11.0};
    for (int k = 0; k < 2; ++k) {
        const double mean = sum[k] / n, var = sum2[k] / n - mean * mean;
        // 5 standard errors of the sample mean: fails with probability ~6e-7 if the sampler is right.
        EXPECT_NEAR(mean, expected[k], 5.0 * std::sqrt(var / n)) << "coordinate " << k;
    }
}

TEST(MeshShape, InteractionOnTransformedRectangle) {
    const Transform to_world =
        Transform::translate({1, 2, 3}) * Transform::rotate({1, 0, 0}, 90.f) * Transform::scale({2, 1, 1});
    const Shape s = make(make_rectangle_mesh(), to_world);
    // Local point (0.5, -0.5, 0) has Mitsuba uv (0.75, 0.25); rotating +z by 90 deg about x gives -y.
    const Vec3f target = to_world.apply_point(Vec3f(0.5f, -0.5f, 0.f));
    const Vec3f n(0, -1, 0);
    const Ray ray(target + n * 5.f, -n);
    const Hit h = intersect(s.mesh, ray);
    ASSERT_TRUE(std::isfinite(h.t));
    const SurfaceInteraction3f si = s.compute_surface_interaction(ray, h.t, h.prim, h.b1, h.b2);
    // Single-precision geometry of magnitude ~5: 1e-5 absolute is a few ulps.
    expect_near(si.p, target, 1e-5f);
    expect_near(si.n, n, 1e-6f);
    expect_near(si.sh_frame.n, n, 1e-6f);
    expect_near(si.sh_frame.s, Vec3f(1, 0, 0), 1e-6f); // along dp/du = to_world(x)
    expect_near(si.sh_frame.t, cross(n, Vec3f(1, 0, 0)), 1e-6f);
    EXPECT_NEAR(si.uv.x, 0.75f, 1e-6f);
    EXPECT_NEAR(si.uv.y, 0.25f, 1e-6f);
    expect_near(si.wi, Vec3f(0, 0, 1), 1e-6f);
    EXPECT_NEAR(si.t, 5.f, 1e-5f);
    EXPECT_EQ(si.shape, &s);
    EXPECT_EQ(si.prim_index, h.prim);
}

TEST(MeshShape, SphereInteractionFollowsMitsubaParameterization) {
    const int rings = 64, segments = 128;
    const Vec3f c(0.5f, -1.f, 2.f);
    const Shape s = make(make_sphere_mesh(c, 1.5f, rings, segments));
    // Interpolated normals, tangents and uvs deviate from the smooth sphere by at most the angular size of a
    // grid cell, g = sqrt(dtheta^2 + dphi^2) ~ 0.055.
    const float g = std::hypot(Pi / rings, 2.f * Pi / segments);
    PCG32 rng;
    for (int i = 0; i < 20; ++i) {
        const float theta = 0.2f + 2.7f * rng.next_float(), phi = 2.f * Pi * rng.next_float();
        const Vec3f d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        const Ray ray(c + d * 4.f, -d);
        const Hit h = intersect(s.mesh, ray);
        ASSERT_TRUE(std::isfinite(h.t));
        const SurfaceInteraction3f si = s.compute_surface_interaction(ray, h.t, h.prim, h.b1, h.b2);
        expect_near(si.sh_frame.n, d, g);
        expect_near(si.sh_frame.s, normalize(Vec3f(-d.y, d.x, 0.f)), 2.f * g);
        EXPECT_GT(dot(si.n, d), std::cos(g));
        EXPECT_NEAR(si.uv.x, phi / (2.f * Pi), 1.f / segments);
        EXPECT_NEAR(si.uv.y, theta / Pi, 1.f / rings);
        EXPECT_GT(si.wi.z, 0.f);
    }
}

TEST(MeshShape, FaceNormalsIgnoreVertexNormals) {
    TriangleMesh m = make_rectangle_mesh();
    m.normals.assign(4, normalize(Vec3f(1, 0, 1)));
    Shape smooth = make(m);
    const Ray ray(Vec3f(0.2f, 0.1f, 1.f), Vec3f(0, 0, -1));
    const Hit h = intersect(smooth.mesh, ray);
    expect_near(smooth.compute_surface_interaction(ray, h.t, h.prim, h.b1, h.b2).sh_frame.n,
                normalize(Vec3f(1, 0, 1)), 1e-6f);
    smooth.face_normals = true;
    smooth.finalize(); // the per-triangle shading data follow the shading mode
    expect_near(smooth.compute_surface_interaction(ray, h.t, h.prim, h.b1, h.b2).sh_frame.n, Vec3f(0, 0, 1),
                1e-6f);
}

// The vertex data as stored, but not the stored mesh's type: surface_interaction() computes every hit.
struct UncachedVertices {
    const TriangleMesh& mesh;
    Vec3f position(uint32_t v) const { return mesh.positions[v]; }
    Vec3f normal(uint32_t v) const { return mesh.normals[v]; }
};

// Hits on the stored mesh use the per-triangle data finalize() keeps (Shape::triangle_shading): the same
// interaction as computing it, bit for bit with flat shading, within rounding where three equal vertex
// normals make the frame constant, and through the per-hit path with varying vertex normals (a sphere).
TEST(MeshShape, CachedTriangleShadingEqualsTheComputedInteraction) {
    TriangleMesh equal = make_rectangle_mesh();
    equal.normals.assign(4, normalize(Vec3f(0.3f, 0.1f, 1)));
    TriangleMesh flat = make_rectangle_mesh();
    flat.normals.clear();
    const Shape shapes[3] = {make(flat, Transform::rotate(Vec3f(1, 2, 3), 40.f)), make(equal),
                             make(make_sphere_mesh(Vec3f(0.5f, 0, 0), 1.f, 16, 32))};
    PCG32 rng(3, 7);
    for (int k = 0; k < 3; ++k) {
        const Shape& s = shapes[k];
        for (int n = 0; n < 200; ++n) {
            const uint32_t prim = uint32_t(rng.next_float() * float(s.mesh.face_count())) % s.mesh.face_count();
            float b1 = rng.next_float(), b2 = rng.next_float();
            if (b1 + b2 > 1.f) b1 = 1.f - b1, b2 = 1.f - b2;
            const Ray ray(Vec3f(0, 0, 5), Vec3f(0, 0, -1));
            const SurfaceInteraction3f cached = s.compute_surface_interaction(ray, 1.f, prim, b1, b2);
            const SurfaceInteraction3f computed =
                surface_interaction<float>(s, prim, Vec2f(b1, b2), UncachedVertices{s.mesh});
            const float tol = k == 0 ? 0.f : 2e-7f;
            expect_near(cached.p, computed.p, tol);
            expect_near(cached.n, computed.n, tol);
            expect_near(cached.sh_frame.s, computed.sh_frame.s, tol);
            expect_near(cached.sh_frame.t, computed.sh_frame.t, tol);
            expect_near(cached.sh_frame.n, computed.sh_frame.n, tol);
            EXPECT_EQ(cached.uv, computed.uv);
        }
    }
}

TEST(MeshShape, FinalizeErrorsNameTheShape) {
    Shape s;
    s.plugin = "ply";
    s.location = {"scene.xml", 12};
    s.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    s.mesh.indices = {0, 1, 2};
    try {
        s.finalize();
        FAIL() << "zero-area mesh accepted";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.xml:12"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("zero surface area"), std::string::npos) << e.what();
    }
    s.mesh.indices = {0, 1, 3};
    try {
        s.finalize();
        FAIL() << "out-of-range index accepted";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("shape 'ply'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("references vertex 3"), std::string::npos) << e.what();
    }
}
