// millcharge view: a window on a running mill (DESIGN.md, "Command line").
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/mill_case.h"
#include "core/scene.h"

namespace mc::viewer {

struct ViewOptions {
  std::string device;          // --device
  int frames = 0;              // > 0: draw this many frames, then exit (scripted)
  std::string screenshot;      // PNG written after the last scripted frame
  int steps_per_frame = 0;     // > 0: fixed; 0: adapt (scripted: 40); < 0: adapt, scripted too
  std::string camera = "end";  // "end" (axial, orthographic) or "iso"
  std::string colour = "speed";  // speed, size, material, impact
  std::string liner = "plain";   // the liner: plain, impact (power) or wear (rate)
  int width = 1280, height = 800;
  bool panel = true;           // the ImGui panel on the left
  // Changes made as if from the panel before the given frame (0 = the first):
  // a --set KEY=VALUE applied to the case as it is then.
  std::vector<std::pair<long, std::string>> edits;
};

// Opens the window, settles the charge of `scene` (built from c and d) with
// the mill at rest, then turns it; returns when the window closes or the
// scripted frames are done. Throws std::runtime_error when no window opens
// and what the solver throws.
int run(const MillCase& c, const MillDerived& d, Scene scene, const ViewOptions& options);

}  // namespace mc::viewer
