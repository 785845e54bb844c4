#include "io/case_file.h"
#include "core/edit_distance.h"
#include "core/plate_wear.h"

#include <toml++/toml.h>

#include "io/stl.h"
#include "io/toml_names.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

namespace mc::io {

namespace {


// Reads one case: remembers where each key came from (file:line or the
// --set argument) so that every message can name it.
class Reader {
 public:
  Reader(std::string source, std::map<std::string, std::string> overridden)
      : source_(std::move(source)), overridden_(std::move(overridden)) {}

  std::string where(const std::string& key, const toml::node* n) const {
    auto it = overridden_.find(key);
    if (it != overridden_.end()) return "--set " + it->second;
    if (n && n->source().begin.line > 0) return source_ + ":" + std::to_string(n->source().begin.line);
    return source_;
  }
  [[noreturn]] void fail(const std::string& key, const toml::node* n, const std::string& what) const {
    throw CaseError(where(key, n) + ": " + key + ": " + what);
  }
  void remember(const std::string& key, const toml::node* n) { located_[key] = where(key, n); }
  std::string located(const std::string& key) const {
    // The key itself, else its nearest enclosing table that was read.
    std::string k = key;
    while (!k.empty()) {
      auto it = located_.find(k);
      if (it != located_.end()) return it->second;
      const std::size_t cut = k.find_last_of(".[");
      if (cut == std::string::npos) break;
      k = k.substr(0, cut);
    }
    return source_;
  }

 private:
  std::string source_;
  std::map<std::string, std::string> overridden_;
  std::map<std::string, std::string> located_;
};

// A message that begins with its key, without it (the reader adds it).
std::string without_key(const std::string& what, const std::string& key) {
  const std::string prefix = key + ": ";
  return what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what;
}

// One table of the case: typed getters that remember where each key is;
// knows() rejects the keys the table may not have.
class Section {
 public:
  Section(Reader& r, const toml::table& t, std::string path) : r_(r), t_(t), path_(std::move(path)) {}

  std::string key(const std::string& k) const { return path_.empty() ? k : path_ + "." + k; }
  bool has(const std::string& k) const { return t_.contains(k); }

  const toml::node* node(const std::string& k) {
    const toml::node* n = t_.get(k);
    if (n) r_.remember(key(k), n);
    return n;
  }

  double number(const std::string& k, std::optional<double> fallback = std::nullopt) {
    const toml::node* n = node(k);
    if (!n) {
      if (fallback) return *fallback;
      r_.fail(key(k), &t_, "missing (a number is required)");
    }
    if (auto v = n->value<double>(); v && (n->is_floating_point() || n->is_integer())) {
      if (!std::isfinite(*v)) r_.fail(key(k), n, "must be a finite number");
      return *v;
    }
    r_.fail(key(k), n, "expected a number, got " + type_name(*n));
  }
  bool boolean(const std::string& k, bool fallback) {
    const toml::node* n = node(k);
    if (!n) return fallback;
    if (auto v = n->value<bool>(); v && n->is_boolean()) return *v;
    r_.fail(key(k), n, "expected true or false, got " + type_name(*n));
  }
  // Three numbers, e.g. [0.0, 0.0, 0.1].
  Vec3 vec3(const std::string& k, Vec3 fallback) {
    const toml::node* n = node(k);
    if (!n) return fallback;
    const toml::array* a = n->as_array();
    if (!a || a->size() != 3) r_.fail(key(k), n, "expected three numbers [x, y, z], got " + type_name(*n));
    double v[3];
    for (int i = 0; i < 3; ++i) {
      const auto x = (*a)[i].value<double>();
      if (!x || !((*a)[i].is_floating_point() || (*a)[i].is_integer()) || !std::isfinite(*x))
        r_.fail(key(k), n, "expected three finite numbers [x, y, z]");
      v[i] = *x;
    }
    return {v[0], v[1], v[2]};
  }
  // A number or the string "auto" (returned as −1).
  double number_or_auto(const std::string& k, double fallback) {
    const toml::node* n = node(k);
    if (!n) return fallback;
    if (auto s = n->value<std::string>()) {
      if (*s == "auto") return -1;
      r_.fail(key(k), n, "expected a number or \"auto\", got \"" + *s + "\"");
    }
    const double v = number(k);
    if (!(v >= 0)) r_.fail(key(k), n, "must be >= 0 or \"auto\"");
    return v;
  }
  long integer(const std::string& k, std::optional<long> fallback = std::nullopt) {
    const toml::node* n = node(k);
    if (!n) {
      if (fallback) return *fallback;
      r_.fail(key(k), &t_, "missing (an integer is required)");
    }
    if (auto v = n->value<int64_t>(); v && n->is_integer()) return static_cast<long>(*v);
    r_.fail(key(k), n, "expected an integer, got " + type_name(*n));
  }
  // A random seed: an integer in [0, 2^32), 1 when absent.
  std::uint32_t seed(const std::string& k) {
    const long v = integer(k, 1);
    if (v < 0 || v > 0xffffffffL) r_.fail(key(k), node(k), "must be in [0, 2^32)");
    return static_cast<std::uint32_t>(v);
  }
  std::string string(const std::string& k, std::optional<std::string> fallback = std::nullopt,
                     const std::vector<std::string>& choices = {}) {
    const toml::node* n = node(k);
    if (!n) {
      if (fallback) return *fallback;
      r_.fail(key(k), &t_, "missing (a string is required)");
    }
    auto v = n->value<std::string>();
    if (!v) r_.fail(key(k), n, "expected a string, got " + type_name(*n));
    if (!choices.empty() && std::find(choices.begin(), choices.end(), *v) == choices.end()) {
      std::string list;
      for (const auto& c : choices) list += (list.empty() ? "\"" : ", \"") + c + "\"";
      r_.fail(key(k), n, "\"" + *v + "\" is not one of " + list);
    }
    return *v;
  }
  const toml::table* table(const std::string& k, bool required) {
    const toml::node* n = node(k);
    if (!n) {
      if (required) r_.fail(key(k), &t_, "missing table [" + key(k) + "]");
      return nullptr;
    }
    if (!n->is_table()) r_.fail(key(k), n, "expected a table, got " + type_name(*n));
    return n->as_table();
  }
  // An array of tables ([[k]]); empty when absent.
  std::vector<const toml::table*> tables(const std::string& k) {
    std::vector<const toml::table*> out;
    const toml::node* n = node(k);
    if (!n) return out;
    if (const toml::table* t = n->as_table()) {  // a single [k] table is one entry
      out.push_back(t);
      return out;
    }
    const toml::array* a = n->as_array();
    if (!a) r_.fail(key(k), n, "expected an array of tables [[" + key(k) + "]], got " + type_name(*n));
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::node* e = a->get(i);
      if (!e->is_table())
        r_.fail(key(k) + "[" + std::to_string(i) + "]", e, "expected a table, got " + type_name(*e));
      out.push_back(e->as_table());
    }
    return out;
  }
  std::string path() const { return path_; }
  const toml::node* self_node() const { return &t_; }

