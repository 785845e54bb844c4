#include "io/sweep_file.h"

#include <toml++/toml.h>

#include "io/toml_names.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "io/case_file.h"

namespace mc::io {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxCases = 100000;

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}
  [[noreturn]] void fail(const std::string& key, const toml::node* n, const std::string& what) const {
    std::string where = source_;
    if (n && n->source().begin.line > 0) where += ":" + std::to_string(n->source().begin.line);
    throw SweepError(where + ": " + (key.empty() ? "" : key + ": ") + what);
  }
  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

// The shortest text that reads back as `v`; a TOML float keeps a point.
std::string float_text(double v, bool toml_float) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  if (toml_float && s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

// A scalar as an axis or `set` value, or nullopt for a table or array.
std::optional<SweepValue> scalar_value(const toml::node& n) {
  SweepValue v;
  if (auto i = n.as_integer()) {
    v.toml = v.text = std::to_string(i->get());
    v.numeric = true;
    v.number = static_cast<double>(i->get());
  } else if (auto f = n.as_floating_point()) {
    const double x = f->get();
    v.toml = float_text(x, true);
    v.text = float_text(x, false);
    v.numeric = std::isfinite(x);
    v.number = x;
  } else if (auto s = n.as_string()) {
    v.toml = quoted(s->get());
    v.text = s->get();
  } else if (auto b = n.as_boolean()) {
    v.toml = v.text = b->get() ? "true" : "false";
  } else {
    return std::nullopt;
  }
  return v;
}

// The leaves of a table of dotted keys ([set], [axes]): `mill.length = 0.1`
// and `"mill.length" = 0.1` both give the key "mill.length". A leaf is a
// node for which is_leaf() holds; other tables are walked into.
template <class IsLeaf>
void leaves(const toml::table& t, const std::string& prefix, IsLeaf is_leaf,
            std::vector<std::pair<std::string, const toml::node*>>& out) {
  for (auto&& [k, v] : t) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (v.is_table() && !is_leaf(v)) leaves(*v.as_table(), key, is_leaf, out);
    else out.emplace_back(key, &v);
  }
}

// File order: toml++ keeps a table's keys sorted, the source keeps the order
// the user wrote them in.
void sort_by_source(std::vector<std::pair<std::string, const toml::node*>>& v) {
  std::stable_sort(v.begin(), v.end(), [](const auto& a, const auto& b) {
    const auto &sa = a.second->source().begin, &sb = b.second->source().begin;
    return sa.line != sb.line ? sa.line < sb.line : sa.column < sb.column;
  });
}

double number_of(const Reader& r, const std::string& key, const toml::node* n) {
  if (!n || !(n->is_integer() || n->is_floating_point()))
    r.fail(key, n, n ? "expected a number, got " + type_name(*n) : "missing (a number is required)");
  const double v = *n->value<double>();
  if (!std::isfinite(v)) r.fail(key, n, "must be a finite number");
  return v;
}

