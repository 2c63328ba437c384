// GPU state-preserving particles, Kolb, Latta & Rezk-Salama 2004 §3. See gpu_particles.hpp.
#include "engine/gpu_particles/gpu_particles.hpp"

#include "engine/gl/gl.hpp"
#include "fluid/core/finite.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <functional>
#include <numbers>

namespace engine {

namespace {

// The shader decodes fluid/collide's texels; these enums are passed as plain integers.
static_assert(static_cast<int>(fluid::DepthMapFormat::float32) == 1 &&
              static_cast<int>(fluid::DepthMapFormat::fixed8) == 2 &&
              static_cast<int>(fluid::DepthMapFormat::front_back16) == 3 &&
              static_cast<int>(fluid::DepthMapFormat::cube8) == 4);
static_assert(static_cast<int>(fluid::DepthCompare::less) == 0 && static_cast<int>(fluid::DepthCompare::greater) == 1);

bool makeFramebuffer(std::span<const GLuint> colour, GLuint& fbo) {
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  std::array<GLenum, 4> buffers{};
  for (std::size_t k = 0; k < colour.size(); ++k) {
    glFramebufferTexture2D(GL_FRAMEBUFFER, static_cast<GLenum>(GL_COLOR_ATTACHMENT0 + k), GL_TEXTURE_2D, colour[k], 0);
    buffers[k] = static_cast<GLenum>(GL_COLOR_ATTACHMENT0 + k);
  }
  glDrawBuffers(static_cast<GLsizei>(colour.size()), buffers.data());
  const bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return complete;
}

GLint loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

void bindTexture(int unit, GLenum target, GLuint tex) {
  glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
  glBindTexture(target, tex);
}

// Every simulation pass writes texels of a state texture: no blending, no depth test, the
// viewport covering `rows` rows of the state textures.
void beginStatePass(const GpuParticles& s, GLuint fbo, GLsizei rows) {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, static_cast<GLsizei>(s.desc.width), rows);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
}

// A birth vertex: index bits, position, velocity, birth time, death time, type, spin.
constexpr std::size_t kBirthFloats = 11;
// Records kept before step() runs them itself (a frame runs them far sooner: a few steps' worth).
constexpr std::size_t kMaxPendingRecords = 1024;

bool isPowerOfTwo(std::uint32_t v) { return v != 0 && (v & (v - 1)) == 0; }

// Rows covering the active range (§3.3.1: the heap keeps it packed at the start).
GLsizei activeRows(const GpuParticles& s) {
  const std::uint32_t w = s.desc.width;
  return static_cast<GLsizei>((s.allocator.active_range + w - 1) / w);
}

// (p, k) of merge-sort pass number `step` of the network for n elements (p = 1, 2, 4, …;
// k = p, p/2, …, 1).
void sortStage(std::uint32_t n, std::uint32_t step, std::uint32_t& p, std::uint32_t& k) {
  p = 1;
  for (;;) {
    const std::uint32_t stages = static_cast<std::uint32_t>(std::countr_zero(p)) + 1;
    if (step < stages) {
      k = p >> step;
      return;
    }
    step -= stages;
    p <<= 1;
    assert(p < n);
    (void)n;
  }
}

GLuint buildUpdateVariant(const std::filesystem::path& dir, unsigned variant, std::string& error) {
  // The collider and map array sizes come from the one place that bounds them (gpu_particles.hpp).
  std::string defines = "#define MAX_COLLIDERS " + std::to_string(kMaxGpuColliders) + "\n#define MAX_MAPS " +
                        std::to_string(kMaxGpuDepthMaps) + "\n";
  if (variant & 1u) defines += "#define ATTRACTORS\n";
  if (variant & 2u) defines += "#define DRAG\n";
  if (variant & 4u) defines += "#define FLOW\n";
  if (variant & 8u) defines += "#define COLLIDERS\n";
  if (variant & 16u) defines += "#define FORMAT_FLOAT32\n";
  if (variant & 32u) defines += "#define FORMAT_FIXED8\n";
  if (variant & 64u) defines += "#define FORMAT_FRONT_BACK16\n";
  if (variant & 128u) defines += "#define FORMAT_CUBE8\n";
  if (variant & 256u) defines += "#define BLASTS\n";
  if (variant & 512u) defines += "#define DIFFUSE\n";
  const std::vector<ShaderStageFiles> stages{{GL_VERTEX_SHADER, {dir / "fullscreen.vert"}},
                                             {GL_FRAGMENT_SHADER, {dir / "collide.glsl", dir / "update.frag"}}};
  return buildProgram(stages, defines, error);
}

}  // namespace

GpuDepthMapView gpuDepthMapView(const fluid::DepthMap& map) {
  GpuDepthMapView v;
  v.format = static_cast<std::uint32_t>(map.format);
  v.compare = static_cast<std::uint32_t>(map.compare);
  v.resolution = map.resolution;
  v.collider_to_map = map.collider_to_map;
  v.z_scale = map.z_scale;
  v.cube_scale = map.cube_scale;
  v.encloses_collider = map.encloses_collider;
  v.texels = map.texels;
  return v;
}

void describeCollider(const fluid::DepthMapCollider& collider, const fluid::ColliderPose& pose,
                      std::vector<GpuDepthMapView>& views, std::vector<float>& normal_table, GpuColliderDesc& out) {
  views.clear();
  bool indexed = false;
  for (const fluid::DepthMap& m : collider.maps()) {
    views.push_back(gpuDepthMapView(m));
    indexed = indexed || m.format != fluid::DepthMapFormat::float32;
  }
  normal_table.clear();
  if (indexed) normal_table = fluid::l1NormalTexture(collider.normalResolution());
  out = GpuColliderDesc{};
  out.maps = views;
  out.normal_resolution = collider.normalResolution();
  out.normal_table = normal_table;
  out.pose = pose;
}

std::uint32_t sortPassCount(std::uint32_t n) {
  if (n < 2) return 0;
  const std::uint32_t m = static_cast<std::uint32_t>(std::bit_width(n) - 1);  // log2 n (n a power of two)
  return m * (m + 1) / 2;
}

