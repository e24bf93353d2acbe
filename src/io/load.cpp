#include "exabricks/io/load.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/io/amrex.h"
#include "exabricks/io/chombo.h"
#include "exabricks/io/enzo.h"
#include "exabricks/io/flash.h"
#include "exabricks/io/model_file.h"
#include "exabricks/io/native.h"
#include "exabricks/io/patch_source.h"
#include "exabricks/io/units.h"
#include "exabricks/io/vtk_amr.h"

#include "hdf5_file.h"
#include "patch_load.h"
#include "patches.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <optional>

namespace exa {
namespace {
bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void selectFields(CellSet& set, const std::vector<std::string>& wanted, const std::string& source) {
  if (wanted.empty()) return;
  std::vector<Field> chosen;
  std::vector<bool> taken(set.fields.size(), false);
  for (const std::string& name : wanted) {
    const int i = set.fieldIndex(name);
    if (i < 0) {
      std::string known;
      for (const Field& f : set.fields)
        known += (known.empty() ? "" : ", ") + f.name;
      fail(source, ": unknown field '", name, "' (fields: ", known, ")");
    }
    if (taken[size_t(i)]) { // named twice: a copy of the one chosen
      for (size_t c = 0; c < chosen.size(); ++c)
        if (chosen[c].name == name) {
          Field copy = chosen[c];
          chosen.push_back(std::move(copy));
          break;
        }
      continue;
    }
    taken[size_t(i)] = true;
    chosen.push_back(std::move(set.fields[size_t(i)])); // moved: no second copy of the values
  }
  set.fields = std::move(chosen);
}
} // namespace

namespace {
std::vector<std::string> scalarOnly(const std::string&) { return {"scalar"}; }
bool isNativeName(const std::string& path) { return endsWith(path, ".cells"); }
bool isGridsName(const std::string& path) { return endsWith(path, ".grids"); }
/// Readers that recognise an input by its name only are probed after every content probe.
bool probesByName(const FormatReader& r) { return r.kind == InputKind::Native || r.kind == InputKind::Grids; }
} // namespace

const std::vector<FormatReader>& formatReaders() {
  static const std::vector<FormatReader> readers = {
      {InputKind::Amrex, "AMReX plotfile", isAmrexPlotfile, listAmrexFields,
       [](const std::string& p, const ReadRequest& r) {
         const io::KeepNonFinite keep(r.keepNonFinite);
         return readAmrex(p, r.fields, r.box, r.finestLevel);
       },
       amrexFieldRange, amrexCensus, amrexLevelCells, amrexPatches},
      {InputKind::Chombo, "Chombo HDF5 file", isChomboFile, listChomboFields,
       [](const std::string& p, const ReadRequest& r) {
         const io::KeepNonFinite keep(r.keepNonFinite);
         return readChombo(p, r.fields, r.finestLevel, r.box);
       },
       nullptr, chomboCensus, chomboLevelCells, chomboPatches},
      {InputKind::Flash, "FLASH HDF5 file", isFlashFile, listFlashFields,
       [](const std::string& p, const ReadRequest& r) {
         const io::KeepNonFinite keep(r.keepNonFinite);
         return readFlash(p, r.fields);
       },
       nullptr, flashCensus, nullptr, flashPatches},
      {InputKind::Enzo, "Enzo output", isEnzoOutput, listEnzoFields,
       [](const std::string& p, const ReadRequest& r) {
         const io::KeepNonFinite keep(r.keepNonFinite);
         return readEnzo(p, r.fields, r.finestLevel, r.box);
       },
       nullptr, enzoCensus, enzoLevelCells, enzoPatches},
      {InputKind::VtkAmr, "VTK overlapping AMR file", isVtkAmrFile, listVtkAmrFields,
       [](const std::string& p, const ReadRequest& r) {
         const io::KeepNonFinite keep(r.keepNonFinite);
         return readVtkAmr(p, r.fields, r.finestLevel, r.box);
       },
       nullptr, vtkAmrCensus, vtkAmrLevelCells, vtkAmrPatches},
      {InputKind::Raw, "raw volume", isRawVolume, scalarOnly,
       [](const std::string& p, const ReadRequest& r) {
         const io::KeepNonFinite keep(r.keepNonFinite);
         return readRaw(p, r.raw);
       }},
      {InputKind::Native, "exabricks cells", isNativeName, listNativeFields,
       [](const std::string& p, const ReadRequest& r) {
         return readNative(p, r.fields, r.box, r.keepNonFinite, r.expectedCells);
       },
       nullptr, nativeCensus},
      {InputKind::Grids, ".grids fixture", isGridsName, scalarOnly,
       [](const std::string& p, const ReadRequest& r) {
         const io::KeepNonFinite keep(r.keepNonFinite);
         return readGrids(p);
       }},
  };
  return readers;
}

const FormatReader* findReader(const std::string& path) {
  for (const FormatReader& r : formatReaders())
    if (!probesByName(r) && r.probe(path)) return &r;
  if (h5::hasSignature(path))
    fail(path, ": an HDF5 file with neither Chombo's nor FLASH's layout, or one that cannot be opened",
         " (truncated or damaged?)");
  for (const FormatReader& r : formatReaders())
    if (probesByName(r) && r.probe(path)) return &r;
  return nullptr;
}

void cropCells(CellSet& set, const box3i& box) {
  keepCells(set, [&](const Cell& c) { return cellOverlaps(c, box); });
}

InputKind detectInput(const std::string& path) {
  if (path.empty()) return InputKind::Default;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, ": no such file or directory");
  const bool folder = std::filesystem::is_directory(path, ec);
  // A FIFO, socket or device would block or stream forever: inputs are files and folders.
  if (!folder && !std::filesystem::is_regular_file(path, ec))
    fail(path, ": not a regular file or a folder (a pipe, socket or device cannot be read as data)");
  if (!folder && isModelFile(path)) return InputKind::Model;
  if (const FormatReader* r = findReader(path)) return r->kind;
  if (folder) {
    // The only folder input is an AMReX plotfile: say what it lacks.
    const std::filesystem::path header = std::filesystem::path(path) / "Header";
    if (!std::filesystem::exists(header, ec))
      fail(path, ": a folder without a Header file, so not an AMReX plotfile (the only folder exabricks reads;",
           " a time series is named by its steps, as in 'run/plt*')");
    fail(path, ": a folder whose Header is not an AMReX plotfile's (its first line should name the plotfile",
         " format, such as HyperCLaw-V1.1)");
  }
  fail(path, ": unknown input format (expected an exabricks model file, NAME.cells, a .grids",
       " fixture, an AMReX plotfile directory, a Chombo or FLASH HDF5 file, an Enzo parameter file,",
       " a VTK .vthb file or a NAME_NXxNYxNZ_TYPE.raw volume)");
}

