#version 330 core
// One ball per instance (cl/instances.h): a square facing the eye that
// covers the sphere's outline; balls.frag traces the sphere inside it.
layout(location = 0) in vec2 corner;         // (±1, ±1)
layout(location = 1) in vec4 centre_radius;  // m, lab frame
layout(location = 2) in vec4 look;           // speed m/s, material, dissipation W, id

uniform mat4 view;
uniform mat4 projection;
uniform int orthographic;
uniform int colour_mode;     // 0 speed, 1 size, 2 material, 3 impact (dissipation power)
uniform vec2 colour_range;   // value at the cold and the hot end (log10 W for impact)
uniform vec3 slab;           // x > 0.5: draw only balls with slab.y <= z <= slab.z

out vec3 v_centre;  // view space
out float v_radius;
out vec3 v_point;   // view space, on the square
out vec3 v_colour;

vec3 ramp(float t) {  // blue, cyan, green, yellow, red: saturated all along
  const vec3 c0 = vec3(0.15, 0.30, 0.95), c1 = vec3(0.05, 0.75, 0.90), c2 = vec3(0.25, 0.85, 0.25),
             c3 = vec3(0.98, 0.80, 0.10), c4 = vec3(0.90, 0.15, 0.10);
  t = clamp(t, 0.0, 1.0) * 4.0;
  if (t < 1.0) return mix(c0, c1, t);
  if (t < 2.0) return mix(c1, c2, t - 1.0);
  if (t < 3.0) return mix(c2, c3, t - 2.0);
  return mix(c3, c4, t - 3.0);
}

vec3 material_colour(int m) {
  const vec3 palette[6] = vec3[6](vec3(0.95, 0.55, 0.15), vec3(0.25, 0.50, 0.95), vec3(0.30, 0.80, 0.35),
                                  vec3(0.85, 0.30, 0.75), vec3(0.95, 0.85, 0.20), vec3(0.20, 0.80, 0.80));
  return palette[m % 6];
}

void main() {
  float r = centre_radius.w;
  if (slab.x > 0.5 && (centre_radius.z < slab.y || centre_radius.z > slab.z)) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: dropped
    return;
  }
  vec3 c = (view * vec4(centre_radius.xyz, 1.0)).xyz;
  vec3 right, up;
  float half_size = r;
  if (orthographic == 1) {
    right = vec3(1.0, 0.0, 0.0);
    up = vec3(0.0, 1.0, 0.0);
  } else {
    // Perpendicular to the line of sight to the centre; the cone of rays
    // that graze the sphere cuts that plane in a circle of r·d/sqrt(d² − r²).
    vec3 dir = normalize(c);
    right = normalize(abs(dir.y) < 0.99 ? cross(dir, vec3(0.0, 1.0, 0.0)) : cross(dir, vec3(1.0, 0.0, 0.0)));
    up = cross(right, dir);
    float d = length(c);
    half_size = r * d / sqrt(max(d * d - r * r, 1e-12));
  }
  v_point = c + half_size * (corner.x * right + corner.y * up);
  v_centre = c;
  v_radius = r;
  gl_Position = projection * vec4(v_point, 1.0);

  float value;
  if (colour_mode == 0) value = look.x;
  else if (colour_mode == 1) value = r;
  else value = log(max(look.z, 1e-9)) / log(10.0);
  float span = max(colour_range.y - colour_range.x, 1e-12);
  v_colour = colour_mode == 2 ? material_colour(int(look.y + 0.5)) : ramp((value - colour_range.x) / span);
}