// {from, to, step} or {from, to, count}: `to` included when the steps reach
// it (within a millionth of a step); integers stay integers.
std::vector<SweepValue> range_values(const Reader& r, const std::string& key, const toml::table& t) {
  for (auto&& [k, v] : t)
    if (k.str() != "from" && k.str() != "to" && k.str() != "step" && k.str() != "count")
      r.fail(key + "." + std::string(k.str()), &v, "unknown key in a range (expected from, to and step or count)");
  const double from = number_of(r, key + ".from", t.get("from"));
  const double to = number_of(r, key + ".to", t.get("to"));
  const bool has_step = t.contains("step"), has_count = t.contains("count");
  if (has_step == has_count) r.fail(key, &t, "a range needs from, to and exactly one of step and count");
  std::vector<double> xs;
  bool integers = t.get("from")->is_integer() && t.get("to")->is_integer();
  if (has_step) {
    const double step = number_of(r, key + ".step", t.get("step"));
    integers = integers && t.get("step")->is_integer();
    if (step == 0 || (to - from) * step < 0)
      r.fail(key + ".step", t.get("step"), "must be " + std::string(to >= from ? "> 0" : "< 0") + " to go from " +
                                               float_text(from, false) + " to " + float_text(to, false));
    const double n = std::floor((to - from) / step + 1e-6);
    if (n + 1 > kMaxCases) r.fail(key, &t, "more than " + std::to_string(kMaxCases) + " values");
    for (long i = 0; i <= static_cast<long>(n); ++i) xs.push_back(from + i * step);
  } else {
    const toml::node* cn = t.get("count");
    if (!cn->is_integer()) r.fail(key + ".count", cn, "expected an integer, got " + type_name(*cn));
    const long count = static_cast<long>(*cn->value<int64_t>());
    if (count < 1 || count > static_cast<long>(kMaxCases))
      r.fail(key + ".count", cn, "must be in [1, " + std::to_string(kMaxCases) + "]");
    if (count == 1 && from != to) r.fail(key + ".count", cn, "a count of 1 needs from = to");
    for (long i = 0; i < count; ++i) xs.push_back(count == 1 ? from : from + (to - from) * i / (count - 1));
    integers = integers && (count == 1 || std::fmod(to - from, count - 1) == 0);
  }
  std::vector<SweepValue> out;
  for (double x : xs) {
    SweepValue v;
    v.numeric = true;
    if (integers) {
      v.number = std::round(x);
      v.toml = v.text = std::to_string(static_cast<long long>(v.number));
    } else {
      // 12 significant digits: 0.5 + 2 × 0.1 is 0.7, not 0.7000000000000001.
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.12g", x);
      v.number = std::strtod(buf, nullptr);
      v.toml = float_text(v.number, true);
      v.text = float_text(v.number, false);
    }
    out.push_back(v);
  }
  return out;
}

bool is_range(const toml::node& n) {
  const toml::table* t = n.as_table();
  return t && (t->contains("from") || t->contains("to") || t->contains("step") || t->contains("count"));
}

std::vector<SweepValue> axis_values(const Reader& r, const std::string& key, const toml::node& n) {
  std::vector<SweepValue> out;
  if (const toml::array* a = n.as_array()) {
    if (a->empty()) r.fail("axes." + key, &n, "an axis needs at least one value");
    for (std::size_t i = 0; i < a->size(); ++i) {
      auto v = scalar_value(*a->get(i));
      if (!v) r.fail("axes." + key + "[" + std::to_string(i) + "]", a->get(i),
                     "expected a number, string or boolean, got " + type_name(*a->get(i)));
      out.push_back(*v);
    }
    if (out.size() > kMaxCases) r.fail("axes." + key, &n, "more than " + std::to_string(kMaxCases) + " values");
  } else if (is_range(n)) {
    out = range_values(r, "axes." + key, *n.as_table());
  } else {
    r.fail("axes." + key, &n,
           "expected a list of values, e.g. [0.6, 0.7], or a range, e.g. {from = 0, to = 30, step = 10}; got " +
               type_name(n));
  }
  return out;
}

// A folder name from the values: "speed_fraction=0.7,face_angle=10". Only
// characters that need no quoting anywhere; others become '_'.
std::string dir_name(const std::vector<std::string>& names, const std::vector<std::string>& values) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i) out += ",";
    out += names[i] + "=" + values[i];
  }
  for (char& ch : out)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '_' || ch == '-' || ch == '+' ||
          ch == '=' || ch == ','))
      ch = '_';
  if (out.size() > 200) out = out.substr(0, 200);
  return out;
}

}  // namespace

