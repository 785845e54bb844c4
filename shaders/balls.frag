#version 330 core
// The sphere itself: the ray through this pixel against the ball, the depth of
// the hit written so that balls cut into each other and into the mill
// correctly; Lambert and Blinn–Phong lighting from a light over the viewer's
// left shoulder.
in vec3 v_centre;
in float v_radius;
in vec3 v_point;
in vec3 v_colour;

uniform mat4 projection;
uniform int orthographic;

out vec4 colour;

void main() {
  vec3 origin = orthographic == 1 ? vec3(v_point.xy, 0.0) : vec3(0.0);
  vec3 dir = orthographic == 1 ? vec3(0.0, 0.0, -1.0) : normalize(v_point);
  vec3 oc = origin - v_centre;
  float b = dot(dir, oc);
  float disc = b * b - (dot(oc, oc) - v_radius * v_radius);
  if (disc < 0.0) discard;
  vec3 hit = origin + (-b - sqrt(disc)) * dir;
  vec3 n = (hit - v_centre) / v_radius;

  vec4 clip = projection * vec4(hit, 1.0);
  gl_FragDepth = 0.5 * (clip.z / clip.w) + 0.5;

  const vec3 light = normalize(vec3(-0.4, 0.6, 0.7));
  vec3 h = normalize(light - dir);
  float diffuse = max(dot(n, light), 0.0);
  float specular = pow(max(dot(n, h), 0.0), 48.0);
  colour = vec4(v_colour * (0.30 + 0.70 * diffuse) + 0.30 * specular, 1.0);
}
