#include "diff/psdr/edge_tree.h"

#include <algorithm>
#include <limits>

namespace penumbra {

namespace {

// The angle between unit vectors, robustly.
float angle_between(const Vec3f& a, const Vec3f& b) { return 2.f * std::atan2(norm(a - b), norm(a + b)); }

constexpr int Pieces = EdgeTree::Pieces;

} // namespace

EdgeViewer::EdgeViewer(const SurfaceInteraction3f& at, const Vec3f& toward) : si(at) {
    si.wi = si.to_local(toward);
    normal = si.sh_frame.n;
    mirror = reflect(toward, normal);
    if (!si.bsdf()) return;
    constexpr float Step = 0.05f;
    peak = lobe(mirror);
    // A direction Step from m, toward the normal (or across it at normal incidence).
    Vec3f across = normal - mirror * dot(normal, mirror);
    if (!(norm(across) > 1e-3f)) across = si.sh_frame.s;
    across = normalize(across - mirror * dot(across, mirror));
    const float beside = lobe(mirror * std::cos(Step) + across * std::sin(Step));
    // (1 + Step² / 2w)² = peak / beside.
    if (peak > beside && beside > 0.f) width2 = Step * Step / (2.f * (std::sqrt(peak / beside) - 1.f));
    if (angle_between(mirror, normal) > 0.5f) diffuse = lobe(normal);
}

float EdgeViewer::lobe(const Vec3f& d) const {
    const Color3f f = si.bsdf()->eval(BSDFContext{}, si, si.to_local(d));
    return std::max(0.f, f.x + f.y + f.z);
}

float EdgeViewer::cone_lobe(const Vec3f& axis, float half) const {
    float glossy = peak;
    if (width2 > 0.f) {
        const float v = width2 + 0.5f * half * half, phi = angle_between(axis, mirror);
        const float t = 1.f + 0.5f * phi * phi / v;
        glossy = peak * width2 / v / (t * t);
    }
    const float to_normal = std::max(0.f, angle_between(axis, normal) - half);
    return glossy + diffuse * std::max(0.f, std::cos(to_normal));
}

EdgeTree::EdgeTree(const SceneEdges& edges) : edges_(edges), leaf_of_(edges.edges.size(), -1) {
    std::vector<uint32_t> order = edges.all.indices;
    if (order.empty()) return;
    nodes_.reserve(2 * order.size());
    build(order, 0, order.size(), -1);
}

int32_t EdgeTree::build(std::vector<uint32_t>& order, size_t begin, size_t end, int32_t parent) {
    const auto endpoints = [&](uint32_t i) {
        const SceneEdges::SceneEdge& se = edges_.edges[i];
        const TriangleMesh& m = se.shape->mesh;
        return std::pair{m.positions[se.edge.v0], m.positions[se.edge.v1]};
    };
    const int32_t id = int32_t(nodes_.size());
    nodes_.emplace_back();
    Node node;
    node.parent = parent;
    node.lo = Vec3f(std::numeric_limits<float>::infinity());
    node.hi = Vec3f(-std::numeric_limits<float>::infinity());
    Vec3f c_lo = node.lo, c_hi = node.hi; // bounds of the edges' midpoints
    for (size_t k = begin; k < end; ++k) {
        const auto [a, b] = endpoints(order[k]);
        node.lo = min(node.lo, min(a, b));
        node.hi = max(node.hi, max(a, b));
        c_lo = min(c_lo, (a + b) * 0.5f);
        c_hi = max(c_hi, (a + b) * 0.5f);
        node.length += norm(b - a);
        node.centroid += (a + b) * (0.5f * norm(b - a));
    }
    node.centroid = node.length > 0.f ? node.centroid / node.length : (node.lo + node.hi) * 0.5f;
    // The length-weighted RMS distance of the edges' endpoints from the centroid.
    float moment = 0.f;
    for (size_t k = begin; k < end; ++k) {
        const auto [a, b] = endpoints(order[k]);
        moment += 0.5f * norm(b - a) * (squared_norm(a - node.centroid) + squared_norm(b - node.centroid));
    }
    node.spread = node.length > 0.f ? std::sqrt(moment / node.length) : 0.f;
    if (end - begin == 1) {
        node.edge = order[begin];
        leaf_of_[node.edge] = id;
    } else {
        const Vec3f extent = c_hi - c_lo;
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
        // The spatial middle of the midpoints' bounds (objects apart stay apart), else the median.
        const float split = 0.5f * (c_lo[axis] + c_hi[axis]);
        const auto below = [&](uint32_t i) {
            const auto [a, b] = endpoints(i);
            return (a + b)[axis] * 0.5f < split;
        };
        size_t mid = size_t(std::partition(order.begin() + long(begin), order.begin() + long(end), below) -
                            order.begin());
        if (mid == begin || mid == end) {
            mid = begin + (end - begin) / 2;
            std::nth_element(order.begin() + long(begin), order.begin() + long(mid),
                             order.begin() + long(end), [&](uint32_t i, uint32_t j) {
                                 const auto [a0, b0] = endpoints(i);
                                 const auto [a1, b1] = endpoints(j);
                                 return (a0 + b0)[axis] < (a1 + b1)[axis];
                             });
        }
        node.left = build(order, begin, mid, id);
        node.right = build(order, mid, end, id);
    }
    nodes_[size_t(id)] = node;
    return id;
}

float EdgeTree::leaf_pieces(const EdgeViewer& viewer, const Node& leaf, std::array<float, Pieces>& w) const {
    // The edge's angular length seen from x times the lobe, piece by piece (a glossy lobe can be narrower
    // than an edge).
    const SceneEdges::SceneEdge& se = edges_.edges[leaf.edge];
    const TriangleMesh& m = se.shape->mesh;
    const Vec3f a = m.positions[se.edge.v0], b = m.positions[se.edge.v1];
    const Vec3f x = viewer.si.p;
    float total = 0.f;
    for (int k = 0; k < Pieces; ++k) {
        const Vec3f to = a + (b - a) * ((float(k) + 0.5f) / Pieces) - x;
        const float r = norm(to);
        w[size_t(k)] = 0.f;
        if (!(r > 0.f)) continue;
        const Vec3f d = to / r;
        if (k == 0 && !grazes(se, d)) return 0.f;
        w[size_t(k)] = norm(cross(b - a, d)) / (r * r * Pieces) * viewer.lobe(d);
        total += w[size_t(k)];
    }
    return std::isfinite(total) ? total : 0.f;
}

float EdgeTree::importance(const EdgeViewer& viewer, const Node& node) const {
    if (node.left < 0) {
        std::array<float, Pieces> w;
        return leaf_pieces(viewer, node, w);
    }
    // A cluster: the lobe model toward its centroid, blurred by its angular spread, over the squared distance
    // (a cluster around x: its spread).
    const Vec3f& x = viewer.si.p;
    const Vec3f to = node.centroid - x;
    const float d = norm(to);
    if (!(d > node.spread))
        return node.length * viewer.cone_lobe(viewer.mirror, Pi) /
               std::max(node.spread * node.spread, 1e-12f);
    return node.length * viewer.cone_lobe(to / d, std::atan(node.spread / d)) / (d * d);
}

float EdgeTree::choice(const EdgeViewer& viewer, const Node& parent, int32_t child) const {
    const float il = importance(viewer, nodes_[size_t(parent.left)]),
                ir = importance(viewer, nodes_[size_t(parent.right)]);
    const float sum = il + ir;
    if (!(sum > 0.f) || !std::isfinite(sum)) return 0.f;
    return (child == parent.left ? il : ir) / sum;
}

EdgePoint EdgeTree::sample(const EdgeViewer& viewer, float u_edge, float u_point, float& pdf) const {
    pdf = 0.f;
    EdgePoint out{};
    if (nodes_.empty()) return out;
    int32_t id = 0;
    float p = 1.f;
    while (nodes_[size_t(id)].left >= 0) {
        const Node& node = nodes_[size_t(id)];
        const float pl = choice(viewer, node, node.left);
        const float pr = choice(viewer, node, node.right);
        if (!(pl + pr > 0.f)) return out;
        if (u_edge < pl) {
            u_edge = std::min(u_edge / pl, 0x1.fffffep-1f);
            id = node.left;
            p *= pl;
        } else {
            u_edge = std::min((u_edge - pl) / pr, 0x1.fffffep-1f);
            id = node.right;
            p *= pr;
        }
    }
    const Node& leaf = nodes_[size_t(id)];
    std::array<float, Pieces> w;
    const float total = leaf_pieces(viewer, leaf, w);
    if (!(total > 0.f) || !(p > 0.f)) return out;
    // The piece by its weight, the point uniform on it.
    int k = 0;
    float target = u_point * total;
    while (k < Pieces - 1 && (target >= w[size_t(k)] || w[size_t(k)] == 0.f))
        target -= w[size_t(k++)];
    if (!(w[size_t(k)] > 0.f)) return out;
    const float within = std::clamp(target / w[size_t(k)], 0.f, 0x1.fffffep-1f);
    out.edge = &edges_.edges[leaf.edge];
    const TriangleMesh& m = out.edge->shape->mesh;
    out.tau = (float(k) + within) / Pieces;
    out.a = m.positions[out.edge->edge.v0];
    out.b = m.positions[out.edge->edge.v1];
    out.p = out.a + (out.b - out.a) * out.tau;
    pdf = p * w[size_t(k)] / total * Pieces / leaf.length;
    return out;
}

float EdgeTree::pdf(const EdgeViewer& viewer, const EdgePoint& x_b) const {
    const auto edge = size_t(x_b.edge - edges_.edges.data());
    if (edge >= leaf_of_.size() || leaf_of_[edge] < 0) return 0.f;
    int32_t id = leaf_of_[edge];
    const Node& leaf = nodes_[size_t(id)];
    std::array<float, Pieces> w;
    const float total = leaf_pieces(viewer, leaf, w);
    const int k = std::clamp(int(x_b.tau * Pieces), 0, Pieces - 1);
    if (!(total > 0.f) || !(w[size_t(k)] > 0.f)) return 0.f;
    float p = w[size_t(k)] / total * Pieces / leaf.length;
    while (nodes_[size_t(id)].parent >= 0) {
        const Node& parent = nodes_[size_t(nodes_[size_t(id)].parent)];
        p *= choice(viewer, parent, id);
        if (!(p > 0.f)) return 0.f;
        id = nodes_[size_t(id)].parent;
    }
    return p;
}

} // namespace penumbra
