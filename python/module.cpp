// pteryla._pteryla: the Python binding of the host API (include/pteryla/pteryla.hpp). A thin client:
// it turns numpy arrays into the API's arrays (checking shape, dtype, finiteness and index range, so a
// bad array raises pteryla.Error and never reaches the library unchecked), releases the GIL while a
// session evaluates, and hands the frame back as numpy arrays. The package around it (python/pteryla)
// adds the dict form of the set-up and the Error class.
//
// Lifetime of zero-copy frames. frame(copy=False) returns read-only arrays over the session's own
// memory; they keep the session alive (their numpy base holds it), and while any of them is alive the
// calls that would rewrite that memory (evaluate, set_pose, set_time, set_lod, set_instance_tolerance, check, ...)
// raise pteryla.Error instead of leaving them dangling.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <exception>
#include <memory>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/pteryla.hpp"

namespace py = pybind11;
using pteryla::Error;

namespace {

static_assert(sizeof(pteryla::FeatherRange) == 4 * sizeof(uint32_t), "ranges are handed out as (n, 4) uint32");

// What the zero-copy views of a session and the session share.
struct Shared {
  size_t liveViews = 0;  // frame(copy=False) results whose arrays are still alive
  bool busy = false;     // evaluate() is running with the GIL released
};

struct PySession {
  std::unique_ptr<pteryla::Session> session;
  std::shared_ptr<Shared> shared = std::make_shared<Shared>();

  // Every call that may rewrite the frame's memory or run the pipeline goes through here first.
  void requireMutable(const char* call) const {
    if (shared->busy)
      throw Error(std::string(call) +
                      ": the session is evaluating in another thread; a session is used by one thread "
                      "at a time",
                  "", "session");
    if (shared->liveViews > 0)
      throw Error(std::string(call) + ": " + std::to_string(shared->liveViews) +
                      " zero-copy frame(s) of this session are still alive and would be overwritten; delete them "
                      "or use frame(copy=True)",
                  "", "frame");
  }
  void requireIdle(const char* call) const {
    if (shared->busy) throw Error(std::string(call) + ": the session is evaluating in another thread", "", "session");
  }
};

// The base object of zero-copy arrays: keeps the session alive and counts as a live view.
struct ViewToken {
  std::shared_ptr<Shared> shared;
  py::object owner;
};

py::array toArray(py::handle h, const char* element) {
  if (py::isinstance<py::array>(h)) return py::reinterpret_borrow<py::array>(h);
  try {
    return py::array(py::module_::import("numpy").attr("asarray")(h));
  } catch (const py::error_already_set&) {
    throw Error("expected an array (numpy array or nested sequence of numbers)", "", element);
  }
}

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

void requireShape(const py::array& a, py::ssize_t cols, const char* element, const char* what) {
  const bool ok = cols == 0 ? a.ndim() == 1 : a.ndim() == 2 && a.shape(1) == cols;
  if (!ok) throw Error(std::string("expected ") + what + ", got shape " + shapeText(a), "", element);
}

// float32 or float64 (n, 3), finite.
py::array_t<double, py::array::c_style | py::array::forcecast> pointsFrom(py::handle h, const char* element) {
  py::array a = toArray(h, element);
  requireShape(a, 3, element, "shape (n, 3): x, y, z per vertex");
  if (a.dtype().kind() != 'f')
    throw Error("expected a float32 or float64 array, got dtype " + std::string(py::str(a.dtype())), "", element);
  auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  const double* p = d.data();
  for (py::ssize_t v = 0; v < d.shape(0); ++v)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(p[3 * v + c]))
        throw Error("coordinate " + std::to_string(c) + " is not a finite number", "", "vertex " + std::to_string(v));
  return d;
}

// An integer array of `cols` columns (0: one dimension), every value in [0, limit).
std::vector<uint32_t> indicesFrom(py::handle h, py::ssize_t cols, uint64_t limit, const std::string& element,
                                  const char* what, const char* rowName) {
  py::array a = toArray(h, element.c_str());
  if (a.size() == 0 && a.ndim() == 1 && cols > 0) a = a.attr("reshape")(0, cols);
  requireShape(a, cols, element.c_str(), what);
  if (a.dtype().kind() != 'i' && a.dtype().kind() != 'u')
    throw Error("expected an integer array (uint32), got dtype " + std::string(py::str(a.dtype())), "", element);
  const bool isUnsigned = a.dtype().kind() == 'u';
  std::vector<uint32_t> out(size_t(a.size()));
  const size_t width = cols ? size_t(cols) : 1;
  auto put = [&](size_t i, long double v) {
    if (v < 0 || v >= (long double)limit)
      throw Error("index " + std::to_string((long long)v) + " is out of range [0, " + std::to_string(limit) + ")", "",
                  rowName + std::string(" ") + std::to_string(i / width));
    out[i] = uint32_t(v);
  };
  if (isUnsigned) {
    auto d = py::array_t<uint64_t, py::array::c_style | py::array::forcecast>::ensure(a);
    for (size_t i = 0; i < out.size(); ++i) put(i, (long double)d.data()[i]);
  } else {
    auto d = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
    for (size_t i = 0; i < out.size(); ++i) put(i, (long double)d.data()[i]);
  }
  return out;
}

