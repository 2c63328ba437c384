// Python module `fluiddemo` (pybind11): the fluid library from numpy.
//   vertices, normals, triangles = fluiddemo.mesh(positions, radius, threshold, cube, threads=0)
//   mesher = fluiddemo.Mesher(radius, threshold, cube); mesher.mesh(positions)  # scratch kept
//   world = fluiddemo.World("dambreak", width="0.1"); world.step(); world.positions  # zero-copy view
//   collider = fluiddemo.bake_collider("model.obj"); distance, normal, valid = collider.query(points)
// Errors raise ValueError with the messages the CLI prints (files: named with the line or item).
// Long calls release the GIL.
#include "fluid/collide/collide.hpp"
#include "fluid/collide/mesh_checks.hpp"
#include "fluid/io/obj_mesh.hpp"
#include "fluid/io/particle_io.hpp"
#include "fluid/io/vtk_io.hpp"
#include "fluid/sph/sph.hpp"
#include "fluid/sph/sph_scenes.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/mesh_io.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace py = pybind11;

namespace {

// ValueError with `message`; bytes of a file quoted in it that are not UTF-8 become U+FFFD.
[[noreturn]] void fail(const std::string& message) {
  PyObject* text = PyUnicode_DecodeUTF8(message.data(), static_cast<Py_ssize_t>(message.size()), "replace");
  PyErr_SetObject(PyExc_ValueError, text);
  Py_XDECREF(text);
  throw py::error_already_set();
}

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// (n, 3) float32 C-contiguous copy-or-view of `points`; `what` names the argument in errors.
FloatArray pointsArgument(const py::handle& points, const char* what) {
  FloatArray a = FloatArray::ensure(points);
  if (!a) fail(std::string(what) + ": not convertible to a float32 array");
  if (a.ndim() != 2 || a.shape(1) != 3)
    fail(std::string(what) + ": expected shape (n, 3), got " +
                          std::string(py::str(py::getattr(a, "shape"))));
  return a;
}

// The mesher's positions argument as a pointer + stride view (fluid::PointView): a float32 (n, 3)
// array whose three floats per row are adjacent is read in place whatever its row stride (a C array,
// or the first three columns of a wider one); anything else is converted once to a C float32 array.
// `keep` holds the array read for as long as the view is used.
fluid::PointView positionsView(const py::handle& positions, py::object& keep) {
  if (py::isinstance<py::array_t<float>>(positions)) {
    const auto a = py::reinterpret_borrow<py::array>(positions);
    if (a.ndim() == 2 && a.shape(1) == 3 && a.strides(1) == py::ssize_t(sizeof(float)) &&
        a.strides(0) >= py::ssize_t(3 * sizeof(float)) && a.strides(0) % py::ssize_t(sizeof(float)) == 0) {
      keep = a;
      return {static_cast<const float*>(a.data()), static_cast<std::size_t>(a.shape(0)),
              static_cast<std::size_t>(a.strides(0))};
    }
  }
  const FloatArray c = pointsArgument(positions, "positions");
  keep = c;
  return {c.data(), static_cast<std::size_t>(c.shape(0)), 3 * sizeof(float)};
}

// Meshes particles as `fluiddemo mesh` does and returns the arrays its mesh file holds (the same
// bits). Keeps its extractor and buffers, so meshing frame after frame allocates little.
struct Mesher {
  fluid::SurfaceParams params;
  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh surface;
  fluid::WeldedMesh welded;

  Mesher(float radius, float threshold, float cube, int threads) {
    params.rc = radius;
    params.threshold = threshold;
    params.cube = cube;
    params.threads = threads;
  }

