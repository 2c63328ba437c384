// The `fluid_surface` effect: each frame the sph_fluid particles become the water surface,
// meshed by marching slices (fluid/surface) or drawn straight from the particles (screen space,
// ray casting). State and mesher glue: game/world/fluid_surface.hpp.
#include "game/world/fluid_surface.hpp"
#include "engine/render/frame.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "fluid/sph/anisotropy.hpp"

#include <imgui.h>

#include <chrono>

namespace game {
namespace {

constexpr std::string_view kOrderNames[] = {"sorted", "unsorted", "exact"};
constexpr SurfaceOrderChoice kOrderValues[] = {SurfaceOrderChoice::sorted, SurfaceOrderChoice::unsorted,
                                               SurfaceOrderChoice::exact};
constexpr std::string_view kFieldNames[] = {"dense", "splat", "cache", "value", "auto"};
constexpr fluid::SurfaceFieldRoute kFieldValues[] = {
    fluid::SurfaceFieldRoute::denseScan, fluid::SurfaceFieldRoute::sliceSplat, fluid::SurfaceFieldRoute::particleCache,
    fluid::SurfaceFieldRoute::valueScan, fluid::SurfaceFieldRoute::automatic};
constexpr std::string_view kNeeds[] = {"sph_fluid"};
constexpr std::string_view kKernelNames[] = {"isotropic", "anisotropic"};
constexpr SurfaceKernel kKernelValues[] = {SurfaceKernel::isotropic, SurfaceKernel::anisotropic};
constexpr std::string_view kFilterNames[] = {"bilateral", "narrow_range"};
constexpr SurfaceDepthFilter kFilterValues[] = {SurfaceDepthFilter::bilateral, SurfaceDepthFilter::narrow_range};
// The anisotropy's neighbourhood radius r, in particle spacings: 1.5 SPH supports (the paper's
// r_i = 2h with h about one spacing would leave a surface particle of a lattice about 16
// neighbours, too few for k_n = 25, the paper's N_ε).
constexpr float kAnisotropyRadiusSpacings = 3.0f;

const ParamTable<FluidSurfaceParams>& table() {
  using P = FluidSurfaceParams;
  static const ParamTable<P> rows{
      oneOf<&P::method>("method", engine::waterBackendNames(),
                        "how the water is drawn, one of the engine's water backends: mesh (marching slices, CPU), "
                        "screen_space (splat depth, bilateral smoothing; Janisz 3.1), raycast (metaball fragment "
                        "lists; Szecsi & Illes 2012), ..."),
      choice<&P::order>("order", kOrderNames, kOrderValues,
                        "triangle order: sorted (back-to-front blocks), unsorted, exact (per slab, depth-sorted)"),
      param<&P::smoothing>("smoothing", 1.0, 4.0, "field cutoff Rc in particle spacings"),
      param<&P::cube>("cube", 0.2, 2.0, "marching cube edge in particle spacings"),
      param<&P::threshold>("threshold", 0.01, 0.24, "iso level T of the particle field"),
      choice<&P::field>("field", kFieldNames, kFieldValues,
                        "how the mesher finds the surface: dense (slice splat, every cube scanned), splat (slice "
                        "splat, seeded walk), cache (the paper's section 6 cache, seeded walk), the same vertices on "
                        "those three; value (dense scan of the value alone, normals by central differences: faster, "
                        "the vertices' last bits may differ) or auto (the library's choice)"),
      param<&P::refraction>("refraction", 0.0, 1.0, "screen offset per metre of water; 0 = off"),
      param<&P::opacity>("opacity", 0.0, 1.0, "blend alpha of one water layer"),
      param<&P::absorption>("absorption", 0.0, 50.0, "Beer-Lambert sigma per metre, RGB"),
      param<&P::visible>("visible",
                         "false: the water is not drawn (the same frame without it; docs/render.md's water masks)"),
      param<&P::async>("async",
                       "mesh on a worker thread while the next steps run, drawing the previous frame's surface "
                       "(Janisz 3.2.6); false: mesh before drawing"),
      choice<&P::kernel>("kernel", kKernelNames, kKernelValues,
                         "every renderer's kernel: isotropic (spheres) or anisotropic (ellipsoids along each "
                         "particle's neighbourhood, Yu & Turk 2013: the mesh's field, screen_space splats, raycast "
                         "metaballs, voxel splats)"),
      param<&P::k_r>("k_r", 1.0, 16.0, "anisotropic: largest ratio of a kernel's longest axis to its shortest"),
      param<&P::k_s>("k_s", 0.25, 4.0, "anisotropic: scale of a stretched kernel's axes (1: the sphere's volume)"),
      param<&P::k_n>("k_n", 0, 200,
                     "anisotropic: a particle with this many neighbours or fewer (within 3 spacings) stays a sphere"),
      param<&P::lambda>("lambda", 0.0, 1.0, "anisotropic: kernel centre smoothing towards the neighbours' mean"),
      choice<&P::ss_filter>("ss_filter", kFilterNames, kFilterValues,
                            "screen_space depth smoothing: bilateral, or narrow_range (Truong & Yuksel 2018)"),
  };
  return rows;
}

class FluidSurfaceEffect final : public EffectOf<FluidSurface> {
 public:
  explicit FluidSurfaceEffect(const SphFluid& fluid) : fluid_(fluid) {}

