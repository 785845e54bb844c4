// Words for TOML values in messages ("must be a number, not a string"),
// shared by the case and sweep readers.
#pragma once

#include <string>

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

}  // namespace mc::io
