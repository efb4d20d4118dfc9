// Lightcuts with visibility bounds, in one process on one scene (the shape of the
// lightcuts-visibility-bounds paper's table): for no bounds, the lower bound only, the upper
// bound only, and both:
//  - mean cut size and its reduction against no bounds, shadow rays per shading point,
//    clusters proved each way;
//  - render time and its ratio to no bounds; both bounds again at equal error (the largest
//    error fraction whose relative error and MSE are at most no bounds');
//  - the cut's error: per-pixel relative error (the paper's average relative error) and MSE
//    against the exact sum over every point light for the same camera samples (a cut with
//    error 0: brute-force shading);
// and lightcuts against `direct` (with --vpls N: `vpl`, the same VPLs) exact visibility at equal time: MSE of each against a
// converged direct reference (many samples of the area lights themselves), and the ratio.
//   visproxy-bench-lightcuts SCENE|room [--width W] [--height H] [--spp N] [--light-points K]
//                            [--error E] [--max-cut C] [--reference-spp R] [--cache DIR]
//                            [--images DIR] [--proxy SPEC]...  (room: the furniture's proxies; a scene
//                            file: the proxies of every instance that names some)
// `room` is the scene of `visproxy generate room`.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/render/scene_proxies.h"
#include "visproxy/image/image.h"
#include "visproxy/render/renderer.h"
#include "visproxy/scene/room.h"

namespace {

using namespace visproxy;

// Mean of |a - r| / r over the pixels whose reference luminance is above 1e-3 of the mean.
double mean_relative_error(const Image& a, const Image& reference) {
  double mean = 0;
  for (const Color& c : reference.pixels) mean += luminance(c);
  mean /= static_cast<double>(std::max<std::size_t>(reference.pixels.size(), 1));
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const double r = luminance(reference.pixels[i]);
    if (!(r > 1e-3 * mean)) continue;
    sum += std::abs(luminance(a.pixels[i]) - r) / r;
    ++count;
  }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

// MSE over all pixels but the `drop` fraction with the largest squared error (luminance of
// the difference), to see past a few pixels that dominate the mean.
double trimmed_mse(const Image& a, const Image& reference, double drop) {
  std::vector<double> errors;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) errors.push_back((a.pixels[i] - reference.pixels[i]).squaredNorm() / 3);
  std::sort(errors.begin(), errors.end());
  const auto keep = static_cast<std::size_t>(static_cast<double>(errors.size()) * (1 - drop));
  double sum = 0;
  for (std::size_t i = 0; i < keep; ++i) sum += errors[i];
  return keep > 0 ? sum / static_cast<double>(keep) : 0.0;
}

}  // namespace