  std::string_view name() const override { return "fluid_surface"; }

  void applyLive(const SectionConfig& section, EffectLinks&) override { state.params = table().parse(section); }

  StepOutcome step(const StepContext&) override { return {}; }  // meshes per frame, not per step

  bool prepareFrame(const FrameContext& frame, std::string& error) override {
    const PhaseScope phase(frame.profiler, engine::Phase::meshing);
    updateAnisotropy();
    const FluidSurfaceParams& p = state.params;
    const fluid::AnisotropyParams mesh_kernels = anisotropyParams();
    const bool stretch_mesh = p.kernel == SurfaceKernel::anisotropic && p.visible;
    if (!meshFluidSurface(state, fluid_, frame.eye, frame.view_dir, stretch_mesh ? &mesh_kernels : nullptr)) {
      error = state.error;
      return false;
    }
    return true;
  }

  // The mesh (back-to-front) or the particles, with the optics; the engine's water pass draws it.
  void submit(engine::FrameBatches& frame, const SubmitContext&) override {
    const FluidSurfaceParams& p = state.params;
    engine::WaterBatch water;
    water.method = p.method;
    water.visible = p.visible;
    water.positions = state.job.mesh.positions;
    water.normals = state.job.mesh.normals;
    water.indices = state.job.mesh.indices;
    water.particles = fluid_.world.particles.position;
    // The mesh's field: Rc and T in the same units, so all three methods draw the same surface.
    water.rc = p.smoothing * fluid::sphSpacing(fluid_.world.params);
    water.threshold = p.threshold;
    if (anisotropy_valid_) {
      water.kernel_g = anisotropy_.g;
      water.kernel_max_axis = anisotropy_.max_axis;
      water.kernel_centres = anisotropy_.centre;
    }
    water.ss_filter = kFilterNames[p.ss_filter == SurfaceDepthFilter::narrow_range ? 1 : 0];
    water.refraction = p.refraction;
    water.opacity = p.opacity;
    water.absorption = p.absorption;
    water_slot_ = frame.water.size();
    frame.water.push_back(water);
  }

  void reportColumns(FrameColumns& row) const override {
    row.add("triangles", static_cast<double>(state.job.mesh.indices.size() / 3));
    row.add("mesh_worker_ms", state.job.worker_ms);
    if (state.raycast.pool == 0) return;  // only the ray caster keeps fragment lists
    row.set("raycast_records", static_cast<double>(state.raycast.records));
    row.set("raycast_dropped", static_cast<double>(state.raycast.dropped));
    row.set("raycast_pool", static_cast<double>(state.raycast.pool));
    row.set("raycast_pool_bound", static_cast<double>(state.raycast.pool_bound));
  }

  // The meshing phase split by the extractor's own clocks (fluid::SurfaceStats; block phases
  // summed over blocks).
  void drawStatus() const override {
    const fluid::SurfaceStats& surface = state.job.mesh.stats;
    ImGui::Text("fluid surface: %llu triangles, %u blocks", static_cast<unsigned long long>(surface.triangles),
                surface.blocks);
    ImGui::Text("  ms: cache %.2f  seed %.2f  march %.2f  prepare+gather %.2f", surface.cacheBuildMs, surface.seedMs,
                surface.marchMs, surface.prepareMs + surface.gatherMs);
    if (anisotropy_valid_)
      ImGui::Text("  anisotropic kernels: %zu of %zu stretched, %.2f ms", anisotropy_.stretched,
                  anisotropy_.g.size(), anisotropy_ms_);
    else if (state.kernel_ms > 0.0)  // the mesher's, made with the mesh (asynchronous: on the worker)
      ImGui::Text("  anisotropic kernels (mesh): %zu stretched, %.2f ms", state.kernels_stretched, state.kernel_ms);
    if (state.raycast.pool > 0) {
      ImGui::Text("  raycast fragments: %llu, dropped (pool full) %llu, pool %.1f MiB",
                  static_cast<unsigned long long>(state.raycast.records),
                  static_cast<unsigned long long>(state.raycast.dropped),
                  static_cast<double>(state.raycast.pool) * 16.0 / (1024.0 * 1024.0));
    }
  }

