// vertex_positions of meshes shaded with smooth vertex normals: as in Mitsuba 3 (Mesh::parameters_changed),
// the normals are recomputed whenever the positions change, and the derivative estimators differentiate them
// through the positions (diff/material_form.h, MovedVertices::normal).
#include "diff/psdr/psdr.h"
#include "diff/vertex_normals.h"
#include "diff_check.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <sstream>

using namespace penumbra;
using namespace penumbra::test;

namespace {

constexpr int GridCells = 8; // per side; the grid spans [-1.6, 1.6]² in x and y

// A gently rolling heightfield z = 0.08 sin(2x) cos(1.5y) as an OBJ without normals (smooth normals are
// computed at load), its slopes below 0.2: lit from high above, it casts no shadow on itself.
std::string heightfield_obj() {
    std::ostringstream obj;
    const int n = GridCells + 1;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float x = -1.6f + 3.2f * i / GridCells, y = -1.6f + 3.2f * j / GridCells;
            obj << "v " << x << " " << y << " " << 0.08f * std::sin(2.f * x) * std::cos(1.5f * y) << "\n";
        }
    for (int j = 0; j < GridCells; ++j)
        for (int i = 0; i < GridCells; ++i) {
            const int a = j * n + i + 1, b = a + 1, c = a + n, d = c + 1;
            obj << "f " << a << " " << b << " " << d << "\nf " << a << " " << d << " " << c << "\n";
        }
    return obj.str();
}

// The heightfield fills the view of a camera looking down on it (no silhouette in view, every shading normal
// turned toward the camera, sample_border keeps the pixel filters whole): under height changes only the
// interior term contributes. A glossy conductor under a point light makes the image depend on the normals.
std::string heightfield_scene(const std::string& mesh, bool face_normals) {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
          <boolean name="sample_border" value="true"/></film></sensor>
      <shape type="obj" id="field"><string name="filename" value=")" +
           mesh + R"("/><boolean name="face_normals" value=")" + (face_normals ? "true" : "false") + R"("/>
        <bsdf type="roughconductor"><float name="alpha" value="0.25"/><string name="distribution" value="ggx"/></bsdf></shape>
      <emitter type="point"><point name="position" value="0.4,0.6,2.5"/><rgb name="intensity" value="6"/></emitter>
    </scene>)";
}

// Heights change by d_z = 0.5 cos(πx/1.6) cos(πy/1.6) (zero on the border): the normals tilt, while the seen
// points barely move along the view direction.
std::vector<float> height_field_direction(const Parameter& positions) {
    std::vector<float> d(size_t(positions.size), 0.f);
    for (int v = 0; v < positions.size / 3; ++v) {
        const float* p = positions.data + 3 * v;
        d[3 * v + 2] = 0.5f * std::cos(Pi * p[0] / 1.6f) * std::cos(Pi * p[1] / 1.6f);
    }
    return d;
}

// A quad filling the view (its edges out of the film), with vertex normals given in the file that turn its
// left side away from the camera: the shading terminator, where a diffuse BSDF's cos θ_i > 0 test makes the
// radiance jump to black, runs down the middle of the image (diff/psdr/shading_terminator.h). A constant sky
// lights it; nothing casts a shadow.
std::string terminator_scene(const std::string& mesh) {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
          <boolean name="sample_border" value="true"/></film></sensor>
      <shape type="obj" id="quad"><string name="filename" value=")" +
           mesh + R"("/><bsdf type="diffuse"><rgb name="reflectance" value="0.8,0.6,0.4"/></bsdf></shape>
      <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    </scene>)";
}

const char* const TiltedQuadObj = "v -3 -3 0\nv 3 -3 0\nv 3 3 0\nv -3 3 0\n"
                                  "vn -1 0.3 -0.5\nvn 0.3 0 1\nvn 0.3 0 1\nvn -1 -0.3 -0.5\n"
                                  "f 1//1 2//2 3//3\nf 1//1 3//3 4//4\n";

// psdr with the interior term and the primary term only (no shadows, no indirect boundaries).
PsdrOptions interior_and_primary(const Scene& scene, int spp, uint64_t seed, int primary_spp) {
    PsdrOptions o;
    o.interior.spp = spp;
    o.interior.seed = seed;
    o.interior.path = path_settings(scene);
    o.primary_spp = primary_spp;
    o.direct_spp = o.indirect_spp = o.pixel_spp = 0;
    return o;
}

