// bdpt in homogeneous participating media against analytic answers: an absorbing slab in front of an area
// light (transmittance exp(-sigma_t d / cos θ)), single scattering from a point light (max_depth 2, the
// line integral along each camera ray by quadrature), and two furnaces (a non-absorbing medium under a
// uniform environment has radiance 1 everywhere): behind null boundaries with the camera inside the medium,
// and inside a dielectric sphere. Tolerances: |z| < 4 for the image mean and < 4.5 for the largest of 16
// block means, with standard errors from 12 independent renders (t with 11 degrees of freedom: P(|t| > 4.5)
// ~ 1e-3 per block), plus the quadrature error bound where a reference is integrated numerically. A furnace
// in a spatially varying medium exercises the tracking estimators behind the Medium interface.
#include "test_bdpt_util.h"

#include "scene/medium.h"

#include <array>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// z-scores of block statistics against exact values (expected[0]: image mean, [1..16]: blocks), with an
// absolute reference error `ref_error` added to the standard errors.
std::vector<double> z_against(const BlockStats& s, const std::vector<double>& expected, double ref_error) {
    std::vector<double> z;
    for (size_t i = 0; i < expected.size(); ++i) {
        const double d = std::abs(s.mean[i] - expected[i]);
        z.push_back(std::max(0.0, d - ref_error) / s.stderr_[i]);
    }
    return z;
}

// Reference block means for a camera at the origin looking along +z (lookat up +y, fov 2 atan(tan_half)):
// film position (sx, sy) in [0,1]² sees the world direction (tan_half (1 - 2 sx), tan_half (1 - 2 sy), 1).
template <typename Radiance> std::vector<double> reference_blocks(float tan_half, int q, const Radiance& L) {
    std::vector<double> out(17, 0.0);
    for (int j = 0; j < 4 * q; ++j)
        for (int i = 0; i < 4 * q; ++i) {
            const double sx = (i + 0.5) / (4 * q), sy = (j + 0.5) / (4 * q);
            const double x = tan_half * (1 - 2 * sx), y = tan_half * (1 - 2 * sy);
            const double n = std::sqrt(x * x + y * y + 1);
            const double v = L(x / n, y / n, 1 / n);
            out[0] += v / (16.0 * q * q);
            out[size_t(1 + (j / q) * 4 + i / q)] += v / (q * q);
        }
    return out;
}

std::string camera_at_origin(float fov, const std::string& extra = "") {
    return bdpt_sensor("perspective", "<lookat origin=\"0,0,0\" target=\"0,0,1\" up=\"0,1,0\"/>", fov, 24,
                       extra);
}

TEST(BDPTMedia, AbsorbingSlabTransmittance) {
    // A slab z in [1, 1.5] with sigma_t = (1, 2, 3), albedo 0, in front of a unit-radiance light at z = 3.
    const std::string slab =
        "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"3,3,0.25\"/><translate "
        "value=\"0,0,1.25\"/></transform><bsdf type=\"null\"/><medium type=\"homogeneous\" name=\"interior\">"
        "<rgb name=\"sigma_t\" value=\"1,2,3\"/><float name=\"albedo\" value=\"0\"/></medium></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"5\"/><rotate y=\"1\" "
        "angle=\"180\"/>"
        "<translate value=\"0,0,3\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/>"
        "</emitter></shape>";
    const float fov = 20.f, tan_half = std::tan(0.5f * fov * float(M_PI) / 180.f);
    const auto reference = reference_blocks(tan_half, 16, [](double, double, double cz) {
        const double d = 0.5 / cz;
        return (std::exp(-1 * d) + std::exp(-2 * d) + std::exp(-3 * d)) / 3.0;
    });
    for (const char* heuristic : {"power", "balance"}) {
        const auto scene = load_scene_string(
            "<scene version=\"3.0.0\">" +
            integrator_xml("bdpt", std::string("<string name=\"heuristic\" value=\"") + heuristic + "\"/>") +
            camera_at_origin(fov) + slab + "</scene>");
        const BlockStats s = block_stats(*scene, 12, 4, 11);
        // 16x16 midpoint quadrature per block of a smooth integrand: relative error < 1e-5.
        const auto z = z_against(s, reference, 1e-5 * reference[0]);
        std::printf("[bdpt slab, %s] mean %.6f vs exact %.6f, z = %.2f, max block |z| = %.2f\n", heuristic,
                    s.mean[0], reference[0], z[0], max_abs(z, 1));
        EXPECT_LT(z[0], 4.0);
        EXPECT_LT(max_abs(z, 1), 4.5);
    }
    // Only directly visible emission reaches the camera: hiding emitters leaves a black image.
    const auto hidden =
        load_scene_string("<scene version=\"3.0.0\">" +
                          integrator_xml("bdpt", "<boolean name=\"hide_emitters\" value=\"true\"/>") +
                          camera_at_origin(fov) + slab + "</scene>");
    RenderOptions opt;
    opt.spp = 2;
    const Image black = render(*hidden, opt);
    for (const Color3f& p : black.pixels)
        EXPECT_EQ(p.x + p.y + p.z, 0.f);
}