  // Keys this section understands: any other key is an error now, before a
  // missing required key is reported (a typo names itself, with a hint).
  Section& knows(std::initializer_list<const char*> keys) {
    const std::set<std::string> known(keys.begin(), keys.end());
    for (auto&& [k, v] : t_) {
      const std::string name(k.str());
      if (known.count(name)) continue;
      std::string best;
      std::size_t best_d = 3;
      for (const auto& u : known)
        if (std::size_t dd = edit_distance(name, u); dd < best_d) best_d = dd, best = u;
      r_.fail(key(name), &v, "unknown key" + (best.empty() ? std::string() : " (did you mean \"" + best + "\"?)"));
    }
    return *this;
  }

 private:
  Reader& r_;
  const toml::table& t_;
  std::string path_;
};

// "charge.size.0.fraction" or "charge.size[0].fraction" → segments.
std::vector<std::string> split_key(const std::string& key) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : key) {
    if (ch == '.' || ch == '[' || ch == ']') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += ch;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

bool is_index(const std::string& s) {
  return !s.empty() && s.size() < 7 && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// toml++ 3.3 (Debian 12's) reaches a TOML_UNREACHABLE, undefined behaviour,
// in is_non_ascii_horizontal_whitespace() for most non-ASCII characters where
// it expects whitespace or a value (found by fuzz/fuzz_case_file.cpp: "2.ƚ11").
// TOML allows non-ASCII text only inside strings and comments, and never right
// after a backslash, so such a byte is refused here, before toml++ sees it.
void refuse_stray_non_ascii(std::string_view t, const std::string& source) {
  auto fail_at = [&](std::size_t i, const char* where) {
    std::size_t line = 1, line_start = 0;
    for (std::size_t k = 0; k < i; ++k)
      if (t[k] == '\n') ++line, line_start = k + 1;
    std::size_t col = 1;
    for (std::size_t k = line_start; k < i; ++k)
      if ((static_cast<unsigned char>(t[k]) & 0xC0) != 0x80) ++col;
    // The character as U+XXXX when it is valid UTF-8, else the byte.
    const auto b = [&](std::size_t k) { return k < t.size() ? static_cast<unsigned char>(t[k]) : 0u; };
    unsigned cp = 0;
    int len = 0;
    if ((b(i) & 0xE0) == 0xC0) cp = b(i) & 0x1F, len = 2;
    else if ((b(i) & 0xF0) == 0xE0) cp = b(i) & 0x0F, len = 3;
    else if ((b(i) & 0xF8) == 0xF0) cp = b(i) & 0x07, len = 4;
    for (int k = 1; k < len; ++k) {
      if ((b(i + k) & 0xC0) != 0x80) {
        len = 0;
        break;
      }
      cp = cp << 6 | (b(i + k) & 0x3F);
    }
    char what[64];
    if (len > 0) std::snprintf(what, sizeof what, "character U+%04X", cp);
    else std::snprintf(what, sizeof what, "byte 0x%02X (not UTF-8)", b(i));
    throw CaseError(source + ":" + std::to_string(line) + ":" + std::to_string(col) + ": not valid TOML: " + what +
                    " " + where);
  };
  enum { code, comment, basic, literal, ml_basic, ml_literal } st = code;
  const std::size_t n = t.size();
  auto at = [&](std::size_t i, const char* s) { return t.compare(i, std::strlen(s), s) == 0; };
  // At a closing delimiter of a multi-line string: up to two more quotes
  // belong to the string; returns the index of the last quote.
  auto close_run = [&](std::size_t i, char q) {
    std::size_t j = i;
    while (j < n && t[j] == q && j - i < 5) ++j;
    return j - 1;
  };
  // A quote opens a string only where TOML allows one: a key at the start of
  // a line or after '.', '{' or ',', a value after '=', '[' or ','. Anywhere
  // else ("8n'...") the document is invalid anyway, and toml++ may read on
  // past the quote, so what follows is checked as outside a string.
  char prev = '\n';
  std::size_t i = 0;
  if (at(0, "\xEF\xBB\xBF")) i = 3;  // a UTF-8 byte order mark
  for (; i < n; ++i) {
    const unsigned char ch = static_cast<unsigned char>(t[i]);
    switch (st) {
      case code: {
        if (ch >= 0x80) fail_at(i, "outside a string or comment");
        const bool may_open = prev == '=' || prev == '[' || prev == ',' || prev == '{' || prev == '.' || prev == '\n';
        if (ch == '#') st = comment;
        else if (may_open && at(i, "\"\"\"")) st = ml_basic, i += 2;
        else if (may_open && at(i, "'''")) st = ml_literal, i += 2;
        else if (may_open && ch == '"') st = basic;
        else if (may_open && ch == '\'') st = literal;
        if (ch != ' ' && ch != '\t' && ch != '\r') prev = static_cast<char>(ch);
        break;
      }
      case comment:
        if (ch == '\n') st = code, prev = '\n';
        break;
      case basic:
      case ml_basic:
        if (ch == '\\') {
          std::size_t j = i + 1;
          if (st == ml_basic)
            while (j < n && (t[j] == ' ' || t[j] == '\t')) ++j;
          if (j < n && static_cast<unsigned char>(t[j]) >= 0x80) fail_at(j, "after a backslash");
          if (j < n && t[j] != '\n' && t[j] != '\r') i = j;  // skip the escaped character
        } else if (st == basic && (ch == '"' || ch == '\n')) {
          st = code, prev = static_cast<char>(ch);
        } else if (st == ml_basic && at(i, "\"\"\"")) {
          i = close_run(i, '"');
          st = code, prev = '"';
        }
        break;
      case literal:
        if (ch == '\'' || ch == '\n') st = code, prev = static_cast<char>(ch);
        break;
      case ml_literal:
        if (at(i, "'''")) {
          i = close_run(i, '\'');
          st = code, prev = '\'';
        }
        break;
    }
  }
}

// Applies one --set to the parsed document; returns the canonical key.
std::string apply_override(toml::table& root, const std::string& arg) {
  const std::size_t eq = arg.find('=');
  if (eq == std::string::npos || eq == 0)
    throw CaseError("--set " + arg + ": expected KEY=VALUE, e.g. --set mill.speed_fraction=0.8");
  const std::string key = arg.substr(0, eq), text = arg.substr(eq + 1);
  const auto parts = split_key(key);
  if (parts.empty()) throw CaseError("--set " + arg + ": empty key");

  toml::table value_doc;
  try {
    const std::string doc = "v = " + text;
    refuse_stray_non_ascii(doc, "--set");
    value_doc = toml::parse(std::string_view(doc), std::string_view("--set"));
  } catch (const toml::parse_error&) {
    value_doc = toml::table{{"v", text}};  // not TOML: a bare string
  } catch (const CaseError&) {
    value_doc = toml::table{{"v", text}};
  }
  toml::node& value = *value_doc.get("v");

  std::string canonical;
  toml::node* at = &root;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string& p = parts[i];
    const bool last = i + 1 == parts.size();
    if (toml::table* t = at->as_table()) {
      if (is_index(p)) throw CaseError("--set " + arg + ": " + canonical + " is a table, not an array");
      canonical += (canonical.empty() ? "" : ".") + p;
      if (last) {
        t->insert_or_assign(p, std::move(value));
        return canonical;
      }
      if (!t->contains(p)) t->insert(p, toml::table{});
      at = t->get(p);
    } else if (toml::array* a = at->as_array()) {
      if (!is_index(p)) throw CaseError("--set " + arg + ": " + canonical + " is an array: give an index, e.g. " + canonical + ".0");
      const std::size_t idx = std::stoul(p);
      if (idx >= a->size())
        throw CaseError("--set " + arg + ": " + canonical + " has " + std::to_string(a->size()) + " entries");
      canonical += "[" + p + "]";
      if (last) {
        a->replace(a->cbegin() + idx, std::move(value));
        return canonical;
      }
      at = a->get(idx);
    } else {
      throw CaseError("--set " + arg + ": " + canonical + " is a value, not a table");
    }
  }
  return canonical;
}

MillCase read_document(const toml::table& root, Reader& r, const std::string& name) {
  MillCase c;
  c.name = name;
  Section top(r, root, "");
  top.knows({"title", "mill", "lifters", "end_lifters", "liner", "walls", "charge", "materials", "contact", "run"});
  c.title = top.string("title", std::string());

  // [contact] first: the law decides which material keys are needed.
  {
    Section s(r, *top.table("contact", true), "contact");
    s.knows({"law", "restitution", "friction", "rolling_friction", "stiffness", "tangential_stiffness_ratio", "pair"});
    c.law = s.string("law", std::nullopt, {"linear", "hertz"}) == "hertz" ? ContactLaw::hertz : ContactLaw::linear;
    c.contact.restitution = s.number("restitution");
    c.contact.mu_slide = s.number("friction");
    c.contact.mu_roll = s.number("rolling_friction", 0.0);
    c.contact.kn = c.law == ContactLaw::linear ? s.number("stiffness") : s.number("stiffness", 1.0);
    c.contact.kt_over_kn = s.number("tangential_stiffness_ratio", 2.0 / 7.0);
    const auto pairs = s.tables("pair");
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      Section p(r, *pairs[k], "contact.pair[" + std::to_string(k) + "]");
      p.knows({"materials", "restitution", "friction", "rolling_friction", "stiffness", "tangential_stiffness_ratio"});
      PairOverride po;
      const toml::node* m = p.node("materials");
      const toml::array* ma = m ? m->as_array() : nullptr;
      if (!ma || ma->size() != 2 || !(*ma)[0].is_string() || !(*ma)[1].is_string())
        r.fail(p.key("materials"), m ? m : p.self_node(), "expected two material names, e.g. [\"steel\", \"ore\"]");
      po.a = *(*ma)[0].value<std::string>();
      po.b = *(*ma)[1].value<std::string>();
      po.interaction = c.contact;
      po.interaction.restitution = p.number("restitution", c.contact.restitution);
      po.interaction.mu_slide = p.number("friction", c.contact.mu_slide);
      po.interaction.mu_roll = p.number("rolling_friction", c.contact.mu_roll);
      po.interaction.kn = p.number("stiffness", c.contact.kn);
      po.interaction.kt_over_kn = p.number("tangential_stiffness_ratio", c.contact.kt_over_kn);
      c.pairs.push_back(po);
    }
  }
  {
    const toml::table* mt = top.table("materials", true);
    Section s(r, *mt, "materials");
    for (auto&& [k, v] : *mt) {
      const std::string mname(k.str());
      const toml::table* t = s.table(mname, true);
      Section m(r, *t, "materials." + mname);
      m.knows({"density", "youngs_modulus", "poisson_ratio", "wear_coefficient", "impact_wear_coefficient",
               "impact_wear_threshold_speed"});
      Material mat;
      mat.name = mname;
      mat.density = m.number("density");
      const bool hertz = c.law == ContactLaw::hertz;
      mat.youngs_modulus = hertz ? m.number("youngs_modulus") : m.number("youngs_modulus", 2.0e11);
      mat.poisson_ratio = hertz ? m.number("poisson_ratio") : m.number("poisson_ratio", 0.3);
      mat.wear_coefficient = m.number("wear_coefficient", kDefaultWearCoefficient);
      if (!(mat.wear_coefficient >= 0 && mat.wear_coefficient < 1e-6))
        r.fail("materials." + mname + ".wear_coefficient", m.node("wear_coefficient"),
               "must be in [0, 1e-6) m^3 per N per m slid (Archard's k over the hardness; about 1e-13 for liner steel)");
      mat.impact_wear_coefficient = m.number("impact_wear_coefficient", 0.0);
      if (!(mat.impact_wear_coefficient >= 0 && mat.impact_wear_coefficient < 1e-6))
        r.fail("materials." + mname + ".impact_wear_coefficient", m.node("impact_wear_coefficient"),
               "must be in [0, 1e-6) m^3 per J of strike energy (1 / the energy that removes a unit volume; 0: no "
               "impact wear)");
      mat.impact_wear_threshold_speed = m.number("impact_wear_threshold_speed", 0.0);
      if (!(mat.impact_wear_threshold_speed >= 0 && mat.impact_wear_threshold_speed < 100))
        r.fail("materials." + mname + ".impact_wear_threshold_speed", m.node("impact_wear_threshold_speed"),
               "must be in [0, 100) m/s (the approach speed below which a strike wears nothing)");
      c.materials.push_back(mat);
    }
    if (c.materials.empty()) r.fail("materials", mt, "define at least one material, e.g. [materials.steel]");
  }
  {
    Section s(r, *top.table("mill", true), "mill");
    s.knows({"diameter", "length", "ends", "cone_angle", "trunnion_diameter", "speed_fraction", "speed_rpm", "liner"});
    c.diameter = s.number("diameter");
    c.length = s.number("length");
    const std::string ends = s.string("ends", std::string("plates"), {"plates", "periodic", "cones"});
    c.periodic = ends == "periodic";
    if (ends == "cones") {
      c.ends.cone_angle_deg = s.number("cone_angle");
      if (!(c.ends.cone_angle_deg > 0 && c.ends.cone_angle_deg < 60))
        r.fail("mill.cone_angle", s.node("cone_angle"), "must be in (0, 60) degrees from the end plane");
      c.ends.trunnion_diameter = s.number("trunnion_diameter");
      if (!(c.ends.trunnion_diameter > 0))
        r.fail("mill.trunnion_diameter", s.node("trunnion_diameter"), "must be > 0 m");
    } else {
      for (const char* k : {"cone_angle", "trunnion_diameter"})
        if (s.has(k)) r.fail(std::string("mill.") + k, s.node(k), "only with mill.ends = \"cones\"");
    }
    const bool frac = s.has("speed_fraction"), rpm = s.has("speed_rpm");
    if (frac == rpm)
      r.fail(frac ? "mill.speed_rpm" : "mill.speed_fraction", frac ? s.node("speed_rpm") : s.self_node(),
             "give exactly one of speed_fraction (of critical) and speed_rpm");
    if (frac) {
      c.speed_fraction = s.number("speed_fraction");
      if (!(c.speed_fraction > 0)) r.fail("mill.speed_fraction", s.node("speed_fraction"), "must be > 0");
    } else {
      c.speed_rpm = s.number("speed_rpm");
      if (!(c.speed_rpm > 0)) r.fail("mill.speed_rpm", s.node("speed_rpm"), "must be > 0 rpm");
    }
    c.liner = s.string("liner");
  }
  if (const toml::table* lt = top.table("lifters", false)) {
    Section s(r, *lt, "lifters");
    s.knows({"rows", "first_angle", "profile"});
    const long rows = s.integer("rows");  // checked before the cast: 2^32 rows is not 0 rows
    if (rows < 0 || rows > 400) r.fail("lifters.rows", s.node("rows"), "must be in [0, 400]");
    c.lifter_rows = static_cast<int>(rows);
    c.lifter_first_angle_deg = s.number("first_angle", 0.0);
    const auto profiles = s.tables("profile");
    for (std::size_t k = 0; k < profiles.size(); ++k) {
      Section p(r, *profiles[k], "lifters.profile[" + std::to_string(k) + "]");
      p.knows({"height", "top_width", "face_angle", "points", "units"});
      LifterProfile lp;
      if (p.has("points")) {
        // A profile of any convex shape: its outline [x, y] from foot to foot
        // (core/lifters.h), in metres or millimetres.
        for (const char* k : {"height", "top_width", "face_angle"})
          if (p.has(k)) r.fail(p.key(k), p.node(k), "goes with h x w x theta profiles, not with points");
        const double unit = p.string("units", std::string("m"), {"m", "mm"}) == "mm" ? 1e-3 : 1.0;
        const toml::node* n = p.node("points");
        const toml::array* a = n->as_array();
        if (!a || a->empty()) r.fail(p.key("points"), n, "expected an array of points [x, y]");
        for (std::size_t q = 0; q < a->size(); ++q) {
          const toml::array* e = (*a)[q].as_array();
          const std::string at = p.key("points") + "[" + std::to_string(q) + "]";
          if (!e || e->size() != 2) r.fail(at, &(*a)[q], "expected two numbers [x, y]");
          double v[2];
          for (int i = 0; i < 2; ++i) {
            const auto x = (*e)[i].value<double>();
            if (!x || !((*e)[i].is_floating_point() || (*e)[i].is_integer()) || !std::isfinite(*x))
              r.fail(at, &(*a)[q], "expected two finite numbers [x, y]");
            v[i] = *x * unit;
          }
          lp.points.push_back({v[0], v[1]});
        }
      } else {
        if (p.has("units")) r.fail(p.key("units"), p.node("units"), "goes with points, not with h x w x theta profiles");
        lp.height = p.number("height");
        lp.top_width = p.number("top_width");
        lp.face_angle_deg = p.number("face_angle");
      }
      c.lifter_pattern.push_back(lp);
    }
  }
  if (const toml::table* et = top.table("end_lifters", false)) {
    Section s(r, *et, "end_lifters");
    s.knows({"rows", "height", "width", "inner_diameter"});
    const long rows = s.integer("rows");
    if (rows < 0 || rows > 400) r.fail("end_lifters.rows", s.node("rows"), "must be in [0, 400]");
    c.ends.lifter_rows = static_cast<int>(rows);
    if (rows > 0) {
      c.ends.lifter_height = s.number("height");
      c.ends.lifter_width = s.number("width");
      if (!(c.ends.lifter_height > 0)) r.fail("end_lifters.height", s.node("height"), "must be > 0 m");
      if (!(c.ends.lifter_width > 0)) r.fail("end_lifters.width", s.node("width"), "must be > 0 m");
    }
    c.ends.lifter_inner_diameter = s.number("inner_diameter", 0.0);
    if (!(c.ends.lifter_inner_diameter >= 0))
      r.fail("end_lifters.inner_diameter", s.node("inner_diameter"), "must be >= 0 m (0: the trunnion, or D/3)");
  }
  if (const toml::table* wt = top.table("walls", false)) {
    Section s(r, *wt, "walls");
    s.knows({"mesh"});
    const auto meshes = s.tables("mesh");
    for (std::size_t k = 0; k < meshes.size(); ++k) {
      Section m(r, *meshes[k], "walls.mesh[" + std::to_string(k) + "]");
      m.knows({"file", "units", "material", "turning", "part", "offset", "angle", "flip"});
      MeshSpec spec;
      spec.file = m.string("file");
      if (spec.file.empty()) r.fail(m.key("file"), m.node("file"), "must name an STL file");
      spec.units = m.string("units", std::string("m"), {"m", "mm"});
      spec.material = m.string("material", std::string());
      spec.turning = m.boolean("turning", true);
      const std::string part = m.string("part", std::string("lifters"), {"lifters", "shell", "ends"});
      spec.part = part == "shell" ? MeshPart::shell : part == "ends" ? MeshPart::ends : MeshPart::lifters;
      spec.offset = m.vec3("offset", Vec3{});
      spec.angle_deg = m.number("angle", 0.0);
      spec.flip = m.boolean("flip", false);
      c.meshes.push_back(spec);
    }
  }
  if (const toml::table* lt = top.table("liner", false)) {
    Section s(r, *lt, "liner");
    s.knows({"shell_bins", "smooth_shell_bins", "axial_bins", "plate_rings", "plate_sectors", "plate_depth_mm"});
    LinerGrid& g = c.liner_grid;
    auto bins = [&](const char* key, int fallback, long lo, long hi) {
      const long v = s.integer(key, fallback);
      if (v < lo || v > hi)
        r.fail(std::string("liner.") + key, s.node(key),
               "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]" + (lo == 0 ? " (0: auto)" : ""));
      return static_cast<int>(v);
    };
    g.shell_bins = bins("shell_bins", g.shell_bins, 1, 64);
    g.smooth_shell_bins = bins("smooth_shell_bins", g.smooth_shell_bins, 4, 720);
    g.axial_bins = bins("axial_bins", g.axial_bins, 0, 256);
    g.plate_rings = bins("plate_rings", g.plate_rings, 1, 64);
    g.plate_sectors = bins("plate_sectors", g.plate_sectors, 0, 720);
    // Worn end plates: [[z = 0 plate's rings, from the axis out], [z = length plate's]], mm.
    if (const toml::node* n = s.node("plate_depth_mm")) {
      const char* shape = "must be two lists (the plate at z = 0, then at z = length) of one depth (mm) per ring";
      const toml::array* a = n->as_array();
      if (!a || a->size() != 2) r.fail("liner.plate_depth_mm", n, shape);
      for (int p = 0; p < 2; ++p) {
        const toml::array* row = (*a)[p].as_array();
        if (!row) r.fail("liner.plate_depth_mm", n, shape);
        for (const toml::node& v : *row) {
          const std::optional<double> d = v.value<double>();
          if (!d) r.fail("liner.plate_depth_mm", n, shape);
          c.plate_depth[p].push_back(*d * 1e-3);
        }
      }
      const double length = c.periodic || c.ends.cones() ? 0.0 : c.length;
      const std::string why = check_plate_depths(c.plate_depth, g.plate_rings, 0.5 * c.diameter, length);
      if (!why.empty()) r.fail("liner.plate_depth_mm", n, why.substr(why[0] == ':' ? 2 : 0));
    }
  }
  {
    Section s(r, *top.table("charge", true), "charge");
    s.knows({"filling", "porosity", "fractions", "seed", "size", "shape"});
    c.filling = s.number("filling");
    c.porosity = s.number("porosity", 0.4);
    c.number_fractions = s.string("fractions", std::string("mass"), {"mass", "number"}) == "number";
    c.seed = s.seed("seed");
    // The case's own clump shapes: spheres [x, y, z, r] in any unit (the
    // shape is scaled to each size class's diameter).
    const auto shapes = s.tables("shape");
    for (std::size_t k = 0; k < shapes.size(); ++k) {
      Section z(r, *shapes[k], "charge.shape[" + std::to_string(k) + "]");
      z.knows({"name", "spheres", "ellipsoid", "count", "seed"});
      ClumpShape sh;
      sh.name = z.string("name");
      if (sh.name.empty() || sh.name == "sphere")
        r.fail(z.key("name"), z.node("name"), "a shape needs a name other than \"\" and \"sphere\"");
      {
        // A name of the library's would leave unsaid which of the two a
        // size class gets.
        const std::vector<std::string> library = library_shape_names();
        if (std::find(library.begin(), library.end(), sh.name) != library.end()) {
          std::string list;
          for (const std::string& n : library) list += (list.empty() ? "" : ", ") + n;
          r.fail(z.key("name"), z.node("name"),
                 "\"" + sh.name + "\" is a library shape's name (" + list +
                     "); give yours another name, e.g. \"" + sh.name + "_ore\"");
        }
      }
      for (const ClumpShape& o : c.shapes)
        if (o.name == sh.name) r.fail(z.key("name"), z.node("name"), "\"" + sh.name + "\" is defined twice");
      const bool listed = z.has("spheres"), filled = z.has("ellipsoid");
      if (listed && filled)
        r.fail(z.key("ellipsoid"), z.node("ellipsoid"),
               "give either spheres = [[x, y, z, radius], ...] or ellipsoid = [a, b, c], not both");
      if (filled) {
        // A rock: `count` spheres filling the ellipsoid of these axes (any
        // unit, any order), as the library's rock fills 1 : 0.8 : 0.6.
        const toml::node* n = z.node("ellipsoid");
        const Vec3 ax = z.vec3("ellipsoid", {});
        if (!(ax.x > 0 && ax.y > 0 && ax.z > 0))
          r.fail(z.key("ellipsoid"), n, "the three axes must be > 0");
        double a[3] = {ax.x, ax.y, ax.z};
        std::sort(a, a + 3, std::greater<double>());
        if (!(a[2] / a[0] > 0.2)) {
          std::ostringstream m;
          m << "the shortest axis must be more than 0.2 of the longest (got " << std::setprecision(3) << a[2] / a[0]
            << "): a flatter rock needs more spheres than a clump should carry";
          r.fail(z.key("ellipsoid"), n, m.str());
        }
        const long count = z.integer("count", 12);
        if (count < 2 || count > 64) r.fail(z.key("count"), z.node("count"), "must be in [2, 64]");
        const std::string name = sh.name;
        sh = rock_shape(static_cast<int>(count), a[1] / a[0], a[2] / a[0], z.seed("seed"));
        sh.name = name;
      } else {
        for (const char* k : {"count", "seed"})
          if (z.has(k))
            r.fail(z.key(k), z.node(k), "goes with ellipsoid = [a, b, c] (a rock filled with spheres), not with spheres");
        const toml::node* n = z.node("spheres");
        if (!n)
          r.fail(z.key("spheres"), z.self_node(),
                 "missing (an array of spheres [x, y, z, radius], or ellipsoid = [a, b, c], is required)");
        const toml::array* a = n->as_array();
        if (!a || a->empty())
          r.fail(z.key("spheres"), n, "expected an array of spheres [x, y, z, radius], at least one");
        for (std::size_t q = 0; q < a->size(); ++q) {
          const toml::array* e = (*a)[q].as_array();
          const std::string at = z.key("spheres") + "[" + std::to_string(q) + "]";
          if (!e || e->size() != 4) r.fail(at, &(*a)[q], "expected four numbers [x, y, z, radius]");
          double v[4];
          for (int i = 0; i < 4; ++i) {
            const auto x = (*e)[i].value<double>();
            if (!x || !((*e)[i].is_floating_point() || (*e)[i].is_integer()) || !std::isfinite(*x))
              r.fail(at, &(*a)[q], "expected four finite numbers [x, y, z, radius]");
            v[i] = *x;
          }
          sh.spheres.push_back({{v[0], v[1], v[2]}, v[3]});
        }
      }
      const toml::node* n = z.node(filled ? "ellipsoid" : "spheres");
      try {
        check_shape(sh, z.key("spheres"));
      } catch (const std::invalid_argument& e) {
        r.fail(z.key("spheres"), n, without_key(e.what(), z.key("spheres")));
      }
      c.shapes.push_back(sh);
    }
    const auto sizes = s.tables("size");
    if (sizes.empty()) r.fail("charge.size", s.self_node(), "the charge needs at least one [[charge.size]] class");
    for (std::size_t k = 0; k < sizes.size(); ++k) {
      Section z(r, *sizes[k], "charge.size[" + std::to_string(k) + "]");
      z.knows({"diameter", "diameter_min", "diameter_max", "material", "fraction", "shape"});
      SizeClass sc;
      const bool one = z.has("diameter"), range = z.has("diameter_min") || z.has("diameter_max");
      if (one == range)
        r.fail(z.key("diameter"), z.self_node(), "give either diameter or diameter_min and diameter_max");
      if (one) {
        sc.diameter_min = sc.diameter_max = z.number("diameter");
      } else {
        sc.diameter_min = z.number("diameter_min");
        sc.diameter_max = z.number("diameter_max");
      }
      sc.material = z.string("material");
      sc.fraction = z.number("fraction", sizes.size() == 1 ? std::optional<double>(1.0) : std::nullopt);
      sc.shape = z.string("shape", std::string());
      if (z.has("shape") && sc.shape.empty())
        r.fail(z.key("shape"), z.node("shape"),
               "an empty name: give \"sphere\" (balls), a library shape or a [[charge.shape]]'s name, or leave the "
               "key out for balls");
      if (sc.shape == "sphere") sc.shape.clear();
      if (!sc.shape.empty()) {
        try {
          size_class_shape(c, sc.shape, z.key("shape"));
        } catch (const std::invalid_argument& e) {
          r.fail(z.key("shape"), z.node("shape"), without_key(e.what(), z.key("shape")));
        }
      }
      c.sizes.push_back(sc);
    }
  }
  {
    Section s(r, *top.table("run", true), "run");
    s.knows({"duration", "tolerance", "max_duration", "warmup", "settle", "settle_damping", "dt", "steps_per_contact",
             "output_interval", "snapshot_interval", "checkpoint_interval", "precision"});
    if (const toml::node* n = s.node("duration"); n && n->is_string()) {
      const std::string v = *n->value<std::string>();
      if (v != "auto")
        r.fail("run.duration", n, "expected a number of seconds or \"auto\" (turn until the power converges), got \"" +
                                      v + "\"");
      c.duration_auto = true;
      c.duration = 0;
    } else {
      c.duration = s.number("duration");
    }
    c.tolerance = s.number("tolerance", 0.01);
    c.max_duration = s.number_or_auto("max_duration", -1);
    c.warmup = s.number("warmup", 0.0);
    c.settle = s.number_or_auto("settle", -1);
    c.settle_damping = s.number_or_auto("settle_damping", 0.0);
    const double dt = s.number_or_auto("dt", -1);
    if (dt == 0) r.fail("run.dt", s.node("dt"), "must be > 0 s or \"auto\"");
    c.dt = dt < 0 ? 0 : dt;
    c.steps_per_contact = s.number("steps_per_contact", 25.0);
    c.output_interval = s.number("output_interval", 0.01);
    c.snapshot_interval = s.number("snapshot_interval", 0.0);
    c.checkpoint_interval = s.number("checkpoint_interval", 0.5);
    c.precision =
        s.string("precision", std::string("float"), {"float", "double"}) == "double" ? Precision::double_ : Precision::single;
  }
  return c;
}

}  // namespace

