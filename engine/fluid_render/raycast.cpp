#include "engine/fluid_render/raycast.hpp"
#include "engine/fluid_render/water_backend.hpp"

#include <algorithm>
#include <cmath>

namespace engine {
namespace {

// max(1, round(per_pixel * w * h)) records, capped at 2^28 (4 GiB of records): the counters are
// 32-bit and a buffer that size is beyond any target here.
std::uint32_t poolRecords(float per_pixel, int w, int h) {
  const double records = std::round(static_cast<double>(per_pixel) * w * h);
  return static_cast<std::uint32_t>(std::clamp(records, 1.0, 268435456.0));
}

std::uint64_t readUsedRecords(GLuint counters) {
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  GLuint counts[2] = {0, 0};
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, counters);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(counts), counts);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  return counts[0];
}

// Gathering (§5): empty lists, zero counters, then every support sphere prepends records. The
// target's colour is masked: the pass writes only the lists.
bool drawsEllipsoids(const RaycastRenderer& r) { return r.shapes.count > 0 && r.shapes.count == r.particles.count; }

void gather(RaycastRenderer& r, GLuint target_fbo, const FluidCamera& camera, float rc) {
  const bool ellipsoids = drawsEllipsoids(r);
  const GLuint program = ellipsoids ? r.ellipsoid_gather_program : r.gather_program;
  const GLuint empty_list = 0xffffffffu, zero[2] = {0, 0};
  glClearTexImage(r.heads, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty_list);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.counters);
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(zero), zero);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  glBindImageTexture(0, r.heads, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, r.nodes);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, r.counters);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, r.particles.buffer);
  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);  // side effects only
  glUseProgram(program);
  setParticleCamera(program, camera, r.desc.base.width, r.desc.base.height);
  setUniform(program, "u_radius", rc);
  glUniform1ui(glGetUniformLocation(program, "u_pool"), r.pool_records);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, r.scene.depth);
  setUniform(program, "u_scene_depth", 0);
  glBindVertexArray(ellipsoids ? r.ellipsoid_vao : r.vao);
  glDrawArraysInstanced(GL_TRIANGLES, 0, 3, static_cast<GLsizei>(r.particles.count));
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}

}  // namespace

void createRaycastRenderer(const RaycastDesc& desc, RaycastRenderer& out) {
  destroyRaycastRenderer(out);
  out = RaycastRenderer{};
  out.desc = desc;
  const int w = desc.base.width, h = desc.base.height;
  if (w < 1 || h < 1 || w > 8192 || h > 8192) {
    out.error = "raycast fluid: size " + std::to_string(w) + "x" + std::to_string(h) + " out of range 1..8192";
    return;
  }
  if (!(desc.pool_per_pixel > 0.0f && desc.pool_per_pixel <= 64.0f)) {
    out.error = "raycast fluid: pool_per_pixel " + std::to_string(desc.pool_per_pixel) + " out of range (0, 64]";
    return;
  }
  if (!(desc.max_pool_per_pixel >= 0.0f && desc.max_pool_per_pixel <= 64.0f)) {
    out.error =
        "raycast fluid: max_pool_per_pixel " + std::to_string(desc.max_pool_per_pixel) + " out of range [0, 64]";
    return;
  }
  const std::filesystem::path dir = desc.base.shader_dir / "fluid";
  std::string error;
  out.gather_program = buildProgramWithStorage(
      std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "particle_billboard.vert"}},
                                    {GL_FRAGMENT_SHADER, {dir / "ray.glsl", dir / "rc_gather.frag"}}},
      false, error);
  out.error += error;
  out.cast_program = buildProgramWithStorage(
      std::vector<ShaderStageFiles>{{GL_COMPUTE_SHADER, {dir / "ray.glsl", dir / "rc_cast.comp"}}}, true, error);
  out.error += error;
  out.ellipsoid_gather_program = buildProgramWithStorage(
      std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "particle_billboard.vert"}},
                                    {GL_FRAGMENT_SHADER, {dir / "ray.glsl", dir / "rc_gather.frag"}}},
      false, error, "#define ELLIPSOID 1\n");
  out.error += error;
  out.ellipsoid_cast_program = buildProgramWithStorage(
      std::vector<ShaderStageFiles>{{GL_COMPUTE_SHADER, {dir / "ray.glsl", dir / "rc_cast.comp"}}}, true, error,
      "#define ELLIPSOID 1\n");
  out.error += error;
  out.shade_program =
      buildProgram(std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "blit.vert"}},
                                                 {GL_FRAGMENT_SHADER,
                                                  {dir / "shading.glsl", dir / "depth.glsl", dir / "ray.glsl",
                                                   dir / "water_shade.glsl", dir / "rc_shade.frag"}}},
                   "", error);
  out.error += error;
  out.blit_program = buildProgram(
      std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "blit.vert"}}, {GL_FRAGMENT_SHADER, {dir / "blit.frag"}}},
      "", error);
  out.error += error;
  if (!out.error.empty()) {
    out.error = "raycast fluid disabled, shader build failed:\n" + out.error;
    return;
  }
  const bool scene_ok = createSceneTargets(w, h, out.scene);
  out.heads = createTexture2D(GL_R32UI, w, h, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
  out.hits = createTexture2D(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, nullptr);
  out.thickness = createTexture2D(GL_R32F, w, h, GL_RED, GL_FLOAT, nullptr);
  out.pool_records = poolRecords(desc.pool_per_pixel, w, h);
  out.max_pool_records = std::max(out.pool_records, poolRecords(desc.max_pool_per_pixel, w, h));
  glGenBuffers(1, &out.nodes);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, out.nodes);
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(out.pool_records) * 16, nullptr, GL_DYNAMIC_COPY);
  glGenBuffers(1, &out.counters);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, out.counters);
  glBufferData(GL_SHADER_STORAGE_BUFFER, 8, nullptr, GL_DYNAMIC_READ);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  createParticleBuffer(out.particles, out.vao);
  createShapeBuffer(out.particles, out.shapes, out.ellipsoid_vao);
  glGenVertexArrays(1, &out.empty_vao);
  if (!scene_ok || glGetError() != GL_NO_ERROR) {
    out.error = "raycast fluid disabled: fragment-list storage not supported (needs GL 4.3 SSBOs and images)";
    return;
  }
  out.ready = true;
}

