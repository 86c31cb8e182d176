// The Python module's C++ half, _pp5sim (pybind11): sessions that run frames on the
// simulated machine, the pixel-memory fields of a frame read from the Renderer boards'
// memory, sweeps, the assembler and per-pixel traces. pp5sim/__init__.py wraps it in the
// Python API (docs/guides/python.md).
//
// Contract:
//  - Errors are the library's own exceptions with the command line's messages: a
//    configuration error (ConfigError) and std::invalid_argument become ValueError, any other
//    std::exception RuntimeError.
//  - A Session elaborates its machine on its first frame and keeps it until it is closed or
//    freed. Each machine lives in a SystemC context of its own (KernelContext), made current
//    whenever it runs, so any number of sessions live and run in turn; SystemC's current
//    context is a process global, so one simulation runs at a time (KernelLock).
//  - Every run releases the GIL. A run on the main thread sees Ctrl-C within milliseconds
//    (SigintWatch, Session::set_cancel): between slices of the SystemC run, between the pixel
//    execution's regions, and after the analytic level's set-up and model; a sweep's point is
//    a run. It stops, the machine holding half a frame is freed, and KeyboardInterrupt is
//    raised; the session's next frame is the same frame again, on a machine made again.
//  - An animated session (animation=True) draws frame k of the scene's animation at its frame
//    k, the scenes `pp5sim animate` draws (check_animation_scenes, then animation_scene as each
//    frame comes: one scene kept at a time); a machine made again mid-run is made for the
//    scene of the frame it runs next.
#include <dlfcn.h>
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/gp/setup_memo.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/animation.hpp"
#include "sim/app/commands.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"
#include "sim/trace/inspect.hpp"
#include "sim/trace/recorder.hpp"
#include "sim/trace/trace_file.hpp"

namespace py = pybind11;
namespace fs = std::filesystem;

namespace pp5::python {

namespace {

// A JSON document as Python objects (dict, list, int, float, str, bool, None), made in C++:
// no Python code runs, so a sweep's Ctrl-C is seen where it checks for it, between points.
py::object json_to_python(const nlohmann::json& j) {
  using T = nlohmann::json::value_t;
  switch (j.type()) {
    case T::boolean:
      return py::bool_(j.get<bool>());
    case T::number_integer:
      return py::int_(j.get<std::int64_t>());
    case T::number_unsigned:
      return py::int_(j.get<std::uint64_t>());
    case T::number_float:
      return py::float_(j.get<double>());
    case T::string:
      return py::str(j.get_ref<const std::string&>());
    case T::array: {
      py::list out;
      for (const nlohmann::json& e : j) out.append(json_to_python(e));
      return std::move(out);
    }
    case T::object: {
      py::dict out;
      for (const auto& [key, value] : j.items()) out[py::str(key)] = json_to_python(value);
      return std::move(out);
    }
    default:
      return py::none();
  }
}

py::object stat_to_python(const StatValue& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return py::int_(*i);
  if (const auto* d = std::get_if<double>(&v)) return py::float_(*d);
  return py::str(std::get<std::string>(v));
}

// Every statistic by its full name, typed, in registration order (a dict keeps it).
py::dict flat_statistics(const Statistics& stats) {
  py::dict out;
  for (const StatisticInfo& i : stats.infos())
    out[py::str(i.name)] = stat_to_python(stats.value(i.name));
  return out;
}

py::dict info_dict(const StatisticInfo& i) {
  py::dict d;
  d["kind"] = stat_kind_name(i.kind);
  d["unit"] = i.unit;
  d["description"] = i.description;
  return d;
}

// The configuration: defaults (or a JSON file), the fidelity level, then the dict's keys as
// --set assignments, in the dict's order.
MachineConfig make_config(const std::string& config_file, const std::string& fidelity,
                          const std::vector<std::pair<std::string, std::string>>& sets) {
  std::vector<std::string> assignments;
  for (const auto& [k, v] : sets) assignments.push_back(k + "=" + v);
  if (!fidelity.empty()) {
    for (std::string& s : fidelity_assignments(fidelity)) assignments.push_back(std::move(s));
  }
  return load_config(config_file, assignments);
}

int threads_or_default(int threads) { return threads > 0 ? threads : default_threads(); }

// Program text (it holds a newline) or a firmware name or path, as --firmware takes it.
Program load_program(const std::string& firmware, const Scene& scene, const MachineConfig& config) {
  if (firmware.find('\n') != std::string::npos)
    return assemble(firmware, "<program text>", assembler_options(config));
  return assemble_file(firmware_for(firmware, scene), assembler_options(config));
}

// --- Scenes from arrays -------------------------------------------------------------------

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

void check_shape(const py::array& a, const char* name, py::ssize_t rows, py::ssize_t columns) {
  const bool ok = columns == 0
                      ? a.ndim() == 1 && (rows < 0 || a.shape(0) == rows)
                      : a.ndim() == 2 && a.shape(1) == columns && (rows < 0 || a.shape(0) == rows);
  if (!ok) {
    std::string shape;
    for (py::ssize_t d = 0; d < a.ndim(); ++d)
      shape += (d ? ", " : "") + std::to_string(a.shape(d));
    const std::string want = (rows < 0 ? std::string("N") : std::to_string(rows)) +
                             (columns ? ", " + std::to_string(columns) : std::string(","));
    throw std::invalid_argument(
        fmt::format("{}: expected an array of shape ({}), got ({})", name, want, shape));
  }
}

void check_unit_range(const FloatArray& a, const char* name) {
  const float* p = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i) {
    if (!(p[i] >= 0.0f && p[i] <= 1.0f)) {
      throw std::invalid_argument(
          fmt::format("{}: value {} at flat index {} is outside [0, 1] (colours are RGB in [0, 1])",
                      name, p[i], i));
    }
  }
}

void check_finite(const FloatArray& a, const char* name) {
  const float* p = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(p[i]))
      throw std::invalid_argument(fmt::format("{}: value at flat index {} is not finite", name, i));
  }
}

