#include "engine/fluid_render/voxel.hpp"
#include "engine/fluid_render/water_backend.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

namespace engine {
namespace {

// Shader storage bindings (shaders/voxel_*.comp).
enum Binding : GLuint {
  kParticles = 0,
  kLayers = 1,
  kBits = 2,
  kSpans = 3,
  kMeta = 4,
  kLinks = 5,
  kDepthA = 6,
  kDepthB = 7,
  kDepthC = 8,
  kSelection = 9,
  kInnerCells = 10,
  kShapes = 11,
};

bool drawsEllipsoids(const VoxelRenderer& r) { return r.shapes.count > 0 && r.shapes.count == r.particles.count; }

GLuint buildVoxelProgram(std::vector<ShaderStageFiles> stages, std::string& error) {
  return buildProgram(stages, voxelShaderPrelude(stages), error);
}

void resizeBuffer(GLuint buffer, std::size_t bytes) {
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(bytes, 16)), nullptr,
               GL_DYNAMIC_COPY);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
}

void setGridUniforms(GLuint p, const VoxelRenderer& r) {
  const glm::mat4& proj = r.view.projection;
  glUniform2i(glGetUniformLocation(p, "u_size"), r.view.width, r.view.height);
  setUniform(p, "u_proj", glm::vec4(proj[0][0], proj[1][1], proj[2][0], proj[2][1]));
  setUniform(p, "u_layer_count", r.layers.count);
  setUniform(p, "u_words", r.layers.words);
  setUniform(p, "u_max_spans", r.desc.max_spans);
}

void dispatchPixels(int w, int h) {
  glDispatchCompute(static_cast<GLuint>((w + 7) / 8), static_cast<GLuint>((h + 7) / 8), 1);
}

using Clock = std::chrono::steady_clock;

// Wall time of a stage when timing is asked for (glFinish first: GL queues work).
struct StageTimer {
  bool on = false;
  Clock::time_point start;
  explicit StageTimer(bool enabled) : on(enabled) {
    if (on) {
      glFinish();
      start = Clock::now();
    }
  }
  void stop(double& ms) {
    if (!on) return;
    glFinish();
    ms += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  }
};

}  // namespace

std::string voxelShaderPrelude(std::span<const ShaderStageFiles> stages) {
  // GLSL 3.30 (so the shared shading files compile unchanged) plus what the passes use: compute,
  // SSBOs, image/atomic ops, findLSB and `precise` (gpu_shader5), packSnorm2x16. The compute
  // extension goes only into compute programs: NVIDIA's compiler takes a vertex or fragment shader
  // that enables it for a compute shader and refuses its user-defined outputs.
  const bool compute =
      std::any_of(stages.begin(), stages.end(), [](const ShaderStageFiles& s) { return s.stage == GL_COMPUTE_SHADER; });
  return std::string(compute ? "#extension GL_ARB_compute_shader : enable\n" : "") +
         "#extension GL_ARB_shader_storage_buffer_object : require\n"
         "#extension GL_ARB_shader_image_load_store : require\n"
         "#extension GL_ARB_shading_language_420pack : require\n"
         "#extension GL_ARB_gpu_shader5 : require\n"
         "#extension GL_ARB_shading_language_packing : require\n";
}

