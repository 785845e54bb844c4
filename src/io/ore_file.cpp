// Reads ore files (ore_file.h).
#include "io/ore_file.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <set>
#include <tuple>
#include <stdexcept>
#include <string>
#include <toml++/toml.h>
#include <utility>
#include <vector>

#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/pbm.h"
#include "grind/sieve_errors.h"
#include "io/toml_names.h"

namespace mc::io {

namespace fs = std::filesystem;
using namespace mc::grind;

namespace {

// The ore file's tables and keys, with file:line in every message.
class OreReader : public TomlFileMessages {
 public:
  OreReader(const toml::table& t, std::string file) : TomlFileMessages(std::move(file)), top_(t) {}

  const toml::table* table(const std::string& name, bool required) const {
    const toml::node* n = top_.get(name);
    if (!n) {
      if (required) fail(name, nullptr, "missing table [" + name + "]");
      return nullptr;
    }
    if (!n->is_table()) fail(name, n, "must be a table, not " + type_name(*n));
    return n->as_table();
  }
  // A number in [lo, hi] (open ends where `open`), or the default when the
  // key is absent and a default is given.
  double number(const toml::table& t, const std::string& prefix, const std::string& key, double lo, double hi,
                const std::string& range, std::optional<double> dflt = std::nullopt) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (dflt) return *dflt;
      fail(prefix + key, nullptr, "missing (" + range + ")");
    }
    if (!n->is_number()) fail(prefix + key, n, "must be a number, not " + type_name(*n));
    const double v = n->value<double>().value();
    if (!std::isfinite(v) || v < lo || v > hi) fail(prefix + key, n, fmt::format("{:g} is out of range: {}", v, range));
    return v;
  }
  std::vector<double> numbers(const toml::table& t, const std::string& prefix, const std::string& key) const {
    const toml::node* n = t.get(key);
    if (!n) fail(prefix + key, nullptr, "missing (an array of numbers)");
    if (!n->is_array()) fail(prefix + key, n, "must be an array of numbers, not " + type_name(*n));
    std::vector<double> v;
    for (const toml::node& e : *n->as_array()) {
      if (!e.is_number()) fail(prefix + key, &e, "must hold numbers only, not " + type_name(e));
      v.push_back(e.value<double>().value());
    }
    if (v.size() < 2) fail(prefix + key, n, "needs at least two values");
    return v;
  }
  const toml::node* node(const toml::table& t, const std::string& key) const { return t.get(key); }

 private:
  const toml::table& top_;
};

constexpr double kInf = std::numeric_limits<double>::infinity();

// An array of numbers of any length (an empty one too).
std::vector<double> any_numbers(const OreReader& r, const toml::node* n, const std::string& key) {
  if (!n->is_array()) r.fail(key, n, "must be an array of numbers, not " + type_name(*n));
  std::vector<double> v;
  for (const toml::node& e : *n->as_array()) {
    if (!e.is_number() || !std::isfinite(e.value<double>().value()))
      r.fail(key, &e, "must hold finite numbers only, not " + type_name(e));
    v.push_back(e.value<double>().value());
  }
  return v;
}