namespace {

/// With NonFinite::Holes: drops every cell with a NaN or infinite value in any field from all
/// fields, says how many per field on stderr and adds them to the options' report.
void makeNonFiniteHoles(CellSet& set, const std::string& source, const LoadOptions& options) {
  if (options.nonFinite != NonFinite::Holes) return;
  std::vector<uint8_t> bad(set.cells.size(), 0);
  std::vector<uint64_t> perField(set.fields.size(), 0);
  for (size_t f = 0; f < set.fields.size(); ++f) {
    const std::vector<float>& v = set.fields[f].values;
    for (size_t i = 0; i < v.size() && i < bad.size(); ++i)
      if (!std::isfinite(v[i])) bad[i] = 1, ++perField[f];
  }
  const uint64_t holes = uint64_t(std::count(bad.begin(), bad.end(), uint8_t(1)));
  if (options.report)
    for (size_t f = 0; f < set.fields.size(); ++f) {
      auto& counts = options.report->nonFinite;
      auto it =
          std::find_if(counts.begin(), counts.end(), [&](const auto& c) { return c.first == set.fields[f].name; });
      if (it == counts.end()) it = counts.insert(counts.end(), {set.fields[f].name, 0});
      it->second += perField[f];
    }
  if (options.report) options.report->holes += holes;
  if (holes == 0) return;
  for (size_t f = 0; f < set.fields.size(); ++f)
    if (perField[f] > 0)
      logWarning(strCat(source, ": ", perField[f], " cells with NaN or infinite values in '", set.fields[f].name,
                        "' treated as holes"));
  if (set.fields.size() > 1)
    logNote(strCat(source, ": ", holes, " cells dropped from every field (a cell is a hole in all fields or none)"));
  size_t i = 0;
  keepCells(set, [&](const Cell&) { return bad[i++] == 0; });
}

} // namespace