TEST(BDPTMedia, SingleScatteringFromPointLight) {
    // The camera and a point light inside a medium box [-4, 4]³ (null boundary, also the sensor's medium);
    // max_depth 2 keeps the paths camera -> medium point -> light:
    //   L(ω) = ∫_0^T sigma_s e^{-sigma_t t} (1 / 4π) I e^{-sigma_t r(t)} / r(t)² dt,
    // T the distance to the box along ω, r(t) the distance from the camera ray's point to the light.
    const float sigma_t = 0.5f, albedo = 0.8f, intensity = 3.f;
    const std::array<double, 3> light{1.0, 1.0, 2.0};
    const std::string medium =
        "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_t\" value=\"0.5\"/>"
        "<float name=\"albedo\" value=\"0.8\"/></medium>";
    const float fov = 40.f, tan_half = std::tan(0.5f * fov * float(M_PI) / 180.f);
    const auto reference = reference_blocks(tan_half, 6, [&](double dx, double dy, double dz) {
        const double T = 4.0 / std::max({std::abs(dx), std::abs(dy), std::abs(dz)});
        const int steps = 4000;
        double sum = 0;
        for (int k = 0; k < steps; ++k) {
            const double t = (k + 0.5) * T / steps;
            const double px = t * dx - light[0], py = t * dy - light[1], pz = t * dz - light[2];
            const double r2 = px * px + py * py + pz * pz, r = std::sqrt(r2);
            sum += sigma_t * albedo * std::exp(-sigma_t * (t + r)) * intensity / (4 * M_PI * r2);
        }
        return sum * T / steps;
    });
    for (const char* heuristic : {"power", "balance"}) {
        const auto scene = load_scene_string(
            "<scene version=\"3.0.0\">" + medium +
            integrator_xml("bdpt",
                           std::string("<integer name=\"max_depth\" value=\"2\"/><string name=\"heuristic\" "
                                       "value=\"") +
                               heuristic + "\"/>") +
            camera_at_origin(fov, "<ref id=\"fog\"/>") +
            "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"4\"/></transform><bsdf "
            "type=\"null\"/>"
            "<ref name=\"interior\" id=\"fog\"/></shape><emitter type=\"point\"><point name=\"position\" "
            "value=\"1,1,2\"/><float name=\"intensity\" value=\"3\"/></emitter></scene>");
        const BlockStats s = block_stats(*scene, 12, 8, 21);
        // 6x6 directions per block, 4000 midpoint steps along the ray (the integrand is smooth: the light is
        // at least 0.3 away from every camera ray): the quadrature error is below 1e-4 relative.
        const auto z = z_against(s, reference, 1e-4 * reference[0]);
        std::printf(
            "[bdpt single scattering, %s] mean %.6f vs quadrature %.6f, z = %.2f, max block |z| = %.2f\n",
            heuristic, s.mean[0], reference[0], z[0], max_abs(z, 1));
        EXPECT_LT(z[0], 4.0);
        EXPECT_LT(max_abs(z, 1), 4.5);
    }
}

// A non-absorbing medium lit by a uniform unit environment: every pixel is 1 (all orders of scattering).
void expect_furnace(const std::string& body, const char* what, int spp, uint64_t seed) {
    for (const char* heuristic : {"power", "balance"}) {
        const auto scene = load_scene_string(
            "<scene version=\"3.0.0\">" +
            integrator_xml("bdpt", std::string("<string name=\"heuristic\" value=\"") + heuristic + "\"/>") +
            body + "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"1\"/></emitter></scene>");
        const BlockStats s = block_stats(*scene, 12, spp, seed);
        const auto z = z_against(s, std::vector<double>(17, 1.0), 0.0);
        std::printf("[bdpt furnace, %s, %s] mean %.5f (stderr %.5f), z = %.2f, max block |z| = %.2f\n", what,
                    heuristic, s.mean[0], s.stderr_[0], z[0], max_abs(z, 1));
        EXPECT_LT(z[0], 4.0) << what << ", " << heuristic;
        EXPECT_LT(max_abs(z, 1), 4.5) << what << ", " << heuristic;
    }
}

