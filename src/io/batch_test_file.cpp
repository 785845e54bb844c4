// Reads and writes batch test files (batch_test_file.h).
#include "io/batch_test_file.h"

#include <fmt/format.h>

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <toml++/toml.h>
#include <vector>

#include "io/toml_names.h"

namespace mc::io {

namespace fs = std::filesystem;

namespace {

class TestReader : public TomlFileMessages {
 public:
  explicit TestReader(std::string file) : TomlFileMessages(std::move(file)) {}
  double number(const toml::table& t, const std::string& key, const std::string& name, double lo, double hi,
                const std::string& range) const {
    const toml::node* n = t.get(key);
    if (!n) fail(name, nullptr, "missing (" + range + ")");
    if (!n->is_number()) fail(name, n, "must be a number, not " + type_name(*n));
    const double v = n->value<double>().value();
    if (!std::isfinite(v) || v < lo || v > hi) fail(name, n, fmt::format("{:g} is out of range: {}", v, range));
    return v;
  }
  std::vector<double> numbers(const toml::table& t, const std::string& key, const std::string& name) const {
    const toml::node* n = t.get(key);
    if (!n) fail(name, nullptr, "missing (an array of numbers)");
    if (!n->is_array()) fail(name, n, "must be an array of numbers, not " + type_name(*n));
    std::vector<double> v;
    for (const toml::node& e : *n->as_array()) {
      if (!e.is_number()) fail(name, &e, "must hold numbers only, not " + type_name(e));
      v.push_back(e.value<double>().value());
      if (!std::isfinite(v.back())) fail(name, &e, "must hold finite numbers");
    }
    return v;
  }
};

std::string text_key(const toml::table& t, const TestReader& r, const std::string& key) {
  const toml::node* n = t.get(key);
  if (!n) return "";
  if (!n->is_string()) r.fail(key, n, "must be a string, not " + type_name(*n));
  return n->value<std::string>().value();
}

}  // namespace

BatchTestFile read_batch_test(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw std::invalid_argument("--fit " + path.string() + ": is a directory, not a file");
  if (!fs::exists(path, ec)) throw std::invalid_argument("--fit " + path.string() + ": no such file");
  toml::table top;
  try {
    top = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}:{}:{}: not valid TOML: {}", path.string(), e.source().begin.line,
                                            e.source().begin.column, e.description()));
  }
  const TestReader r(path.string());
  r.knows(top, "", {"title", "mill", "run", "sieve_mm", "holdup_kg", "noise_pp", "feed", "product"});
  BatchTestFile f;
  grind::BatchTest& t = f.test;
  f.title = text_key(top, r, "title");
  f.mill = text_key(top, r, "mill");
  f.run = text_key(top, r, "run");
  if (top.get("holdup_kg")) t.holdup_kg = r.number(top, "holdup_kg", "holdup_kg", 1e-6, 1e9, "kg > 0");
  if (top.get("noise_pp"))
    t.noise_pp = r.number(top, "noise_pp", "noise_pp", 0, 20, "percentage points, 0 to 20");

  const std::vector<double> sieve = r.numbers(top, "sieve_mm", "sieve_mm");
  const toml::node* sn = top.get("sieve_mm");
  if (sieve.size() < 2) r.fail("sieve_mm", sn, "needs at least two sieves");
  for (std::size_t k = 0; k < sieve.size(); ++k) {
    if (!(sieve[k] > 0)) r.fail("sieve_mm", sn, fmt::format("sieve {} is {:g} mm: sizes must be > 0", k + 1, sieve[k]));
    if (k > 0 && !(sieve[k] < sieve[k - 1]))
      r.fail("sieve_mm", sn,
             fmt::format("{:g} mm does not follow {:g} mm: sieves must descend, coarsest first", sieve[k], sieve[k - 1]));
    t.sieve_m.push_back(sieve[k] * 1e-3);
  }
  const double slack = 2 * t.noise_pp / 100;  // two readings, each off by the noise

  // One row of cumulative passing at the sieves: in 0..1, not rising toward
  // the finer sieves beyond the noise.
  auto row = [&](const toml::table& tab, const std::string& name) {
    const std::vector<double> p = r.numbers(tab, "passing", name);
    const toml::node* n = tab.get("passing");
    if (p.size() != sieve.size())
      r.fail(name, n, fmt::format("holds {} values for {} sieves in sieve_mm", p.size(), sieve.size()));
    for (std::size_t k = 0; k < p.size(); ++k) {
      if (!(p[k] >= 0 && p[k] <= 1))
        r.fail(name, n, fmt::format("{:g} at {:g} mm: each passing must be in 0..1", p[k], sieve[k]));
      if (k > 0 && p[k] > p[k - 1] + slack)
        r.fail(name, n,
               fmt::format("{:g} at {:g} mm above {:g} at {:g} mm: passing must not rise as the sieves get finer "
                           "(beyond twice noise_pp)",
                           p[k], sieve[k], p[k - 1], sieve[k - 1]));
    }
    return p;
  };

  const toml::node* fn = top.get("feed");
  if (!fn) r.fail("feed", nullptr, "missing table [feed] (passing = the feed's cumulative passing at sieve_mm)");
  if (!fn->is_table()) r.fail("feed", fn, "must be a table, not " + type_name(*fn));
  const toml::table& feed = *fn->as_table();
  r.knows(feed, "feed.", {"passing"});
  t.feed_passing = row(feed, "feed.passing");
  if (std::fabs(t.feed_passing.front() - 1) > 1e-9)
    r.fail("feed.passing", feed.get("passing"),
           fmt::format("the coarsest sieve ({:g} mm) must pass all the feed (1), not {:g}", sieve.front(),
                       t.feed_passing.front()));

  const toml::node* pn = top.get("product");
  if (!pn) r.fail("product", nullptr, "missing: give each grinding time as [[product]] with time_min and passing");
  if (!pn->is_array_of_tables()) r.fail("product", pn, "must be an array of tables [[product]]");
  const toml::array& prods = *pn->as_array();
  std::size_t k = 0;
  for (const toml::node& e : prods) {
    ++k;
    const toml::table& p = *e.as_table();
    const std::string pre = fmt::format("product[{}].", k);
    r.knows(p, pre, {"time_min", "passing"});
    const double tm = r.number(p, "time_min", pre + "time_min", 1e-6, 1e6, "minutes > 0");
    if (!t.times_min.empty() && !(tm > t.times_min.back()))
      r.fail(pre + "time_min", p.get("time_min"),
             fmt::format("{:g} does not follow {:g}: grinding times must ascend", tm, t.times_min.back()));
    const std::vector<double> pass = row(p, pre + "passing");
    // Grinding only makes finer: passing does not fall with time.
    const std::vector<double>& before = t.passing.empty() ? t.feed_passing : t.passing.back();
    for (std::size_t s = 0; s < pass.size(); ++s)
      if (pass[s] < before[s] - slack)
        r.fail(pre + "passing", p.get("passing"),
               fmt::format("{:g} at {:g} mm after {:g} min is below the {:g} before it: passing must not fall with "
                           "grinding time (beyond twice noise_pp)",
                           pass[s], sieve[s], tm, before[s]));
    t.times_min.push_back(tm);
    t.passing.push_back(pass);
  }
  if (t.times_min.empty()) r.fail("product", pn, "needs at least one [[product]]");
  return f;
}