CellSet loadCells(const std::string& path, const LoadOptions& options) {
  CellSet set;
  const InputKind kind = detectInput(path);
  if (kind == InputKind::Model) fail(path, ": is a built model file; raw cells are needed here");
  if (kind == InputKind::Default) {
    set = defaultDataset();
  } else {
    ReadRequest request;
    request.fields = options.fields;
    request.box = options.box;
    request.raw = options.raw;
    request.keepNonFinite = options.nonFinite == NonFinite::Holes;
    const FormatReader* reader = findReader(path);
    if (options.finestLevel > 0 && !reader->levelCells)
      fail(path, ": a ", reader->name,
           " is read with all its levels (coarse levels alone: AMReX, Chombo, Enzo and VTK overlapping AMR files)");
    request.finestLevel = options.finestLevel;
    set = reader->read(path, request);
    assignConventionalUnits(reader->kind, set);
  }
  const std::string source = path.empty() ? kDefaultDatasetName : path;
  selectFields(set, options.fields, source);
  if (!options.box.empty()) cropCells(set, options.box);
  makeNonFiniteHoles(set, source, options);
  validateCells(set, source);
  return set;
}

namespace {

/// The lattice box a part reads: its box within the 32-bit lattice.
box3i readBoxOf(const box3l& part) {
  box3i out;
  for (int a = 0; a < 3; ++a) {
    out.lower[a] = int32_t(std::max<int64_t>(part.lower[a], INT32_MIN));
    out.upper[a] = int32_t(std::min<int64_t>(part.upper[a], INT32_MAX));
  }
  return out;
}

/// The census of an input with more than `partCells` cells, when its reader counts them without
/// reading the cells (NAME.cells by its size, then a streamed census; AMReX, Chombo, Enzo and VTK
/// from their box lists),
/// and its cell count; none otherwise.
std::optional<Census> censusIfLarger(const std::string& path, InputKind kind, const FormatReader& reader,
                                     uint64_t partCells, uint64_t& cells) {
  if (!reader.census) return std::nullopt;
  if (kind == InputKind::Native && fileSize(path) / sizeof(Cell) <= partCells) return std::nullopt;
  Census census = reader.census(path);
  cells = uint64_t(std::llround(census.cells()));
  if (cells <= partCells) return std::nullopt;
  return census;
}

/// Builds a model in parts, for data larger than one build should hold: a k-d partition of the
/// census into parts of about `partCells` cells, split only at multiples of the coarsest cell
/// width so that no cell is cut; each part is read through the reader's box, keeps the cells
/// inside it and is built into bricks (cells and values permuted in place), its values appended
/// to the model's. Memory: the values of the whole data plus one part's cells.
Model buildInParts(const std::string& path, const FormatReader& reader, const LoadOptions& options,
                   const Census& census, uint64_t cells) {
  const uint64_t partCells = std::max<uint64_t>(options.partCells, 1);
  const int parts = int(std::min<uint64_t>((cells + partCells - 1) / partCells, uint64_t(1) << 16));
  const KdPartition partition = KdPartition::balance(census, parts, int64_t(1) << census.coarsestLevel);
  logInfo(strCat("building ", cells, " cells in ", parts, " parts"));
  Timer timer;
  Model model;
  std::vector<std::vector<float>> values; // per field, brick order
  Progress progress("building bricks by parts", uint64_t(parts) + 1);
  uint64_t offset = 0;
  for (int p = 0; p < parts; ++p) {
    const box3l& box = partition.box(p);
    ReadRequest request;
    request.fields = options.fields;
    request.box = readBoxOf(box);
    request.raw = options.raw;
    request.keepNonFinite = options.nonFinite == NonFinite::Holes;
    CellSet set = reader.read(path, request);
    assignConventionalUnits(reader.kind, set);
    selectFields(set, options.fields, path);
    // Keep the cells inside the part: each cell lies in exactly one.
    keepCells(set, [&](const Cell& c) { return centreInside(c.lower, c.level, box); });
    progress.advance(1);
    if (set.cells.empty()) continue;
    makeNonFiniteHoles(set, path, options);
    const size_t kept = set.cells.size();
    if (kept == 0) continue;
    validateCells(set, path);
    if (model.fieldNames.empty()) {
      model.world = set.world;
      model.simulation = set.simulation;
      for (const Field& f : set.fields) {
        model.fieldNames.push_back(f.name);
        model.fieldUnits.push_back(f.units);
      }
      values.resize(set.fields.size());
      for (auto& v : values)
        v.reserve(cells);
    }
    if (offset + kept >= uint64_t(UINT32_MAX))
      fail(path, ": too many cells: more than ", offset + kept - 1, " (limit 2^32-1)");
    std::vector<std::vector<float>*> arrays;
    for (Field& f : set.fields)
      arrays.push_back(&f.values);
    std::vector<Brick> bricks;
    try {
      bricks = buildBricksReordering(set.cells, arrays, options.build.bricks);
    } catch (const Error& e) { // a conflict names the two cells by position: this read's order is not the file's
      throw Error(strCat(path, ": ", e.what()));
    }
    for (Brick& b : bricks) {
      b.valueOffset += uint32_t(offset);
      model.bricks.push_back(b);
    }
    std::vector<Cell>().swap(set.cells);
    for (size_t f = 0; f < set.fields.size(); ++f) {
      values[f].insert(values[f].end(), set.fields[f].values.begin(), set.fields[f].values.end());
      std::vector<float>().swap(set.fields[f].values);
    }
    offset += kept;
  }
  if (model.bricks.empty()) fail(path, ": no cells");
  for (auto& v : values)
    model.fieldValues.push_back(std::move(v));
  model.stats.brickSeconds = timer.seconds();
  model.stats.parts = parts;
  buildRegionsOf(model, options.build.regions);
  progress.finish();
  logInfo(strCat("built ", model.bricks.size(), " bricks and ", model.regions.regions.size(), " regions in ",
                 timer.seconds(), " s"));
  return model;
}

} // namespace