void createGpuParticles(const GpuParticlesDesc& desc, GpuParticles& out) {
  destroyGpuParticles(out);
  out = GpuParticles{};
  out.desc = desc;
  if (!isPowerOfTwo(desc.width) || !isPowerOfTwo(desc.height) || desc.width > 4096 || desc.height > 4096) {
    out.error = "gpu particles: width and height must be powers of two up to 4096 (got " + std::to_string(desc.width) +
                "x" + std::to_string(desc.height) + ")";
    return;
  }
  if (desc.types.empty() || desc.types.size() > static_cast<std::size_t>(kMaxParticleTypes)) {
    out.error = "gpu particles: 1.." + std::to_string(kMaxParticleTypes) + " particle types needed (got " +
                std::to_string(desc.types.size()) + ")";
    return;
  }
  if (!(desc.dt > 0.0f) || !std::isfinite(desc.dt)) {
    out.error = "gpu particles: dt must be a positive finite number of seconds";
    return;
  }
  for (std::size_t t = 0; t < desc.types.size(); ++t)
    if (!std::isfinite(desc.types[t].gravity_scale) || !(desc.types[t].damping >= 0.0f) ||
        !std::isfinite(desc.types[t].damping)) {
      out.error = "gpu particles: type " + std::to_string(t) +
                  " has a non-finite gravity_scale or a damping that is "
                  "not finite and >= 0";
      return;
    }
  const std::filesystem::path dir = desc.shader_dir / "gpu_particles";
  auto program = [&](std::vector<ShaderStageFiles> stages, GLuint& id) {
    std::string error;
    id = buildProgram(stages, "", error);
    if (id == 0) out.error += error;
  };
  // The plain update variant is built now, so a broken update shader disables the system at
  // creation; the others are built on first use (updateProgram).
  {
    std::string error;
    out.update_variants[0] = buildUpdateVariant(dir, 0, error);
    if (out.update_variants[0] == 0) out.error += error;
  }
  program({{GL_VERTEX_SHADER, {dir / "birth.vert"}}, {GL_FRAGMENT_SHADER, {dir / "birth.frag"}}}, out.birth.id);
  program({{GL_VERTEX_SHADER, {dir / "fullscreen.vert"}}, {GL_FRAGMENT_SHADER, {dir / "sort_key.frag"}}},
          out.sort_key.id);
  program({{GL_VERTEX_SHADER, {dir / "fullscreen.vert"}}, {GL_FRAGMENT_SHADER, {dir / "sort_pass.frag"}}},
          out.sort_pass.id);
  program({{GL_VERTEX_SHADER, {dir / "sprite.vert"}}, {GL_FRAGMENT_SHADER, {dir / "sprite.frag"}}}, out.sprite.id);
  if (!out.error.empty()) {
    out.error = "gpu particles disabled, shader build failed:\n" + out.error;
    return;
  }

  const auto w = static_cast<GLsizei>(desc.width), h = static_cast<GLsizei>(desc.height);
  out.capacity = desc.width * desc.height;
  std::vector<float> zeros(static_cast<std::size_t>(out.capacity) * 4, 0.0f);
  for (int k = 0; k < 2; ++k) {
    out.state0[k] = createTexture2D(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, zeros.data());
    out.state1[k] = createTexture2D(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, zeros.data());
  }
  out.attributes = createTexture2D(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, zeros.data());
  // Identity permutation, every key "dead" until the first key refresh.
  std::vector<float> pairs(static_cast<std::size_t>(out.capacity) * 2);
  for (std::uint32_t i = 0; i < out.capacity; ++i) {
    pairs[2 * i] = 3.0e38f;
    pairs[2 * i + 1] = static_cast<float>(i);
  }
  for (int k = 0; k < 2; ++k) out.sort_tex[k] = createTexture2D(GL_RG32F, w, h, GL_RG, GL_FLOAT, pairs.data());
  bool complete = true;
  for (int k = 0; k < 2; ++k) {
    complete &= makeFramebuffer(std::array<GLuint, 2>{out.state0[k], out.state1[k]}, out.fbo[k]);
    complete &= makeFramebuffer(std::array<GLuint, 3>{out.state0[k], out.state1[k], out.attributes}, out.birth_fbo[k]);
    complete &= makeFramebuffer(std::array<GLuint, 1>{out.sort_tex[k]}, out.sort_fbo[k]);
  }
  // Key-frame table: row 2t colours, row 2t+1 sizes.
  std::vector<float> table(static_cast<std::size_t>(kParticleKeyframes) * 2 * desc.types.size() * 4, 0.0f);
  for (std::size_t t = 0; t < desc.types.size(); ++t) {
    for (int k = 0; k < kParticleKeyframes; ++k) {
      const ParticleKeyframe& key = desc.types[t].keys[static_cast<std::size_t>(k)];
      float* colour = &table[((2 * t) * kParticleKeyframes + static_cast<std::size_t>(k)) * 4];
      float* size = &table[((2 * t + 1) * kParticleKeyframes + static_cast<std::size_t>(k)) * 4];
      for (int c = 0; c < 4; ++c) colour[c] = std::clamp(key.colour[c], 0.0f, 1.0f);
      size[0] = std::max(0.0f, key.size);
    }
  }
  out.type_tex = createTexture2D(GL_RGBA32F, kParticleKeyframes, static_cast<GLsizei>(2 * desc.types.size()), GL_RGBA,
                                 GL_FLOAT, table.data());
  // A 1³ flow field so the sampler is always complete.
  glGenTextures(1, &out.flow_tex);
  glBindTexture(GL_TEXTURE_3D, out.flow_tex);
  const float zero4[4] = {0, 0, 0, 0};
  glTexImage3D(GL_TEXTURE_3D, 0, GL_RGBA32F, 1, 1, 1, 0, GL_RGBA, GL_FLOAT, zero4);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  // The same for the diffuse sprites' fluid grid (zero count: every diffuse sprite is spray).
  glGenTextures(1, &out.fluid_tex);
  glBindTexture(GL_TEXTURE_3D, out.fluid_tex);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_RGBA32F, 1, 1, 1, 0, GL_RGBA, GL_FLOAT, zero4);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glBindTexture(GL_TEXTURE_3D, 0);
  // Collider buffers (one word / one float so the buffer textures are never empty).
  const std::uint32_t word = 0;
  const float one = 0.0f;
  glGenBuffers(1, &out.collider_buffer);
  glBindBuffer(GL_TEXTURE_BUFFER, out.collider_buffer);
  glBufferData(GL_TEXTURE_BUFFER, 4, &word, GL_STATIC_DRAW);
  glGenTextures(1, &out.collider_tbo);
  glBindTexture(GL_TEXTURE_BUFFER, out.collider_tbo);
  glTexBuffer(GL_TEXTURE_BUFFER, GL_R32UI, out.collider_buffer);
  glGenBuffers(1, &out.normal_buffer);
  glBindBuffer(GL_TEXTURE_BUFFER, out.normal_buffer);
  glBufferData(GL_TEXTURE_BUFFER, 4, &one, GL_STATIC_DRAW);
  glGenTextures(1, &out.normal_tbo);
  glBindTexture(GL_TEXTURE_BUFFER, out.normal_tbo);
  glTexBuffer(GL_TEXTURE_BUFFER, GL_R32F, out.normal_buffer);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  // Birth points: index (int) + position + velocity + attributes, interleaved.
  glGenVertexArrays(1, &out.birth_vao);
  glGenBuffers(1, &out.birth_vbo);
  glBindVertexArray(out.birth_vao);
  glBindBuffer(GL_ARRAY_BUFFER, out.birth_vbo);
  constexpr auto stride = static_cast<GLsizei>(kBirthFloats * sizeof(float));
  glEnableVertexAttribArray(0);
  glVertexAttribIPointer(0, 1, GL_INT, stride, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(4));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(16));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 4, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(28));
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glGenVertexArrays(1, &out.empty_vao);

  if (!complete || glGetError() != GL_NO_ERROR) {
    out.error = "gpu particles disabled: RGBA32F/RG32F render targets are not supported by this driver";
    return;
  }
  initAllocator(out.allocator, out.capacity, desc.budget);
  out.ready = true;
}

