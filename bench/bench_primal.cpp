// In one run:
//  - Mitsuba's Cornell box (mitsuba-data/docs/scenes/variants_cbox_rgb.xml, 500x500, max_depth 6, when
//    ../shared is present): primal samples/s per core with 1 and with 2 threads (the thread scaling);
//  - the primal cost per sample on the bumpy sphere at 1k, 10k, 100k and 1M triangles (growth with n);
// and on a 200k-triangle scene:
//  - primal throughput of `path` and raw Embree incoherent-ray throughput on the same geometry (their ratio);
//  - the reverse-mode gradient pass (interior term, every data parameter enabled: 300k+ scalars, most of them
//    vertex positions) against the primal pass at the same samples per pixel (their time ratio per sample);
//  - the peak resident memory of each pass (Linux VmHWM, reset before it);
//  - the cost model of the sample budgets (diff/sample_cost.h): seconds per counted cost unit of each pass,
//    relative to the forward-mode interior's (1 everywhere if the model were exact).
#include "core/atomic_file.h"
#include "core/distribution.h"
#include "core/rng.h"
#include "core/warp.h"
#include "diff/psdr/interior.h"
#include "diff/psdr/psdr.h"
#include "render/render.h"
#include "scene/scene.h"

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <sstream>

using namespace penumbra;

namespace {

constexpr int kRings = 320; // 2 * 320 * 320 = 204,800 triangles

// A bumpy sphere of 2 rings² triangles written as binary PLY: a stand-in for a scanned object.
std::string write_bumpy_sphere(const std::filesystem::path& dir, int kRings) {
    const int kSegments = kRings;
    std::vector<Vec3f> v;
    for (int i = 0; i <= kRings; ++i)
        for (int j = 0; j < kSegments; ++j) {
            const float th = Pi * i / kRings, ph = 2 * Pi * j / kSegments;
            const float r = 1.f + 0.05f * std::sin(7 * th) * std::sin(9 * ph);
            v.emplace_back(r * std::sin(th) * std::cos(ph), r * std::cos(th), r * std::sin(th) * std::sin(ph));
        }
    std::vector<std::array<uint32_t, 3>> f;
    for (int i = 0; i < kRings; ++i)
        for (int j = 0; j < kSegments; ++j) {
            const uint32_t a = i * kSegments + j, b = i * kSegments + (j + 1) % kSegments;
            const uint32_t c = a + kSegments, d = b + kSegments;
            f.push_back({a, c, b});
            f.push_back({b, c, d});
        }
    const std::string path = (dir / ("bumpy" + std::to_string(kRings) + ".ply")).string();
    std::ostringstream out; // written atomically: benchmarks running at once share the file
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << v.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << f.size()
        << "\nproperty list uchar uint vertex_indices\nend_header\n";
    out.write(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(Vec3f));
    for (const auto& t : f) {
        const uint8_t n = 3;
        out.write(reinterpret_cast<const char*>(&n), 1);
        out.write(reinterpret_cast<const char*>(t.data()), 12);
    }
    write_text_atomically(path, out.str());
    return path;
}

std::unique_ptr<Scene> make_scene(int rings = kRings) {
    const auto dir = std::filesystem::temp_directory_path() / "penumbra_bench";
    std::filesystem::create_directories(dir);
    const std::string ply = write_bumpy_sphere(dir, rings);
    return load_scene_string(R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="6"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,1.5,4.5" target="0,0,0" up="0,1,0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="192"/><integer name="height" value="192"/></film>
      </sensor>
      <shape type="ply"><string name="filename" value=")" + ply + R"("/>
        <bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></shape>
      <shape type="rectangle"><transform name="to_world"><scale value="6"/><rotate x="1" angle="-90"/>
        <translate value="0,-1.1,0"/></transform><bsdf type="diffuse"/></shape>
      <shape type="rectangle"><transform name="to_world"><scale value="0.7"/><rotate x="1" angle="90"/>
        <translate value="0,3,0"/></transform><emitter type="area"><rgb name="radiance" value="20"/></emitter></shape>
      <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
    </scene>)",
                             dir.string());
}

