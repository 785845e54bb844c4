// millcharge view: a window on a running mill (DESIGN.md, "Command line").
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "core/mill_case.h"
#include "core/scene.h"
#include "io/checkpoint.h"

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
  // view --from: the checkpoint of the run in `from_dir` to open on, its
  // case the one given to run(); the window turns on from its state.
  const io::Checkpoint* from = nullptr;
  std::string from_dir;
  // Scripted: the state after the last frame saved into this folder, as the
  // panel's "save state" saves it.
  std::string save_state_dir;
  // When the command began: the first frame's time is counted from it.
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
};

// Opens the window, settles the charge of `scene` (built from c and d) with
// the mill at rest, then turns it (with options.from: goes on from the
// checkpoint's state, settling or turning as the run was); returns when the
// window closes or the scripted frames are done. Throws std::runtime_error
// when no window opens, std::invalid_argument when the checkpoint's state
// does not fit the scene, and what the solver throws.
int run(const MillCase& c, const MillDerived& d, Scene scene, const ViewOptions& options);

}  // namespace mc::viewer