Scene scene_from_arrays(const py::object& vertices, const py::object& triangles,
                        const py::object& colors, const py::object& centers,
                        const py::object& radii, const py::object& sphere_colors,
                        const std::string& firmware) {
  Scene scene;
  scene.name = "arrays";
  scene.description = "geometry given as NumPy arrays";
  const glm::vec3 grey(0.8f);
  if (!vertices.is_none()) {
    if (triangles.is_none()) throw std::invalid_argument("vertices: given without triangles");
    const FloatArray v = vertices.cast<FloatArray>();
    check_shape(v, "vertices", -1, 3);
    check_finite(v, "vertices");
    const IndexArray t = triangles.cast<IndexArray>();
    check_shape(t, "triangles", -1, 3);
    const py::ssize_t n = v.shape(0);
    std::optional<FloatArray> c;
    if (!colors.is_none()) {
      c = colors.cast<FloatArray>();
      check_shape(*c, "colors", n, 3);
      check_unit_range(*c, "colors");
    }
    scene.mesh.vertices.resize(static_cast<std::size_t>(n));
    for (py::ssize_t i = 0; i < n; ++i) {
      Vertex& out = scene.mesh.vertices[static_cast<std::size_t>(i)];
      out.position = glm::vec3(v.at(i, 0), v.at(i, 1), v.at(i, 2));
      out.color = c ? glm::vec3(c->at(i, 0), c->at(i, 1), c->at(i, 2)) : grey;
    }
    for (py::ssize_t i = 0; i < t.shape(0); ++i) {
      glm::uvec3 tri;
      for (int k = 0; k < 3; ++k) {
        const std::int64_t index = t.at(i, k);
        if (index < 0 || index >= n) {
          throw std::invalid_argument(fmt::format(
              "triangles: row {} has vertex index {}, expected 0..{}", i, index, n - 1));
        }
        tri[k] = static_cast<unsigned>(index);
      }
      scene.mesh.triangles.push_back(tri);
    }
    compute_smooth_normals(scene.mesh);
  } else if (!triangles.is_none() || !colors.is_none()) {
    throw std::invalid_argument("triangles, colors: given without vertices");
  }
  if (!centers.is_none()) {
    const FloatArray p = centers.cast<FloatArray>();
    check_shape(p, "sphere_centers", -1, 3);
    check_finite(p, "sphere_centers");
    const py::ssize_t n = p.shape(0);
    if (radii.is_none()) throw std::invalid_argument("sphere_centers: given without sphere_radii");
    const FloatArray r = radii.cast<FloatArray>();
    check_shape(r, "sphere_radii", n, 0);
    std::optional<FloatArray> c;
    if (!sphere_colors.is_none()) {
      c = sphere_colors.cast<FloatArray>();
      check_shape(*c, "sphere_colors", n, 3);
      check_unit_range(*c, "sphere_colors");
    }
    for (py::ssize_t i = 0; i < n; ++i) {
      Sphere s;
      s.center = glm::vec3(p.at(i, 0), p.at(i, 1), p.at(i, 2));
      s.radius = r.at(i);
      if (!(s.radius > 0.0f && std::isfinite(s.radius))) {
        throw std::invalid_argument(
            fmt::format("sphere_radii: radius {} at index {} is not positive", s.radius, i));
      }
      if (c) s.color = glm::vec3(c->at(i, 0), c->at(i, 1), c->at(i, 2));
      scene.spheres.push_back(s);
    }
  } else if (!radii.is_none() || !sphere_colors.is_none()) {
    throw std::invalid_argument("sphere_radii, sphere_colors: given without sphere_centers");
  }
  if (scene.mesh.triangles.empty() && scene.spheres.empty())
    throw std::invalid_argument("the scene has no triangles and no spheres");
  // The camera framed on every vertex and every sphere's bounding box, as a mesh file is.
  Mesh points;
  points.vertices = scene.mesh.vertices;
  for (const Sphere& s : scene.spheres) {
    for (int corner = 0; corner < 8; ++corner) {
      Vertex v;
      v.position = s.center + s.radius * glm::vec3(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1,
                                                   corner & 4 ? 1 : -1);
      points.vertices.push_back(v);
    }
  }
  scene.camera = frame_mesh(points, glm::vec3(0.3f, 0.4f, 1.0f), kBuiltinFovYDegrees);
  scene.lights = {default_light(scene.camera)};
  scene.background = kBuiltinBackground;
  scene.firmware = firmware.find('\n') == std::string::npos ? firmware : "";
  return scene;
}

// --- Fields read from pixel memory --------------------------------------------------------

// One requested field and the NumPy array it fills (screen height x width, of a dtype that
// holds the field: the smallest of 8, 16, 32, 64 bits, signed for a signed field).
struct FieldTarget {
  std::string name;
  Field field;
  int bytes = 8;
  char* data = nullptr;
};

template <typename T>
void scatter(const std::uint64_t* values, const Field& f, int region_width, int x0, int y0,
             int columns, int rows, int screen_width, char* data) {
  T* out = reinterpret_cast<T*>(data);
  const unsigned shift = 64u - static_cast<unsigned>(f.width);
  for (int py = 0; py < rows; ++py) {
    const std::uint64_t* in = values + static_cast<std::size_t>(py) * region_width;
    T* row = out + static_cast<std::size_t>(y0 + py) * screen_width + x0;
    for (int px = 0; px < columns; ++px) {
      std::uint64_t v = in[px];
      if (f.is_signed && f.width < 64)
        v = static_cast<std::uint64_t>(static_cast<std::int64_t>(v << shift) >> shift);
      row[px] = static_cast<T>(v);
    }
  }
}

// Attached to every Renderer board: at the end of each region, each requested field of the
// region's pixel memory goes into its place on the screen. Regions are disjoint, so boards on
// different host threads write different pixels.
class FieldCapture {
 public:
  FieldCapture(const MachineConfig& config, std::vector<FieldTarget> targets)
      : config_(config), targets_(std::move(targets)) {
    for (int k = 0; k < config.renderer.count; ++k)
      boards_.push_back(std::make_unique<Board>(*this));
  }
  BoardObserver* observer(int renderer) {
    return boards_.at(static_cast<std::size_t>(renderer)).get();
  }