Scene& scene() {
    static std::unique_ptr<Scene> s = make_scene();
    return *s;
}

double g_path_rays_per_s = 0, g_raw_rays_per_s = 0; // raw: volume workload
bool g_primal_robust = false; // the primal's Embree flags (Parameters later turns the watertight test on)
double g_primal_seconds_per_sample = 0, g_gradient_seconds_per_sample = 0;
size_t g_gradient_dimension = 0;
double g_derivative_seconds_per_sample = 0, g_derivative_seconds_per_unit = 0, g_gradient_seconds_per_unit = 0;
// The peak resident set of the primal, the forward-mode derivative, the boundary terms and the gradient on the
// 200k-triangle scene: Linux's high-water mark (VmHWM), reset before each (clear_refs 5; the scene is loaded).
double g_peak_mb[4] = {0, 0, 0, 0};
const char* const PeakNames[4] = {"primal", "forward-mode derivative", "boundary terms", "gradient"};
void reset_peak_rss() { std::ofstream("/proc/self/clear_refs") << "5"; }
double peak_rss_mb() {
    std::ifstream status("/proc/self/status");
    for (std::string line; std::getline(status, line);)
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
    return 0;
}

// Renders `s` with `opt` for as long as the benchmark runs; the totals of the render statistics.
struct RenderTotals {
    double rays = 0, samples = 0, seconds = 0;
};
RenderTotals time_renders(benchmark::State& state, const Scene& s, const RenderOptions& opt) {
    RenderTotals t;
    for (auto _ : state) {
        RenderStats stats;
        render(s, opt, &stats);
        t.rays += double(stats.rays);
        t.samples += double(stats.samples);
        t.seconds += stats.seconds;
    }
    return t;
}

void BM_PathPrimal(benchmark::State& state) {
    reset_peak_rss();
    g_primal_robust = scene().robust_intersections;
    RenderOptions opt;
    opt.spp = 4;
    const RenderTotals t = time_renders(state, scene(), opt);
    g_path_rays_per_s = t.rays / t.seconds;
    g_primal_seconds_per_sample = t.seconds / t.samples;
    g_peak_mb[0] = peak_rss_mb();
    state.counters["rays/s"] = g_path_rays_per_s;
    state.counters["samples/s"] = t.samples / t.seconds;
    state.counters["triangles"] = double(scene().triangle_count());
}

// Raw Embree on the same geometry, same build quality, flags and threads as the primal: rtcIntersect1 on
// incoherent rays drawn from one of two workloads.
enum class RayWorkload {
    Surface, // origins on the surfaces (by area), directions uniform over the hemisphere of the normal: the
             // distribution of a path tracer's secondary rays
    Volume,  // origins uniform in the scene's bounding sphere, directions uniform (most rays miss everything)
};

struct RawEmbree {
    RTCDevice device = rtcNewDevice(nullptr);
    RTCScene scene = rtcNewScene(device);
    explicit RawEmbree(const Scene& s) {
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
        if (g_primal_robust) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
        for (const auto& shape : s.shapes) {
            RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                  12, shape->mesh.vertex_count()));
            std::memcpy(v, shape->mesh.positions.data(), shape->mesh.vertex_count() * 12);
            auto* i = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                     12, shape->mesh.face_count()));
            std::memcpy(i, shape->mesh.indices.data(), shape->mesh.indices.size() * 4);
            rtcCommitGeometry(g);
            rtcAttachGeometry(scene, g);
            rtcReleaseGeometry(g);
        }
        rtcCommitScene(scene);
    }
    ~RawEmbree() {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }
};

