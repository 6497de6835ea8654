// Inverse rendering: recover material and emitter parameters and the poses of shapes from a target image by
// Adam on the gradient of an image loss (interior term, diff/psdr/interior.h, or the psdr total with the boundary
// terms, diff/psdr/psdr.h). Driven by a JSON configuration (docs/optimize.md):
//
//   scene           string     scene file, relative to the configuration file
//   defines         object     <default> overrides, name → string or number
//   parameters      object     name → {"init": number | [values], "lr": number,
//                              "bounds": [lo | null, hi | null]} ("init" defaults to the scene's value,
//                              "bounds" to none). A pose is "<shape>.translate" (3 values, world units)
//                              and/or "<shape>.rotate" (a rotation vector in degrees about the shape's
//                              bounding-box center, no bounds), both relative to the scene's pose
//                              (optim/problem.h); "<shape>.deform@cx,cy,cz" a deformation handle at c (3
//                              values, its displacement, world units; several per shape, not with a pose;
//                              optim/deformation.h). "free": [bool, ...] the optimized components (one per
//                              component, or 3 for a vertex_positions: x, y, z of every vertex).
//                              "parameterization": {"type": "large_steps", "lambda": λ (default 19),
//                              "uniform_adam": bool (default true)}: a <shape>.vertex_positions stepped in
//                              u = (I + λL) x (optim/large_steps.h; no bounds, "free" of 3 only), by Adam
//                              with one second moment for the whole mesh (optim/adam.h) unless uniform_adam
//                              is false. "init" (and a target value) of a vertex_positions may be a mesh file
//                              (.ply/.obj, relative to the configuration, same vertex count and order): its
//                              positions as stored
//   target          object     {"image": path relative to the configuration}  or
//                              {"values": {name → number | [values] | mesh}, "spp": int}: the same scene with
//                              these values of optimized parameters (the others keep the scene's), rendered
//                              at start (for every view); absent when every view has its "image"
//   views           array      several views (optim/views.h; default: the scene's sensor alone), each
//                              {"sensor": id | index, "look_at": {"origin": [x,y,z], "target": [x,y,z],
//                              "up": [x,y,z]}, "image": target path, "name": string}: a sensor of the scene,
//                              or a camera pose (of the given sensor, default the scene's first: its
//                              intrinsics and film), or both; "image" in every view or in none
//   views_per_iteration int    views rendered and differentiated per iteration, drawn at random without
//                              replacement (0 = all; default 0); loss and gradient are the mean over them
//   method          string     "auto" (default: psdr when a pose is optimized, else interior) or any
//                              derivative method (diff/method.h: psdr, interior, paths, ...); "interior" with
//                              a pose is an error (it has no silhouette or shadow term)
//   options         object     the method's options, name → value as on the command line without dashes
//                              ({"first-vertex": "material", "q": 0.3}; '_' may replace '-')
//   primary_spp     int        psdr: primary boundary samples per pixel (0 disables the term)
//   direct_spp      int        psdr: direct boundary samples per pixel (0 disables the term)
//   indirect_spp    int        psdr: indirect boundary samples per pixel and technique (0 disables it)
//                              With none of the three, gradient_spp is the psdr total's budget, split over
//                              the terms by a calibration pass at the first iteration (diff/psdr/budget.h); with
//                              any of them, the others default to 4 and the interior gets gradient_spp.
//   loss            string     "l2" (default) | "rel_l2" | "matching" (paper 003 Eq. 25, methods dpm-g/dpm-c)
//   iterations      int        number of Adam steps
//   spp             int        samples per pixel of the primal image of each iteration
//   gradient_spp    int        samples per pixel of the gradient (see primary_spp), independent of the
//                              primal's
//   seed            int        base seed (default 0)
//   output          string     output directory (default "optimize_out"), relative to the working directory
//   snapshot_every  int        write iter_NNNN.png (several views: iter_NNNN_<view>.png) every N iterations
//                              (0 = never; default 10)
//   lr_decay        number     learning-rate factor reached at the last iteration, decayed exponentially
//                              (default 1: constant rates)
//   threads         int        worker threads (0 = all; default 0)
#pragma once
#include "core/image_loss.h"
#include "diff/method.h"
#include "optim/problem.h"
#include "optim/views.h"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace penumbra {