pteryla::CoatSetup setupFrom(py::handle h) {
  if (h.is_none()) return {};
  if (py::isinstance<py::dict>(h))
    return py::module_::import("pteryla._setup").attr("setup_from_dict")(h).cast<pteryla::CoatSetup>();
  try {
    return h.cast<pteryla::CoatSetup>();
  } catch (const py::cast_error&) {
    throw Error("expected a pteryla.Setup, a dict of scene sections or None", "", "setup");
  }
}

std::string pathFrom(py::handle h) { return py::str(py::module_::import("os").attr("fspath")(h)); }

std::string orderingName(pteryla::CoatSetup::Ordering o) {
  switch (o) {
    case pteryla::CoatSetup::Ordering::Axis:
      return "axis";
    case pteryla::CoatSetup::Ordering::Tracts:
      return "tracts";
    case pteryla::CoatSetup::Ordering::Flow:
      return "flow";
  }
  return "axis";
}

void setOrdering(pteryla::CoatSetup& c, const std::string& v) {
  if (v == "axis")
    c.ordering = pteryla::CoatSetup::Ordering::Axis;
  else if (v == "tracts")
    c.ordering = pteryla::CoatSetup::Ordering::Tracts;
  else if (v == "flow")
    c.ordering = pteryla::CoatSetup::Ordering::Flow;
  else
    throw Error("unknown ordering '" + v + "' (expected axis, tracts or flow)", "", "ordering.method");
}

void setPacking(pteryla::CoatSetup& c, const std::string& v) {
  if (v == "drape")
    c.packing = pteryla::CoatSetup::Packing::Drape;
  else if (v == "height_field")
    c.packing = pteryla::CoatSetup::Packing::HeightField;
  else
    throw Error("unknown packing '" + v + "' (expected drape or height_field)", "", "packing.method");
}

