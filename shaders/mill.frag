#version 330 core
in vec3 v_normal;
in vec3 v_point;
in vec3 v_colour;

uniform vec4 base_colour;  // alpha < 1: translucent
uniform int lit;           // 0: flat colour (marks)
uniform int orthographic;
uniform int vertex_colour;  // 1: the vertices' colours (the liner's sums), else base_colour

out vec4 colour;

void main() {
  if (lit == 0) {
    colour = vertex_colour == 1 ? vec4(v_colour, base_colour.a) : base_colour;
    return;
  }
  vec4 base = vertex_colour == 1 ? vec4(v_colour, base_colour.a) : base_colour;
  vec3 n = normalize(v_normal);
  vec3 to_eye = orthographic == 1 ? vec3(0.0, 0.0, 1.0) : normalize(-v_point);
  if (dot(n, to_eye) < 0.0) n = -n;  // both sides lit
  const vec3 light = normalize(vec3(-0.4, 0.6, 0.7));
  float diffuse = max(dot(n, light), 0.0);
  float specular = pow(max(dot(n, normalize(light + to_eye)), 0.0), 24.0);
  colour = vec4(base.rgb * (0.35 + 0.65 * diffuse) + 0.12 * specular, base.a);
}
