// The energy books of a run on disk: spectra.csv and wear.csv, the
// `spectra` and `liner` blocks of summary.json, and the liner as a ParaView
// mesh with its sums per cell (liner.vtp and one per snapshot, turned to the
// mill's angle then). Pictures are in io/png_plot.h.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/liner.h"
#include "io/vtk.h"
#include "sim/energy_report.h"

namespace mc::io {

// Throw std::runtime_error when the file cannot be written.
void write_spectra_csv(const std::filesystem::path& path, const SpectraReport& r);
void write_wear_csv(const std::filesystem::path& path, const LinerLayout& layout, const LinerReport& r);
// lifter_wear.csv: each lifter profile's wear stations, foot to foot.
// With `halves` (the stations over the window's first and second halves,
// or empty), each station's sliding wear and strike energy in each half.
void write_lifter_wear_csv(const std::filesystem::path& path, const std::vector<LifterStation>& stations,
                           const std::vector<std::vector<LifterStation>>& halves = {});

nlohmann::ordered_json spectra_json(const SpectraReport& r);
nlohmann::ordered_json liner_json(const LinerLayout& layout, const LinerReport& r, const Material& liner);
// summary.json's `per_metre` block: a run's power, torque, collisions and
// liner sums over its length (a periodic slice's, or a whole mill's between
// its end plates), per metre of mill.
nlohmann::ordered_json per_metre_json(double length_m, double torque_power_W, double dissipation_power_W,
                                      double torque_Nm, const SpectraReport& spectra, const LinerReport& liner);

// The liner's elements as polygons turned by `mill_angle` (rad) about +z
// into the lab frame, with the report's rates per cell (a null report: the
// geometry with zeros).
PolyMesh liner_mesh(const LinerLayout& layout, const LinerReport* r, double mill_angle, double time_s);

// spectra.png: the power of the collisions up to an energy per collision
// (cumulative, log axis), a line per pair type and for all, and below it the
// collision rate per bin.
void write_spectra_png(const std::filesystem::path& path, const std::string& title, const SpectraReport& r);

// liner.png (`relative`: wear at the default stand-in coefficient, said
// so on its wear axes): the liner unrolled (mill-frame angle × axial position), impact
// power and wear rate per element with the lifter rows outlined, and the
// mean wear of each part.
void write_liner_png(const std::filesystem::path& path, const std::string& title, const LinerLayout& layout,
                     const LinerReport& r, bool relative = false);

// "shell gap 3 bin 1, axial 2" and the like.
std::string element_name(const LinerLayout& layout, int element);

}  // namespace mc::io
