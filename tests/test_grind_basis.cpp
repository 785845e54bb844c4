// Which energy the spectrum model reads (docs/grinding.md): the ore's
// rates.energy_basis, what a fitted ore records, and the severity spectrum
// of a Bond-mill run read with each collision's own R*.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "app/commands.h"
#include "app/grind.h"
#include "grind/circuit.h"
#include "io/ore_file.h"
#include "io/run_folder.h"

using namespace mc::grind;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) {
  return fs::temp_directory_path() / ("millcharge_test_basis_" + std::to_string(::getpid()) + "_" + name);
}

std::string example_ore() {
  std::ifstream in(fs::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The example ore with `extra` after its [rates] keys (and `tail` at the end).
fs::path ore_with(const std::string& name, const std::string& extra, const std::string& tail = "") {
  std::string s = example_ore();
  const std::string key = "efficiency = 1.0";
  const auto at = s.find(key);
  REQUIRE(at != std::string::npos);
  s.insert(at + key.size(), "\n" + extra);
  const fs::path p = temp(name + ".toml");
  std::ofstream(p) << s << "\n" << tail;
  return p;
}

const char* kFitted =
    "[fitted]\ncontact_law = \"linear\"\nrestitution = 0.4\nfriction = 0.4\nstiffness_N_m = 1e6\n";

}  // namespace

TEST_CASE("the ore says which energy its fracture parameters were measured on", "[grind][basis]") {
  const Ore plain = mc::io::read_ore(ore_with("plain", ""));
  CHECK(plain.energy_basis == EnergyBasis::impact);
  CHECK_FALSE(plain.energy_basis_given);
  CHECK(mc::io::read_ore(ore_with("loss", "energy_basis = \"loss\"")).energy_basis == EnergyBasis::loss);
  CHECK(mc::io::read_ore(ore_with("impact", "energy_basis = \"impact\"")).energy_basis == EnergyBasis::impact);
  CHECK(mc::io::read_ore(ore_with("one", "energy_basis = \"loss_one_radius\"")).energy_basis ==
        EnergyBasis::loss_one_radius);
  CHECK_THROWS_WITH(mc::io::read_ore(ore_with("bad", "energy_basis = \"kinetic\"")),
                    Catch::Contains("rates.energy_basis") && Catch::Contains("\"impact\""));
  CHECK_THROWS_WITH(mc::io::read_ore(ore_with("num", "energy_basis = 1")), Catch::Contains("rates.energy_basis"));
  // An ore fitted before the severity spectra: its [fitted] table has no
  // basis; it was fitted on the normal loss with one radius, and reads so.
  const Ore old = mc::io::read_ore(ore_with("old_fit", "", kFitted));
  CHECK(old.energy_basis == EnergyBasis::loss_one_radius);
  CHECK(old.fitted_under.energy_basis == "loss_one_radius");
  // A file that says one basis and records a fit on another reads (a new
  // fit replaces the record); grind refuses it where it makes products.
  const Ore clash = mc::io::read_ore(ore_with("old_fit_impact", "energy_basis = \"impact\"", kFitted));
  CHECK(clash.energy_basis == EnergyBasis::impact);
  CHECK(clash.energy_basis_given);
  const std::string fitted_impact = std::string(kFitted) + "energy_basis = \"impact\"\n";
  CHECK(mc::io::read_ore(ore_with("new_fit", "", fitted_impact)).energy_basis == EnergyBasis::impact);
  CHECK_THROWS_WITH(mc::io::read_ore(ore_with("bad_fit", "", std::string(kFitted) + "energy_basis = \"x\"\n")),
                    Catch::Contains("fitted.energy_basis"));
  // Written and read back, the basis and the record stay.
  for (const char* b : {"impact", "loss", "loss_one_radius"}) {
    const Ore o = mc::io::read_ore(ore_with(std::string("rt_") + b, std::string("energy_basis = \"") + b + "\"",
                                            std::string(kFitted) + "energy_basis = \"" + b + "\"\n"));
    const fs::path back = temp(std::string("back_") + b + ".toml");
    std::ofstream(back) << mc::io::ore_toml(o, "");
    const Ore again = mc::io::read_ore(back);
    CHECK(again.energy_basis == o.energy_basis);
    CHECK(again.fitted_under.energy_basis == b);
  }
  // Another rate model records no basis.
  std::string energy;
  {
    std::ifstream in(fs::path(MC_ASSET_DIR) / "ores" / "example_energy.toml");
    std::stringstream ss;
    ss << in.rdbuf();
    energy = ss.str() + "\n" + kFitted;
  }
  const fs::path ep = temp("energy_fitted.toml");
  std::ofstream(ep) << energy;
  CHECK(mc::io::read_ore(ep).fitted_under.energy_basis.empty());
}

TEST_CASE("grind reads the severity spectrum of the ore's basis, each bin with its collisions' own R*",
          "[grind][basis]") {
  const fs::path dir = temp("bond_run");
  fs::remove_all(dir);
  mc::app::RunOptions o;
  o.c.case_path = std::string(MC_ASSET_DIR) + "/cases/bond.toml";
  o.c.overrides = {"run.settle=0.05", "run.warmup=0.1", "run.output_interval=0.01", "run.snapshot_interval=0",
                   "run.checkpoint_interval=0"};
  o.c.duration = 0.5;
  o.out = dir.string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_run(o) == 0);
  const mc::io::Run impact = mc::io::read_run(dir, true, EnergyBasis::impact);
  const mc::io::Run loss = mc::io::read_run(dir, true, EnergyBasis::loss);
  nlohmann::json doc;
  std::ifstream(dir / "summary.json") >> doc;
  const double collisions = doc["spectra"]["total"]["collisions_per_s"].get<double>();
  // Every collision is in both, once (the bins without energy are left out
  // of the model: count those apart).
  double n_impact = 0, n_loss = 0, w_impact = 0, w_loss = 0;
  for (const SpectrumBin& b : impact.spectrum) n_impact += b.collisions_per_s, w_impact += b.collisions_per_s * b.energy_J;
  for (const SpectrumBin& b : loss.spectrum) n_loss += b.collisions_per_s, w_loss += b.collisions_per_s * b.energy_J;
  const double normal_W = doc["spectra"]["total"]["normal_W"].get<double>();
  const double impact_W = doc["spectra"]["total"]["impact_W"].get<double>();
  std::printf("Bond mill 0.4 s: %.0f collisions/s; impact spectrum %.0f of them, %.4g W (summary %.4g W); loss "
              "spectrum %.0f, %.4g W (normal loss %.4g W)\n",
              collisions, n_impact, w_impact, impact_W, n_loss, w_loss, normal_W);
  CHECK(n_impact <= collisions * (1 + 1e-9));
  CHECK(n_impact > 0.9 * collisions);
  CHECK(w_impact == Approx(impact_W).epsilon(1e-6));
  CHECK(w_loss == Approx(normal_W).epsilon(1e-6));
  // R* of the Bond charge (36.8, 29.7, 25.4, 19.1 and 15.5 mm balls): two
  // balls from r r'/(r + r') = 3.875 mm (two of the smallest) to 9.2 mm
  // (two of the largest), a ball on a wall its radius, 7.75 to 18.4 mm.
  // Each bin's mean lies in its pair's range, and the ball-ball bins spread
  // across it (one radius for all would put them on one value).
  std::ifstream in(dir / "spectra.csv");
  std::string line;
  std::getline(in, line);
  double lo_bb = 1, hi_bb = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    REQUIRE(f.size() == 21);
    const double n = std::stod(f[15]), r = std::stod(f[17]);
    if (n <= 0) continue;
    const bool wall = f[0] != "steel-steel";
    INFO(line);
    // A ball on a wall (the shell's concave cylinder too) meets it with
    // its own radius.
    if (wall) {
      CHECK(r >= 0.00775 * (1 - 1e-6));
      CHECK(r <= 0.0184 * (1 + 1e-6));
    } else {
      CHECK(r >= 0.003875 * (1 - 1e-6));
      CHECK(r <= 0.0092 * (1 + 1e-6));
      lo_bb = std::min(lo_bb, r), hi_bb = std::max(hi_bb, r);
    }
  }
  std::printf("ball-ball bins' mean R* from %.3f to %.3f mm\n", 1e3 * lo_bb, 1e3 * hi_bb);
  CHECK(hi_bb - lo_bb > 0.001);
  // The rate of the top class (2.8 mm) by hand from spectra.csv's columns
  // of each basis: sum over pairs and bins of N m_cap(d, R*) P(E / m_cap),
  // E and R* the bin's means; against grind's. And what one radius for
  // every collision (half the charge's number-mean radius between balls,
  // the radius on walls) made of it.
  const Ore ore = mc::io::read_ore(fs::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml");
  const double d = ore.sizes.mid_m(0);
  for (const EnergyBasis basis : {EnergyBasis::impact, EnergyBasis::loss}) {
    const std::string kind = basis_name(basis);
    std::ifstream csv(dir / "spectra.csv");
    std::getline(csv, line);
    std::vector<std::string> head;
    {
      std::stringstream ss(line);
      for (std::string x; std::getline(ss, x, ',');) head.push_back(x);
    }
    auto col = [&](const std::string& name) {
      const auto it = std::find(head.begin(), head.end(), name);
      REQUIRE(it != head.end());
      return static_cast<std::size_t>(it - head.begin());
    };
    const std::size_t cn = col(kind + "_collisions_per_s"), cw = col(kind + "_W"), cr = col(kind + "_r_eff_m");
    const std::size_t cn1 = col("normal_spectrum_collisions_per_s"), cw1 = col("normal_spectrum_W");
    double by_hand = 0, one_radius = 0;
    while (std::getline(csv, line)) {
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      const double n = std::stod(f[cn]), w = std::stod(f[cw]), r = std::stod(f[cr]);
      if (n > 0 && w > 0) {
        const double m = captured_mass(d, r, ore.density, ore.packing);
        by_hand += n * m * ore.fracture.broken(w / n / m, d);
      }
      const double n1 = std::stod(f[cn1]), w1 = std::stod(f[cw1]);
      if (basis == EnergyBasis::loss && n1 > 0 && w1 > 0) {
        const double r1 = f[0] == "steel-steel" ? 0.5 * loss.ball_radius_m : loss.ball_radius_m;
        const double m = captured_mass(d, r1, ore.density, ore.packing);
        one_radius += n1 * m * ore.fracture.broken(w1 / n1 / m, d);
      }
    }
    const mc::io::Run& run = basis == EnergyBasis::impact ? impact : loss;
    const MillRates rates = mill_rates(ore, run.spectrum, run.power_W, 1.0);
    if (basis == EnergyBasis::loss) {
      // The legacy reading gives what one radius for all gives by hand.
      const mc::io::Run legacy = mc::io::read_run(dir, true, EnergyBasis::loss_one_radius);
      const MillRates lr = mill_rates(ore, legacy.spectrum, legacy.power_W, 1.0);
      CHECK(lr.S_per_min[0] == Approx(60 * one_radius).epsilon(1e-9));
    }
    std::printf("S(%.2f mm) on the %s: %.6g /min by grind, %.6g /min by hand", 1e3 * d, kind.c_str(),
                rates.S_per_min[0], 60 * by_hand);
    if (basis == EnergyBasis::loss)
      std::printf("; one radius for all on the normal spectrum %.6g /min (%.3f of it)", 60 * one_radius,
                  one_radius / by_hand);
    std::printf("\n");
    INFO(kind);
    CHECK(rates.S_per_min[0] == Approx(60 * by_hand).epsilon(1e-6));
  }
  // End to end: grind with each basis writes the rates of that basis, and
  // refuses an ore that says one basis and records a fit on another.
  for (const char* b : {"impact", "loss", "loss_one_radius"}) {
    mc::app::GrindOptions g;
    g.run_dir = dir.string();
    g.ore = ore_with(std::string("e2e_") + b, std::string("energy_basis = \"") + b + "\"").string();
    g.out = temp(std::string("grind_") + b).string();
    g.times_min = {1};
    g.quiet = true;
    REQUIRE(mc::app::cmd_grind(g) == 0);
    std::ifstream rc(fs::path(g.out) / "rates.csv");
    std::getline(rc, line);
    std::getline(rc, line);  // class 0
    const double s0 = std::stod(line.substr(line.rfind(',', line.rfind(',') - 1) + 1));
    Ore ob = ore;
    EnergyBasis eb = EnergyBasis::impact;
    REQUIRE(basis_of(b, &eb));
    const mc::io::Run rb = mc::io::read_run(dir, true, eb);
    const double holdup = mill_holdup_kg(ob, rb.porosity, rb.filling, rb.mill_volume);
    INFO(b);
    CHECK(s0 == Approx(mill_rates(ob, rb.spectrum, rb.power_W, holdup).S_per_min[0]).epsilon(1e-6));
  }
  {
    mc::app::GrindOptions g;
    g.run_dir = dir.string();
    g.ore = ore_with("clash", "energy_basis = \"impact\"", kFitted).string();
    g.out = temp("grind_clash").string();
    g.times_min = {1};
    g.quiet = true;
    CHECK_THROWS_WITH(mc::app::cmd_grind(g), Catch::Contains("rates.energy_basis is \"impact\"") &&
                                                 Catch::Contains("fitted on \"loss_one_radius\""));
    CHECK(!fs::exists(g.out));
    // Fitted again on the impact (a work index), the ore records the new
    // basis and grinds without the clash.
    g.out = temp("refit").string();
    g.times_min.clear();
    g.bond_p1_um = 150;
    g.fit_wi_kWh_t = 40;  // above the 29.7 kWh/t that eta 1 gives in this short run
    REQUIRE(mc::app::cmd_grind(g) == 0);
    const Ore refit = mc::io::read_ore(fs::path(g.out) / "ore_fitted.toml");
    CHECK(refit.energy_basis == EnergyBasis::impact);
    CHECK(refit.fitted_under.energy_basis == "impact");
  }
  fs::remove_all(dir);
}
