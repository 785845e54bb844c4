// The options of `millcharge life` (docs/liner-life.md), in one place for
// the command line and for a sweep of life studies (docs/sweeps.md, "Life
// studies side by side"), which gives each study its `[life]` options: the
// same names, the same checks, the same messages.
#pragma once

#include <nlohmann/json.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/prepare.h"

namespace CLI {
class App;
}

namespace mc::app {

// --out, --stages, --hours, ... --force, --quiet on the life command (its
// case options, CASE, --set, --device, are the commands' common ones).
void add_life_options(CLI::App* life, LifeOptions& o);

// The life options a sweep can give a study: every option of
// add_life_options but those the sweep sets itself (--out, --force,
// --quiet), without the dashes.
std::vector<std::string> sweep_life_option_names();

// A study's options from "--key=value" arguments, read by the life
// command's own parser and checks; std::invalid_argument naming the option
// where one is not a life option or its value is not valid.
LifeOptions life_options_from(const std::vector<std::string>& args);

// How the options go together and with the case, as `millcharge life`
// checks them before it writes anything (app/life.cpp); std::invalid_argument
// naming the option or key.
void check_life(const LifeOptions& o, const Prepared& base);

// The case a study wears: the given one, or with --axial-segments on bars
// of [lifters], the case with the bars as their mesh twin, whose file is
// new-bars.stl in `out` (life/bar_twin.h; `twin_edge_m` its triangles'
// size, else 0). What a twin cannot do is refused here, before it is made;
// nothing is written.
Prepared life_base(const LifeOptions& o, const Prepared& given, const std::filesystem::path& out,
                   double* twin_edge_m);

// The request a study records in life.json and resumes only with the same
// (app/life.cpp), of the case life_base gave and its twin's size; a sweep
// compares a case folder's study with it.
nlohmann::json life_request(const LifeOptions& o, const Prepared& base, double twin_edge_m);

}  // namespace mc::app