  // The backend's account of the frame it drew this effect's water in (the ray caster's fragment lists).
  void readRenderStats(std::span<const engine::WaterStats> water) override {
    state.raycast = water_slot_ < water.size() ? water[water_slot_] : engine::WaterStats{};
  }

 private:
  // The kernels' parameters from the table: the neighbourhood radius in particle spacings.
  fluid::AnisotropyParams anisotropyParams() const {
    const FluidSurfaceParams& p = state.params;
    fluid::AnisotropyParams a;
    a.radius = kAnisotropyRadiusSpacings * fluid::sphSpacing(fluid_.world.params);
    a.k_r = p.k_r;
    a.k_s = p.k_s;
    a.k_n = p.k_n;
    a.lambda = p.lambda;
    return a;
  }

  // Once per frame, for a particle renderer with kernel = anisotropic: g and the smoothed centres
  // of every particle (fluid/sph/anisotropy.hpp) from the store's positions in place (the mesher
  // makes its own with the mesh, meshFluidSurface). Rendering only: nothing here enters the state
  // hash.
  void updateAnisotropy() {
    const FluidSurfaceParams& p = state.params;
    const engine::WaterBackendDesc* backend = engine::findWaterBackend(p.method);
    anisotropy_valid_ =
        p.kernel == SurfaceKernel::anisotropic && p.visible && backend != nullptr && !backend->needs_mesh;
    if (!anisotropy_valid_) return;
    const auto t0 = std::chrono::steady_clock::now();
    // False for a non-finite position: the batch then carries the particles alone and the
    // renderer refuses them with its own message.
    anisotropy_valid_ =
        fluid::computeAnisotropy(fluid_.world.particles.position, anisotropyParams(), anisotropy_scratch_, anisotropy_);
    anisotropy_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

  const SphFluid& fluid_;
  std::size_t water_slot_ = 0;  // this frame's index in FrameBatches::water
  fluid::Anisotropy anisotropy_;
  fluid::AnisotropyScratch anisotropy_scratch_;
  bool anisotropy_valid_ = false;  // this frame's anisotropy_ matches the particles
  double anisotropy_ms_ = 0.0;
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string& error) {
  if (ctx.links.fluid == nullptr) {  // World checks `needs` first; this guards a direct call
    error = "fluid_surface: needs sph_fluid";
    return nullptr;
  }
  auto effect = std::make_unique<FluidSurfaceEffect>(*ctx.links.fluid);
  effect->state.params = table().parse(section);
  return effect;
}

}  // namespace

bool surfaceParamsFrom(const SectionConfig& section, FluidSurfaceParams& out, std::string& /*error*/) {
  out = table().parse(section);  // the schema admits only the listed methods and orders
  return true;
}

using enum ColumnFormat;
constexpr ColumnSpec kColumns[] = {
    {"triangles", count, "triangles of the meshed surfaces (the water's and the goo's)"},
    {"mesh_worker_ms", milliseconds,
     "the asynchronous meshing worker's time for the surfaces drawn (meshing_ms is then the main thread's wait)"},
    {"raycast_records", count, "method raycast: fragment records the frame asked for (0 otherwise)"},
    {"raycast_dropped", count, "method raycast: records dropped because the pool was full"},
    {"raycast_pool", count, "method raycast: the pool's size in records (16 bytes each)"},
    {"raycast_pool_bound", count, "method raycast: the most records the pool may grow to"},
};

const EffectDesc& fluidSurfaceEffect() {
  static const EffectDesc desc{"fluid_surface",
                               "marching-slices mesh of sph_fluid drawn as refractive water (needs sph_fluid)",
                               table().specs, kNeeds, &build, kColumns};
  return desc;
}

}  // namespace game
