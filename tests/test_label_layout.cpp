// The viewer's mark labels (src/viewer/label_layout.h): an impact point on
// the toe is labelled clear of the toe's label, and each stays in the
// picture.
#include <catch2/catch.hpp>

#include <cmath>

#include "viewer/label_layout.h"

using mc::viewer::LabelBox;
using mc::viewer::place_label;

TEST_CASE("a label whose mark lies on another's moves out along its ray, clear of it", "[viewer][labels]") {
  // A mill of 300 px radius about (800, 400); the marks at 1.27 R (toe,
  // shoulder) and 1.42 R (impact); labels 60 x 14 px.
  const float cx = 800, cy = 400, R = 300;
  auto ray = [&](float deg) {
    return [=](float r) {
      const float a = deg * 3.14159265f / 180;
      return std::pair<float, float>(cx + r * R * std::cos(a), cy - r * R * std::sin(a));
    };
  };
  for (float impact : {262.0f, 265.0f, 268.0f, 275.0f}) {
    INFO("toe 265, impact " << impact);
    std::vector<LabelBox> taken;
    const float r0 = mc::viewer::kMarkLabelRadius, dr = mc::viewer::kMarkLabelStep;
    taken.push_back(place_label(ray(265), 60, 14, r0, dr, 8, 362, 1278, 2, 798, {}));
    taken.push_back(place_label(ray(30), 80, 14, r0, dr, 8, 362, 1278, 2, 798, taken));
    // At the picture's bottom edge the toe's label is clamped: moving out
    // does nothing there, the label must move in.
    CHECK(taken[0].y1 == Approx(798));
    // Without the move, the impact label would cover the toe's.
    const LabelBox naive = place_label(ray(impact), 60, 14, r0, dr, 1, 362, 1278, 2, 798, {});
    if (std::fabs(impact - 265) < 5) CHECK(naive.overlaps(taken[0]));
    const LabelBox b = place_label(ray(impact), 60, 14, r0, dr, 8, 362, 1278, 2, 798, taken);
    CHECK_FALSE(b.overlaps(taken[0]));
    CHECK_FALSE(b.overlaps(taken[1]));
    CHECK(b.x0 >= 362);
    CHECK(b.x1 <= 1278);
    CHECK(b.y0 >= 2);
    CHECK(b.y1 <= 798);
  }
  // Clamped into the picture: a mark past its edge keeps its label inside.
  const LabelBox edge = place_label(ray(90), 60, 14, 2.0f, 0.07f, 8, 362, 1278, 2, 798, {});
  CHECK(edge.y0 == Approx(2));
}