struct OptimizeConfig {
    std::string scene; // resolved path
    std::map<std::string, std::string> defines;
    std::vector<OptimizedParameter> parameters;
    std::string target_image; // resolved path, or empty for a rendered target (or the views' images)
    std::map<std::string, std::vector<float>> target_values;
    int target_spp = 1024;
    std::string method = "auto";  // "auto" or a registered derivative method (diff/method.h)
    MethodOptions method_options; // its options (including the psdr budget keys above)
    LossKind loss = LossKind::L2;
    int iterations = 100;
    int spp = 16, gradient_spp = 16;
    uint64_t seed = 0;
    std::string output = "optimize_out";
    int snapshot_every = 10;
    double lr_decay = 1.0;
    int threads = 0;
    std::vector<ViewSpec> views; // empty: the scene's sensor
    int views_per_iteration = 0; // 0: all
};

// Parses a configuration; relative paths resolve against `base_dir`. Unknown keys and wrong types throw Error
// naming `source` and the key.
OptimizeConfig parse_optimize_config(const nlohmann::json& json, const std::string& base_dir,
                                     const std::string& source = "<config>");
OptimizeConfig load_optimize_config(const std::string& path);

struct IterationRecord {
    int iteration = 0;
    double loss = 0;
    // ‖θ − θ*‖ / ‖θ*‖ over the Data parameters; the largest translation error (scene units) and rotation
    // error (degrees) over the poses. NaN when θ* is unknown or there is no such parameter.
    double parameter_error = std::numeric_limits<double>::quiet_NaN();
    double translation_error = std::numeric_limits<double>::quiet_NaN();
    double rotation_error = std::numeric_limits<double>::quiet_NaN();
    double seconds = 0; // since the loop started
    uint64_t dropped_samples = 0; // gradient samples left out for a non-finite value (the NaN policy)
};

struct ParameterResult {
    std::string name;
    std::vector<double> initial, final, truth;                        // truth empty when unknown
    double relative_error = std::numeric_limits<double>::quiet_NaN(); // Data: ‖final − truth‖ / ‖truth‖
    // translate: ‖t − t*‖ (scene units); rotate: the angle of R R*ᵀ (degrees)
    double pose_error = std::numeric_limits<double>::quiet_NaN();
};

// A <shape>.vertex_positions against its known target (optim/shape_metrics.h), at the start and the end.
struct ShapeResult {
    std::string name;
    double initial_vertex_error = 0, final_vertex_error = 0; // mean ‖x_i − x*_i‖ (scene units)
    double initial_chamfer = 0, final_chamfer = 0;           // symmetric Chamfer distance of the vertex sets
};

struct OptimizeResult {
    std::vector<IterationRecord> history;
    std::vector<ParameterResult> parameters;
    double final_parameter_error = std::numeric_limits<double>::quiet_NaN();
    double final_translation_error = std::numeric_limits<double>::quiet_NaN();
    double final_rotation_error = std::numeric_limits<double>::quiet_NaN();
    std::string method;      // the method used
    std::string description; // the method's description of its first gradient (psdr: the calibrated budget)
    double target_seconds = 0, seconds = 0;
    std::vector<ShapeResult> shapes; // vertex_positions parameters with a known target
    double peak_memory_mb = 0;       // the process's peak resident set (getrusage), at the end
};

// Runs the optimization; writes log.csv, snapshots, final.png (several views: final_<view>.png), loss.png,
// result.json and, for each vertex_positions, final_<shape>.ply into config.output. log.csv and result.json
// list the values of parameters with at most 64 scalars (a mesh's are in its .ply).
// `on_iteration` is called after each iteration's loss is known.
OptimizeResult optimize(const OptimizeConfig& config,
                        const std::function<void(const IterationRecord&)>& on_iteration = {});

} // namespace penumbra
