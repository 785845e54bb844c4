// millcharge check: a case validated, and its derived values printed.
#include "app/commands.h"
#include "app/prepare.h"
#include "core/clump.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <numeric>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "compute/context.h"
#include "core/charge_edit.h"
#include "core/lifters.h"
#include "core/liner.h"
#include "core/mill_case.h"
#include "core/wall_mesh.h"
#include "core/morrell.h"
#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/checkpoint.h"
#include "io/energy_out.h"
#include "io/png_plot.h"
#include "life/bar_twin.h"
#include "io/stl.h"
#include "io/vtk.h"
#include "sim/batch_means.h"
#include "sim/energy_report.h"
#include "sim/mill_run.h"
#include "sim/solver.h"
#include "viewer/viewer.h"

namespace mc::app {

namespace fs = std::filesystem;

int cmd_check(const CaseOptions& o) {
  const Prepared p = prepare(o);
  const MillCase& c = p.c;
  const MillDerived& d = p.d;
  std::printf("case            %s%s%s\n", p.path.string().c_str(), c.title.empty() ? "" : ": ", c.title.c_str());
  std::printf("mill            D %.4g m x L %.4g m%s, %d lifter rows, liner \"%s\"\n", c.diameter, c.length,
              c.periodic ? " (a periodic slice)" : "", c.lifter_rows, c.liner.c_str());
  if (c.periodic)
    std::printf("ends            periodic (mill.ends): no end plates, a ball leaving one end enters at the other; "
                "shortest slice %.4g m (%.0f largest balls); power, torque, spectra and wear also per metre\n",
                d.shortest_slice, kSliceDiameters);
  else if (c.ends.cones())
    std::printf("ends            cone heads (mill.ends = \"cones\") beyond the belly's z = 0 and %.4g m\n", c.length);
  else
    std::printf("ends            end plates at z = 0 and %.4g m (mill.ends = \"periodic\" would make a slice: at "
                "least %.4g m)\n",
                c.length, d.shortest_slice);
  std::printf("critical speed  %.2f rpm  (42.3/sqrt(D - d), d = largest ball %.4g mm)\n", d.critical_rpm,
              1000 * d.largest_ball_diameter);
  std::printf("speed           %.2f rpm = %.1f %% of critical  (%.4g rad/s, %.4g s per revolution, tip %.3g m/s)\n",
              d.speed_rpm, 100 * d.speed_fraction, d.omega, d.revolution_s, d.tip_speed);
  std::printf("volume          %.4g m^3 inside the shell, lifters excluded (lifters %.3g m^3)\n", d.mill_volume,
              d.lifter_volume);
  std::printf("charge          J %.3f requested: %s balls, %s; J %.4f from the whole ball counts (the balls' bulk "
              "volume at the case's porosity over the free volume)\n",
              c.filling, thousands(d.n_balls).c_str(), kilograms(d.charge_mass).c_str(), d.filling_from_counts);
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    const SizeClass& s = c.sizes[k];
    char dia[64];
    if (s.diameter_min == s.diameter_max) std::snprintf(dia, sizeof dia, "%.4g mm", 1000 * s.diameter_min);
    else std::snprintf(dia, sizeof dia, "%.4g-%.4g mm", 1000 * s.diameter_min, 1000 * s.diameter_max);
    std::printf("  size %-9zu %s %s: %s %s, %s fraction %.3f\n", k, dia, s.material.c_str(),
                thousands(d.class_counts[k]).c_str(), s.shape.empty() ? "balls" : "clumps", c.number_fractions ? "number" : "mass",
                s.fraction);
    if (!s.shape.empty()) {
      // The clump at a volume-equivalent diameter of 1: its spheres, its
      // extent along its principal axes and its moments over m d².
      const ClumpShape u = normalised_shape(size_class_shape(c, s.shape, "charge.size"), 1.0);
      const ClumpMassProperties mp = clump_mass_properties(u);
      double ext[3] = {0, 0, 0};
      for (const ClumpSphere& q : u.spheres) {
        ext[0] = std::max(ext[0], std::fabs(q.centre.x) + q.radius);
        ext[1] = std::max(ext[1], std::fabs(q.centre.y) + q.radius);
        ext[2] = std::max(ext[2], std::fabs(q.centre.z) + q.radius);
      }
      std::printf("    shape \"%s\": a rigid body of %zu spheres, %.3g x %.3g x %.3g d along its principal axes, "
                  "moments %.4g, %.4g, %.4g m d^2 (a ball: 0.1)\n",
                  s.shape.c_str(), u.spheres.size(), 2 * ext[0], 2 * ext[1], 2 * ext[2], mp.principal.x / mp.volume,
                  mp.principal.y / mp.volume, mp.principal.z / mp.volume);
    }
  }
  if (c.ends.cones())
    std::printf("cones           %.4g deg from the end plane, trunnion %.4g m: each head %.4g m deep (the mill "
                "%.4g m long on the axis)\n",
                c.ends.cone_angle_deg, c.ends.trunnion_diameter, cone_depth(c.ends, 0.5 * c.diameter),
                c.length + 2 * cone_depth(c.ends, 0.5 * c.diameter));
  if (!c.meshes.empty() || c.ends.cones() || c.ends.lifter_rows > 0) {
    const std::vector<WallMesh> meshes = place_meshes(c);
    const MeshTopology topo = mesh_topology(meshes);
    for (std::size_t k = 0; k < meshes.size(); ++k) {
      const WallMesh& m = meshes[k];
      const char* part = m.part == MeshPart::shell ? "shell" : m.part == MeshPart::ends ? "ends" : "lifters";
      char vol[96];
      if (m.volume > 0) std::snprintf(vol, sizeof vol, "closed, %.4g m^3 taken from the mill", m.volume);
      else std::snprintf(vol, sizeof vol, "open (its volume is not taken from the mill)");
      const std::string name = k < c.meshes.size() ? c.meshes[k].path : m.name;
      std::printf("mesh %-10zu %s: %s triangles, %s, %s, part \"%s\", material \"%s\"\n", k, name.c_str(),
                  thousands(static_cast<long>(m.triangles.size())).c_str(), vol,
                  m.turning ? "turning with the mill" : "standing still", part, m.material.name.c_str());
    }
    std::printf("meshes          %s triangles, %d edges, %d vertices in %d smooth surfaces (cl/mesh.h)\n",
                thousands(topo.n_triangles).c_str(), topo.n_edges, topo.n_vertices, topo.n_patches);
  }
  if (!o.write_lifters.empty()) {
    // The parametric bars cut at the shell, as an STL: a start for CAD, or a
    // [[walls.mesh]] that stands for them.
    const Scene w = build_walls(c, d);
    if (w.walls.lifters.empty())
      throw std::invalid_argument("--write-lifters: the case has no lifter bars (lifters.rows = 0)");
    const auto tris = mc::life::bar_twin_triangles(c, d, o.lifter_mesh_mm * 1e-3);
    std::error_code ec;
    const std::filesystem::path parent = std::filesystem::path(o.write_lifters).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    io::write_file_atomic(o.write_lifters, io::stl_binary(tris, c.name + " lifters, m"));
    std::printf("lifters         %d bars as %s triangles (binary STL, metres, mill frame at t = 0): %s\n",
                c.lifter_rows, thousands(static_cast<long>(tris.size())).c_str(), o.write_lifters.c_str());
  }
  std::ostringstream stiffness;
  if (c.law == ContactLaw::linear) stiffness << ", kn " << c.contact.kn << " N/m";
  std::printf("contact         %s, e %.3g, friction %.3g, rolling %.3g%s (defaults; %zu pair overrides)\n",
              c.law == ContactLaw::linear ? "linear spring-dashpot" : "Hertz-Mindlin", c.contact.restitution,
              c.contact.mu_slide, c.contact.mu_roll, stiffness.str().c_str(), c.pairs.size());
  std::printf("contact time    %.4g s, shortest ball-ball contact%s\n", d.contact_time,
              c.law == ContactLaw::hertz ? " (impact at the tip speed)" : "");
  std::printf("dt              %.4g s (%s; %.1f steps per contact)\n", d.dt,
              d.dt_auto ? "auto" : "from the case", d.contact_time / d.dt);
  const long steps = std::lround(d.turn_limit_s / d.dt);
  char turn[256];
  if (c.duration_auto)
    std::snprintf(turn, sizeof turn,
                  "turn auto: until the power's standard error is %.3g %% of its mean, at most %.4g s = %.3g "
                  "revolutions (%s steps)",
                  100 * c.tolerance, d.turn_limit_s, d.turn_limit_s / d.revolution_s, thousands(steps).c_str());
  else
    std::snprintf(turn, sizeof turn, "turn %.4g s = %.3g revolutions (%s steps)", c.duration,
                  c.duration / d.revolution_s, thousands(steps).c_str());
  std::printf("run             settle %s (damping %.3g 1/s), %s, warm-up %.4g s, %s\n",
              c.settle < 0 ? "auto" : (std::to_string(c.settle) + " s").c_str(), d.settle_damping, turn, c.warmup,
              c.precision == Precision::double_ ? "double" : "float");
  const MorrellResult m = morrell_c_model(morrell_input(c, d));
  std::printf("morrell c-model power %s (k %.2f x net %s), toe %.1f deg, shoulder %.1f deg\n",
              watts(m.charge_power_W).c_str(), kMorrellK, watts(m.net_power_W).c_str(), m.toe_deg, m.shoulder_deg);
  if (p.scene.bodies.empty())
    std::printf("packing         %s balls placed without overlaps\n", thousands(static_cast<long>(p.scene.balls.size())).c_str());
  else
    std::printf("packing         %s clumps (%s spheres) and %s balls placed without overlaps\n",
                thousands(static_cast<long>(p.scene.bodies.size())).c_str(),
                thousands(static_cast<long>(p.scene.balls.size()) - p.scene.bodies.front().first).c_str(),
                thousands(static_cast<long>(p.scene.bodies.front().first)).c_str());
  return 0;
}

}  // namespace mc::app
