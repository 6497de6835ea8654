// Implicit edges in the boundary test of warped-area sampling (paper 004 §5.5, diff/was/implicit_edges.h): the
// triangle–triangle segments and the broad phase against brute force, a cube sunk halfway into a floor (the
// square intersection curve, B next to it and far from it), the warp at the curve with and without implicit
// edges, and the construction time on the 220k-triangle hedge.
#include "core/rng.h"
#include "diff/vertex_normals.h"
#include "diff/was/auxiliary_rays.h"
#include "mesh_test_util.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

using namespace penumbra;

namespace {

struct Rng {
    PCG32 pcg;
    float next_1d() { return pcg.next_float(); }
    Vec2f next_2d() {
        const float a = pcg.next_float();
        return Vec2f(a, pcg.next_float());
    }
};

// An n × n grid of quads over [−h, h]² at height 0, as OBJ text.
std::string floor_obj(int n, float h) {
    std::ostringstream obj;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            obj << "v " << -h + 2.f * h * float(i) / float(n) << ' ' << -h + 2.f * h * float(j) / float(n)
                << " 0\n";
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
            obj << "f " << a << ' ' << b << ' ' << d << "\nf " << a << ' ' << d << ' ' << c << '\n';
        }
    return obj.str();
}

// The cube [−h, h]³, each face an n × n grid of quads with its own vertices, faces turned outward.
std::string cube_obj(int n, float h) {
    std::ostringstream obj;
    int base = 1;
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.f, 1.f}) {
            // (u, v, normal) axes with u × v = normal · side.
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i <= n; ++i) {
                    float p[3];
                    p[axis] = side * h;
                    p[u] = -h + 2.f * h * float(i) / float(n);
                    p[v] = -h + 2.f * h * float(j) / float(n);
                    obj << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
                }
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
                    if (side > 0.f)
                        obj << "f " << a << ' ' << b << ' ' << d << "\nf " << a << ' ' << d << ' ' << c
                            << '\n';
                    else
                        obj << "f " << a << ' ' << d << ' ' << b << "\nf " << a << ' ' << c << ' ' << d
                            << '\n';
                }
            base += (n + 1) * (n + 1);
        }
    return obj.str();
}

// The cube [−1/2, 1/2]³ (faces 3 × 3) sunk halfway into a 4 × 4 floor (10 × 10): no vertex of either lies
// on the other, so the intersection is the square max(|x|, |y|) = 1/2, z = 0, cut into pieces by the
// triangles it crosses.
constexpr float HalfCube = 0.5f;
struct SunkCube {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Parameters> params;
    std::unique_ptr<MaterialForm> form;
    BoundaryTest with, without;

    explicit SunkCube(const std::string& motion)
        : scene(load()), with(*scene), without(*scene, 0.01f, false) {
        params = std::make_unique<Parameters>(*scene);
        params->enable({parse_param_selection("cube.translate=" + motion)});
        form = std::make_unique<MaterialForm>(*scene, *params, FirstVertex::Auto);
    }
    static std::unique_ptr<Scene> load() {
        static test::ScratchDir dir("penumbra_implicit_");
        const std::string floor = test::write_file(dir.path, "floor.obj", floor_obj(10, 2.f)),
                          cube = test::write_file(dir.path, "cube.obj", cube_obj(3, HalfCube));
        const auto shape = [](const std::string& id, const std::string& file) {
            return "<shape type=\"obj\" id=\"" + id + "\"><string name=\"filename\" value=\"" + file +
                   "\"/><bsdf type=\"diffuse\"/></shape>";
        };
        return load_scene_string("<scene version=\"3.0.0\"><emitter type=\"constant\"/>" +
                                 shape("floor", floor) + shape("cube", cube) + "</scene>");
    }
    const Shape& shape(const std::string& id) const {
        for (const auto& s : scene->shapes)
            if (s->id == id) return *s;
        throw Error("no shape " + id);
    }
};

} // namespace

