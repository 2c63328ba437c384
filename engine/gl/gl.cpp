#include "engine/gl/gl.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace engine {

void deleteBuffer(GLuint id) { glDeleteBuffers(1, &id); }
void deleteVertexArray(GLuint id) { glDeleteVertexArrays(1, &id); }
void deleteTexture(GLuint id) { glDeleteTextures(1, &id); }
void deleteFramebuffer(GLuint id) { glDeleteFramebuffers(1, &id); }
void deleteRenderbuffer(GLuint id) { glDeleteRenderbuffers(1, &id); }
void deleteProgram(GLuint id) { glDeleteProgram(id); }
void deleteShader(GLuint id) { glDeleteShader(id); }

const char* glErrorName(GLenum error) {
  switch (error) {
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW:
      return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW:
      return "GL_STACK_OVERFLOW";
    default:
      return "unknown GL error";
  }
}

int checkGl(GlErrorLog& log, std::string_view where) {
  int found = 0;
  // glGetError returns one flag per call; a lost context could keep returning errors, so cap.
  for (GLenum error = glGetError(); error != GL_NO_ERROR && found < 32; error = glGetError()) {
    if (log.count == 0 && found == 0) log.first = std::string(glErrorName(error)) + " after " + std::string(where);
    ++found;
  }
  log.count += found;
  return found;
}

namespace {

// Parses a leading "<digits>" at `s[pos]`; returns -1 when there is none.
long parseNumber(std::string_view s, std::size_t& pos) {
  if (pos >= s.size() || s[pos] < '0' || s[pos] > '9') return -1;
  long value = 0;
  while (pos < s.size() && s[pos] >= '0' && s[pos] <= '9') value = value * 10 + (s[pos++] - '0');
  return value;
}

std::string formatLine(std::string_view line, std::span<const std::string> names) {
  std::size_t pos = 0;
  std::string_view prefix_word;
  if (line.starts_with("ERROR: "))
    prefix_word = "error: ", pos = 7;
  else if (line.starts_with("WARNING: "))
    prefix_word = "warning: ", pos = 9;
  const long source = parseNumber(line, pos);
  const std::string& file_label =
      names[source >= 0 && static_cast<std::size_t>(source) < names.size() ? static_cast<std::size_t>(source)
                                                                           : names.size() - 1];
  if (source >= 0 && pos < line.size()) {
    long number = -1, column = -1;
    std::size_t p = pos;
    if (line[p] == ':') {  // Mesa "0:12(7): msg" or "ERROR: 0:12: msg"
      ++p;
      number = parseNumber(line, p);
      if (number >= 0 && p < line.size() && line[p] == '(') {
        ++p;
        column = parseNumber(line, p);
        if (p < line.size() && line[p] == ')') ++p;
      }
    } else if (line[p] == '(') {  // NVIDIA "0(12) : msg"
      ++p;
      number = parseNumber(line, p);
      if (p < line.size() && line[p] == ')') ++p;
    }
    if (number >= 0) {
      while (p < line.size() && (line[p] == ' ' || line[p] == ':')) ++p;
      std::string out = file_label + ":" + std::to_string(number);
      if (column >= 0) {
        out += ':';
        out += std::to_string(column);
      }
      out += ": ";
      out += prefix_word;
      out += line.substr(p);
      return out;
    }
  }
  return file_label + ": " + std::string(line);
}

}  // namespace

std::string formatShaderLog(std::string_view log, const std::string& file_label) {
  return formatShaderLog(log, std::span<const std::string>(&file_label, 1));
}

std::string formatShaderLog(std::string_view log, std::span<const std::string> source_names) {
  static const std::string kUnnamed = "<shader>";
  if (source_names.empty()) source_names = std::span<const std::string>(&kUnnamed, 1);
  std::string out;
  while (!log.empty()) {
    const std::size_t end = log.find('\n');
    std::string_view line = log.substr(0, end);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\0')) line.remove_suffix(1);
    if (!line.empty()) {
      if (!out.empty()) out += '\n';
      out += formatLine(line, source_names);
    }
    if (end == std::string_view::npos) break;
    log.remove_prefix(end + 1);
  }
  if (out.empty()) out = source_names.back() + ": failed without a log";
  return out;
}

namespace {

// The driver's info log of a shader or program (glGet*iv + glGet*InfoLog).
std::string shaderInfoLog(GLuint shader) {
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
  glGetShaderInfoLog(shader, length, nullptr, log.data());
  return log;
}

std::string programInfoLog(GLuint program) {
  GLint length = 0;
  glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
  glGetProgramInfoLog(program, length, nullptr, log.data());
  return log;
}

// Compiles one stage from several source strings; `names[N]` names string N in the error.
GlShader compileSources(GLenum stage, std::span<const std::string> sources, std::span<const std::string> names,
                        std::string& error) {
  GlShader shader(glCreateShader(stage));
  if (!shader) {
    error = names.back() + ": glCreateShader failed";
    return {};
  }
  std::vector<const char*> texts;
  std::vector<GLint> lengths;
  for (const std::string& source : sources) {
    texts.push_back(source.c_str());
    lengths.push_back(static_cast<GLint>(source.size()));
  }
  glShaderSource(shader.id(), static_cast<GLsizei>(texts.size()), texts.data(), lengths.data());
  glCompileShader(shader.id());
  GLint ok = GL_FALSE;
  glGetShaderiv(shader.id(), GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    error = formatShaderLog(shaderInfoLog(shader.id()), names);
    return {};
  }
  return shader;
}

// Links the compiled `shaders` into a program (detached again afterwards); a link error is
// reported against `label`.
GlProgram linkShaders(std::span<const GlShader> shaders, const std::string& label, std::string& error) {
  GlProgram program(glCreateProgram());
  for (const GlShader& shader : shaders) glAttachShader(program.id(), shader.id());
  glLinkProgram(program.id());
  for (const GlShader& shader : shaders) glDetachShader(program.id(), shader.id());
  GLint ok = GL_FALSE;
  glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    error = formatShaderLog(programInfoLog(program.id()), label + " (link)");
    return {};
  }
  return program;
}

}  // namespace

