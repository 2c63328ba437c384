#pragma once
// What `fluiddemo render` draws a static particle set over, headless, and where: a striped wall
// behind the set and a floor under it (the GL tests' scene, so refraction and absorption show),
// an RGBA8 target read back for the PNG, and a wait for the GPU that ends each timed stage. The
// command lives in game/, which makes no GL call: these do it.

#include "engine/fluid_render/fluid_render.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace engine {

struct Backdrop {
  GLuint program = 0, vao = 0, vbo = 0;
};

// The wall on the far side of the set's box [lo, hi] from `eye` and the floor below its lowest
// sphere (radius below lo.y); shaders from SHADERS/fluid/backdrop.*. False + error.
bool createBackdrop(const std::filesystem::path& shaders, glm::vec3 lo, glm::vec3 hi, float radius, glm::vec3 eye,
                    Backdrop& b, std::string& error);
void destroyBackdrop(Backdrop& b);
// Clears `fbo` to `sky` and draws the backdrop with depth.
void drawBackdrop(const Backdrop& b, GLuint fbo, const FluidCamera& camera, int w, int h, glm::vec3 sky);

struct ColourTarget {
  GLuint fbo = 0, colour = 0;
  int width = 0, height = 0;
};
void createColourTarget(int width, int height, ColourTarget& out);
void readColourTarget(const ColourTarget& target, std::vector<std::uint8_t>& rgba);  // bottom row first
void destroyColourTarget(ColourTarget& target);

// Waits until the GPU has done everything asked so far: a timed stage then includes its GPU work.
void finishGpu();

}  // namespace engine