void destroyGpuParticles(GpuParticles& s) {
  glUseProgram(0);  // a deleted program stays alive while it is current
  auto textures = [](std::span<GLuint> ids) {
    for (GLuint& id : ids) {
      if (id != 0) glDeleteTextures(1, &id);
      id = 0;
    }
  };
  textures(s.state0);
  textures(s.state1);
  textures(s.sort_tex);
  std::array<GLuint, 6> singles{s.attributes, s.type_tex, s.flow_tex, s.collider_tbo, s.normal_tbo, s.fluid_tex};
  textures(singles);
  s.attributes = s.type_tex = s.flow_tex = s.collider_tbo = s.normal_tbo = s.fluid_tex = 0;
  for (GLuint* fbo : {&s.fbo[0], &s.fbo[1], &s.birth_fbo[0], &s.birth_fbo[1], &s.sort_fbo[0], &s.sort_fbo[1]}) {
    if (*fbo != 0) glDeleteFramebuffers(1, fbo);
    *fbo = 0;
  }
  for (GLuint* buffer : {&s.collider_buffer, &s.normal_buffer, &s.birth_vbo}) {
    if (*buffer != 0) glDeleteBuffers(1, buffer);
    *buffer = 0;
  }
  for (GLuint* vao : {&s.birth_vao, &s.empty_vao}) {
    if (*vao != 0) glDeleteVertexArrays(1, vao);
    *vao = 0;
  }
  for (GLuint& id : s.update_variants) {
    if (id != 0) glDeleteProgram(id);
    id = 0;
  }
  for (GpuProgram* p : {&s.birth, &s.sort_key, &s.sort_pass, &s.sprite}) {
    if (p->id != 0) glDeleteProgram(p->id);
    p->id = 0;
  }
  s.pending.clear();  // work recorded for textures that no longer exist
  s.pending_births.clear();
  s.pending_grid.clear();
  s.ready = false;
}

std::size_t spawn(GpuParticles& s, const BirthBatch& batch) {
  if (!s.ready) return 0;
  const std::size_t n = batch.size();
  assert(batch.velocities.size() == n && batch.lifetimes.size() == n && batch.types.size() == n &&
         batch.spins.size() == n);
  GpuWorkRecord record;
  record.kind = GpuWorkRecord::Kind::births;
  record.first = static_cast<std::uint32_t>(s.pending_births.size() / kBirthFloats);
  std::size_t born = 0;
  const auto type_count = static_cast<std::uint32_t>(s.desc.types.size());
  for (std::size_t k = 0; k < n; ++k) {
    const glm::vec3 p = batch.positions[k], v = batch.velocities[k];
    const float life = batch.lifetimes[k], spin = batch.spins[k];
    // Bad content is dropped, never uploaded: NaN/inf or a non-positive lifetime.
    if (!(fluid::isFinite(p) && fluid::isFinite(v) && std::isfinite(life) && life > 0.0f && std::isfinite(spin))) {
      continue;
    }
    std::uint32_t index = 0;
    if (!allocateIndex(s.allocator, index)) break;  // full: the rest of the batch is dropped
    const float death = s.time + life;
    s.death_queue.emplace_back(death, index);
    std::push_heap(s.death_queue.begin(), s.death_queue.end(), std::greater<>());
    const float type = static_cast<float>(std::min(batch.types[k], type_count - 1));
    float index_bits;
    const auto index_int = static_cast<std::int32_t>(index);
    std::memcpy(&index_bits, &index_int, 4);
    const float vertex[kBirthFloats] = {index_bits, p.x, p.y, p.z, v.x, v.y, v.z, s.time, death, type, spin};
    s.pending_births.insert(s.pending_births.end(), vertex, vertex + kBirthFloats);
    ++born;
  }
  if (born == 0) return 0;
  record.count = static_cast<std::uint32_t>(born);
  s.pending.push_back(record);
  return born;
}

