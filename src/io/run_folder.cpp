// Reads a finished run's folder for `millcharge grind` (run_folder.h).
#include "io/run_folder.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/mill_case.h"
#include "io/case_file.h"
#include "io/csv_read.h"
#include "io/json_read.h"

namespace mc::io {

namespace fs = std::filesystem;
using grind::SpectrumBin;

Run read_run(const fs::path& dir, bool need_spectrum, grind::EnergyBasis basis) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw std::invalid_argument(dir.string() + ": not a run folder");
  const fs::path sj = dir / "summary.json";
  const nlohmann::json doc = read_json_file(sj, "grind needs a finished run (millcharge run)");
  const JsonAt j(doc, sj.string());
  Run r;
  try {
    r.power_W = j["power_W"]["torque"].number();
    r.filling = j["filling"].number();
    if (j.has("title")) r.title = j["title"].text();
    if (j.has("speed_rpm")) r.speed_rpm = j["speed_rpm"].number();
    const JsonAt pw = j["power_W"];
    if (pw.has("dissipation") && pw["dissipation"].value().is_number()) r.dissipation_W = pw["dissipation"].number();
    if (pw.has("imbalance") && pw["imbalance"].value().is_number()) r.imbalance = pw["imbalance"].number();
    if (pw.has("energy_change") && pw["energy_change"].value().is_number())
      r.energy_change_W = pw["energy_change"].number();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + "; not a millcharge run's summary");
  }
  if (!(r.power_W > 0)) throw std::invalid_argument(sj.string() + ": power_W.torque is not > 0: the mill drew no power");
  const MillCase c = read_case(dir / "case.toml");
  const MillDerived d = derive(c);
  r.mill_volume = d.mill_volume;
  r.porosity = c.porosity;
  double n = 0, sum_r = 0;
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    n += d.class_counts[k];
    sum_r += d.class_counts[k] * 0.25 * (c.sizes[k].diameter_min + c.sizes[k].diameter_max);
  }
  r.ball_radius_m = n > 0 ? sum_r / n : 0;
  for (const SizeClass& sc : c.sizes) r.clumps = r.clumps || !sc.shape.empty();  // the reader clears "sphere"
  r.contact.law = c.law == ContactLaw::hertz ? "hertz" : "linear";
  r.contact.restitution = c.contact.restitution;
  r.contact.friction = c.contact.mu_slide;
  r.contact.rolling_friction = c.contact.mu_roll;
  r.contact.stiffness_N_m = c.contact.kn;
  for (const Material& m : c.materials)
    if (!c.sizes.empty() && m.name == c.sizes.front().material) r.contact.youngs_modulus_Pa = m.youngs_modulus;
  r.pair_overrides = static_cast<int>(c.pairs.size());
  for (const PairOverride& po : c.pairs)
    r.contact.pairs += fmt::format("{}{}-{}: e {:g}, friction {:g}, rolling {:g}, kn {:g}",
                                   r.contact.pairs.empty() ? "" : "; ", po.a, po.b, po.interaction.restitution,
                                   po.interaction.mu_slide, po.interaction.mu_roll, po.interaction.kn);
  if (!need_spectrum) return r;
  const fs::path sc = dir / "spectra.csv";
  const CsvTable t = read_csv_strict(sc, "the spectrum model needs the run's collision spectra");
  const std::string older = "the run is from an older millcharge; run it again";
  r.basis = basis;
  // The legacy reading (an ore fitted before the severity spectra): the
  // normal energy spectrum, binned by the loss alone, with one radius.
  const bool legacy = basis == grind::EnergyBasis::loss_one_radius;
  const std::string kind = legacy ? std::string("normal") : grind::basis_name(basis);
  const std::string col_n = legacy ? "normal_spectrum_collisions_per_s" : kind + "_collisions_per_s",
                    col_w = legacy ? "normal_spectrum_W" : kind + "_W", col_r = kind + "_r_eff_m";
  if (!t.has(col_n) || !t.has(col_w) || (!legacy && !t.has(col_r)) || !t.has("pair"))
    throw std::invalid_argument(sc.string() + ": has no " + kind + (legacy ? " energy" : " severity") +
                                " spectrum (columns " + col_n + ", " + col_w + (legacy ? "" : ", " + col_r) +
                                "): " + older);
  const int c_pair = t.column("pair"), c_bin = t.column("bin"), c_n = t.column(col_n), c_w = t.column(col_w),
            c_r = legacy ? -1 : t.column(col_r);
  const int c_all = t.has("collisions_per_s") ? t.column("collisions_per_s") : -1;
  // Each pair's bins 0, 1, ... in order, every pair with as many: a file
  // cut at a line's end, or with rows lost, is refused by its line.
  std::vector<std::string> pairs;
  std::vector<double> pair_collisions;
  long bins = -1, bin = 0;
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    const std::string& pair = t.rows[k][c_pair];
    if (pairs.empty() || pair != pairs.back()) {
      if (!pairs.empty() && bins < 0) bins = bin;
      if (!pairs.empty() && bin != bins)
        throw std::invalid_argument(fmt::format("{}: pair {} has {} bins, the first pair {}; the file is damaged",
                                                t.where(k - 1), pairs.back(), bin, bins));
      if (std::find(pairs.begin(), pairs.end(), pair) != pairs.end())
        throw std::invalid_argument(t.where(k) + ": pair " + pair + " again after other pairs; the file is damaged");
      pairs.push_back(pair);
      pair_collisions.push_back(0);
      bin = 0;
    }
    if (t.number(k, c_bin) != bin)
      throw std::invalid_argument(fmt::format("{}: bin {} of pair {} where bin {} was due; the file is damaged",
                                              t.where(k), t.rows[k][c_bin], pair, bin));
    ++bin;
    if (c_all >= 0) pair_collisions.back() += t.number(k, c_all);
  }
  if (pairs.empty()) throw std::invalid_argument(sc.string() + ": no rows; the file is damaged");
  if (bins >= 0 && bin != bins)
    throw std::invalid_argument(fmt::format("{}: pair {} has {} bins, the first pair {}: the file was cut short",
                                            t.where(t.rows.size() - 1), pairs.back(), bin, bins));
  // The pairs and their collision rates are those summary.json gives.
  if (doc.contains("spectra") && doc["spectra"].is_object() && doc["spectra"].contains("by_pair") &&
      doc["spectra"]["by_pair"].is_array() && c_all >= 0) {
    const auto& by_pair = doc["spectra"]["by_pair"];
    std::vector<std::string> want;
    for (const auto& q : by_pair)
      if (q.is_object() && q.contains("pair") && q["pair"].is_string()) want.push_back(q["pair"].get<std::string>());
    if (want != pairs) {
      std::string a, b;
      for (const std::string& x : want) a += (a.empty() ? "" : ", ") + x;
      for (const std::string& x : pairs) b += (b.empty() ? "" : ", ") + x;
      throw std::invalid_argument(sc.string() + ": holds the pairs " + b + ", summary.json " + a +
                                  "; the file is damaged or from another run");
    }
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto it = by_pair[k].find("collisions_per_s");
      const double rate = it != by_pair[k].end() && it->is_number() ? it->get<double>() : std::nan("");
      if (std::isfinite(rate) && std::fabs(pair_collisions[k] - rate) > 1e-5 * std::max(rate, 1.0))
        throw std::invalid_argument(fmt::format(
            "{}: pair {} sums to {:.6g} collisions/s, summary.json gives {:.6g}; the file is damaged or from "
            "another run",
            sc.string(), pairs[k], pair_collisions[k], rate));
    }
  }
  double all_collisions = 0, normal_collisions = 0;
  for (double c : pair_collisions) all_collisions += c;  // empty without the column
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    SpectrumBin b;
    b.collisions_per_s = t.number(k, c_n);
    normal_collisions += b.collisions_per_s;
    const double w = t.number(k, c_w);
    if (b.collisions_per_s <= 0 || w <= 0) continue;
    // The bin's mean energy and mean R*: its caught mass is that of its
    // collisions together, and the specific energy their R*-weighted mean.
    b.energy_J = w / b.collisions_per_s;
    if (legacy) {
      // Equal balls meet with half a radius; a ball meets a wall with its own.
      const std::string& pair = t.rows[k][c_pair];
      auto ends = [&](const std::string& tail) {
        return pair.size() > tail.size() && pair.compare(pair.size() - tail.size(), tail.size(), tail) == 0;
      };
      const bool wall = ends("-shell") || ends("-lifter") || ends("-end plate") || ends("-ends");
      b.r_eff_m = wall ? r.ball_radius_m : 0.5 * r.ball_radius_m;
      r.spectrum.push_back(b);
      continue;
    }
    b.r_eff_m = t.number(k, c_r);
    if (!(b.r_eff_m > 0))
      throw std::invalid_argument(fmt::format("{}: {} is {} where the bin holds collisions; the file is damaged",
                                              t.where(k), col_r, t.rows[k][c_r]));
    r.spectrum.push_back(b);
  }
  if (c_all >= 0 && all_collisions > 0 && std::fabs(normal_collisions - all_collisions) > 0.01 * all_collisions)
    throw std::invalid_argument(fmt::format(
        "{}: the {} spectrum holds {:.1f} % of the collisions (a run resumed from an older millcharge's "
        "checkpoint); run it again",
        sc.string(), kind, 100 * normal_collisions / all_collisions));
  if (r.spectrum.empty()) throw std::invalid_argument(sc.string() + ": no collisions in the " + kind + " spectrum");
  return r;
}

}  // namespace mc::io
