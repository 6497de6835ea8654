// Extended path space manifolds (paper 003 §3.1, diff/dpm/epsm.h): the geometric derivatives of Eq. 2 for each
// constraint type against central differences of the same paths re-solved in closed form (double precision)
// under the moved geometry: a rotating or translating mirror seen along a fixed eye ray (fixed direction +
// half vector), a rotating glass slab refracting it twice (η and 1/η), the mirror point connecting the eye to a
// fixed floor point (the fixed-density EPSM of DPM-G), and a photon reflected onto the floor followed by its
// density-estimation vertex (vertex merging, Eq. 24). Reverse mode must equal forward mode.
#include "core/error.h"
#include "diff/dpm/epsm.h"
#include "diff/vertex_normals.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <array>
#include <functional>

using namespace penumbra;

namespace {

struct V3 {
    double x, y, z;
    V3 operator+(const V3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    V3 operator-(const V3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    V3 operator*(double s) const { return {x * s, y * s, z * s}; }
};
double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(const V3& a, const V3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 unit(const V3& a) { return a * (1.0 / std::sqrt(dot(a, a))); }
V3 v3(const Vec3f& v) { return {v.x, v.y, v.z}; }
Vec3f f3(const V3& v) { return Vec3f(float(v.x), float(v.y), float(v.z)); }

// Rodrigues: v rotated by angle t about the unit axis a.
V3 turn(const V3& v, const V3& a, double t) {
    return v * std::cos(t) + cross(a, v) * std::sin(t) + a * (dot(a, v) * (1.0 - std::cos(t)));
}
// The point where the line o + s d meets the plane through c with normal n.
V3 meet(const V3& o, const V3& d, const V3& c, const V3& n) { return o + d * (dot(c - o, n) / dot(d, n)); }
V3 reflect(const V3& d, const V3& n) { return d - n * (2.0 * dot(d, n)); }
// Snell refraction of the travel direction d at normal n (either side), from index eta_i into eta_t.
V3 refract(const V3& d, V3 n, double eta_i, double eta_t) {
    if (dot(d, n) > 0) n = n * -1.0;
    const double r = eta_i / eta_t, c = -dot(d, n), k = 1.0 - r * r * (1.0 - c * c);
    return unit(d * r + n * (r * c - std::sqrt(k)));
}

// The parameter's central difference of f (a point as a function of θ), step h.
V3 central(const std::function<V3(double)>& f, double h) { return (f(h) - f(-h)) * (0.5 / h); }

// The camera at (0, 1, 2) (its sensor unused), a 45° mirror at (0, 1, −2) facing the camera and the floor,
// the floor y = 0, and a glass slab (a cube 0.6 × 0.1 × 0.6 at (1.5, 0.5, 0)).
const char* scene_xml = R"(<scene version="3.0.0">
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
    <shape type="rectangle" id="mirror">
        <transform name="to_world"><scale value="0.8"/><rotate x="1" angle="45"/><translate value="0, 1, -2"/></transform>
        <bsdf type="conductor"/>
    </shape>
    <shape type="rectangle" id="floor">
        <transform name="to_world"><scale value="10"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"/>
    </shape>
    <shape type="cube" id="slab">
        <transform name="to_world"><scale x="0.6" y="0.1" z="0.6"/><translate value="1.5, 0.5, 0"/></transform>
        <bsdf type="dielectric"/>
    </shape>
</scene>)";

const V3 eye{0, 1, 2}, mirror_center{0, 1, -2}, mirror_normal = unit({0, -1, 1});
const V3 floor_normal{0, 1, 0}, floor_point{0, 0, 0};

struct Fixture {
    std::unique_ptr<Scene> scene = load_scene_string(scene_xml);
    Parameters params{*scene};

    explicit Fixture(const std::string& selection) { params.enable({parse_param_selection(selection)}); }
    SurfaceInteraction3f hit(const V3& o, const V3& d) const {
        // Started a little along d, off the surface the ray leaves.
        const SurfaceInteraction3f si = scene->intersect(Ray(f3(o + unit(d) * 1e-4), f3(unit(d))));
        EXPECT_TRUE(si.is_valid());
        return si;
    }
    // Solves, then returns the tangent (forward mode, the selection's direction) of vertex `i`'s position.
    std::vector<V3> tangents(const std::vector<EpsmVertex>& vertices, const std::vector<EpsmConstraint>& constraints) {
        Tape& tape = Tape::current();
        tape.clear();
        EpsmPath path;
        EXPECT_TRUE(solve_epsm(params, vertices, constraints, path));
        std::vector<float> t;
        tape.forward(tape_direction(params).data(), t);
        const auto of = [&](const Var& v) { return v.id < 0 ? 0.0 : double(t[size_t(v.id)]); };
        std::vector<V3> out;
        for (const Vec3<Var>& x : path.x) out.push_back({of(x.x), of(x.y), of(x.z)});
        // Reverse mode: ⟨w, dx/dθ⟩ for a fixed weighting of every coordinate equals the forward tangent's.
        std::vector<std::pair<int32_t, float>> seeds;
        double expected = 0.0;
        for (size_t i = 0; i < path.x.size(); ++i) {
            const float w[3] = {1.f + float(i), -0.5f, 0.25f * float(i + 1)};
            const Var* c[3] = {&path.x[i].x, &path.x[i].y, &path.x[i].z};
            for (int k = 0; k < 3; ++k) {
                seeds.push_back({c[k]->id, w[k]});
                expected += w[k] * of(*c[k]);
            }
        }
        std::vector<double> g(size_t(params.dimension()), 0.0);
        std::vector<float> scratch;
        tape.backward(seeds, g.data(), scratch);
        double reverse = 0.0;
        for (int k = 0; k < params.dimension(); ++k) reverse += g[size_t(k)] * params.direction()[size_t(k)];
        EXPECT_NEAR(reverse, expected, 1e-4 * (1.0 + std::abs(expected)));
        tape.clear();
        return out;
    }
};

// |a − b| within a relative 2e-3 of |b| (the tape is single precision) plus 1e-4.
void expect_close(const V3& a, const V3& b, const char* what) {
    const double err = std::sqrt(dot(a - b, a - b)), scale = std::sqrt(dot(b, b));
    EXPECT_LE(err, 2e-3 * scale + 1e-4) << what << ": EPSM (" << a.x << ", " << a.y << ", " << a.z << ") vs FD ("
                                        << b.x << ", " << b.y << ", " << b.z << ")";
}

// The eye ray d's hits on the mirror and, reflected, on the floor (at θ0).
std::pair<SurfaceInteraction3f, SurfaceInteraction3f> mirror_path(const Fixture& f, const V3& d) {
    const SurfaceInteraction3f x2 = f.hit(eye, d);
    const SurfaceInteraction3f x3 = f.hit(v3(x2.p), reflect(d, mirror_normal));
    EXPECT_EQ(x2.shape->id, "mirror");
    EXPECT_EQ(x3.shape->id, "floor");
    return {x2, x3};
}

// The mirror's plane under its motion: rotation by θ about `axis` through its center, or translation θ d.
struct MirrorMotion {
    bool rotate;
    V3 vector;
    V3 center(double t) const { return rotate ? mirror_center : mirror_center + vector * t; }
    V3 normal(double t) const { return rotate ? turn(mirror_normal, vector, t) : mirror_normal; }
};

const std::vector<std::pair<std::string, MirrorMotion>> mirror_motions = {
    {"mirror.rotate@0,1,-2=0.6,0,0.8", {true, {0.6, 0, 0.8}}},
    {"mirror.rotate@0,1,-2=0,0.8,0.6", {true, {0, 0.8, 0.6}}},
    {"mirror.translate=0.3,-0.4,0.5", {false, {0.3, -0.4, 0.5}}},
};

} // namespace

// DPM-C's eye subpath (§5.2.1): a fixed eye ray meets the mirror (fixed direction at the eye), whose half
// vector sends it to the floor.
TEST(Epsm, ReflectionAlongAFixedEyeRay) {
    const V3 d = unit({0.05, -0.1, -1});
    for (const auto& [selection, motion] : mirror_motions) {
        Fixture f(selection);
        const auto [x2, x3] = mirror_path(f, d);
        const std::vector<V3> t = f.tangents(
            {EpsmVertex::camera(f3(eye)), EpsmVertex::surface(x2), EpsmVertex::surface(x3)},
            {EpsmConstraint::fixed_direction(0, 1), EpsmConstraint::half_vector(1, 0, 2)});
        const auto mirror_point = [&](double s) { return meet(eye, d, motion.center(s), motion.normal(s)); };
        const auto floor_hit = [&](double s) {
            return meet(mirror_point(s), reflect(d, motion.normal(s)), floor_point, floor_normal);
        };
        SCOPED_TRACE(selection);
        expect_close(t[0], {0, 0, 0}, "eye");
        expect_close(t[1], central(mirror_point, 1e-4), "mirror vertex");
        expect_close(t[2], central(floor_hit, 1e-4), "floor vertex");
    }
}

// Two refractions through a rotating glass slab (η = 1.5, then 1/1.5): the generalized half vector.
TEST(Epsm, RefractionThroughARotatingSlab) {
    Fixture f("slab.rotate@1.5,0.5,0=0.6,0,0.8");
    const V3 o{1.1, 1.6, 0.5}, d = unit(V3{1.5, 0.5, 0.05} - o);
    const V3 axis{0.6, 0, 0.8}, center{1.5, 0.5, 0};
    const auto plane_point = [&](double y, double s) { return center + turn(V3{0, y - 0.5, 0}, axis, s); };
    const auto plane_normal = [&](double s) { return turn(V3{0, 1, 0}, axis, s); };
    const auto path = [&](double s) {
        const V3 top = meet(o, d, plane_point(0.6, s), plane_normal(s));
        const V3 inside = refract(d, plane_normal(s), 1.0, 1.5);
        const V3 bottom = meet(top, inside, plane_point(0.4, s), plane_normal(s));
        const V3 out = refract(inside, plane_normal(s), 1.5, 1.0);
        return std::array<V3, 3>{top, bottom, meet(bottom, out, floor_point, floor_normal)};
    };
    const std::array<V3, 3> p0 = path(0.0);
    const SurfaceInteraction3f top = f.hit(o, d);
    const SurfaceInteraction3f bottom = f.hit(v3(top.p), p0[1] - p0[0]);
    const SurfaceInteraction3f ground = f.hit(v3(bottom.p), p0[2] - p0[1]);
    ASSERT_EQ(top.shape->id, "slab");
    ASSERT_EQ(bottom.shape->id, "slab");
    ASSERT_EQ(ground.shape->id, "floor");
    expect_close(v3(ground.p), p0[2], "reference path");
    const std::vector<V3> t =
        f.tangents({EpsmVertex::camera(f3(o)), EpsmVertex::surface(top), EpsmVertex::surface(bottom),
                    EpsmVertex::surface(ground)},
                   {EpsmConstraint::fixed_direction(0, 1), EpsmConstraint::half_vector(1, 0, 2, 1.5f),
                    EpsmConstraint::half_vector(2, 1, 3, 1.f / 1.5f)});
    for (int k = 0; k < 3; ++k)
        expect_close(t[size_t(k) + 1], central([&](double s) { return path(s)[size_t(k)]; }, 1e-4),
                     k == 0 ? "top" : k == 1 ? "bottom" : "floor");
}

// The fixed-density EPSM of DPM-G (§5.2.2): eye and floor point fixed, the mirror point moves so that the
// mirror still connects them (the eye ray turns).
TEST(Epsm, MirrorPointConnectingTheEyeToAFixedFloorPoint) {
    const V3 d = unit({0.05, -0.1, -1});
    for (const auto& [selection, motion] : mirror_motions) {
        Fixture f(selection);
        const auto [x2, x3] = mirror_path(f, d);
        const V3 xs = v3(x3.p);
        const std::vector<V3> t = f.tangents(
            {EpsmVertex::camera(f3(eye)), EpsmVertex::surface(x2), EpsmVertex::surface(x3)},
            {EpsmConstraint::half_vector(1, 0, 2), EpsmConstraint::fixed_position(2)});
        // The mirror image of the floor point: the mirror point lies on the line from the eye to it.
        const auto mirror_point = [&](double s) {
            const V3 c = motion.center(s), n = motion.normal(s);
            const V3 image = xs - n * (2.0 * dot(xs - c, n));
            return meet(eye, image - eye, c, n);
        };
        SCOPED_TRACE(selection);
        expect_close(t[1], central(mirror_point, 1e-4), "mirror vertex");
        expect_close(t[2], {0, 0, 0}, "floor vertex (fixed)");
    }
}

// The vertex-merging EPSM (Eq. 24): a photon from a point light (fixed direction) reflected by the mirror onto
// the floor; the density-estimation vertex on the (static, flat) floor keeps its offset to the photon.
TEST(Epsm, VertexMergingFollowsThePhoton) {
    const V3 light{0.2, 1.3, 1.0}, d = unit(V3{0.05, 1.0, -2.0} - light);
    for (const auto& [selection, motion] : mirror_motions) {
        Fixture f(selection);
        const SurfaceInteraction3f y1 = f.hit(light, d);
        const SurfaceInteraction3f photon = f.hit(v3(y1.p), reflect(d, mirror_normal));
        ASSERT_EQ(photon.shape->id, "floor");
        const SurfaceInteraction3f xs = f.hit(v3(photon.p) + V3{0.03, 0.05, -0.02}, {0, -1, 0});
        ASSERT_EQ(xs.shape->id, "floor");
        const std::vector<V3> t = f.tangents(
            {EpsmVertex::point(f3(light)), EpsmVertex::surface(y1), EpsmVertex::surface(photon),
             EpsmVertex::surface(xs)},
            {EpsmConstraint::fixed_direction(0, 1), EpsmConstraint::half_vector(1, 0, 2),
             EpsmConstraint::vertex_merge(3, 2)});
        const auto photon_point = [&](double s) {
            const V3 y = meet(light, d, motion.center(s), motion.normal(s));
            return meet(y, reflect(d, motion.normal(s)), floor_point, floor_normal);
        };
        SCOPED_TRACE(selection);
        const V3 expected = central(photon_point, 1e-4);
        expect_close(t[2], expected, "photon");
        expect_close(t[3], expected, "density-estimation vertex");
    }
}

// Constraints that do not determine the unknowns: a count mismatch is an error naming the counts, a
// singular system (two constraints on one vertex, none on another) is refused and leaves the tape as it was.
TEST(Epsm, UnderdeterminedAndSingularSystems) {
    Fixture f("mirror.translate=0,0,1");
    const auto [x2, x3] = mirror_path(f, unit({0.05, -0.1, -1}));
    const std::vector<EpsmVertex> vertices{EpsmVertex::camera(f3(eye)), EpsmVertex::surface(x2),
                                           EpsmVertex::surface(x3)};
    EpsmPath path;
    try {
        solve_epsm(f.params, vertices, {EpsmConstraint::fixed_direction(0, 1)}, path);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("1 constraints for 2 vertices"), std::string::npos) << e.what();
    }
    try {
        solve_epsm(f.params, vertices,
                   {EpsmConstraint::fixed_direction(0, 1), EpsmConstraint::half_vector(1, 0, 7)}, path);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("constraint 1"), std::string::npos) << e.what();
    }
    Tape& tape = Tape::current();
    tape.clear();
    EXPECT_FALSE(solve_epsm(f.params, vertices,
                            {EpsmConstraint::fixed_direction(0, 1), EpsmConstraint::fixed_position(1)}, path));
    EXPECT_EQ(tape.size(), 0u);
    EXPECT_EQ(tape.leaf_count(), 0u);
}
