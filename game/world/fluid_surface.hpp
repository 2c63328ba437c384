#pragma once
// The `fluid_surface` effect: each frame, marching slices (fluid/surface, Rosenberg & Birdwell
// 2008) turn the `sph_fluid` particles into a triangle mesh, emitted back-to-front for the
// camera (paper §5) so the water renderer (engine/fluid_render) can blend it in index order.
// Requires sph_fluid (buildWorld refuses a scene listing it alone). This part is CPU only; the
// effect submits the mesh or the particles as an engine::WaterBatch and the engine draws it.

#include "engine/render/frame.hpp"
#include "fluid/sph/anisotropy.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/surface_job.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace game {

enum class SurfaceOrderChoice { sorted, unsorted, exact };
// Every renderer's kernel: spheres, or ellipsoids stretched along each particle's neighbourhood
// (Yu & Turk 2013, fluid/sph/anisotropy.hpp; the mesh's field too). Screen-space's depth filter.
enum class SurfaceKernel { isotropic, anisotropic };
enum class SurfaceDepthFilter { bilateral, narrow_range };

struct FluidSurfaceParams {
  // The engine's water backend that draws it (engine/fluid_render/water_backend.hpp); only the
  // backends that draw a mesh run the CPU mesher.
  std::string method = "mesh";
  SurfaceOrderChoice order = SurfaceOrderChoice::sorted;
  float smoothing = 2.0f;  // Rc in particle spacings
  float cube = 0.5f;       // lattice cube edge S in particle spacings
  float threshold = 0.2f;  // iso level T in (0, 0.25)
  // How the mesher finds the surface (fluid::SurfaceFieldRoute; the exact routes give the same
  // vertices, the dense scan also the rare pieces §4's seeds miss; the value scan is faster, with
  // central-difference normals). The dense scan by default (the library's automatic choice too): at the game's
  // lattice (Rc = 4 S) it costs less than the slice splat's seeded walk and the paper's §6 cache
  // on the fountain's frames (docs/surface.md, "The game's scale").
  fluid::SurfaceFieldRoute field = fluid::SurfaceFieldRoute::denseScan;
  float refraction = 0.08f;  // engine::WaterParams::refraction; 0 = off
  float opacity = 0.85f;
  glm::vec3 absorption = engine::WaterParams{}.absorption;  // Beer–Lambert σ per metre
  bool visible = true;  // false: the renderer draws no water (the mesher still runs)
  // Mesh on a worker thread while the next steps run and draw the previous frame's surface
  // (Janisz §3.2.6); false: mesh the current particles before drawing them.
  bool async = true;
  // Anisotropic kernels (fluid::AnisotropyParams; the mapping to the paper's names is in
  // fluid/sph/anisotropy.hpp), computed once per frame for every renderer (the mesher too).
  SurfaceKernel kernel = SurfaceKernel::isotropic;
  float k_r = 4.0f;     // largest axis ratio
  float k_s = 1.0f;     // axis scale (1: the sphere's volume)
  int k_n = 25;         // more neighbours than this to be stretched
  float lambda = 0.9f;  // kernel centre smoothing
  SurfaceDepthFilter ss_filter = SurfaceDepthFilter::bilateral;
};

// Reads a validated "fluid_surface" section through the effect's parameter table
// (game/effects/fluid_surface.cpp). The schema already refused unknown methods and orders, so it
// returns true; the signature stays for callers that check.
bool surfaceParamsFrom(const SectionConfig& section, FluidSurfaceParams& out, std::string& error);

// The mesher's parameters meshFluidSurface uses for particles `spacing` apart (fluid::sphSpacing),
// seen from `eye` along `view_dir` (threads left at the extractor's default). Public so that
// benchmarks mesh with exactly the game's settings.
fluid::SurfaceParams surfaceParamsFor(const FluidSurfaceParams& p, float spacing, glm::vec3 eye, glm::vec3 view_dir);

// The mesher's anisotropic kernels (Yu & Turk 2013, fluid/sph/anisotropy.hpp), made with the mesh:
// on the caller's thread when meshing is synchronous, inside the worker's job when asynchronous
// (from the job's own copy of the positions), so an asynchronous frame's main thread pays only the
// copy. Held by pointer: the worker's job reads it at a fixed address.
struct SurfaceKernelJob {
  std::vector<glm::vec3> positions;  // the asynchronous job's copy
  fluid::AnisotropyParams params;
  fluid::SurfaceParams surface;
  fluid::AnisotropyScratch scratch;
  fluid::Anisotropy kernels;
  double ms = 0.0;  // the kernels' time in the job last run (written by the job)
};

struct FluidSurface {
  FluidSurfaceParams params;
  // Made at the first anisotropic mesh; declared before `job`, so a worker job reading it is
  // finished (the job's worker stops) before it goes.
  std::unique_ptr<SurfaceKernelJob> kernel_job;
  SurfaceJob job;            // the mesh drawn this frame and the worker's time on it (game/world/surface_job.hpp)
  std::uint64_t meshes = 0;  // frames meshed
  std::string error;         // last extraction error (mesh cleared then)
  std::size_t kernels_stretched = 0;             // the mesh's kernels: stretched particles and CPU ms
  double kernel_ms = 0.0;                        // (0 for spheres)
  // Method raycast, last frame (engine::lastWaterStats, read after the frame): fragment-list
  // records asked for and records dropped because the pool was full, and the pool's size in
  // records after the frame (it grows with the demand up to pool_bound).
  engine::WaterStats raycast;
};

// Meshes the current particles of `fluid` for an eye at `eye` looking along `view_dir`. With
// method screen_space or raycast the mesh is left empty (those renderers draw the particles).
// With params.async, `job.mesh` becomes the surface of the particles handed over at the previous
// call and the current ones start meshing on the worker; the first call (nothing handed over yet)
// waits for its own job, so the first frame has water. Returns false with surface.error set when
// extraction refuses the input (async: the input of the job collected).
// `anisotropy` (null for spheres): the mesh is the field of the particles' anisotropic kernels, their
// ellipsoids at the smoothed centres (fluid::SurfaceInput::stretch), made as SurfaceKernelJob says.
bool meshFluidSurface(FluidSurface& surface, const SphFluid& fluid, glm::vec3 eye, glm::vec3 view_dir,
                      const fluid::AnisotropyParams* anisotropy = nullptr);

}  // namespace game
