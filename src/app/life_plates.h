// The end plates of a life study (docs/liner-life.md#the-end-plates): what
// a stage's run booked on them (its wear.csv), their state in life.json,
// and life_plates.csv and life_plates.png. The arithmetic is life/plates.h's.
#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/life_state.h"
#include "io/json_read.h"
#include "life/plates.h"

namespace mc::app::life {

// The wear.csv rows of part "plate" (sliding wear at the case's
// coefficient and strike energy), `rings` × `sectors` per plate as the
// case cuts them; std::invalid_argument naming the file and the row where
// one is damaged, missing or booked twice.
mc::life::PlateBooks read_plate_books(const std::filesystem::path& wear_csv, int rings, int sectors);

// life.json's keys for them, and their strict reading (`rings` × `sectors`,
// finite and >= 0).
nlohmann::json plate_books_json(const mc::life::PlateBooks& b);
mc::life::PlateBooks plate_books_of(const io::JsonAt& sliding, const io::JsonAt& strike, int rings, int sectors);

// Two lists of `rings` values (per plate, z = 0 then z = length), each
// finite and >= 0.
std::array<std::vector<double>, 2> plate_rows_of(const io::JsonAt& a, int rings, double scale = 1);
nlohmann::json plate_rows_json(const std::array<std::vector<double>, 2>& v, double scale = 1);

// The bars' length in stage s (m): the mill's, and where the end plates
// have worn, the plates' depth at the shell on either end, where the bars
// and the shell reach into the dish (the runs book those contacts on them).
double bar_length(const Stage& s, double length);

// life_plates.csv: per stage, plate and ring its depth, its wear rate and
// standard error at the study's mix, and what the stage's step booked and
// removed (cm³). hours = case hours / factor; rates per those hours.
struct PlateTableBasis {
  double factor = 1;
  WearMix mix;
  double length = 0;  // m, where the second plate stands
  std::string basis;
};
void write_plate_table(const std::filesystem::path& out, const std::vector<Stage>& stages, const PlateTableBasis& b);

// life_plates.png: each plate's depth against the radius, a line per stage.
void write_plate_picture(const std::filesystem::path& file, const std::string& title, const std::vector<Stage>& stages,
                         const PlateTableBasis& b, bool relative);

}  // namespace mc::app::life
