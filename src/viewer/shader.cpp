#include "viewer/shader.h"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

namespace mc::viewer {

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read shader " + path + " (set MILLCHARGE_SHADER_DIR to the shaders/ folder)");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

GLuint compile(GLenum type, const std::string& file) {
  const std::string path = shader_dir() + "/" + file;
  const std::string source = read_text(path);
  const GLuint sh = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(sh, 1, &text, nullptr);
  glCompileShader(sh);
  GLint ok = 0;
  glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetShaderiv(sh, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(static_cast<std::size_t>(n) + 1, '\0');
    glGetShaderInfoLog(sh, n, nullptr, log.data());
    glDeleteShader(sh);
    throw std::runtime_error("shader " + path + " does not compile:\n" + log.data());
  }
  return sh;
}

}  // namespace

std::string shader_dir() {
  if (const char* env = std::getenv("MILLCHARGE_SHADER_DIR")) return env;
  return MC_SHADER_DIR;
}

ShaderProgram::ShaderProgram(const std::string& vertex, const std::string& fragment) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex);
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, fragment);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  program_ = glCreateProgram();
  glAttachShader(program_, vs);
  glAttachShader(program_, fs);
  glLinkProgram(program_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(program_, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(static_cast<std::size_t>(n) + 1, '\0');
    glGetProgramInfoLog(program_, n, nullptr, log.data());
    glDeleteProgram(program_);
    throw std::runtime_error("shaders " + vertex + " + " + fragment + " do not link:\n" + log.data());
  }
}

ShaderProgram::~ShaderProgram() {
  if (program_) glDeleteProgram(program_);
}

GLint ShaderProgram::location(const char* name) {
  auto it = locations_.find(name);
  if (it != locations_.end()) return it->second;
  const GLint loc = glGetUniformLocation(program_, name);  // −1: unused, ignored by glUniform
  locations_.emplace(name, loc);
  return loc;
}

void ShaderProgram::set(const char* name, int v) { glUniform1i(location(name), v); }
void ShaderProgram::set(const char* name, float v) { glUniform1f(location(name), v); }
void ShaderProgram::set(const char* name, const glm::vec2& v) { glUniform2fv(location(name), 1, glm::value_ptr(v)); }
void ShaderProgram::set(const char* name, const glm::vec3& v) { glUniform3fv(location(name), 1, glm::value_ptr(v)); }
void ShaderProgram::set(const char* name, const glm::vec4& v) { glUniform4fv(location(name), 1, glm::value_ptr(v)); }
void ShaderProgram::set(const char* name, const glm::mat4& m) {
  glUniformMatrix4fv(location(name), 1, GL_FALSE, glm::value_ptr(m));
}

}  // namespace mc::viewer