TEST(WasImplicitEdges, TriangleIntersectionSegment) {
    // A vertical triangle through a horizontal one: the crossing is the vertical triangle's chord at z = 0
    // clipped by the horizontal triangle.
    const Triangle3f flat{Vec3f(-1.f, -1.f, 0.f), Vec3f(1.f, -1.f, 0.f), Vec3f(0.f, 1.f, 0.f)};
    const Triangle3f upright{Vec3f(0.25f, -2.f, -1.f), Vec3f(0.25f, 2.f, -1.f), Vec3f(0.25f, 0.f, 1.f)};
    const auto s = triangle_intersection(flat, upright);
    ASSERT_TRUE(s.has_value());
    // Chord of `upright` at z = 0: y ∈ [−1, 1]; `flat` at x = 1/4 spans y ∈ [−1, 1 − 2 · 1/4] = [−1, 1/2].
    const float y0 = std::min(s->a.y, s->b.y), y1 = std::max(s->a.y, s->b.y);
    EXPECT_NEAR(y0, -1.f, 1e-6f);
    EXPECT_NEAR(y1, 0.5f, 1e-6f);
    for (const Vec3f& p : {s->a, s->b}) {
        EXPECT_NEAR(p.x, 0.25f, 1e-6f);
        EXPECT_NEAR(p.z, 0.f, 1e-6f);
    }
    // The same pair in the other order, and non-crossing configurations.
    EXPECT_TRUE(triangle_intersection(upright, flat).has_value());
    const Triangle3f above{Vec3f(0.25f, -2.f, 0.5f), Vec3f(0.25f, 2.f, 0.5f), Vec3f(0.25f, 0.f, 2.f)};
    EXPECT_FALSE(triangle_intersection(flat, above).has_value());
    const Triangle3f beside{Vec3f(3.f, -2.f, -1.f), Vec3f(3.f, 2.f, -1.f), Vec3f(3.f, 0.f, 1.f)};
    EXPECT_FALSE(triangle_intersection(flat, beside).has_value()); // crosses the plane, not the triangle
    const Triangle3f coplanar{Vec3f(0.f, 0.f, 0.f), Vec3f(2.f, 0.f, 0.f), Vec3f(0.f, 2.f, 0.f)};
    EXPECT_FALSE(triangle_intersection(flat, coplanar).has_value());
}

