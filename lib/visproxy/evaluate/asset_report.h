#pragma once
// The report of a per-mesh folder (`visproxy build --per-mesh`): each mesh's own report,
// and one table over the asset, a row per mesh and a total.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string_view>

#include "visproxy/evaluate/report.h"

namespace visproxy {

/// Writes the report of every built mesh of the per-mesh folder `folder` into the mesh's
/// own folder (report_figures and write_report, each mesh read once from `asset`, or from
/// asset.json's source when empty), then FOLDER/report.md and FOLDER/recommendation.json:
/// one row per mesh (name, instances, triangles, and per use the file to ship or the mesh,
/// with that file's triangles; schema data/schemas/asset-recommendation.schema.json) and a total over the asset's
/// instances: its triangles, and those of what is shipped for each use. A use no mesh's report recommends a proxy for
/// (not measured yet, or no proxy predicted cheaper) ships the mesh. `on_part(name)` is
/// called before each mesh. Returns recommendation.json's object.
nlohmann::json write_asset_report(const std::filesystem::path& folder, const std::filesystem::path& asset,
                                  const ReportOptions& options = {},
                                  const std::function<void(std::string_view)>& on_part = {});

}  // namespace visproxy
