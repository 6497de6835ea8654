// `Var`: the AD scalar of penumbra's differentiable estimators. Operations are recorded on a per-thread tape
// (a Wengert list of nodes with up to two inputs and their local partials); the tape is cleared after every
// path, so memory is bounded by one path's length whatever the sample count. The same tape serves both modes:
//   - reverse mode: a backward sweep propagates adjoints from outputs to parameter leaves (gradient), and
//   - forward mode: a forward sweep propagates tangents from parameter leaves (a direction) to outputs.
// Constants (id < 0) record nothing, so code evaluated with Var costs only where parameters flow.
#pragma once
#include "core/math.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace penumbra {

class Tape {
public:
    struct Node {
        int32_t a, b;   // input node ids (-1: none)
        float da, db;   // local partials d(node)/d(a), d(node)/d(b)
    };
    struct Leaf {
        int32_t node;
        int32_t param; // index into the parameter vector
    };

    static Tape& current() {
        thread_local Tape tape;
        return tape;
    }
    int32_t push(int32_t a, float da, int32_t b = -1, float db = 0.f) {
        nodes_.push_back({a, b, da, db});
        return int32_t(nodes_.size() - 1);
    }
    int32_t leaf(int32_t param) {
        const int32_t id = push(-1, 0.f);
        leaves_.push_back({id, param});
        return id;
    }
    void clear() {
        nodes_.clear();
        leaves_.clear();
    }
    size_t size() const { return nodes_.size(); }
    size_t leaf_count() const { return leaves_.size(); }
    // Drops what was recorded after the tape had `nodes` nodes and `leaves` leaves (a scratch computation).
    void rewind(size_t nodes, size_t leaves) {
        nodes_.resize(nodes);
        leaves_.resize(leaves);
    }

    // Forward mode: the tangent of every node for the parameter-space direction `direction` (tangent[id]).
    void forward(const float* direction, std::vector<float>& tangent) const {
        tangent.assign(nodes_.size(), 0.f);
        for (const Leaf& l : leaves_) tangent[l.node] = direction[l.param];
        for (size_t i = 0; i < nodes_.size(); ++i) {
            const Node& n = nodes_[i];
            if (n.a < 0) continue; // a leaf
            tangent[i] = n.da * tangent[n.a] + (n.b >= 0 ? n.db * tangent[n.b] : 0.f);
        }
    }
    // Reverse mode: propagates the adjoints `seeds` (node, adjoint) back to the leaves and adds them to
    // gradient[param]; adds nothing and returns false when a leaf's adjoint is not finite (the NaN policy: the
    // sample is dropped and counted by the caller).
    bool backward(const std::vector<std::pair<int32_t, float>>& seeds, double* gradient, std::vector<float>& adjoint) const {
        adjoint.assign(nodes_.size(), 0.f);
        for (const auto& [node, a] : seeds)
            if (node >= 0) adjoint[node] += a;
        for (size_t i = nodes_.size(); i-- > 0;) {
            const float a = adjoint[i];
            if (a == 0.f) continue;
            const Node& n = nodes_[i];
            if (n.a >= 0) adjoint[n.a] += a * n.da;
            if (n.b >= 0) adjoint[n.b] += a * n.db;
        }
        for (const Leaf& l : leaves_)
            if (!std::isfinite(adjoint[l.node])) return false;
        for (const Leaf& l : leaves_) gradient[l.param] += adjoint[l.node];
        return true;
    }
    const std::vector<Node>& nodes() const { return nodes_; }
    const std::vector<Leaf>& leaves() const { return leaves_; }

private:
    std::vector<Node> nodes_;
    std::vector<Leaf> leaves_;
};

struct Var {
    float v = 0.f;
    int32_t id = -1; // tape node, or -1 for a constant

    Var() = default;
    Var(float value) : v(value) {} // NOLINT: constants convert implicitly
    Var(double value) : v(float(value)) {}
    Var(int value) : v(float(value)) {}
    Var(float value, int32_t node) : v(value), id(node) {}

    // A differentiable parameter with the given value and index in the parameter vector.
    static Var parameter(float value, int32_t param) { return Var(value, Tape::current().leaf(param)); }
    bool is_constant() const { return id < 0; }

    Var& operator+=(const Var& o) { return *this = *this + o; }
    Var& operator-=(const Var& o) { return *this = *this - o; }
    Var& operator*=(const Var& o) { return *this = *this * o; }
    Var& operator/=(const Var& o) { return *this = *this / o; }