GlObjectNames glNames(const RaycastRenderer& r) {
  GlObjectNames n;
  if (r.scene.fbo != 0) listNames(r.scene, n);
  for (GLuint t : {r.heads, r.hits, r.thickness})
    if (t != 0) n.textures.push_back(t);
  for (GLuint b : {r.nodes, r.counters, r.particles.buffer, r.shapes.buffer})
    if (b != 0) n.buffers.push_back(b);
  for (GLuint v : {r.vao, r.empty_vao, r.ellipsoid_vao})
    if (v != 0) n.vertex_arrays.push_back(v);
  for (GLuint p : {r.gather_program, r.cast_program, r.shade_program, r.blit_program, r.ellipsoid_gather_program,
                   r.ellipsoid_cast_program})
    if (p != 0) n.programs.push_back(p);
  return n;
}

void destroyRaycastRenderer(RaycastRenderer& r) {
  destroySceneTargets(r.scene);
  for (GLuint* t : {&r.heads, &r.hits, &r.thickness})
    if (*t != 0) glDeleteTextures(1, t);
  for (GLuint* b : {&r.nodes, &r.counters, &r.particles.buffer, &r.shapes.buffer})
    if (*b != 0) glDeleteBuffers(1, b);
  for (GLuint* v : {&r.vao, &r.empty_vao, &r.ellipsoid_vao})
    if (*v != 0) glDeleteVertexArrays(1, v);
  for (GLuint p : {r.gather_program, r.cast_program, r.shade_program, r.blit_program, r.ellipsoid_gather_program,
                   r.ellipsoid_cast_program})
    if (p != 0) glDeleteProgram(p);
  const RaycastDesc desc = r.desc;
  r = RaycastRenderer{};
  r.desc = desc;
}