// Rays are generated up front so that only traversal is timed.
std::vector<Ray> make_rays(const Scene& s, RayWorkload workload, int n) {
    std::vector<Ray> rays(n);
    std::vector<float> areas;
    for (const auto& shape : s.shapes) areas.push_back(shape->surface_area());
    const DiscreteDistribution shapes(areas);
    const BoundingSphere bs = s.bounding_sphere();
    PCG32 rng(17, 3);
    for (Ray& ray : rays) {
        if (workload == RayWorkload::Surface) {
            float u = rng.next_float();
            const Shape& shape = *s.shapes[shapes.sample(u)];
            const PositionSample3f ps = shape.sample_position({u, rng.next_float()});
            Vec3f d = warp::square_to_uniform_sphere({rng.next_float(), rng.next_float()});
            if (dot(d, ps.n) < 0.f) d = -d;
            Interaction3f it;
            it.p = ps.p;
            it.n = ps.n;
            ray = it.spawn_ray(d);
        } else {
            const Vec3f o = bs.center + warp::square_to_uniform_sphere({rng.next_float(), rng.next_float()}) *
                                            (bs.radius * std::cbrt(rng.next_float()));
            ray = Ray(o, warp::square_to_uniform_sphere({rng.next_float(), rng.next_float()}));
        }
    }
    return rays;
}

void BM_RawEmbree(benchmark::State& state, RayWorkload workload, double* rays_per_s) {
    const RawEmbree raw(scene());
    constexpr int n_rays = 1 << 20;
    const std::vector<Ray> rays = make_rays(scene(), workload, n_rays);
    double seconds = 0, traced = 0;
    std::atomic<int> hits{0};
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        tbb::parallel_for(tbb::blocked_range<int>(0, n_rays, 4096), [&](const tbb::blocked_range<int>& r) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            int local_hits = 0;
            for (int k = r.begin(); k < r.end(); ++k) {
                const Ray& ray = rays[k];
                RTCRayHit rh{};
                rh.ray.org_x = ray.o.x, rh.ray.org_y = ray.o.y, rh.ray.org_z = ray.o.z;
                rh.ray.dir_x = ray.d.x, rh.ray.dir_y = ray.d.y, rh.ray.dir_z = ray.d.z;
                rh.ray.tnear = 0.f, rh.ray.tfar = ray.tmax, rh.ray.mask = ~0u;
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(raw.scene, &ctx, &rh);
                local_hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
            hits += local_hits;
        });
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        traced += n_rays;
    }
    *rays_per_s = traced / seconds;
    state.counters["rays/s"] = *rays_per_s;
    state.counters["hit_fraction"] = double(hits) / traced;
}

double g_surface_rays_per_s = 0;

// Reverse mode with an adjoint of ones (the gradient of the image sum), all data parameters enabled.
void BM_Gradient(benchmark::State& state) {
    reset_peak_rss();
    Parameters params(scene());
    params.enable_all_data();
    const Film& film = *scene().sensor->film;
    const Image adjoint(film.width, film.height, Color3f(1.f));
    DiffOptions o;
    o.spp = 4;
    o.path = path_settings(scene());
    double seconds = 0, samples = 0, units = 0;
    for (auto _ : state) {
        const Gradient g = render_gradient(scene(), params, adjoint, o);
        benchmark::DoNotOptimize(g.values.data());
        seconds += g.seconds;
        samples += double(film.width) * film.height * o.spp;
        units += g.cost.units();
    }
    g_gradient_seconds_per_sample = seconds / samples;
    g_gradient_seconds_per_unit = seconds / units;
    g_gradient_dimension = size_t(params.dimension());
    g_peak_mb[3] = peak_rss_mb();
    state.counters["parameters"] = double(params.dimension());
    state.counters["samples/s"] = samples / seconds;
}

// Mitsuba 3's Cornell box as its file says (500x500, max_depth 6), 4 spp per iteration, on 1 or 2 threads.
const std::string kCornellBox = PENUMBRA_SHARED_DIR "/mitsuba-data/docs/scenes/variants_cbox_rgb.xml";
double g_cbox_samples_per_core_s[3] = {0, 0, 0};

void BM_CornellBox(benchmark::State& state) {
    const int threads = int(state.range(0));
    if (!std::filesystem::exists(kCornellBox)) {
        state.SkipWithError("mitsuba-data absent");
        for (auto _ : state) {
        }
        return;
    }
    static std::unique_ptr<Scene> cbox = load_scene(kCornellBox);
    RenderOptions opt;
    opt.spp = 4;
    opt.threads = threads;
    const RenderTotals t = time_renders(state, *cbox, opt);
    g_cbox_samples_per_core_s[threads] = t.samples / t.seconds / threads;
    state.counters["samples/s/core"] = g_cbox_samples_per_core_s[threads];
    state.counters["64spp_seconds"] = 500.0 * 500.0 * 64.0 / (t.samples / t.seconds);
}