Sweep parse_sweep(const std::string& text, const fs::path& file) {
  const std::string source = file.string();
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::ostringstream m;
    m << source << ":" << e.source().begin.line << ":" << e.source().begin.column << ": not valid TOML: "
      << e.description();
    throw SweepError(m.str());
  }
  Reader r(source);
  Sweep s;
  s.file = file;
  static const std::set<std::string> known = {"name", "case", "combine", "zip", "device", "throughput",
                                              "set", "axes", "slurm", "command", "life"};
  for (auto&& [k, v] : root)
    if (!known.count(std::string(k.str())))
      r.fail(std::string(k.str()), &v,
             "unknown key (a sweep file has name, case, command, combine, zip, device, throughput, [set], [axes], "
             "[life] and [slurm]; case keys go in [set] or [axes])");

  auto string_key = [&](const char* k, const std::string& fallback) {
    const toml::node* n = root.get(k);
    if (!n) return fallback;
    if (!n->is_string()) r.fail(k, n, "expected a string, got " + type_name(*n));
    return *n->value<std::string>();
  };
  s.name = string_key("name", file.stem().string());
  if (s.name.empty() || s.name.find_first_of("/ \t\n") != std::string::npos)
    r.fail("name", root.get("name"), "must be a word without spaces or slashes (it names the Slurm job and the folder)");

  // The base case: beside the sweep file, else among the shipped cases.
  const toml::node* cn = root.get("case");
  if (!cn) r.fail("case", nullptr, "missing: the base case, e.g. case = \"lab.toml\"");
  const std::string case_text = string_key("case", "");
  fs::path base = case_text;
  if (base.is_relative()) {
    const fs::path beside = file.parent_path() / base;
    base = fs::exists(beside) || !fs::exists(case_dir() / base) ? beside : case_dir() / base;
  }
  std::error_code ec;
  if (!fs::is_regular_file(base, ec))
    r.fail("case", cn, "\"" + case_text + "\": no such case file (looked beside the sweep file and in " +
                           case_dir().string() + ")");
  s.base_case = fs::absolute(base).lexically_normal();

  s.device = string_key("device", "");
  s.command = string_key("command", "run");
  if (s.command != "run" && s.command != "life")
    r.fail("command", root.get("command"),
           "\"" + s.command + "\" is not one of \"run\" (each case a run) and \"life\" (each case a life study)");
  // [life]: the life options every study gets. Their names and values are
  // checked by the life command's own parser, case by case (app/sweep.cpp).
  if (const toml::node* n = root.get("life")) {
    if (!s.is_life())
      r.fail("life", n, "[life] holds a life study's options: give command = \"life\" too");
    if (!n->is_table()) r.fail("life", n, "expected a table [life] of life options, got " + type_name(*n));
    std::vector<std::pair<std::string, const toml::node*>> keys;
    leaves(*n->as_table(), "", [](const toml::node&) { return false; }, keys);
    sort_by_source(keys);
    for (auto& [key, node] : keys) {
      auto v = scalar_value(*node);
      if (!v) r.fail("life." + key, node, "expected a value, got " + type_name(*node));
      SweepLifeOption o;
      o.key = key;
      std::replace(o.key.begin(), o.key.end(), '_', '-');
      o.value = *v;
      o.line = static_cast<int>(node->source().begin.line);
      s.life.push_back(o);
    }
  }
  if (s.is_life() && s.life.empty())
    r.fail("life", nullptr, "command = \"life\" needs a table [life] with the studies' options, e.g. stages = 8 "
                            "and hours = 16000");
  if (const toml::node* n = root.get("throughput")) {
    s.throughput = number_of(r, "throughput", n);
    if (!(s.throughput > 0)) r.fail("throughput", n, "must be > 0 particle-updates per second");
  }

  if (const toml::node* n = root.get("set")) {
    if (!n->is_table()) r.fail("set", n, "expected a table [set] of case keys, got " + type_name(*n));
    std::vector<std::pair<std::string, const toml::node*>> keys;
    leaves(*n->as_table(), "", [](const toml::node&) { return false; }, keys);
    sort_by_source(keys);
    for (auto& [key, node] : keys) {
      std::ostringstream value;
      if (auto v = scalar_value(*node)) value << v->toml;
      else if (const toml::array* a = node->as_array()) value << *a;
      else r.fail("set." + key, node, "expected a value, got " + type_name(*node));
      s.set.push_back(key + "=" + value.str());
    }
  }

  const toml::node* an = root.get("axes");
  if (!an) r.fail("axes", nullptr, "missing: a table [axes] with at least one case key and its values");
  if (!an->is_table()) r.fail("axes", an, "expected a table [axes], got " + type_name(*an));
  {
    std::vector<std::pair<std::string, const toml::node*>> keys;
    leaves(*an->as_table(), "", [](const toml::node& n) { return is_range(n); }, keys);
    sort_by_source(keys);
    if (keys.empty()) r.fail("axes", an, "no axes: give at least one case key with its values");
    for (auto& [key, node] : keys) {
      SweepAxis a;
      a.key = key;
      a.values = axis_values(r, key, *node);
      a.group = static_cast<int>(s.axes.size());
      if (key.rfind(kLifeAxisPrefix, 0) == 0) {
        if (!s.is_life())
          r.fail("axes." + key, node, "a life option varies in a sweep of life studies only: give command = \"life\"");
        std::string option = key.substr(std::string(kLifeAxisPrefix).size());
        std::replace(option.begin(), option.end(), '_', '-');
        a.key = kLifeAxisPrefix + option;
        for (const SweepLifeOption& o : s.life)
          if (o.key == option) r.fail("axes." + key, node, "is also in [life]; give it in one place");
      }
      for (const std::string& fixed : s.set)
        if (fixed.substr(0, fixed.find('=')) == key)
          r.fail("axes." + key, node, "is also in [set]; give it in one place");
      std::set<std::string> seen;
      for (const SweepValue& v : a.values)
        if (!seen.insert(v.toml).second) r.fail("axes." + key, node, "the value " + v.text + " is listed twice");
      s.axes.push_back(std::move(a));
    }
  }

  const std::string combine = string_key("combine", "cross");
  if (combine != "cross" && combine != "zip")
    r.fail("combine", root.get("combine"), "\"" + combine + "\" is not one of \"cross\", \"zip\"");
  s.zipped = combine == "zip";
  if (const toml::node* zn = root.get("zip")) {
    if (s.zipped) r.fail("zip", zn, "not needed with combine = \"zip\" (every axis is zipped)");
    const toml::array* groups = zn->as_array();
    if (!groups) r.fail("zip", zn, "expected a list of lists of axis keys, e.g. [[\"a.b\", \"c.d\"]]");
    std::set<std::string> used;
    for (std::size_t g = 0; g < groups->size(); ++g) {
      const toml::array* keys = groups->get(g)->as_array();
      if (!keys || keys->size() < 2)
        r.fail("zip[" + std::to_string(g) + "]", groups->get(g), "expected a list of two or more axis keys");
      int group = -1;
      for (std::size_t i = 0; i < keys->size(); ++i) {
        const auto key = keys->get(i)->value<std::string>();
        auto it = key ? std::find_if(s.axes.begin(), s.axes.end(), [&](const SweepAxis& a) { return a.key == *key; })
                      : s.axes.end();
        if (it == s.axes.end())
          r.fail("zip[" + std::to_string(g) + "]", keys->get(i),
                 (key ? "\"" + *key + "\" is not" : std::string("expected")) + " a key of [axes]");
        if (!used.insert(*key).second) r.fail("zip", keys->get(i), "\"" + *key + "\" is in two groups");
        if (group < 0) group = it->group;
        else it->group = group;
      }
    }
  }
  if (s.zipped)
    for (SweepAxis& a : s.axes) a.group = 0;
  // Zipped axes have as many values each.
  std::map<int, const SweepAxis*> first_of;
  for (const SweepAxis& a : s.axes) {
    auto [it, fresh] = first_of.emplace(a.group, &a);
    if (!fresh && it->second->values.size() != a.values.size())
      r.fail("axes." + a.key, an,
             "has " + std::to_string(a.values.size()) + " values but zipped " + it->second->key + " has " +
                 std::to_string(it->second->values.size()) + "; zipped axes run together and need as many values");
  }
  double count = 1;
  for (auto& [g, a] : first_of) count *= static_cast<double>(a->values.size());
  if (count > kMaxCases)
    r.fail("axes", an, "the axes make " + float_text(count, false) + " cases, more than " + std::to_string(kMaxCases));

  if (const toml::node* sn = root.get("slurm")) {
    const toml::table* t = sn->as_table();
    if (!t) r.fail("slurm", sn, "expected a table [slurm], got " + type_name(*sn));
    for (auto&& [k, v] : *t) {
      const std::string key = "slurm." + std::string(k.str());
      auto integer = [&](int lo, int hi) {
        if (!v.is_integer()) r.fail(key, &v, "expected an integer, got " + type_name(v));
        const int64_t x = *v.value<int64_t>();
        if (x < lo || x > hi) r.fail(key, &v, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        return static_cast<int>(x);
      };
      auto text = [&] {
        if (!v.is_string()) r.fail(key, &v, "expected a string, got " + type_name(v));
        return *v.value<std::string>();
      };
      if (k.str() == "partition") s.slurm.partition = text();
      else if (k.str() == "time") {
        s.slurm.time = text();
        if (!slurm_time_valid(s.slurm.time))
          r.fail(key, &v, "\"" + s.slurm.time + "\" is not a Slurm time limit: expected " + kSlurmTimeForms);
      }
      else if (k.str() == "gpus_per_task") s.slurm.gpus_per_task = integer(0, 64);
      else if (k.str() == "cpus_per_task") s.slurm.cpus_per_task = integer(0, 4096);
      else if (k.str() == "max_running") s.slurm.max_running = integer(0, 100000);
      else if (k.str() == "signal_grace") s.slurm.signal_grace_s = integer(0, 65535);
      else if (k.str() == "sbatch_args") {
        const toml::array* a = v.as_array();
        if (!a) r.fail(key, &v, "expected a list of sbatch options, e.g. [\"--qos=long\"]");
        for (std::size_t i = 0; i < a->size(); ++i) {
          auto o = a->get(i)->value<std::string>();
          if (!o || o->rfind("--", 0) != 0)
            r.fail(key, a->get(i), "expected sbatch options as strings starting with --, e.g. \"--qos=long\"");
          s.slurm.sbatch_args.push_back(*o);
        }
      } else {
        r.fail(key, &v,
               "unknown key (slurm has partition, time, gpus_per_task, cpus_per_task, max_running, signal_grace, "
               "sbatch_args)");
      }
    }
  }
  return s;
}