void beginRaycastOpaquePass(RaycastRenderer& r, glm::vec4 clear_colour) {
  if (!r.ready) return;
  glBindFramebuffer(GL_FRAMEBUFFER, r.scene.fbo);
  glViewport(0, 0, r.desc.base.width, r.desc.base.height);
  glClearColor(clear_colour.r, clear_colour.g, clear_colour.b, clear_colour.a);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

bool uploadRaycastParticles(RaycastRenderer& r, std::span<const glm::vec3> positions, std::string& error) {
  r.shapes.count = 0;  // spherical metaballs
  return uploadParticles(r.particles, positions, error);
}

bool uploadRaycastEllipsoids(RaycastRenderer& r, std::span<const glm::vec3> centres, std::span<const glm::mat3> g,
                             std::span<const float> max_axis, std::string& error) {
  return uploadEllipsoids(r.particles, r.shapes, centres, g, max_axis, error);
}

void drawRaycastFluid(RaycastRenderer& r, GLuint target_fbo, const FluidCamera& camera, const WaterParams& water,
                      const RaycastParams& params) {
  if (!r.ready) return;
  const int w = r.desc.base.width, h = r.desc.base.height;
  const float rc = std::max(params.rc, 1e-5f);
  const float threshold = std::clamp(params.threshold, 1e-4f, 0.2499f);
  glViewport(0, 0, w, h);
  glDisable(GL_CULL_FACE);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glActiveTexture(GL_TEXTURE0);
  r.used = r.dropped = 0;
  // Scene colour into the target first (the gather below writes no colour).
  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glUseProgram(r.blit_program);
  glBindTexture(GL_TEXTURE_2D, r.scene.colour);
  setUniform(r.blit_program, "u_colour", 0);
  glBindVertexArray(r.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  if (r.particles.count > 0) {
    gather(r, target_fbo, camera, rc);
    if (params.grow_pool && r.pool_records < r.max_pool_records) {
      // The paper sizes its storage ahead (§6); here the frame's own demand does: an overflowed
      // pool is enlarged with 25 % headroom (a growing fountain then reallocates rarely) and the
      // gather repeated, so the picture has no holes unless the demand passes the bound.
      const std::uint64_t used = readUsedRecords(r.counters);
      if (used > r.pool_records) {
        const double wanted = std::ceil(1.25 * static_cast<double>(used));
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.nodes);
        r.pool_records = static_cast<std::uint32_t>(std::min<double>(wanted, r.max_pool_records));
        glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(r.pool_records) * 16, nullptr, GL_DYNAMIC_COPY);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        ++r.pool_growths;
        gather(r, target_fbo, camera, rc);
      }
    }
    // The cast (§6) per pixel into the hit and thickness images.
    const bool ellipsoids = drawsEllipsoids(r);
    const GLuint cast = ellipsoids ? r.ellipsoid_cast_program : r.cast_program;
    if (ellipsoids) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, r.shapes.buffer);
    glUseProgram(cast);
    setParticleCamera(cast, camera, w, h);
    setUniform(cast, "u_rc", rc);
    setUniform(cast, "u_threshold", threshold);
    setUniform(cast, "u_scene_depth", 0);
    glBindImageTexture(0, r.heads, 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
    glBindImageTexture(1, r.hits, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(2, r.thickness, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    glDispatchCompute(static_cast<GLuint>((w + 7) / 8), static_cast<GLuint>((h + 7) / 8), 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    glUseProgram(0);  // Mesa 22.3 kept the program made current right after a compute one alive after its deletion
    for (GLuint i = 0; i < 3; ++i) glBindImageTexture(i, 0, 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
  }
  glBindVertexArray(r.empty_vao);
  if (r.particles.count > 0) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    const GLuint p = r.shade_program;
    glUseProgram(p);
    setParticleCamera(p, camera, w, h);
    setWaterShading(p, water);
    const GLuint textures[] = {r.scene.colour, r.scene.depth, r.hits, r.thickness};
    const char* names[] = {"u_scene_colour", "u_scene_depth", "u_hits", "u_thickness"};
    for (int i = 0; i < 4; ++i) {
      glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(i));
      glBindTexture(GL_TEXTURE_2D, textures[i]);
      setUniform(p, names[i], i);
    }
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisable(GL_BLEND);
    glActiveTexture(GL_TEXTURE0);
    for (GLuint i = 0; i < 4; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, 0);
    if (params.read_counters) {
      glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
      GLuint counts[2] = {0, 0};
      glBindBuffer(GL_SHADER_STORAGE_BUFFER, r.counters);
      glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(counts), counts);
      glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
      r.used = counts[0];
      r.dropped = counts[1];
    }
  }
  glBindVertexArray(0);
  glUseProgram(0);  // a deleted program stays alive while current
}

// Metaball ray casting as a water backend (water_backend.hpp); its fragment-list use is its stats.
namespace {
class RaycastWaterBackend final : public WaterBackend {
 public:
  explicit RaycastWaterBackend(const FluidRenderDesc& desc) {
    RaycastDesc rc;
    rc.base = desc;
    createRaycastRenderer(rc, renderer_);
  }
  ~RaycastWaterBackend() override { destroyRaycastRenderer(renderer_); }
  bool ready() const override { return renderer_.ready; }
  const std::string& error() const override { return renderer_.error; }
  GLuint upload(const WaterInput& in, std::string& error) override {
    if (!renderer_.ready) return 0;
    // Ellipsoidal metaballs when the input carries anisotropic kernels (one per particle).
    const bool ellipsoids = !in.kernel_g.empty() && in.kernel_g.size() == in.particles.size();
    const bool ok = ellipsoids ? uploadRaycastEllipsoids(renderer_, in.kernel_centres, in.kernel_g,
                                                         in.kernel_max_axis, error)
                               : uploadRaycastParticles(renderer_, in.particles, error);
    return ok ? renderer_.scene.fbo : 0;
  }
  void draw(GLuint target_fbo, const FluidCamera& camera, const WaterParams& water, const WaterInput& in) override {
    RaycastParams params;
    params.rc = in.rc;
    params.threshold = in.threshold;
    drawRaycastFluid(renderer_, target_fbo, camera, water, params);
  }
  WaterStats stats() const override {
    return {renderer_.used, renderer_.dropped, renderer_.pool_records, renderer_.max_pool_records};
  }

 private:
  RaycastRenderer renderer_;
};
}  // namespace

const WaterBackendDesc& raycastWaterBackend() {
  static const WaterBackendDesc desc{
      "raycast",
      "metaballs, spherical or ellipsoidal, ray cast through per-pixel fragment lists (Szecsi & Illes 2012)", false,
      [](const FluidRenderDesc& d) -> std::unique_ptr<WaterBackend> { return std::make_unique<RaycastWaterBackend>(d); }};
  return desc;
}

}  // namespace engine
