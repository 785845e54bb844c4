// The mill, cut away so that the charge shows: the far half of the shell
// (back faces culled: only the inside facing the eye is drawn; the near half
// translucent over the balls), the back end
// plate (the front one is left out; a periodic slice has none), the lifter
// bars as extruded polygons,
// dark rims at both ends that outline the shell in the end view, and marks
// for the toe and the shoulder just outside the shell.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "core/liner.h"
#include "core/scene.h"
#include "viewer/gl.h"
#include "viewer/shader.h"

namespace mc::viewer {

struct MillMarks {
  bool show = false;
  float toe_deg = 0, shoulder_deg = 0;  // counter-clockwise from 3 o'clock, lab frame
  bool impact = false;                  // the impact point of the cataracting charge
  float impact_deg = 0;
};

class MillRenderer {
 public:
  MillRenderer();
  ~MillRenderer();
  MillRenderer(const MillRenderer&) = delete;
  MillRenderer& operator=(const MillRenderer&) = delete;

  // Rebuilds the meshes from the walls (after a lifter edit).
  void set_walls(const Walls& walls);
  // The liner's elements (the shell's, the lifter faces', the back plate's),
  // drawn over the plain parts in a colour each when coloured is on.
  void set_liner(const LinerLayout& layout);
  void set_liner_colours(const std::vector<glm::vec3>& per_element);
  // Opaque parts, before the balls.
  void draw(const glm::mat4& view, const glm::mat4& projection, bool orthographic, double mill_angle,
            bool show_shell, bool liner_coloured = false);
  // The near half of the shell, translucent: after the balls.
  void draw_near_shell(const glm::mat4& view, const glm::mat4& projection, bool orthographic, double mill_angle);
  // Marks on top of everything, after the balls.
  void draw_marks(const glm::mat4& view, const glm::mat4& projection, const MillMarks& marks);

 private:
  void use_turning(const glm::mat4& view, const glm::mat4& projection, bool orthographic, double mill_angle);
  struct Vertex {
    glm::vec3 position, normal;
  };
  struct Mesh {
    GLuint vao = 0, vbo = 0;
    GLsizei count = 0;
    void create();
    void destroy();
    void upload(const std::vector<Vertex>& v);
    void draw() const;
  };
  // A mesh with a colour per vertex, and the liner element of each vertex.
  struct ColourVertex {
    glm::vec3 position, normal, colour;
  };
  struct ColourMesh {
    GLuint vao = 0, vbo = 0;
    std::vector<ColourVertex> vertices;
    std::vector<int> element;
    void create();
    void destroy();
    void upload();
    void draw() const;
  };
  ShaderProgram shader_;
  Mesh shell_, plate_, rims_, lifters_, marks_;
  Mesh still_;  // mesh walls that stand still: drawn in the lab frame
  ColourMesh liner_shell_, liner_parts_;  // culled like the shell; the rest
  ColourMesh liner_still_;                // still meshes' elements, lab frame
  // Per mesh wall (Walls::meshes), its triangles left out of the picture
  // (the front end's, as the front end plate is).
  std::vector<std::vector<bool>> mesh_hidden_;
  float radius_ = 0, length_ = 0;
  bool end_plates_ = true;  // false for a periodic slice
};

}  // namespace mc::viewer
