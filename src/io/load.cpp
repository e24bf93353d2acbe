#include "exabricks/io/load.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/io/amrex.h"
#include "exabricks/io/chombo.h"
#include "exabricks/io/enzo.h"
#include "exabricks/io/flash.h"
#include "exabricks/io/hdf5.h"
#include "exabricks/io/model_file.h"
#include "exabricks/io/native.h"
#include "exabricks/io/vtk_amr.h"

#include <filesystem>

namespace exa {
namespace {
bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void selectFields(CellSet& set, const std::vector<std::string>& wanted, const std::string& source) {
  if (wanted.empty()) return;
  std::vector<Field> chosen;
  for (const std::string& name : wanted) {
    const int i = set.fieldIndex(name);
    if (i < 0) {
      std::string known;
      for (const Field& f : set.fields) known += (known.empty() ? "" : ", ") + f.name;
      fail(source, ": unknown field '", name, "' (fields: ", known, ")");
    }
    chosen.push_back(set.fields[size_t(i)]);
  }
  set.fields = std::move(chosen);
}
} // namespace

InputKind detectInput(const std::string& path) {
  if (path.empty()) return InputKind::Default;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, ": no such file or directory");
  if (!std::filesystem::is_directory(path, ec) && isModelFile(path)) return InputKind::Model;
  if (isAmrexPlotfile(path)) return InputKind::Amrex;
  if (isChomboFile(path)) return InputKind::Chombo;
  if (isFlashFile(path)) return InputKind::Flash;
  if (isEnzoOutput(path)) return InputKind::Enzo;
  if (isVtkAmrFile(path)) return InputKind::VtkAmr;
  if (isRawVolume(path)) return InputKind::Raw;
  if (isHdf5File(path))
    fail(path, ": an HDF5 file with neither Chombo's nor FLASH's layout, or one that cannot be opened",
         " (truncated or damaged?)");
  if (endsWith(path, ".cells")) return InputKind::Native;
  if (endsWith(path, ".grids")) return InputKind::Grids;
  fail(path, ": unknown input format (expected an exabricks model file, NAME.cells, a .grids",
       " fixture, an AMReX plotfile directory, a Chombo or FLASH HDF5 file, an Enzo parameter file,",
       " a VTK .vthb file or a NAME_NXxNYxNZ_TYPE.raw volume)");
}

CellSet loadCells(const std::string& path, const LoadOptions& options) {
  CellSet set;
  switch (detectInput(path)) {
  case InputKind::Default:
    set = defaultDataset();
    break;
  case InputKind::Native:
    set = readNative(path, options.fields);
    break;
  case InputKind::Grids:
    set = readGrids(path);
    break;
  case InputKind::Amrex:
    set = readAmrex(path, options.fields);
    break;
  case InputKind::Chombo:
    set = readChombo(path, options.fields);
    break;
  case InputKind::Flash:
    set = readFlash(path, options.fields);
    break;
  case InputKind::Enzo:
    set = readEnzo(path, options.fields);
    break;
  case InputKind::VtkAmr:
    set = readVtkAmr(path, options.fields);
    break;
  case InputKind::Raw:
    set = readRaw(path, options.raw);
    break;
  case InputKind::Model:
    fail(path, ": is a built model file; raw cells are needed here");
  }
  const std::string source = path.empty() ? kDefaultDatasetName : path;
  selectFields(set, options.fields, source);
  validateCells(set, source);
  return set;
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
  CellSet cells = loadCells(path, options);
  logInfo(strCat("read ", cells.size(), " cells in ", timer.seconds(), " s"));
  try {
    return buildModel(std::move(cells), options.build);
  } catch (const Error& e) {
    throw Error(strCat(path.empty() ? kDefaultDatasetName : path, ": ", e.what()));
  }
}

std::vector<std::string> listFields(const std::string& path) {
  switch (detectInput(path)) {
  case InputKind::Native:
    return listNativeFields(path);
  case InputKind::Grids:
    return {"scalar"};
  case InputKind::Amrex:
    return listAmrexFields(path);
  case InputKind::Chombo:
    return listChomboFields(path);
  case InputKind::Flash:
    return listFlashFields(path);
  case InputKind::Enzo:
    return listEnzoFields(path);
  case InputKind::VtkAmr:
    return listVtkAmrFields(path);
  case InputKind::Raw:
    return {"scalar"};
  case InputKind::Model:
    return readModel(path).fieldNames;
  case InputKind::Default:
    break;
  }
  std::vector<std::string> names;
  for (const Field& f : defaultDataset().fields) names.push_back(f.name);
  return names;
}

} // namespace exa