 private:
  class Board : public BoardObserver {
   public:
    explicit Board(FieldCapture& c) : c_(c) {}
    void begin_packet(const PacketContext&, const ProcedureCode&, const RendererBoard&) override {}
    void after_instruction(int, const Instruction&, ArrayCycles, const RendererBoard&) override {}
    void end_region(int region, const RendererBoard& board) override {
      const PixelBackend& a = board.array();
      const MachineConfig& config = c_.config_;
      const int x0 = config.region_x0(region), y0 = config.region_y0(region);
      const int columns = std::min(a.width(), config.screen.width - x0);
      const int rows = std::min(a.height(), config.screen.height - y0);
      values_.resize(static_cast<std::size_t>(a.width()) * a.height());
      for (const FieldTarget& t : c_.targets_) {
        a.read_field(t.field, values_.data());
        const int w = config.screen.width;
        switch (t.bytes) {
          case 1:
            scatter<std::uint8_t>(values_.data(), t.field, a.width(), x0, y0, columns, rows, w,
                                  t.data);
            break;
          case 2:
            scatter<std::uint16_t>(values_.data(), t.field, a.width(), x0, y0, columns, rows, w,
                                   t.data);
            break;
          case 4:
            scatter<std::uint32_t>(values_.data(), t.field, a.width(), x0, y0, columns, rows, w,
                                   t.data);
            break;
          default:
            scatter<std::uint64_t>(values_.data(), t.field, a.width(), x0, y0, columns, rows, w,
                                   t.data);
            break;
        }
      }
    }

   private:
    FieldCapture& c_;
    std::vector<std::uint64_t> values_;  // one region of one field, reused
  };
  MachineConfig config_;
  std::vector<FieldTarget> targets_;
  std::vector<std::unique_ptr<Board>> boards_;
};

int field_bytes(int width) { return width <= 8 ? 1 : width <= 16 ? 2 : width <= 32 ? 4 : 8; }

py::dtype field_dtype(const Field& f) {
  const int bytes = field_bytes(f.width);
  return py::dtype(fmt::format("{}{}", f.is_signed ? 'i' : 'u', bytes));
}

// --- Programs -----------------------------------------------------------------------------

py::dict bit_budget_dict(const Program& p) {
  py::dict d;
  d["program"] = p.name;
  d["memory_bits"] = p.memory_bits;
  d["bits_used"] = p.bits_used();
  d["resident_bits"] = p.resident_bits;
  d["overlay_bits"] = p.overlay_bits;
  d["staging_bits"] = p.staging_bits;
  int field_bits = 0, scratch_bits = 0, spilled_bits = 0;
  for (const FieldDecl& f : p.fields) {
    (f.spilled ? spilled_bits : f.scratch ? scratch_bits : field_bits) += f.width;
  }
  d["field_bits"] = field_bits;
  d["scratch_bits"] = scratch_bits;
  d["spilled_bits"] = spilled_bits;
  return d;
}

py::list field_map(const Program& p) {
  py::list out;
  for (const FieldDecl& f : p.fields) {
    py::dict d;
    d["name"] = f.name;
    d["width"] = f.width;
    d["signed"] = f.is_signed;
    d["lo"] = f.spilled ? py::object(py::none()) : py::object(py::int_(f.lo));
    d["scratch"] = f.scratch;
    d["spilled"] = f.spilled;
    d["block"] = f.spilled ? py::object(py::int_(f.block)) : py::object(py::none());
    d["line"] = f.line;
    py::list users;
    for (int k = 0; k < static_cast<int>(Procedure::count); ++k) {
      if (f.uses[static_cast<std::size_t>(k)]) users.append(kProcedureNames[k]);
    }
    d["procedures"] = users;
    out.append(d);
  }
  return out;
}

// Each defined procedure's instructions with their cycles, priced as `pp5sim asm` prices them
// (the instruction table's cost, with the scene's frame parameters).
py::dict cycle_costs(const Program& p, const TimingParams& timing, const ParameterValues& params) {
  OwnedValues values{};
  values.parameters = params;
  py::dict out;
  for (int k = 0; k < static_cast<int>(Procedure::count); ++k) {
    const ProcedureCode& code = p.procedures[static_cast<std::size_t>(k)];
    if (!code.defined) continue;
    py::list rows;
    std::uint64_t total = 0;
    for (const Instruction& ins : code.code) {
      const std::uint64_t cycles = instruction_cost(ins, timing, values).count;
      total += cycles;
      rows.append(py::make_tuple(ins.line, disassemble(ins), cycles, ins.line == 0));
    }
    py::dict d;
    d["instructions"] = rows;
    d["total"] = total;
    out[kProcedureNames[k]] = d;
  }
  return out;
}

struct PyProgram {
  std::shared_ptr<const Program> program;
  MachineConfig config;
  std::shared_ptr<const Scene> scene;
  ParameterValues parameters() const {
    return GeometryEngine(geometry_params(config), *scene).frame_parameters();
  }
};

// --- Frames -------------------------------------------------------------------------------

struct PyFrame {
  int index = 0;
  py::object image;  // (height, width, 3) uint8, or None for a timing-only frame
  py::dict fields;   // name -> (height, width) array
  FrameResult result;
  std::shared_ptr<const Program> program;
  MachineConfig config;
};

// --- Ctrl-C inside a frame ----------------------------------------------------------------

// While a frame runs on the main thread, SIGINT sets g_frame_cancel (which the boards check
// between regions: Session::set_cancel) and is passed on to the handler it replaced (Python's,
// which notes it for PyErr_CheckSignals).
std::atomic<bool> g_frame_cancel{false};
struct sigaction g_python_sigint {};

extern "C" void pp5_on_sigint(int signal) {
  g_frame_cancel.store(true);
  if (g_python_sigint.sa_handler != SIG_DFL && g_python_sigint.sa_handler != SIG_IGN)
    g_python_sigint.sa_handler(signal);
}