// psdr (interior + primary term, which samples the terminator) against finite differences; with
// primary_spp = 0 (the interior term alone) the check must fail.
void expect_terminator_matches_fd(const std::string& param) {
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    const uint64_t seed = env ? std::strtoull(env, nullptr, 10) : 0;
    const TempDir dir;
    auto scene = load_scene_string(terminator_scene(dir.write("quad.obj", TiltedQuadObj)));
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    PsdrOptions o = interior_and_primary(*scene, 8, 5 + 1000 * seed, 8);
    o.interior.batches = 16;
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 64;
    ro.seed = 77 + 1000 * seed;
    const FiniteDifference fd = finite_difference(*scene, params, 1e-2, ro, 16);
    const DiffCheck total = check_against(d, fd);
    const DiffCheck interior = check_against(d.term("interior").derivative, d.term("interior").stderr_img,
                                             fd.derivative, fd.stderr_img);
    std::printf("  %s: interior+primary %s\n  interior only %s\n", param.c_str(), describe(total).c_str(),
                describe(interior).c_str());
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(interior.passes()) << "negative control: the terminator must matter: " << describe(interior);
}

// A unit icosphere (the icosahedron's faces split in four `levels` times, vertices pushed to the sphere) of
// radius 0.8 as an OBJ without normals.
std::string icosphere_obj(int levels) {
    const float t = (1.f + std::sqrt(5.f)) / 2.f;
    std::vector<Vec3f> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<int, int>, int> middle;
        const auto mid = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            if (auto it = middle.find(key); it != middle.end()) return it->second;
            v.push_back((v[size_t(a)] + v[size_t(b)]) * 0.5f);
            return middle[key] = int(v.size()) - 1;
        };
        std::vector<std::array<int, 3>> split;
        for (const auto& [a, b, c] : f) {
            const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
            split.insert(split.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
        }
        f = split;
    }
    std::ostringstream obj;
    for (const Vec3f& p : v) {
        const Vec3f q = normalize(p) * 0.8f;
        obj << "v " << q.x << " " << q.y << " " << q.z << "\n";
    }
    for (const auto& [a, b, c] : f)
        obj << "f " << a + 1 << " " << b + 1 << " " << c + 1 << "\n";
    return obj.str();
}

// psdr in both modes on the same samples (one batch) with a random adjoint a: ⟨a, J v⟩ of the forward image
// (lhs) against ⟨Jᵀ a, v⟩ of the gradient (rhs), v = params.direction(); scale = Σ|a J v|, and the forward
// result.
struct DotProducts {
    double lhs = 0, rhs = 0, scale = 0;
    DerivativeImage forward;
    Image adjoint;
};
DotProducts dot_products(const Scene& scene, const Parameters& params, const PsdrOptions& o, uint64_t seed) {
    DotProducts r;
    r.forward = psdr_derivative(scene, params, o);
    r.adjoint = Image(r.forward.derivative.width, r.forward.derivative.height);
    PCG32 rng(seed);
    for (auto& a : r.adjoint.pixels) a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
    const Gradient reverse = psdr_gradient(scene, params, r.adjoint, o);
    for (size_t i = 0; i < r.adjoint.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            r.lhs += double(r.adjoint.pixels[i][k]) * r.forward.derivative.pixels[i][k];
            r.scale += std::abs(double(r.adjoint.pixels[i][k]) * r.forward.derivative.pixels[i][k]);
        }
    for (size_t k = 0; k < reverse.values.size(); ++k) r.rhs += reverse.values[k] * params.direction()[k];
    return r;
}

// Enables field.vertex_positions along a random direction (components uniform in [-0.5, 0.5)), returned.
std::vector<float> enable_random_positions(Parameters& params, PCG32& rng) {
    std::vector<float> d(size_t(params.find("field.vertex_positions").size));
    for (float& x : d) x = rng.next_float() - 0.5f;
    params.enable({{"field.vertex_positions", d}});
    return d;
}

} // namespace