    friend Var operator-(const Var& a) { return unary(-a.v, a, -1.f); }
    friend Var operator+(const Var& a, const Var& b) { return binary(a.v + b.v, a, 1.f, b, 1.f); }
    friend Var operator-(const Var& a, const Var& b) { return binary(a.v - b.v, a, 1.f, b, -1.f); }
    friend Var operator*(const Var& a, const Var& b) { return binary(a.v * b.v, a, b.v, b, a.v); }
    friend Var operator/(const Var& a, const Var& b) {
        const float inv = 1.f / b.v;
        return binary(a.v * inv, a, inv, b, -a.v * inv * inv);
    }
    friend bool operator<(const Var& a, const Var& b) { return a.v < b.v; }
    friend bool operator>(const Var& a, const Var& b) { return a.v > b.v; }
    friend bool operator<=(const Var& a, const Var& b) { return a.v <= b.v; }
    friend bool operator>=(const Var& a, const Var& b) { return a.v >= b.v; }
    friend bool operator==(const Var& a, const Var& b) { return a.v == b.v; }
    friend bool operator!=(const Var& a, const Var& b) { return a.v != b.v; }

    // y = f(a) with dy/da = d.
    static Var unary(float y, const Var& a, float d) {
        if (a.id < 0) return Var(y);
        return Var(y, Tape::current().push(a.id, d));
    }
    static Var binary(float y, const Var& a, float da, const Var& b, float db) {
        if (a.id < 0 && b.id < 0) return Var(y);
        if (a.id < 0) return Var(y, Tape::current().push(b.id, db));
        if (b.id < 0) return Var(y, Tape::current().push(a.id, da));
        return Var(y, Tape::current().push(a.id, da, b.id, db));
    }
};

inline float detach(const Var& x) { return x.v; }

// Elementary functions (found by ADL from templated physics code that says `using std::sqrt; sqrt(x)`).
inline Var sqrt(const Var& x) {
    const float y = std::sqrt(x.v);
    return Var::unary(y, x, y > 0.f ? 0.5f / y : 0.f);
}
inline Var abs(const Var& x) { return Var::unary(std::abs(x.v), x, x.v >= 0.f ? 1.f : -1.f); }
inline Var fabs(const Var& x) { return abs(x); }
inline Var exp(const Var& x) {
    const float y = std::exp(x.v);
    return Var::unary(y, x, y);
}
inline Var log(const Var& x) { return Var::unary(std::log(x.v), x, 1.f / x.v); }
inline Var sin(const Var& x) { return Var::unary(std::sin(x.v), x, std::cos(x.v)); }
inline Var cos(const Var& x) { return Var::unary(std::cos(x.v), x, -std::sin(x.v)); }
inline Var tan(const Var& x) {
    const float c = std::cos(x.v);
    return Var::unary(std::tan(x.v), x, 1.f / (c * c));
}
inline Var asin(const Var& x) { return Var::unary(std::asin(x.v), x, 1.f / std::sqrt(std::max(1e-12f, 1.f - x.v * x.v))); }
inline Var acos(const Var& x) {
    return Var::unary(std::acos(x.v), x, -1.f / std::sqrt(std::max(1e-12f, 1.f - x.v * x.v)));
}
inline Var atan(const Var& x) { return Var::unary(std::atan(x.v), x, 1.f / (1.f + x.v * x.v)); }
inline Var atan2(const Var& y, const Var& x) {
    const float r2 = x.v * x.v + y.v * y.v;
    const float inv = r2 > 0.f ? 1.f / r2 : 0.f;
    return Var::binary(std::atan2(y.v, x.v), y, x.v * inv, x, -y.v * inv);
}
inline Var pow(const Var& x, const Var& e) {
    const float y = std::pow(x.v, e.v);
    const float dx = e.v == 0.f ? 0.f : e.v * std::pow(x.v, e.v - 1.f);
    const float de = x.v > 0.f ? y * std::log(x.v) : 0.f;
    return Var::binary(y, x, dx, e, de);
}
inline Var erf(const Var& x) {
    return Var::unary(std::erf(x.v), x, 2.f / std::sqrt(Pi) * std::exp(-x.v * x.v));
}
inline Var copysign(const Var& x, const Var& s) {
    const float sign = std::signbit(x.v) == std::signbit(s.v) ? 1.f : -1.f;
    return Var::unary(std::copysign(x.v, s.v), x, sign);
}
inline Var min(const Var& a, const Var& b) { return a.v <= b.v ? a : b; }
inline Var max(const Var& a, const Var& b) { return a.v >= b.v ? a : b; }
inline Var fmin(const Var& a, const Var& b) { return min(a, b); }
inline Var fmax(const Var& a, const Var& b) { return max(a, b); }
inline bool isfinite(const Var& x) { return std::isfinite(x.v); }
inline bool isnan(const Var& x) { return std::isnan(x.v); }
inline bool signbit(const Var& x) { return std::signbit(x.v); }
inline Var floor(const Var& x) { return Var(std::floor(x.v)); } // piecewise constant: zero derivative

} // namespace penumbra