bool setColliders(GpuParticles& s, std::span<const GpuColliderDesc> colliders, std::string& error) {
  runPendingWork(s);  // the steps recorded so far collide with the colliders they were recorded with
  error.clear();
  if (colliders.size() > static_cast<std::size_t>(kMaxGpuColliders)) {
    error = "gpu colliders: at most " + std::to_string(kMaxGpuColliders) + " colliders (got " +
            std::to_string(colliders.size()) + ")";
    return false;
  }
  std::size_t maps = 0;
  for (const GpuColliderDesc& c : colliders) maps += c.maps.size();
  if (maps > static_cast<std::size_t>(kMaxGpuDepthMaps)) {
    error = "gpu colliders: at most " + std::to_string(kMaxGpuDepthMaps) + " depth maps in all (got " +
            std::to_string(maps) + ")";
    return false;
  }
  std::vector<std::uint32_t> words;
  std::vector<float> normals;
  GpuParticles next = {};
  int m = 0;
  for (std::size_t c = 0; c < colliders.size(); ++c) {
    const GpuColliderDesc& col = colliders[c];
    next.collider_first_map[c] = m;
    next.collider_poses[c] = col.pose;
    bool indexed = false;
    for (std::size_t k = 0; k < col.maps.size(); ++k, ++m) {
      const GpuDepthMapView& map = col.maps[k];
      const std::size_t texel_bytes = map.format == 1                      ? 16
                                      : map.format == 3                    ? 8
                                      : map.format == 2 || map.format == 4 ? 4
                                                                           : 0;
      const std::size_t texels = static_cast<std::size_t>(map.resolution) * map.resolution * (map.format == 4 ? 6 : 1);
      const std::string name = "gpu colliders: collider " + std::to_string(c) + " map " + std::to_string(k);
      if (texel_bytes == 0) {
        error = name + ": unknown format " + std::to_string(map.format);
        return false;
      }
      if (map.resolution == 0 || map.texels.size() != texels * texel_bytes) {
        error = name + ": texels has " + std::to_string(map.texels.size()) + " bytes, resolution " +
                std::to_string(map.resolution) + " needs " + std::to_string(texels * texel_bytes);
        return false;
      }
      indexed = indexed || map.format != 1;
      const std::size_t first = words.size();
      words.resize(first + map.texels.size() / 4);
      std::memcpy(words.data() + first, map.texels.data(), map.texels.size());
      const auto mi = static_cast<std::size_t>(m);
      next.map_info[4 * mi] = static_cast<std::int32_t>(map.format);
      next.map_info[4 * mi + 1] = static_cast<std::int32_t>(map.compare);
      next.map_info[4 * mi + 2] = static_cast<std::int32_t>(map.resolution);
      next.map_info[4 * mi + 3] = static_cast<std::int32_t>(first);
      next.map_params[4 * mi] = map.z_scale;
      next.map_params[4 * mi + 1] = map.cube_scale.x;
      next.map_params[4 * mi + 2] = map.cube_scale.y;
      next.map_params[4 * mi + 3] = map.cube_scale.z;
      next.map_encloses[mi] = map.encloses_collider ? 1 : 0;
      next.map_matrices[mi] = map.collider_to_map;
    }
    next.normal_res[c] = col.normal_resolution;
    next.normal_offset[c] = static_cast<std::int32_t>(normals.size());
    if (indexed) {
      const std::size_t need =
          3u * static_cast<std::size_t>(col.normal_resolution) * static_cast<std::size_t>(col.normal_resolution);
      if (col.normal_resolution < 1 || col.normal_resolution > 256 || col.normal_table.size() != need) {
        error = "gpu colliders: collider " + std::to_string(c) + ": normal_table has " +
                std::to_string(col.normal_table.size()) + " floats, normal_resolution " +
                std::to_string(col.normal_resolution) + " needs " + std::to_string(need);
        return false;
      }
      normals.insert(normals.end(), col.normal_table.begin(), col.normal_table.end());
    }
  }
  next.collider_first_map[colliders.size()] = m;
  if (!s.ready) return true;  // nothing to upload to; validation still reported
  if (words.empty()) words.push_back(0);
  if (normals.empty()) normals.push_back(0.0f);
  glBindBuffer(GL_TEXTURE_BUFFER, s.collider_buffer);
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(words.size() * 4), words.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_TEXTURE_BUFFER, s.normal_buffer);
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(normals.size() * 4), normals.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  s.collider_count = static_cast<int>(colliders.size());
  s.map_count = m;
  s.format_mask = 0;
  for (int k = 0; k < m; ++k) s.format_mask |= 1u << (next.map_info[static_cast<std::size_t>(4 * k)] - 1);
  s.collider_first_map = next.collider_first_map;
  s.collider_poses = next.collider_poses;
  s.map_info = next.map_info;
  s.map_params = next.map_params;
  s.map_encloses = next.map_encloses;
  s.map_matrices = next.map_matrices;
  s.normal_res = next.normal_res;
  s.normal_offset = next.normal_offset;
  return true;
}

void setColliderPose(GpuParticles& s, int collider, const fluid::ColliderPose& pose) {
  assert(collider >= 0 && collider < kMaxGpuColliders);
  s.collider_poses[static_cast<std::size_t>(collider)] = pose;
}

bool setFlowField(GpuParticles& s, const FlowFieldDesc& flow, std::string& error) {
  runPendingWork(s);
  error.clear();
  if (flow.velocities.empty()) {
    s.flow_enabled = false;
    return true;
  }
  const glm::ivec3 n = flow.size;
  if (n.x < 1 || n.y < 1 || n.z < 1 || n.x > 512 || n.y > 512 || n.z > 512 ||
      flow.velocities.size() != static_cast<std::size_t>(n.x) * n.y * n.z) {
    error = "flow field: size " + std::to_string(n.x) + "x" + std::to_string(n.y) + "x" + std::to_string(n.z) +
            " (each 1..512) does not match " + std::to_string(flow.velocities.size()) + " velocities";
    return false;
  }
  if (!(flow.extent.x > 0.0f && flow.extent.y > 0.0f && flow.extent.z > 0.0f)) {
    error = "flow field: extent must be positive on every axis";
    return false;
  }
  for (const glm::vec3& v : flow.velocities) {
    if (!fluid::isFinite(v)) {
      error = "flow field: non-finite velocity";
      return false;
    }
  }
  if (!s.ready) return true;
  glBindTexture(GL_TEXTURE_3D, s.flow_tex);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_RGB32F, n.x, n.y, n.z, 0, GL_RGB, GL_FLOAT, flow.velocities.data());
  glBindTexture(GL_TEXTURE_3D, 0);
  s.flow_enabled = true;
  s.flow_origin = flow.origin;
  s.flow_extent = flow.extent;
  return true;
}

