// GLSL programs from the files in shaders/, with the compiler's log and the
// file name in every error, and uniforms set by name.
#pragma once

#include <string>
#include <unordered_map>

#include <glm/glm.hpp>

#include "viewer/gl.h"

namespace mc::viewer {

// Folder of the .glsl files: $MILLCHARGE_SHADER_DIR, else the source tree's shaders/.
std::string shader_dir();

class ShaderProgram {
 public:
  // Compiles and links shader_dir()/vertex and shader_dir()/fragment; throws
  // std::runtime_error with the log on failure.
  ShaderProgram(const std::string& vertex, const std::string& fragment);
  ~ShaderProgram();
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  void use() const { glUseProgram(program_); }
  void set(const char* name, int v);
  void set(const char* name, float v);
  void set(const char* name, const glm::vec2& v);
  void set(const char* name, const glm::vec3& v);
  void set(const char* name, const glm::vec4& v);
  void set(const char* name, const glm::mat4& m);

 private:
  GLint location(const char* name);
  GLuint program_ = 0;
  std::unordered_map<std::string, GLint> locations_;
};

}  // namespace mc::viewer
