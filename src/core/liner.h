// The liner as surface elements in the mill frame: the shell between two
// lifter rows in angular bins over its bare arc, each lifter row's leading
// face, top and trailing face, both in axial bins, and the end plates in
// rings and sectors (none in a periodic slice). The force kernels sum
// impacts, impact and shear energy and wear on these elements (cl/books.h,
// in the same order); the outputs and the viewer draw them. Also the
// spectra's pair types. No OpenCL.
#pragma once

#include <string>
#include <vector>

#include "core/scene.h"

namespace mc {

enum class LinerPart { shell, lifter, plate, mesh };

// Lifter faces in element order (cl/layout.h MC_FACE_*).
enum class LifterFace { leading = 0, top = 1, trailing = 2 };

struct LinerElement {
  LinerPart part = LinerPart::shell;
  int row = 0;      // shell: the gap from row `row` to the next; lifter: its row; plate: 0 (z = 0) or 1;
                    // mesh: the mesh (Walls::meshes)
  int bin = 0;      // shell: angular bin in the gap; lifter: the face (LifterFace); plate: ring;
                    // mesh: the triangle in its mesh
  int sector = 0;   // plate: sector
  int axial = 0;    // shell and lifter: axial bin
  double area_m2 = 0;
  double density = 0;  // kg/m³ of its material, for wear in kg (0: the liner's)
  double impact_wear_coefficient = -1;  // m³/J of its material (< 0: the liner's)
  bool still = false;  // a mesh triangle that stands still (its outline in the lab frame)
  // Where it lies, mill frame: angles (rad, counter-clockwise from +x at
  // mill angle 0), axial span, radii.
  double theta0 = 0, theta1 = 0, z0 = 0, z1 = 0, r0 = 0, r1 = 0;
  // Its outline for drawing: a polygon in the mill frame, ordered
  // counter-clockwise as seen from the charge.
  std::vector<Vec3> outline;
};

struct LinerLayout {
  double shell_radius = 0, length = 0;
  int n_lifters = 0;
  int shell_bins = 0;    // per gap (or around a smooth shell)
  int axial_bins = 1;
  int plate_rings = 1, plate_sectors = 1;
  int first_lifter = 0;  // index of the first lifter element
  int first_plate = 0;
  int first_mesh = 0;    // the mesh triangles, one element each, in the device order (core/wall_mesh.h)
  std::vector<double> lifter_centre;      // rad, mill frame
  std::vector<double> lifter_half_angle;  // rad: half the arc the bar covers on the shell
  // rad from the row's centre to where the bar meets the shell, ahead
  // (counter-clockwise, its leading foot) and behind: a worn bar's are unequal.
  std::vector<double> lifter_lead_angle, lifter_trail_angle;
  std::vector<LinerElement> elements;
  int size() const { return static_cast<int>(elements.size()); }
};

LinerLayout liner_layout(const Scene& scene);

// The angles (rad) from a bar's row centre `centre` (rad) to where its
// cross-section meets a shell of radius R: ahead (counter-clockwise) and
// behind (signed: a bar wholly ahead of its centre has a negative trail);
// the bar covers lead + trail of the shell.
struct FootAngles {
  double lead = 0, trail = 0;
};
FootAngles lifter_foot_angles(const std::vector<Vec2>& polygon, double shell_radius, double centre);

// The spectra's pair types: each pair of ball materials (a <= b), then per
// ball material its contacts with the shell, the lifters and the end plates
// (cl/books.h ball_pair_type, wall_pair_type).
int n_pair_types(int n_materials);
std::string pair_type_name(const Scene& scene, int type);  // "steel-steel", "steel-shell", ...
bool pair_type_is_wall(int n_materials, int type);

}  // namespace mc