// [fitted]'s covariance and held parameters (grind::FitCovariance): what a
// batch test's fit leaves open. None: an ore fitted before they were kept.
void read_covariance(const OreReader& r, const toml::table& ft, FitCovariance& u) {
  const toml::node* dn = ft.get("degrees_of_freedom");
  if (!dn) {
    for (const char* k :
         {"covariance_variables", "covariance_values", "covariance", "residual_variance_pp2", "held", "edge", "best",
          "information", "ssr_held", "ssr_best", "ssr_limit", "tables_fnv1a"})
      if (ft.get(k)) r.fail(std::string("fitted.") + k, ft.get(k), "given without fitted.degrees_of_freedom");
    return;
  }
  u.given = true;
  u.dof = static_cast<int>(r.number(ft, "fitted.", "degrees_of_freedom", 1, 1e9, "an integer >= 1"));
  u.residual_variance_pp2 = r.number(ft, "fitted.", "residual_variance_pp2", 0, kInf, ">= 0 (pp²)");
  // The sums of squares where the held parameters are held and where they
  // fit best, and the limit (none: an ore written before they were kept).
  u.ssr_fit = r.number(ft, "fitted.", "ssr_held", 0, kInf, ">= 0", 0.0);
  u.ssr_best = r.number(ft, "fitted.", "ssr_best", 0, kInf, ">= 0", 0.0);
  u.ssr_limit = r.number(ft, "fitted.", "ssr_limit", 0, kInf, ">= 0", 0.0);
  if (const toml::node* hn = ft.get("tables_fnv1a")) {
    if (!hn->is_string()) r.fail("fitted.tables_fnv1a", hn, "must be a string (\"sizes HEX breakage HEX rates HEX\")");
    u.tables_hash = hn->value<std::string>().value();
  }
  const toml::node* vn = ft.get("covariance_variables");
  if (!vn || !vn->is_array()) r.fail("fitted.covariance_variables", vn, "missing (an array of names, maybe empty)");
  for (const toml::node& e : *vn->as_array()) {
    const std::string v = e.is_string() ? e.value<std::string>().value() : std::string();
    const std::string name = grind::parameter_of_variable(v);
    if (name.empty())
      r.fail("fitted.covariance_variables", &e,
             "\"" + v + "\" is not a fitted variable (log(NAME) for a scale, NAME for zeta1, zeta2, "
             "breakage.phi)");
    u.names.push_back(name);
  }
  const std::size_t np = u.names.size();
  const toml::node* xn = ft.get("covariance_values");
  if (!xn) r.fail("fitted.covariance_values", nullptr, "missing (the fitted variables' values)");
  u.values = any_numbers(r, xn, "fitted.covariance_values");
  if (u.values.size() != np)
    r.fail("fitted.covariance_values", xn, fmt::format("{} values for {} variables", u.values.size(), np));
  const toml::node* cn = ft.get("covariance");
  if (!cn || !cn->is_array()) r.fail("fitted.covariance", cn, "missing (an array of rows, one per variable)");
  for (const toml::node& row : *cn->as_array()) u.matrix.push_back(any_numbers(r, &row, "fitted.covariance"));
  bool square = u.matrix.size() == np;
  for (std::size_t a = 0; a < u.matrix.size() && square; ++a) {
    square = u.matrix[a].size() == np && u.matrix[a][a] >= 0;
    for (std::size_t b = 0; b < a && square; ++b) square = std::fabs(u.matrix[a][b] - u.matrix[b][a]) <=
                                                           1e-6 * std::sqrt(u.matrix[a][a] * u.matrix[b][b]) + 1e-300;
  }
  if (!square)
    r.fail("fitted.covariance", cn,
           fmt::format("must be a symmetric {} x {} matrix with a non-negative diagonal (one row per variable)", np, np));
  const toml::node* hn = ft.get("held");
  if (hn && !hn->is_array_of_tables()) r.fail("fitted.held", hn, "must be an array of tables ([[fitted.held]])");
  for (const toml::node& e : hn ? *hn->as_array() : toml::array{}) {
    const toml::table& t = *e.as_table();
    r.knows(t, "fitted.held.", {"name", "value", "lo", "hi", "why", "free_at_lo", "free_at_hi"});
    grind::HeldParameter h;
    const toml::node* nn = t.get("name");
    h.name = nn && nn->is_string() ? nn->value<std::string>().value() : "";
    if (!find_ore_parameter(h.name)) r.fail("fitted.held.name", nn ? nn : &e, "not a parameter a fit can move");
    h.value = r.number(t, "fitted.held.", "value", -kInf, kInf, "a number");
    h.lo = r.number(t, "fitted.held.", "lo", -kInf, h.value, "at most value");
    h.hi = r.number(t, "fitted.held.", "hi", h.value, kInf, "at least value");
    if (const toml::node* w = t.get("why"); w && w->is_string()) h.why = w->value<std::string>().value();
    for (auto [key, dst] : {std::pair{"free_at_lo", &h.free_at_lo}, std::pair{"free_at_hi", &h.free_at_hi}}) {
      const toml::node* fn = t.get(key);
      if (!fn) continue;
      *dst = any_numbers(r, fn, std::string("fitted.held.") + key);
      if (!dst->empty() && dst->size() != np)
        r.fail(std::string("fitted.held.") + key, fn, fmt::format("{} values for {} variables", dst->size(), np));
    }
    u.held.push_back(h);
  }
  // Two arrays of numbers, one a held parameter and one a free variable:
  // [fitted.best] and each [[fitted.edge]].
  auto point = [&](const toml::table& t, const std::string& where, grind::HeldEdge& c) {
    r.knows(t, where + ".", {"held", "free", "profile_of"});
    if (const toml::node* on = t.get("profile_of")) {
      const std::optional<std::string> name = on->value<std::string>();
      for (std::size_t k = 0; name && k < u.held.size(); ++k)
        if (u.held[k].name == *name) c.of = static_cast<int>(k);
      if (c.of < 0) r.fail(where + ".profile_of", on, "must name a held parameter ([[fitted.held]] name)");
    }
    for (auto [key, dst, want] : {std::tuple{"held", &c.held, u.held.size()}, std::tuple{"free", &c.free, np}}) {
      const toml::node* fn = t.get(key);
      if (!fn) r.fail(where + "." + key, nullptr, "missing");
      *dst = any_numbers(r, fn, where + "." + key);
      if (dst->size() != want)
        r.fail(where + "." + key, fn,
               fmt::format("{} values for {} {}", dst->size(), want,
                           std::string(key) == "held" ? "held parameters ([[fitted.held]])" : "variables"));
    }
  };
  if (const toml::node* bn = ft.get("best")) {
    if (!bn->is_table()) r.fail("fitted.best", bn, "must be a table ([fitted.best])");
    point(*bn->as_table(), "fitted.best", u.best);
  }
  if (const toml::node* in = ft.get("information")) {
    const std::size_t nv = np + u.held.size();
    if (!in->is_array()) r.fail("fitted.information", in, "must be an array of rows");
    for (const toml::node& row : *in->as_array()) u.information.push_back(any_numbers(r, &row, "fitted.information"));
    bool square = u.information.size() == nv;
    for (const auto& row : u.information) square = square && row.size() == nv;
    if (!square)
      r.fail("fitted.information", in,
             fmt::format("must be a {} x {} matrix (one row per variable, then per held parameter)", nv, nv));
  }
  const toml::node* kn = ft.get("edge");
  if (!kn) return;
  if (!kn->is_array_of_tables()) r.fail("fitted.edge", kn, "must be an array of tables ([[fitted.edge]])");
  for (const toml::node& e : *kn->as_array()) {
    grind::HeldEdge c;
    point(*e.as_table(), "fitted.edge", c);
    u.edges.push_back(c);
  }
}

