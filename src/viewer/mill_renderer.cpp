#include "viewer/mill_renderer.h"

#include <cmath>
#include <cstdint>

#include <glm/gtc/matrix_transform.hpp>

#include "core/plate_wear.h"

namespace mc::viewer {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kSegments = 120;

}  // namespace

void MillRenderer::Mesh::create() {
  glGenVertexArrays(1, &vao);
  glGenBuffers(1, &vbo);
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<const void*>(std::uintptr_t{sizeof(glm::vec3)}));
  glBindVertexArray(0);
}

void MillRenderer::Mesh::destroy() {
  glDeleteBuffers(1, &vbo);
  glDeleteVertexArrays(1, &vao);
}

void MillRenderer::Mesh::upload(const std::vector<Vertex>& v) {
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(v.size() * sizeof(Vertex)), v.data(), GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  count = static_cast<GLsizei>(v.size());
}

void MillRenderer::Mesh::draw() const {
  if (count == 0) return;
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, count);
  glBindVertexArray(0);
}

void MillRenderer::ColourMesh::create() {
  glGenVertexArrays(1, &vao);
  glGenBuffers(1, &vbo);
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  for (GLuint a = 0; a < 3; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, sizeof(ColourVertex),
                          reinterpret_cast<const void*>(std::uintptr_t{a * sizeof(glm::vec3)}));
  }
  glBindVertexArray(0);
}

void MillRenderer::ColourMesh::destroy() {
  glDeleteBuffers(1, &vbo);
  glDeleteVertexArrays(1, &vao);
}

void MillRenderer::ColourMesh::upload() {
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(ColourVertex)), vertices.data(),
               GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void MillRenderer::ColourMesh::draw() const {
  if (vertices.empty()) return;
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices.size()));
  glBindVertexArray(0);
}

MillRenderer::MillRenderer() : shader_("mill.vert", "mill.frag") {
  for (Mesh* m : {&shell_, &plate_, &rims_, &lifters_, &marks_, &still_}) m->create();
  for (ColourMesh* m : {&liner_shell_, &liner_parts_, &liner_still_}) m->create();
}

MillRenderer::~MillRenderer() {
  for (Mesh* m : {&shell_, &plate_, &rims_, &lifters_, &marks_, &still_}) m->destroy();
  for (ColourMesh* m : {&liner_shell_, &liner_parts_, &liner_still_}) m->destroy();
}

void MillRenderer::set_liner(const LinerLayout& layout) {
  for (ColourMesh* m : {&liner_shell_, &liner_parts_, &liner_still_}) {
    m->vertices.clear();
    m->element.clear();
  }
  const glm::vec3 grey{0.55f, 0.56f, 0.58f};
  for (int e = 0; e < layout.size(); ++e) {
    const LinerElement& el = layout.elements[e];
    if (el.part == LinerPart::plate && el.row != 0) continue;  // the front plate is left out
    if (el.part == LinerPart::mesh && static_cast<std::size_t>(el.row) < mesh_hidden_.size() &&
        static_cast<std::size_t>(el.bin) < mesh_hidden_[el.row].size() && mesh_hidden_[el.row][el.bin])
      continue;  // as set_walls leaves it out
    ColourMesh& m = el.part == LinerPart::shell ? liner_shell_ : el.still ? liner_still_ : liner_parts_;
    // A worn plate's outline follows its dish (core/liner.cpp), as the
    // grey plate behind it does (set_walls).
    const std::vector<Vec3>& o = el.outline;
    for (std::size_t k = 1; k + 1 < o.size(); ++k) {
      glm::vec3 a(o[0].x, o[0].y, o[0].z), b(o[k].x, o[k].y, o[k].z), c(o[k + 1].x, o[k + 1].y, o[k + 1].z);
      glm::vec3 n = glm::cross(b - a, c - a);
      if (glm::length(n) <= 0) continue;
      n = glm::normalize(n);
      // The shell's triangles face the axis, so that culling leaves its far half.
      if (el.part == LinerPart::shell && glm::dot(n, -glm::vec3(a.x, a.y, 0)) < 0) {
        std::swap(b, c);
        n = -n;
      }
      for (const glm::vec3& p : {a, b, c}) {
        m.vertices.push_back({p, n, grey});
        m.element.push_back(e);
      }
    }
  }
  liner_shell_.upload();
  liner_parts_.upload();
  liner_still_.upload();
}