namespace {

/// A read error that already names its file: passed on without the source's name in front.
struct NamedReadError : Error {
  using Error::Error;
};

/// A NAME.cells input built with its values read after the bricks (buildModelValuesAfter): the
/// cells and every field are never held together.
Model loadNativeValuesAfter(const std::string& path, const LoadOptions& options, const Timer& timer) {
  CellSet cells;
  cells.cells = readNativeCells(path);
  const uint64_t count = cells.cells.size();
  const std::vector<std::string> names = nativeFieldsToRead(path, options.fields, count);
  for (const std::string& name : names)
    cells.fields.push_back(Field{name, {}});
  logInfo(strCat("read ", count, " cells in ", timer.seconds(), " s"));
  try {
    return buildModelValuesAfter(
        std::move(cells),
        [&](size_t f) {
          try {
            return readNativeField(path, names[f], count);
          } catch (const Error& e) {
            throw NamedReadError(e.what());
          }
        },
        options.build);
  } catch (const NamedReadError&) {
    throw;
  } catch (const CellConflict& c) {
    throw Error(strCat(path, ": ", locateConflict(c, readNativeCells(path))));
  } catch (const Error& e) {
    throw Error(strCat(path, ": ", e.what()));
  }
}

} // namespace

bool buildsFromBoxes(const std::string& path, const LoadOptions& options) {
  const InputKind kind = path.empty() ? InputKind::Default : detectInput(path);
  return kind == InputKind::Model || (!path.empty() && io::patchReader(kind, path, options) != nullptr);
}

