#include "scene/tet_mesh.h"

#include "core/error.h"

#define TETLIBRARY
#include <tetgen.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <tuple>

namespace penumbra {

namespace {

// TetGen's exit codes (terminatetetgen) in words.
std::string tetgen_reason(int code) {
    switch (code) {
    case 1:
        return "out of memory";
    case 2:
        return "TetGen's internal error";
    case 3:
        return "the surface intersects itself (or triangles overlap)";
    case 4:
        return "an input feature is too small for TetGen's tolerance";
    case 5:
        return "two input facets are too close to each other";
    case 10:
        return "TetGen rejected the input";
    default:
        return "TetGen's exit code " + std::to_string(code);
    }
}

double det3(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return dot(a, cross(b, c)); }

} // namespace

double TetMesh::volume(size_t t) const {
    const auto& v = tets[t];
    const Vec3d d(vertices[v[3]]);
    return det3(Vec3d(vertices[v[0]]) - d, Vec3d(vertices[v[1]]) - d, Vec3d(vertices[v[2]]) - d) / 6.0;
}

TetMesh tetrahedralize(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices,
                       const std::string& name, double max_volume) {
    TetMesh mesh;
    // Coincident input vertices (seams of split normals or uvs) become one PLC vertex.
    std::map<std::tuple<float, float, float>, uint32_t> welded;
    mesh.input_vertex.resize(positions.size());
    for (size_t i = 0; i < positions.size(); ++i) {
        const Vec3f& p = positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw Error("cannot tetrahedralize " + name + ": vertex " + std::to_string(i) + " is not finite");
        const auto [it, added] = welded.try_emplace({p.x, p.y, p.z}, uint32_t(mesh.vertices.size()));
        if (added) mesh.vertices.push_back(p);
        mesh.input_vertex[i] = it->second;
    }
    std::set<std::array<uint32_t, 3>> seen;
    std::vector<std::array<uint32_t, 3>> triangles;
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        std::array<uint32_t, 3> tri = {mesh.input_vertex[indices[t]], mesh.input_vertex[indices[t + 1]],
                                       mesh.input_vertex[indices[t + 2]]};
        std::array<uint32_t, 3> key = tri;
        std::sort(key.begin(), key.end());
        if (key[0] == key[1] || key[1] == key[2] || !seen.insert(key).second) continue;
        triangles.push_back(tri);
    }
    if (triangles.size() < 4) throw Error("cannot tetrahedralize " + name + ": fewer than 4 triangles");

    tetgenio in, out;
    in.firstnumber = 0;
    in.numberofpoints = int(mesh.vertices.size());
    in.pointlist = new REAL[3 * mesh.vertices.size()];
    for (size_t i = 0; i < mesh.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k)
            in.pointlist[3 * i + k] = REAL(mesh.vertices[i][k]);
    in.numberoffacets = int(triangles.size());
    in.facetlist = new tetgenio::facet[triangles.size()];
    for (size_t t = 0; t < triangles.size(); ++t) {
        tetgenio::facet& f = in.facetlist[t];
        tetgenio::init(&f);
        f.numberofpolygons = 1;
        f.polygonlist = new tetgenio::polygon[1];
        tetgenio::init(&f.polygonlist[0]);
        f.polygonlist[0].numberofvertices = 3;
        f.polygonlist[0].vertexlist = new int[3];
        for (int k = 0; k < 3; ++k)
            f.polygonlist[0].vertexlist[k] = int(triangles[t][k]);
    }
    // Debian's TetGen crashes on intersecting facets instead of reporting them: its detection pass (-d)
    // first, which lists the intersecting faces.
    const auto run = [&](std::string switches, tetgenio& result) {
        try {
            ::tetrahedralize(switches.data(), &in, &result);
        } catch (int code) {
            throw Error("cannot tetrahedralize " + name + ": " + tetgen_reason(code));
        }
    };
    {
        tetgenio intersections;
        run("pdzQ", intersections);
        if (intersections.numberoftrifaces > 0)
            throw Error("cannot tetrahedralize " + name + ": the surface intersects itself (" +
                        std::to_string(intersections.numberoftrifaces) + " triangles meet others)");
    }
    char bound[64] = "";
    if (max_volume > 0.0) std::snprintf(bound, sizeof(bound), "a%.12f", max_volume);
    run(std::string("pYzQq") + bound, out);
    if (out.numberoftetrahedra <= 0 || out.numberofpoints < in.numberofpoints)
        throw Error("cannot tetrahedralize " + name +
                    ": TetGen produced no tetrahedra (is the surface closed?)");
    mesh.surface_vertex_count = mesh.vertices.size();
    for (int i = in.numberofpoints; i < out.numberofpoints; ++i)
        mesh.vertices.emplace_back(float(out.pointlist[3 * i]), float(out.pointlist[3 * i + 1]),
                                   float(out.pointlist[3 * i + 2]));
    mesh.tets.resize(size_t(out.numberoftetrahedra));
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
        for (int k = 0; k < 4; ++k)
            mesh.tets[t][k] = uint32_t(out.tetrahedronlist[4 * t + k]);
        // Positive orientation, whatever TetGen's convention.
        if (mesh.volume(t) < 0.0) std::swap(mesh.tets[t][0], mesh.tets[t][1]);
    }
    return mesh;
}