void createVoxelRenderer(const VoxelDesc& desc, VoxelRenderer& out) {
  destroyVoxelRenderer(out);
  out = VoxelRenderer{};
  out.desc = desc;
  const int w = desc.base.width, h = desc.base.height;
  if (w < 1 || h < 1 || w > 8192 || h > 8192) {
    out.error = "voxel fluid: size " + std::to_string(w) + "x" + std::to_string(h) + " out of range 1..8192";
    return;
  }
  if (desc.max_spans < 1 || desc.max_spans > 7) {
    out.error = "voxel fluid: max_spans " + std::to_string(desc.max_spans) + " out of range 1..7";
    return;
  }
  if (desc.max_layers < 32 || desc.max_layers > 16384) {
    out.error = "voxel fluid: max_layers " + std::to_string(desc.max_layers) + " out of range 32..16384";
    return;
  }
  if (desc.tile_budget_bytes < 4096) {
    out.error = "voxel fluid: tile_budget_bytes " + std::to_string(desc.tile_budget_bytes) + " below 4096";
    return;
  }
  const std::filesystem::path dir = desc.base.shader_dir, fluid_dir = dir / "fluid";
  const std::filesystem::path common = dir / "voxel_common.glsl", surface = dir / "voxel_surface.glsl";
  std::string error;
  auto compute = [&](std::vector<std::filesystem::path> files) {
    const GLuint p = buildVoxelProgram({{GL_COMPUTE_SHADER, std::move(files)}}, error);
    out.error += error;
    return p;
  };
  out.splat_program = compute({common, dir / "voxel_splat.comp"});
  out.compress_program = compute({common, dir / "voxel_compress.comp"});
  out.connect_program = compute({common, dir / "voxel_connect.comp"});
  out.filter_program = compute({common, surface, dir / "voxel_filter.comp"});
  out.normals_program = compute({common, surface, dir / "voxel_normals.comp"});
  out.shade_program = buildVoxelProgram({{GL_VERTEX_SHADER, {fluid_dir / "blit.vert"}},
                                         {GL_FRAGMENT_SHADER,
                                          {fluid_dir / "shading.glsl", fluid_dir / "depth.glsl", fluid_dir / "ray.glsl",
                                           fluid_dir / "water_shade.glsl", common, dir / "voxel_shade.frag"}}},
                                        error);
  out.error += error;
  out.blit_program = buildProgram(std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {fluid_dir / "blit.vert"}},
                                                                {GL_FRAGMENT_SHADER, {fluid_dir / "blit.frag"}}},
                                  "", error);
  out.error += error;
  if (!out.error.empty()) {
    out.error = "voxel fluid disabled, shader build failed:\n" + out.error;
    return;
  }
  const bool scene_ok = createSceneTargets(w, h, out.scene);
  for (GLuint* b : {&out.shapes.buffer, &out.selection, &out.inner_cells, &out.layer_table, &out.tile_bits, &out.spans,
                    &out.meta, &out.links, &out.depth_raw, &out.depth_ping, &out.depth_pong, &out.normals}) {
    glGenBuffers(1, b);
    resizeBuffer(*b, 16);
  }
  // What outlives the tiles (§4.5, §5.2), per pixel: its column record, and per stored span the
  // layers, links, three depth pairs (raw and the filter's ping-pong) and two normals.
  const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  const std::size_t per_span = static_cast<std::size_t>(desc.max_spans) * pixels;
  resizeBuffer(out.spans, per_span * 8);
  resizeBuffer(out.meta, pixels * 16);
  resizeBuffer(out.links, per_span * 8);
  for (GLuint b : {out.depth_raw, out.depth_ping, out.depth_pong}) resizeBuffer(b, per_span * 8);
  resizeBuffer(out.normals, per_span * 8);
  out.stats.span_bytes = pixels * 16 + per_span * 8 * 6;
  createParticleBuffer(out.particles, out.vao);
  glGenVertexArrays(1, &out.empty_vao);
  if (!scene_ok || glGetError() != GL_NO_ERROR) {
    out.error = "voxel fluid disabled: storage buffers not supported (needs GL 4.3 SSBOs and compute)";
    return;
  }
  out.ready = true;
}

