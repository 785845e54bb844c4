// Where the picture's labels go (toe, shoulder, impact point): each beside
// its mark, inside the picture, and clear of the labels already placed. A
// pure function of pixels, so the tests hold it without a window.
#pragma once

#include <algorithm>
#include <functional>
#include <vector>

namespace mc::viewer {

// The mark labels' first radius, in shell radii (outside the marks'
// wedges, which reach 1.36 R), and their step along the ray.
inline constexpr float kMarkLabelRadius = 1.45f;
inline constexpr float kMarkLabelStep = 0.07f;

struct LabelBox {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixels
  bool overlaps(const LabelBox& o, float gap_x = 4, float gap_y = 2) const {
    return !(x1 + gap_x < o.x0 || o.x1 < x0 - gap_x || y1 + gap_y < o.y0 || o.y1 < y0 - gap_y);
  }
};

// A w × h label centred on at(radius) (its mark's ray, in pixels), clamped
// into [x_min, x_max] × [y_min, y_max]; where it would cover one of
// `taken`, tried again along the ray, `step` further out, then as far in,
// then two steps out, ... (in as well as out: near the picture's edge the
// clamp holds a label that moves out where it was), up to `tries` places;
// the last stays where it is.
inline LabelBox place_label(const std::function<std::pair<float, float>(float)>& at, float w, float h, float radius,
                            float step, int tries, float x_min, float x_max, float y_min, float y_max,
                            const std::vector<LabelBox>& taken) {
  LabelBox b;
  for (int k = 0; k < tries; ++k) {
    const float r = radius + step * static_cast<float>(k % 2 == 1 ? (k + 1) / 2 : -(k / 2));
    const auto [px, py] = at(r);
    b.x0 = std::clamp(px - 0.5f * w, x_min, std::max(x_min, x_max - w));
    b.y0 = std::clamp(py - 0.5f * h, y_min, std::max(y_min, y_max - h));
    b.x1 = b.x0 + w, b.y1 = b.y0 + h;
    bool clear = true;
    for (const LabelBox& t : taken) clear = clear && !b.overlaps(t);
    if (clear) break;
  }
  return b;
}

}  // namespace mc::viewer
