#include "patch_load.h"
#include "patches.h"

#include "exabricks/core/error.h"
#include "exabricks/core/kept.h"
#include "exabricks/core/log.h"
#include "exabricks/io/model_file.h"
#include "exabricks/io/units.h"

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

namespace exa {
namespace io {

std::string metadataStamp(const std::string& path) {
  std::string stamp;
  std::error_code ec;
  for (const std::filesystem::path& p : {std::filesystem::path(path), std::filesystem::path(path) / "Header",
                                         std::filesystem::path(path + ".hierarchy")}) {
    const auto t = std::filesystem::last_write_time(p, ec);
    if (ec) continue;
    stamp += strCat(p.string(), ":", t.time_since_epoch().count(), ":",
                    std::filesystem::is_regular_file(p, ec) ? std::filesystem::file_size(p, ec) : 0, ";");
  }
  return stamp;
}

/// The input's patches, read from its metadata once while they are unchanged: the parts of a
/// step under a memory budget, each built through the same box lists, parse them once. Only
/// sources of plain files are kept, whose reads any thread may share.
PatchSource patchesOf(const std::string& path, const FormatReader& reader, const std::vector<std::string>& fields,
                      int finestLevel) {
  static KeptResults<PatchSource> kept(1);
  std::string key = strCat(path, "|", finestLevel, "|", metadataStamp(path));
  for (const std::string& f : fields)
    key += "|" + f;
  if (std::shared_ptr<const PatchSource> source = kept.find(key)) return *source;
  PatchSource source = reader.patches(path, fields, finestLevel);
  if (source.concurrentReads) kept.keep(key, source); // else its reads share a library handle (HDF5)
  return source;
}

namespace {
/// The format's conventional units where the file states none.
void nameUnits(const FormatReader& reader, PatchSource& source) {
  CellSet named;
  for (size_t f = 0; f < source.fieldNames.size(); ++f)
    named.fields.push_back(Field{source.fieldNames[f], {}, source.fieldUnits[f]});
  assignConventionalUnits(reader.kind, named);
  for (size_t f = 0; f < named.fields.size(); ++f)
    source.fieldUnits[f] = named.fields[f].units;
}
} // namespace

Model loadModelOfPatches(const std::string& path, const FormatReader& reader, const LoadOptions& options,
                         int finestLevel, const PatchKeep& keep) {
  PatchSource source = patchesOf(path, reader, options.fields, finestLevel);
  nameUnits(reader, source);
  return buildModelOfPatches(source, keep, options.build);
}

namespace {
/// A model file's bricks as patches: one patch per brick (bricks hold leaf cells alone, so none
/// covers another), its values read brick by brick from the open file.
PatchSource modelPatches(const std::string& path, const std::vector<std::string>& wanted, int finestLevel) {
  if (finestLevel > 0) fail(path, ": a model file holds its leaf cells alone: its coarse levels cannot be read apart");
  auto table = std::make_shared<const ModelTable>(readModelTable(path));
  const std::vector<size_t> picked = pickFields(path, table->fieldNames, wanted);
  PatchSource source = sourceOfFields(path, table->fieldNames, picked);
  source.world = table->world;
  source.patches.reserve(table->bricks.size());
  for (const Brick& b : table->bricks)
    source.patches.push_back({vec3l(b.lower), vec3l(b.size), int64_t(b.cellWidth())});
  source.name = [path](size_t i) { return strCat(path, ": brick ", i); };
  source.read = [table, picked, path](size_t i, std::vector<std::vector<float>>& values) {
    const Brick& b = table->bricks.at(i);
    values.resize(picked.size());
    for (size_t k = 0; k < picked.size(); ++k) {
      values[k].resize(b.cellCount());
      table->readValues(path, picked[k], b, values[k].data());
      for (size_t c = 0; c < values[k].size(); ++c)
        if (!std::isfinite(values[k][c]))
          fail(path, ": brick ", i, ": field '", table->fieldNames[picked[k]], "' holds a non-finite value at cell ", c,
               " (a damaged model file; build it again)");
    }
  };
  source.concurrentReads = true; // positioned reads of one descriptor
  return source;
}

Census modelCensus(const std::string& path) { return censusOfBricks(readModelTable(path).bricks); }
std::vector<std::string> modelFields(const std::string& path) { return readModelTable(path).fieldNames; }
} // namespace

const FormatReader& modelPartsReader() {
  static const FormatReader reader{InputKind::Model,
                                   "exabricks model",
                                   isModelFile,
                                   modelFields,
                                   [](const std::string& path, const ReadRequest&) -> CellSet {
                                     fail(path,
                                          ": a model file is loaded whole (loadModel) or in parts from its bricks");
                                   },
                                   nullptr,
                                   modelCensus,
                                   nullptr,
                                   modelPatches};
  return reader;
}

const FormatReader* patchReader(InputKind kind, const std::string& path, const LoadOptions& options) {
  if (kind == InputKind::Default || kind == InputKind::Model || options.nonFinite != NonFinite::Refuse) return nullptr;
  const FormatReader* reader = findReader(path);
  return reader && reader->patches ? reader : nullptr;
}

Census censusOfInput(const std::string& path, const FormatReader& reader) {
  static KeptResults<Census> kept(1);
  const std::string key = strCat(path, "|", metadataStamp(path));
  if (std::shared_ptr<const Census> census = kept.find(key)) return *census;
  Timer timer;
  Census census = reader.census(path);
  logInfo(strCat("census of ", path, ": ", census.boxes.size(), " boxes, ", std::llround(census.cells()),
                 " leaf cells, in ", timer.seconds(), " s"));
  return *kept.keep(key, std::move(census));
}

} // namespace io

namespace {
/// A model's cells with their values, brick after brick.
CellSet cellsOf(const Model& m) {
  CellSet set;
  set.world = m.world;
  set.simulation = m.simulation;
  for (size_t f = 0; f < m.fieldNames.size(); ++f)
    set.fields.push_back(Field{m.fieldNames[f], {}, f < m.fieldUnits.size() ? m.fieldUnits[f] : ""});
  set.cells.reserve(m.cellCount());
  for (const Brick& b : m.bricks)
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x) {
          set.cells.push_back(Cell{b.lower + vec3i(x, y, z) * b.cellWidth(), b.level});
          const size_t slot = b.valueOffset + size_t((z * b.size.y + y) * b.size.x + x);
          for (size_t f = 0; f < set.fields.size(); ++f)
            set.fields[f].values.push_back(m.fieldValues[f][slot]);
        }
  return set;
}
} // namespace

