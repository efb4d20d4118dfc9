// Every mesh format Assimp reads beyond visproxy's own four: glTF 2.0, FBX, Collada, 3DS,
// and the rest (Debian's libassimp). The node hierarchy is flattened: each node's meshes
// placed by the product of the transforms down to it, in double. Points and lines are
// dropped, polygons triangulated by Assimp.
//
// Assimp is not written for hostile input: a 5 KB Collada file can make it allocate 17 GB,
// and malformed files have crashed it. So it runs in a child process (assimp_isolated)
// with limits on memory and processor time, and hands the mesh back through a pipe; a
// crash, a limit reached or a refusal becomes one InvalidInputError naming the file.

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/assimp_support.h"
#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy::parsing {
namespace {

constexpr unsigned kImportSteps = aiProcess_Triangulate | aiProcess_ValidateDataStructure;

TriangleMesh flatten(const aiScene* scene, const std::filesystem::path& source) {
  if (scene->mRootNode == nullptr) throw InvalidInputError(source, "Assimp read no node hierarchy");
  // Each mesh once, placed as often as nodes use it.
  std::vector<TriangleMesh> parts;
  parts.reserve(scene->mNumMeshes);
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) parts.push_back(triangles_of(*scene->mMeshes[i], source));
  TriangleMesh mesh;
  std::vector<std::pair<const aiNode*, Eigen::Affine3d>> stack{{scene->mRootNode, to_affine(scene->mRootNode->mTransformation)}};
  std::size_t nodes = 0;
  while (!stack.empty()) {
    const auto [node, transform] = stack.back();
    stack.pop_back();
    if (++nodes > 10'000'000) throw InvalidInputError(source, "more than 10 million nodes");
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      if (node->mMeshes[i] >= scene->mNumMeshes) throw InvalidInputError(source, "a node names a mesh that does not exist");
      const TriangleMesh& part = parts[node->mMeshes[i]];
      if (mesh.positions.size() + part.positions.size() > std::numeric_limits<VertexIndex>::max())
        throw InvalidInputError(source, "more than 2^32 - 1 vertices once the nodes are placed");
      append_mesh(mesh, transformed_mesh(part, transform));
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c)
      if (node->mChildren[c] != nullptr) stack.emplace_back(node->mChildren[c], transform * to_affine(node->mChildren[c]->mTransformation));
  }
  if (mesh.triangles.empty()) throw InvalidInputError(source, "holds no triangles (Assimp found no faces with three corners)");
  return mesh;
}

}  // namespace

std::string one_line(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text.empty() ? std::string("no reason given") : text;
}

Eigen::Affine3d to_affine(const aiMatrix4x4& m) {
  Eigen::Matrix4d matrix;
  matrix << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return Eigen::Affine3d(matrix);
}

TriangleMesh triangles_of(const aiMesh& part, const std::filesystem::path& source) {
  if (part.mNumVertices > 0 && part.mVertices == nullptr) throw InvalidInputError(source, "a mesh without positions");
  TriangleMesh mesh;
  mesh.positions.reserve(part.mNumVertices);
  for (unsigned v = 0; v < part.mNumVertices; ++v) mesh.positions.emplace_back(part.mVertices[v].x, part.mVertices[v].y, part.mVertices[v].z);
  for (unsigned f = 0; f < part.mNumFaces; ++f) {
    const aiFace& face = part.mFaces[f];
    if (face.mNumIndices != 3) continue;  // points and lines
    Triangle t;
    for (unsigned k = 0; k < 3; ++k) {
      if (face.mIndices[k] >= part.mNumVertices) throw InvalidInputError(source, "a face index is out of range");
      t[k] = face.mIndices[k];
    }
    mesh.triangles.push_back(t);
  }
  return mesh;
}

bool assimp_reads(const std::filesystem::path& path) {
  const std::string extension = lowercase_extension(path);
  if (extension.size() < 2) return false;
  static const Assimp::Importer importer;
  return importer.IsExtensionSupported(extension.c_str());
}

