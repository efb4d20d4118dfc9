#pragma once
// The job `visproxy render` does, in one place that the CLI and the Python module call:
// the scene read, its proxies built, proved and cached, the world made, the image
// rendered, and the outputs written; with the one table of its options (name, flag, help,
// how a value is read) from which the CLI makes its flags and Python its keywords.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/render/renderer.h"
#include "visproxy/render/scene_proxies.h"

namespace visproxy {

/// Everything a render job is asked.
struct RenderJob {
  std::filesystem::path scene;   ///< a JSON scene or a glTF/Assimp file (load_scene)
  std::filesystem::path output;  ///< .pfm or .exr (a PNG and OUT.stats.json beside it); empty: nothing written
  RenderOptions options;
  /// Not given: 2, or 0.25 with the vpl integrator (whose hundreds of connections per
  /// shading point share the variance).
  std::optional<double> correction_scale;
  std::string proxy;  ///< stochastic: this spec for every instance that names proxies (empty: each one's first)
  std::filesystem::path cache;          ///< proxy cache folder (empty: default_proxy_cache())
  int width = 0, height = 0;            ///< the image's size, when not 0 (else the scene camera's)
  bool count = false;                   ///< counted traversal (RenderWorldOptions::counting)
  bool maps = false;                    ///< also the cost, p1 and cut maps beside the output
  std::filesystem::path cut_reference;  ///< lightcuts with maps: a cut map to compare with
  double exposure = 1;                  ///< scale before the PNG's sRGB encoding
};

/// One option of a render job: its name (Python keyword, stats key), its command-line
/// flag, its help, and how a value sets it.
struct RenderOption {
  enum class Type { integer, real, text, choice, flag };
  std::string_view name;  ///< "probe_rays"
  std::string_view flag;  ///< "--probe-rays"; flags that turn something off are named so ("--no-split")
  Type type = Type::text;
  std::string help;     ///< ends with the default
  std::string choices;  ///< choice: "{a, b, c}"
  /// Sets the option from its text (numbers and choices checked: OptionError naming the flag).
  std::function<void(RenderJob&, std::string_view)> set;
  /// Flags: sets the option on or off; `name` reads in the positive sense (split: true is
  /// tracing the own instance exactly; the flag --no-split sets it false).
  std::function<void(RenderJob&, bool)> set_flag;
};

/// Every option of a render job, in the order the help lists them.
const std::vector<RenderOption>& render_options();
/// The option named `name` (Python keyword) or with the flag `name` ("--spp"); nullptr if none.
const RenderOption* find_render_option(std::string_view name);

/// What render_scene reports while it works.
struct RenderCallbacks {
  /// A proxy about to be read from the cache (cached) or built.
  std::function<void(std::string_view mesh, std::string_view spec, bool cached)> on_proxy;
  /// A proxy verified now: whether its claim holds, and why not.
  std::function<void(std::string_view mesh, std::string_view spec, bool holds, std::string_view counterexample)>
      on_verify;
  std::function<void(int passes, double seconds)> on_pass;  ///< after each pass
  WarningHandler on_warning;                                ///< the mesh readers' warnings
};

/// A rendered job.
struct RenderedScene {
  Scene scene;  ///< as rendered (the job's size applied)
  std::vector<MeshProxies> proxies;
  std::vector<std::string> notes;  ///< the world's notes: proxies not used with their kind's guarantees, and why
  RenderResult result;
  /// OUT.stats.json: the job's options as applied, each instance's proxies, the notes and
  /// the render's stats.
  nlohmann::json document;
};

/// Checks the job (an output that is neither .pfm nor .exr, options render() refuses, a cut
/// reference without lightcuts and maps), reads the scene, prepares the proxies the job
/// needs (none for exact visibility without visibility bounds), makes the world and
/// renders. Throws InvalidInputError or OptionError naming what is wrong.
RenderedScene render_scene(const RenderJob& job, const RenderCallbacks& callbacks = {});

/// Writes the job's outputs: the linear image, OUT.png, OUT.stats.json and, with maps, the
/// maps; each under a temporary name first. Nothing when the job has no output.
void write_render_outputs(const RenderJob& job, const RenderedScene& rendered);

}  // namespace visproxy