int main(int argc, char** argv) try {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  if (argc < 2) {
    std::fprintf(stderr, "usage: visproxy-bench-lightcuts SCENE|room [--width W] [--height H] [--spp N] [--light-points K] [--error E] "
                         "[--max-cut C] [--reference-spp R] [--vpls N] [--cache DIR] [--images DIR] [--proxy SPEC]...\n");
    return 2;
  }
  const std::string scene_argument = argv[1];
  int width = 0, height = 0, spp = 4, light_points = 1024, max_cut = 1000, reference_spp = 64, vpls = 0;
  double error = 0.02;
  std::filesystem::path cache = default_proxy_cache(), images;
  std::vector<std::string> room_proxies;
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw Error(flag + ": needs a value");
    const std::string value = argv[++i];
    if (flag == "--width") width = std::stoi(value);
    else if (flag == "--height") height = std::stoi(value);
    else if (flag == "--spp") spp = std::stoi(value);
    else if (flag == "--light-points") light_points = std::stoi(value);
    else if (flag == "--error") error = std::stod(value);
    else if (flag == "--max-cut") max_cut = std::stoi(value);
    else if (flag == "--reference-spp") reference_spp = std::stoi(value);
    else if (flag == "--vpls") vpls = std::stoi(value);
    else if (flag == "--cache") cache = value;
    else if (flag == "--images") images = value;
    else if (flag == "--proxy") room_proxies.push_back(value);
    else throw Error("unknown option " + flag);
  }
  Scene scene;
  if (scene_argument == "room") {
    RoomOptions room;
    if (!room_proxies.empty()) room.proxies = room_proxies;
    scene = parse_scene(room_scene_json(room), "room.json");
  } else {
    scene = load_scene(scene_argument);
    // --proxy: these proxies for every instance that names some.
    if (!room_proxies.empty())
      for (SceneInstance& instance : scene.instances)
        if (!instance.proxies.empty()) instance.proxies = room_proxies;
  }
  if (width > 0) scene.camera.width = width;
  if (height > 0) scene.camera.height = height;
  const std::vector<MeshProxies> proxies = prepare_scene_proxies(scene, {.cache = cache, .stochastic_spec = std::nullopt, .seed = 1, .on_proxy = nullptr});
  const RenderWorld world(scene, proxies, {.counting = false, .ray_masks = true, .keep_solids = true});
  for (const std::string& note : world.notes()) std::printf("note: %s\n", note.c_str());
  if (!images.empty()) std::filesystem::create_directories(images);

  RenderOptions options{.integrator = IntegratorKind::lightcuts, .spp = spp, .seed = 1, .light_points = light_points};
  options.vpls = std::max(vpls, 1);
  options.lightcut_vpls = vpls > 0;
  std::printf("%s, %dx%d, %d spp, %d point lights per area light and the VPLs of %d light paths, error %.3g, max cut %d, seed 1\n",
              scene_argument.c_str(), scene.camera.width, scene.camera.height, spp, light_points, vpls, error, max_cut);

  // Brute force over every point light, for the same camera samples.
  options.lightcut = {.error = 0, .max_cut = std::numeric_limits<int>::max(), .bounds = VisibilityBounds::none, .check_proofs = false};
  const RenderResult exact_sum = render(scene, world, options);
  std::printf("every point light traced (cut error 0): %.1f s, mean cut %.1f, %.1f shadow rays per shading point\n\n",
              exact_sum.stats.seconds, exact_sum.stats.integrator["cut_size_mean"].get<double>(),
              exact_sum.stats.integrator["shadow_rays_per_shading_point"].get<double>());

  std::printf("%-8s %10s %9s %10s %8s %9s %12s %12s %10s %11s\n", "bounds", "mean cut", "vs none", "rays/pt", "time s",
              "vs none", "unoccluded", "occluded", "rel. error", "MSE");
  double none_cut = 0, none_time = 0, largest_cut = 0;
  RenderResult both;
  Image none_image;
  std::vector<Image> cut_maps;
  for (const VisibilityBounds bounds : {VisibilityBounds::none, VisibilityBounds::lower, VisibilityBounds::upper, VisibilityBounds::both}) {
    options.lightcut = {.error = error, .max_cut = max_cut, .bounds = bounds, .check_proofs = false};
    RenderResult result = render(scene, world, options);
    const nlohmann::json& s = result.stats.integrator;
    const double cut = s["cut_size_mean"].get<double>();
    if (bounds == VisibilityBounds::none) {
      none_cut = cut, none_time = result.stats.seconds;
      for (const Color& c : result.cut_map.pixels) largest_cut = std::max(largest_cut, c.x());
    }
    std::printf("%-8s %10.1f %8.0f%% %10.1f %8.2f %8.2fx %12llu %12llu %9.2f%% %11.3e\n",
                std::string(name_of(bounds)).c_str(), cut, 100 * (cut / none_cut - 1),
                s["shadow_rays_per_shading_point"].get<double>(), result.stats.seconds, none_time / result.stats.seconds,
                static_cast<unsigned long long>(s["clusters_proved_unoccluded"].get<std::uint64_t>()),
                static_cast<unsigned long long>(s["clusters_proved_occluded"].get<std::uint64_t>()),
                100 * mean_relative_error(result.image, exact_sum.image), mean_squared_error(result.image, exact_sum.image));
    if (!images.empty()) {
      const std::string name = std::string(name_of(bounds));
      write_png(images / ("lightcuts-" + name + ".png"), result.image, 1.0);
      write_png(images / ("lightcuts-" + name + ".cut.png"), result.cut_map, largest_cut > 0 ? 1 / largest_cut : 1.0);
    }
    cut_maps.push_back(result.cut_map);
    if (bounds == VisibilityBounds::none) none_image = result.image;
    if (bounds == VisibilityBounds::both) both = std::move(result);
  }
  // Both bounds at equal error: the largest error fraction (bisected in log scale over
  // [error / 8, error]) at which both the mean relative error and the MSE are at most those
  // of no bounds at `error`: the bounds' saving spent on accuracy.
  {
    const double none_relative = mean_relative_error(none_image, exact_sum.image);
    const double none_mse = mean_squared_error(none_image, exact_sum.image);
    double lo = std::log(error / 8), hi = std::log(error);
    std::optional<RenderResult> found;
    double found_error = 0;
    for (int step = 0; step < 6; ++step) {
      const double e = std::exp(step == 0 ? hi : 0.5 * (lo + hi));
      options.lightcut = {.error = e, .max_cut = max_cut, .bounds = VisibilityBounds::both, .check_proofs = false};
      RenderResult result = render(scene, world, options);
      const bool equal = mean_relative_error(result.image, exact_sum.image) <= none_relative &&
                         mean_squared_error(result.image, exact_sum.image) <= none_mse;
      if (equal) {
        if (!found || e > found_error) found = std::move(result), found_error = e;
        if (step == 0) break;
        lo = std::log(e);
      } else {
        hi = std::log(e);
      }
    }
    if (!found) {
      std::printf("both bounds: no error fraction down to %.3g gives the error of no bounds\n", error / 8);
    } else {
      const nlohmann::json& s = found->stats.integrator;
      const double cut = s["cut_size_mean"].get<double>();
      std::printf("%-8s %10.1f %8.0f%% %10.1f %8.2f %8.2fx %12llu %12llu %9.2f%% %11.3e   (error %.3g: at most no bounds' error)\n",
                  "both", cut, 100 * (cut / none_cut - 1), s["shadow_rays_per_shading_point"].get<double>(), found->stats.seconds,
                  none_time / found->stats.seconds, static_cast<unsigned long long>(s["clusters_proved_unoccluded"].get<std::uint64_t>()),
                  static_cast<unsigned long long>(s["clusters_proved_occluded"].get<std::uint64_t>()),
                  100 * mean_relative_error(found->image, exact_sum.image), mean_squared_error(found->image, exact_sum.image), found_error);
    }
  }
  if (!images.empty()) {
    Image reduction(scene.camera.width, scene.camera.height);
    for (std::size_t i = 0; i < reduction.pixels.size(); ++i) {
      const double before = cut_maps.front().pixels[i].x(), now = cut_maps.back().pixels[i].x();
      reduction.pixels[i] = Color::Constant(before > 0 ? std::clamp(1 - now / before, 0.0, 1.0) : 0.0);
    }
    write_png(images / "lightcuts-cut-reduction.png", reduction, 1.0);
    // At half size, 2 x 2: the image without and with both bounds above their cut maps (one
    // scale: white = the largest mean cut without bounds).
    const int w = scene.camera.width / 2, h = scene.camera.height / 2;
    Image montage(2 * w, 2 * h);
    const std::array<const Image*, 4> quadrants{&none_image, &both.image, &cut_maps.front(), &cut_maps.back()};
    for (int q = 0; q < 4; ++q) {
      const double scale = q < 2 ? 1.0 : (largest_cut > 0 ? 1 / largest_cut : 1.0);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const Image& from = *quadrants[static_cast<std::size_t>(q)];
          const Color sum = from.at(2 * x, 2 * y) + from.at(2 * x + 1, 2 * y) + from.at(2 * x, 2 * y + 1) + from.at(2 * x + 1, 2 * y + 1);
          montage.at((q % 2) * w + x, (q / 2) * h + y) = sum * (scale / 4);
        }
    }
    write_png(images / "lightcuts-montage.png", montage, 1.0);
  }

  // Against direct illumination with exact visibility at equal time, both measured against a
  // converged direct reference (the area lights themselves, not their point lights).
  // With VPLs the peer is the vpl integrator (M area-light samples plus every VPL, the same
  // VPLs and clamp), exact visibility.
  RenderOptions direct{.integrator = vpls > 0 ? IntegratorKind::vpl : IntegratorKind::direct, .spp = reference_spp, .shadow_rays = 4, .seed = 1000};
  direct.vpls = options.vpls;
  const RenderResult reference = render(scene, world, direct);
  direct.spp = 1 << 20, direct.shadow_rays = 1, direct.seed = 1, direct.seconds = both.stats.seconds;
  const RenderResult equal_time = render(scene, world, direct);
  const double direct_mse = mean_squared_error(equal_time.image, reference.image);
  const double lightcuts_mse = mean_squared_error(both.image, reference.image);
  const char* peer = vpls > 0 ? "vpl" : "direct";
  std::printf("\nagainst a converged %s reference (%d spp x 4 shadow rays, %.0f s), at equal time:\n", peer, reference_spp,
              reference.stats.seconds);
  std::printf("  lightcuts, both bounds: %.2f s, MSE %.3e (point lights and cut together)\n", both.stats.seconds, lightcuts_mse);
  std::printf("  %s, exact visibility: %.2f s (%d spp x 1 shadow ray), MSE %.3e\n", peer, equal_time.stats.seconds,
              equal_time.stats.passes, direct_mse);
  std::printf("  MSE %s / lightcuts: %.2f (above 1: lightcuts wins at equal time)\n", peer, direct_mse / lightcuts_mse);
  const double direct_trimmed = trimmed_mse(equal_time.image, reference.image, 0.01);
  const double lightcuts_trimmed = trimmed_mse(both.image, reference.image, 0.01);
  std::printf("  without each image's 1 %% of pixels with the largest error: lightcuts %.3e, %s %.3e, ratio %.2f\n",
              lightcuts_trimmed, peer, direct_trimmed, direct_trimmed / lightcuts_trimmed);
  if (!images.empty()) {
    write_png(images / "direct-reference.png", reference.image, 1.0);
    write_png(images / "direct-equal-time.png", equal_time.image, 1.0);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "visproxy-bench-lightcuts: %s\n", e.what());
  return 1;
}