void MillRenderer::set_liner_colours(const std::vector<glm::vec3>& per_element) {
  for (ColourMesh* m : {&liner_shell_, &liner_parts_, &liner_still_}) {
    for (std::size_t v = 0; v < m->vertices.size(); ++v) {
      const int e = m->element[v];
      if (e >= 0 && static_cast<std::size_t>(e) < per_element.size()) m->vertices[v].colour = per_element[e];
    }
    m->upload();
  }
}

void MillRenderer::set_walls(const Walls& w) {
  radius_ = static_cast<float>(w.shell_radius);
  length_ = static_cast<float>(w.length);
  end_plates_ = !w.periodic && w.end_plates;
  const float R = radius_, L = length_;
  auto at = [](float r, float a, float z) { return glm::vec3(r * std::cos(a), r * std::sin(a), z); };

  // Shell: front faces on the inside, so culling back faces leaves the far half.
  std::vector<Vertex> shell;
  for (int k = 0; k < kSegments; ++k) {
    const float a0 = 2 * kPi * k / kSegments, a1 = 2 * kPi * (k + 1) / kSegments;
    const glm::vec3 n0 = -at(1, a0, 0), n1 = -at(1, a1, 0);
    const Vertex p00{at(R, a0, 0), n0}, p10{at(R, a1, 0), n1}, p01{at(R, a0, L), n0}, p11{at(R, a1, L), n1};
    shell.insert(shell.end(), {p00, p11, p10, p00, p01, p11});
  }
  shell_.upload(shell);

  // Back end plate just behind z = 0, facing +z (behind the lifters' end
  // caps, which would fight it for depth at z = 0); a worn one on its dish
  // (core/plate_wear.h), just behind the liner's colours drawn on it.
  const float behind = -0.004f * R;
  std::vector<Vertex> plate;
  const glm::vec3 up_z{0, 0, 1};
  for (const Triangle& t : plate_face_triangles(w.plate_depth[0], w.shell_radius, kSegments)) {
    const glm::vec3 a(t.v[0].x, t.v[0].y, t.v[0].z), b(t.v[1].x, t.v[1].y, t.v[1].z), c(t.v[2].x, t.v[2].y, t.v[2].z);
    const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a)), shift(0, 0, behind);
    plate.insert(plate.end(), {{a + shift, n}, {b + shift, n}, {c + shift, n}});
  }
  plate_.upload(plate);

  // Rims: rings from R to 1.06 R just outside both ends, facing out of the
  // mill (in front of the lifters' end caps).
  std::vector<Vertex> rims;
  for (float z : {behind, L - behind}) {
    const glm::vec3 n{0, 0, z > 0 ? 1.0f : -1.0f};
    for (int k = 0; k < kSegments; ++k) {
      const float a0 = 2 * kPi * k / kSegments, a1 = 2 * kPi * (k + 1) / kSegments;
      const Vertex i0{at(R, a0, z), n}, i1{at(R, a1, z), n}, o0{at(1.06f * R, a0, z), n}, o1{at(1.06f * R, a1, z), n};
      if (z > 0) rims.insert(rims.end(), {i0, o0, o1, i0, o1, i1});
      else rims.insert(rims.end(), {i0, o1, o0, i0, i1, o1});
    }
  }
  rims_.upload(rims);

  // Lifters: side faces and end caps of each counter-clockwise polygon.
  std::vector<Vertex> bars;
  for (const auto& poly : w.lifters) {
    const std::size_t n = poly.size();
    for (std::size_t k = 0; k < n; ++k) {
      const Vec2 a = poly[k], b = poly[(k + 1) % n];
      const glm::vec3 nrm = glm::normalize(glm::vec3(b.y - a.y, -(b.x - a.x), 0));
      const Vertex a0{{a.x, a.y, 0}, nrm}, b0{{b.x, b.y, 0}, nrm}, a1{{a.x, a.y, L}, nrm}, b1{{b.x, b.y, L}, nrm};
      bars.insert(bars.end(), {a0, b0, b1, a0, b1, a1});
    }
    for (std::size_t k = 1; k + 1 < n; ++k) {
      const Vec2 a = poly[0], b = poly[k], c = poly[k + 1];
      bars.insert(bars.end(), {{{a.x, a.y, L}, up_z}, {{b.x, b.y, L}, up_z}, {{c.x, c.y, L}, up_z}});
      bars.insert(bars.end(), {{{a.x, a.y, 0}, -up_z}, {{c.x, c.y, 0}, -up_z}, {{b.x, b.y, 0}, -up_z}});
    }
  }
  // Mesh walls, drawn as the lifters are (their triangles face the charge;
  // culling is off for these): those that turn with the mill with the
  // lifters, those that stand still in the lab frame.
  std::vector<Vertex> still;
  mesh_hidden_.assign(w.meshes.size(), {});
  for (std::size_t k = 0; k < w.meshes.size(); ++k) {
    const WallMesh& m = w.meshes[k];
    std::vector<Vertex>& into = m.turning ? bars : still;
    mesh_hidden_[k].assign(m.triangles.size(), false);
    for (std::size_t i = 0; i < m.triangles.size(); ++i) {
      const Triangle& t = m.triangles[i];
      // The front end (z past the middle, towards the camera) is left out,
      // as the front end plate is.
      if (m.part == MeshPart::ends && t.v[0].z + t.v[1].z + t.v[2].z > 1.5 * w.length) {
        mesh_hidden_[k][i] = true;
        continue;
      }
      const glm::vec3 a(t.v[0].x, t.v[0].y, t.v[0].z), b(t.v[1].x, t.v[1].y, t.v[1].z), c(t.v[2].x, t.v[2].y, t.v[2].z);
      const glm::vec3 n = glm::cross(b - a, c - a);
      if (glm::length(n) <= 0) continue;
      const glm::vec3 nrm = glm::normalize(n);
      into.insert(into.end(), {{a, nrm}, {b, nrm}, {c, nrm}});
    }
  }
  lifters_.upload(bars);
  still_.upload(still);
}