// [fitted]: the contact the ore was fitted under (grind::ContactRecord).
void read_fitted(const OreReader& r, const toml::table& ft, ContactRecord& c) {
  r.knows(ft, "fitted.", {"contact_law", "restitution", "friction", "rolling_friction", "stiffness_N_m",
                          "youngs_modulus_Pa", "pairs", "test", "run", "parameters", "rms_residual_pp", "residual_lag1",
                          "sieve_error_rho",
                          "energy_basis", "covariance_variables", "covariance_values", "covariance",
                          "residual_variance_pp2", "degrees_of_freedom", "held", "edge", "best", "information",
                          "ssr_held", "ssr_best", "ssr_limit", "tables_fnv1a"});
  auto text = [&](const std::string& key) {
    const toml::node* n = ft.get(key);
    if (!n) return std::string();
    if (!n->is_string()) r.fail("fitted." + key, n, "must be a string, not " + type_name(*n));
    return n->value<std::string>().value();
  };
  c.law = text("contact_law");
  if (c.law != "linear" && c.law != "hertz")
    r.fail("fitted.contact_law", ft.get("contact_law"), "must be \"linear\" or \"hertz\"");
  c.restitution = r.number(ft, "fitted.", "restitution", 0, 1, "0 to 1");
  c.friction = r.number(ft, "fitted.", "friction", 0, 10, "0 to 10");
  c.rolling_friction = r.number(ft, "fitted.", "rolling_friction", 0, 10, "0 to 10", 0.0);
  if (c.law == "linear") c.stiffness_N_m = r.number(ft, "fitted.", "stiffness_N_m", 0, kInf, "N/m > 0");
  if (c.law == "hertz") c.youngs_modulus_Pa = r.number(ft, "fitted.", "youngs_modulus_Pa", 0, kInf, "Pa > 0");
  c.pairs = text("pairs");
  c.energy_basis = text("energy_basis");  // none: a fit from before the severity spectra (set below)
  grind::EnergyBasis b;
  if (ft.get("energy_basis") && !grind::basis_of(c.energy_basis, &b))
    r.fail("fitted.energy_basis", ft.get("energy_basis"), "must be \"impact\", \"loss\" or \"loss_one_radius\"");
  c.test = text("test");
  c.run = text("run");
  c.parameters = text("parameters");
  c.rms_residual_pp = r.number(ft, "fitted.", "rms_residual_pp", 0, kInf, ">= 0", 0.0);
  if (ft.get("residual_lag1")) c.residual_lag1 = r.number(ft, "fitted.", "residual_lag1", -1, 1, "within -1 .. 1");
  c.sieve_error_rho = r.number(ft, "fitted.", "sieve_error_rho", 0, grind::kMaxSieveRho, "0 to 0.98", 0.0);
  read_covariance(r, ft, c.covariance);
}

