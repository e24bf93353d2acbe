#include "exabricks/io/model_info.h"

#include <nlohmann/json.hpp>

namespace exa {

std::string datasetInfoJson(const Model& described, const std::string& input, uint64_t cells, const box3i& lattice,
                            const std::vector<range1f>& fieldRanges) {
  const vec3d worldLo = described.world.toWorld(vec3d(lattice.lower));
  const vec3d worldHi = described.world.toWorld(vec3d(lattice.upper));
  auto range = [](const range1f& r) -> nlohmann::json {
    if (r.empty()) return {{"min", nullptr}, {"max", nullptr}};
    return {{"min", r.lower}, {"max", r.upper}};
  };
  const SimulationState& sim = described.simulation;
  nlohmann::json j;
  j["input"] = input;
  j["cells"] = cells;
  j["bounds"] = {
      {"lattice",
       {{"lower", {lattice.lower.x, lattice.lower.y, lattice.lower.z}},
        {"upper", {lattice.upper.x, lattice.upper.y, lattice.upper.z}}}},
      {"world", {{"lower", {worldLo.x, worldLo.y, worldLo.z}}, {"upper", {worldHi.x, worldHi.y, worldHi.z}}}}};
  j["simulation"] = {{"time", sim.hasTime() ? nlohmann::json(sim.time) : nlohmann::json()},
                     {"cycle", sim.hasCycle() ? nlohmann::json(sim.cycle) : nlohmann::json()},
                     {"redshift", sim.hasRedshift() ? nlohmann::json(sim.redshift) : nlohmann::json()}};
  j["world"] = {{"origin", {described.world.origin.x, described.world.origin.y, described.world.origin.z}},
                {"scale", {described.world.scale.x, described.world.scale.y, described.world.scale.z}}};
  nlohmann::json fields = nlohmann::json::array();
  for (size_t f = 0; f < described.fieldNames.size(); ++f)
    fields.push_back({{"name", described.fieldNames[f]},
                      {"units", described.unitsOf(int(f))},
                      {"range", range(f < fieldRanges.size() ? fieldRanges[f] : range1f())}});
  j["fields"] = fields;
  return j.dump();
}

std::string modelInfoJson(const Model& model, const std::string& input, double loadSeconds) {
  const ModelSummary s = summarize(model);
  const double perCell = s.cells ? 1.0 / double(s.cells) : 0.0;
  nlohmann::json j = nlohmann::json::parse(datasetInfoJson(model, input, s.cells, model.cellBounds(), s.fieldRanges));
  j["bricks"] = s.bricks;
  j["single_cell_bricks"] = s.singleCellBricks;
  j["regions"] = s.regions;
  j["bricks_per_region_by_count"] = s.bricksPerRegionByCount;
  j["bricks_per_region_by_volume"] = s.bricksPerRegionByVolume;
  j["max_bricks_per_region"] = s.maxBricksPerRegion;
  nlohmann::json levels = nlohmann::json::array();
  for (const auto& l : s.levels)
    levels.push_back({{"level", l.level}, {"cell_width", 1 << l.level}, {"cells", l.cells}, {"bricks", l.bricks}});
  j["levels"] = levels;
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