GlObjectNames glNames(const VoxelRenderer& r) {
  GlObjectNames n;
  if (r.scene.fbo != 0) listNames(r.scene, n);
  for (GLuint b : {r.particles.buffer, r.shapes.buffer, r.selection, r.inner_cells, r.layer_table, r.tile_bits, r.spans,
                   r.meta, r.links, r.depth_raw, r.depth_ping, r.depth_pong, r.normals})
    if (b != 0) n.buffers.push_back(b);
  for (GLuint v : {r.vao, r.empty_vao})
    if (v != 0) n.vertex_arrays.push_back(v);
  for (GLuint p : {r.splat_program, r.compress_program, r.connect_program, r.filter_program, r.normals_program,
                   r.shade_program, r.blit_program})
    if (p != 0) n.programs.push_back(p);
  return n;
}

void destroyVoxelRenderer(VoxelRenderer& r) {
  destroySceneTargets(r.scene);
  for (GLuint* b : {&r.particles.buffer, &r.shapes.buffer, &r.selection, &r.inner_cells, &r.layer_table, &r.tile_bits,
                    &r.spans, &r.meta, &r.links, &r.depth_raw, &r.depth_ping, &r.depth_pong, &r.normals})
    if (*b != 0) glDeleteBuffers(1, b);
  for (GLuint* v : {&r.vao, &r.empty_vao})
    if (*v != 0) glDeleteVertexArrays(1, v);
  for (GLuint p : {r.splat_program, r.compress_program, r.connect_program, r.filter_program, r.normals_program,
                   r.shade_program, r.blit_program})
    if (p != 0) glDeleteProgram(p);
  const VoxelDesc desc = r.desc;
  r = VoxelRenderer{};
  r.desc = desc;
}

void beginVoxelOpaquePass(VoxelRenderer& r, glm::vec4 clear_colour) {
  if (!r.ready) return;
  glBindFramebuffer(GL_FRAMEBUFFER, r.scene.fbo);
  glViewport(0, 0, r.desc.base.width, r.desc.base.height);
  glClearColor(clear_colour.r, clear_colour.g, clear_colour.b, clear_colour.a);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

namespace {

// Spheres (g empty) or ellipsoids at `positions`, then the §4.3 pre-pass.
bool uploadVoxelSet(VoxelRenderer& r, std::span<const glm::vec3> positions, std::span<const glm::mat3> g,
                    std::span<const float> max_axis, bool ellipsoids, float cell, int full_count, std::string& error) {
  r.bounds_lo = glm::vec3(0.0f);
  r.bounds_hi = glm::vec3(-1.0f);
  r.use_selection = false;
  r.selection_count = 0;
  r.inner_count = 0;
  r.max_axis = 1.0f;
  r.stats.ellipsoids = false;
  if (ellipsoids) {
    if (!uploadEllipsoids(r.particles, r.shapes, positions, g, max_axis, error)) return false;
    for (float a : max_axis) r.max_axis = std::max(r.max_axis, a);
    r.stats.ellipsoids = drawsEllipsoids(r);
  } else {
    r.shapes.count = 0;
    if (!uploadParticles(r.particles, positions, error)) return false;
  }
  r.stats.particles = r.particles.count;
  r.stats.splatted = r.particles.count;
  r.stats.inner_cells = 0;
  if (positions.empty()) return true;
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const glm::vec3& p : positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  r.bounds_lo = lo;
  r.bounds_hi = hi;
  if (cell > 0.0f && r.selection != 0) {
    std::vector<std::uint32_t> kept;
    std::vector<glm::vec3> inner;
    kept.reserve(positions.size());
    fluid::dropInnerCellParticles(positions, cell, full_count, kept, inner);
    std::vector<glm::vec4> spheres(inner.size());
    for (std::size_t i = 0; i < inner.size(); ++i) spheres[i] = glm::vec4(inner[i], fluid::kInnerCellRadius * cell);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.selection);
    glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(kept.size() * 4, 16)),
                 kept.data(), GL_STREAM_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.inner_cells);
    glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(spheres.size() * 16, 16)),
                 spheres.data(), GL_STREAM_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    r.use_selection = true;
    r.selection_count = static_cast<std::uint32_t>(kept.size());
    r.inner_count = static_cast<std::uint32_t>(spheres.size());
    r.stats.splatted = r.selection_count;
    r.stats.inner_cells = r.inner_count;
  }
  return true;
}

}  // namespace

