// A scene's parameters as named arrays of values (Mitsuba 3's `mi.traverse(scene)`), for the Python module:
// the Data parameters of diff/parameters.h under their traverse() keys, and the geometric motions as values
// too, all relative to the scene as loaded (value 0):
//   <shape|instance>.translate [3]  t, world units
//   <shape|instance>.rotate    [3]  r, a rotation vector (radians) about the reference bounding-box center c0
//   <shape|instance>.scale     [1]  s, uniform:  x = c0 + t + (1 + s) R(r) (x0 − c0),  n = R(r) n0
//   <sensor>.translate / .rotate, <emitter>.translate / .rotate   the same about their reference position
//                                   (no scale; directional lights and envmaps rotate only)
// Derivatives are taken by Parameters' motions at the current pose (paper 001 §4.1): a change dt is the
// translate motion; dr is the rotation ω = J_l(r) dr (diff/pose.h) about the current center c0 + t; ds is
// the scale motion about c0 + t by ds / (1 + s). So dL/dt = g_t, dL/dr = J_l(r)ᵀ g_ω, dL/ds = g_s / (1 + s).
#pragma once
#include "diff/parameters.h"
#include "diff/pose.h"

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

class ParameterTable {
  public:
    struct Entry {
        std::string name;
        std::vector<int> shape; // {3}, {1}, {N, 3} (vertex positions), {H, W, 3} (images)
        bool motion = false;
        bool geometry = false; // changing it moves geometry (the BVH is rebuilt)
    };

    explicit ParameterTable(Scene& scene);
    ~ParameterTable();
    ParameterTable(const ParameterTable&) = delete;
    ParameterTable& operator=(const ParameterTable&) = delete;

    const std::vector<Entry>& entries() const { return entries_; }
    // The entry's index; throws Parameters::find's error (with suggestions) for an unknown name. A constant's
    // `<owner>.<param>.value` may be named without `.value`.
    int find(const std::string& name) const;
    // The entry's values: as last set (staged or applied); motions: the pose's t, r or s.
    std::vector<float> get(int entry) const;
    // Stages the entry's values (all of them); throws Error naming the entry on a wrong count, a non-finite
    // value or a scale s <= -1.
    void set(int entry, const float* values, size_t count);
    // Writes the staged values into the scene: Data values, poses applied to the reference meshes / sensor /
    // emitter transforms; the BVH is rebuilt once if geometry moved. The selection is made again at the new
    // values. Throws Error if a shape's vertex_positions would be combined with a non-zero pose.
    void apply();

    // Reverse mode: differentiate with respect to these entries at the current (applied) values.
    void select(const std::vector<int>& entries);
    // Forward mode: a direction per entry in its value space (as many values as the entry has).
    void select(const std::vector<std::pair<int, std::vector<float>>>& directions);
    Parameters& parameters() { return *params_; }
    // A gradient in parameters()' enabled layout mapped to each selected entry's value space (selection
    // order).
    std::vector<std::vector<double>> chain(const std::vector<double>& raw) const;

  private:
    // A pose's values: translation, rotation vector, scale.
    struct PoseValues {
        Vec3d t{0.0}, r{0.0};
        double s = 0.0;
        bool zero() const { return t == Vec3d(0.0) && r == Vec3d(0.0) && s == 0.0; }
        bool operator==(const PoseValues& o) const { return t == o.t && r == o.r && s == o.s; }
    };
    struct Pose;
    struct Item {
        const Parameter* param;
        int pose = -1; // motions: index into poses_
    };
    struct Selected {
        int entry;
        int offset; // first index in parameters()' layout
    };
    const Entry& entry(int index) const; // throws Error for an index out of range
    int size(int entry) const;
    Pose& pose_of(int entry) const;
    std::vector<Shape*> deformed_by(const Parameter& p) const;
    std::vector<PoseValues> pose_values() const;
    void check(const std::vector<PoseValues>& values, std::vector<const Shape*> deformed,
               const std::vector<int>& selected) const;
    void enable(const std::vector<std::pair<int, std::vector<float>>>& directions, bool forward);

    Scene& scene_;
    std::unique_ptr<Parameters> params_;
    std::vector<Entry> entries_;
    std::vector<Item> items_;
    std::vector<std::unique_ptr<Pose>> poses_;
    std::map<int, std::vector<float>> staged_;
    std::vector<const Shape*> deformed_; // shapes whose vertex_positions were set
    std::vector<std::pair<int, std::vector<float>>> selection_;
    bool forward_ = false;
    std::vector<Selected> selected_;
};

} // namespace penumbra