// The lit shader with the mill's parts turned to the mill angle.
void MillRenderer::use_turning(const glm::mat4& view, const glm::mat4& projection, bool orthographic,
                               double mill_angle) {
  shader_.use();
  shader_.set("view", view);
  shader_.set("projection", projection);
  shader_.set("orthographic", orthographic ? 1 : 0);
  shader_.set("lit", 1);
  shader_.set("model", glm::rotate(glm::mat4(1.0f), static_cast<float>(mill_angle), glm::vec3(0, 0, 1)));
}

void MillRenderer::draw(const glm::mat4& view, const glm::mat4& projection, bool orthographic, double mill_angle,
                        bool show_shell, bool liner_coloured) {
  use_turning(view, projection, orthographic, mill_angle);
  shader_.set("vertex_colour", 0);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  if (show_shell) {
    shader_.set("base_colour", glm::vec4(0.55f, 0.56f, 0.58f, 1.0f));
    shell_.draw();
  }
  if (end_plates_) {  // a slice is open at both ends
    shader_.set("base_colour", glm::vec4(0.24f, 0.25f, 0.27f, 1.0f));
    plate_.draw();
  }
  shader_.set("base_colour", glm::vec4(0.40f, 0.41f, 0.43f, 1.0f));
  rims_.draw();
  glDisable(GL_CULL_FACE);
  shader_.set("base_colour", glm::vec4(0.62f, 0.63f, 0.65f, 1.0f));
  lifters_.draw();
  if (still_.count > 0) {  // in the lab frame, then back to the mill's
    use_turning(view, projection, orthographic, 0.0);
    still_.draw();
    use_turning(view, projection, orthographic, mill_angle);
  }
  if (liner_coloured) {
    // Over the plain parts, pulled forward in depth.
    shader_.set("vertex_colour", 1);
    shader_.set("base_colour", glm::vec4(1, 1, 1, 1));
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(-1.0f, -2.0f);
    if (show_shell) {
      glEnable(GL_CULL_FACE);
      glCullFace(GL_BACK);
      liner_shell_.draw();
      glDisable(GL_CULL_FACE);
    }
    liner_parts_.draw();
    if (!liner_still_.vertices.empty()) {
      use_turning(view, projection, orthographic, 0.0);
      shader_.set("vertex_colour", 1);
      shader_.set("base_colour", glm::vec4(1, 1, 1, 1));
      liner_still_.draw();
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    shader_.set("vertex_colour", 0);
  }
}

void MillRenderer::draw_near_shell(const glm::mat4& view, const glm::mat4& projection, bool orthographic,
                                   double mill_angle) {
  use_turning(view, projection, orthographic, mill_angle);
  shader_.set("vertex_colour", 0);
  shader_.set("base_colour", glm::vec4(0.70f, 0.72f, 0.76f, 0.22f));
  glEnable(GL_CULL_FACE);
  glCullFace(GL_FRONT);  // the outside of the near half
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glDepthMask(GL_FALSE);
  shell_.draw();
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  glCullFace(GL_BACK);
  glDisable(GL_CULL_FACE);
}

void MillRenderer::draw_marks(const glm::mat4& view, const glm::mat4& projection, const MillMarks& marks) {
  if (!marks.show) return;
  // Wedges at the front end, drawn over everything: toe and shoulder from
  // 1.07 R to 1.22 R, the impact point outside them (1.24 R to 1.36 R), so
  // that an impact point on the toe hides neither.
  std::vector<Vertex> quads;
  const float R = radius_, z = length_;
  const glm::vec3 n{0, 0, 1};
  auto wedge = [&](float deg, float from = 1.07f, float to = 1.22f) {
    const float a = deg * kPi / 180.0f, h = 0.9f * kPi / 180.0f;
    auto at = [&](float r, float b) { return glm::vec3(r * std::cos(b), r * std::sin(b), z); };
    const Vertex i0{at(from * R, a - h), n}, i1{at(from * R, a + h), n}, o0{at(to * R, a - h), n},
        o1{at(to * R, a + h), n};
    quads.insert(quads.end(), {i0, o0, o1, i0, o1, i1});
  };
  shader_.use();
  shader_.set("view", view);
  shader_.set("projection", projection);
  shader_.set("model", glm::mat4(1.0f));
  shader_.set("lit", 0);
  shader_.set("vertex_colour", 0);
  glDisable(GL_DEPTH_TEST);
  wedge(marks.toe_deg);
  marks_.upload(quads);
  shader_.set("base_colour", glm::vec4(0.92f, 0.24f, 0.24f, 1.0f));  // toe: red, as in charge.png
  marks_.draw();
  quads.clear();
  wedge(marks.shoulder_deg);
  marks_.upload(quads);
  shader_.set("base_colour", glm::vec4(0.96f, 0.55f, 0.12f, 1.0f));  // shoulder: orange
  marks_.draw();
  if (marks.impact) {
    quads.clear();
    wedge(marks.impact_deg, 1.24f, 1.36f);
    marks_.upload(quads);
    shader_.set("base_colour", glm::vec4(1.0f, 0.2f, 0.85f, 1.0f));  // impact point: magenta
    marks_.draw();
  }
  glEnable(GL_DEPTH_TEST);
}

}  // namespace mc::viewer