bool on_main_thread() {
  const py::module_ threading = py::module_::import("threading");
  return threading.attr("current_thread")().is(threading.attr("main_thread")());
}

// Installs pp5_on_sigint for its lifetime, on the main thread when Python handles SIGINT with
// a handler of its own (not when it is ignored or left to the default).
class SigintWatch {
 public:
  SigintWatch() {
    g_frame_cancel.store(false);
    if (!on_main_thread()) return;
    struct sigaction current {};
    if (sigaction(SIGINT, nullptr, &current) != 0 || (current.sa_flags & SA_SIGINFO) != 0 ||
        current.sa_handler == SIG_DFL || current.sa_handler == SIG_IGN)
      return;
    g_python_sigint = current;
    struct sigaction ours = current;
    ours.sa_handler = pp5_on_sigint;
    installed_ = sigaction(SIGINT, &ours, nullptr) == 0;
  }
  ~SigintWatch() {
    if (installed_) sigaction(SIGINT, &g_python_sigint, nullptr);
  }
  SigintWatch(const SigintWatch&) = delete;
  SigintWatch& operator=(const SigintWatch&) = delete;
  bool installed() const { return installed_; }

 private:
  bool installed_ = false;
};

// Raises KeyboardInterrupt (Python's handler runs first, if SIGINT was delivered).
[[noreturn]] void raise_interrupt() {
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  PyErr_SetNone(PyExc_KeyboardInterrupt);
  throw py::error_already_set();
}