MillCase parse_case(std::string_view text, const std::string& source, const std::vector<std::string>& overrides) {
  refuse_stray_non_ascii(text, source);
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::ostringstream m;
    m << source << ":" << e.source().begin.line << ":" << e.source().begin.column << ": not valid TOML: "
      << e.description();
    throw CaseError(m.str());
  }
  if (root.empty())
    throw CaseError(source + ": empty: a case needs the tables [mill], [charge], [materials], [contact] and [run] "
                             "(see assets/cases/lab.toml)");
  std::map<std::string, std::string> overridden;
  for (const std::string& o : overrides) overridden[apply_override(root, o)] = o;
  Reader r(source, overridden);
  std::string name = std::filesystem::path(source).stem().string();
  MillCase c = read_document(root, r, name);
  // The mesh walls' files, relative to the case file's folder.
  const std::filesystem::path base = std::filesystem::path(source).parent_path();
  for (std::size_t k = 0; k < c.meshes.size(); ++k) {
    MeshSpec& m = c.meshes[k];
    const std::string key = "walls.mesh[" + std::to_string(k) + "].file";
    std::filesystem::path p(m.file);
    if (p.is_relative()) p = base / p;
    p = p.lexically_normal();
    m.path = p.string();
    try {
      m.triangles = read_stl(p, m.units == "mm" ? 1e-3 : 1.0).triangles;
    } catch (const MeshError& e) {
      throw CaseError(r.located(key) + ": " + key + ": " + e.what());
    }
  }
  try {
    derive(c);
  } catch (const std::invalid_argument& e) {
    // derive() names the key first ("mill.diameter: ..."); add where it is.
    const std::string msg = e.what();
    const std::size_t colon = msg.find(": ");
    const std::string key = colon == std::string::npos ? "" : msg.substr(0, colon);
    throw CaseError(r.located(key) + ": " + msg);
  }
  return c;
}

MillCase read_case(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    throw CaseError(file.string() + ": no such case file (cases are in " + case_dir().string() + ")");
  if (std::filesystem::is_directory(file, ec)) throw CaseError(file.string() + ": is a folder, not a case file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CaseError(file.string() + ": cannot be read");
  std::ostringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  if (text.size() > (1u << 20)) throw CaseError(file.string() + ": larger than 1 MiB; not a case file");
  return parse_case(text, file.string(), overrides);
}

std::filesystem::path case_dir() {
  if (const char* env = std::getenv("MILLCHARGE_ASSET_DIR"); env && *env)
    return std::filesystem::path(env) / "cases";
  return std::filesystem::path(MC_ASSET_DIR) / "cases";
}

std::filesystem::path default_case() { return case_dir() / "lab.toml"; }

}  // namespace mc::io