// [breakage] with model = "t10": Tavares' energy-dependent t10 (grind::T10Breakage).
void read_t10(const OreReader& r, const toml::table& bk, T10Breakage& t) {
  r.knows(bk, "breakage.", {"model", "t10_max_percent", "b_prime", "tn_n", "tn_alpha", "tn_beta"});
  t.a = r.number(bk, "breakage.", "t10_max_percent", 1, 100, "A, the largest t10, 1 to 100 %") / 100;
  t.b_prime = r.number(bk, "breakage.", "b_prime", 1e-3, 100, "b', 0.001 to 100");
  t.n = r.numbers(bk, "breakage.", "tn_n");
  t.alpha = r.numbers(bk, "breakage.", "tn_alpha");
  t.beta = r.numbers(bk, "breakage.", "tn_beta");
  for (const char* key : {"tn_alpha", "tn_beta"}) {
    const std::vector<double>& v = std::string(key) == "tn_alpha" ? t.alpha : t.beta;
    if (v.size() != t.n.size())
      r.fail(std::string("breakage.") + key, bk.get(key),
             fmt::format("holds {} values for the {} sizes of breakage.tn_n", v.size(), t.n.size()));
    for (double x : v)
      if (!(x > 0 && x <= 100))
        r.fail(std::string("breakage.") + key, bk.get(key), fmt::format("{:g} is out of range: 0 to 100, > 0", x));
  }
  for (std::size_t k = 0; k < t.n.size(); ++k) {
    if (!(t.n[k] > 1 && t.n[k] <= 1000))
      r.fail("breakage.tn_n", bk.get("tn_n"), fmt::format("{:g} is out of range: n from 1 to 1000, > 1", t.n[k]));
    if (t.n[k] == 10)
      r.fail("breakage.tn_n", bk.get("tn_n"), "holds 10: t10 is the model's own (t10_max_percent, b_prime); leave it out");
    if (k > 0 && !(t.n[k] > t.n[k - 1])) r.fail("breakage.tn_n", bk.get("tn_n"), "the sizes n must ascend");
  }
  // t_n must fall as n rises (a finer size passes less) at every t10 the
  // model can give: checked on a grid up to A.
  for (int g = 0; g <= 60; ++g) {
    const double t10 = t.a * std::pow(1e-3, 1 - g / 60.0);
    double above = 1;  // t_n of the next coarser size
    std::string above_name = "t_1";
    bool ten = false;
    auto check = [&](double n, double tn) {
      if (tn > above + 1e-9)
        r.fail("breakage.tn_alpha", bk.get("tn_alpha"),
               fmt::format("t_{:g} ({:.4g} %) is above {} ({:.4g} %) at t10 = {:.4g} %: t_n must fall as n rises; "
                           "check tn_alpha and tn_beta",
                           n, 100 * tn, above_name, 100 * above, 100 * t10));
      above = tn;
      above_name = fmt::format("t_{:g}", n);
    };
    for (std::size_t k = 0; k < t.n.size(); ++k) {
      if (!ten && t.n[k] > 10) check(10, t10), ten = true;
      check(t.n[k], t.tn(k, t10));
    }
    if (!ten) check(10, t10);
  }
}

}  // namespace