bool setFluidGrid(GpuParticles& s, const FluidGridDesc& grid, std::string& error) {
  error.clear();
  GpuWorkRecord record;
  record.kind = GpuWorkRecord::Kind::fluid_grid;
  if (!grid.cells.empty()) {
    const glm::ivec3 n = grid.size;
    if (n.x < 1 || n.y < 1 || n.z < 1 || n.x > 512 || n.y > 512 || n.z > 512 ||
        grid.cells.size() != static_cast<std::size_t>(n.x) * n.y * n.z) {
      error = "fluid grid: size " + std::to_string(n.x) + "x" + std::to_string(n.y) + "x" + std::to_string(n.z) +
              " (each 1..512) does not match " + std::to_string(grid.cells.size()) + " cells";
      return false;
    }
    if (!(grid.cell > 0.0f) || !std::isfinite(grid.cell) || !fluid::isFinite(grid.origin) ||
        !(grid.neighbour_scale >= 0.0f) || !std::isfinite(grid.neighbour_scale)) {
      error = "fluid grid: cell must be positive, origin and neighbour_scale finite";
      return false;
    }
    for (const glm::vec4& c : grid.cells)
      if (!fluid::isFinite(glm::vec3(c)) || !std::isfinite(c.w)) {
        error = "fluid grid: non-finite cell";
        return false;
      }
  }
  if (!s.ready) return true;
  record.first = static_cast<std::uint32_t>(s.pending_grid.size());
  record.count = static_cast<std::uint32_t>(grid.cells.size());
  record.grid_size = grid.size;
  record.grid_box = glm::vec4(grid.origin, grid.cell);
  record.grid_scale = grid.neighbour_scale;
  s.pending_grid.insert(s.pending_grid.end(), grid.cells.begin(), grid.cells.end());
  // Only the last of several grids recorded between two steps matters: drop an unrun one before it.
  if (!s.pending.empty() && s.pending.back().kind == GpuWorkRecord::Kind::fluid_grid) {
    s.pending.back() = record;
  } else {
    s.pending.push_back(record);
  }
  return true;
}

namespace {

int activeBlasts(const GpuStepParams& params) { return std::clamp(params.blast_count, 0, kMaxBlasts); }

// Bit set of the update pass's compile-time features for these parameters and colliders.
unsigned updateVariant(const GpuParticles& s, const GpuStepParams& params) {
  const float drag = stokesDragRate(params);
  return (std::clamp(params.attractor_count, 0, kMaxAttractors) > 0 ? 1u : 0u) | (drag > 0.0f ? 2u : 0u) |
         (drag > 0.0f && s.flow_enabled ? 4u : 0u) | (s.collider_count > 0 ? 8u | (s.format_mask << 4) : 0u) |
         (activeBlasts(params) > 0 ? 256u : 0u) |
         (std::any_of(s.desc.types.begin(), s.desc.types.end(), [](const ParticleTypeDesc& t) { return t.diffuse; })
              ? 512u
              : 0u);
}

}  // namespace

namespace {

// An invalid blast (validateBlast) is skipped rather than sent: it would push NaN into every sprite.
void setBlastUniforms(GLuint prog, const GpuStepParams& params) {
  std::array<glm::vec4, kMaxBlasts> centre_impulse{};
  std::array<glm::vec2, kMaxBlasts> radii{};
  int count = 0;
  for (int k = 0; k < activeBlasts(params); ++k) {
    const fluid::Blast& blast = params.blasts[static_cast<std::size_t>(k)];
    if (!fluid::validateBlast(blast).empty()) continue;
    centre_impulse[static_cast<std::size_t>(count)] = glm::vec4(blast.centre, blast.impulse_at_1m);
    radii[static_cast<std::size_t>(count)] = glm::vec2(blast.core_radius, blast.reach);
    ++count;
  }
  const float area_over_mass = std::numbers::pi_v<float> * params.particle_radius * params.particle_radius /
                               std::max(params.particle_mass, 1e-12f);
  glUniform1i(loc(prog, "u_blast_count"), count);
  glUniform4fv(loc(prog, "u_blasts"), kMaxBlasts, glm::value_ptr(centre_impulse[0]));
  glUniform2fv(loc(prog, "u_blast_radii"), kMaxBlasts, glm::value_ptr(radii[0]));
  glUniform1f(loc(prog, "u_blast_area_over_mass"), std::isfinite(area_over_mass) ? area_over_mass : 0.0f);
  glUniform1f(loc(prog, "u_blast_max_dv"), std::max(params.blast_max_speed_change, 0.0f));
}

}  // namespace

bool prepareStep(GpuParticles& s, const GpuStepParams& params) {
  if (!s.ready) return false;
  const unsigned variant = updateVariant(s, params);
  if (s.update_variants[variant] != 0) return true;
  std::string error;
  s.update_variants[variant] = buildUpdateVariant(s.desc.shader_dir / "gpu_particles", variant, error);
  if (s.update_variants[variant] == 0) {
    // Shader files changed or a driver rejects a variant: turn the effect off, keep running.
    s.error = "gpu particles disabled, update shader variant " + std::to_string(variant) + " failed:\n" + error;
    s.ready = false;
    return false;
  }
  return true;
}

void step(GpuParticles& s, const GpuStepParams& params) {
  if (!s.ready) return;
  s.time += s.desc.dt;
  ++s.steps;
  // §3.3.1: the CPU registers deaths on its own and frees the indices (same float compare as
  // the shader: time >= death time).
  while (!s.death_queue.empty() && s.death_queue.front().first <= s.time) {
    std::pop_heap(s.death_queue.begin(), s.death_queue.end(), std::greater<>());
    releaseIndex(s.allocator, s.death_queue.back().second);
    s.death_queue.pop_back();
  }
  GpuWorkRecord record;
  record.kind = GpuWorkRecord::Kind::step;
  record.time = s.time;
  // Rows past the active range are not touched; dead texels there are flagged by their age.
  record.rows = activeRows(s);
  record.params = params;
  record.poses = s.collider_poses;
  s.pending.push_back(record);
  // A loop that steps without drawing (no frame runs the work) still has bounded memory.
  if (s.pending.size() >= kMaxPendingRecords) runPendingWork(s);
}