// The primal cost per sample against the triangle count (the bumpy sphere, 4 spp per iteration).
constexpr int kCurveRings[4] = {22, 71, 224, 707}; // 968, 10082, 100352, 999698 triangles
double g_curve_seconds_per_sample[4] = {0, 0, 0, 0};
size_t g_curve_triangles[4] = {0, 0, 0, 0};

void BM_TriangleCount(benchmark::State& state) {
    const int k = int(state.range(0));
    const std::unique_ptr<Scene> s = make_scene(kCurveRings[k]);
    RenderOptions opt;
    opt.spp = 4;
    const RenderTotals t = time_renders(state, *s, opt);
    g_curve_seconds_per_sample[k] = t.seconds / t.samples;
    g_curve_triangles[k] = s->triangle_count();
    state.counters["triangles"] = double(g_curve_triangles[k]);
    state.counters["samples/s"] = t.samples / t.seconds;
}

BENCHMARK(BM_CornellBox)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->MinTime(5.0)->UseRealTime();
BENCHMARK(BM_TriangleCount)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
BENCHMARK(BM_PathPrimal)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
// Forward mode along a translation of the mesh (every vertex moves).
void BM_Derivative(benchmark::State& state) {
    reset_peak_rss();
    Parameters params(scene());
    params.enable({{scene().shapes[0]->id.empty() ? "shape_0.translate" : scene().shapes[0]->id + ".translate", {0, 1, 0}}});
    const Film& film = *scene().sensor->film;
    DiffOptions o;
    o.spp = 4;
    o.path = path_settings(scene());
    double seconds = 0, samples = 0, units = 0;
    for (auto _ : state) {
        const DerivativeImage d = render_derivative(scene(), params, o);
        benchmark::DoNotOptimize(d.derivative.pixels.data());
        seconds += d.seconds;
        samples += double(film.width) * film.height * o.spp;
        units += d.cost.units();
    }
    g_derivative_seconds_per_sample = seconds / samples;
    g_derivative_seconds_per_unit = seconds / units;
    g_peak_mb[1] = peak_rss_mb();
    state.counters["samples/s"] = samples / seconds;
}

// The boundary terms along the same translation, one sample per pixel each (edge sets prepared once, outside
// the timed loop): time per boundary sample relative to a primal sample.
double g_boundary_seconds_per_sample[3] = {0, 0, 0}, g_boundary_seconds_per_unit[3] = {0, 0, 0};
const char* const BoundaryTermNames[3] = {"primary", "direct", "indirect"};

void BM_Boundary(benchmark::State& state) {
    const int term = int(state.range(0));
    if (term == 0) reset_peak_rss(); // the peak over the three terms
    Parameters params(scene());
    params.enable({{scene().shapes[0]->id.empty() ? "shape_0.translate" : scene().shapes[0]->id + ".translate", {0, 1, 0}}});
    const Film& film = *scene().sensor->film;
    BoundaryOptions o;
    o.samples_per_pixel = 1;
    o.path = path_settings(scene());
    const SceneEdges edges(scene());
    const PrimaryBoundary primary(scene(), edges);
    const DirectBoundary direct(scene(), edges);
    const IndirectBoundary indirect(scene(), edges);
    const BoundaryTerm* const terms[3] = {&primary, &direct, &indirect};
    double seconds = 0, samples = 0;
    SampleCost cost;
    o.cost = &cost;
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        const Image d = terms[term]->derivative(params, o);
        benchmark::DoNotOptimize(d.pixels.data());
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        samples += double(film.width) * film.height * o.samples_per_pixel;
    }
    g_boundary_seconds_per_sample[term] = seconds / samples;
    g_boundary_seconds_per_unit[term] = seconds / cost.units();
    state.SetLabel(BoundaryTermNames[term]);
    g_peak_mb[2] = peak_rss_mb();
    state.counters["samples/s"] = samples / seconds;
}

