// The views of a multi-view optimization (docs/optimize.md, "Multi-view"): each view is one of the scene's
// sensors (by index or id), optionally placed at a camera pose (Mitsuba's look_at: origin, target, up), with
// its own target (an image, or the scene rendered at the true values). An iteration renders and
// differentiates every view, or a random subset of them, and averages the losses and gradients:
//   L(θ) = (1/|S|) Σ_{v ∈ S} L_v(I_v(θ), T_v),   dL/dθ = (1/|S|) Σ_{v ∈ S} Σ_pixels ∂L_v/∂I_v · dI_v/dθ,
// with S ⊆ views drawn uniformly without replacement per iteration, so that E_S[L] is the mean over all
// views.
#pragma once
#include "core/vector.h"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace penumbra {

class Scene;
class Sensor;
struct Transform;

struct CameraPose {
    Vec3f origin, target, up;
};

struct ViewSpec {
    std::string name;   // log and file names: given, else "pose<i>" (a look_at), the sensor's id or "view<i>"
    std::string sensor; // the scene's sensor: an index or an id (empty: the scene's default)
    std::optional<CameraPose> pose; // replaces the sensor's to_world while the view is rendered
    std::string target_image;       // resolved path, or empty: rendered from the true values
};

// Parses "views" (a non-empty array of {"sensor": id | index, "look_at": {"origin", "target", "up"}, "image":
// path, "name": string}, at least one of sensor and look_at per view); paths resolve against `base_dir`.
// Unknown keys and wrong types throw Error naming `source` and the key.
std::vector<ViewSpec> parse_views(const nlohmann::json& json, const std::string& base_dir,
                                  const std::string& source);

// Puts a scene's sensors in the configuration of one view at a time; restores the selected sensor and every
// sensor's to_world when destroyed.
class ViewSelector {
  public:
    // Resolves every view's sensor now: an unknown sensor throws Error naming the view and the scene's
    // sensors. Views must have distinct names.
    ViewSelector(Scene& scene, std::vector<ViewSpec> views);
    ~ViewSelector();
    ViewSelector(const ViewSelector&) = delete;
    ViewSelector& operator=(const ViewSelector&) = delete;

    size_t size() const { return views_.size(); }
    const ViewSpec& view(size_t i) const { return views_.at(i); }
    // Makes view i the scene's rendered sensor (at its pose).
    void select(size_t i);
    // The film size of view i.
    int width(size_t i) const;
    int height(size_t i) const;

  private:
    Scene& scene_;
    std::vector<ViewSpec> views_;
    std::vector<std::shared_ptr<Sensor>> sensors_; // per view
    std::shared_ptr<Sensor> saved_selection_;
    std::vector<std::unique_ptr<Transform>> saved_to_world_; // per scene sensor
};

// The views of iteration `iteration`: all of them (per_iteration 0 or ≥ count), else per_iteration distinct
// views drawn uniformly (a partial Fisher-Yates shuffle seeded by seed and iteration), in increasing order.
std::vector<size_t> views_of_iteration(size_t count, int per_iteration, uint64_t seed, int iteration);

} // namespace penumbra