  py::tuple mesh(const py::handle& positions) {
    py::object kept;  // the array the view reads, alive until the mesh is made
    const fluid::SurfaceInput input{positionsView(positions, kept)};
    fluid::SurfaceParams frame = params;
    if (const std::string error = fluid::unreachableThreshold(input, frame, "threshold", "positions"); !error.empty())
      fail(error);
    fluid::SurfaceStatus st;
    {
      py::gil_scoped_release unlocked;
      fluid::centreSurfaceOrigin(input, frame);
      st = extractor.extract(input, frame, surface);
      if (st.ok()) {
        fluid::MeshWriteOptions options;
        options.originX = frame.originX, options.originY = frame.originY, options.originZ = frame.originZ;
        fluid::weldSurfaceMesh(surface, options, welded);
      }
    }
    if (!st.ok()) fail(st.error);
    const py::ssize_t v = static_cast<py::ssize_t>(welded.positions.size());
    const py::ssize_t t = static_cast<py::ssize_t>(welded.indices.size() / 3);
    py::array_t<float> vertices({v, py::ssize_t{3}}), normals({v, py::ssize_t{3}});
    py::array_t<std::uint32_t> triangles({t, py::ssize_t{3}});
    std::memcpy(vertices.mutable_data(), welded.positions.data(), welded.positions.size() * sizeof(glm::vec3));
    std::memcpy(normals.mutable_data(), welded.normals.data(), welded.normals.size() * sizeof(glm::vec3));
    std::memcpy(triangles.mutable_data(), welded.indices.data(), welded.indices.size() * sizeof(std::uint32_t));
    return py::make_tuple(vertices, normals, triangles);
  }
};

py::tuple mesh(const py::handle& positions, float radius, float threshold, float cube, int threads) {
  Mesher mesher(radius, threshold, cube, threads);
  return mesher.mesh(positions);
}

// The particle files `fluiddemo mesh --in` reads (.xyz, .csv, .ply, legacy .vtk) as an (n, 3) array.
py::array_t<float> readParticles(const std::string& path) {
  fluid::ParticlePositions particles;
  fluid::IoStatus st;
  {
    py::gil_scoped_release unlocked;
    st = fluid::readParticleFile(path, particles);
  }
  if (!st.ok()) fail(st.error);
  const py::ssize_t n = static_cast<py::ssize_t>(particles.size());
  py::array_t<float> out({n, py::ssize_t{3}});
  float* p = out.mutable_data();
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  if (!particles.empty()) std::memcpy(p, particles.data(), particles.size() * sizeof(glm::vec3));
  return out;
}

// Writes (n, 3) points as .xyz, .ply (binary) or legacy .vtk (binary or ASCII); never replaces a
// file unless `force`.
void writeParticles(const std::string& path, const py::handle& points, bool binary, bool force) {
  const FloatArray a = pointsArgument(points, "points");
  fluid::ParticlePositions particles;
  const float* p = a.data();
  for (py::ssize_t i = 0; i < a.shape(0); ++i) particles.push_back({p[3 * i], p[3 * i + 1], p[3 * i + 2]});
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const fluid::OverwritePolicy overwrite = force ? fluid::OverwritePolicy::replace : fluid::OverwritePolicy::refuse;
  fluid::IoStatus st;
  if (ext == ".xyz") {
    st = fluid::writeParticleXyz(path, particles, overwrite);
  } else if (ext == ".ply") {
    st = fluid::writeParticlePly(path, particles, overwrite);
  } else if (ext == ".vtk") {
    st = fluid::writeParticleVtk(path, particles, binary ? fluid::VtkEncoding::binary : fluid::VtkEncoding::ascii,
                                 overwrite);
  } else {
    st.error = path + ": unknown particle file extension '" + ext + "' (write .xyz, .ply or .vtk)";
  }
  if (!st.ok()) fail(st.error);
}

// An SPH world made from a measurement scene (fluid/sph/sph_scenes.hpp).
struct World {
  std::unique_ptr<fluid::SphScene> scene = std::make_unique<fluid::SphScene>();
};

World makeWorld(const std::string& name, const std::string& solver, const py::kwargs& keys) {
  fluid::SphSolverKind kind;
  if (!fluid::parseSphSolver(solver, kind))
    fail("solver: unknown solver '" + solver + "' (expected wcsph or dfsph)");
  std::vector<std::pair<std::string, std::string>> overrides;
  for (const auto& [key, value] : keys) overrides.emplace_back(py::str(key), py::str(value));
  World world;
  if (const fluid::SphStatus st = fluid::makeSphScene(name, kind, overrides, *world.scene); !st.ok())
    fail(st.error);
  return world;
}

// A (n, 3) float32 view of `data` (glm::vec3 is three packed floats) that keeps `owner` alive.
py::array vec3View(const std::vector<glm::vec3>& data, py::handle owner) {
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  py::array view(py::dtype::of<float>(), {static_cast<py::ssize_t>(data.size()), py::ssize_t{3}},
                 {static_cast<py::ssize_t>(sizeof(glm::vec3)), static_cast<py::ssize_t>(sizeof(float))},
                 data.data(), owner);
  // Read-only: the arrays are the solver's own store, which a step re-sorts and moves.
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

struct Collider {
  std::shared_ptr<fluid::DepthMapCollider> shape;
};

Collider bakeCollider(const std::string& path, int resolution, const std::string& maps, int threads) {
  fluid::ObjMesh model;
  if (const fluid::IoStatus read = fluid::readObjMesh(path, model); !read.ok()) fail(read.error);
  const fluid::MeshView view{model.positions, model.indices};
  const fluid::ClosedMeshReport closed = fluid::checkClosed(view);
  if (!closed.closed())
    fail(path + ": the mesh is open: " + std::to_string(closed.boundary_edges) +
                          " boundary edges (edges of one triangle, after welding coincident vertices); depth maps "
                          "of an open mesh call points inside it outside");
  std::vector<fluid::MapSpec> specs;
  std::string error;
  if (!fluid::parseMapSpec(maps, fluid::meshBounds(view), resolution, fluid::DepthMapFormat::front_back16, specs,
                           error))
    fail("maps: " + error);
  Collider collider{std::make_shared<fluid::DepthMapCollider>()};
  fluid::BakeDesc desc;
  desc.threads = threads;
  fluid::BakeStatus st;
  {
    py::gil_scoped_release unlocked;
    st = fluid::bakeDepthMaps(view, specs, desc, *collider.shape);
  }
  if (!st.ok()) fail(path + ": " + st.error);
  return collider;
}

py::tuple queryCollider(const Collider& collider, const py::handle& points) {
  const FloatArray a = pointsArgument(points, "points");
  const py::ssize_t n = a.shape(0);
  const std::span<const glm::vec3> in(reinterpret_cast<const glm::vec3*>(a.data()), static_cast<std::size_t>(n));
  std::vector<fluid::ColliderSample> samples(in.size());
  {
    py::gil_scoped_release unlocked;
    fluid::queryParallel(*collider.shape, in, samples, {});
  }
  py::array_t<float> distance(n), normal({n, py::ssize_t{3}});
  py::array_t<bool> valid(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const fluid::ColliderSample& s = samples[static_cast<std::size_t>(i)];
    distance.mutable_at(i) = s.distance;
    for (int k = 0; k < 3; ++k) normal.mutable_at(i, k) = s.normal[k];
    valid.mutable_at(i) = s.valid;
  }
  return py::make_tuple(distance, normal, valid);
}

}  // namespace

PYBIND11_MODULE(fluiddemo, m) {
  m.doc() = "fluiddemo's fluid library: marching-slices meshing, SPH worlds, depth-map colliders";
  m.def("mesh", &mesh, py::arg("positions"), py::arg("radius") = 3.0f, py::arg("threshold") = 0.2f,
        py::arg("cube") = 1.0f, py::arg("threads") = 0,
        "Mesh particles ((n, 3) floats) by marching slices. radius: the field's cutoff radius Rc (world units, "
        "`fluiddemo mesh --rc`); threshold: iso value T; cube: lattice edge S; threads: 0 = all. Returns "
        "(vertices (v, 3) float32, normals (v, 3) float32, triangles (t, 3) uint32), the arrays `fluiddemo mesh` "
        "writes (seams welded, counter-clockwise outward).");
  py::class_<Mesher>(m, "Mesher",
                     "Mesher(radius=3, threshold=0.2, cube=1, threads=0): mesh(positions) as fluiddemo.mesh, keeping "
                     "its scratch memory between calls (for sequences of frames).")
      .def(py::init<float, float, float, int>(), py::arg("radius") = 3.0f, py::arg("threshold") = 0.2f,
           py::arg("cube") = 1.0f, py::arg("threads") = 0)
      .def("mesh", &Mesher::mesh, py::arg("positions"));
  m.def("read_particles", &readParticles, py::arg("path"),
        "Read a particle file (.xyz, .csv, .ply or legacy .vtk, as `fluiddemo mesh --in`) into an (n, 3) "
        "float32 array. Raises ValueError naming the file and line for bad content.");
  m.def("write_particles", &writeParticles, py::arg("path"), py::arg("points"), py::arg("binary") = true,
        py::arg("force") = false,
        "Write (n, 3) points as .xyz, .ply or legacy .vtk (binary=False: ASCII VTK); an existing file is "
        "replaced only with force=True.");
  m.def("scene_names", &fluid::sphSceneNames, "Names of the SPH scenes World() takes.");

  py::class_<World>(m, "World", "An SPH world made from a scene (dambreak, column, fountain, dambreak_box).")
      .def(py::init(&makeWorld), py::arg("scene"), py::arg("solver") = "dfsph",
           "World(scene, solver='dfsph', **keys): keys as `fluiddemo simulate --set key=value`.")
      .def(
          "step",
          [](World& w, float max_dt) {
            fluid::SphStatus st;
            {
              py::gil_scoped_release unlocked;
              st = fluid::stepSph(w.scene->world, max_dt);
            }
            if (!st.ok()) fail(st.error);
            return w.scene->world.last_dt;
          },
          py::arg("max_dt") = 0.0f, "One adaptive step of at most max_dt s (0: the scene's bound); returns dt.")
      .def(
          "advance",
          [](World& w, double seconds) {
            fluid::SphStatus st;
            {
              py::gil_scoped_release unlocked;
              st = fluid::advanceSph(w.scene->world, seconds, [](const fluid::SphStepStats&) {});
            }
            if (!st.ok()) fail(st.error);
          },
          py::arg("seconds"), "Steps until `seconds` have passed (the last steps land on it).")
      .def_property_readonly(
          "positions", [](py::object self) { return vec3View(self.cast<World&>().scene->world.particles.position, self); },
          "(n, 3) float32 view of the particle positions (m), no copy: valid until the next step (particles are "
          "re-sorted and may be added); its .base is the world.")
      .def_property_readonly(
          "velocities",
          [](py::object self) { return vec3View(self.cast<World&>().scene->world.particles.velocity, self); },
          "(n, 3) float32 view of the velocities (m/s), no copy, as positions.")
      .def_property_readonly(
          "ids",
          [](py::object self) {
            const auto& id = self.cast<World&>().scene->world.particles.id;
            py::array view(py::dtype::of<std::uint32_t>(), {static_cast<py::ssize_t>(id.size())}, id.data(), self);
            view.attr("setflags")(py::arg("write") = false);
            return view;
          },
          "(n,) uint32 view of the stable particle ids (the order of the arrays changes every step).")
      .def_property_readonly("time", [](const World& w) { return w.scene->world.time; })
      .def_property_readonly("particle_radius", [](const World& w) { return w.scene->world.params.particle_radius; })
      .def("__len__", [](const World& w) { return w.scene->world.particles.size(); });

  py::class_<Collider>(m, "Collider", "A baked depth-map collider (Kolb et al. 2004).")
      .def("query", &queryCollider, py::arg("points"),
           "points (n, 3) in the model's coordinates -> (distance (n,) float32, negative inside; normal (n, 3) "
           "float32, outward; valid (n,) bool, False beyond the maps' reach)")
      .def_property_readonly("depth_maps", [](const Collider& c) { return c.shape->depthMapCount(); })
      .def_property_readonly("bytes", [](const Collider& c) { return c.shape->bytes(); });
  m.def("bake_collider", &bakeCollider, py::arg("obj"), py::arg("resolution") = 128, py::arg("maps") = "axes",
        py::arg("threads") = 0,
        "Bake a closed OBJ model into depth maps (maps: as `fluiddemo bake-collider --maps`, default three "
        "front-back pairs). Raises ValueError naming the file and line for bad input.");
}
