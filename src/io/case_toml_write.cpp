// The resolved case written back as TOML (io/case_file.h case_to_toml): every
// key, defaults and --set applied, as a run folder's case.toml holds it.
#include <toml++/toml.h>

#include <sstream>
#include <string>

#include "io/case_file.h"

namespace mc::io {

std::string case_to_toml(const MillCase& c) {
  auto interaction = [](const Interaction& in, toml::table t) {
    t.insert("restitution", in.restitution);
    t.insert("friction", in.mu_slide);
    t.insert("rolling_friction", in.mu_roll);
    t.insert("stiffness", in.kn);
    t.insert("tangential_stiffness_ratio", in.kt_over_kn);
    return t;
  };
  toml::table root;
  if (!c.title.empty()) root.insert("title", c.title);
  toml::table mill{{"diameter", c.diameter},
                   {"length", c.length},
                   {"ends", c.periodic ? "periodic" : c.ends.cones() ? "cones" : "plates"},
                   {"liner", c.liner}};
  if (c.ends.cones()) {
    mill.insert("cone_angle", c.ends.cone_angle_deg);
    mill.insert("trunnion_diameter", c.ends.trunnion_diameter);
  }
  if (c.speed_rpm > 0) mill.insert("speed_rpm", c.speed_rpm);
  else mill.insert("speed_fraction", c.speed_fraction);
  root.insert("mill", mill);
  toml::array profiles;
  for (const LifterProfile& p : c.lifter_pattern) {
    if (p.polygon()) {
      toml::array points;
      for (const Vec2& v : p.points) points.push_back(toml::array{v.x, v.y});
      profiles.push_back(toml::table{{"points", points}});
    } else {
      profiles.push_back(toml::table{{"height", p.height}, {"top_width", p.top_width}, {"face_angle", p.face_angle_deg}});
    }
  }
  root.insert("lifters", toml::table{{"rows", c.lifter_rows}, {"first_angle", c.lifter_first_angle_deg}, {"profile", profiles}});
  if (c.ends.lifter_rows > 0)
    root.insert("end_lifters", toml::table{{"rows", c.ends.lifter_rows},
                                          {"height", c.ends.lifter_height},
                                          {"width", c.ends.lifter_width},
                                          {"inner_diameter", c.ends.lifter_inner_diameter}});
  if (!c.meshes.empty()) {
    toml::array meshes;
    for (const MeshSpec& m : c.meshes) {
      toml::table t{{"file", std::filesystem::absolute(m.path).string()},
                    {"units", m.units},
                    {"turning", m.turning},
                    {"part", m.part == MeshPart::shell ? "shell" : m.part == MeshPart::ends ? "ends" : "lifters"},
                    {"offset", toml::array{m.offset.x, m.offset.y, m.offset.z}},
                    {"angle", m.angle_deg},
                    {"flip", m.flip}};
      if (!m.material.empty()) t.insert("material", m.material);
      meshes.push_back(t);
    }
    root.insert("walls", toml::table{{"mesh", meshes}});
  }
  const LinerGrid& g = c.liner_grid;
  toml::table liner{{"shell_bins", g.shell_bins},
                    {"smooth_shell_bins", g.smooth_shell_bins},
                    {"axial_bins", g.axial_bins},
                    {"plate_rings", g.plate_rings},
                    {"plate_sectors", g.plate_sectors}};
  if (!c.plate_depth[0].empty() || !c.plate_depth[1].empty()) {
    toml::array plates;
    for (const auto& depth : c.plate_depth) {
      toml::array row;
      for (double d : depth) row.push_back(d * 1e3);
      plates.push_back(row);
    }
    liner.insert("plate_depth_mm", plates);
  }
  root.insert("liner", liner);
  toml::array sizes;
  for (const SizeClass& s : c.sizes) {
    toml::table t{{"material", s.material}, {"fraction", s.fraction}};
    if (!s.shape.empty()) t.insert("shape", s.shape);
    if (s.diameter_min == s.diameter_max) {
      t.insert("diameter", s.diameter_min);
    } else {
      t.insert("diameter_min", s.diameter_min);
      t.insert("diameter_max", s.diameter_max);
    }
    sizes.push_back(t);
  }
  toml::table charge{{"filling", c.filling},
                     {"porosity", c.porosity},
                     {"fractions", c.number_fractions ? "number" : "mass"},
                     {"seed", static_cast<int64_t>(c.seed)},
                     {"size", sizes}};
  if (!c.shapes.empty()) {
    toml::array shapes;
    for (const ClumpShape& sh : c.shapes) {
      toml::array spheres;
      for (const ClumpSphere& q : sh.spheres)
        spheres.push_back(toml::array{q.centre.x, q.centre.y, q.centre.z, q.radius});
      shapes.push_back(toml::table{{"name", sh.name}, {"spheres", spheres}});
    }
    charge.insert("shape", shapes);
  }
  root.insert("charge", charge);
  toml::table materials;
  for (const Material& m : c.materials) {
    toml::table t{{"density", m.density},
                  {"youngs_modulus", m.youngs_modulus},
                  {"poisson_ratio", m.poisson_ratio},
                  {"wear_coefficient", m.wear_coefficient}};
    if (m.impact_wear_coefficient > 0) t.insert("impact_wear_coefficient", m.impact_wear_coefficient);
    if (m.impact_wear_threshold_speed > 0) t.insert("impact_wear_threshold_speed", m.impact_wear_threshold_speed);
    materials.insert(m.name, std::move(t));
  }
  root.insert("materials", materials);
  toml::table contact = interaction(c.contact, toml::table{{"law", c.law == ContactLaw::hertz ? "hertz" : "linear"}});
  toml::array pairs;
  for (const PairOverride& p : c.pairs)
    pairs.push_back(interaction(p.interaction, toml::table{{"materials", toml::array{p.a, p.b}}}));
  if (!pairs.empty()) contact.insert("pair", pairs);
  root.insert("contact", contact);
  toml::table run{{"tolerance", c.tolerance},
                  {"warmup", c.warmup},
                  {"steps_per_contact", c.steps_per_contact},
                  {"output_interval", c.output_interval},
                  {"snapshot_interval", c.snapshot_interval},
                  {"checkpoint_interval", c.checkpoint_interval},
                  {"precision", c.precision == Precision::double_ ? "double" : "float"}};
  if (c.duration_auto) run.insert("duration", "auto");
  else run.insert("duration", c.duration);
  if (c.max_duration >= 0) run.insert("max_duration", c.max_duration);
  else run.insert("max_duration", "auto");
  if (c.settle >= 0) run.insert("settle", c.settle);
  else run.insert("settle", "auto");
  if (c.settle_damping >= 0) run.insert("settle_damping", c.settle_damping);
  else run.insert("settle_damping", "auto");
  if (c.dt > 0) run.insert("dt", c.dt);
  else run.insert("dt", "auto");
  root.insert("run", run);
  std::ostringstream out;
  out << "# The resolved case of this run (every key, defaults and --set applied).\n" << root << "\n";
  return out.str();
}

}  // namespace mc::io
