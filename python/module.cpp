// `penumbra._penumbra`: the native half of the Python module. A thin front over the library's API (load scene
// → parameters → render → derivative / gradient through diff/method.h); python/penumbra/__init__.py turns it
// into torch tensors and autograd. Images cross without copies (numpy arrays owning the C++ image); the GIL
// is released while rendering and Ctrl-C interrupts the work (core/interrupt.h); errors arrive as
// penumbra.Error with penumbra's message (file:line for scene files).
#include "core/interrupt.h"
#include "core/progress.h"
#include "core/sinkhorn.h"
#include "diff/method.h"
#include "diff/parameter_table.h"
#include "render/render.h"
#include "scene/scene.h"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <future>
#include <mutex>
#include <thread>

#include <tbb/task_arena.h>

namespace py = pybind11;
using namespace penumbra;

namespace {

// An estimate's warnings (what it leaves out) as Python UserWarnings.
void warn(const std::vector<std::string>& warnings) {
    for (const std::string& w : warnings)
        if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
}

// A loaded scene, its parameter table and the derivative methods used on it (kept: psdr calibrates its budget
// once per configuration).
struct PyScene {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<ParameterTable> table;
    std::map<std::string, std::unique_ptr<DerivativeMethod>> methods;
    std::mutex mutex; // one call at a time per scene
};

// H x W x 3 float32 array owning `image` (Color3f is three packed floats).
py::array_t<float> to_array(Image image) {
    static_assert(sizeof(Color3f) == 3 * sizeof(float), "Color3f must be three packed floats");
    auto* owned = new Image(std::move(image));
    py::capsule free_image(owned, [](void* p) { delete static_cast<Image*>(p); });
    const py::ssize_t h = owned->height, w = owned->width, f = sizeof(float);
    return py::array_t<float>({h, w, py::ssize_t(3)}, {w * 3 * f, 3 * f, f}, &owned->pixels[0].x, free_image);
}

Image from_array(const py::array_t<float, py::array::c_style | py::array::forcecast>& a, int width,
                 int height, const char* what) {
    if (a.ndim() != 3 || a.shape(0) != height || a.shape(1) != width || a.shape(2) != 3)
        throw Error(std::string(what) + ": expected an array of shape (" + std::to_string(height) + ", " +
                    std::to_string(width) + ", 3), the film's size");
    Image img(width, height);
    std::memcpy(&img.pixels[0].x, a.data(), sizeof(float) * 3 * img.pixels.size());
    return img;
}

std::shared_ptr<PyScene> wrap(std::unique_ptr<Scene> scene) {
    auto s = std::make_shared<PyScene>();
    s->scene = std::move(scene);
    s->table = std::make_unique<ParameterTable>(*s->scene);
    return s;
}

std::map<std::string, std::string> strings(const py::dict& d) {
    std::map<std::string, std::string> out;
    for (const auto& [k, v] : d) {
        std::string value;
        if (py::isinstance<py::bool_>(v))
            value = v.cast<bool>() ? "true" : "false";
        else
            value = py::str(v);
        out[py::str(k)] = value;
    }
    return out;
}

// Runs `work` on a worker thread without the GIL; the calling thread checks for Ctrl-C every 50 ms and, on a
// signal, interrupts the work (it unwinds at the next tile or sample chunk) and raises KeyboardInterrupt.
template <typename T> T run_interruptible(const std::function<T()>& work) {
    clear_interrupt();
    std::packaged_task<T()> task(work);
    std::future<T> result = task.get_future();
    std::thread worker;
    {
        py::gil_scoped_release release;
        worker = std::thread(std::move(task));
    }
    bool interrupted = false;
    while (true) {
        std::future_status status;
        {
            py::gil_scoped_release release;
            status = result.wait_for(std::chrono::milliseconds(50));
        }
        if (status == std::future_status::ready) break;
        if (!interrupted && PyErr_CheckSignals() != 0) {
            request_interrupt();
            interrupted = true;
        }
    }
    {
        py::gil_scoped_release release;
        worker.join();
    }
    if (interrupted) {
        try {
            result.get();
        } catch (const Interrupted&) {
        }
        throw py::error_already_set(); // the KeyboardInterrupt PyErr_CheckSignals set
    }
    return result.get();
}

// Selects sensor `index` for the duration of a call.
class SensorScope {
  public:
    SensorScope(Scene& scene, int index) : scene_(scene) { scene.select_sensor(std::to_string(index)); }
    ~SensorScope() { scene_.sensor = scene_.sensors.front(); }

