#version 330 core
// The mill's surfaces (shell, end plate, lifters, rims) and flat marks.
layout(location = 0) in vec3 position;  // m, mill frame (marks: lab frame)
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 colour_in;  // the liner's elements (vertex_colour)

uniform mat4 model;  // the mill's turn about +z
uniform mat4 view;
uniform mat4 projection;

out vec3 v_normal;  // view space
out vec3 v_point;
out vec3 v_colour;

void main() {
  vec4 p = view * model * vec4(position, 1.0);
  v_point = p.xyz;
  v_colour = colour_in;
  v_normal = mat3(view) * mat3(model) * normal;
  gl_Position = projection * p;
}