template <class T>
py::array arrayOf(pteryla::View<T> v, std::vector<py::ssize_t> shape, py::handle base, const char* dtype = nullptr) {
  const py::dtype dt = dtype ? py::dtype(dtype) : py::dtype::of<T>();
  if (!base) {
    py::array a(dt, shape);
    if (v.size) std::memcpy(a.mutable_data(), v.data, v.size * sizeof(T));
    return a;
  }
  py::array a(dt, shape, v.size ? static_cast<const void*>(v.data) : nullptr, base);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

struct PyFrame {
  size_t featherCount = 0;
  py::array follicleKeys, tracts, present, origins, normals, tangents, binormals, elevations;
  py::array positions, vertexNormals, uvs, alphas, vertexFeathers, triangles, ranges;
  py::list materials;
};

PyFrame frameOf(py::object self, bool copy) {
  PySession& s = self.cast<PySession&>();
  s.requireIdle("frame");
  const pteryla::Frame& f = s.session->frame();
  py::object base;
  if (!copy) {
    auto* token = new ViewToken{s.shared, self};
    base = py::capsule(token, [](void* p) {
      auto* t = static_cast<ViewToken*>(p);
      --t->shared->liveViews;
      delete t;
    });
    ++s.shared->liveViews;
  }
  const auto n = py::ssize_t(f.featherCount);
  const auto nv = py::ssize_t(f.positions.size / 3);
  PyFrame r;
  r.featherCount = f.featherCount;
  r.follicleKeys = arrayOf(f.follicleKeys, {n}, base);
  r.tracts = arrayOf(f.tracts, {n}, base);
  r.present = arrayOf(f.present, {n}, base, "bool");
  r.origins = arrayOf(f.origins, {n, 3}, base);
  r.normals = arrayOf(f.normals, {n, 3}, base);
  r.tangents = arrayOf(f.tangents, {n, 3}, base);
  r.binormals = arrayOf(f.binormals, {n, 3}, base);
  r.elevations = arrayOf(f.elevations, {n}, base);
  r.positions = arrayOf(f.positions, {nv, 3}, base);
  r.vertexNormals = arrayOf(f.vertexNormals, {nv, 3}, base);
  r.uvs = arrayOf(f.uvs, {py::ssize_t(f.uvs.size / 2), 2}, base);
  r.alphas = arrayOf(f.alphas, {py::ssize_t(f.alphas.size)}, base);
  r.vertexFeathers = arrayOf(f.vertexFeathers, {nv}, base);
  r.triangles = arrayOf(f.indices, {py::ssize_t(f.indices.size / 3), 3}, base);
  pteryla::View<uint32_t> ranges{f.ranges.empty() ? nullptr : &f.ranges.data->feather, 4 * f.ranges.size};
  r.ranges = arrayOf(ranges, {py::ssize_t(f.ranges.size), 4}, base);
  for (const pteryla::Material& m : f.materials) {
    py::dict d;
    d["name"] = m.name;
    d["texture"] = m.texture;
    d["alpha_texture"] = m.alphaTexture;
    d["pattern"] = m.pattern;
    d["base_color"] = py::make_tuple(m.baseColor[0], m.baseColor[1], m.baseColor[2]);
    d["uv"] = m.uv;
    r.materials.append(d);
  }
  return r;
}

template <class T>
py::object orNone(const std::optional<T>& v) {
  return v ? py::cast(*v) : py::none();
}

py::dict metricsDict(const pteryla::Metrics& m) {
  py::dict d;  // the keys and order of `pteryla check`
  d["follicles"] = orNone(m.follicles);
  d["hex_fraction"] = orNone(m.hexFraction);
  d["nn_cv"] = orNone(m.nnCv);
  d["feathers"] = orNone(m.feathers);
  d["intersecting_pairs"] = orNone(m.intersectingPairs);
  d["intersecting_pairs_unpacked"] = orNone(m.intersectingPairsUnpacked);
  d["intersecting_pairs_proxy"] = orNone(m.intersectingPairsProxy);
  d["skin_penetrations"] = orNone(m.skinPenetrations);
  d["coverage"] = orNone(m.coverage);
  d["elevation_p50"] = orNone(m.elevationP50);
  d["elevation_p90"] = orNone(m.elevationP90);
  d["fixed_feathers"] = orNone(m.fixedFeathers);
  d["hidden_feathers"] = orNone(m.hiddenFeathers);
  d["intersecting_feathers"] = m.intersectingPairs ? py::cast(m.intersectingFeathers) : py::none();
  d["penetrating_feathers"] = m.skinPenetrations ? py::cast(m.penetratingFeathers) : py::none();
  return d;
}

// Runs `work` with the GIL released; library exceptions cross back once the GIL is held again.
template <class F>
auto withoutGil(PySession& s, F&& work) {
  s.shared->busy = true;
  std::exception_ptr failure;
  decltype(work()) result{};
  {
    py::gil_scoped_release release;
    try {
      result = work();
    } catch (...) {
      failure = std::current_exception();
    }
  }
  s.shared->busy = false;
  if (failure) std::rethrow_exception(failure);
  return result;
}

bool evaluate(PySession& s, py::object progress) {
  s.requireMutable("evaluate");
  std::optional<py::error_already_set> pending;  // raised by the callback (or Ctrl-C); re-raised below
  const bool callable = !progress.is_none();
  if (callable && !PyCallable_Check(progress.ptr()))
    throw Error("progress must be a callable (stage: str, fraction: float) -> bool, or None", "", "progress");
  pteryla::Progress cb = [&](const std::string& stage, double fraction) {
    py::gil_scoped_acquire gil;
    if (pending) return false;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!callable) return true;
      py::object answer = progress(stage, fraction);
      if (answer.is_none()) return true;
      const int truth = PyObject_IsTrue(answer.ptr());
      if (truth < 0) throw py::error_already_set();
      return truth == 1;
    } catch (py::error_already_set& e) {
      pending = std::move(e);
      return false;
    }
  };
  const bool done = withoutGil(s, [&] { return s.session->evaluate(cb); });
  if (pending) {
    py::error_already_set e = *pending;
    pending.reset();
    throw e;
  }
  return done;
}

PySession makeSession(py::handle positions, py::handle triangles, py::handle setup, py::handle faceGroups,
                      py::handle groupNames, bool repair) {
  pteryla::SkinArrays skin;
  auto p = pointsFrom(positions, "positions");
  if (p.shape(0) == 0) throw Error("the skin has no vertices", "", "positions");
  skin.positions.assign(p.data(), p.data() + p.size());
  const uint64_t nv = uint64_t(p.shape(0));
  skin.triangles = indicesFrom(triangles, 3, nv, "triangles", "shape (m, 3): 3 vertex indices per triangle", "face");
  if (skin.triangles.empty()) throw Error("the skin has no triangles", "", "triangles");
  if (!groupNames.is_none()) skin.groupNames = groupNames.cast<std::vector<std::string>>();
  if (!faceGroups.is_none()) {
    py::array g = toArray(faceGroups, "face_groups");
    requireShape(g, 0, "face_groups", "shape (m,): a group index per face, -1 for none");
    if (g.dtype().kind() != 'i' && g.dtype().kind() != 'u')
      throw Error("expected an integer array, got dtype " + std::string(py::str(g.dtype())), "", "face_groups");
    auto d = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(g);
    for (py::ssize_t f = 0; f < d.size(); ++f) {
      const int64_t v = d.data()[f];
      if (v < -1 || v >= int64_t(skin.groupNames.size()))
        throw Error("group " + std::to_string(v) + " is not -1 or an index into group_names (" +
                        std::to_string(skin.groupNames.size()) + " names)",
                    "", "face_groups[" + std::to_string(f) + "]");
      skin.faceGroups.push_back(int32_t(v));
    }
  }
  skin.repair = repair;
  const pteryla::CoatSetup coat = setupFrom(setup);
  PySession s;
  s.session = withoutGil(s, [&] { return std::make_unique<pteryla::Session>(skin, coat); });
  return s;
}

}  // namespace

