// Words for TOML values in messages ("must be a number, not a string"),
// shared by the case and sweep readers; the file:line messages and the
// unknown-key check the ore and batch test readers share.
#pragma once

#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include <toml++/toml.h>

namespace mc::io {

inline std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    default: return "a date or time";
  }
}

// A TOML file's reader: "FILE:LINE: KEY: what" for every fault.
class TomlFileMessages {
 public:
  explicit TomlFileMessages(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void fail(const std::string& key, const toml::node* n, const std::string& what) const {
    std::string where = file_;
    if (n && n->source().begin.line > 0) where += ":" + std::to_string(n->source().begin.line);
    throw std::invalid_argument(where + ": " + key + ": " + what);
  }
  // Refuses the first key of t (named prefix + key) that is not in `keys`.
  void knows(const toml::table& t, const std::string& prefix, const std::set<std::string>& keys) const {
    for (const auto& [k, v] : t)
      if (!keys.count(std::string(k.str()))) {
        std::string list;
        for (const auto& x : keys) list += (list.empty() ? "" : ", ") + x;
        fail(prefix + std::string(k.str()), &v, "unknown key (known here: " + list + ")");
      }
  }

 private:
  std::string file_;
};

}  // namespace mc::io
