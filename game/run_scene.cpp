// runScene(): builds the world a scene asks for, runs the engine loop (window or headless) with
// a fixed simulation step and interpolated rendering, and reports what happened.
#include "game/run_scene.hpp"

#include "engine/assets/assets.hpp"
#include "engine/camera/camera.hpp"
#include "engine/fluid_render/fluid_render.hpp"
#include "engine/fluid_render/raycast.hpp"
#include "engine/fluid_render/screen_space.hpp"
#include "engine/gl/gl.hpp"
#include "engine/loop/fixed_step.hpp"
#include "engine/platform/platform.hpp"
#include "engine/profile/profiler.hpp"
#include "engine/render/image_write.hpp"
#include "engine/render/renderer.hpp"
#include "engine/ui/overlay.hpp"
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <imgui.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>

namespace game {
namespace {

// GPU copies of the fountain's models and textures.
struct SceneAssets {
  engine::GpuMesh ground, basin, statue, crate;
  engine::GpuTexture paving, stone, wood;
};

bool loadSceneAssets(const std::filesystem::path& content_dir, SceneAssets& out, std::string& error) {
  struct MeshJob {
    const char* file;
    engine::GpuMesh* target;
  };
  const MeshJob meshes[] = {
      {"ground.obj", &out.ground}, {"basin.obj", &out.basin}, {"statue.obj", &out.statue}, {"crate.obj", &out.crate}};
  for (const MeshJob& job : meshes) {
    engine::MeshData data;
    if (!engine::loadMesh(content_dir / "models" / job.file, data, error)) return false;
    *job.target = engine::uploadMesh(data);
  }
  struct TextureJob {
    const char* file;
    engine::GpuTexture* target;
  };
  const TextureJob textures[] = {{"paving.png", &out.paving}, {"stone.png", &out.stone}, {"crate.png", &out.wood}};
  for (const TextureJob& job : textures) {
    engine::ImageData image;
    if (!engine::loadImage(content_dir / "textures" / job.file, image, error)) return false;
    *job.target = engine::uploadTexture(image);
  }
  return true;
}

std::filesystem::path shaderDirectory() {
  if (const char* dir = std::getenv("FLUIDDEMO_SHADER_DIR"); dir != nullptr && *dir != '\0') return dir;
  return shadersDir();
}

glm::mat4 bodyMatrix(const engine::BodyState& a, const engine::BodyState& b, float alpha, float scale) {
  const glm::vec3 position = glm::mix(a.position, b.position, alpha);
  const glm::quat rotation = glm::slerp(a.rotation, b.rotation, alpha);
  return glm::translate(glm::mat4(1.0f), position) * glm::mat4_cast(rotation) *
         glm::scale(glm::mat4(1.0f), glm::vec3(scale));
}

// Draw list for the current state, interpolated by `alpha` between the last two steps.
void buildDrawList(const World& world, const SceneAssets& assets, float alpha, std::vector<engine::DrawItem>& items) {
  items.clear();
  engine::DrawItem ground;
  ground.mesh = &assets.ground;
  ground.texture = &assets.paving;
  ground.specular = 0.05f;
  ground.casts_shadow = false;
  items.push_back(ground);
  engine::DrawItem basin;
  basin.mesh = &assets.basin;
  basin.texture = &assets.stone;
  basin.specular = 0.2f;
  items.push_back(basin);
  engine::DrawItem statue = basin;
  statue.mesh = &assets.statue;
  statue.tint = glm::vec3(0.95f, 0.97f, 1.0f);
  items.push_back(statue);
  if (findState<RigidBodies>(world)) {
    const RigidBodies& bodies = *findState<RigidBodies>(world);
    for (std::size_t i = 0; i < bodies.crates.size(); ++i) {
      engine::DrawItem crate;
      crate.mesh = &assets.crate;
      crate.texture = &assets.wood;
      crate.specular = 0.08f;
      crate.model = bodyMatrix(bodies.previous[i], bodies.current[i], alpha, bodies.params.crate_size);
      items.push_back(crate);
    }
  }
}

// Overlay window with the scene's tunable parameters; edits world.scene in place.
// Returns {changed, restart requested}.
std::pair<bool, bool> drawScenePanel(World& world) {
  bool changed = false;
  bool restart = false;
  ImGui::SetNextWindowPos(ImVec2(std::max(ImGui::GetIO().DisplaySize.x - 390.0f, 400.0f), 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 0), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Scene")) {
    ImGui::End();
    return {false, false};
  }
  ImGui::Text("scene '%s', step %llu", world.scene.name.c_str(), static_cast<unsigned long long>(world.steps));
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->drawStatus();
  if (world.failures.count > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "run-time failures: %llu (frames go on)",
                       static_cast<unsigned long long>(world.failures.count));
    ImGui::TextWrapped("last: %s", world.failures.last.c_str());
  }
  ImGui::TextDisabled("LMB throw crate, RMB/Tab look, WASD move, F12 screenshot");
  ImGui::PushItemWidth(ImGui::GetWindowWidth() * 0.5f);
  auto edit_section = [&](SectionConfig& section) {
    const SectionSpec* spec = findSection(section.name);
    if (spec == nullptr || !ImGui::TreeNodeEx(section.name.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) return;
    for (const ParamSpec& param : spec->params) {
      auto it = section.params.find(param.key);
      if (it == section.params.end()) continue;
      ParamValue& value = it->second;
      const std::string label(param.key);
      bool edited = false;
      switch (param.type) {
        case ParamType::number: {
          const double speed = std::max((param.max - param.min) * 1e-3, std::abs(value.number) * 5e-3);
          edited = ImGui::DragScalar(label.c_str(), ImGuiDataType_Double, &value.number, static_cast<float>(speed),
                                     &param.min, &param.max, "%.3f", ImGuiSliderFlags_AlwaysClamp);
          break;
        }
        case ParamType::integer: {
          int v = static_cast<int>(value.number);
          const int lo = static_cast<int>(param.min), hi = static_cast<int>(param.max);
          edited = ImGui::DragInt(label.c_str(), &v, 1.0f, lo, hi, "%d", ImGuiSliderFlags_AlwaysClamp);
          value.number = v;
          break;
        }
        case ParamType::boolean:
          edited = ImGui::Checkbox(label.c_str(), &value.boolean);
          break;
        case ParamType::vec3:
          edited = ImGui::DragFloat3(label.c_str(), &value.vec.x, 0.05f, static_cast<float>(param.min),
                                     static_cast<float>(param.max), "%.2f", ImGuiSliderFlags_AlwaysClamp);
          break;
        case ParamType::text:
          if (param.choices.empty()) {
            ImGui::Text("%s: %s", label.c_str(), value.text.c_str());
          } else if (ImGui::BeginCombo(label.c_str(), value.text.c_str())) {
            for (std::string_view choice : param.choices) {
              const std::string item(choice);
              if (ImGui::Selectable(item.c_str(), value.text == item)) {
                edited = value.text != item;
                value.text = item;
              }
            }
            ImGui::EndCombo();
          }
          break;
      }
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%.*s", static_cast<int>(param.doc.size()), param.doc.data());
      changed |= edited;
    }
    ImGui::TreePop();
  };
  edit_section(world.scene.camera);
  for (SectionConfig& effect : world.scene.effects) edit_section(effect);
  edit_section(world.scene.scene);
  ImGui::TextDisabled("counts, sizes and scene.* apply on restart");
  ImGui::PopItemWidth();
  restart = ImGui::Button("Restart scene with these values");
  ImGui::End();
  return {changed, restart};
}

// The water renderer exists only while the world has a fluid_surface (created on first need,
// recreated when the framebuffer size or fluid_surface.method changes; only the chosen method's
// renderer holds GL objects). A renderer whose shaders failed stays `ready == false`: the game
// runs on without the water, and the error is printed once.
struct WaterPass {
  engine::FluidRenderer renderer;            // method mesh
  engine::ScreenSpaceRenderer screen_space;  // method screen_space
  engine::RaycastRenderer raycast;           // method raycast
  engine::FluidMethod method = engine::FluidMethod::mesh;
  bool created = false;
  int width = 0, height = 0;
};

void releaseWaterPass(WaterPass& pass) {
  if (pass.created) {
    engine::destroyFluidRenderer(pass.renderer);
    engine::destroyScreenSpaceRenderer(pass.screen_space);
    engine::destroyRaycastRenderer(pass.raycast);
  }
  pass.created = false;
}

engine::FluidMethod methodOf(const FluidSurfaceParams& p) {
  switch (p.method) {
    case SurfaceMethodChoice::screen_space:
      return engine::FluidMethod::screen_space;
    case SurfaceMethodChoice::raycast:
      return engine::FluidMethod::raycast;
    case SurfaceMethodChoice::mesh:
      break;
  }
  return engine::FluidMethod::mesh;
}

void createWaterPass(WaterPass& pass, engine::FluidMethod method, int width, int height) {
  engine::FluidRenderDesc desc;
  desc.width = width;
  desc.height = height;
  desc.shader_dir = shaderDirectory();
  bool ready = false;
  std::string error;
  if (method == engine::FluidMethod::screen_space) {
    engine::createScreenSpaceRenderer(desc, pass.screen_space);
    ready = pass.screen_space.ready;
    error = pass.screen_space.error;
  } else if (method == engine::FluidMethod::raycast) {
    engine::RaycastDesc rc;
    rc.base = desc;
    engine::createRaycastRenderer(rc, pass.raycast);
    ready = pass.raycast.ready;
    error = pass.raycast.error;
  } else {
    engine::createFluidRenderer(desc, pass.renderer);
    ready = pass.renderer.ready;
    error = pass.renderer.error;
  }
  pass.method = method;
  pass.width = width;
  pass.height = height;
  pass.created = true;
  if (!ready)
    std::fprintf(stderr, "fluiddemo: fluid_surface %s renderer unavailable: %s\n", engine::fluidMethodName(method),
                 error.c_str());
}

void drawWater(WaterPass& pass, engine::Renderer& renderer, World& world, const engine::FrameView& view) {
  if (!findState<FluidSurface>(world) || !findState<SphFluid>(world)) {
    releaseWaterPass(pass);
    return;
  }
  const FluidSurfaceParams& p = findState<FluidSurface>(world)->params;
  if (!p.visible) return;  // the renderer's objects stay for when the water shows again
  const engine::FluidMethod method = methodOf(p);
  if (pass.created && (pass.width != renderer.width || pass.height != renderer.height || pass.method != method))
    releaseWaterPass(pass);
  if (!pass.created) createWaterPass(pass, method, renderer.width, renderer.height);
  GLuint scene_fbo = 0;
  std::string upload_error;
  bool uploaded = true;
  const std::vector<glm::vec3>& particles = findState<SphFluid>(world)->world.particles.position;
  if (method == engine::FluidMethod::screen_space && pass.screen_space.ready) {
    scene_fbo = pass.screen_space.scene.fbo;
    uploaded = engine::uploadScreenSpaceParticles(pass.screen_space, particles, upload_error);
  } else if (method == engine::FluidMethod::raycast && pass.raycast.ready) {
    scene_fbo = pass.raycast.scene.fbo;
    uploaded = engine::uploadRaycastParticles(pass.raycast, particles, upload_error);
  } else if (method == engine::FluidMethod::mesh && pass.renderer.ready) {
    scene_fbo = pass.renderer.scene_fbo;
    const fluid::SurfaceMesh& mesh = findState<FluidSurface>(world)->mesh;
    uploaded = engine::uploadFluidMesh(pass.renderer, mesh.positions, mesh.normals, mesh.indices, upload_error);
  }
  if (scene_fbo == 0) return;  // the chosen renderer is unavailable
  if (!uploaded) {
    std::fprintf(stderr, "fluiddemo: fluid upload: %s\n", upload_error.c_str());
    return;
  }
  // The opaque scene (colour + depth) is the water's background: copy it into the fluid
  // renderer's scene targets (same size, DEPTH24 both), then draw the water back into the
  // scene FBO so screenshots and the window blit see it.
  glBindFramebuffer(GL_READ_FRAMEBUFFER, renderer.scene_fbo.id());
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, scene_fbo);
  glBlitFramebuffer(0, 0, renderer.width, renderer.height, 0, 0, renderer.width, renderer.height,
                    GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  engine::FluidCamera camera;
  camera.view = view.view;
  camera.projection = view.projection;
  camera.eye = view.eye;
  camera.near_plane = world.camera.near_plane;
  camera.far_plane = world.camera.far_plane;
  engine::WaterParams water;
  water.refraction = p.refraction;
  water.opacity = p.opacity;
  water.absorption = p.absorption;
  // Sky reflected by the water: the renderer's own sky colours, so the water matches the scene.
  const engine::Lighting lighting;
  water.sky_zenith = lighting.sky_zenith;
  water.sky_horizon = lighting.sky_horizon;
  water.light_direction = lighting.sun_direction;
  // The mesh's field: Rc and T in the same units, so all three methods draw the same surface.
  const float rc = p.smoothing * fluid::sphSpacing(findState<SphFluid>(world)->world.params);
  // Keep the scene's alpha at 1: the PNG output would otherwise turn see-through under water.
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
  if (method == engine::FluidMethod::screen_space) {
    engine::ScreenSpaceParams ss;
    ss.radius = 0.975f * rc / 3.0f;  // a lone particle's iso-surface radius
    ss.filter_radius = 0.5f * rc;
    engine::drawScreenSpaceFluid(pass.screen_space, renderer.scene_fbo.id(), camera, water, ss);
  } else if (method == engine::FluidMethod::raycast) {
    engine::RaycastParams rp;
    rp.rc = rc;
    rp.threshold = p.threshold;
    engine::drawRaycastFluid(pass.raycast, renderer.scene_fbo.id(), camera, water, rp);
    findState<FluidSurface>(world)->raycast_records = pass.raycast.used;
    findState<FluidSurface>(world)->raycast_dropped = pass.raycast.dropped;
    findState<FluidSurface>(world)->raycast_pool = pass.raycast.pool_records;
    findState<FluidSurface>(world)->raycast_pool_bound = pass.raycast.max_pool_records;
  } else {
    engine::drawFluid(pass.renderer, renderer.scene_fbo.id(), camera, water);
  }
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  engine::checkGl(renderer.errors, "fluid surface");
}

}  // namespace

bool displayAvailable() {
  const char* driver = std::getenv("SDL_VIDEODRIVER");
  if (driver != nullptr && (std::string_view(driver) == "offscreen" || std::string_view(driver) == "dummy"))
    return false;
  const char* x11 = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  return (x11 != nullptr && *x11 != '\0') || (wayland != nullptr && *wayland != '\0');
}

void printRunSummary(std::FILE* out, const SceneConfig& scene, const RunOptions& options, const RunReport& report) {
  std::fprintf(out, "fluiddemo: scene '%s', %d frames, %llu simulation steps, %dx%d %s\n", scene.name.c_str(),
               report.frames_rendered, static_cast<unsigned long long>(report.simulation_steps), options.width,
               options.height, options.headless ? "headless" : "window");
  std::fprintf(out, "renderer: %s\n", report.gl_renderer.c_str());
  std::string systems;
  for (const std::string& system : report.systems_constructed) systems += (systems.empty() ? "" : ", ") + system;
  std::fprintf(out, "systems running: %s\n", systems.empty() ? "(none)" : systems.c_str());
  std::fprintf(out, "%-10s %10s %10s %10s\n", "phase", "mean ms", "max ms", "samples");
  for (const PhaseTiming& phase : report.phases) {
    std::fprintf(out, "%-10s %10.3f %10.3f %10llu\n", phase.phase.c_str(), phase.mean_ms, phase.max_ms,
                 static_cast<unsigned long long>(phase.samples));
  }
  std::fprintf(out, "%-10s %10.3f\n", "frame", report.mean_frame_ms);
  if (report.runtime_failures > 0) {
    std::fprintf(out, "run-time failures: %llu (the frames went on); first: %s; last: %s\n",
                 static_cast<unsigned long long>(report.runtime_failures), report.first_failure.c_str(),
                 report.last_failure.c_str());
  }
}

std::string_view playerActionName(PlayerAction action) {
  switch (action) {
    case PlayerAction::throw_crate:
      return "throw_crate";
  }
  return "?";
}

bool parsePlayerAction(std::string_view name, PlayerAction& out) {
  for (PlayerAction action : {PlayerAction::throw_crate}) {
    if (name == playerActionName(action)) {
      out = action;
      return true;
    }
  }
  return false;
}

void applyPlayerAction(World& world, PlayerAction action) {
  switch (action) {
    case PlayerAction::throw_crate:
      playerThrow(world);
      break;
  }
}

int runScene(const SceneConfig& scene, const RunOptions& options, RunReport& report, std::string& error) {
  report = RunReport{};
  const std::filesystem::path content_dir = contentDir();
  World world;
  if (!buildWorld(scene, content_dir, world, error)) return 1;
  // The sprites' GL objects are freed while the context is still current, on every way out.
  struct GpuEffects {
    World& world;
    ~GpuEffects() { detachWorldGpu(world); }
  };
  report.systems_constructed = world.systems;

  engine::PlatformDesc platform_desc;
  platform_desc.width = options.width;
  platform_desc.height = options.height;
  platform_desc.headless = options.headless;
#ifdef FLUIDDEMO_GL_DEBUG
  platform_desc.debug_context = true;
#endif
  engine::Platform platform;
  if (!engine::createPlatform(platform_desc, platform, error)) return 1;
  report.gl_renderer = platform.gl_renderer;
#ifdef FLUIDDEMO_GL_DEBUG
  engine::enableDebugOutput();
#endif
  int code = 0;
  {
    // GL objects live in this scope so they die before the context.
    const int fb_width = options.headless ? std::clamp(options.width, 64, 8192) : platform.width;
    const int fb_height = options.headless ? std::clamp(options.height, 64, 8192) : platform.height;
    engine::Renderer renderer;
    SceneAssets assets;
    engine::Overlay overlay;
    WaterPass water_pass;
    // llvmpipe (headless CI) pays for every shadow texel it clears; 1024 is plenty at 720p there.
    const int shadow_size = options.headless ? 1024 : 2048;
    if (!engine::createRenderer(shaderDirectory(), fb_width, fb_height, renderer, error, shadow_size) ||
        !loadSceneAssets(content_dir, assets, error) || !engine::createOverlay(platform, overlay, error)) {
      code = 1;
    } else {
      attachWorldGpu(world, shaderDirectory(), content_dir);
      const GpuEffects gpu_effects{world};
      overlay.visible = options.show_ui;
      engine::FixedStepDesc clock_desc;
      clock_desc.step_seconds = world.step_seconds;
      clock_desc.substeps = world.substeps;
      clock_desc.max_steps_per_frame = scene.scene.integer("max_steps_per_frame");
      engine::FixedStepClock clock = engine::makeFixedStepClock(clock_desc);
      engine::Profiler profiler;
      engine::InputState input;
      engine::Lighting lighting;
      std::vector<engine::DrawItem> items;
      std::vector<std::uint8_t> pixels;
      std::vector<PlayerAction> actions;
      std::filesystem::path hook_screenshot;
      auto last_time = std::chrono::steady_clock::now();
      std::uint64_t steps_done = 0;

      for (int frame = 0; options.frames <= 0 || frame < options.frames; ++frame) {
        engine::beginFrame(profiler);
        const auto now = std::chrono::steady_clock::now();
        const double real_dt = std::chrono::duration<double>(now - last_time).count();
        last_time = now;
        const double frame_dt = options.fixed_frame_time ? world.step_seconds : real_dt;
        {
          engine::ScopedPhase phase(profiler, engine::Phase::input);
          engine::pollInput(platform, input, engine::overlayWantsMouse(overlay), engine::overlayWantsKeyboard(overlay),
                            &engine::overlayProcessEvent);
          if (input.toggle_ui) overlay.visible = !overlay.visible;
          engine::CameraInput camera_input;
          camera_input.forward = (input.forward ? 1.0f : 0.0f) - (input.back ? 1.0f : 0.0f);
          camera_input.right = (input.right ? 1.0f : 0.0f) - (input.left ? 1.0f : 0.0f);
          camera_input.up = (input.up ? 1.0f : 0.0f) - (input.down ? 1.0f : 0.0f);
          camera_input.fast = input.fast;
          camera_input.look_dx = input.mouse_dx;
          camera_input.look_dy = input.mouse_dy;
          engine::updateCamera(world.camera, camera_input, static_cast<float>(frame_dt));
          actions.clear();
          if (input.left_click) actions.push_back(PlayerAction::throw_crate);
          FrameInput frame_input{world, frame, actions, {}};
          if (options.hooks.before_steps) options.hooks.before_steps(frame_input);
          for (PlayerAction action : actions) applyPlayerAction(world, action);
          hook_screenshot = std::move(frame_input.screenshot);
          if (input.resized && !options.headless) {
            std::string resize_error;
            if (!engine::resizeRenderer(renderer, platform.width, platform.height, resize_error)) {
              error = resize_error;
              code = 1;
            }
          }
        }
        if (input.quit || code != 0) {
          engine::endFrame(profiler);
          break;
        }
        const int steps = engine::advanceFrame(clock, frame_dt);
        for (int s = 0; s < steps; ++s) stepWorld(world, &profiler);
        steps_done += static_cast<std::uint64_t>(steps);
        // With a fixed frame time the accumulator is always empty: show the newest state.
        const float alpha = options.fixed_frame_time ? 1.0f : static_cast<float>(engine::interpolationAlpha(clock));

        meshWorld(world, &profiler);  // meshing phase; no-op without fluid_surface

        const bool last_frame = options.frames > 0 && frame + 1 == options.frames;
        {
          engine::ScopedPhase phase(profiler, engine::Phase::render);
          buildDrawList(world, assets, alpha, items);
          engine::FrameView view;
          view.view = engine::cameraView(world.camera);
          view.projection = engine::cameraProjection(
              world.camera, static_cast<float>(renderer.width) / static_cast<float>(renderer.height));
          view.eye = world.camera.position;
          engine::renderScene(renderer, view, lighting, items, true);
          drawWater(water_pass, renderer, world, view);
          if (findState<SpriteParticles>(world)) {
            drawSpriteParticles(*findState<SpriteParticles>(world), renderer.scene_fbo.id(), renderer.width,
                                renderer.height, view.view, view.projection, view.eye);
            engine::checkGl(renderer.errors, "sprites");
          }
          if (input.screenshot || !hook_screenshot.empty() ||
              (last_frame && (!options.screenshot.empty() || options.capture_last_frame))) {
            engine::readSceneRgba(renderer, pixels);
          }
          if (!hook_screenshot.empty()) {
            std::string write_error;
            if (!engine::writePngBottomUp(hook_screenshot, renderer.width, renderer.height, pixels, write_error)) {
              error = write_error;
              code = 1;
            }
          }
          if (input.screenshot) {
            const std::filesystem::path path = engine::nextFreeScreenshotPath(".", "fluiddemo");
            std::string write_error;
            if (engine::writePngBottomUp(path, renderer.width, renderer.height, pixels, write_error)) {
              std::printf("screenshot: %s\n", path.string().c_str());
            } else {
              std::fprintf(stderr, "fluiddemo: %s\n", write_error.c_str());
            }
          }
          if (last_frame) {
            if (!options.screenshot.empty() &&
                !engine::writePngBottomUp(options.screenshot, renderer.width, renderer.height, pixels, error)) {
              code = 1;
            }
            if (options.capture_last_frame) {
              report.frame_width = renderer.width;
              report.frame_height = renderer.height;
              report.last_frame_rgba = pixels;
              // The same passes with nothing drawn but the clear, for the smoke test's blank check.
              engine::renderScene(renderer, view, lighting, {}, false);
              engine::readSceneRgba(renderer, report.blank_frame_rgba);
            }
          }
          // Headless there is nobody to show the window to; the scene FBO is the output.
          if (!platform.headless) engine::presentToWindow(renderer, platform.width, platform.height);
        }
        {
          engine::ScopedPhase phase(profiler, engine::Phase::ui);
          if (overlay.visible) {
            engine::beginOverlayFrame(overlay);
            engine::drawProfilerWindow(profiler, world.systems, platform.gl_renderer);
            const auto [changed, restart] = drawScenePanel(world);
            if (options.hooks.draw_overlay) options.hooks.draw_overlay();
            engine::endOverlayFrame(overlay);
            engine::checkGl(renderer.errors, "overlay");
            if (changed) applyLiveParams(world);
            if (restart) {
              const SceneConfig edited = world.scene;
              const engine::FpsCamera camera = world.camera;
              std::string rebuild_error;
              detachWorldGpu(world);
              if (buildWorld(edited, content_dir, world, rebuild_error)) {
                world.camera = camera;
                report.systems_constructed = world.systems;
                attachWorldGpu(world, shaderDirectory(), content_dir);
              } else {
                std::fprintf(stderr, "fluiddemo: restart failed: %s\n", rebuild_error.c_str());
              }
            }
          }
        }
        engine::swapWindow(platform);
        engine::endFrame(profiler);
        ++report.frames_rendered;
        if (code != 0) break;
        if (options.hooks.after_frame) {
          FrameResult result{world, frame, steps, {}, 0.0};
          for (int p = 0; p < engine::kPhaseCount; ++p) result.phase_ms[p] = profiler.current_ms[p];
          const int last = (profiler.head - 1 + engine::Profiler::kHistory) % engine::Profiler::kHistory;
          result.frame_ms = profiler.frame_history[last];
          if (!options.hooks.after_frame(result)) {
            report.stopped_by_hook = true;
            break;
          }
        }
      }
      report.simulation_steps = steps_done;
      report.nonfinite_state = world.nonfinite_state;
      report.runtime_failures = world.failures.count;
      report.first_failure = world.failures.first;
      report.last_failure = world.failures.last;
      report.mean_frame_ms = engine::frameMeanMs(profiler);
      for (int p = 0; p < engine::kPhaseCount; ++p) {
        const auto phase = static_cast<engine::Phase>(p);
        PhaseTiming timing;
        timing.phase = std::string(engine::phaseName(phase));
        timing.mean_ms = engine::phaseMeanMs(profiler, phase);
        timing.max_ms = profiler.stats[p].max_ms;
        timing.samples = profiler.stats[p].frames;
        report.phases.push_back(timing);
      }
      engine::checkGl(renderer.errors, "end of run");
    }
    releaseWaterPass(water_pass);
    report.gl_errors = renderer.errors.count;
    if (renderer.errors.count > 0)
      std::fprintf(stderr, "fluiddemo: first GL error: %s\n", renderer.errors.first.c_str());
    engine::destroyOverlay(overlay);
  }
  engine::destroyPlatform(platform);
  return code;
}

}  // namespace game
