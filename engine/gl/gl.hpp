#pragma once
// Thin OpenGL layer: move-only handles, shader programs loaded from files with errors that
// name the file and line, and GL error accounting. Core-profile entry points come from
// GLVND's libOpenGL (GL_GLEXT_PROTOTYPES), so a context only needs to be current.

#include <GL/gl.h>
#include <GL/glext.h>

#include <glm/glm.hpp>

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace engine {

// Move-only owner of one GL object name; `Delete` frees it (needs a current context).
template <void (*Delete)(GLuint)>
class GlHandle {
 public:
  GlHandle() = default;
  explicit GlHandle(GLuint id) : id_(id) {}
  GlHandle(GlHandle&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
  GlHandle& operator=(GlHandle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, 0);
    }
    return *this;
  }
  GlHandle(const GlHandle&) = delete;
  GlHandle& operator=(const GlHandle&) = delete;
  ~GlHandle() { reset(); }
  void reset() {
    if (id_ != 0) Delete(id_);
    id_ = 0;
  }
  GLuint id() const { return id_; }
  // Hands the name to the caller, who then deletes it.
  [[nodiscard]] GLuint release() { return std::exchange(id_, 0); }
  explicit operator bool() const { return id_ != 0; }

 private:
  GLuint id_ = 0;
};

void deleteBuffer(GLuint id);
void deleteVertexArray(GLuint id);
void deleteTexture(GLuint id);
void deleteFramebuffer(GLuint id);
void deleteRenderbuffer(GLuint id);
void deleteProgram(GLuint id);
void deleteShader(GLuint id);

using GlBuffer = GlHandle<deleteBuffer>;
using GlVertexArray = GlHandle<deleteVertexArray>;
using GlTexture = GlHandle<deleteTexture>;
using GlFramebuffer = GlHandle<deleteFramebuffer>;
using GlRenderbuffer = GlHandle<deleteRenderbuffer>;
using GlProgram = GlHandle<deleteProgram>;
using GlShader = GlHandle<deleteShader>;

// GL errors seen by checkGl(); the first one is kept with where it happened.
struct GlErrorLog {
  int count = 0;
  std::string first;  // e.g. "GL_INVALID_ENUM after scene pass"
};

// Drains glGetError(); returns how many errors were pending and records them in `log`.
int checkGl(GlErrorLog& log, std::string_view where);
const char* glErrorName(GLenum error);

// Rewrites a driver's info log so every message starts with "file:line:". Understands Mesa
// ("0:12(7): error: ...") and NVIDIA/AMD ("0(12) : error ...", "ERROR: 0:12: ...") forms.
// The leading number is the source string: `source_names[N]` names string N (a number past the
// end takes the last name). Lines it cannot parse are kept and prefixed with the last name.
std::string formatShaderLog(std::string_view log, std::span<const std::string> source_names);
// The same for a shader compiled from one source string.
std::string formatShaderLog(std::string_view log, const std::string& file_label);

// Compiles one stage from `source`; on failure returns 0-handle and sets `error`
// ("<file_label>:<line>: <message>").
GlShader compileShader(GLenum stage, const std::string& source, const std::string& file_label, std::string& error);

// Reads `<shader_dir>/<vertex_name>` and `<shader_dir>/<fragment_name>`, compiles and links.
// A missing file, a compile error or a link error gives an empty handle and a message that
// names the file (and line for compile errors).
GlProgram loadProgram(const std::filesystem::path& shader_dir, std::string_view vertex_name,
                      std::string_view fragment_name, std::string& error);

// One stage built from several files (e.g. a shared .glsl library, then the stage's own file).
// The files carry no #version line: buildProgram() puts "#version 330 core" and the prelude
// first, each file as its own source string.
struct ShaderStageFiles {
  GLenum stage = GL_VERTEX_SHADER;
  std::vector<std::filesystem::path> files;
};

// Builds and links a program from per-stage file lists. Returns 0 and fills `error` (one
// "file:line[:column]: message" per driver message, see formatShaderLog) when a file is missing
// or unreadable, or compiling/linking fails. `prelude` (e.g. #defines) follows the version
// line and is reported as "<prelude>". The caller owns the returned program.
GLuint buildProgram(std::span<const ShaderStageFiles> stages, const std::string& prelude, std::string& error);

// A 2D texture (one level, clamped at the edges, `filter` for min and mag) holding `data`
// (may be null: uninitialised). The caller owns it; the texture binding is left at 0.
GLuint createTexture2D(GLenum internal_format, GLsizei width, GLsizei height, GLenum format, GLenum type,
                       const void* data, GLint filter = GL_NEAREST);

// Uniform setters by name (looked up every call; the programs here are small).
void setUniform(GLuint program, const char* name, int value);
void setUniform(GLuint program, const char* name, float value);
void setUniform(GLuint program, const char* name, const glm::vec2& value);
void setUniform(GLuint program, const char* name, const glm::vec3& value);
void setUniform(GLuint program, const char* name, const glm::vec4& value);
void setUniform(GLuint program, const char* name, const glm::mat4& value);

// Installs a KHR_debug callback (GL 4.3+ or the extension) that prints driver messages of
// medium or high severity to stderr. Returns false when the context has no debug output.
bool enableDebugOutput();

}  // namespace engine
