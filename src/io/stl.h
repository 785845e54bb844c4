// Triangle meshes in STL, binary or ASCII: the liners, lifters and ends that
// come from CAD. Reading checks the mesh as the solver will need it and
// refuses a bad one with one message naming the file and, where it applies,
// the triangle (counted from 1, as CAD tools and ParaView's cell ids + 1 do):
//   liner.stl: triangle 17 has zero area (vertices 2 and 3 coincide)
// Writing is binary STL, written whole or not at all.
#pragma once

#include <array>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/vec.h"

namespace mc::io {

// A bad mesh: the message is complete.
struct MeshError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

using mc::Triangle;  // vertices in the order the file gives them

struct TriangleMesh {
  std::vector<Triangle> triangles;
  bool binary = false;  // the file's form
  std::string name;     // ASCII "solid NAME", or the binary header's text
};

// A vertex as the file gives it times `scale` (1 for metres, 0.001 for mm).
// Detects the form: a binary file is exactly 84 + 50 n bytes with n the count
// in its header (CAD tools often begin binary headers with "solid" too); any
// other file must be ASCII STL. Refused, naming the file: an empty or
// unreadable file, a file that is neither form, a truncated one (binary: the
// size against the count; ASCII: a missing "endsolid" or an unfinished
// facet, with the line), a vertex that is not a finite number, a triangle of
// zero area (its longest edge times its height under 1e-9 of its longest
// edge squared: a sliver or repeated vertices), a triangle that repeats
// another (the same three vertices in any order), and a mesh of no
// triangles.
TriangleMesh read_stl(const std::filesystem::path& path, double scale = 1.0);

// The same from bytes in memory; `source` names it in messages.
TriangleMesh parse_stl(std::string_view bytes, const std::string& source, double scale = 1.0);

// Binary STL of `triangles` with facet normals from the vertex order
// (counter-clockwise seen from the side the normal points to).
std::string stl_binary(const std::vector<Triangle>& triangles, std::string_view header = "millcharge");
std::string stl_ascii(const std::vector<Triangle>& triangles, std::string_view name = "millcharge");

// The unit normal of a triangle from its vertex order (zero for a degenerate
// one).
Vec3 triangle_normal(const Triangle& t);

}  // namespace mc::io