bool slurm_time_valid(const std::string& t) {
  std::vector<std::string> fields;
  std::string days;
  std::string rest = t;
  if (const auto dash = t.find('-'); dash != std::string::npos) {
    days = t.substr(0, dash);
    rest = t.substr(dash + 1);
    if (days.empty() || days.find_first_not_of("0123456789") != std::string::npos) return false;
  }
  std::size_t from = 0;
  while (true) {
    const auto colon = rest.find(':', from);
    fields.push_back(rest.substr(from, colon == std::string::npos ? std::string::npos : colon - from));
    if (colon == std::string::npos) break;
    from = colon + 1;
  }
  if (fields.size() > 3) return false;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::string& f = fields[i];
    if (f.empty() || f.find_first_not_of("0123456789") != std::string::npos) return false;
    const bool leading = i == 0 && days.empty();
    if (!leading && (f.size() > 2 || std::stoi(f) >= (i == 0 ? 24 : 60))) return false;
    if (leading && f.size() > 9) return false;
  }
  return true;
}

Sweep read_sweep(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw SweepError(file.string() + ": no such sweep file");
  if (fs::is_directory(file, ec)) throw SweepError(file.string() + ": is a folder, not a sweep file");
  std::ifstream in(file, std::ios::binary);
  std::ostringstream buf;
  buf << in.rdbuf();
  if (!in && !in.eof()) throw SweepError(file.string() + ": cannot be read");
  if (buf.str().size() > (1u << 20)) throw SweepError(file.string() + ": larger than 1 MiB; not a sweep file");
  return parse_sweep(buf.str(), fs::absolute(file).lexically_normal());
}