PYBIND11_MODULE(_pteryla, m) {
  m.doc() = "pteryla: bird feather coats on any triangle mesh (the host API of include/pteryla/pteryla.hpp).";

  // pteryla.Error (python/pteryla/_error.py) carries file, element and detail like pteryla::Error.
  // Held for the life of the process (a static py::object would be released after the interpreter).
  static py::handle errorType = py::object(py::module_::import("pteryla._error").attr("Error")).release();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const pteryla::Error& e) {
      py::object err = errorType(e.what(), e.file(), e.element(), e.detail());
      PyErr_SetObject(errorType.ptr(), err.ptr());
    } catch (const pteryla::InternalError& e) {
      PyErr_SetString(PyExc_RuntimeError, (std::string("pteryla internal error: ") + e.what()).c_str());
    }
  });

  m.def("version", &pteryla::version, "The library's version, e.g. '0.1.0'.");
  m.def("data_directory", &pteryla::dataDirectory,
        "The directory of the bundled data (feathers/, meshes/, scenes/, textures/).");

  py::class_<pteryla::TractSetup>(m, "Tract", R"(A feather tract: a set of skin faces carrying one kind of feather.

Fields (scene-format names in brackets): name, groups, faces, count, density, feather_file [feather],
feather_scale (0 = auto), feather_spacings, relax_iterations [relax.iterations], seed (None: derived from
the Setup's seed; an int re-scatters only this tract).)")
      .def(py::init([](std::string name, std::vector<std::string> groups, py::object faces, size_t count,
                       double density, py::object featherFile, double featherScale, double featherSpacings,
                       int relaxIterations, std::optional<uint64_t> seed, bool moult) {
             pteryla::TractSetup t;
             t.name = std::move(name);
             t.groups = std::move(groups);
             if (!faces.is_none())
               t.faces = indicesFrom(faces, 0, uint64_t(1) << 32, "faces", "shape (k,): face indices", "faces");
             t.count = count;
             t.density = density;
             if (!featherFile.is_none()) t.featherFile = pathFrom(featherFile);
             t.featherScale = featherScale;
             t.featherSpacings = featherSpacings;
             t.relaxIterations = relaxIterations;
             t.seed = seed;
             t.moult = moult;
             return t;
           }),
           py::arg("name"), py::kw_only(), py::arg("groups") = std::vector<std::string>{},
           py::arg("faces") = py::none(), py::arg("count") = 0, py::arg("density") = 0.0,
           py::arg("feather_file") = py::none(), py::arg("feather_scale") = 0.0, py::arg("feather_spacings") = 3.5,
           py::arg("relax_iterations") = 40, py::arg("seed") = py::none(), py::arg("moult") = true)
      .def_readwrite("name", &pteryla::TractSetup::name)
      .def_readwrite("groups", &pteryla::TractSetup::groups)
      .def_property(
          "faces",
          [](const pteryla::TractSetup& t) {
            return py::array_t<uint32_t>(py::ssize_t(t.faces.size()), t.faces.data());
          },
          [](pteryla::TractSetup& t, py::object f) {
            t.faces = indicesFrom(f, 0, uint64_t(1) << 32, "faces", "shape (k,): face indices", "faces");
          },
          "Face indices (triangles of the skin); with groups, their union. Neither: the whole skin.")
      .def_readwrite("count", &pteryla::TractSetup::count, "Exact number of follicles (0: use density).")
      .def_readwrite("density", &pteryla::TractSetup::density, "Follicles per unit area (count 0).")
      .def_readwrite("feather_file", &pteryla::TractSetup::featherFile,
                     "Feather definition file (docs/feather-format.md); '' = the bundled contour feather.")
      .def_readwrite("feather_scale", &pteryla::TractSetup::featherScale)
      .def_readwrite("feather_spacings", &pteryla::TractSetup::featherSpacings)
      .def_readwrite("relax_iterations", &pteryla::TractSetup::relaxIterations)
      .def_readwrite("seed", &pteryla::TractSetup::seed,
                     "This tract's own follicle seed (None: derived from Setup.seed and the tract's index).")
      .def_readwrite("moult", &pteryla::TractSetup::moult, "False: keeps its feathers when Setup.moult is enabled.")
      .def("__repr__", [](const pteryla::TractSetup& t) {
        return "pteryla.Tract(" + py::repr(py::str(t.name)).cast<std::string>() + ", count=" + std::to_string(t.count) +
               ", density=" + py::repr(py::float_(t.density)).cast<std::string>() + ")";
      });

  py::class_<pteryla::MoultSetup>(m, "Moult",
                                  R"(Feather replacement over time (docs/moult.md): a window moves through each
tract's feathers from start to start + duration; feathers in it are lost, then regrow.

Fields: enabled (False: no moult), start, duration (> 0), window (0, 1], sequence ('centre_out',
'boundary_in', 'increasing_u', 'radial', 'random', ...), gap [0, 1), random [0, 1], seed.)")
      .def(py::init([](bool enabled, double start, double duration, double window, std::string sequence, double gap,
                       double random, uint64_t seed) {
             pteryla::MoultSetup o;
             o.enabled = enabled;
             o.start = start;
             o.duration = duration;
             o.window = window;
             o.sequence = std::move(sequence);
             o.gap = gap;
             o.random = random;
             o.seed = seed;
             return o;
           }),
           py::kw_only(), py::arg("enabled") = true, py::arg("start") = 0.0, py::arg("duration") = 1.0,
           py::arg("window") = 0.2, py::arg("sequence") = "centre_out", py::arg("gap") = 0.05, py::arg("random") = 0.0,
           py::arg("seed") = 1)
      .def_readwrite("enabled", &pteryla::MoultSetup::enabled)
      .def_readwrite("start", &pteryla::MoultSetup::start)
      .def_readwrite("duration", &pteryla::MoultSetup::duration)
      .def_readwrite("window", &pteryla::MoultSetup::window)
      .def_readwrite("sequence", &pteryla::MoultSetup::sequence)
      .def_readwrite("gap", &pteryla::MoultSetup::gap)
      .def_readwrite("random", &pteryla::MoultSetup::random)
      .def_readwrite("seed", &pteryla::MoultSetup::seed);

  py::class_<pteryla::ControlSetup>(m, "Control",
                                    R"(An expressive control (docs/controls.md): at a skin point, it raises,
aims, turns, twists and lags the feathers within radius as its keys say.

Control(at, radius, *, name='', falloff=0, tracts=[], keys=[{'t': 0, 'lift': 1}], interpolation='linear',
seed=1, twist_angle=45, max_lift=90). A key is a dict with 't' and any of 'lift', 'aim', 'direction',
'random', 'dynamic' (each in [0, 1]) and 'offset' ([x, y, z]). Raises need packing 'height_field'.)")
      .def(py::init([](std::array<double, 3> at, double radius, std::string name, double falloff,
                       std::vector<std::string> tracts, py::list keys, std::string interpolation, uint64_t seed,
                       double twistAngle, double maxLift) {
             pteryla::ControlSetup c;
             c.at = at;
             c.radius = radius;
             c.name = std::move(name);
             c.falloff = falloff;
             c.tracts = std::move(tracts);
             c.interpolation = std::move(interpolation);
             c.seed = seed;
             c.twistAngleDeg = twistAngle;
             c.maxLiftDeg = maxLift;
             for (size_t k = 0; k < keys.size(); ++k) {
               const std::string where = "keys[" + std::to_string(k) + "]";
               if (!py::isinstance<py::dict>(keys[k])) throw pteryla::Error("expected a dict", "", where);
               pteryla::ControlKey key;
               bool haveT = false;
               for (auto item : keys[k].cast<py::dict>()) {
                 const std::string name = py::str(item.first);
                 if (name == "t") {
                   key.t = item.second.cast<double>();
                   haveT = true;
                 } else if (name == "offset") {
                   key.offset = item.second.cast<std::array<double, 3>>();
                 } else if (name == "lift")
                   key.lift = item.second.cast<double>();
                 else if (name == "aim")
                   key.aim = item.second.cast<double>();
                 else if (name == "direction")
                   key.direction = item.second.cast<double>();
                 else if (name == "random")
                   key.random = item.second.cast<double>();
                 else if (name == "dynamic")
                   key.dynamic = item.second.cast<double>();
                 else
                   throw pteryla::Error("unknown key (expected t, lift, aim, direction, random, dynamic, offset)", "",
                                        where + "." + name);
               }
               if (!haveT) throw pteryla::Error("a key needs its time 't'", "", where + ".t");
               c.keys.push_back(key);
             }
             return c;
           }),
           py::arg("at"), py::arg("radius"), py::kw_only(), py::arg("name") = "", py::arg("falloff") = 0.0,
           py::arg("tracts") = std::vector<std::string>{}, py::arg("keys") = py::list(),
           py::arg("interpolation") = "linear", py::arg("seed") = 1, py::arg("twist_angle") = 45.0,
           py::arg("max_lift") = 90.0)
      .def_readwrite("name", &pteryla::ControlSetup::name)
      .def_readwrite("at", &pteryla::ControlSetup::at)
      .def_readwrite("radius", &pteryla::ControlSetup::radius)
      .def_readwrite("falloff", &pteryla::ControlSetup::falloff)
      .def_readwrite("tracts", &pteryla::ControlSetup::tracts)
      .def_readwrite("interpolation", &pteryla::ControlSetup::interpolation)
      .def_readwrite("seed", &pteryla::ControlSetup::seed)
      .def_readwrite("twist_angle", &pteryla::ControlSetup::twistAngleDeg)
      .def_readwrite("max_lift", &pteryla::ControlSetup::maxLiftDeg)
      .def_property_readonly("key_count", [](const pteryla::ControlSetup& c) { return c.keys.size(); });

  py::class_<pteryla::CoatSetup>(m, "Setup", R"(The coat set-up a Session is built from.

tracts: list of Tract (empty: one tract "all" over the whole skin); axis: body axis points, head to
tail (empty: the longest bounding-box axis); ordering: "axis", "tracts" or "flow"; tract_order: tract
names bottom layer first (ordering "tracts"); packing: "drape" or "height_field"; seed: int;
moult: pteryla.Moult (default: off); controls: list of pteryla.Control.)")
      .def(py::init([](std::vector<pteryla::TractSetup> tracts, std::vector<std::array<double, 3>> axis,
                       const std::string& ordering, std::vector<std::string> tractOrder, const std::string& packing,
                       uint64_t seed, std::optional<pteryla::MoultSetup> moult,
                       std::vector<pteryla::ControlSetup> controls) {
             pteryla::CoatSetup c;
             c.tracts = std::move(tracts);
             c.axis = std::move(axis);
             setOrdering(c, ordering);
             c.tractOrder = std::move(tractOrder);
             setPacking(c, packing);
             c.seed = seed;
             if (moult) c.moult = *moult;
             c.controls = std::move(controls);
             return c;
           }),
           py::kw_only(), py::arg("tracts") = std::vector<pteryla::TractSetup>{},
           py::arg("axis") = std::vector<std::array<double, 3>>{}, py::arg("ordering") = "axis",
           py::arg("tract_order") = std::vector<std::string>{}, py::arg("packing") = "drape", py::arg("seed") = 1,
           py::arg("moult") = py::none(), py::arg("controls") = std::vector<pteryla::ControlSetup>{})
      .def_readwrite("tracts", &pteryla::CoatSetup::tracts)
      .def_readwrite("axis", &pteryla::CoatSetup::axis)
      .def_property(
          "ordering", [](const pteryla::CoatSetup& c) { return orderingName(c.ordering); }, &setOrdering,
          "Layer order for packing: 'axis', 'tracts' or 'flow' (docs/coat.md).")
      .def_readwrite("tract_order", &pteryla::CoatSetup::tractOrder)
      .def_property(
          "packing",
          [](const pteryla::CoatSetup& c) {
            return c.packing == pteryla::CoatSetup::Packing::Drape ? "drape" : "height_field";
          },
          &setPacking, "'drape' or 'height_field' (docs/packing.md).")
      .def_readwrite("seed", &pteryla::CoatSetup::seed, "Same skin + set-up + seed = same coat, bit for bit.")
      .def_readwrite("moult", &pteryla::CoatSetup::moult, "pteryla.Moult (enabled False: no moult).")
      .def_readwrite("controls", &pteryla::CoatSetup::controls, "Expressive controls: list of pteryla.Control.");

  py::class_<PyFrame>(m, "Frame", R"(One evaluated frame as numpy arrays.

Per feather (n = feather_count): follicle_keys uint64 (n,), tracts uint32 (n,), present bool (n,),
origins/normals/tangents/binormals float64 (n, 3), elevations float64 (n,) radians.
Coat mesh (v vertices, t triangles): positions/vertex_normals float32 (v, 3), uvs float32 (v, 2),
alphas float32 (v,) or (0,), vertex_feathers uint32 (v,), triangles uint32 (t, 3), ranges uint32 (r, 4)
[feather, first_index, index_count, material] per present feather bottom layer first, materials: list of
dicts (name, texture, alpha_texture, pattern, base_color, uv: 'global', 'barb' or 'growth').)")
      .def_readonly("feather_count", &PyFrame::featherCount)
      .def_readonly("follicle_keys", &PyFrame::follicleKeys)
      .def_readonly("tracts", &PyFrame::tracts)
      .def_readonly("present", &PyFrame::present)
      .def_readonly("origins", &PyFrame::origins)
      .def_readonly("normals", &PyFrame::normals)
      .def_readonly("tangents", &PyFrame::tangents)
      .def_readonly("binormals", &PyFrame::binormals)
      .def_readonly("elevations", &PyFrame::elevations)
      .def_readonly("positions", &PyFrame::positions)
      .def_readonly("vertex_normals", &PyFrame::vertexNormals)
      .def_readonly("uvs", &PyFrame::uvs)
      .def_readonly("alphas", &PyFrame::alphas)
      .def_readonly("vertex_feathers", &PyFrame::vertexFeathers)
      .def_readonly("triangles", &PyFrame::triangles)
      .def_readonly("ranges", &PyFrame::ranges)
      .def_readonly("materials", &PyFrame::materials);

  py::class_<PySession>(m, "Session", R"(A coat on one skin: build once, then per frame pose, evaluate, read.

Session(positions, triangles, setup=None, *, face_groups=None, group_names=None, repair=False)
  positions: float32/float64 (n, 3); triangles: integer (m, 3), counter-clockwise seen from outside;
  setup: pteryla.Setup, a dict of scene-format sections, or None; face_groups: int (m,) indices into
  group_names (-1 none). Bad input raises pteryla.Error naming the element.
Session.from_scene_file(path): a scene file (docs/scene-format.md) or a bare mesh.)")
      .def(py::init(&makeSession), py::arg("positions"), py::arg("triangles"), py::arg("setup") = py::none(),
           py::kw_only(), py::arg("face_groups") = py::none(), py::arg("group_names") = py::none(),
           py::arg("repair") = false)
      .def_static(
          "from_scene_file",
          [](py::object path) {
            const std::string p = pathFrom(path);
            PySession s;
            s.session =
                withoutGil(s, [&] { return std::make_unique<pteryla::Session>(pteryla::Session::fromSceneFile(p)); });
            return s;
          },
          py::arg("path"), "A session from a scene file (.json) or a bare mesh (.obj/.ply/.off/.stl).")
      .def_property_readonly(
          "vertex_count", [](const PySession& s) { return s.session->vertexCount(); },
          "Vertices of the rest skin (what set_pose expects).")
      .def_property_readonly("face_count", [](const PySession& s) { return s.session->faceCount(); })
      .def(
          "set_pose",
          [](PySession& s, py::handle positions) {
            s.requireMutable("set_pose");
            auto p = pointsFrom(positions, "positions");
            std::vector<double> v(p.data(), p.data() + p.size());
            s.session->setPose(v);
          },
          py::arg("positions"),
          "The posed skin: (n, 3) floats, the rest skin's vertex count and order. Raises pteryla.Error and keeps "
          "the last pose on bad input.")
      .def(
          "clear_pose",
          [](PySession& s) {
            s.requireMutable("clear_pose");
            s.session->clearPose();
          },
          "Back to the rest skin (or the scene's skeleton).")
      .def(
          "set_time",
          [](PySession& s, double t) {
            s.requireMutable("set_time");
            s.session->setTime(t);
          },
          py::arg("t"), "Evaluation time (moult, skeleton and controls of a scene file).")
      .def_property_readonly("time", [](const PySession& s) { return s.session->time(); })
      .def(
          "set_fixed_elevations",
          [](PySession& s, py::handle keys, py::handle elevations) {
            s.requireMutable("set_fixed_elevations");
            auto k = py::array_t<uint64_t, py::array::c_style | py::array::forcecast>::ensure(keys);
            auto e = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(elevations);
            if (!k || k.ndim() != 1) throw pteryla::Error("expected a 1-D array of follicle keys", "", "follicle_keys");
            if (!e || e.ndim() != 1) throw pteryla::Error("expected a 1-D array of radians", "", "elevations");
            std::vector<uint64_t> kv(k.data(), k.data() + k.size());
            std::vector<double> ev(e.data(), e.data() + e.size());
            try {
              s.session->setFixedElevations(kv, ev);
            } catch (const pteryla::Error& err) {
              // The host API names its parameter follicleKeys; here it is follicle_keys.
              const std::string el = err.element();
              if (el.rfind("follicleKeys", 0) != 0) throw;
              throw pteryla::Error(err.detail(), err.file(), "follicle_keys" + el.substr(12));
            }
          },
          py::arg("follicle_keys"), py::arg("elevations"),
          "Fixes these feathers' elevations (radians in [0, pi/2], by Frame.follicle_keys), replacing what "
          "packing gives them; replaces the whole set (empty arrays: none). Packing 'height_field' only.")
      .def_property(
          "pose_mode",
          [](const PySession& s) { return s.session->poseMode() == pteryla::PoseMode::Follow ? "follow" : "repack"; },
          [](PySession& s, const std::string& mode) {
            s.requireMutable("pose_mode");
            if (mode == "follow")
              s.session->setPoseMode(pteryla::PoseMode::Follow);
            else if (mode == "repack")
              s.session->setPoseMode(pteryla::PoseMode::Repack);
            else
              throw pteryla::Error("expected 'repack' or 'follow', got '" + mode + "'", "", "pose_mode");
          },
          R"(How set_pose moves the coat: 'repack' (default) re-lays it on the posed skin (a full evaluation
per pose); 'follow' lays it once on the rest skin (or the scene's skeleton pose) and lets the posed
skin carry it, elevations and drape fixed as laid (one pass over the vertices per pose).)")
      .def(
          "set_lod",
          [](PySession& s, double f) {
            s.requireMutable("set_lod");
            s.session->setLod(f);
          },
          py::arg("fraction"), "Fraction of barbs meshed, in (0, 1]. Only the mesh is redone.")
      .def_property_readonly("lod", [](const PySession& s) { return s.session->lod(); })
      .def(
          "set_instance_tolerance",
          [](PySession& s, double f) {
            s.requireMutable("set_instance_tolerance");
            s.session->setInstanceTolerance(f);
          },
          py::arg("fraction"),
          "Instancing, in [0, 0.1] (0 = off): mature feathers within this fraction of their length of an earlier "
          "feather are meshed from its curves, identical unplaced meshes stored once. Only the mesh is redone.")
      .def_property_readonly("instance_tolerance", [](const PySession& s) { return s.session->instanceTolerance(); })
      .def("evaluate", &evaluate, py::arg("progress") = py::none(),
           R"(Brings the frame up to date with the GIL released; returns True when done.

progress(stage: str, fraction: float) is called from the evaluating threads (with the GIL); returning
False cancels (evaluate returns False, and the next evaluate carries on). An exception raised by it
cancels and is re-raised here; so is Ctrl-C.)")
      .def("frame", &frameOf, py::arg("copy") = true,
           R"(The last complete evaluation (raises pteryla.Error when an input changed since: call evaluate()).

copy=True: arrays of their own. copy=False: read-only views of the session's memory without a copy;
they keep the session alive, and while any is alive the calls that would overwrite them (evaluate,
set_pose, clear_pose, set_time, set_lod, set_instance_tolerance, check) raise pteryla.Error.)")
      .def(
          "check",
          [](PySession& s) {
            s.requireMutable("check");
            return metricsDict(withoutGil(s, [&] { return s.session->metrics(); }));
          },
          "The independent checker's numbers as a dict with the keys of `pteryla check` (None = not "
          "measured). Evaluates first if needed; costs more than an evaluation.")
      .def(
          "render",
          [](PySession& s, py::object path, int width, int height, const std::string& style) {
            const std::string p = pathFrom(path);
            s.requireMutable("render");
            pteryla::RenderSettings r;
            r.width = width;
            r.height = height;
            r.style = style;
            withoutGil(s, [&] {
              s.session->render(p, r);
              return 0;
            });
          },
          py::arg("path"), py::arg("width") = 0, py::arg("height") = 0, py::arg("style") = "",
          "Renders the frame (evaluating first if needed) through Mesa's off-screen OpenGL, as `pteryla render` "
          "does, to a .png/.jpg/.tif/.exr written through a temporary file. width, height: pixels (0, 0: the "
          "scene's render.size). style: '' (the scene's), 'shaded' or "
          "'scratchboard'. Raises pteryla.Error naming the setting or file; not for pose_mode 'follow' with a pose. "
          "The session keeps its off-screen renderer (context and uploaded coat) for the next render; "
          "release_renderer() frees it.")
      .def(
          "release_renderer",
          [](PySession& s) {
            s.requireMutable("release_renderer");
            s.session->releaseRenderer();
          },
          "Frees the off-screen renderer render() keeps (its context and the uploaded skin and coat); the next "
          "render() makes a new one.")
      .def(
          "export",
          [](PySession& s, py::object path, py::object times, double fps, const std::string& coatAs,
             double metersPerUnit) -> py::object {
            const std::string p = pathFrom(path);
            const std::string ext = std::filesystem::path(p).extension().string();
            if (times.is_none() && (ext == ".obj" || ext == ".ply") && coatAs == "curves") {
              s.requireIdle("export");
              withoutGil(s, [&] {
                s.session->exportMesh(p);
                return 0;
              });
              return py::none();
            }
            // glTF/USD, or a range of times: evaluates other frames, so no view may be alive.
            s.requireMutable("export");
            pteryla::ExportSettings settings;
            settings.coatAs = coatAs;
            settings.fps = fps;
            settings.metersPerUnit = metersPerUnit;
            if (!times.is_none())
              for (py::handle t : times) settings.times.push_back(py::cast<double>(t));
            const pteryla::ExportSummary r = withoutGil(s, [&] { return s.session->exportTo(p, settings); });
            py::dict d;
            d["bytes"] = r.bytes;
            d["frames"] = r.frames;
            d["seconds"] = r.seconds;
            return std::move(d);
          },
          py::arg("path"), py::arg("times") = py::none(), py::arg("fps") = 24.0, py::arg("coat_as") = "curves",
          py::arg("meters_per_unit") = 1.0,
          "Writes the coat (and skin) by the extension: .glb/.gltf (glTF 2.0), .usda (USD; coat_as = "
          "'curves', 'cards' or 'instances'), .obj/.ply. times: a list of increasing times for an animated "
          "glTF/USD (fps sets their timing); default the session's time. Returns {bytes, frames, seconds} "
          "for glTF/USD (docs/export.md).");
}
