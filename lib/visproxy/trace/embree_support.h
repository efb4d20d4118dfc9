#pragma once
// Shared Embree plumbing for the modules that trace rays (RayScene, the renderer): a
// device whose errors are thrown as visproxy::Error, and geometry built from visproxy's
// meshes and sphere sets. Includes Embree's header: for .cpp files only.

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// An Embree device. Embree reports errors through a callback, which must not throw
/// through Embree's frames: it records the first error and throw_if_failed() throws it
/// (std::bad_alloc when Embree ran out of memory, as the constructor does).
class EmbreeDevice {
 public:
  EmbreeDevice();
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice get() const { return device_; }
  void throw_if_failed();

  /// A new scene with high build quality and robust traversal (rays do not slip through
  /// shared edges); the caller releases it.
  RTCScene new_scene();

 private:
  struct ErrorState {
    std::mutex mutex;
    RTCError code = RTC_ERROR_NONE;
    std::string message;
  };
  static void record(void* user, RTCError code, const char* text);
  ErrorState errors_;
  RTCDevice device_ = nullptr;
};

/// Attaches `mesh` to `scene` as one triangle geometry (vertices rounded to float) with
/// the given mask; returns its geometry id.
unsigned attach_triangles(EmbreeDevice& device, RTCScene scene, const TriangleMesh& mesh, unsigned mask = 0xFFFFFFFFu);

/// Attaches `spheres` as solid balls (user geometry intersected in double precision; a
/// segment that starts or ends inside a ball is blocked). `spheres` must outlive the
/// scene. For occlusion queries only: rtcIntersect finds no sphere hit.
unsigned attach_spheres(EmbreeDevice& device, RTCScene scene, std::span<const Sphere> spheres, unsigned mask = 0xFFFFFFFFu);

/// A node of a binary BVH from build_binary_bvh: an inner node holds its two children and
/// their boxes (single precision, as given to the builder), a leaf its primitives' ids.
struct BinaryBvhNode {
  float lower[2][3], upper[2][3];
  const BinaryBvhNode* children[2] = {nullptr, nullptr};
  std::uint32_t count = 0;              ///< a leaf's primitives
  const std::uint32_t* ids = nullptr;   ///< their primID
  bool leaf = false;
};

/// Builds a binary BVH (leaves of at most 4) over `primitives` with Embree's builder, in
/// parallel, in the memory of `bvh` (a new RTCBVH the caller releases after its last query);
/// returns the root, or nullptr when there are no primitives. Low quality is Embree's
/// Morton-code builder (several times faster to build, somewhat slower to query), medium
/// its binned SAH builder; high (spatial splits) is not supported.
const BinaryBvhNode* build_binary_bvh(EmbreeDevice& device, RTCBVH bvh, std::vector<RTCBuildPrimitive> primitives,
                                      RTCBuildQuality quality);

/// The float at or below (above) a double: for boxes that must hold what they bound.
float round_down(double value);
float round_up(double value);

/// Whether the segment origin + t direction, tnear < t < tfar, meets the closed ball
/// (double precision, numerically stable roots).
bool segment_meets_ball(const Sphere& sphere, const Vertex& origin, const Vertex& direction, double tnear, double tfar);

/// Fills an RTCRay for the open segment from `from` to `to` (tnear 0, tfar 1, all mask bits).
RTCRay segment_ray(const Vertex& from, const Vertex& to);

}  // namespace visproxy