namespace {

// The mesh as bytes through the pipe: vertex and triangle counts, then the coordinates and
// the indices, in this machine's byte order.
std::string encode(const TriangleMesh& mesh) {
  const std::uint64_t counts[2] = {mesh.positions.size(), mesh.triangles.size()};
  std::string bytes(reinterpret_cast<const char*>(counts), sizeof counts);
  for (const Vertex& p : mesh.positions) bytes.append(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
  for (const Triangle& t : mesh.triangles) bytes.append(reinterpret_cast<const char*>(t.data()), 3 * sizeof(VertexIndex));
  return bytes;
}

TriangleMesh decode(const std::string& bytes, const std::filesystem::path& source) {
  std::uint64_t counts[2];
  if (bytes.size() < sizeof counts) throw InvalidInputError(source, "Assimp's reader returned a truncated mesh");
  std::memcpy(counts, bytes.data(), sizeof counts);
  const std::uint64_t expected = sizeof counts + counts[0] * 3 * sizeof(double) + counts[1] * 3 * sizeof(VertexIndex);
  if (counts[0] > bytes.size() || counts[1] > bytes.size() || expected != bytes.size())
    throw InvalidInputError(source, "Assimp's reader returned a truncated mesh");
  TriangleMesh mesh;
  mesh.positions.resize(counts[0]);
  mesh.triangles.resize(counts[1]);
  const char* at = bytes.data() + sizeof counts;
  for (Vertex& p : mesh.positions) {
    std::memcpy(p.data(), at, 3 * sizeof(double));
    at += 3 * sizeof(double);
  }
  for (Triangle& t : mesh.triangles) {
    std::memcpy(t.data(), at, 3 * sizeof(VertexIndex));
    at += 3 * sizeof(VertexIndex);
  }
  return mesh;
}

// The process's address space now, in bytes (the child's limit is counted on top of it).
std::uint64_t address_space_in_use() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

std::uint64_t memory_allowance(std::uint64_t input_bytes) {
  if (const char* given = std::getenv("VISPROXY_ASSIMP_MEMORY_MB")) {
    char* end = nullptr;
    const unsigned long long mb = std::strtoull(given, &end, 10);
    if (end != given && *end == '\0' && mb > 0) return mb << 20;
  }
  return (std::uint64_t{1} << 30) + 64 * input_bytes;
}

// Processor time for one file: 20 s and 1 s per MB of input, at most an hour
// (VISPROXY_ASSIMP_SECONDS overrides it). Assimp reads about 50 MB/s.
rlim_t time_allowance(std::uint64_t input_bytes) {
  if (const char* given = std::getenv("VISPROXY_ASSIMP_SECONDS")) {
    char* end = nullptr;
    const unsigned long long seconds = std::strtoull(given, &end, 10);
    if (end != given && *end == '\0' && seconds > 0) return static_cast<rlim_t>(seconds);
  }
  return static_cast<rlim_t>(std::min<std::uint64_t>(20 + (input_bytes >> 20), 3600));
}

void write_all(int fd, const std::string& bytes) {
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace

std::string assimp_isolated_bytes(const std::filesystem::path& source, std::uint64_t input_bytes,
                                  const std::function<std::string()>& read) {
  const std::uint64_t allowance = memory_allowance(input_bytes);
  const rlim_t seconds = time_allowance(input_bytes);
  const std::uint64_t limit = address_space_in_use() + allowance;
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) return read();  // no isolation to be had: read in this process
  const pid_t child = ::fork();
  if (child < 0) {
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    return read();
  }
  if (child == 0) {
    ::close(pipe_fds[0]);
    // A crash ends the child, whatever handlers this process installed (a fuzzer's, an
    // interpreter's): the parent reports it.
    for (const int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGXCPU}) ::signal(signal, SIG_DFL);
    const rlimit memory{limit, limit};
    ::setrlimit(RLIMIT_AS, &memory);
    const rlimit cpu{seconds, seconds + 5};
    ::setrlimit(RLIMIT_CPU, &cpu);
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    std::string reply;
    try {
      reply = "M" + read();
    } catch (const InvalidInputError& error) {
      reply = "E" + error.problem();
    } catch (const std::bad_alloc&) {
      reply = "B";
    } catch (const std::exception& error) {
      reply = "E" + std::string("Assimp's reader failed: ") + error.what();
    }
    write_all(pipe_fds[1], reply);
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  std::string reply;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    reply.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(pipe_fds[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string memory_text = std::to_string(allowance >> 20) + " MB";
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    if (signal == SIGXCPU || signal == SIGKILL)
      throw InvalidInputError(source, "Assimp took more than " + std::to_string(seconds) +
                                          " s of processor time reading it (set VISPROXY_ASSIMP_SECONDS to allow more)");
    throw InvalidInputError(source, "Assimp crashed reading it (" + std::string(::strsignal(signal)) + ")");
  }
  const bool out_of_memory = reply == "B" || (reply.starts_with("E") && reply.find("bad_alloc") != std::string::npos);
  if (out_of_memory)
    throw InvalidInputError(source, "Assimp needs more than " + memory_text +
                                        " of memory to read it (set VISPROXY_ASSIMP_MEMORY_MB to allow more)");
  if (reply.starts_with("E")) throw InvalidInputError(source, reply.substr(1));
  if (!reply.starts_with("M")) throw InvalidInputError(source, "Assimp's reader ended without an answer");
  return reply.substr(1);
}

TriangleMesh assimp_isolated(const std::filesystem::path& source, std::uint64_t input_bytes,
                             const std::function<TriangleMesh()>& read) {
  return decode(assimp_isolated_bytes(source, input_bytes, [&] { return encode(read()); }), source);
}

std::uint64_t assimp_input_bytes(const std::filesystem::path& path) {
  // A .gltf's buffers and images lie beside it: count the folder's files as its input.
  std::uint64_t input_bytes = 0;
  std::error_code error;
  if (lowercase_extension(path) == ".gltf") {
    for (const auto& item : std::filesystem::directory_iterator(path.parent_path().empty() ? "." : path.parent_path(), error))
      if (item.is_regular_file(error)) input_bytes += item.file_size(error);
  } else {
    input_bytes = std::filesystem::file_size(path, error);
  }
  return input_bytes;
}

TriangleMesh read_assimp_file(const std::filesystem::path& path) {
  return assimp_isolated(path, assimp_input_bytes(path), [&] {
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(path.string(), kImportSteps);
    if (scene == nullptr) throw InvalidInputError(path, "Assimp cannot read it: " + one_line(importer.GetErrorString()));
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0)
      throw InvalidInputError(path, "Assimp read it only in part (a scene without meshes, or a mesh it could not complete)");
    return flatten(scene, path);
  });
}

TriangleMesh parse_assimp(std::string_view bytes, const std::filesystem::path& source) {
  return assimp_isolated(source, bytes.size(), [&] {
    Assimp::Importer importer;
    const std::string hint = lowercase_extension(source).empty() ? std::string() : lowercase_extension(source).substr(1);
    const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kImportSteps, hint.c_str());
    if (scene == nullptr) throw InvalidInputError(source, "Assimp cannot read it: " + one_line(importer.GetErrorString()));
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0)
      throw InvalidInputError(source, "Assimp read it only in part (a scene without meshes, or a mesh it could not complete)");
    return flatten(scene, source);
  });
}

}  // namespace visproxy::parsing
