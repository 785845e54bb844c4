// Lifter bars from their profile, extruded along the mill (DESIGN.md,
// "World"): a trapezoid h × w × θ on the shell, or any convex outline given
// as points (a measured or a worn lifter).
#pragma once

#include <string>
#include <vector>

#include "core/vec.h"

namespace mc {

// Points of a polygon profile at most: the kernels' vertices of a bar
// (cl/layout.h MC_POLY_MAX_VERTS; the feet become the base's corners).
inline constexpr int kLifterMaxPoints = 16;
// Wear stations along a bar's exposed outline (cl/layout.h MC_WEAR_STATIONS).
inline constexpr int kWearStations = 32;

struct LifterProfile {
  double height = 0.05;      // radial, m
  double top_width = 0.05;   // m
  double face_angle_deg = 0; // of both faces from the radial line
  // A profile of any convex shape instead: its outline above the shell in
  // the bar's own frame, x along the shell's tangent at the bar's centre
  // (m, positive on the leading side, the face that lifts the charge), y the
  // height above that tangent (m). The first and last points are the feet,
  // on the shell (y = 0); in either direction. Empty: the trapezoid above.
  std::vector<Vec2> points;
  bool polygon() const { return !points.empty(); }
};

// The outline of a profile from its leading foot over the top to its
// trailing foot (counter-clockwise), in the bar's frame: a polygon profile's
// points in that order, or the trapezoid's four corners.
std::vector<Vec2> profile_outline(const LifterProfile& p);

// Why an outline (in the bar's frame) cannot be a lifter in a shell of
// radius R with room for a ball of diameter `room` above it, or "" when it
// can: fewer than 3 points, feet off the shell, points outside it, a bar
// reaching the axis (with a hint when the points look like millimetres),
// points that coincide, an outline that crosses itself or is not convex.
std::string profile_outline_fault(const std::vector<Vec2>& outline, double R, double room);

// What a plant measures on a lifter, from its outline (bar's frame):
// height, the top's width (the edges above half the height that face the
// axis more than the sides, across), each face's angle from the radial line
// (the chord of the face between 10 % and 90 % of the height; positive when
// the face lays back), and the cross-section's area above the shell.
struct ProfileMeasures {
  double height = 0, top_width = 0, leading_angle_deg = 0, trailing_angle_deg = 0, area = 0;
};
ProfileMeasures measure_profile(const std::vector<Vec2>& outline);

// Where the wear stations of a bar lie (cl/layout.h LifterPolygon.wear):
// the path along the polygon's edges from vertex `start`, and the exposed
// outline on it from `from` to `to` (m), where it leaves and re-enters the
// shell of radius R.
struct WearPath {
  int start = 0;
  double from = 0, to = 0;
};
WearPath lifter_wear_path(const std::vector<Vec2>& polygon, double R);

// A bar's faces by their place on its exposed outline, as lengths along its
// wear path (WearPath): the leading face from `from` to `top_from`, the top
// to `top_to`, the trailing face to `to`. The top is the run of edges round
// the summit that lie above half the bar's height and are flatter than 45°
// to the shell's tangent; a bar with no such edge (a triangle, a face laid
// back past 45° to a point) has as top the part above 90 % of its height.
// However far a face lays back it stays a face: the leading face always runs
// from the leading foot up to the top. `centre` is the direction of the bar's
// centre from the axis (unit), which sets its height above the shell.
struct FaceSplit {
  double from = 0, top_from = 0, top_to = 0, to = 0;
};
FaceSplit lifter_face_split(const std::vector<Vec2>& polygon, double R, Vec2 centre);

// The counter-clockwise cross-section of one bar centred at `angle` (rad) on a
// shell of inside radius `shell_radius`. The base lies just outside the shell
// so that no gap opens between bar and shell.
std::vector<Vec2> lifter_polygon(double shell_radius, const LifterProfile& p, double angle);

// `rows` bars evenly spaced from angle `first`, row k taking
// pattern[k % pattern.size()] (high/low alternation).
std::vector<std::vector<Vec2>> lifter_rows(double shell_radius, int rows,
                                           const std::vector<LifterProfile>& pattern,
                                           double first = 0.0);

// The bars of lifter_rows as closed triangle meshes from z = 0 to `length`:
// each bar's faces (its polygon's edges extruded) and its two end caps, every
// triangle facing out of the bar. What a CAD tool would export for the same
// liner (an STL of the parametric lifters). With max_edge > 0 (m), each
// face is cut into rows and columns of at most that size (the ends fanned
// from the bar's centroid through every point of its cut outline): a mesh
// fine enough for its wear to round a bar's edges (app/life_mesh.h).
std::vector<Triangle> lifter_triangles(const std::vector<std::vector<Vec2>>& bars, double length,
                                       double max_edge = 0);

// The bars cut where they enter the shell of radius R (the part behind the
// shell dropped; a chord closes each): the cross-sections a CAD model of
// lifters bolted to the shell has, for lifter_triangles.
std::vector<std::vector<Vec2>> bars_on_shell(const std::vector<std::vector<Vec2>>& bars, double R);

// Whether two convex polygons overlap by more than `tol` (m) across every
// separating direction: bars that meet as solids.
bool convex_polygons_overlap(const std::vector<Vec2>& a, const std::vector<Vec2>& b, double tol);

// Signed distance from (x, y) to a convex counter-clockwise polygon: negative
// inside. For packing and checks on the host (the kernels use cl/walls.h).
double polygon_signed_distance(const std::vector<Vec2>& poly, double x, double y);

}  // namespace mc
