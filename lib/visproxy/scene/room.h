#pragma once
// A procedural room for many-light rendering: a closed box room with a table and four
// chairs under one ceiling light, in the spirit of the lightcuts-visibility-bounds paper's
// test scene (a room with a table and chairs lit by one area light). Every piece of
// furniture is a closed mesh of disjoint boxes, so that inside proxies exist for it.

#include <string>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct RoomOptions {
  /// Proxies every piece of furniture names (the first outside one is the shaft test's,
  /// the first inside one the occlusion test's).
  std::vector<std::string> proxies{"hull", "inner:128,grid=128"};
  int width = 640, height = 480;
};

/// The table (a top on four legs) and a chair (seat, four legs, back), each a closed mesh of
/// disjoint axis-aligned boxes (outward triangles), in metres, standing on y = 0.
TriangleMesh make_table();
TriangleMesh make_chair();
/// The room: the inside of a closed 5 x 2.6 x 5 m box (triangles facing inwards).
TriangleMesh make_room_shell();

/// The scene file (visproxy-scene JSON) of the room: the meshes inline, one table, four
/// chairs around it, a 1 x 0.8 m light just below the ceiling, a camera in a corner.
std::string room_scene_json(const RoomOptions& options = {});

}  // namespace visproxy