bool uploadVoxelParticles(VoxelRenderer& r, std::span<const glm::vec3> positions, float cell, int full_count,
                          std::string& error) {
  return uploadVoxelSet(r, positions, {}, {}, false, cell, full_count, error);
}

bool uploadVoxelParticles(VoxelRenderer& r, std::span<const glm::vec3> positions, std::string& error) {
  return uploadVoxelSet(r, positions, {}, {}, false, 0.0f, 0, error);
}

bool uploadVoxelEllipsoids(VoxelRenderer& r, std::span<const glm::vec3> centres, std::span<const glm::mat3> g,
                           std::span<const float> max_axis, float cell, int full_count, std::string& error) {
  return uploadVoxelSet(r, centres, g, max_axis, true, cell, full_count, error);
}

bool uploadVoxelEllipsoids(VoxelRenderer& r, std::span<const glm::vec3> centres, std::span<const glm::mat3> g,
                           std::span<const float> max_axis, std::string& error) {
  return uploadVoxelSet(r, centres, g, max_axis, true, 0.0f, 0, error);
}

bool voxelBeginFrame(VoxelRenderer& r, const FluidCamera& camera, const VoxelParams& params,
                     std::vector<fluid::VoxelTile>& tiles) {
  tiles.clear();
  const int w = r.desc.base.width, h = r.desc.base.height;
  r.view = fluid::VoxelView{w, h, camera.view, camera.projection};
  if (!r.ready || r.particles.count == 0 || r.bounds_lo.x > r.bounds_hi.x) return false;
  // View-adaptive depth range (§3.1): the particles' box in this view, widened by the radius (an
  // ellipsoid's bounding radius) and cut to the camera's planes, so the layers are spent where the
  // water is.
  const float radius = std::max(params.radius, 1e-5f) * std::max(r.max_axis, 1.0f);
  float dmin = std::numeric_limits<float>::max(), dmax = -dmin;
  for (int corner = 0; corner < 8; ++corner) {
    const glm::vec3 p((corner & 1) ? r.bounds_hi.x : r.bounds_lo.x, (corner & 2) ? r.bounds_hi.y : r.bounds_lo.y,
                      (corner & 4) ? r.bounds_hi.z : r.bounds_lo.z);
    const float d = -(camera.view * glm::vec4(p, 1.0f)).z;
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  const float nearest = std::max(camera.near_plane, dmin - radius);
  const float farthest = std::min(camera.far_plane, dmax + radius);
  if (!(farthest > nearest)) return false;
  fluid::makeVoxelLayers(r.view, nearest, farthest, params.angle_degrees, r.desc.max_layers, r.layers);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.layer_table);
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(r.layers.depth.size() * sizeof(float)),
               r.layers.depth.data(), GL_STREAM_DRAW);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  // Tiles (§3.1): the largest run of whole rows whose bit grid fits the budget (Table 1: wide
  // tiles splat fewer times), or a forced size.
  const std::size_t column_bytes = static_cast<std::size_t>(r.layers.words) * 4;
  const std::size_t fit = std::max<std::size_t>(r.desc.tile_budget_bytes / column_bytes, 1);
  int tw = r.desc.tile_width > 0 ? std::min(r.desc.tile_width, w) : static_cast<int>(std::min<std::size_t>(fit, w));
  int th = r.desc.tile_height > 0 ? std::min(r.desc.tile_height, h)
                                  : static_cast<int>(std::clamp<std::size_t>(fit / tw, 1, h));
  const std::size_t grid_bytes = static_cast<std::size_t>(tw) * th * column_bytes;
  if (grid_bytes > r.tile_bits_bytes) {
    resizeBuffer(r.tile_bits, grid_bytes);
    r.tile_bits_bytes = grid_bytes;
  }
  for (int y = 0; y < h; y += th)
    for (int x = 0; x < w; x += tw) tiles.push_back({x, y, std::min(tw, w - x), std::min(th, h - y)});
  VoxelStats& s = r.stats;
  s.layers = r.layers.count;
  s.words = r.layers.words;
  s.angle_degrees = r.layers.angle_degrees;
  s.nearest = nearest;
  s.farthest = farthest;
  s.tiles = static_cast<int>(tiles.size());
  s.tile_width = tw;
  s.tile_height = th;
  s.tile_grid_bytes = grid_bytes;
  s.dense_grid_bytes = static_cast<std::uint64_t>(w) * h * column_bytes;
  return true;
}

