// millcharge view: the window on a case (viewer/viewer.h).
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>

#include "app/commands.h"
#include "app/prepare.h"
#include "viewer/viewer.h"

namespace mc::app {

int cmd_view(const ViewOptions& o) {
  Prepared p = prepare(o.c);
  viewer::ViewOptions v;
  v.device = o.c.device;
  v.frames = o.frames;
  v.screenshot = o.screenshot;
  v.steps_per_frame = o.steps_per_frame;
  v.camera = o.camera;
  v.colour = o.colour;
  v.liner = o.liner;
  v.width = o.width;
  v.height = o.height;
  v.panel = !o.no_panel;
  for (const std::string& e : o.edits) {
    const auto colon = e.find(':');
    char* end = nullptr;
    const long frame = colon == std::string::npos ? -1 : std::strtol(e.c_str(), &end, 10);
    if (colon == std::string::npos || end != e.c_str() + colon || frame < 0 || e.find('=', colon) == std::string::npos)
      throw std::invalid_argument("--edit " + e + ": expected FRAME:KEY=VALUE, e.g. --edit 100:charge.filling=0.35");
    v.edits.emplace_back(frame, e.substr(colon + 1));
  }
  if (!o.screenshot.empty() && o.frames <= 0)
    throw std::invalid_argument("--screenshot needs --frames N (the picture is taken after the last frame)");
  return viewer::run(p.c, p.d, std::move(p.scene), v);
}


}  // namespace mc::app