// Setting vertex_positions recomputes the smooth normals from the new positions (set_values, and displace for
// finite differences); rigid motions rotate them; face_normals meshes keep none.
TEST(SmoothNormals, RecomputedWhenVertexPositionsChange) {
    const TempDir dir;
    const std::string mesh = dir.write("field.obj", heightfield_obj());
    auto scene = load_scene_string(heightfield_scene(mesh, false));
    Shape& shape = *scene->shapes[0];
    Parameters params(*scene);
    const Parameter& positions = params.find("field.vertex_positions");
    params.enable({{"field.vertex_positions", height_field_direction(positions)}});
    std::vector<float> values = params.values();
    for (size_t k = 2; k < values.size(); k += 3)
        values[k] *= 3.f;
    params.set_values(*scene, values);
    TriangleMesh expected = shape.mesh;
    recompute_vertex_normals(expected);
    ASSERT_EQ(shape.mesh.normals.size(), expected.normals.size());
    const int center = (GridCells / 2) * (GridCells + 1) + GridCells / 2 - 1; // a vertex off the axes
    EXPECT_GT(std::abs(shape.mesh.normals[size_t(center)].x), 0.05f) << "the steeper field tilts the normals";
    for (size_t v = 0; v < expected.normals.size(); ++v)
        EXPECT_EQ(shape.mesh.normals[v], expected.normals[v]) << "vertex " << v;

    // displace() (finite differences) recomputes them at the displaced positions and restores them after.
    const std::vector<Vec3f> before = shape.mesh.normals;
    params.displace(*scene, 0.2);
    expected = shape.mesh;
    recompute_vertex_normals(expected);
    EXPECT_EQ(shape.mesh.normals[size_t(center)], expected.normals[size_t(center)]);
    EXPECT_FALSE(shape.mesh.normals[size_t(center)] == before[size_t(center)]);
    params.displace(*scene, 0.0);
    EXPECT_EQ(shape.mesh.normals[size_t(center)], before[size_t(center)]);
    params.disable_all();

    // A rotation turns the stored normals rigidly.
    params.enable({parse_param_selection("field.rotate=0,0,1")});
    params.displace(*scene, 0.5);
    const Vec3f n = before[size_t(center)], r = shape.mesh.normals[size_t(center)];
    EXPECT_NEAR(r.z, n.z, 1e-6f);
    EXPECT_NEAR(std::hypot(r.x, r.y), std::hypot(n.x, n.y), 1e-6f);
    EXPECT_GT(std::abs(r.x - n.x) + std::abs(r.y - n.y), 1e-3f);
    params.disable_all();

    auto flat = load_scene_string(heightfield_scene(mesh, true));
    Parameters flat_params(*flat);
    flat_params.enable({parse_param_selection("field.vertex_positions=0,0,1")});
    flat_params.set_values(*flat, flat_params.values());
    EXPECT_TRUE(flat->shapes[0]->mesh.normals.empty());
}