grind::Ore read_ore(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw std::invalid_argument("--ore " + path.string() + ": is a directory, not a file");
  if (!fs::exists(path, ec)) throw std::invalid_argument("--ore " + path.string() + ": no such file");
  toml::table top;
  try {
    top = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}:{}:{}: not valid TOML: {}", path.string(), e.source().begin.line,
                                            e.source().begin.column, e.description()));
  }
  const std::string file = path.string();
  OreReader r(top, file);
  Ore o;
  r.knows(top, "", {"name", "density", "holdup_kg", "powder_filling", "bed_porosity", "bulk_density", "tanks",
                    "sizes", "feed", "breakage", "rates", "fitted"});
  if (const toml::node* n = top.get("name")) o.name = n->value<std::string>().value_or("");
  o.density = r.number(top, "", "density", 500, 25000, "kg/m^3 of the ore's solid, 500 to 25000");
  const bool has_holdup = top.get("holdup_kg"), has_u = top.get("powder_filling");
  if (has_holdup == has_u)
    r.fail(has_holdup ? "powder_filling" : "holdup_kg", has_u ? top.get("powder_filling") : nullptr,
           "give exactly one of holdup_kg (kg of ore in the mill) and powder_filling (U, the share of the ball "
           "bed's voids the ore fills)");
  if (has_holdup) o.holdup_kg = r.number(top, "", "holdup_kg", 0, kInf, "kg > 0");
  if (o.holdup_kg == 0 && has_holdup) r.fail("holdup_kg", top.get("holdup_kg"), "must be > 0 kg");
  if (has_u) o.powder_filling = r.number(top, "", "powder_filling", 0.01, 3, "0.01 to 3 (1: the voids just full)");
  o.bed_porosity = r.number(top, "", "bed_porosity", 0.2, 0.7, "0.2 to 0.7", 0.4);
  o.bulk_density = r.number(top, "", "bulk_density", 300, 15000, "kg/m^3 of the packed feed, 300 to 15000",
                            o.density * (1 - o.bed_porosity));
  if (o.bulk_density >= o.density)
    r.fail("bulk_density", top.get("bulk_density"), "must be below the solid's density");
  o.tanks = static_cast<int>(r.number(top, "", "tanks", 1, 1000, "1 to 1000 tanks in series", 1));

  const toml::table& sz = *r.table("sizes", true);
  r.knows(sz, "sizes.", {"top_mm", "ratio", "classes"});
  const double top_mm = r.number(sz, "sizes.", "top_mm", 1e-3, 1e3, "mm, 0.001 to 1000");
  const double ratio = r.number(sz, "sizes.", "ratio", 1.05, 4, "1.05 to 4 (sqrt 2 or 2^0.25 are the usual series)",
                                std::sqrt(2.0));
  const double classes = r.number(sz, "sizes.", "classes", 4, 200, "4 to 200");
  if (classes != std::floor(classes)) r.fail("sizes.classes", sz.get("classes"), "must be a whole number");
  o.sizes = geometric_series(top_mm * 1e-3, ratio, static_cast<int>(classes));

  const toml::table& fd = *r.table("feed", true);
  r.knows(fd, "feed.", {"sieve_mm", "passing"});
  const std::vector<double> sieve = r.numbers(fd, "feed.", "sieve_mm");
  const std::vector<double> pass = r.numbers(fd, "feed.", "passing");
  if (sieve.size() != pass.size())
    r.fail("feed.passing", fd.get("passing"),
           fmt::format("holds {} values for {} sieves in feed.sieve_mm", pass.size(), sieve.size()));
  for (std::size_t k = 0; k < sieve.size(); ++k) {
    if (!(sieve[k] > 0)) r.fail("feed.sieve_mm", fd.get("sieve_mm"), "sizes must be > 0 mm");
    if (k > 0 && !(sieve[k] < sieve[k - 1]))
      r.fail("feed.sieve_mm", fd.get("sieve_mm"), "sizes must descend, coarsest first");
    if (!(pass[k] >= 0 && pass[k] <= 1)) r.fail("feed.passing", fd.get("passing"), "each passing must be in 0..1");
    if (k > 0 && pass[k] > pass[k - 1])
      r.fail("feed.passing", fd.get("passing"), "passing must not rise as the sieves get finer");
  }
  if (std::fabs(pass.front() - 1) > 1e-9)
    r.fail("feed.passing", fd.get("passing"),
           fmt::format("the coarsest sieve ({:g} mm) must pass all the feed (1), not {:g}: the feed must sum to 1",
                       sieve.front(), pass.front()));
  if (sieve.front() > top_mm * (1 + 1e-9))
    r.fail("sizes.top_mm", sz.get("top_mm"),
           fmt::format("{:g} mm is below the feed's top size {:g} mm: the size series does not cover the feed", top_mm,
                       sieve.front()));
  std::vector<double> sieve_m;
  for (double s : sieve) sieve_m.push_back(s * 1e-3);
  o.feed = feed_masses(o.sizes, sieve_m, pass);
  o.sieve_m = sieve_m;
  o.sieve_passing = pass;
  o.ratio = ratio;
  o.f80_m = passing_size(o.sizes, o.feed, 0.8);

  const toml::table& bk = *r.table("breakage", true);
  const toml::node* bm = bk.get("model");
  if (bm && !bm->is_string()) r.fail("breakage.model", bm, "must be a string, not " + type_name(*bm));
  const std::string appearance = bm ? bm->value<std::string>().value() : "austin";
  if (appearance == "austin") {
    r.knows(bk, "breakage.", {"model", "phi", "gamma", "beta"});
    o.breakage.phi = r.number(bk, "breakage.", "phi", 0, 1, "0 to 1");
    o.breakage.gamma = r.number(bk, "breakage.", "gamma", 0.2, 3, "0.2 to 3");
    o.breakage.beta = r.number(bk, "breakage.", "beta", 1, 10, "1 to 10");
  } else if (appearance == "t10") {
    o.appearance = Appearance::t10;
    read_t10(r, bk, o.t10);
  } else {
    r.fail("breakage.model", bm, "must be \"austin\" (Austin's B) or \"t10\" (Tavares' energy-dependent t10), not \"" +
                                     appearance + "\"");
  }

  const toml::table& rt = *r.table("rates", true);
  const toml::node* mn = rt.get("model");
  const std::string model = mn ? mn->value<std::string>().value_or("?") : "";
  if (model == "austin") {
    o.model = RateModel::austin;
    r.knows(rt, "rates.", {"model", "a_per_min", "alpha", "mu_mm", "lambda"});
    o.austin.a_per_min = r.number(rt, "rates.", "a_per_min", 1e-6, 100, "per minute at 1 mm, 1e-6 to 100");
    o.austin.alpha = r.number(rt, "rates.", "alpha", 0.1, 3, "0.1 to 3");
    o.austin.mu_m = r.number(rt, "rates.", "mu_mm", 1e-3, 1e3, "mm, 0.001 to 1000") * 1e-3;
    o.austin.lambda = r.number(rt, "rates.", "lambda", 0.5, 10, "0.5 to 10");
  } else if (model == "energy") {
    o.model = RateModel::energy;
    r.knows(rt, "rates.", {"model", "s1e_t_per_kWh", "x1_mm", "zeta1", "zeta2"});
    o.energy.s1e_t_per_kWh = r.number(rt, "rates.", "s1e_t_per_kWh", 1e-6, 100, "t/kWh, 1e-6 to 100");
    o.energy.x1_m = r.number(rt, "rates.", "x1_mm", 1e-3, 1e3, "mm, 0.001 to 1000") * 1e-3;
    o.energy.zeta1 = r.number(rt, "rates.", "zeta1", -5, 5, "-5 to 5");
    o.energy.zeta2 = r.number(rt, "rates.", "zeta2", -5, 5, "-5 to 5", 0.0);
  } else if (model == "spectrum") {
    o.model = RateModel::spectrum;
    r.knows(rt, "rates.",
            {"model", "e_inf_J_kg", "d0_mm", "phi", "sigma", "emax_ratio", "packing", "efficiency", "energy_basis"});
    o.fracture.e_inf_J_kg = r.number(rt, "rates.", "e_inf_J_kg", 1e-3, 1e5, "J/kg, 0.001 to 1e5");
    o.fracture.d0_m = r.number(rt, "rates.", "d0_mm", 1e-4, 1e3, "mm, 1e-4 to 1000") * 1e-3;
    o.fracture.phi = r.number(rt, "rates.", "phi", 0, 5, "0 to 5");
    o.fracture.sigma = r.number(rt, "rates.", "sigma", 0.05, 3, "0.05 to 3");
    o.fracture.emax_ratio = r.number(rt, "rates.", "emax_ratio", 1.01, 1e3, "1.01 to 1000", 10.0);
    o.packing = r.number(rt, "rates.", "packing", 0.05, 1.1547, "0.05 to 1.1547 (the share of a square lattice's sites that the caught monolayer fills; its area fraction is pi/4 of that, and 1.1547 = 2/sqrt(3) is a hexagonal layer's 0.907)", 0.6);
    o.efficiency = r.number(rt, "rates.", "efficiency", 1e-4, 1, "1e-4 to 1", 1.0);
  } else {
    r.fail("rates.model", mn, "must be \"austin\", \"energy\" or \"spectrum\"" +
                                  (mn ? std::string(", not \"") + model + "\"" : std::string(" (missing)")));
  }
  if (o.appearance == Appearance::t10 && o.model != RateModel::spectrum)
    r.fail("breakage.model", bm,
           "\"t10\" takes each collision's energy from the run's normal spectrum: it needs rates.model = "
           "\"spectrum\" (with another rate model give Austin's B: phi, gamma, beta)");
  if (const toml::table* ft = r.table("fitted", false)) read_fitted(r, *ft, o.fitted_under);
  if (o.model == RateModel::spectrum) {
    // The energy the fracture parameters are set against: as the file says,
    // else as the fit it records (a fit from before the severity spectra:
    // the normal loss with one radius), else the impact energy (Tavares'
    // drop-weight energies are energies delivered). A file that says one
    // and records a fit on another is refused where its products are made
    // (grind), not here: a new fit replaces the record.
    std::string& fitted = o.fitted_under.energy_basis;
    if (!o.fitted_under.law.empty() && fitted.empty()) fitted = "loss_one_radius";
    o.energy_basis = grind::EnergyBasis::impact;
    if (!fitted.empty()) grind::basis_of(fitted, &o.energy_basis);
    if (const toml::node* bn = rt.get("energy_basis")) {
      if (!bn->is_string() || !grind::basis_of(*bn->value<std::string>(), &o.energy_basis))
        r.fail("rates.energy_basis", bn,
               "must be \"impact\" (the energy at first touch, as drop-weight tests deliver), \"loss\" (the "
               "normal energy the collision loses) or \"loss_one_radius\" (the normal loss with one radius for "
               "every collision, as ores were fitted before the severity spectra)");
      o.energy_basis_given = true;
    }
  } else {
    o.fitted_under.energy_basis.clear();  // a basis means nothing to the other rate models
  }
  return o;
}