Model loadModel(const std::string& path, const LoadOptions& options) {
  Timer timer;
  if (detectInput(path) == InputKind::Model) {
    Model m = readModel(path);
    for (const std::string& name : options.fields)
      if (m.fieldIndex(name) < 0) m.requireField(name);
    logInfo(strCat("read model ", path, " in ", timer.seconds(), " s"));
    return m;
  }
  const std::string source = path.empty() ? kDefaultDatasetName : path;
  const InputKind kind = detectInput(path);
  if (const FormatReader* reader = io::patchReader(kind, path, options)) {
    PatchKeep keep;
    if (!options.box.empty())
      keep = {PatchKeep::Rule::Overlapping, box3l(vec3l(options.box.lower), vec3l(options.box.upper))};
    Model m = io::loadModelOfPatches(path, *reader, options, options.finestLevel, keep);
    if (m.bricks.empty()) fail(path, ": no cells", options.box.empty() ? "" : " in the box asked for");
    logInfo(strCat("read and built in ", timer.seconds(), " s"));
    return m;
  }
  if (options.partCells > 0 && options.box.empty() && kind != InputKind::Default && options.finestLevel == 0) {
    const FormatReader* reader = findReader(path);
    uint64_t count = 0;
    if (const std::optional<Census> census = censusIfLarger(path, kind, *reader, options.partCells, count))
      return buildInParts(path, *reader, options, *census, count);
  }
  if (kind == InputKind::Native && options.box.empty() && options.nonFinite != NonFinite::Holes &&
      options.finestLevel == 0)
    return loadNativeValuesAfter(path, options, timer);
  CellSet cells = loadCells(path, options);
  logInfo(strCat("read ", cells.size(), " cells in ", timer.seconds(), " s"));
  try {
    return buildModel(std::move(cells), options.build);
  } catch (const CellConflict& c) {
    // The build permuted the cells; the input, read again, names the two by index.
    throw Error(strCat(source, ": ", locateConflict(c, loadCells(path, options).cells)));
  } catch (const Error& e) {
    throw Error(strCat(source, ": ", e.what()));
  }
}

std::optional<range1f> fieldRangeFromMetadata(const std::string& path, const std::string& field) {
  const FormatReader* reader = findReader(path);
  if (!reader || !reader->fieldRange) return std::nullopt;
  return reader->fieldRange(path, field);
}

std::vector<std::string> listFields(const std::string& path) {
  const InputKind kind = detectInput(path);
  if (kind == InputKind::Model) return readModelTable(path).fieldNames;
  if (kind != InputKind::Default) return findReader(path)->listFields(path);
  std::vector<std::string> names;
  for (const Field& f : defaultDataset().fields)
    names.push_back(f.name);
  return names;
}

Census loadCensus(const std::string& path, const LoadOptions& options) {
  const InputKind kind = detectInput(path);
  if (kind == InputKind::Model) return io::censusOfInput(path, io::modelPartsReader());
  if (kind != InputKind::Default) {
    const FormatReader* reader = findReader(path);
    if (reader->census) return io::censusOfInput(path, *reader);
  }
  LoadOptions cellsOnly = options;
  cellsOnly.box = box3i();
  const CellSet set = loadCells(path, cellsOnly);
  CellCensus census;
  census.add(set.cells.data(), set.cells.size());
  return census.finish();
}

std::optional<Model> loadModelPart(const std::string& path, const LoadOptions& options, const box3l& part,
                                   int coarsestLevel, double expectedCells) {
  const std::string source = path.empty() ? kDefaultDatasetName : path;
  const box3l reach = shadingReach(part, coarsestLevel);
  const InputKind kind = detectInput(path);
  const FormatReader* patches = kind == InputKind::Model ? &io::modelPartsReader() // the bricks reaching the part
                                                         : io::patchReader(kind, path, options);
  if (patches) {
    Model m = io::loadModelOfPatches(path, *patches, options, 0, {PatchKeep::Rule::Reaching, reach});
    if (m.bricks.empty()) return std::nullopt;
    return m;
  }
  CellSet set;
  const box3i readBox = haloReadBox(reach, coarsestLevel);
  if (kind == InputKind::Default) {
    set = defaultDataset();
  } else {
    ReadRequest request;
    request.fields = options.fields;
    request.box = readBox;
    request.expectedCells = size_t(std::max(0.0, std::ceil(expectedCells)));
    request.raw = options.raw;
    request.keepNonFinite = options.nonFinite == NonFinite::Holes;
    const FormatReader* reader = findReader(path);
    set = reader->read(path, request);
    assignConventionalUnits(reader->kind, set);
  }
  selectFields(set, options.fields, source);
  keepSupportOf(set, reach);
  makeNonFiniteHoles(set, source, options);
  if (set.cells.empty()) return std::nullopt;
  validateCells(set, source);
  try {
    return buildModel(std::move(set), options.build);
  } catch (const Error& e) {
    throw Error(strCat(source, ": ", e.what()));
  }
}

} // namespace exa