std::vector<std::string> short_axis_names(const Sweep& s) {
  auto last = [](const std::string& key) {
    const std::size_t cut = key.find_last_of(".]");
    return cut == std::string::npos ? key : key.substr(cut + 1);
  };
  std::vector<std::string> out;
  for (const SweepAxis& a : s.axes) {
    int same = 0;
    for (const SweepAxis& b : s.axes) same += last(b.key) == last(a.key);
    out.push_back(same > 1 ? a.key : last(a.key));
  }
  return out;
}

std::vector<SweepCase> expand(const Sweep& s) {
  // Groups in the order of their first axis; a group's values by index.
  std::vector<int> groups;
  for (const SweepAxis& a : s.axes)
    if (std::find(groups.begin(), groups.end(), a.group) == groups.end()) groups.push_back(a.group);
  std::vector<std::size_t> sizes;
  for (int g : groups)
    for (const SweepAxis& a : s.axes)
      if (a.group == g) {
        sizes.push_back(a.values.size());
        break;
      }
  std::size_t total = 1;
  for (std::size_t n : sizes) total *= n;

  const std::vector<std::string> names = short_axis_names(s);
  std::vector<SweepCase> out;
  std::map<std::string, int> dirs;
  for (std::size_t k = 0; k < total; ++k) {
    // The last group changes fastest.
    std::vector<std::size_t> at(groups.size());
    std::size_t rest = k;
    for (std::size_t g = groups.size(); g-- > 0;) {
      at[g] = rest % sizes[g];
      rest /= sizes[g];
    }
    SweepCase c;
    c.index = static_cast<int>(k);
    c.overrides = s.set;
    for (const SweepLifeOption& o : s.life) c.life_args.push_back("--" + o.key + "=" + o.value.text);
    std::vector<std::string> texts;
    for (const SweepAxis& a : s.axes) {
      const std::size_t g = std::find(groups.begin(), groups.end(), a.group) - groups.begin();
      c.value_index.push_back(static_cast<int>(at[g]));
      if (a.key.rfind(kLifeAxisPrefix, 0) == 0)
        c.life_args.push_back("--" + a.key.substr(std::string(kLifeAxisPrefix).size()) + "=" + a.values[at[g]].text);
      else
        c.overrides.push_back(a.key + "=" + a.values[at[g]].toml);
      texts.push_back(a.values[at[g]].text);
    }
    c.dir = dir_name(names, texts);
    auto [it, fresh] = dirs.emplace(c.dir, c.index);
    if (!fresh)
      throw SweepError(s.file.string() + ": cases " + std::to_string(it->second) + " and " + std::to_string(c.index) +
                       " would share the folder cases/" + c.dir + " (" + case_label(s, c) +
                       "): zipped axes repeat a combination, or values differ only in characters a folder name "
                       "cannot hold");
    out.push_back(std::move(c));
  }
  return out;
}

std::string case_label(const Sweep& s, const SweepCase& c) {
  std::string out;
  for (std::size_t i = 0; i < s.axes.size(); ++i) {
    if (i) out += ", ";
    out += s.axes[i].key + "=" + s.axes[i].values[c.value_index[i]].text;
  }
  return out;
}

}  // namespace mc::io
