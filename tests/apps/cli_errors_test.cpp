// Bad input to `visproxy info`: exit code 2, one line on stderr naming the file and the
// problem, nothing on stdout.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "apps/cli_test_support.h"
#include "test_support.h"

namespace visproxy {
namespace {

struct Malformed {
  const char* file;     // name inside the test folder
  std::string content;  // written unless `create` is false
  const char* problem;  // fragment the message must contain
  bool create = true;
};

std::string binary_garbage(std::size_t size) {
  std::string bytes(size, '\0');
  std::uint32_t state = 12345;  // fixed seed: the same garbage every run
  for (char& c : bytes) {
    state = state * 1664525u + 1013904223u;
    c = static_cast<char>(state >> 24);
  }
  return bytes;
}

const std::string kPlyHeader =
    "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

void PrintTo(const Malformed& input, std::ostream* out) { *out << input.file; }

class CliRejects : public testing::ScratchFolder, public ::testing::WithParamInterface<Malformed> {};

TEST_P(CliRejects, WithExitCodeTwoAndOneLineNamingTheFile) {
  const Malformed& input = GetParam();
  std::filesystem::create_directory(folder_ / "folder.off");
  const auto path = folder_ / input.file;
  if (input.create) std::ofstream(path, std::ios::binary) << input.content;
  const auto result = testing::run_visproxy("info '" + path.string() + "'");
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_TRUE(result.out.empty()) << result.out;
  ASSERT_FALSE(result.err.empty());
  EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "exactly one line: " << result.err;
  EXPECT_NE(result.err.find(path.string()), std::string::npos) << "names the file: " << result.err;
  EXPECT_NE(result.err.find(input.problem), std::string::npos) << result.err;
  if (input.create) {
    std::ifstream check(path, std::ios::binary);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(check), {}), input.content) << "the input is untouched";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Info, CliRejects,
    ::testing::Values(
        Malformed{"empty.off", "", "the file is empty"},
        Malformed{"truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n", "header claims 4 vertices and 2 faces"},
        Malformed{"malformed.obj", "v 0 0 0\nv 1 0 0\nv 0 one 0\nf 1 2 3\n", ":3: expected vertex y, found 'one'"},
        Malformed{"index-out-of-range.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
                  "a vertex index 7 is out of range"},
        Malformed{"nan.off", "OFF\n3 1 0\n0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n", "vertex y is not finite"},
        Malformed{"inf.obj", "v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n", "vertex z is not finite"},
        Malformed{"huge-header.off", "OFF\n1000000000000 1000000000000 0\n0 0 0\n", "header claims 1000000000000 vertices"},
        Malformed{"huge-header.ply",
                  "ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
                  "header claims 1000000000000 'vertex' elements"},
        Malformed{"truncated-binary.ply", kPlyHeader + std::string(36, '\0') + "\x03", "truncated"},
        Malformed{"garbage.stl", binary_garbage(1000), "binary STL header claims"},
        Malformed{"garbage.off", binary_garbage(1000), "binary data"},
        Malformed{"garbage.ply", binary_garbage(1000), "does not start with 'ply'"},
        Malformed{"garbage.obj", "v 1 2 3\n" + binary_garbage(200), "binary data"},
        Malformed{"truncated.stl", "solid part\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n",
                  "expected 'vertex' or 'endloop'"},
        Malformed{"no-faces.obj", "v 0 0 0\nv 1 0 0\n", "contains no faces"},
        Malformed{"bad-format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown PLY format"},
        Malformed{"model.txt", "3DS", "unknown mesh file extension '.txt'"},
        Malformed{"model.3ds", "3DS", "Assimp cannot read it"},
        Malformed{"model.glb", "glTF" + binary_garbage(100), "Assimp cannot read it"},
        Malformed{"model.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": 7}", "Assimp cannot read it"},
        Malformed{"model.dae", "<?xml version=\"1.0\"?><COLLADA><library_geometries>", "Assimp cannot read it"},
        Malformed{"model.fbx", "Kaydara FBX Binary  \x00\x1a\x00" + binary_garbage(64), "Assimp cannot read it"},
        Malformed{"missing.off", "", "cannot open", false},
        Malformed{"folder.off", "", "not a regular file", false}),
    [](const ::testing::TestParamInfo<Malformed>& param_info) { return testing::test_name_from(param_info.param.file); });

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(testing::run_visproxy("").exit_code, 2);
  EXPECT_EQ(testing::run_visproxy("frobnicate").exit_code, 2);
  EXPECT_EQ(testing::run_visproxy("info").exit_code, 2);
  const auto result = testing::run_visproxy("info x.off --weld sometimes");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.err,
            "visproxy: --weld: 'sometimes' is not one of {auto, never, always} (see 'visproxy info --help')\n");
}

// A usage error names the option, what is wrong with it, and the help of the subcommand it
// belongs to, however deep: one line, exit code 2, nothing written.
class CliUsage : public testing::ScratchFolder {};

