#include "engine/gpu_particles/gl_program.hpp"

#include <cctype>
#include <fstream>
#include <sstream>

namespace engine {

namespace {

bool readFile(const std::filesystem::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  out = ss.str();
  return static_cast<bool>(in) || in.eof();
}

// Parses digits at s[pos], advancing pos; false when none.
bool parseNumber(const std::string& s, std::size_t& pos, unsigned long& value) {
  const std::size_t start = pos;
  value = 0;
  while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos])))
    value = value * 10 + static_cast<unsigned long>(s[pos++] - '0');
  return pos > start;
}

}  // namespace

std::string mapShaderLog(const std::string& log, std::span<const std::string> names) {
  std::istringstream lines(log);
  std::string line, out;
  while (std::getline(lines, line)) {
    // Skip a leading "ERROR: " / "WARNING: " tag (some drivers) but keep it in the message.
    std::size_t pos = 0;
    std::string tag;
    for (const char* prefix : {"ERROR: ", "WARNING: "}) {
      const std::string p(prefix);
      if (line.compare(0, p.size(), p) == 0) {
        tag = p;
        pos = p.size();
      }
    }
    unsigned long source = 0, row = 0, column = 0;
    std::size_t cursor = pos;
    bool mapped = false;
    if (parseNumber(line, cursor, source) && source < names.size()) {
      if (cursor < line.size() && line[cursor] == ':') {  // Mesa: "0:12(5): error: ..."
        ++cursor;
        if (parseNumber(line, cursor, row)) {
          if (cursor < line.size() && line[cursor] == '(') {
            ++cursor;
            parseNumber(line, cursor, column);
            if (cursor < line.size() && line[cursor] == ')') ++cursor;
          }
          mapped = true;
        }
      } else if (cursor < line.size() && line[cursor] == '(') {  // NVIDIA: "0(12) : error ..."
        ++cursor;
        if (parseNumber(line, cursor, row) && cursor < line.size() && line[cursor] == ')') {
          ++cursor;
          mapped = true;
        }
      }
    }
    if (mapped) {
      std::string rest = line.substr(cursor);
      while (!rest.empty() && (rest.front() == ' ' || rest.front() == ':')) rest.erase(rest.begin());
      out += names[source] + ":" + std::to_string(row) + ": " + tag + rest + "\n";
    } else if (!line.empty()) {
      out += line + "\n";
    }
  }
  return out;
}

GLuint buildProgram(std::span<const ShaderStageFiles> stages, const std::string& prelude, std::string& error) {
  error.clear();
  const GLuint program = glCreateProgram();
  std::vector<GLuint> shaders;
  bool ok = true;
  for (const ShaderStageFiles& stage : stages) {
    // Source string 0 is the version line + prelude; the files follow. Each file starts with
    // "#line 1 N" (N = its source-string number) so drivers that report positions in the
    // concatenated text (Mesa) still name the right file and line.
    std::vector<std::string> texts{"#version 330 core\n" + prelude + "\n"};
    std::vector<std::string> names{"<prelude>"};
    for (const std::filesystem::path& file : stage.files) {
      std::string text;
      if (!readFile(file, text)) {
        error += file.string() + ": cannot read shader file\n";
        ok = false;
        continue;
      }
      texts.push_back("#line 1 " + std::to_string(texts.size()) + "\n" + text + "\n");
      names.push_back(file.string());
    }
    if (!ok) continue;
    std::vector<const char*> pointers;
    for (const std::string& t : texts) pointers.push_back(t.c_str());
    const GLuint shader = glCreateShader(stage.stage);
    glShaderSource(shader, static_cast<GLsizei>(pointers.size()), pointers.data(), nullptr);
    glCompileShader(shader);
    GLint status = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &status);
    if (status != GL_TRUE) {
      GLint length = 0;
      glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
      std::string log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
      glGetShaderInfoLog(shader, length, nullptr, log.data());
      std::string mapped = mapShaderLog(log.c_str(), names);
      if (mapped.empty()) mapped = names.back() + ": compile failed (empty driver log)\n";
      error += mapped;
      ok = false;
    }
    shaders.push_back(shader);
    glAttachShader(program, shader);
  }
  if (ok) {
    glLinkProgram(program);
    GLint status = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &status);
    if (status != GL_TRUE) {
      GLint length = 0;
      glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
      std::string log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
      glGetProgramInfoLog(program, length, nullptr, log.data());
      error += "link failed: " + std::string(log.c_str()) + "\n";
      ok = false;
    }
  }
  for (GLuint shader : shaders) glDeleteShader(shader);
  if (!ok) {
    glDeleteProgram(program);
    return 0;
  }
  return program;
}

}  // namespace engine