// SystemC's current context is a process global: one simulation (made, run or freed) at a
// time, whatever Python thread asks. Taken with the GIL held; it waits with the GIL released,
// and a holder never waits for the GIL before it has the lock, so neither waits on the other.
std::mutex g_kernel_mutex;
class KernelLock {
 public:
  KernelLock() : lock_(g_kernel_mutex, std::try_to_lock) {
    if (!lock_.owns_lock()) {
      py::gil_scoped_release release;
      lock_.lock();
    }
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

// Runs `body(cancel)` (making a Session and/or running a frame, given the flag to watch) with
// the GIL released and Ctrl-C watched on the main thread; false when Ctrl-C stopped it
// (FrameCancelled: a session it ran holds half a frame). Called with SystemC held.
template <typename Body>
bool watched(Body&& body) {
  SigintWatch watch;
  const std::atomic<bool>* cancel = watch.installed() ? &g_frame_cancel : nullptr;
  py::gil_scoped_release release;
  try {
    body(cancel);
    return true;
  } catch (const FrameCancelled&) {
    return false;
  }
}

// --- Sessions -----------------------------------------------------------------------------

// An animated session's frames (sim/animation.hpp): every frame's scene, made and checked when
// the session is made, as `pp5sim animate` makes them.
// An animated session's frames: every frame's scene made and checked when the session is
// made (check_animation_scenes), then kept one at a time, made again as its frame comes
// (a long animation stepped frame by frame holds one scene, as pp5sim animate does).
struct PyAnimation {
  std::string name, motion;
  double fps = 0;
  std::shared_ptr<const Animation> source;
  int frames = 0;
  // Frame k's scene; the last one made is kept.
  std::shared_ptr<const Scene> scene(int k) const {
    if (k != kept_frame) {
      kept = animation_scene(*source, k);
      kept_frame = k;
    }
    return kept;
  }
  mutable std::shared_ptr<const Scene> kept;
  mutable int kept_frame = -1;
};

class PySession {
 public:
  PySession(const MachineConfig& config, std::shared_ptr<const Scene> scene,
            std::shared_ptr<const Program> program, int threads,
            std::optional<PyAnimation> animation, double setup_seconds)
      : config_(config),
        scene_(std::move(scene)),
        program_(std::move(program)),
        threads_(threads),
        animation_(std::move(animation)),
        setup_seconds_(setup_seconds) {}
  ~PySession() { close(); }

  // Frees the machine (and its SystemC context); the next frame makes them again.
  void close() {
    if (!session_) return;
    accumulate_closed();
    KernelLock kernel;
    session_.reset();
  }

  PyFrame frame(const std::vector<std::string>& field_names, bool pixels) {
    using F = MachineConfig::Fidelity;
    std::vector<FieldTarget> targets;
    PyFrame f;
    for (const std::string& name : field_names) {
      const FieldDecl* d = program_->find_field(name);
      if (d == nullptr) {
        std::vector<std::string> names;
        for (const FieldDecl& x : program_->fields) names.push_back(x.name);
        throw std::invalid_argument(fmt::format("fields: program {} has no field '{}' (fields: {})",
                                                program_->name, name, fmt::join(names, " ")));
      }
      if (d->spilled) {
        throw std::invalid_argument(fmt::format(
            "fields: '{}' of program {} lives in the backing store, not in pixel memory", name,
            program_->name));
      }
      if (!pixels || config_.fidelity.pixels == F::Pixels::none) {
        throw std::invalid_argument(fmt::format(
            "fields: '{}' is read from pixel memory, which a timing-only frame does not execute "
            "(fidelity.pixels=none or pixels=False)",
            name));
      }
      FieldTarget t;
      t.name = name;
      t.field = Field{d->lo, d->width, d->is_signed};
      t.bytes = field_bytes(d->width);
      py::array a(field_dtype(t.field), {config_.screen.height, config_.screen.width});
      std::memset(a.mutable_data(), 0, static_cast<std::size_t>(a.nbytes()));
      t.data = static_cast<char*>(a.mutable_data());
      f.fields[py::str(name)] = a;
      targets.push_back(t);
    }
    std::unique_ptr<FieldCapture> capture;
    if (!targets.empty()) capture = std::make_unique<FieldCapture>(config_, std::move(targets));
    std::function<BoardObserver*(int)> observe;
    if (capture) observe = [&](int k) { return capture->observer(k); };
    f.result = run(observe, pixels);
    return finish(std::move(f), frames_ - 1);
  }

  // The rest of an animation's frames, overlapped as the machine ran them
  // (Session::run_frames: the GPs set up frame n + 1 from its scene while the Renderers draw
  // frame n): on a session that has run no frame yet. Its machine is freed afterwards.
  std::vector<PyFrame> run_animation(bool pixels) {
    if (!animation_ || frames_ > 0) {
      throw std::invalid_argument(
          "run_animation: an animated session (animation=True) that has run no frame yet");
    }
    close();
    std::vector<FrameResult> results;
    bool done = false;
    {
      KernelLock kernel;
      done = watched([&](const std::atomic<bool>* cancel) {
        session_ = std::make_unique<Session>(config_, animation_->scene(0), program_, threads_,
                                             nullptr, cancel);
        session_->set_setup_seconds(setup_seconds_);
        session_->set_cancel(cancel);
        const PyAnimation& a = *animation_;
        overlapped_ = session_->run_frames(
            a.frames, [&results](int, FrameResult& r) { results.push_back(std::move(r)); }, pixels,
            [&a](int k) { return a.scene(k); });
        session_->set_cancel(nullptr);
      });
    }
    if (!done) {
      // Ctrl-C: no frame of the run is kept; the machine is freed and the animation can be run
      // again from its first frame.
      close();
      overlapped_ = RunSummary{};
      raise_interrupt();
    }
    frames_ = static_cast<int>(results.size());
    close();  // an overlapped machine runs no further frame
    std::vector<PyFrame> out;
    for (std::size_t k = 0; k < results.size(); ++k) {
      PyFrame f;
      f.result = std::move(results[k]);
      out.push_back(finish(std::move(f), static_cast<int>(k)));
    }
    return out;
  }
  // The sustained figures of run_animation's run (frames 0 when there was none).
  const RunSummary& overlapped() const { return overlapped_; }

  // A frame recorded for pixel (x, y), and `pp5sim trace why`'s explanation of it.
  std::string why(int x, int y) {
    const std::string refused = below_bit_level(config_, "why");
    if (!refused.empty()) throw std::invalid_argument(refused);
    trace::Selection sel;
    sel.rects.push_back(trace::Rect{x, y, 1, 1});
    trace::Recorder recorder(config_, *frame_scene(), *program_, sel, frames_);
    for (int k = 0; k < config_.renderer.count; ++k) recorder.observer(k);
    run([&](int k) { return recorder.observer(k); }, true);
    std::uint64_t count = 0;
    const std::vector<std::uint8_t> records = recorder.records(count);
    const trace::Trace tr =
        trace::parse_trace(trace::encode_trace(recorder.header(), records, count), "<session>");
    return trace::why_report(tr, trace::Pixel{x, y});
  }

  int frames() const { return frames_; }
  const MachineConfig& config() const { return config_; }
  const Scene& scene() const { return *scene_ptr(); }
  // The scene of the next frame (an animation's last once it has ended).
  std::shared_ptr<const Scene> scene_ptr() const {
    if (!animation_) return scene_;
    return animation_->scene(std::min(frames_, animation_->frames - 1));
  }
  const std::optional<PyAnimation>& animation() const { return animation_; }
  std::shared_ptr<const Program> program() const { return program_; }
  int threads() const { return threads_; }
  RunSummary summary() const {
    RunSummary s = closed_;
    if (session_) add(s, session_->summary());
    return s;
  }

 private:
  FrameResult run(const std::function<BoardObserver*(int)>& observe, bool pixels) {
    const std::shared_ptr<const Scene> scene = frame_scene();
    std::optional<FrameResult> r;
    bool done = false;
    {
      KernelLock kernel;
      done = watched([&](const std::atomic<bool>* cancel) {
        if (!session_) {
          // A machine made again (after close() or Ctrl-C) mid-animation is made for this
          // frame's scene.
          session_ = std::make_unique<Session>(config_, scene, program_, threads_, nullptr, cancel);
          // The scene's construction and the assembly, reported by the session's first frame.
          if (frames_ == 0) session_->set_setup_seconds(setup_seconds_);
        } else if (animation_ && frames_ > 0) {
          session_->set_scene(scene);  // as pp5sim animate does before each frame after the first
        }
        session_->set_cancel(cancel);
        try {
          r = session_->frame(observe, nullptr, pixels);
        } catch (...) {
          session_->set_cancel(nullptr);
          throw;
        }
        session_->set_cancel(nullptr);
      });
    }
    if (!done) {
      // Ctrl-C: the machine, which holds half a frame, is freed (the next frame makes it
      // again, for the same frame number).
      close();
      raise_interrupt();
    }
    ++frames_;
    return std::move(*r);
  }
  // The scene of frame frames_: the session's, or the animation's frame (refused past its end).
  std::shared_ptr<const Scene> frame_scene() const {
    if (!animation_) return scene_;
    const int count = animation_->frames;
    if (frames_ >= count) {
      throw std::invalid_argument(fmt::format(
          "the animation of '{}' has {} frames, all simulated; make the session with frames=N "
          "for more",
          animation_->name, count));
    }
    return animation_->scene(frames_);
  }
  PyFrame finish(PyFrame f, int index) const {
    f.index = index;
    f.program = program_;
    f.config = config_;
    const FrameImage& image = f.result.image;
    if (image.has_pixels()) {
      // The frame buffer's rows, copied once into the array.
      py::array_t<std::uint8_t> a({image.height(), image.width(), 3});
      std::uint8_t* out = a.mutable_data();
      for (int y = 0; y < image.height(); ++y)
        image.row(y, out + static_cast<std::size_t>(y) * image.width() * 3);
      f.image = a;
    } else {
      f.image = py::none();
    }
    f.result.image = FrameImage();  // the array holds the pixels now
    return f;
  }
  static void add(RunSummary& a, const RunSummary& b) {
    if (b.frames == 0) return;
    a.shortest_frame_seconds = a.frames
                                   ? std::min(a.shortest_frame_seconds, b.shortest_frame_seconds)
                                   : b.shortest_frame_seconds;
    a.longest_frame_seconds = std::max(a.longest_frame_seconds, b.longest_frame_seconds);
    a.frames += b.frames;
    a.simulated_seconds += b.simulated_seconds;
    a.host_seconds += b.host_seconds;
  }
  void accumulate_closed() { add(closed_, session_->summary()); }

  MachineConfig config_;
  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<const Program> program_;
  int threads_;
  std::unique_ptr<Session> session_;
  std::optional<PyAnimation> animation_;
  int frames_ = 0;
  RunSummary closed_;  // the frames of machines freed so far
  RunSummary overlapped_;
  double setup_seconds_;  // host.setup_seconds of the first frame
};

// --- Sweeps -------------------------------------------------------------------------------

py::object config_value(const nlohmann::json& config, const std::string& key) {
  const auto dot = key.find('.');
  return json_to_python(config.at(key.substr(0, dot)).at(key.substr(dot + 1)));
}

// One row of a sweep: the swept keys (typed, as the configuration holds them), sweep.csv's
// columns, the fidelity levels, then every statistic by name.
py::dict sweep_row(const std::vector<std::string>& keys, const nlohmann::json& config_json,
                   const Statistics& stats) {
  py::dict row;
  for (const std::string& k : keys) row[py::str(k)] = config_value(config_json, k);
  for (const auto& [column, name] : sweep_metric_columns())
    row[py::str(column)] = stat_to_python(stats.value(name));
  row["fidelity_pixels"] = json_to_python(config_json.at("fidelity").at("pixels"));
  row["fidelity_timing"] = json_to_python(config_json.at("fidelity").at("timing"));
  for (const StatisticInfo& i : stats.infos()) {
    if (!row.contains(i.name)) row[py::str(i.name)] = stat_to_python(stats.value(i.name));
  }
  return row;
}

// A sweep's points: the product of `axes` (the first key varying slowest, as pp5sim sweep),
// or, when `points` is not empty, those points, each the value of every axis key in order
// (`axes` then holds each key's distinct values). Every key's values are checked as
// pp5sim sweep checks them (check_sweep_axis), and every point's configuration and program
// before the first point runs. Each point is a frame of a Session of its own, interruptible
// as a session's frame is.
py::list sweep(const MachineConfig& base, std::shared_ptr<const Scene> scene,
               const std::string& firmware,
               const std::vector<std::pair<std::string, std::vector<std::string>>>& axes,
               const std::vector<std::vector<std::string>>& points, int threads) {
  if (axes.empty())
    throw std::invalid_argument("grid: give at least one key, e.g. {'gp.count': [1, 2, 4]}");
  const char* form = points.empty() ? "grid" : "points";
  std::vector<std::string> keys;
  std::set<std::string> seen;
  constexpr std::uint64_t kMaxPoints = 1000000;  // as pp5sim sweep
  std::uint64_t count = 1;
  for (const auto& [key, values] : axes) {
    const std::string where = fmt::format("{} {}={}", form, key, fmt::join(values, ","));
    if (!seen.insert(key).second)
      throw std::invalid_argument(fmt::format("{}: key '{}' is swept twice", where, key));
    if (values.empty()) throw std::invalid_argument(fmt::format("{}: no values", where));
    check_sweep_axis(where, key, values, base);
    keys.push_back(key);
    if (points.empty() && count > kMaxPoints / values.size()) {
      throw std::invalid_argument(fmt::format(
          "grid: more than {} points; split the sweep or sweep fewer values", kMaxPoints));
    }
    count *= values.size();
  }
  if (!points.empty()) {
    count = points.size();
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (points[i].size() != keys.size()) {
        throw std::invalid_argument(fmt::format("points: point {} has {} values for {} keys", i,
                                                points[i].size(), keys.size()));
      }
    }
  }
  std::map<std::tuple<int, int, int, int>, std::shared_ptr<const Program>> assembled;
  auto program_of = [&](const MachineConfig& c) {
    const AssemblerOptions a = assembler_options(c);
    const auto key =
        std::make_tuple(a.memory_bits, a.backing_store_bits, a.block_bits, a.enable_stack_depth);
    auto it = assembled.find(key);
    if (it == assembled.end())
      it =
          assembled.emplace(key, std::make_shared<const Program>(load_program(firmware, *scene, c)))
              .first;
    return it->second;
  };
  auto config_of = [&](std::uint64_t index) {
    std::vector<std::string> sets(keys.size());
    if (!points.empty()) {
      for (std::size_t k = 0; k < keys.size(); ++k) sets[k] = keys[k] + "=" + points[index][k];
    } else {
      for (std::size_t k = keys.size(); k-- > 0;) {
        const auto& values = axes[k].second;
        sets[k] = keys[k] + "=" + values[index % values.size()];
        index /= values.size();
      }
    }
    MachineConfig c = base;
    c.set(sets);
    return c;
  };
  for (std::uint64_t i = 0; i < count; ++i) program_of(config_of(i));  // check all first
  SetupMemo memo(*scene);
  py::list rows;
  for (std::uint64_t i = 0; i < count; ++i) {
    const MachineConfig config = config_of(i);
    const std::shared_ptr<const Program> program = program_of(config);
    std::optional<FrameResult> r;
    bool done = false;
    {
      KernelLock kernel;
      done = watched([&](const std::atomic<bool>* cancel) {
        Session session(config, scene, program, threads, &memo, cancel);
        r = session.frame();
      });
    }
    if (!done) raise_interrupt();
    rows.append(sweep_row(keys, config.to_json(), r->stats));
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  }
  return rows;
}

// The folder this extension was loaded from.
std::string module_dir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&module_dir), &info) == 0 || info.dli_fname == nullptr)
    return "";
  return fs::path(info.dli_fname).parent_path().string();
}

}  // namespace

}  // namespace pp5::python