void voxelSplatTile(VoxelRenderer& r, const VoxelParams& params, fluid::VoxelTile tile) {
  const std::size_t bytes = static_cast<std::size_t>(tile.width) * tile.height * r.layers.words * 4;
  const GLuint zero = 0;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.tile_bits);
  glClearBufferSubData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, 0, static_cast<GLsizeiptr>(bytes), GL_RED_INTEGER,
                       GL_UNSIGNED_INT, &zero);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  const GLuint p = r.splat_program;
  glUseProgram(p);
  setGridUniforms(p, r);
  setUniform(p, "u_world_to_view", r.view.view);
  setUniform(p, "u_radius", std::max(params.radius, 1e-5f));
  glUniform4i(glGetUniformLocation(p, "u_tile"), tile.x, tile.y, tile.width, tile.height);
  const std::uint32_t count = r.use_selection ? r.selection_count : r.particles.count;
  const std::uint32_t inner = r.use_selection ? r.inner_count : 0u;
  const std::uint32_t groups = (count + inner + 63) / 64, row_groups = std::min<std::uint32_t>(groups, 65535);
  glUniform1ui(glGetUniformLocation(p, "u_count"), count);
  glUniform1ui(glGetUniformLocation(p, "u_inner_count"), inner);
  glUniform1ui(glGetUniformLocation(p, "u_row"), row_groups * 64);
  setUniform(p, "u_use_selection", r.use_selection ? 1 : 0);
  setUniform(p, "u_ellipsoids", drawsEllipsoids(r) ? 1 : 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kParticles, r.particles.buffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kShapes, r.shapes.buffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kLayers, r.layer_table);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBits, r.tile_bits);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSelection, r.selection);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kInnerCells, r.inner_cells);
  if (groups > 0) glDispatchCompute(row_groups, (groups + row_groups - 1) / row_groups, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  glUseProgram(0);  // Mesa 22.3 kept a program current after a compute dispatch alive past its deletion
}

void voxelCompressTile(VoxelRenderer& r, const VoxelParams& params, fluid::VoxelTile tile) {
  const GLuint p = r.compress_program;
  glUseProgram(p);
  setGridUniforms(p, r);
  glUniform4i(glGetUniformLocation(p, "u_tile"), tile.x, tile.y, tile.width, tile.height);
  setUniform(p, "u_min_gap", std::max(params.min_gap, 0.0f));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kLayers, r.layer_table);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBits, r.tile_bits);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSpans, r.spans);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kMeta, r.meta);
  dispatchPixels(tile.width, tile.height);
  // The next tile's clear and splat overwrite the grid this pass reads.
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  glUseProgram(0);
}

