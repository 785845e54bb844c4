// The plot font's bytes, built into the program so that no run depends on
// a font file the machine may lack (a headless server, a GPU image).
// MC_PLOT_FONT_FILE (CMakeLists.txt) names the TrueType file read at build
// time: DejaVu Sans from Debian's fonts-dejavu-core, whose licence allows
// it to be embedded and redistributed (docs/outputs.md, "Pictures").
#include "io/plot_font_data.h"

// .incbin copies the file into the object as it is assembled: no generated
// source of a few megabytes, and the bytes are the file's, exactly.
asm(".section .rodata\n"
    ".balign 16\n"
    "mc_plot_font_begin:\n"
    ".incbin \"" MC_PLOT_FONT_FILE "\"\n"
    "mc_plot_font_end:\n"
    ".previous\n");

extern "C" const unsigned char mc_plot_font_begin[];
extern "C" const unsigned char mc_plot_font_end[];

namespace mc::io {

std::pair<const unsigned char*, std::size_t> builtin_plot_font() {
  return {mc_plot_font_begin, static_cast<std::size_t>(mc_plot_font_end - mc_plot_font_begin)};
}

}  // namespace mc::io