TEST(BDPTMedia, FurnaceInsideNullBoundedMedium) {
    // Chromatic extinction and forward scattering; the camera sits in the medium (the sensor's medium).
    expect_furnace(
        "<medium type=\"homogeneous\" id=\"fog\"><rgb name=\"sigma_t\" value=\"1,2,0.5\"/>"
        "<float name=\"albedo\" value=\"1\"/><phase type=\"hg\"><float name=\"g\" value=\"0.4\"/></phase>"
        "</medium>" +
            camera_at_origin(60.f, "<ref id=\"fog\"/>") +
            "<shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape>",
        "null cube", 8, 31);
}

TEST(BDPTMedia, FurnaceInsideDielectricSphere) {
    // Light enters and leaves the medium only through delta refractions: medium vertices connect to each
    // other inside the sphere, and to the outside only through the subpaths.
    expect_furnace(
        bdpt_sensor("perspective", "<lookat origin=\"0,0,-3\" target=\"0,0,0\" up=\"0,1,0\"/>", 30.f, 24) +
            "<shape type=\"sphere\"><bsdf type=\"dielectric\"/><medium type=\"homogeneous\" "
            "name=\"interior\"><float name=\"sigma_t\" value=\"2\"/><float name=\"albedo\" value=\"1\"/>"
            "<phase type=\"hg\"><float name=\"g\" value=\"-0.3\"/></phase></medium></shape>",
        "dielectric sphere", 8, 41);
}

// A spatially varying, non-homogeneous medium (sampled by delta and ratio tracking against a majorant twice
// the largest extinction), standing in for `heterogeneous` grids: bdpt only sees the Medium interface.
class WavyMedium : public MediumBase<WavyMedium> {
  public:
    bool is_homogeneous() const override { return false; }
    template <typename T> Color3<T> sigma_t_t(const Vec3<T>& p) const {
        using std::sin;
        return Color3<T>(T(1.5f) + sin(T(3.f) * p.x) * T(0.5f) + p.y * T(0.5f));
    }
    template <typename T> Color3<T> albedo_t(const Vec3<T>&) const { return Color3<T>(T(1.f)); }
    void majorants(const Vec3f&, const Vec3f&, float tmin, float tmax,
                   const MajorantVisitor& f) const override {
        if (tmin < tmax) f(tmin, tmax, 5.f);
    }
};

TEST(BDPTMedia, FurnaceInsideHeterogeneousMedium) {
    for (const char* heuristic : {"power", "balance"}) {
        const auto scene = load_scene_string(
            "<scene version=\"3.0.0\"><medium type=\"homogeneous\" id=\"fog\"><phase type=\"hg\"><float "
            "name=\"g\" value=\"0.3\"/></phase></medium>" +
            integrator_xml("bdpt", std::string("<string name=\"heuristic\" value=\"") + heuristic + "\"/>") +
            camera_at_origin(60.f, "<ref id=\"fog\"/>") +
            "<shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape>"
            "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"1\"/></emitter></scene>");
        auto wavy = std::make_shared<WavyMedium>();
        wavy->phase = scene->sensor->medium->phase;
        scene->sensor->medium = wavy;
        for (const auto& shape : scene->shapes)
            shape->interior = wavy;
        const BlockStats s = block_stats(*scene, 12, 8, 51);
        const auto z = z_against(s, std::vector<double>(17, 1.0), 0.0);
        std::printf(
            "[bdpt furnace, heterogeneous, %s] mean %.5f (stderr %.5f), z = %.2f, max block |z| = %.2f\n",
            heuristic, s.mean[0], s.stderr_[0], z[0], max_abs(z, 1));
        EXPECT_LT(z[0], 4.0) << heuristic;
        EXPECT_LT(max_abs(z, 1), 4.5) << heuristic;
    }
}

} // namespace
