#pragma once
// Small GL helpers private to the GPU particle and fluid-render passes: shader programs built
// from several files with compile errors mapped back to file:line. (The engine branch has its
// own loader; this one exists so these passes do not wait for it, and can be swapped later.)

#include <GL/gl.h>
#include <GL/glext.h>

#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace engine {

// One shader stage: the files are concatenated in order after a "#version 330 core" line,
// each as its own source string so the driver's "string:line" messages map back to a file.
struct ShaderStageFiles {
  GLenum stage = GL_VERTEX_SHADER;
  std::vector<std::filesystem::path> files;
};

// Builds and links a program. Returns 0 and fills `error` ("file:line: message", one per line
// of the driver log) when a file is missing or unreadable, or compiling/linking fails.
// `prelude` is inserted after the version line (e.g. #defines), reported as "<prelude>".
GLuint buildProgram(std::span<const ShaderStageFiles> stages, const std::string& prelude, std::string& error);

// Rewrites a driver info log, replacing "N:L(C)" (Mesa) or "N(L)" (NVIDIA) source references
// with "file:L". names[N] is the file of source string N. Exposed for its unit test.
std::string mapShaderLog(const std::string& log, std::span<const std::string> names);

}  // namespace engine