namespace {

// How ore_toml writes a number, a list and a string.
std::string g(double v) { return fmt::format("{:.10g}", v); }
std::string list(const std::vector<double>& v, double scale) {
  std::string s = "[";
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + g(v[k] * scale);
  return s + "]";
}
std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' || c == '\\' ? std::string("\\") + c : std::string(1, c);
  return q + "\"";
}

// The [sizes], [breakage] and [rates] tables as ore_toml writes them.
struct OreTables {
  std::string sizes, breakage, rates;
};
OreTables tables(const grind::Ore& o) {
  OreTables t;
  std::string s;
  s += "\n[sizes]\ntop_mm = " + g(o.sizes.top_m.front() * 1e3) + "\nratio = " + g(o.ratio) +
       "\nclasses = " + std::to_string(o.sizes.size()) + "\n";
  t.sizes = s;
  s.clear();
  if (o.appearance == Appearance::t10)
    s += "\n[breakage]\nmodel = \"t10\"\nt10_max_percent = " + g(100 * o.t10.a) + "\nb_prime = " + g(o.t10.b_prime) +
         "\ntn_n = " + list(o.t10.n, 1) + "\ntn_alpha = " + list(o.t10.alpha, 1) + "\ntn_beta = " + list(o.t10.beta, 1) +
         "\n";
  else
    s += "\n[breakage]\nphi = " + g(o.breakage.phi) + "\ngamma = " + g(o.breakage.gamma) + "\nbeta = " +
         g(o.breakage.beta) + "\n";
  s += "\n[rates]\n";
  if (o.model == RateModel::austin)
    s += "model = \"austin\"\na_per_min = " + g(o.austin.a_per_min) + "\nalpha = " + g(o.austin.alpha) +
         "\nmu_mm = " + g(o.austin.mu_m * 1e3) + "\nlambda = " + g(o.austin.lambda) + "\n";
  if (o.model == RateModel::energy)
    s += "model = \"energy\"\ns1e_t_per_kWh = " + g(o.energy.s1e_t_per_kWh) + "\nx1_mm = " + g(o.energy.x1_m * 1e3) +
         "\nzeta1 = " + g(o.energy.zeta1) + "\nzeta2 = " + g(o.energy.zeta2) + "\n";
  if (o.model == RateModel::spectrum)
    s += "model = \"spectrum\"\ne_inf_J_kg = " + g(o.fracture.e_inf_J_kg) + "\nd0_mm = " + g(o.fracture.d0_m * 1e3) +
         "\nphi = " + g(o.fracture.phi) + "\nsigma = " + g(o.fracture.sigma) + "\nemax_ratio = " +
         g(o.fracture.emax_ratio) + "\npacking = " + g(o.packing) + "\nefficiency = " + g(o.efficiency) +
         "\nenergy_basis = " + quoted(grind::basis_name(o.energy_basis)) + "\n";
  t.rates = s.substr(s.find("\n[rates]"));
  t.breakage = s.substr(0, s.find("\n[rates]"));
  return t;
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

}  // namespace

