// Opens whatever the user names: a model file (known by its magic bytes), any input a registered
// reader recognises (io/reader.h), or the embedded default dataset when no input is given.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/io/reader.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace exa {

/// What loading does with NaN and infinite field values: refuse them (an error naming the first
/// record, the default), or make every cell that holds one in any loaded field a hole: the cell
/// is dropped from all fields, as a cell the data lacks, and the basis sums skip it.
enum class NonFinite { Refuse, Holes };

/// What a load made holes of (NonFinite::Holes): per loaded field, the cells with a NaN or
/// infinite value in it, and the cells dropped (a cell bad in several fields counts once).
struct LoadReport {
  std::vector<std::pair<std::string, uint64_t>> nonFinite;
  uint64_t holes = 0;
};

struct LoadOptions {
  std::vector<std::string> fields; ///< fields to load (all when empty)
  BuildOptions build;
  RawOptions raw; ///< dimensions, type and merging of raw volumes
  box3i box;      ///< finest-lattice box: only cells that overlap it (empty: all)
  /// Inputs with more cells than this whose reader takes a census without reading the cells and
  /// that are not built from their boxes (NAME.cells; patch-based files with NonFinite::Holes)
  /// are built in parts of about this many cells, each read through the reader's box: the build
  /// then holds the values of all cells but the records of one part only. 0: always in one piece.
  uint64_t partCells = uint64_t(1) << 27;
  NonFinite nonFinite = NonFinite::Refuse;
  /// Coarse levels only (ReadRequest::finestLevel; AMReX, Chombo, Enzo, VTK): cells narrower than
  /// 2^finestLevel finest cells are not read, the coarser cells under them are leaves. 0: all.
  int finestLevel = 0;
  /// Not null: receives what the load made holes of (counts add up over the parts of a build).
  /// The readers of native NAME.cells inputs keep such values; those of other formats refuse them.
  std::shared_ptr<LoadReport> report;
};

/// Determines the kind of input; throws with the path when it is not recognised.
InputKind detectInput(const std::string& path);

/// Whether this input is built without cell records: from its boxes (structure without values),
/// or, for a model file, from its bricks (mapped whole, or read brick by brick in parts).
bool buildsFromBoxes(const std::string& path, const LoadOptions& options = {});

/// Reads raw cells (not for model files).
CellSet loadCells(const std::string& path, const LoadOptions& options = {});

/// Reads a model file, or builds the model: from the input's boxes where its reader gives them
/// (FormatReader::patches, unless NonFinite::Holes), else from the cells read. Errors name the
/// input.
Model loadModel(const std::string& path, const LoadOptions& options = {});

/// A field's value range from the input's metadata alone, where its format records one (AMReX
/// plotfiles: the per-box minima and maxima); none otherwise.
std::optional<range1f> fieldRangeFromMetadata(const std::string& path, const std::string& field);

/// A first picture from the coarse levels.
struct CoarseFirst {
  int level = 0;          ///< read levels of cells 2^level finest cells wide and wider (0: all; none needed)
  int finestLevel = 0;    ///< the input's finest level
  double cells = 0;       ///< cells in every level's boxes
  double coarseCells = 0; ///< cells in the boxes of `level` and coarser
};
/// The finest level whose boxes, with those of every coarser level, hold at most `maxCells`
/// cells (read alone with LoadOptions::finestLevel); level 0 when the input holds no more than
/// that, or its format cannot read coarse levels alone (AMReX, Chombo, Enzo and VTK overlapping AMR
/// files can: they list every level's boxes apart from the values, and store every level's values).
CoarseFirst coarseFirstLevel(const std::string& path, double maxCells);
/// Every choice coarseFirstLevel can make: first the whole (level 0), then each level finer than
/// the finest with the cells of it and every coarser level, from the coarsest alone to the finer;
/// the whole alone when the format cannot read coarse levels alone, none for a model file.
std::vector<CoarseFirst> coarseFirstChoices(const std::string& path);

/// A first picture before the coarse levels: the coarsest level's cells merged in blocks of
/// factor^3 into about `maxCells` cells, each the mean of its cells (factor: the fewest merges
/// that get there, a power of two to which every box of that level is aligned). None where the
/// input is not built from its boxes, its coarsest level holds no more than `maxCells` cells, or
/// its boxes allow no merge.
struct MergedCoarsest {
  Model model;
  int64_t factor = 1; ///< cells merged per axis
  int level = 0;      ///< the coarsest level's
  double cells = 0;   ///< in the coarsest level's boxes
};
std::optional<MergedCoarsest> loadMergedCoarsest(const std::string& path, const LoadOptions& options, double maxCells);

/// A first picture of an input without coarse levels to read alone (a model file, FLASH,
/// NAME.cells, a patch-based file of one level): every leaf cell merged into cubes 2^level
/// finest cells wide, each the mean of the cells in it by their volume; the narrowest cubes, at
/// least as wide as every cell, that the cells' volume keeps within about `maxCells`. Read piece
/// by piece (brick, block, 65,536 records), so that the cubes are all it holds. `ranges` are
/// the cells' value ranges, not the means'. None where the input is not of those kinds or holds
/// no more than `maxCells` cells.
struct MergedLeaves {
  Model model;
  int level = 0;               ///< the cubes'
  double cells = 0;            ///< leaf cells merged
  std::vector<range1f> ranges; ///< per field, of the leaf cells
  int finestLevel = 0;         ///< of the leaf cells
  box3i cellBounds;            ///< of the leaf cells (the cubes' reach further)
};
std::optional<MergedLeaves> loadMergedLeaves(const std::string& path, const LoadOptions& options, double maxCells);
/// Whether loadMergedLeaves reads this input.
bool mergesLeaves(const std::string& path);
/// The cubes loadMergedLeaves makes of the input for `maxCells`, estimated from its census: the
/// cells' volume over a cube's (the cubes at the edges of the cells' boxes add some).
double mergedLeavesCubes(const std::string& path, const LoadOptions& options, double maxCells);

/// Names of the fields an input holds, without building anything.
std::vector<std::string> listFields(const std::string& path);

/// Where an input's cells lie, for splitting it among processes: from the headers alone (AMReX
/// plotfiles), by reading only the cell records in pieces (NAME.cells), from a model file's
/// bricks, or else by reading the cells.
Census loadCensus(const std::string& path, const LoadOptions& options = {});

/// The share of a dataset one process renders in data-parallel mode: every cell whose basis
/// support reaches into the lattice box `part` grown by shadingReach (the part and its halo,
/// wide enough for smooth shading at the part's faces; readers that take a box
/// read little more), built into a model; none when no cell reaches it. Model files are read
/// whole and their bricks that reach the part kept. `expectedCells`: about how many cells the
/// part and its halo hold, at most (its census count), for readers that reserve room; 0: unknown.
std::optional<Model> loadModelPart(const std::string& path, const LoadOptions& options, const box3l& part,
                                   int coarsestLevel, double expectedCells = 0);

} // namespace exa