TEST_F(CliUsage, ErrorsPointAtTheSubcommandsHelp) {
  const std::string never = (folder_ / "never").string();
  const std::pair<std::string, std::string> cases[] = {
      {"build x.off -o " + never + " --tets delaunay",
       "visproxy: --tets: 'delaunay' is not one of {normals, tetgen} (see 'visproxy build --help')\n"},
      {"compare x.json -o " + never + " --integrator lightcuts",
       "visproxy: --integrator: 'lightcuts' is not one of {direct, vpl} (see 'visproxy compare --help')\n"},
      {"generate hairball -o " + never + " --frobnicate",
       "visproxy: The following argument was not expected: --frobnicate (see 'visproxy generate hairball --help')\n"},
  };
  for (const auto& [arguments, expected] : cases) {
    const auto result = testing::run_visproxy(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments;
    EXPECT_EQ(result.err, expected) << arguments;
    EXPECT_TRUE(result.out.empty()) << arguments << ": " << result.out;
  }
  EXPECT_FALSE(std::filesystem::exists(never));
}

// Seeds and counts are unsigned: "-3" is refused, not read as 2^64 - 3 and run with.
TEST_F(CliUsage, NegativeSeedsAndCountsAreRefused) {
  const std::string never = (folder_ / "never").string();
  for (const std::string& arguments :
       {"build x.off -o " + never + " --seed -3", "verify x.off " + never + " --seed -1",
        "measure x.off " + never + " --seed -7", "generate hairball -o " + never + " --seed -2",
        "batch list.txt -o " + never + " --seed -5"}) {
    const auto result = testing::run_visproxy(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << ": " << result.out;
    EXPECT_NE(result.err.find("' is negative (see 'visproxy "), std::string::npos) << arguments << ": " << result.err;
    EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "exactly one line: " << result.err;
  }
  EXPECT_FALSE(std::filesystem::exists(never));
}

// Choices show their names in the help, not CLI11's value map.
TEST(Cli, ChoicesAreListedByName) {
  const auto help = testing::run_visproxy("build --help");
  EXPECT_NE(help.out.find("--weld {auto, never, always}"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--tets {normals, tetgen}"), std::string::npos) << help.out;
  EXPECT_EQ(help.out.find("->"), std::string::npos) << help.out;
  const auto ok = testing::run_visproxy("info x.off --weld NEVER");  // case-insensitive: fails on the file, not the choice
  EXPECT_EQ(ok.exit_code, 2);
  EXPECT_EQ(ok.err.find("--weld"), std::string::npos) << ok.err;
}

TEST(Cli, HelpAndVersionExitWithZero) {
  const auto help = testing::run_visproxy("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("info"), std::string::npos);
  EXPECT_NE(help.out.find("Exit codes"), std::string::npos);
  const auto info_help = testing::run_visproxy("info --help");
  EXPECT_EQ(info_help.exit_code, 0);
  EXPECT_NE(info_help.out.find("--json"), std::string::npos);
  EXPECT_NE(info_help.out.find("--weld"), std::string::npos);
  EXPECT_EQ(testing::run_visproxy("--version").exit_code, 0);
}

// A mistyped subcommand gets one line and exit code 2, with or without --help, instead of
// the top-level help or "A subcommand is required".
TEST(Cli, UnknownSubcommandSuggestsTheNearestOne) {
  for (const char* arguments : {"biuld", "biuld --help", "biuld model.off -o out", "--help biuld"}) {
    const auto result = testing::run_visproxy(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments;
    EXPECT_TRUE(result.out.empty()) << arguments << ": " << result.out;
    EXPECT_EQ(result.err, "visproxy: unknown subcommand 'biuld' (did you mean 'build'?)\n") << arguments;
  }
  EXPECT_EQ(testing::run_visproxy("rendr").err, "visproxy: unknown subcommand 'rendr' (did you mean 'render'?)\n");
  EXPECT_EQ(testing::run_visproxy("inof --help").err, "visproxy: unknown subcommand 'inof' (did you mean 'info'?)\n");
}

TEST(Cli, FarOffSubcommandGetsNoSuggestion) {
  for (const char* arguments : {"frobnicate", "frobnicate --help", "xy"}) {
    const auto result = testing::run_visproxy(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments;
    EXPECT_TRUE(result.out.empty()) << arguments << ": " << result.out;
    EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "exactly one line: " << result.err;
    EXPECT_EQ(result.err.find("did you mean"), std::string::npos) << result.err;
    EXPECT_EQ(result.err.rfind("visproxy: unknown subcommand '", 0), 0u) << result.err;
  }
}

TEST(Cli, EverySubcommandsHelpExitsWithZero) {
  for (const char* command : {"info", "build", "verify", "measure", "report", "render", "generate", "compare"}) {
    const auto result = testing::run_visproxy(std::string(command) + " --help");
    EXPECT_EQ(result.exit_code, 0) << command << ": " << result.err;
    EXPECT_NE(result.out.find(command), std::string::npos) << result.out;
    EXPECT_TRUE(result.err.empty()) << command << ": " << result.err;
  }
}

}  // namespace
}  // namespace visproxy