std::string ore_tables_hash(const grind::Ore& o) {
  const OreTables t = tables(o);
  // The basis too: an ore of another rate model keeps it outside [rates].
  return fmt::format("sizes {:016x} breakage {:016x} rates {:016x}", fnv1a(t.sizes), fnv1a(t.breakage),
                     fnv1a(t.rates + "energy_basis " + grind::basis_name(o.energy_basis)));
}

std::string changed_tables(const grind::Ore& o, const std::string& kept) {
  if (kept.empty()) return "";
  const std::string now = ore_tables_hash(o);
  if (now == kept) return "";
  std::string out;
  std::vector<std::string> which;
  for (const char* name : {"sizes", "breakage", "rates"}) {
    auto field = [&](const std::string& h) {
      const std::size_t at = h.find(std::string(name) + " ");
      return at == std::string::npos ? std::string() : h.substr(at, std::strlen(name) + 17);
    };
    if (field(now) != field(kept)) which.push_back(std::string("[") + name + "]");
  }
  if (which.empty()) return "the ore's tables";
  for (std::size_t k = 0; k < which.size(); ++k)
    out += (k == 0 ? "" : k + 1 == which.size() ? " and " : ", ") + which[k];
  return out;
}

namespace {

// [fitted]'s covariance and held parameters, as read_covariance reads them.
std::string covariance_toml(const FitCovariance& u) {
  if (!u.given) return "";
  auto g = [](double v) { return fmt::format("{:.10g}", v); };
  auto list = [&](const std::vector<double>& v) {
    std::string s = "[";
    for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + g(v[k]);
    return s + "]";
  };
  std::string s = "# What the fit leaves open (docs/grinding-intervals.md): the covariance of the fitted\n"
                  "# variables (the logarithm of a scale), and the range each held parameter may take\n";
  s += "covariance_variables = [";
  for (std::size_t k = 0; k < u.names.size(); ++k) s += (k ? ", \"" : "\"") + grind::variable_name(u.names[k]) + "\"";
  s += "]\ncovariance_values = " + list(u.values) + "\ncovariance = [";
  for (std::size_t a = 0; a < u.matrix.size(); ++a) s += (a ? ", " : "") + list(u.matrix[a]);
  s += "]\nresidual_variance_pp2 = " + g(u.residual_variance_pp2) + "\ndegrees_of_freedom = " +
       std::to_string(u.dof) + "\n";
  if (!u.information.empty()) {
    s += "information = [";  // JᵀJ / s² of the free variables, then the held parameters'
    for (std::size_t a = 0; a < u.information.size(); ++a) s += (a ? ", " : "") + list(u.information[a]);
    s += "]   # the tests' information: the variables, then the held parameters (log of a scale)\n";
  }
  if (!u.tables_hash.empty())
    s += "tables_fnv1a = \"" + u.tables_hash + "\"   # [sizes], [breakage], [rates] as fitted: an edit leaves no intervals\n";
  if (u.ssr_limit > 0)
    s += "ssr_held = " + g(u.ssr_fit) + "   # the weighted sum of squares where the held parameters are held\nssr_best = " +
         g(u.ssr_best) + "   # where they fit best ([fitted.best])\nssr_limit = " + g(u.ssr_limit) +
         "  # the 95 % limit from there: ssr_held above it, the ore lies outside the data's 95 % region\n";
  for (const grind::HeldParameter& h : u.held) {
    s += "\n[[fitted.held]]\nname = \"" + h.name + "\"\nvalue = " + g(h.value) + "\nlo = " + g(h.lo) +
         "\nhi = " + g(h.hi) + "\n";
    std::string why;
    for (char c : h.why) why += c == '"' || c == '\\' ? std::string("\\") + c : std::string(1, c);
    if (!why.empty()) s += "why = \"" + why + "\"\n";
    if (!h.free_at_lo.empty()) s += "free_at_lo = " + list(h.free_at_lo) + "\n";
    if (!h.free_at_hi.empty()) s += "free_at_hi = " + list(h.free_at_hi) + "\n";
  }
  if (!u.best.held.empty())
    s += "\n[fitted.best]           # where the held parameters fit the data best, the free ones refitted there\n"
         "held = " + list(u.best.held) + "\nfree = " + list(u.best.free) + "\n";
  for (const grind::HeldEdge& c : u.edges) {
    s += "\n[[fitted.edge]]\nheld = " + list(c.held) + "\nfree = " + list(c.free) + "\n";
    if (c.of >= 0 && static_cast<std::size_t>(c.of) < u.held.size())
      s += "profile_of = \"" + u.held[static_cast<std::size_t>(c.of)].name + "\"   # an end of its profile\n";
  }
  return s;
}

}  // namespace