void voxelSurfaces(VoxelRenderer& r, const VoxelParams& params) {
  const int w = r.view.width, h = r.view.height;
  StageTimer connect_timer(params.time_stages);
  GLuint p = r.connect_program;
  glUseProgram(p);
  setGridUniforms(p, r);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kLayers, r.layer_table);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSpans, r.spans);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kMeta, r.meta);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kLinks, r.links);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthA, r.depth_raw);
  dispatchPixels(w, h);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  connect_timer.stop(r.stats.connect_ms);

  // §4.6: iterations until the farthest-reaching point is done; each point stops at its own count.
  StageTimer filter_timer(params.time_stages);
  const int iterations = params.filter_radius > 0.0f ? std::clamp(params.max_filter_iterations, 0, 20) : 0;
  GLuint in = r.depth_raw;
  p = r.filter_program;
  glUseProgram(p);
  setGridUniforms(p, r);
  setUniform(p, "u_max_iterations", iterations);
  setUniform(p, "u_filter_radius", std::max(params.filter_radius, 0.0f));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthC, r.depth_raw);
  for (int i = 0; i < iterations; ++i) {
    const GLuint out = (i % 2 == 0) ? r.depth_ping : r.depth_pong;
    setUniform(p, "u_iteration", i);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthA, in);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthB, out);
    dispatchPixels(w, h);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    in = out;
  }
  r.depth_final = in;
  filter_timer.stop(r.stats.filter_ms);

  StageTimer normals_timer(params.time_stages);
  p = r.normals_program;
  glUseProgram(p);
  setGridUniforms(p, r);
  setUniform(p, "u_world_to_view", r.view.view);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthA, r.depth_final);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthB, r.normals);
  dispatchPixels(w, h);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  glUseProgram(0);
  normals_timer.stop(r.stats.normals_ms);
}

void readVoxelTileBits(const VoxelRenderer& r, fluid::VoxelTile tile, std::vector<std::uint32_t>& words) {
  words.assign(static_cast<std::size_t>(tile.width) * tile.height * r.layers.words, 0u);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.tile_bits);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(words.size() * 4), words.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
}

void readVoxelSpans(const VoxelRenderer& r, std::vector<fluid::VoxelSpan>& spans,
                    std::vector<fluid::VoxelColumn>& columns) {
  const std::size_t pixels = static_cast<std::size_t>(r.desc.base.width) * r.desc.base.height;
  spans.assign(pixels * r.desc.max_spans, {});
  std::vector<std::uint32_t> meta(pixels * 4);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.spans);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(spans.size() * 8), spans.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.meta);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(meta.size() * 4), meta.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  columns.resize(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    columns[i].stored = meta[4 * i];
    columns[i].total = meta[4 * i + 1];
    std::memcpy(&columns[i].hidden_gap, &meta[4 * i + 2], 4);
  }
}

