// The plot font built into the program (plot_font_data.cpp).
#pragma once

#include <cstddef>
#include <utility>

namespace mc::io {

// The bytes of the TrueType font the build embedded (DejaVu Sans), and
// their count.
std::pair<const unsigned char*, std::size_t> builtin_plot_font();

}  // namespace mc::io