  private:
    Scene& scene_;
};

// Sensor motions belong to the first sensor (diff/parameters.h): refuse them while another one renders.
void check_sensor_motions(const PyScene& s, const std::vector<int>& entries, int sensor) {
    if (sensor == 0) return;
    const std::string id = s.scene->sensors.front()->id.empty() ? "sensor" : s.scene->sensors.front()->id;
    for (int e : entries) {
        const std::string& name = s.table->entries()[size_t(e)].name;
        if (name == id + ".translate" || name == id + ".rotate")
            throw Error("'" + name +
                        "' moves the first sensor; it cannot be differentiated while rendering sensor " +
                        std::to_string(sensor));
    }
}

DerivativeMethod& method_for(PyScene& s, const std::string& name, const py::dict& options) {
    MethodOptions o;
    std::string key = name;
    for (const auto& [given, v] : strings(options)) {
        std::string k = given;
        std::replace(k.begin(), k.end(), '_', '-');
        key += "|" + k + "=" + v;
        o.set(k, v);
    }
    auto it = s.methods.find(key);
    if (it == s.methods.end()) it = s.methods.emplace(key, make_method(name, o)).first;
    return *it->second;
}

MethodRun run_settings(int spp, uint64_t seed, int threads, int batches) {
    if (spp <= 0) throw Error("spp must be positive, got " + std::to_string(spp));
    MethodRun run;
    run.spp = spp;
    run.seed = seed;
    run.threads = threads;
    run.batches = batches;
    return run;
}

} // namespace