void requestReadback(GpuParticles& s) {
  if (!s.ready) return;
  GpuWorkRecord record;
  record.kind = GpuWorkRecord::Kind::readback;
  record.step_index = s.steps;
  // Which texels are live now: the work may run after later steps have freed or taken some.
  s.readback_live.assign(s.allocator.live.begin(), s.allocator.live.begin() + s.allocator.active_range);
  // One read-back at a time: an earlier one not yet run is replaced by this one.
  std::erase_if(s.pending, [](const GpuWorkRecord& r) { return r.kind == GpuWorkRecord::Kind::readback; });
  s.pending.push_back(record);
}

namespace {

void runBirths(GpuParticles& s, const GpuWorkRecord& record) {
  // Orphan-and-fill: the buffer grows only when a bigger batch arrives.
  glBindBuffer(GL_ARRAY_BUFFER, s.birth_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::size_t{record.count} * kBirthFloats * sizeof(float)),
               s.pending_births.data() + std::size_t{record.first} * kBirthFloats, GL_STREAM_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  beginStatePass(s, s.birth_fbo[s.current], static_cast<GLsizei>(s.desc.height));
  glEnable(GL_PROGRAM_POINT_SIZE);
  glUseProgram(s.birth.id);
  glUniform2i(loc(s.birth.id, "u_size"), static_cast<GLint>(s.desc.width), static_cast<GLint>(s.desc.height));
  glUniform1i(loc(s.birth.id, "u_verlet"), s.desc.integrator == Integrator::verlet ? 1 : 0);
  glUniform1f(loc(s.birth.id, "u_dt"), s.desc.dt);
  glBindVertexArray(s.birth_vao);
  glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(record.count));
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void runFluidGrid(GpuParticles& s, const GpuWorkRecord& record) {
  if (record.count == 0) {
    s.fluid_enabled = false;
    return;
  }
  glBindTexture(GL_TEXTURE_3D, s.fluid_tex);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_RGBA32F, record.grid_size.x, record.grid_size.y, record.grid_size.z, 0, GL_RGBA,
               GL_FLOAT, s.pending_grid.data() + record.first);
  glBindTexture(GL_TEXTURE_3D, 0);
  s.fluid_enabled = true;
  s.fluid_origin = glm::vec3(record.grid_box);
  s.fluid_cell = record.grid_box.w;
  s.fluid_neighbour_scale = record.grid_scale;
}

void runStepPass(GpuParticles& s, const GpuWorkRecord& record) {
  const GpuStepParams& params = record.params;
  const GLsizei rows = record.rows;
  const int src = s.current, dst = 1 - s.current;
  if (rows == 0) return;
  const int attractor_count = std::clamp(params.attractor_count, 0, kMaxAttractors);
  const float drag = stokesDragRate(params);
  if (!prepareStep(s, params)) return;
  const GLuint prog = s.update_variants[updateVariant(s, params)];
  beginStatePass(s, s.fbo[dst], rows);
  glUseProgram(prog);
  bindTexture(0, GL_TEXTURE_2D, s.state0[src]);
  bindTexture(1, GL_TEXTURE_2D, s.state1[src]);
  bindTexture(2, GL_TEXTURE_2D, s.attributes);
  bindTexture(3, GL_TEXTURE_3D, s.flow_tex);
  bindTexture(4, GL_TEXTURE_BUFFER, s.collider_tbo);
  bindTexture(5, GL_TEXTURE_BUFFER, s.normal_tbo);
  bindTexture(6, GL_TEXTURE_3D, s.fluid_tex);
  glUniform1i(loc(prog, "u_fluid"), 6);
  glUniform1i(loc(prog, "u_fluid_on"), s.fluid_enabled ? 1 : 0);
  glUniform3fv(loc(prog, "u_fluid_origin"), 1, glm::value_ptr(s.fluid_origin));
  glUniform1f(loc(prog, "u_fluid_cell"), s.fluid_cell);
  glUniform1f(loc(prog, "u_neighbour_scale"), s.fluid_neighbour_scale);
  glUniform2f(loc(prog, "u_class_counts"), params.diffuse.spray_below, params.diffuse.bubble_above);
  glUniform1f(loc(prog, "u_buoyancy"), std::isfinite(params.diffuse.buoyancy) ? params.diffuse.buoyancy : 0.0f);
  glUniform1f(loc(prog, "u_bubble_drag"),
              std::isfinite(params.diffuse.drag) ? std::clamp(params.diffuse.drag, 0.0f, 1.0f) : 0.0f);
  glUniform1i(loc(prog, "u_state0"), 0);
  glUniform1i(loc(prog, "u_state1"), 1);
  glUniform1i(loc(prog, "u_attributes"), 2);
  glUniform1i(loc(prog, "u_flow"), 3);
  glUniform1i(loc(prog, "u_map_words"), 4);
  glUniform1i(loc(prog, "u_normals"), 5);
  glUniform1f(loc(prog, "u_time"), record.time);
  glUniform1f(loc(prog, "u_dt"), s.desc.dt);
  glUniform1i(loc(prog, "u_verlet"), s.desc.integrator == Integrator::verlet ? 1 : 0);
  glUniform3fv(loc(prog, "u_gravity"), 1, glm::value_ptr(params.gravity));
  glUniform3fv(loc(prog, "u_wind"), 1, glm::value_ptr(params.wind));
  std::array<float, kMaxParticleTypes> type_gravity{}, type_damping{};
  std::array<GLint, kMaxParticleTypes> type_diffuse{};
  for (std::size_t t = 0; t < s.desc.types.size(); ++t) {
    type_gravity[t] = s.desc.types[t].gravity_scale;
    type_damping[t] = s.desc.types[t].damping;
    type_diffuse[t] = s.desc.types[t].diffuse ? 1 : 0;
  }
  glUniform1iv(loc(prog, "u_type_diffuse"), kMaxParticleTypes, type_diffuse.data());
  glUniform1fv(loc(prog, "u_type_gravity"), kMaxParticleTypes, type_gravity.data());
  glUniform1fv(loc(prog, "u_type_damping"), kMaxParticleTypes, type_damping.data());
  const int attractors = attractor_count;
  std::array<glm::vec4, kMaxAttractors> att{};
  std::array<float, kMaxAttractors> soft{};
  for (int k = 0; k < attractors; ++k) {
    const Attractor& a = params.attractors[static_cast<std::size_t>(k)];
    att[static_cast<std::size_t>(k)] = glm::vec4(a.position, a.strength);
    soft[static_cast<std::size_t>(k)] = std::max(a.softening, 1e-4f);
  }
  glUniform1i(loc(prog, "u_attractor_count"), attractors);
  glUniform4fv(loc(prog, "u_attractors"), kMaxAttractors, glm::value_ptr(att[0]));
  glUniform1fv(loc(prog, "u_softening"), kMaxAttractors, soft.data());
  glUniform1f(loc(prog, "u_drag"), drag);
  setBlastUniforms(prog, params);
  glUniform3fv(loc(prog, "u_flow_origin"), 1, glm::value_ptr(s.flow_origin));
  glUniform3fv(loc(prog, "u_flow_extent"), 1, glm::value_ptr(s.flow_extent));
  // Colliders.
  glUniform1i(loc(prog, "u_collider_count"), s.collider_count);
  glUniform1iv(loc(prog, "u_collider_first_map"), kMaxGpuColliders + 1, s.collider_first_map.data());
  glUniform4iv(loc(prog, "u_map_info"), kMaxGpuDepthMaps, s.map_info.data());
  glUniform4fv(loc(prog, "u_map_params"), kMaxGpuDepthMaps, s.map_params.data());
  glUniform1iv(loc(prog, "u_map_encloses"), kMaxGpuDepthMaps, s.map_encloses.data());
  glUniformMatrix4fv(loc(prog, "u_map_matrix"), kMaxGpuDepthMaps, GL_FALSE, glm::value_ptr(s.map_matrices[0]));
  glUniform1iv(loc(prog, "u_normal_res"), kMaxGpuColliders, s.normal_res.data());
  glUniform1iv(loc(prog, "u_normal_offset"), kMaxGpuColliders, s.normal_offset.data());
  std::array<glm::vec4, kMaxGpuColliders> rot{};
  std::array<glm::vec3, kMaxGpuColliders> trans{}, lin{}, ang{};
  for (std::size_t c = 0; c < kMaxGpuColliders; ++c) {
    const fluid::ColliderPose& pose = record.poses[c];
    rot[c] = glm::vec4(pose.rotation.x, pose.rotation.y, pose.rotation.z, pose.rotation.w);
    trans[c] = pose.translation;
    lin[c] = pose.linear_velocity;
    ang[c] = pose.angular_velocity;
  }
  glUniform4fv(loc(prog, "u_pose_rotation"), kMaxGpuColliders, glm::value_ptr(rot[0]));
  glUniform3fv(loc(prog, "u_pose_translation"), kMaxGpuColliders, glm::value_ptr(trans[0]));
  glUniform3fv(loc(prog, "u_pose_linear"), kMaxGpuColliders, glm::value_ptr(lin[0]));
  glUniform3fv(loc(prog, "u_pose_angular"), kMaxGpuColliders, glm::value_ptr(ang[0]));
  glUniform1f(loc(prog, "u_fixed_step"), fluid::kFixedDepthStep);
  glUniform1f(loc(prog, "u_cube_step"), fluid::kCubeRadiusStep);
  glUniform1f(loc(prog, "u_friction"), params.material.friction);
  glUniform1f(loc(prog, "u_resilience"), params.material.resilience);
  glUniform1f(loc(prog, "u_friction_threshold"), params.material.friction_speed_threshold);
  glUniform1f(loc(prog, "u_skin"), params.skin);
  glUniform1i(loc(prog, "u_push_out_iterations"), std::clamp(params.push_out_iterations, 0, 8));
  glBindVertexArray(s.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  s.current = dst;
}

void runReadback(GpuParticles& s, const GpuWorkRecord& record);

}  // namespace