using namespace pp5;
using namespace pp5::python;

PYBIND11_MODULE(_pp5sim, m) {
  m.doc() = "pp5sim's C++ half; use the package pp5sim (docs/guides/python.md)";
  // The installed programs and mesh reader, relative to the installed module (the
  // executable, from which pp5sim finds them, is python3 here). In a build tree they are not
  // there, and the build's own are found as pp5sim finds them.
  const std::string dir = module_dir();
  if (!dir.empty()) {
    set_builtin_programs_dir(
        (fs::path(dir) / PP5_PROGRAMS_FROM_MODULE).lexically_normal().string());
    const fs::path assimp =
        (fs::path(dir) / PP5_ASSIMP_FROM_MODULE / "libpp5_assimp.so").lexically_normal();
    std::error_code error;
    if (fs::is_regular_file(assimp, error)) setenv("PP5_ASSIMP_MODULE", assimp.c_str(), 0);
  }

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ConfigError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  m.def("default_threads", &default_threads);
  m.def("fidelity_assignments", &fidelity_assignments);
  m.def("builtin_scenes", &builtin_scene_names);
  m.def("builtin_programs", &builtin_program_names);
  m.def("resolve_firmware", &resolve_firmware);

  m.def("make_config", [](const std::string& file, const std::string& fidelity,
                          const std::vector<std::pair<std::string, std::string>>& sets) {
    return json_to_python(make_config(file, fidelity, sets).to_json());
  });
  m.def("describe_config", [] {
    py::list out;
    for (const ParameterInfo& p : describe_parameters()) {
      py::dict d;
      d["key"] = p.key;
      d["unit"] = p.unit;
      d["description"] = p.description;
      d["default"] = p.default_value;
      d["range"] = p.range;
      d["computed"] = p.computed;
      d["calibration"] = calibration_name(p.calibration);
      d["basis"] = p.basis;
      out.append(d);
    }
    return out;
  });
  m.def("describe_statistics",
        [](const std::string& firmware, const std::vector<std::string>& sets) {
          std::vector<StatisticInfo> infos;
          {
            KernelLock kernel;  // it runs a frame of its own
            py::gil_scoped_release release;
            infos = describe_statistics(resolve_firmware(firmware), sets);
          }
          py::dict out;
          for (const StatisticInfo& i : infos) out[py::str(i.name)] = info_dict(i);
          return out;
        });
  m.def("statistics_from_json", [](const std::string& text, const std::string& origin) {
    nlohmann::json doc;
    try {
      doc = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
      throw std::invalid_argument(fmt::format("{}: {}", origin, e.what()));
    }
    return flat_statistics(Statistics::from_json(doc));
  });

  py::class_<PyProgram>(m, "Program")
      .def_property_readonly("name", [](const PyProgram& p) { return p.program->name; })
      .def_property_readonly("listing",
                             [](const PyProgram& p) {
                               return listing(*p.program, timing_params(p.config), p.parameters(),
                                              fmt::format("scene '{}'", p.scene->name));
                             })
      .def_property_readonly("fields", [](const PyProgram& p) { return field_map(*p.program); })
      .def_property_readonly("cycles",
                             [](const PyProgram& p) {
                               return cycle_costs(*p.program, timing_params(p.config),
                                                  p.parameters());
                             })
      .def_property_readonly("bit_budget",
                             [](const PyProgram& p) { return bit_budget_dict(*p.program); })
      .def_property_readonly("bit_budget_table", [](const PyProgram& p) {
        return bit_budget_table(*p.program, timing_params(p.config));
      });

  m.def(
      "assemble",
      [](const std::string& firmware, const std::string& config_file,
         const std::vector<std::pair<std::string, std::string>>& sets, const std::string& scene) {
        PyProgram p;
        p.config = make_config(config_file, "", sets);
        p.scene = std::make_shared<const Scene>(load_scene(scene));
        p.program = std::make_shared<const Program>(load_program(firmware, *p.scene, p.config));
        return p;
      },
      py::arg("firmware"), py::arg("config_file"), py::arg("sets"), py::arg("scene"));

  py::class_<PyFrame>(m, "Frame")
      .def_readonly("index", &PyFrame::index)
      .def_readonly("image", &PyFrame::image)
      .def_readonly("fields", &PyFrame::fields)
      .def_property_readonly("stats_json",
                             [](const PyFrame& f) { return json_to_python(f.result.stats_json); })
      .def_property_readonly("statistics",
                             [](const PyFrame& f) { return flat_statistics(f.result.stats); })
      .def_property_readonly("statistics_info",
                             [](const PyFrame& f) {
                               py::dict out;
                               for (const StatisticInfo& i : f.result.stats.infos())
                                 out[py::str(i.name)] = info_dict(i);
                               return out;
                             })
      .def("stat",
           [](const PyFrame& f, const std::string& name) {
             return stat_to_python(f.result.stats.value(name));
           })
      .def_property_readonly("frame_seconds",
                             [](const PyFrame& f) { return f.result.frame_seconds; })
      .def_property_readonly("triangles_per_second",
                             [](const PyFrame& f) { return f.result.triangles_per_second; })
      .def_property_readonly("rates",
                             [](const PyFrame& f) {
                               py::dict d;
                               for (const auto& [column, name] : sweep_metric_columns())
                                 d[py::str(column)] = stat_to_python(f.result.stats.value(name));
                               return d;
                             })
      .def_property_readonly("bit_budget",
                             [](const PyFrame& f) { return bit_budget_dict(*f.program); })
      .def_property_readonly(
          "bit_budget_table",
          [](const PyFrame& f) { return bit_budget_table(*f.program, timing_params(f.config)); })
      .def_property_readonly("summary", [](const PyFrame& f) {
        return summary(f.result, *f.program, timing_params(f.config));
      });

  py::class_<PySession>(m, "Session")
      .def(py::init([](const std::string& scene, const py::object& vertices,
                       const py::object& triangles, const py::object& colors,
                       const py::object& centers, const py::object& radii,
                       const py::object& sphere_colors, const std::vector<int>& tessellation,
                       const std::string& firmware, const std::string& config_file,
                       const std::string& fidelity,
                       const std::vector<std::pair<std::string, std::string>>& sets, int threads,
                       bool animate, int frames, double fps) {
             MachineConfig config = make_config(config_file, fidelity, sets);
             // host.setup_seconds: from here to the assembled program (pp5sim render's span).
             const auto setup_start = std::chrono::steady_clock::now();
             std::shared_ptr<const Scene> s;
             std::optional<PyAnimation> animation;
             const bool arrays = !vertices.is_none() || !centers.is_none() ||
                                 !triangles.is_none() || !radii.is_none();
             if (!animate && (frames != 0 || fps != 0))
               throw std::invalid_argument("frames, fps: given without animation=True");
             if (animate && arrays) {
               throw std::invalid_argument(
                   "animation: a scene given as arrays does not move; give a built-in name or "
                   "a scene file");
             }
             if (frames < 0) throw std::invalid_argument("frames: expected a count >= 1");
             if (fps < 0) throw std::invalid_argument("fps: expected frames per second > 0");
             if (arrays) {
               s = std::make_shared<const Scene>(scene_from_arrays(
                   vertices, triangles, colors, centers, radii, sphere_colors, ""));
             } else {
               SceneOptions o;
               if (!tessellation.empty()) {
                 if (tessellation.size() != 2)
                   throw std::invalid_argument("tessellation: expected (u, v)");
                 o.tessellation_u = tessellation[0];
                 o.tessellation_v = tessellation[1];
               }
               if (animate) {
                 // The frames pp5sim animate draws for the same arguments.
                 AnimationOptions ao;
                 ao.scene = o;
                 ao.frames = frames;
                 ao.fps = fps;
                 auto a = std::make_shared<const Animation>(load_animation(scene, ao));
                 s = check_animation_scenes(*a, config);  // every frame's, checked; frame 0's
                 animation = PyAnimation{a->name(), a->motion(), a->fps(), a, a->frames(), s, 0};
               } else {
                 s = std::make_shared<const Scene>(load_scene(scene, o));
               }
             }
             auto program = std::make_shared<const Program>(load_program(firmware, *s, config));
             const double setup_seconds =
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_start)
                     .count();
             return std::make_unique<PySession>(config, s, program, threads_or_default(threads),
                                                std::move(animation), setup_seconds);
           }),
           py::arg("scene"), py::arg("vertices"), py::arg("triangles"), py::arg("colors"),
           py::arg("sphere_centers"), py::arg("sphere_radii"), py::arg("sphere_colors"),
           py::arg("tessellation"), py::arg("firmware"), py::arg("config_file"),
           py::arg("fidelity"), py::arg("sets"), py::arg("threads"), py::arg("animate") = false,
           py::arg("frames") = 0, py::arg("fps") = 0.0)
      .def("frame", &PySession::frame, py::arg("fields") = std::vector<std::string>{},
           py::arg("pixels") = true)
      .def("why", &PySession::why, py::arg("x"), py::arg("y"))
      .def("close", &PySession::close)
      .def("run_animation", &PySession::run_animation, py::arg("pixels") = true)
      .def_property_readonly("frames", &PySession::frames)
      .def_property_readonly("threads", &PySession::threads)
      .def_property_readonly("animation",
                             [](const PySession& s) -> py::object {
                               if (!s.animation()) return py::none();
                               const PyAnimation& a = *s.animation();
                               py::dict d;
                               d["name"] = a.name;
                               d["motion"] = a.motion;
                               d["frames"] = a.frames;
                               d["fps"] = a.fps;
                               return std::move(d);
                             })
      .def_property_readonly(
          "config", [](const PySession& s) { return json_to_python(s.config().to_json()); })
      .def_property_readonly("scene_name", [](const PySession& s) { return s.scene().name; })
      .def_property_readonly("triangles",
                             [](const PySession& s) { return s.scene().mesh.triangles.size(); })
      .def_property_readonly("spheres", [](const PySession& s) { return s.scene().spheres.size(); })
      .def_property_readonly("program",
                             [](const PySession& s) {
                               PyProgram p;
                               p.program = s.program();
                               p.config = s.config();
                               p.scene = s.scene_ptr();
                               return p;
                             })
      .def_property_readonly("summary", [](const PySession& s) {
        const RunSummary r = s.summary();
        py::dict d;
        d["frames"] = r.frames;
        d["simulated_seconds"] = r.simulated_seconds;
        d["mean_frame_seconds"] = r.mean_frame_seconds();
        d["shortest_frame_seconds"] = r.shortest_frame_seconds;
        d["longest_frame_seconds"] = r.longest_frame_seconds;
        d["host_seconds"] = r.host_seconds;
        d["host_over_simulated"] = r.host_over_simulated();
        d["text"] = r.text();
        const RunSummary& o = s.overlapped();
        if (o.frames > 0) {
          // An animation run overlapped (run_animation): the sustained figures.
          d["overlapped"] = o.overlapped;
          d["sustained_frame_seconds"] = o.sustained_frame_seconds;
          d["sustained_frames_per_second"] =
              o.sustained_frame_seconds > 0 ? 1 / o.sustained_frame_seconds : 0.0;
          d["mean_latency_seconds"] = o.mean_latency_seconds;
          d["longest_latency_seconds"] = o.longest_latency_seconds;
          d["overlapped_frames"] = o.overlapped_frames;
          d["text"] = r.text() + o.sustained_text();
        }
        return d;
      });

  m.def("sweep", [](const std::string& scene, int tess_u, int tess_v, const std::string& firmware,
                    const std::string& config_file, const std::string& fidelity,
                    const std::vector<std::pair<std::string, std::string>>& sets,
                    const std::vector<std::pair<std::string, std::vector<std::string>>>& axes,
                    const std::vector<std::vector<std::string>>& points, int threads) {
    const MachineConfig base = make_config(config_file, fidelity, sets);
    SceneOptions o;
    o.tessellation_u = tess_u;
    o.tessellation_v = tess_v;
    auto s = std::make_shared<const Scene>(load_scene(scene, o));
    return sweep(base, s, firmware, axes, points, threads_or_default(threads));
  });
}
