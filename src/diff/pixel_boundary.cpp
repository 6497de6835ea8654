#include "diff/pixel_boundary.h"

#include "diff/material_form.h"
#include "diff/media_radiance.h"
#include "render/light_medium.h"
#include "render/volume_visibility.h"

#include <cmath>

namespace penumbra {

bool needs_pixel_boundary(const Scene& scene, const Parameters& params, FirstVertex first_vertex) {
    const Film& film = *scene.sensor->film;
    return (film.rfilter->plugin == "box" || !film.sample_border) &&
           !image_space_first_vertex(scene, params, first_vertex);
}

namespace {

// The pixel edges as unit segments: vertical ones x = k, y ∈ [row, row + 1] (k = 0..W, one per row), then
// horizontal ones y = k, x ∈ [column, column + 1]; each is cut into `strata` equal parts with one sample
// each. A continuous filter cut at the film's edge (no sample_border) jumps there only: k = 0 and W (0 and
// H).
struct PixelEdges {
    int width, height, strata;
    bool film_edge_only;
    uint64_t lines(int extent) const { return film_edge_only ? 2 : uint64_t(extent + 1); }
    int line(uint64_t i, int extent) const { return film_edge_only ? (i == 0 ? 0 : extent) : int(i); }
    uint64_t segments() const { return lines(width) * height + lines(height) * width; }
    uint64_t samples() const { return segments() * uint64_t(strata); }
};

// Sample i: stratum j of a unit segment. A pixel's opposite edges (and all edges of a row or column) use the
// same offset along the edge and the same random numbers for the path traced there (the sampler is restarted
// per row/column and stratum), so that what flows in through one edge and out through the other cancels
// sample by sample where the image is smooth, instead of only in expectation.
BoundarySample sample_pixel_edge(const Scene& scene, const MaterialForm& form, bool media,
                                 const FilmEdgeVelocity& warp, const PixelEdges& grid, const PathSettings& settings, uint64_t seed, uint64_t i,
                                 Sampler& sampler, RayCounter& rays) {
    BoundarySample out;
    const Sensor& sensor = *scene.sensor;
    const int W = grid.width, H = grid.height;
    const uint64_t segment = i / uint64_t(grid.strata), j = i % uint64_t(grid.strata);
    const uint64_t vertical = grid.lines(W) * H;
    const bool is_vertical = segment < vertical;
    // The segment's line k, its position along the line (row or column) and the line family's stream.
    const int extent = is_vertical ? W : H;
    const uint64_t per_row = grid.lines(extent), index = is_vertical ? segment : segment - vertical;
    const uint64_t along = index / per_row;
    const int k = grid.line(index % per_row, extent);
    const uint64_t stream = (is_vertical ? along : uint64_t(H) + along) * uint64_t(grid.strata) + j;
    sampler.start(seed, stream, 0);
    const float t = float(along) + (float(j) + sampler.next_1d()) / float(grid.strata);
    const Vec2f s = is_vertical ? Vec2f(float(k), t) : Vec2f(t, float(k));
    const Vec2f across = is_vertical ? Vec2f(1.f, 0.f) : Vec2f(0.f, 1.f);

    // L(s): the radiance seen through s, where the filter alone jumps. Where a discontinuity of the image lies
    // exactly on the pixel edge (an axis-aligned shadow or silhouette seen head-on) the two sides' limits differ
    // and the pixels are not differentiable there: their symmetric derivative, which central differences give,
    // takes the mean of the two, so L is taken just off the edge on a random side.
    const Vec2f side = across * (sampler.next_1d() < 0.5f ? -1e-4f : 1e-4f);
    const auto [ray, ray_weight] = sensor.sample_ray(s + side, sampler.next_2d());
    // In media the first vertex is where a free flight along the ray ends (a medium vertex moves by the volume
    // motion, a surface point by its shape's).
    Color3f L;
    Vec3<Var> x;
    if (media) {
        const ArrivingRadiance a = arriving_radiance(scene, ray, sensor_medium(scene), settings, sampler, rays);
        if (a.end.kind == FlightEnd::Kind::Medium) x = form.volume_motion().position(a.end.p, a.end.medium, nullptr);
        else if (a.end.kind == FlightEnd::Kind::Surface) x = form.vertex(a.end.si).p;
        else return out; // the environment seen directly does not move with the geometry
        L = a.radiance * ray_weight;
    } else {
        ++rays.rays;
        const SurfaceInteraction3f hit = scene.intersect(ray);
        if (hit.is_valid()) {
            L = trace_path<float>(scene, sampler, ray, hit, hit, ReferenceGeometry{}, settings, rays) * ray_weight;
            x = form.vertex(hit).p;
        } else if (warp && !settings.hide_emitters) {
            L = scene.eval_environment(ray.d) * ray_weight; // the warp field moves it (camera rotation)
        } else {
            return out; // the environment seen directly does not move with the geometry
        }
    }
    if (is_black(L)) return out;

    // ṡ · across for the material point seen at s, or the warp field's V(s) · across.
    Var velocity;
    if (warp) {
        velocity = warp(s, across, stream, rays);
    } else {
        const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
        Vec2<Var> s_t;
        Var jacobian;
        if (!sensor.film_position(form.to_reference_camera(x, eye), Vec3<Var>(Vec3f(0.f, 0.f, 1.f)), s_t, jacobian))
            return out;
        velocity = is_vertical ? s_t.x - Var(s.x) : s_t.y - Var(s.y);
    }

    // The pixel before the line (outward normal +across) loses what crosses it, the one after gains it; the
    // splats reach every pixel whose filter jumps there (P_j of Film::filter_weight). Each unit segment is a
    // stratum of the total edge length, so 1/pdf = the number of segments.
    const float inv_pdf = float(grid.segments()), nudge = 1e-3f;
    if (k > 0) out.add_splat(s - across * nudge, L * -inv_pdf, velocity);
    if (k < extent) out.add_splat(s + across * nudge, L * inv_pdf, velocity);
    return out;
}

constexpr uint64_t Salt = 0x4CF5AD432745937FULL;

PixelEdges pixel_edges(const Film& film, const BoundaryOptions& options, int strata) {
    PixelEdges grid{film.width, film.height, strata, film.rfilter->plugin != "box"};
    if (strata > 0) return grid;
    // The budget per pixel spread evenly over the ~2 edge segments per pixel.
    grid.strata = std::max(1, int(std::lround(double(options.samples_per_pixel) * film.width * film.height / double(grid.segments()))));
    return grid;
}

} // namespace

Image PixelBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    const Film& film = *scene_.sensor->film;
    if (!needs_pixel_boundary(scene_, params, options.first_vertex)) return Image(film.width, film.height);
    const MaterialForm form(scene_, params, options.first_vertex);
    const bool media = scene_has_media(scene_);
    const PixelEdges grid = pixel_edges(film, options, strata_);
    return boundary_derivative(scene_, params, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_pixel_edge(scene_, form, media, velocity_, grid, options.path, options.seed ^ Salt, index.i, sampler, rays);
    }, grid.samples());
}

void PixelBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                             std::vector<double>& gradient) const {
    if (!needs_pixel_boundary(scene_, params, options.first_vertex)) return;
    const MaterialForm form(scene_, params, options.first_vertex);
    const bool media = scene_has_media(scene_);
    const PixelEdges grid = pixel_edges(*scene_.sensor->film, options, strata_);
    boundary_gradient(scene_, params, adjoint, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_pixel_edge(scene_, form, media, velocity_, grid, options.path, options.seed ^ Salt, index.i, sampler, rays);
    }, gradient, grid.samples());
}

} // namespace penumbra
