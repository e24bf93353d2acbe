#include "exabricks/io/model_info.h"

#include <nlohmann/json.hpp>

namespace exa {

std::string modelInfoJson(const Model& model, const std::string& input, double loadSeconds) {
  const ModelSummary s = summarize(model);
  const box3i lattice = model.cellBounds();
  const vec3d worldLo = model.world.toWorld(vec3d(lattice.lower));
  const vec3d worldHi = model.world.toWorld(vec3d(lattice.upper));
  const double perCell = s.cells ? 1.0 / double(s.cells) : 0.0;
  auto range = [](const range1f& r) -> nlohmann::json {
    if (r.empty()) return {{"min", nullptr}, {"max", nullptr}};
    return {{"min", r.lower}, {"max", r.upper}};
  };
  nlohmann::json j;
  j["input"] = input;
  j["cells"] = s.cells;
  j["bricks"] = s.bricks;
  j["single_cell_bricks"] = s.singleCellBricks;
  j["regions"] = s.regions;
  j["bricks_per_region_by_count"] = s.bricksPerRegionByCount;
  j["bricks_per_region_by_volume"] = s.bricksPerRegionByVolume;
  j["max_bricks_per_region"] = s.maxBricksPerRegion;
  j["bounds"] = {
      {"lattice",
       {{"lower", {lattice.lower.x, lattice.lower.y, lattice.lower.z}},
        {"upper", {lattice.upper.x, lattice.upper.y, lattice.upper.z}}}},
      {"world", {{"lower", {worldLo.x, worldLo.y, worldLo.z}}, {"upper", {worldHi.x, worldHi.y, worldHi.z}}}}};
  j["simulation"] = {
      {"time", model.simulation.hasTime() ? nlohmann::json(model.simulation.time) : nlohmann::json()},
      {"cycle", model.simulation.hasCycle() ? nlohmann::json(model.simulation.cycle) : nlohmann::json()},
      {"redshift", model.simulation.hasRedshift() ? nlohmann::json(model.simulation.redshift) : nlohmann::json()}};
  j["world"] = {{"origin", {model.world.origin.x, model.world.origin.y, model.world.origin.z}},
                {"scale", {model.world.scale.x, model.world.scale.y, model.world.scale.z}}};
  nlohmann::json levels = nlohmann::json::array();
  for (const auto& l : s.levels)
    levels.push_back({{"level", l.level}, {"cell_width", 1 << l.level}, {"cells", l.cells}, {"bricks", l.bricks}});
  j["levels"] = levels;
  nlohmann::json fields = nlohmann::json::array();
  for (size_t f = 0; f < model.fieldNames.size(); ++f)
    fields.push_back(
        {{"name", model.fieldNames[f]}, {"units", model.unitsOf(int(f))}, {"range", range(s.fieldRanges[f])}});
  j["fields"] = fields;
  j["memory_bytes"] = {{"bricks", s.brickBytes},
                       {"regions", s.regionBytes},
                       {"values", s.valueBytes},
                       {"structures_per_cell", double(s.brickBytes + s.regionBytes) * perCell}};
  j["build_seconds"] = {{"bricks", model.stats.brickSeconds},
                        {"regions", model.stats.regionSeconds},
                        {"value_ranges", model.stats.rangeSeconds},
                        {"load_total", loadSeconds}};
  j["build_parts"] = model.stats.parts;
  return j.dump(2);
}

} // namespace exa