std::string batch_test_toml(const BatchTestFile& f) {
  const grind::BatchTest& t = f.test;
  std::string s = "# A batch grinding test (docs/grinding-fit.md): cumulative passing at each sieve,\n"
                  "# the feed and the product after each grinding time.\n";
  if (!f.title.empty()) s += fmt::format("title = \"{}\"\n", f.title);
  if (!f.mill.empty()) s += fmt::format("mill = \"{}\"\n", f.mill);
  if (!f.run.empty()) s += fmt::format("run = \"{}\"\n", f.run);
  if (t.holdup_kg > 0) s += fmt::format("holdup_kg = {:.10g}\n", t.holdup_kg);
  s += fmt::format("noise_pp = {:g}\n", t.noise_pp);
  // Sizes to 10 significant digits, passing to 10 decimals: a test written
  // from a model reads back to far below any sieving's scatter.
  auto list = [](const std::vector<double>& v, double scale, bool fixed) {
    std::string out = "[";
    for (std::size_t k = 0; k < v.size(); ++k)
      out += (k ? ", " : "") + (fixed ? fmt::format("{:.10f}", v[k] * scale) : fmt::format("{:.10g}", v[k] * scale));
    return out + "]";
  };
  s += "sieve_mm = " + list(t.sieve_m, 1e3, false) + "\n\n[feed]\npassing = " + list(t.feed_passing, 1, true) + "\n";
  for (std::size_t k = 0; k < t.times_min.size(); ++k)
    s += fmt::format("\n[[product]]\ntime_min = {:g}\npassing = {}\n", t.times_min[k], list(t.passing[k], 1, true));
  return s;
}

}  // namespace mc::io