std::optional<MergedCoarsest> loadMergedCoarsest(const std::string& path, const LoadOptions& options, double maxCells) {
  const FormatReader* reader = path.empty() ? nullptr : io::patchReader(detectInput(path), path, options);
  const std::vector<CoarseFirst> choices = reader ? coarseFirstChoices(path) : std::vector<CoarseFirst>();
  if (choices.empty()) return std::nullopt;
  MergedCoarsest m;
  m.level = choices.size() > 1 ? choices[1].level : choices[0].finestLevel; // choices[1]: the coarsest alone
  m.cells = choices.size() > 1 ? choices[1].coarseCells : choices[0].cells;
  int64_t factor = 1; // the fewest merges that bring the coarsest level within maxCells
  while (m.cells / double(factor * factor * factor) > maxCells && m.level + io::log2Exact(factor) < kMaxLevel)
    factor *= 2;
  if (factor == 1) return std::nullopt;
  PatchSource source = io::patchesOf(path, *reader, options.fields, m.level);
  m.factor = alignedMerge(source.patches, factor);
  if (m.factor == 1) return std::nullopt;
  Timer timer;
  source = mergedPatches(source, m.factor);
  io::nameUnits(*reader, source);
  // Built from the boxes (read on every core), then again from its cells: a merged box holds a
  // few cells, and the cells' own build joins them into bricks as large as their level allows,
  // so that a sample reconstructs from a few bricks instead of dozens.
  m.model = buildModel(cellsOf(buildModelOfPatches(source, {}, options.build)), options.build);
  logInfo(strCat("the coarsest level's ", std::llround(m.cells), " cells merged by ", m.factor, " per axis in ",
                 timer.seconds(), " s"));
  return m;
}

std::vector<CoarseFirst> coarseFirstChoices(const std::string& path) {
  std::vector<CoarseFirst> choices;
  if (path.empty() || detectInput(path) == InputKind::Model) return choices;
  const FormatReader* reader = findReader(path);
  if (!reader || !reader->levelCells) return choices;
  const std::vector<double> cells = reader->levelCells(path);
  CoarseFirst whole;
  whole.finestLevel = -1;
  for (int l = 0; l < int(cells.size()); ++l) {
    whole.cells += cells[size_t(l)];
    if (whole.finestLevel < 0 && cells[size_t(l)] > 0) whole.finestLevel = l;
  }
  whole.finestLevel = std::max(whole.finestLevel, 0);
  choices.push_back(whole);
  double coarse = 0;
  for (int l = int(cells.size()) - 1; l > whole.finestLevel; --l) {
    if (cells[size_t(l)] == 0) continue;
    coarse += cells[size_t(l)];
    CoarseFirst c = whole;
    c.level = l;
    c.coarseCells = coarse;
    choices.push_back(c);
  }
  return choices;
}

CoarseFirst coarseFirstLevel(const std::string& path, double maxCells) {
  const std::vector<CoarseFirst> choices = coarseFirstChoices(path);
  if (choices.empty() || choices[0].cells <= maxCells) return choices.empty() ? CoarseFirst() : choices[0];
  // The finest level whose cells, with those of every coarser level, stay within maxCells (the
  // coarsest level alone when it holds more). Only a coarser picture than the whole is worth
  // drawing first.
  CoarseFirst best = choices[0];
  for (size_t k = 1; k < choices.size() && (k == 1 || choices[k].coarseCells <= maxCells); ++k)
    best = choices[k];
  return best;
}

} // namespace exa