void runPendingWork(GpuParticles& s) {
  if (!s.ready || s.pending.empty()) return;
  for (const GpuWorkRecord& record : s.pending) {
    switch (record.kind) {
      case GpuWorkRecord::Kind::births:
        runBirths(s, record);
        break;
      case GpuWorkRecord::Kind::step:
        runStepPass(s, record);
        break;
      case GpuWorkRecord::Kind::readback:
        runReadback(s, record);
        break;
      case GpuWorkRecord::Kind::fluid_grid:
        runFluidGrid(s, record);
        break;
    }
  }
  s.pending.clear();
  s.pending_births.clear();
  s.pending_grid.clear();
}

float stokesDragRate(const GpuStepParams& params) {
  const float rate = 6.0f * std::numbers::pi_v<float> * params.viscosity * params.particle_radius /
                     std::max(params.particle_mass, 1e-12f);
  return std::isfinite(rate) ? std::max(rate, 0.0f) : 0.0f;
}

void refreshSortKeys(GpuParticles& s, glm::vec3 eye) {
  if (!s.ready) return;
  runPendingWork(s);  // the keys are the positions after every recorded step
  const auto w = static_cast<GLsizei>(s.desc.width);
  beginStatePass(s, s.sort_fbo[1 - s.sort_current], static_cast<GLsizei>(s.desc.height));
  glBindVertexArray(s.empty_vao);
  const GLuint prog = s.sort_key.id;
  glUseProgram(prog);
  bindTexture(0, GL_TEXTURE_2D, s.sort_tex[s.sort_current]);
  bindTexture(1, GL_TEXTURE_2D, s.state0[s.current]);
  bindTexture(2, GL_TEXTURE_2D, s.attributes);
  glUniform1i(loc(prog, "u_pairs"), 0);
  glUniform1i(loc(prog, "u_state0"), 1);
  glUniform1i(loc(prog, "u_attributes"), 2);
  glUniform3fv(loc(prog, "u_eye"), 1, glm::value_ptr(eye));
  glUniform1f(loc(prog, "u_time"), s.time);
  glUniform1i(loc(prog, "u_width"), w);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  s.sort_current = 1 - s.sort_current;
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void sortPasses(GpuParticles& s, std::uint32_t passes) {
  if (!s.ready) return;
  const auto w = static_cast<GLsizei>(s.desc.width);
  beginStatePass(s, s.sort_fbo[1 - s.sort_current], static_cast<GLsizei>(s.desc.height));
  glBindVertexArray(s.empty_vao);
  const GLuint prog = s.sort_pass.id;
  glUseProgram(prog);
  glUniform1i(loc(prog, "u_pairs"), 0);
  glUniform1i(loc(prog, "u_width"), w);
  glUniform1i(loc(prog, "u_count"), static_cast<GLint>(s.capacity));
  const std::uint32_t total = sortPassCount(s.capacity);
  for (std::uint32_t k = 0; k < passes && total > 0; ++k) {
    std::uint32_t p = 0, kk = 0;
    sortStage(s.capacity, s.sort_step, p, kk);
    glBindFramebuffer(GL_FRAMEBUFFER, s.sort_fbo[1 - s.sort_current]);
    bindTexture(0, GL_TEXTURE_2D, s.sort_tex[s.sort_current]);
    glUniform1i(loc(prog, "u_p"), static_cast<GLint>(p));
    glUniform1i(loc(prog, "u_k"), static_cast<GLint>(kk));
    glDrawArrays(GL_TRIANGLES, 0, 3);
    s.sort_current = 1 - s.sort_current;
    // §3.3.3: the network restarts once finished, so the order keeps following the camera.
    s.sort_step = (s.sort_step + 1) % total;
  }
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void sortStep(GpuParticles& s, glm::vec3 eye, std::uint32_t passes) {
  if (!s.ready) return;
  refreshSortKeys(s, eye);
  sortPasses(s, passes == 0 ? s.desc.sort_passes_per_frame : passes);
}

void drawSprites(GpuParticles& s, const glm::mat4& view_projection, float projection_scale_y, int viewport_height) {
  if (!s.ready) return;
  runPendingWork(s);
  const GLuint prog = s.sprite.id;
  glUseProgram(prog);
  bindTexture(0, GL_TEXTURE_2D, s.sort_tex[s.sort_current]);
  bindTexture(1, GL_TEXTURE_2D, s.state0[s.current]);
  bindTexture(2, GL_TEXTURE_2D, s.attributes);
  bindTexture(3, GL_TEXTURE_2D, s.type_tex);
  bindTexture(4, GL_TEXTURE_2D, s.state1[s.current]);
  glUniform1i(loc(prog, "u_pairs"), 0);
  glUniform1i(loc(prog, "u_state0"), 1);
  glUniform1i(loc(prog, "u_attributes"), 2);
  glUniform1i(loc(prog, "u_types"), 3);
  glUniform1i(loc(prog, "u_state1"), 4);
  std::array<GLint, kMaxParticleTypes> type_diffuse{};
  for (std::size_t t = 0; t < s.desc.types.size(); ++t) type_diffuse[t] = s.desc.types[t].diffuse ? 1 : 0;
  glUniform1iv(loc(prog, "u_type_diffuse"), kMaxParticleTypes, type_diffuse.data());
  const auto last_type = static_cast<std::uint32_t>(s.desc.types.size() - 1);
  glUniform3i(loc(prog, "u_class_types"), static_cast<GLint>(std::min(s.desc.class_types[0], last_type)),
              static_cast<GLint>(std::min(s.desc.class_types[1], last_type)),
              static_cast<GLint>(std::min(s.desc.class_types[2], last_type)));
  glUniform1i(loc(prog, "u_verlet"), s.desc.integrator == Integrator::verlet ? 1 : 0);
  glUniformMatrix4fv(loc(prog, "u_view_projection"), 1, GL_FALSE, glm::value_ptr(view_projection));
  glUniform1f(loc(prog, "u_time"), s.time);
  glUniform1f(loc(prog, "u_point_scale"), projection_scale_y * static_cast<float>(viewport_height) * 0.5f);
  glUniform1i(loc(prog, "u_width"), static_cast<GLint>(s.desc.width));
  glEnable(GL_PROGRAM_POINT_SIZE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);  // premultiplied "over", needs back-to-front order
  glDepthMask(GL_FALSE);
  glBindVertexArray(s.empty_vao);
  glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(s.capacity));
  glBindVertexArray(0);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
}

namespace {

void readTexture(GLuint fbo, GLenum attachment, GLsizei w, GLsizei h, GLenum format, int channels,
                 std::vector<float>& out) {
  out.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(channels));
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
  glReadBuffer(attachment);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, w, h, format, GL_FLOAT, out.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
}

// Reads one float attachment of the particle textures into `out`, one element per texel.
template <typename Vec>
void readParticleTexture(const GpuParticles& s, GLuint fbo, GLenum attachment, GLenum format, std::vector<Vec>& out) {
  out.clear();
  if (!s.ready) return;
  constexpr int kComponents = static_cast<int>(sizeof(Vec) / sizeof(float));
  std::vector<float> raw;
  readTexture(fbo, attachment, static_cast<GLsizei>(s.desc.width), static_cast<GLsizei>(s.desc.height), format,
              kComponents, raw);
  out.resize(s.capacity);
  std::memcpy(out.data(), raw.data(), raw.size() * sizeof(float));
}

// The live texels of one state attachment, in index order, as they are between two records.
void readLive(GpuParticles& s, GLenum attachment, std::vector<glm::vec4>& out) {
  readParticleTexture(s, s.fbo[s.current], attachment, GL_RGBA, s.read_scratch);
  out.clear();
  for (std::size_t i = 0; i < s.readback_live.size() && i < s.read_scratch.size(); ++i)
    if (s.readback_live[i] != 0) out.push_back(s.read_scratch[i]);
}

void runReadback(GpuParticles& s, const GpuWorkRecord& record) {
  readLive(s, GL_COLOR_ATTACHMENT0, s.readback.positions);
  readLive(s, GL_COLOR_ATTACHMENT1, s.readback.velocities);
  s.readback.step = record.step_index;
}

}  // namespace

void readPositions(GpuParticles& s, std::vector<glm::vec4>& out) {
  runPendingWork(s);
  readParticleTexture(s, s.fbo[s.current], GL_COLOR_ATTACHMENT0, GL_RGBA, out);
}

void readState1(GpuParticles& s, std::vector<glm::vec4>& out) {
  runPendingWork(s);
  readParticleTexture(s, s.fbo[s.current], GL_COLOR_ATTACHMENT1, GL_RGBA, out);
}

void readSortPairs(GpuParticles& s, std::vector<glm::vec2>& out) {
  runPendingWork(s);
  readParticleTexture(s, s.sort_fbo[s.sort_current], GL_COLOR_ATTACHMENT0, GL_RG, out);
}

}  // namespace engine