std::string ore_toml(const grind::Ore& o, const std::string& header) {
  std::string s = header;
  s += "name = " + quoted(o.name) + "\n";
  s += "density = " + g(o.density) + "\n";
  s += o.holdup_kg > 0 && o.powder_filling == 0 ? "holdup_kg = " + g(o.holdup_kg) + "\n"
                                                : "powder_filling = " + g(o.powder_filling) + "\n";
  s += "bed_porosity = " + g(o.bed_porosity) + "\n";
  if (o.bulk_density > 0) s += "bulk_density = " + g(o.bulk_density) + "\n";
  s += "tanks = " + std::to_string(o.tanks) + "\n";
  const OreTables t = tables(o);
  s += t.sizes;
  s += "\n[feed]\nsieve_mm = " + list(o.sieve_m, 1e3) + "\npassing = " + list(o.sieve_passing, 1) + "\n";
  s += t.breakage + t.rates;
  const ContactRecord& f = o.fitted_under;
  if (!f.law.empty()) {
    s += "\n[fitted]                # the run the ore was fitted through: its parameters hold under this contact\n";
    s += "contact_law = " + quoted(f.law) + "\n";
    s += "restitution = " + g(f.restitution) + "\nfriction = " + g(f.friction) + "\nrolling_friction = " +
         g(f.rolling_friction) + "\n";
    if (f.law == "linear") s += "stiffness_N_m = " + g(f.stiffness_N_m) + "\n";
    if (f.law == "hertz") s += "youngs_modulus_Pa = " + g(f.youngs_modulus_Pa) + "\n";
    if (!f.pairs.empty()) s += "pairs = " + quoted(f.pairs) + "\n";
    if (!f.energy_basis.empty()) s += "energy_basis = " + quoted(f.energy_basis) + "\n";
    if (!f.test.empty()) s += "test = " + quoted(f.test) + "\n";
    if (!f.run.empty()) s += "run = " + quoted(f.run) + "\n";
    if (!f.parameters.empty()) s += "parameters = " + quoted(f.parameters) + "\n";
    s += "rms_residual_pp = " + g(f.rms_residual_pp) + "\n";
    if (std::isfinite(f.residual_lag1)) s += "residual_lag1 = " + g(f.residual_lag1) + "\n";
    if (f.sieve_error_rho > 0) s += "sieve_error_rho = " + g(f.sieve_error_rho) + "\n";
    s += covariance_toml(f.covariance);
  }
  return s;
}

}  // namespace mc::io