// The interior derivative under height changes of a smooth-normal heightfield against central finite
// differences (which recompute the normals at ±h). With the normals held fixed in the derivative (as before
// they followed the positions) this check fails by far: relerr 1.02, mean 0.020 against -0.470.
TEST(SmoothNormals, HeightfieldVertexPositionsMatchFiniteDifferences) {
    const TempDir dir;
    auto scene = load_scene_string(heightfield_scene(dir.write("field.obj", heightfield_obj()), false));
    Parameters params(*scene);
    params.enable(
        {{"field.vertex_positions", height_field_direction(params.find("field.vertex_positions"))}});
    const DerivativePair r = derivative_and_fd(*scene, params, 16, 32, 1e-2);
    const DiffCheck c = check_against(r.derivative, r.fd);
    std::printf("  smooth-normal heightfield: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-3) << "the reference derivative is ~0, a weak test";
}

// The shading terminator moving with the surface: a translation across it and a rotation about the view axis.
TEST(ShadingTerminator, TranslatedQuadMatchesFiniteDifferences) {
    expect_terminator_matches_fd("quad.translate=1,0.3,0");
}

TEST(ShadingTerminator, RotatedQuadMatchesFiniteDifferences) {
    expect_terminator_matches_fd("quad.rotate=0,0,1");
}

// The case of examples/multiview_mesh.py: a smooth-normal icosphere under a sun and a sky, stretched toward
// an ellipsoid. Silhouettes, the shading terminator next to them, and the normals' dependence on the
// positions all contribute; psdr against finite differences. Without the terminator term it fails (mean z -7
// to -9, 6-8% of the 2x2 blocks beyond 4 sigma); with it, seeds 0-7 gave |z| <= 3.3 and 0-2.8% such blocks
// (seed 3 fails on the 2% bound: the terminator's single-sample jumps are heavy-tailed next to silhouettes).
TEST(SmoothNormals, IcosphereStretchedTowardAnEllipsoid) {
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    const uint64_t seed = env ? std::strtoull(env, nullptr, 10) : 0;
    const TempDir dir;
    auto scene = load_scene_string(R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0.8,3.2" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
      <shape type="obj" id="blob"><string name="filename" value=")" +
                                   dir.write("ico.obj", icosphere_obj(2)) + R"("/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8,0.5,0.3"/></bsdf></shape>
      <emitter type="directional"><vector name="direction" value="-1,-2,-0.7"/><rgb name="irradiance" value="3"/></emitter>
      <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter>
    </scene>)");
    Parameters params(*scene);
    const Parameter& positions = params.find("blob.vertex_positions");
    std::vector<float> d(size_t(positions.size));
    const float axes[3] = {1.f / 0.8f - 1.f, 0.6f / 0.8f - 1.f, 0.f};
    for (int k = 0; k < positions.size; ++k)
        d[size_t(k)] = positions.data[k] * axes[k % 3];
    params.enable({{"blob.vertex_positions", d}});
    const DerivativeImage r =
        psdr_derivative(*scene, params, batched(*scene, 3 + 1000 * seed, 48, 48, 16, 0));
    RenderOptions ro;
    ro.spp = 192;
    ro.seed = 50 + 1000 * seed;
    const FiniteDifference fd = finite_difference(*scene, params, 2e-2, ro, 16);
    const DiffCheck c = check_against(r, fd);
    std::printf("  icosphere: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
}

// Reverse mode includes the terminator: ⟨a, Jv⟩ of the forward image equals ⟨Jᵀa, v⟩ of the gradient on the
// same samples (one batch), up to float rounding.
TEST(ShadingTerminator, ReverseModeMatchesForwardMode) {
    const TempDir dir;
    auto scene = load_scene_string(terminator_scene(dir.write("quad.obj", TiltedQuadObj)));
    Parameters params(*scene);
    params.enable({parse_param_selection("quad.translate=1,0.3,0")});
    PsdrOptions o = interior_and_primary(*scene, 4, 5, 8);
    const DotProducts r = dot_products(*scene, params, o, 3);
    double primary = 0;
    const Image& primary_term = r.forward.term("primary").derivative;
    for (size_t i = 0; i < r.adjoint.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k)
            primary += std::abs(double(r.adjoint.pixels[i][k]) * primary_term.pixels[i][k]);
    EXPECT_GT(primary, 0.5 * r.scale) << "the terminator should carry most of this derivative";
    EXPECT_NEAR(r.lhs, r.rhs, 1e-4 * r.scale + 1e-6);
}

// The recomputed vertex normals are leaves of the tape (diff/vertex_normals.h): their tangents along a
// direction of the positions match central differences of recompute_vertex_normals, and the chain of their
// adjoints to the positions is the transpose of that map (⟨a, J d⟩ = ⟨Jᵀ a, d⟩).
TEST(SmoothNormals, NormalLeavesChainToThePositions) {
    const TempDir dir;
    auto scene = load_scene_string(heightfield_scene(dir.write("ico.obj", icosphere_obj(2)), false));
    Shape& shape = *scene->shapes[0];
    Parameters params(*scene);
    PCG32 rng(11);
    const std::vector<float> d = enable_random_positions(params, rng);
    ASSERT_EQ(params.tape_dimension(), 2 * params.dimension());
    const std::vector<float> direction = tape_direction(params);
    const size_t V = shape.mesh.positions.size();
    const auto normals_at = [&](float h) {
        TriangleMesh moved = shape.mesh;
        for (size_t v = 0; v < V; ++v)
            moved.positions[v] += Vec3f(d[3 * v], d[3 * v + 1], d[3 * v + 2]) * h;
        recompute_vertex_normals(moved);
        return moved.normals;
    };
    const float h = 1e-3f;
    const std::vector<Vec3f> plus = normals_at(h), minus = normals_at(-h);
    double error = 0, size = 0;
    for (size_t v = 0; v < V; ++v)
        for (int k = 0; k < 3; ++k) {
            const double fd = (double(plus[v][k]) - double(minus[v][k])) / (2.0 * h);
            error += std::abs(direction[size_t(params.dimension()) + 3 * v + size_t(k)] - fd);
            size += std::abs(fd);
        }
    EXPECT_LT(error / size, 2e-3) << "tangents of the normal leaves against central differences";
    EXPECT_GT(size / double(V), 0.1) << "the direction must turn the normals";

    std::vector<double> gradient(size_t(params.tape_dimension()), 0.0);
    double lhs = 0;
    for (size_t k = 0; k < 3 * V; ++k) {
        const double a = rng.next_float() - 0.5f;
        gradient[size_t(params.dimension()) + k] = a;
        lhs += a * direction[size_t(params.dimension()) + k];
    }
    chain_vertex_normal_gradient(params, gradient);
    ASSERT_EQ(gradient.size(), size_t(params.dimension()));
    double rhs = 0;
    for (size_t k = 0; k < gradient.size(); ++k) rhs += gradient[k] * d[k];
    EXPECT_NEAR(lhs, rhs, 1e-4 * std::abs(lhs) + 1e-6);
}

// The whole estimator (interior, and the primary term at silhouettes) in both modes on the same samples: the
// normals' adjoints chained once per pass equal their tangents along the direction.
TEST(SmoothNormals, ReverseModeMatchesForwardModeUnderVertexPositions) {
    const TempDir dir;
    auto scene = load_scene_string(heightfield_scene(dir.write("ico.obj", icosphere_obj(2)), false));
    Parameters params(*scene);
    PCG32 rng(5);
    enable_random_positions(params, rng);
    PsdrOptions o = interior_and_primary(*scene, 4, 9, 4);
    const DotProducts r = dot_products(*scene, params, o, 6);
    EXPECT_GT(r.scale, 1e-3);
    EXPECT_NEAR(r.lhs, r.rhs, 1e-4 * r.scale + 1e-6);
}

// The shading horizon (diff/psdr/shading_horizon.h) alone: a coarse smooth-normal icosphere (80 faces, no
// other shape: a convex solid shadows itself only across its faces' planes, which no edge carries) under
// `lights`, `param` moving the lights or the ball; nothing reaches the ball that another surface reflects.
// psdr against central finite differences (step h); without the horizon (the interior and the boundary terms
// as before) the check must fail.
void expect_horizon_matters(const std::string& lights, const std::string& param, float fov, double h) {
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    const uint64_t seed = env ? std::strtoull(env, nullptr, 10) : 0;
    const TempDir dir;
    auto scene = load_scene_string(R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <sensor type="perspective"><float name="fov" value=")" +
                                   std::to_string(fov) + R"("/>
        <transform name="to_world"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
      <shape type="obj" id="ball"><string name="filename" value=")" +
                                   dir.write("ico.obj", icosphere_obj(1)) + R"("/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8,0.6,0.4"/></bsdf></shape>)" +
                                   lights + "</scene>");
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    PsdrOptions o = batched(*scene, 3 + 1000 * seed, 64, 16, 8, 0);
    const DerivativeImage with = psdr_derivative(*scene, params, o);
    o.interior.shading_horizon = false;
    const DerivativeImage without = psdr_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 256;
    ro.seed = 50 + 1000 * seed;
    const FiniteDifference fd = finite_difference(*scene, params, h, ro, 16);
    const DiffCheck c = check_against(with, fd);
    const DiffCheck n = check_against(without, fd);
    std::printf("  %s\n  with the horizon: %s\n  without: %s\n", param.c_str(), describe(c).c_str(),
                describe(n).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
    EXPECT_FALSE(n.passes()) << "negative control: the horizon must matter: " << describe(n);
}

// A small area light out of view, to the side, moves up across the planes of the faces near the terminator.
TEST(ShadingHorizon, AreaLightMovingOverSmoothIcosphere) {
    expect_horizon_matters(R"(<shape type="rectangle" id="light">
        <transform name="to_world"><scale value="0.25"/><lookat origin="2.2,0.2,0.4" target="0,0,0" up="0,1,0"/></transform>
        <emitter type="area"><rgb name="radiance" value="20"/></emitter></shape>)",
                           "light.translate=0,1,0", 36.f, 2e-2);
}

// The same light, the ball turning about the vertical: the creases between its faces, where the solid hides a
// different part of the light on either side, move on the film (a narrow view: no silhouette).
TEST(ShadingHorizon, SmoothIcosphereTurningUnderAnAreaLight) {
    expect_horizon_matters(R"(<shape type="rectangle" id="light">
        <transform name="to_world"><scale value="0.25"/><lookat origin="2.2,0.2,0.4" target="0,0,0" up="0,1,0"/></transform>
        <emitter type="area"><rgb name="radiance" value="20"/></emitter></shape>)",
                           "ball.rotate=0,1,0", 14.f, 1e-2);
}