PYBIND11_MODULE(_penumbra, m) {
    m.doc() = "penumbra: a physics-based differentiable renderer (native module; use the `penumbra` package)";
    py::register_exception<Error>(m, "Error", PyExc_RuntimeError);

    py::class_<PyScene, std::shared_ptr<PyScene>>(m, "NativeScene")
        .def("sensors",
             [](const PyScene& s) {
                 py::list out;
                 for (const auto& sensor : s.scene->sensors)
                     out.append(py::make_tuple(sensor->id, sensor->film->width, sensor->film->height));
                 return out;
             })
        .def("sample_count",
             [](const PyScene& s, int sensor) {
                 SensorScope scope(*s.scene, sensor);
                 return s.scene->sensor->sampler->effective_spp(0);
             })
        .def("faces",
             [](const PyScene& s, const std::string& shape) {
                 // Mitsuba's read-only `<shape>.faces`; shapes are named as in diff/parameters.h.
                 std::string names;
                 for (size_t i = 0; i < s.scene->shapes.size(); ++i) {
                     const Shape& sh = *s.scene->shapes[i];
                     const std::string name = sh.id.empty() ? "shape_" + std::to_string(i) : sh.id;
                     if (name == shape) {
                         py::array_t<int64_t> out({py::ssize_t(sh.mesh.face_count()), py::ssize_t(3)});
                         std::copy(sh.mesh.indices.begin(), sh.mesh.indices.end(), out.mutable_data());
                         return out;
                     }
                     names += (names.empty() ? "" : ", ") + name;
                 }
                 throw Error("unknown shape '" + shape + "' (shapes: " + names + ")");
             })
        .def("entries",
             [](const PyScene& s) {
                 py::list out;
                 for (const ParameterTable::Entry& e : s.table->entries())
                     out.append(py::make_tuple(e.name, e.shape, e.motion, e.geometry));
                 return out;
             })
        .def("find", [](const PyScene& s, const std::string& name) { return s.table->find(name); })
        .def("get",
             [](PyScene& s, int entry) {
                 std::vector<float> v = s.table->get(entry);
                 return py::array_t<float>(py::ssize_t(v.size()), v.data());
             })
        .def("set",
             [](PyScene& s, int entry,
                const py::array_t<float, py::array::c_style | py::array::forcecast>& values) {
                 std::lock_guard<std::mutex> lock(s.mutex);
                 s.table->set(entry, values.data(), size_t(values.size()));
             })
        .def("apply",
             [](PyScene& s) {
                 std::lock_guard<std::mutex> lock(s.mutex);
                 run_interruptible<int>([&] { return s.table->apply(), 0; });
             })
        .def(
            "render",
            [](PyScene& s, int spp, uint64_t seed, int threads, int sensor, bool progress) {
                std::lock_guard<std::mutex> lock(s.mutex);
                ProgressBar bar(progress, "render");
                RenderStats stats;
                Image image = run_interruptible<Image>([&] {
                    SensorScope scope(*s.scene, sensor);
                    RenderOptions o;
                    o.spp = spp;
                    o.seed = seed;
                    o.threads = threads;
                    o.progress = bar.callback();
                    return render(*s.scene, o, &stats);
                });
                if (stats.dropped_samples > 0)
                    warn({std::to_string(stats.dropped_samples) +
                          " sample(s) with a non-finite value were left out of the image"});
                return to_array(std::move(image));
            },
            py::arg("spp"), py::arg("seed"), py::arg("threads"), py::arg("sensor"), py::arg("progress"))
        .def("gradient",
             [](PyScene& s, const std::vector<int>& entries,
                const py::array_t<float, py::array::c_style | py::array::forcecast>& adjoint, int spp,
                uint64_t seed, int threads, int sensor, const std::string& method, const py::dict& options,
                bool progress) {
                 std::lock_guard<std::mutex> lock(s.mutex);
                 check_sensor_motions(s, entries, sensor);
                 DerivativeMethod& dm = method_for(s, method, options);
                 ProgressBar bar(progress, "gradient");
                 MethodRun run = run_settings(spp, seed, threads, 1);
                 run.progress = bar.callback();
                 SensorScope scope(*s.scene, sensor);
                 const Film& film = *s.scene->sensor->film;
                 const Image a = from_array(adjoint, film.width, film.height, "adjoint image");
                 std::vector<std::string> warnings;
                 const std::vector<std::vector<double>> g =
                     run_interruptible<std::vector<std::vector<double>>>([&] {
                         s.table->select(entries);
                         Gradient mg = dm.gradient(*s.scene, s.table->parameters(), a, run);
                         warnings = std::move(mg.warnings);
                         return s.table->chain(mg.values);
                     });
                 warn(warnings);
                 py::list out;
                 for (const std::vector<double>& v : g) {
                     py::array_t<float> arr(py::ssize_t(v.size()));
                     std::copy(v.begin(), v.end(), arr.mutable_data());
                     out.append(arr);
                 }
                 return out;
             })
        .def("derivative", [](PyScene& s, const std::vector<std::pair<int, std::vector<float>>>& directions,
                              int spp, uint64_t seed, int threads, int sensor, int batches,
                              const std::string& method, const py::dict& options, bool progress) {
            std::lock_guard<std::mutex> lock(s.mutex);
            std::vector<int> entries;
            for (const auto& d : directions)
                entries.push_back(d.first);
            check_sensor_motions(s, entries, sensor);
            DerivativeMethod& dm = method_for(s, method, options);
            ProgressBar bar(progress, "derivative");
            MethodRun run = run_settings(spp, seed, threads, batches);
            run.progress = bar.callback();
            SensorScope scope(*s.scene, sensor);
            DerivativeImage d = run_interruptible<DerivativeImage>([&] {
                s.table->select(directions);
                return dm.derivative(*s.scene, s.table->parameters(), run);
            });
            warn(d.warnings);
            py::object se = d.stderr_img.pixels.empty() ? py::object(py::none())
                                                        : py::object(to_array(std::move(d.stderr_img)));
            return py::make_tuple(to_array(std::move(d.derivative)), se);
        });

    m.def(
        "load_file",
        [](const std::string& path, const py::dict& defines) {
            const std::map<std::string, std::string> d = strings(defines);
            return wrap(run_interruptible<std::unique_ptr<Scene>>([&] { return load_scene(path, d); }));
        },
        py::arg("path"), py::arg("defines"));
    m.def(
        "load_string",
        [](const std::string& xml, const std::string& base_dir, const py::dict& defines) {
            const std::map<std::string, std::string> d = strings(defines);
            return wrap(run_interruptible<std::unique_ptr<Scene>>(
                [&] { return load_scene_string(xml, base_dir, d); }));
        },
        py::arg("xml"), py::arg("base_dir"), py::arg("defines"));
    m.def(
        "read_image", [](const std::string& path) { return to_array(read_image(path)); }, py::arg("path"));
    m.def(
        "write_image",
        [](const std::string& path, const py::array_t<float, py::array::c_style | py::array::forcecast>& a) {
            if (a.ndim() != 3 || a.shape(2) != 3) throw Error("write_image: expected an H x W x 3 array");
            write_image(path, from_array(a, int(a.shape(1)), int(a.shape(0)), "write_image"));
        },
        py::arg("path"), py::arg("image"));
    // Entropic optimal transport on 5-D points (core/sinkhorn.h); `plan` adds the dense n x m plan.
    m.def(
        "sinkhorn",
        [](const Points5& x, const Eigen::VectorXd& a, const Points5& y, const Eigen::VectorXd& b, double blur,
           double scaling, double position_weight, double tolerance, int max_iterations, int threads,
           bool plan) {
            SinkhornOptions o;
            o.blur = blur;
            o.scaling = scaling;
            o.position_weight = position_weight;
            o.tolerance = tolerance;
            o.max_iterations = max_iterations;
            Eigen::MatrixXd dense;
            const SinkhornResult r = run_interruptible<SinkhornResult>([&] {
                tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());
                return arena.execute([&] {
                    SinkhornResult result = sinkhorn(x, a, y, b, o);
                    if (plan) dense = transport_plan(x, a, y, b, result, o);
                    return result;
                });
            });
            py::dict out;
            out["f"] = r.f;
            out["g"] = r.g;
            out["matched"] = r.matched;
            out["epsilon"] = r.epsilon;
            out["annealing_steps"] = r.annealing_steps;
            out["iterations"] = r.iterations;
            out["marginal_error"] = r.marginal_error;
            if (plan) out["plan"] = dense;
            return out;
        },
        py::arg("x"), py::arg("a"), py::arg("y"), py::arg("b"), py::arg("blur") = 0.01, py::arg("scaling") = 0.9,
        py::arg("position_weight") = 1.0, py::arg("tolerance") = 1e-3, py::arg("max_iterations") = 1000,
        py::arg("threads") = 0, py::arg("plan") = false);
    m.def("methods", [] {
        py::list out;
        for (const MethodInfo& info : derivative_methods()) {
            py::list options;
            for (const MethodOption& o : info.options) {
                const char* type = o.type == MethodOption::Type::Int     ? "int"
                                   : o.type == MethodOption::Type::Float ? "float"
                                   : o.type == MethodOption::Type::Bool  ? "bool"
                                                                         : "str";
                std::string name = o.name;
                std::replace(name.begin(), name.end(), '-', '_');
                options.append(py::make_tuple(name, type, o.help, o.choices));
            }
            out.append(py::make_tuple(info.name, info.help, options));
        }
        return out;
    });
}