TEST(WasImplicitEdges, BroadPhaseFindsEveryCrossingPair) {
    // Random small triangles in a box, one shape: every crossing pair of non-adjacent triangles, found by
    // brute force over all pairs, is found once by the BVH collision.
    static test::ScratchDir dir("penumbra_implicit_bf_");
    PCG32 rng(7);
    std::ostringstream obj;
    const int count = 1500;
    for (int t = 0; t < count; ++t) {
        const Vec3f c(rng.next_float(), rng.next_float(), rng.next_float());
        for (int k = 0; k < 3; ++k)
            obj << "v " << c.x + 0.1f * (rng.next_float() - 0.5f) << ' '
                << c.y + 0.1f * (rng.next_float() - 0.5f) << ' ' << c.z + 0.1f * (rng.next_float() - 0.5f)
                << '\n';
        obj << "f " << 3 * t + 1 << ' ' << 3 * t + 2 << ' ' << 3 * t + 3 << '\n';
    }
    const std::string file = test::write_file(dir.path, "soup.obj", obj.str());
    const auto scene = load_scene_string("<scene version=\"3.0.0\"><shape type=\"obj\" id=\"soup\"><string "
                                         "name=\"filename\" value=\"" +
                                         file + "\"/></shape></scene>");
    const TriangleMesh& mesh = scene->shapes[0]->mesh;
    const auto tri = [&](size_t f) {
        const uint32_t* i = &mesh.indices[3 * f];
        return Triangle3f{mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
    };
    size_t brute = 0;
    for (size_t a = 0; a < mesh.face_count(); ++a)
        for (size_t b = a + 1; b < mesh.face_count(); ++b)
            brute += triangle_intersection(tri(a), tri(b)).has_value();
    const ImplicitEdges edges(*scene);
    size_t stored = 0;
    for (uint32_t f = 0; f < mesh.face_count(); ++f)
        stored += edges.segments(*scene->shapes[0], f).size();
    std::printf("triangle soup: %zu crossing pairs by brute force, %zu by the BVH collision\n", brute,
                edges.pair_count());
    EXPECT_GT(brute, 100u);
    EXPECT_EQ(edges.pair_count(), brute);
    EXPECT_EQ(stored, 2 * brute);
}

TEST(WasImplicitEdges, SunkCubeSquareAndBoundaryValues) {
    const SunkCube c("1,0,0");
    const ImplicitEdges& edges = *c.with.implicit_edges();
    EXPECT_EQ(c.without.implicit_edges(), nullptr);
    // Each shape's segments tile the square: on it, and of total length its perimeter 8 · 1/2.
    for (const char* id : {"floor", "cube"}) {
        const Shape& s = c.shape(id);
        double length = 0.0;
        for (uint32_t f = 0; f < s.mesh.face_count(); ++f)
            for (const ImplicitSegment& seg : edges.segments(s, f)) {
                length += norm(seg.b - seg.a);
                for (const Vec3f& p : {seg.a, seg.b}) {
                    EXPECT_NEAR(p.z, 0.f, 1e-6f);
                    EXPECT_NEAR(std::max(std::abs(p.x), std::abs(p.y)), HalfCube, 1e-6f);
                }
            }
        std::printf("sunk cube: %s segments of total length %.6f (square perimeter %.1f)\n", id, length,
                    8.0 * HalfCube);
        EXPECT_NEAR(length, 8.0 * HalfCube, 1e-5);
    }
    // B seen from x at floor points (1/2 + δ, 0.1, 0) beside the face x = 1/2, and cube points (1/2, 0.1, δ).
    const Vec3f x(2.f, 0.3f, 1.2f);
    const auto b_at = [&](const BoundaryTest& b, const Vec3f& target, const std::string& shape) {
        const Vec3f d = normalize(target - x);
        const SurfaceInteraction3f hit = c.scene->intersect(Ray(x, d));
        EXPECT_EQ(hit.shape->id, shape);
        return b(hit, x, d);
    };
    // The sine of the angle between the ray to p and the line x = 1/2, z = 0 (dense search along it).
    const auto sine_to_edge = [&](const Vec3f& p) {
        const Vec3f d = normalize(p - x);
        float best = 1.f;
        for (int k = 0; k <= 200000; ++k) {
            const Vec3f q(HalfCube, -HalfCube + float(k) / 200000.f, 0.f);
            best = std::min(best, norm(cross(normalize(q - x), d)));
        }
        return best;
    };
    const auto spread_map = [](float u) { return u / (1.f - 0.99f * (1.f - u)); };
    for (const auto& [shape, offset] :
         {std::pair{"floor", Vec3f(1.f, 0.f, 0.f)}, {"cube", Vec3f(0.f, 0.f, 1.f)}})
        for (float delta : {0.001f, 0.002f, 0.05f}) {
            const Vec3f p = Vec3f(HalfCube, 0.1f, 0.f) + offset * delta;
            const float with = b_at(c.with, p, shape), without = b_at(c.without, p, shape);
            const float factor = spread_map(sine_to_edge(p));
            std::printf(
                "sunk cube, %s at δ = %.3f: B = %.5f with implicit edges, %.5f without (factor %.5f)\n",
                shape, delta, with, without, factor);
            EXPECT_NEAR(with, without * factor, 2e-3f * without);
            if (delta < 0.01f) {
                EXPECT_LT(with, 0.25f * without);
            }
        }
    // Linear in the distance near the edge (slope 1/β): doubling δ doubles B, up to O(u/β) ≈ 10%.
    const float near1 = b_at(c.with, Vec3f(HalfCube + 0.0005f, 0.1f, 0.f), "floor"),
                near2 = b_at(c.with, Vec3f(HalfCube + 0.001f, 0.1f, 0.f), "floor");
    EXPECT_NEAR(near2 / near1, 2.f, 0.2f);
    // Far from the square, on a floor triangle it does not cross: the paper's value, bit for bit.
    const Vec3f far(1.3f, 0.1f, 0.f);
    EXPECT_EQ(b_at(c.with, far, "floor"), b_at(c.without, far, "floor"));
    EXPECT_TRUE(
        edges.segments(c.shape("floor"), c.scene->intersect(Ray(x, normalize(far - x))).prim_index).empty());
}

namespace {

// The warp V(ω) (Eq. 7, consistent estimator) at the direction from x toward the curve point q, averaged
// over independent estimates, as the component along the curve's image normal m: mean and standard error.
struct NormalWarp {
    double mean, se;
};
NormalWarp normal_warp(const SunkCube& c, const BoundaryTest& boundary, const Vec3f& x, const Vec3f& q,
                       const Vec3f& m, const WarpOptions& o, int estimates) {
    const Vec3f omega = normalize(q - x);
    Interaction3f reference;
    reference.p = x;
    const WarpVertex vertex{reference, Vec3<Var>(x)};
    std::vector<float> tangent;
    const int batches = 20;
    std::vector<double> means;
    for (int b = 0; b < batches; ++b) {
        Rng rng{PCG32(31, uint64_t(b))};
        double sum = 0.0;
        for (int i = 0; i < estimates / batches; ++i) {
            Tape::current().clear();
            const WarpEstimate e = estimate_warp_at(*c.scene, *c.form, boundary, vertex, omega, o, rng);
            Tape::current().forward(tape_direction(*c.params).data(), tangent);
            const auto d = [&](const Var& v) { return v.is_constant() ? 0.f : tangent[size_t(v.id)]; };
            sum += dot(Vec3f(d(e.direction.x), d(e.direction.y), d(e.direction.z)), m);
        }
        means.push_back(sum / (estimates / batches));
    }
    double mean = 0.0, var = 0.0;
    for (double v : means)
        mean += v / batches;
    for (double v : means)
        var += (v - mean) * (v - mean) / (batches - 1);
    return {mean, std::sqrt(var / batches)};
}

} // namespace

TEST(WasImplicitEdges, WarpAtTheCurveOfASunkCube) {
    // x looks at q on the curve where the face x = 1/2 meets the floor. The image normal of the curve
    // (tangent t = e_y) at ω is m ∝ ω × t. The floor is static (direct warp 0); the cube's direct warp at q
    // is V_cube = P_ω v / |q − x| for the cube's velocity v. The curve's own velocity: sliding (v = e_x)
    // drags the curve with the cube, V_true = V_cube; lifting (v = e_z) leaves it in place, V_true = 0. The
    // harmonic weights do not depend on the motion, so with the material direct warps V = f V_cube with the
    // same fraction f in both motions: relative errors 1 − f and f, at least 1/2 in one of them whatever B
    // does (asserted > 0.4 without implicit edges: f ≈ 1/2). With them, trace_auxiliary's edge-following
    // warp (edge_following_point) gives the aux rays next to the edge its velocity: the error is the
    // consistent estimator's bias, which shrinks as N' grows (measured 0.07, 0.04 at N' = 32, 128).
    // Tolerances: the standard errors of the means are ~1e-3 of V_cube, and every threshold is > 50 of them
    // from the measured values; the thresholds separate a consistent warp from the two-sided average.
    const Vec3f x(2.2f, 0.3f, 1.4f), q(HalfCube, 0.1f, 0.f);
    const Vec3f omega = normalize(q - x), m = normalize(cross(omega, Vec3f(0.f, 1.f, 0.f)));
    const float range = norm(q - x);
    for (const auto& [motion, velocity, moves] :
         {std::tuple{"1,0,0", Vec3f(1.f, 0.f, 0.f), true}, {"0,0,1", Vec3f(0.f, 0.f, 1.f), false}}) {
        const SunkCube c(motion);
        const float cube_side = dot(velocity - omega * dot(omega, velocity), m) / range;
        const float truth = moves ? cube_side : 0.f;
        const auto error = [&](const BoundaryTest& b, int aux_count, const char* name) {
            WarpOptions o;
            o.aux_count = aux_count;
            const NormalWarp v = normal_warp(c, b, x, q, m, o, 4000);
            const double e = std::abs(v.mean - truth) / std::abs(cube_side);
            std::printf("sunk cube, motion %s, N' = %d, %s: V·m = %.5f ± %.5f, cube side %.5f, truth %.5f: "
                        "relative error %.3f ± %.3f\n",
                        motion, aux_count, name, v.mean, v.se, cube_side, truth, e,
                        v.se / std::abs(cube_side));
            return e;
        };
        EXPECT_GT(error(c.without, 32, "without implicit edges"), 0.4);
        const double follow32 = error(c.with, 32, "implicit edges in B, edge-following warp");
        const double follow128 = error(c.with, 128, "implicit edges in B, edge-following warp");
        EXPECT_LT(follow32, 0.15);
        EXPECT_LT(follow128, 0.7 * follow32);
    }
}

TEST(WasImplicitEdges, HedgeConstructionTime) {
    const auto scene = load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/was/hedge.xml");
    const auto seconds = [](auto&& f) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    size_t pairs = 0, on_floor = 0;
    const double implicit = seconds([&] {
        const ImplicitEdges edges(*scene);
        pairs = edges.pair_count();
        for (const auto& s : scene->shapes)
            if (s->id == "floor")
                for (uint32_t f = 0; f < s->mesh.face_count(); ++f)
                    on_floor += edges.segments(*s, f).size();
    });
    // A guard against a broad phase that does not scale (all pairs would be 2.4e10 triangle tests); measured
    // 0.24 s alone on a shared 2-core machine.
    const double with = seconds([&] { BoundaryTest b(*scene); });
    const double without = seconds([&] { BoundaryTest b(*scene, 0.01f, false); });
    std::printf(
        "hedge (%zu triangles): implicit edges %.3f s (%zu crossing pairs, %zu of them with the floor); "
        "BoundaryTest %.3f s with them, %.3f s without\n",
        scene->triangle_count(), implicit, pairs, on_floor, with, without);
    EXPECT_GT(on_floor, 0u);
    EXPECT_LT(implicit, 5.0);
}