GlShader compileShader(GLenum stage, const std::string& source, const std::string& file_label, std::string& error) {
  return compileSources(stage, std::span<const std::string>(&source, 1), std::span<const std::string>(&file_label, 1),
                        error);
}

namespace {

bool readText(const std::filesystem::path& path, std::string& out, std::string& error) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    error = path.string() + ": cannot open shader file";
    return false;
  }
  std::ostringstream text;
  text << file.rdbuf();
  out = text.str();
  if (out.empty()) {
    error = path.string() + ": shader file is empty";
    return false;
  }
  return true;
}

}  // namespace

GlProgram loadProgram(const std::filesystem::path& shader_dir, std::string_view vertex_name,
                      std::string_view fragment_name, std::string& error) {
  const std::filesystem::path vertex_path = shader_dir / vertex_name;
  const std::filesystem::path fragment_path = shader_dir / fragment_name;
  std::string vertex_source, fragment_source;
  if (!readText(vertex_path, vertex_source, error) || !readText(fragment_path, fragment_source, error)) return {};
  GlShader shaders[2];
  shaders[0] = compileShader(GL_VERTEX_SHADER, vertex_source, vertex_path.string(), error);
  if (!shaders[0]) return {};
  shaders[1] = compileShader(GL_FRAGMENT_SHADER, fragment_source, fragment_path.string(), error);
  if (!shaders[1]) return {};
  return linkShaders(shaders, vertex_path.string() + " + " + fragment_path.string(), error);
}

GLuint buildProgram(std::span<const ShaderStageFiles> stages, const std::string& prelude, std::string& error) {
  error.clear();
  std::vector<GlShader> shaders;
  std::string files;  // every file, for a link error
  for (const ShaderStageFiles& stage : stages) {
    // Source string 0 is the version line + prelude; the files follow. Each file starts with
    // "#line 1 N" (N = its source-string number) so drivers that report positions in the
    // concatenated text (Mesa) still name the right file and line.
    std::vector<std::string> texts{"#version 330 core\n" + prelude + "\n"};
    std::vector<std::string> names{"<prelude>"};
    bool read_all = true;
    for (const std::filesystem::path& file : stage.files) {
      std::string text, read_error;
      if (!readText(file, text, read_error)) {
        error += read_error + "\n";
        read_all = false;
        continue;
      }
      texts.push_back("#line 1 " + std::to_string(texts.size()) + "\n" + text + "\n");
      names.push_back(file.string());
      files += (files.empty() ? "" : " + ") + file.string();
    }
    if (!read_all) continue;
    std::string compile_error;
    GlShader shader = compileSources(stage.stage, texts, names, compile_error);
    if (!shader) {
      error += compile_error + "\n";
      continue;
    }
    shaders.push_back(std::move(shader));
  }
  if (!error.empty()) return 0;
  GlProgram program = linkShaders(shaders, files, error);
  if (!program) {
    error += "\n";
    return 0;
  }
  return program.release();
}

GLuint createTexture2D(GLenum internal_format, GLsizei width, GLsizei height, GLenum format, GLenum type,
                       const void* data, GLint filter) {
  GLuint texture = 0;
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal_format), width, height, 0, format, type, data);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glBindTexture(GL_TEXTURE_2D, 0);
  return texture;
}

void setUniform(GLuint program, const char* name, int value) {
  glUniform1i(glGetUniformLocation(program, name), value);
}
void setUniform(GLuint program, const char* name, float value) {
  glUniform1f(glGetUniformLocation(program, name), value);
}
void setUniform(GLuint program, const char* name, const glm::vec2& value) {
  glUniform2fv(glGetUniformLocation(program, name), 1, glm::value_ptr(value));
}
void setUniform(GLuint program, const char* name, const glm::vec3& value) {
  glUniform3fv(glGetUniformLocation(program, name), 1, glm::value_ptr(value));
}
void setUniform(GLuint program, const char* name, const glm::vec4& value) {
  glUniform4fv(glGetUniformLocation(program, name), 1, glm::value_ptr(value));
}
void setUniform(GLuint program, const char* name, const glm::mat4& value) {
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, glm::value_ptr(value));
}

namespace {

void GLAPIENTRY debugCallback(GLenum /*source*/, GLenum type, GLuint id, GLenum severity, GLsizei /*length*/,
                              const GLchar* message, const void* /*user*/) {
  if (severity == GL_DEBUG_SEVERITY_NOTIFICATION || severity == GL_DEBUG_SEVERITY_LOW) return;
  std::fprintf(stderr, "GL debug [%s type 0x%x id %u]: %s\n", severity == GL_DEBUG_SEVERITY_HIGH ? "high" : "medium",
               type, id, message);
}

}  // namespace

bool enableDebugOutput() {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  bool has_debug = major > 4 || (major == 4 && minor >= 3);
  if (!has_debug) {
    GLint count = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &count);
    for (GLint i = 0; i < count && !has_debug; ++i) {
      const auto* name = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
      has_debug = name != nullptr && std::strcmp(name, "GL_KHR_debug") == 0;
    }
  }
  if (!has_debug) return false;
  glEnable(GL_DEBUG_OUTPUT);
  glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
  glDebugMessageCallback(debugCallback, nullptr);
  return true;
}

}  // namespace engine