TetLocator::TetLocator(const TetMesh& mesh) {
    lo_ = Vec3f(Infinity);
    Vec3f hi(-Infinity);
    for (const Vec3f& p : mesh.vertices) {
        lo_ = min(lo_, p);
        hi = max(hi, p);
    }
    const Vec3f extent = max(hi - lo_, Vec3f(1e-6f));
    const float largest = std::max({extent.x, extent.y, extent.z});
    // About one tet per cell, the cells as cubic as the box allows.
    const float per_axis = std::cbrt(float(mesh.tets.size()));
    for (int k = 0; k < 3; ++k)
        res_[k] = std::clamp(int(std::ceil(per_axis * extent[k] / largest)), 1, 128);
    cell_size_ = extent / Vec3f(float(res_.x), float(res_.y), float(res_.z));
    const auto cell_of = [&](const Vec3f& p, int k) {
        return std::clamp(int((p[k] - lo_[k]) / cell_size_[k]), 0, res_[k] - 1);
    };
    std::vector<std::array<int, 6>> ranges(mesh.tets.size());
    cell_start_.assign(size_t(res_.x) * res_.y * res_.z + 1, 0);
    frames_.resize(mesh.tets.size());
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
        const auto& v = mesh.tets[t];
        Vec3f a = mesh.vertices[v[0]], b = a;
        for (int j = 1; j < 4; ++j) {
            a = min(a, mesh.vertices[v[j]]);
            b = max(b, mesh.vertices[v[j]]);
        }
        for (int k = 0; k < 3; ++k) {
            ranges[t][k] = cell_of(a, k);
            ranges[t][k + 3] = cell_of(b, k);
        }
        for (int z = ranges[t][2]; z <= ranges[t][5]; ++z)
            for (int y = ranges[t][1]; y <= ranges[t][4]; ++y)
                for (int x = ranges[t][0]; x <= ranges[t][3]; ++x)
                    ++cell_start_[size_t((z * res_.y + y) * res_.x + x) + 1];
        // Barycentrics (u, v, w) of [a-d, b-d, c-d]^-1 (p - d); the 4th is 1 - u - v - w.
        const Vec3d d(mesh.vertices[v[3]]);
        const Vec3d e[3] = {Vec3d(mesh.vertices[v[0]]) - d, Vec3d(mesh.vertices[v[1]]) - d,
                            Vec3d(mesh.vertices[v[2]]) - d};
        const double inv_det = 1.0 / det3(e[0], e[1], e[2]);
        frames_[t].origin = mesh.vertices[v[3]];
        frames_[t].inverse[0] = Vec3f(cross(e[1], e[2]) * inv_det);
        frames_[t].inverse[1] = Vec3f(cross(e[2], e[0]) * inv_det);
        frames_[t].inverse[2] = Vec3f(cross(e[0], e[1]) * inv_det);
    }
    for (size_t c = 1; c < cell_start_.size(); ++c)
        cell_start_[c] += cell_start_[c - 1];
    cell_tets_.resize(cell_start_.back());
    std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (size_t t = 0; t < mesh.tets.size(); ++t)
        for (int z = ranges[t][2]; z <= ranges[t][5]; ++z)
            for (int y = ranges[t][1]; y <= ranges[t][4]; ++y)
                for (int x = ranges[t][0]; x <= ranges[t][3]; ++x)
                    cell_tets_[fill[size_t((z * res_.y + y) * res_.x + x)]++] = uint32_t(t);
}

std::optional<TetLocator::Location> TetLocator::locate(const Vec3f& p) const {
    int c[3];
    for (int k = 0; k < 3; ++k) {
        const float s = (p[k] - lo_[k]) / cell_size_[k];
        if (!(s >= -1e-4f && s <= float(res_[k]) + 1e-4f)) return std::nullopt;
        c[k] = std::clamp(int(s), 0, res_[k] - 1);
    }
    const size_t cell = size_t((c[2] * res_.y + c[1]) * res_.x + c[0]);
    // The tet whose smallest barycentric is largest: the containing one, or the nearest across a face when p
    // lies on it up to rounding.
    std::optional<Location> best;
    float best_min = -1e-4f;
    for (uint32_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
        const Frame& f = frames_[cell_tets_[i]];
        const Vec3f q = p - f.origin;
        const float u = dot(f.inverse[0], q), v = dot(f.inverse[1], q), w = dot(f.inverse[2], q);
        const std::array<float, 4> bary = {u, v, w, 1.f - u - v - w};
        const float smallest = std::min({bary[0], bary[1], bary[2], bary[3]});
        if (smallest > best_min) {
            best_min = smallest;
            best = Location{cell_tets_[i], bary};
            if (smallest >= 0.f) break;
        }
    }
    return best;
}

} // namespace penumbra