void drawVoxelFluid(VoxelRenderer& r, GLuint target_fbo, const FluidCamera& camera, const WaterParams& water,
                    const VoxelParams& params) {
  if (!r.ready) return;
  const int w = r.desc.base.width, h = r.desc.base.height;
  VoxelStats& s = r.stats;
  s.splat_ms = s.compress_ms = s.connect_ms = s.filter_ms = s.normals_ms = s.shade_ms = 0.0;
  glViewport(0, 0, w, h);
  glDisable(GL_CULL_FACE);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glActiveTexture(GL_TEXTURE0);
  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glUseProgram(r.blit_program);
  glBindTexture(GL_TEXTURE_2D, r.scene.colour);
  setUniform(r.blit_program, "u_colour", 0);
  glBindVertexArray(r.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  std::vector<fluid::VoxelTile> tiles;
  if (!voxelBeginFrame(r, camera, params, tiles)) {
    glBindVertexArray(0);
    glUseProgram(0);
    return;
  }
  for (const fluid::VoxelTile& tile : tiles) {
    StageTimer splat(params.time_stages);
    voxelSplatTile(r, params, tile);
    splat.stop(s.splat_ms);
    StageTimer compress(params.time_stages);
    voxelCompressTile(r, params, tile);
    compress.stop(s.compress_ms);
  }
  voxelSurfaces(r, params);

  StageTimer shade_timer(params.time_stages);
  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glViewport(0, 0, w, h);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  const GLuint p = r.shade_program;
  glUseProgram(p);
  setParticleCamera(p, camera, w, h);
  setWaterShading(p, water);
  setGridUniforms(p, r);
  setUniform(p, "u_refraction_rays", params.refraction_rays ? 1 : 0);
  setUniform(p, "u_max_ray_steps", std::clamp(params.max_ray_steps, 1, 256));
  setUniform(p, "u_max_ray_length", std::max(params.max_ray_length, 0.0f));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kLayers, r.layer_table);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kMeta, r.meta);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthA, r.depth_final);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kDepthB, r.normals);
  const GLuint textures[] = {r.scene.colour, r.scene.depth};
  const char* names[] = {"u_scene_colour", "u_scene_depth"};
  for (int i = 0; i < 2; ++i) {
    glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(i));
    glBindTexture(GL_TEXTURE_2D, textures[i]);
    setUniform(p, names[i], i);
  }
  glBindVertexArray(r.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDisable(GL_BLEND);
  glActiveTexture(GL_TEXTURE0);
  for (GLuint i = 0; i <= kShapes; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, 0);
  glBindVertexArray(0);
  glUseProgram(0);  // a deleted program stays alive while current
  shade_timer.stop(s.shade_ms);
  if (params.time_stages) {
    std::vector<fluid::VoxelSpan> spans;
    std::vector<fluid::VoxelColumn> columns;
    readVoxelSpans(r, spans, columns);
    s.stored_spans = s.overflow_columns = 0;
    for (const fluid::VoxelColumn& c : columns) {
      s.stored_spans += c.stored;
      s.overflow_columns += c.total > c.stored;
    }
  }
}

// The voxel renderer as a water backend (water_backend.hpp): the game draws with it by name.
namespace {

class VoxelWaterBackend final : public WaterBackend {
 public:
  explicit VoxelWaterBackend(const FluidRenderDesc& desc) {
    VoxelDesc voxel;
    voxel.base = desc;
    createVoxelRenderer(voxel, renderer_);
  }
  ~VoxelWaterBackend() override { destroyVoxelRenderer(renderer_); }
  bool ready() const override { return renderer_.ready; }
  const std::string& error() const override { return renderer_.error; }
  GLuint upload(const WaterInput& in, std::string& error) override {
    if (!renderer_.ready) return 0;
    // Anisotropic kernels when the input carries them (one per particle): ellipsoids at the
    // smoothed centres, the radius unchanged (a sphere's g is the identity).
    const bool ellipsoids = !in.kernel_g.empty() && in.kernel_g.size() == in.particles.size();
    const bool ok = ellipsoids
                        ? uploadVoxelEllipsoids(renderer_, in.kernel_centres, in.kernel_g, in.kernel_max_axis, error)
                        : uploadVoxelParticles(renderer_, in.particles, error);
    return ok ? renderer_.scene.fbo : 0;
  }
  void draw(GLuint target_fbo, const FluidCamera& camera, const WaterParams& water, const WaterInput& in) override {
    VoxelParams params;
    params.radius = 0.975f * in.rc / 3.0f;  // a lone particle's iso-surface radius in the mesh's field
    params.min_gap = params.radius;         // §3.2: gaps under one radius are bridged
    params.filter_radius = 1.5f * params.radius;
    drawVoxelFluid(renderer_, target_fbo, camera, water, params);
  }

 private:
  VoxelRenderer renderer_;
};

}  // namespace

const WaterBackendDesc& voxelWaterBackend() {
  static const WaterBackendDesc desc{
      "voxel",
      "spheres or ellipsoids splatted into a tiled perspective bit grid, spans per pixel, linked and filtered "
      "(Zirr & Dachsbacher 2015)",
      false,
      [](const FluidRenderDesc& d) -> std::unique_ptr<WaterBackend> { return std::make_unique<VoxelWaterBackend>(d); }};
  return desc;
}

}  // namespace engine
