// Reads a mesh, builds its convex hull with visproxy, proves that the hull contains the
// mesh, and prints one line: the library used from an installed package.
//   consumer MESH

#include <cstdio>
#include <exception>
#include <vector>

#include <visproxy/core/errors.h>
#include <visproxy/core/version.h>
#include <visproxy/mesh/read_mesh.h>
#include <visproxy/proxy/build_proxies.h>
#include <visproxy/verify/containment.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer MESH\n");
    return 2;
  }
  try {
    const visproxy::TriangleMesh mesh = visproxy::read_mesh(argv[1]);
    const std::vector<visproxy::ProxySpec> specs = {visproxy::parse_proxy_spec("hull")};
    const std::vector<visproxy::BuiltProxy> built =
        visproxy::build_proxies(mesh, argv[1], specs, {.hausdorff_samples = 1000, .gssa_lines = 1000});
    const bool contained = visproxy::check_containment(built.at(0).mesh, mesh).contained();
    std::printf("visproxy %s: %s, %zu triangles; hull %zu triangles, contains the mesh: %s\n", visproxy::version(), argv[1],
                mesh.triangles.size(), built.at(0).mesh.triangles.size(), contained ? "proved" : "NOT proved");
    return contained ? 0 : 1;
  } catch (const visproxy::InvalidInputError& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 3;
  }
}
