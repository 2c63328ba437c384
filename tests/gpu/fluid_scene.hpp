#pragma once
// Fixed scene for the fluid-render tests and screenshots: a striped wall and a floor as the
// opaque scene, a blob of particles on a lattice turned into a mesh by fluid/surface.

#include "engine/fluid_render/fluid_render.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <glm/glm.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace gputest {

inline constexpr glm::vec3 kFluidTarget{-0.2f, 0.45f, 0.15f};  // the camera looks here

struct FluidScene {
  engine::FluidCamera camera;
  GLuint backdrop_program = 0, backdrop_vao = 0, backdrop_vbo = 0;
  std::vector<glm::vec3> particles;
  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
  int width = 0, height = 0;
};

// A colour render target of the given format and its framebuffer, deleted by the destructor (a
// GL context must be current for both).
struct ColourTarget {
  GLuint fbo = 0, texture = 0;
  ColourTarget(int width, int height, GLenum format);
  ~ColourTarget();
  ColourTarget(const ColourTarget&) = delete;
  ColourTarget& operator=(const ColourTarget&) = delete;
};

// Builds the backdrop program/geometry and the particle blob; camera at `eye` looking at the blob.
bool createFluidScene(FluidScene& scene, int width, int height, glm::vec3 eye, std::string& error);
void destroyFluidScene(FluidScene& scene);
// Extracts the mesh with the given order (none / backToFront / exact slabs) for the camera.
bool extractMesh(FluidScene& scene, fluid::SurfaceOrder order, bool exact_slabs, std::string& error);
// Draws the striped backdrop into the currently bound framebuffer (depth test on, left off after).
void drawBackdrop(const FluidScene& scene);
// Opaque pass + fluid into `target_fbo`; returns RGBA8 pixels (bottom row first).
std::vector<unsigned char> renderFrame(FluidScene& scene, engine::FluidRenderer& renderer, GLuint target_fbo,
                                       const engine::WaterParams& params, bool with_mesh);

// Binary PPM (P6) for golden images.
bool writePpm(const std::filesystem::path& path, int w, int h, const std::vector<unsigned char>& rgba);
bool readPpm(const std::filesystem::path& path, int& w, int& h, std::vector<unsigned char>& rgb, std::string& error);

}  // namespace gputest
