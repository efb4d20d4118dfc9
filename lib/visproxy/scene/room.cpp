#include "visproxy/scene/room.h"

#include <nlohmann/json.hpp>

namespace visproxy {
namespace {

// Appends the box [lo, hi] with outward (or, `inwards`, inward) triangles.
void add_box(TriangleMesh& mesh, const Vertex& lo, const Vertex& hi, bool inwards = false) {
  const auto first = static_cast<VertexIndex>(mesh.positions.size());
  for (int k = 0; k < 8; ++k) mesh.positions.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
  // Each face as two triangles wound counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    Triangle a{first + static_cast<VertexIndex>(f[0]), first + static_cast<VertexIndex>(f[1]), first + static_cast<VertexIndex>(f[2])};
    Triangle b{first + static_cast<VertexIndex>(f[0]), first + static_cast<VertexIndex>(f[2]), first + static_cast<VertexIndex>(f[3])};
    if (inwards) std::swap(a[1], a[2]), std::swap(b[1], b[2]);
    mesh.triangles.push_back(a);
    mesh.triangles.push_back(b);
  }
}

nlohmann::json inline_mesh(const TriangleMesh& mesh) {
  nlohmann::json positions = nlohmann::json::array(), triangles = nlohmann::json::array();
  for (const Vertex& p : mesh.positions) positions.push_back({p.x(), p.y(), p.z()});
  for (const Triangle& t : mesh.triangles) triangles.push_back({t[0], t[1], t[2]});
  return {{"positions", positions}, {"triangles", triangles}};
}

}  // namespace

TriangleMesh make_table() {
  TriangleMesh mesh;
  add_box(mesh, {-0.8, 0.70, -0.45}, {0.8, 0.75, 0.45});
  // Legs stop 1 mm below the top, so that every box is its own closed component.
  for (const double x : {-0.72, 0.72})
    for (const double z : {-0.37, 0.37}) add_box(mesh, {x - 0.03, 0.0, z - 0.03}, {x + 0.03, 0.699, z + 0.03});
  return mesh;
}

TriangleMesh make_chair() {
  TriangleMesh mesh;
  add_box(mesh, {-0.225, 0.43, -0.225}, {0.225, 0.47, 0.225});
  for (const double x : {-0.2, 0.2})
    for (const double z : {-0.2, 0.2}) add_box(mesh, {x - 0.02, 0.0, z - 0.02}, {x + 0.02, 0.429, z + 0.02});
  add_box(mesh, {-0.225, 0.471, 0.185}, {0.225, 0.95, 0.225});
  return mesh;
}

TriangleMesh make_room_shell() {
  TriangleMesh mesh;
  add_box(mesh, {-2.5, 0.0, -2.5}, {2.5, 2.6, 2.5}, true);
  return mesh;
}

std::string room_scene_json(const RoomOptions& options) {
  using nlohmann::json;
  json proxies = options.proxies;
  json instances = json::array();
  instances.push_back({{"mesh", "room"}, {"albedo", {0.72, 0.7, 0.66}}});
  instances.push_back({{"mesh", "table"}, {"albedo", {0.55, 0.36, 0.2}}, {"proxies", proxies}});
  // Two chairs on each long side, backs away from the table.
  for (const double x : {-0.4, 0.4})
    for (const double side : {1.0, -1.0})
      instances.push_back({{"mesh", "chair"},
                           {"albedo", {0.3, 0.42, 0.6}},
                           {"transform", {{"rotate", {{"axis", {0, 1, 0}}, {"degrees", side > 0 ? 0 : 180}}}, {"translate", {x, 0.0, 0.75 * side}}}},
                           {"proxies", proxies}});
  const json scene = {
      {"format", "visproxy-scene"},
      {"format_version", 1},
      {"description",
       "A procedural room (visproxy generate room): a closed 5 x 2.6 x 5 m room with a table and four chairs, each a closed mesh "
       "of disjoint boxes, under one 1 x 0.8 m ceiling light; metres. The many-light test scene of lightcuts with visibility bounds."},
      {"meshes", {{"room", inline_mesh(make_room_shell())}, {"table", inline_mesh(make_table())}, {"chair", inline_mesh(make_chair())}}},
      {"instances", instances},
      {"lights", json::array({{{"type", "parallelogram"}, {"corner", {-0.5, 2.59, -0.4}}, {"edge1", {1.0, 0, 0}}, {"edge2", {0, 0, 0.8}},
                               {"radiance", {14, 13, 11}}}})},
      {"camera", {{"from", {2.3, 1.75, 2.3}}, {"at", {0, 0.45, 0}}, {"up", {0, 1, 0}}, {"fov_degrees", 55},
                  {"width", options.width}, {"height", options.height}}}};
  return scene.dump(1) + "\n";
}

}  // namespace visproxy