BENCHMARK(BM_Derivative)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
BENCHMARK(BM_Boundary)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
BENCHMARK(BM_Gradient)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
BENCHMARK_CAPTURE(BM_RawEmbree, surface_incoherent, RayWorkload::Surface, &g_surface_rays_per_s)
    ->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
BENCHMARK_CAPTURE(BM_RawEmbree, volume_incoherent, RayWorkload::Volume, &g_raw_rays_per_s)
    ->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();

} // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    scene(); // load outside the timed region
    benchmark::RunSpecifiedBenchmarks();
    if (g_cbox_samples_per_core_s[1] > 0 && g_cbox_samples_per_core_s[2] > 0)
        std::printf("Cornell box (Mitsuba's, 500x500, max_depth 6): %.3g samples/s per core on 1 thread, %.3g on 2 "
                    "(2-thread efficiency %.2f); 64 spp on 2 threads: %.1f s\n",
                    g_cbox_samples_per_core_s[1], g_cbox_samples_per_core_s[2],
                    g_cbox_samples_per_core_s[2] / g_cbox_samples_per_core_s[1],
                    500.0 * 500.0 * 64.0 / (2.0 * g_cbox_samples_per_core_s[2]));
    if (g_curve_seconds_per_sample[0] > 0) {
        std::printf("primal time per sample against triangles (relative to the smallest):");
        for (int k = 0; k < 4; ++k)
            if (g_curve_seconds_per_sample[k] > 0)
                std::printf(" %zu: %.2f,", g_curve_triangles[k], g_curve_seconds_per_sample[k] / g_curve_seconds_per_sample[0]);
        std::printf("\n");
    }
    if (g_path_rays_per_s > 0 && g_surface_rays_per_s > 0 && g_raw_rays_per_s > 0) {
        std::printf("%zu triangles, %d threads\n", scene().triangle_count(), tbb::this_task_arena::max_concurrency());
        std::printf("path integrator rays/s / raw Embree surface-origin incoherent rays/s = %.3f\n",
                    g_path_rays_per_s / g_surface_rays_per_s);
        std::printf("path integrator rays/s / raw Embree volume-origin incoherent rays/s  = %.3f\n",
                    g_path_rays_per_s / g_raw_rays_per_s);
    }
    if (g_primal_seconds_per_sample > 0 && g_gradient_seconds_per_sample > 0)
        std::printf("gradient pass / primal pass, time per sample = %.2f  (%zu parameter scalars)\n",
                    g_gradient_seconds_per_sample / g_primal_seconds_per_sample, g_gradient_dimension);
    if (g_primal_seconds_per_sample > 0 && g_derivative_seconds_per_sample > 0)
        std::printf("forward-mode derivative pass / primal pass, time per sample = %.2f\n",
                    g_derivative_seconds_per_sample / g_primal_seconds_per_sample);
    for (int term = 0; term < 3; ++term)
        if (g_primal_seconds_per_sample > 0 && g_boundary_seconds_per_sample[term] > 0)
            std::printf("%s boundary sample / primal sample, time = %.2f\n", BoundaryTermNames[term],
                        g_boundary_seconds_per_sample[term] / g_primal_seconds_per_sample);
    if (g_derivative_seconds_per_unit > 0) {
        std::printf("cost model (seconds per counted unit / the forward interior's):");
        for (int term = 0; term < 3; ++term)
            if (g_boundary_seconds_per_unit[term] > 0)
                std::printf(" %s %.2f,", BoundaryTermNames[term], g_boundary_seconds_per_unit[term] / g_derivative_seconds_per_unit);
        if (g_gradient_seconds_per_unit > 0)
            std::printf(" reverse interior %.2f", g_gradient_seconds_per_unit / g_derivative_seconds_per_unit);
        std::printf("\n");
    }
    if (g_peak_mb[3] > 0) {
        std::printf("peak resident memory (MB) on the %zu-triangle scene:", scene().triangle_count());
        for (int k = 0; k < 4; ++k)
            if (g_peak_mb[k] > 0) std::printf(" %s %.0f,", PeakNames[k], g_peak_mb[k]);
        std::printf("\n");
    }
    benchmark::Shutdown();
    return 0;
}
