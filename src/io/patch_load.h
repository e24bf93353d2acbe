// Loads built from an input's boxes (structure without values): the readers' patch sources kept
// while the input's metadata are unchanged, the census counted once, and the models built from
// them.
#pragma once

#include "exabricks/amr/partition.h"
#include "exabricks/io/load.h"
#include "exabricks/io/patch_source.h"
#include "exabricks/io/reader.h"

#include <string>
#include <vector>

namespace exa::io {

/// When an input's metadata were last written, and how large they are: its path's, a folder's
/// Header's and an Enzo hierarchy's.
std::string metadataStamp(const std::string& path);

/// The input's patches of cells 2^finestLevel wide and wider, read from its metadata once while
/// they are unchanged. Only sources of plain files are kept, whose reads any thread may share.
PatchSource patchesOf(const std::string& path, const FormatReader& reader, const std::vector<std::string>& fields,
                      int finestLevel);

/// A patch-based input built from its boxes: the cells `keep` keeps of the levels the options
/// ask for (cells 2^finestLevel wide and wider). A model without bricks when none is kept.
Model loadModelOfPatches(const std::string& path, const FormatReader& reader, const LoadOptions& options,
                         int finestLevel, const PatchKeep& keep);

/// Model files read in parts (a step under a memory budget): the census and the patches from
/// the brick table (readModelTable), each brick's values read on demand. Loaded whole, a model
/// file is mapped instead (readModel).
const FormatReader& modelPartsReader();

/// The reader that builds a load of this kind from the input's boxes, if any: readers that give
/// them, unless non-finite values are to become holes (cells dropped one by one).
const FormatReader* patchReader(InputKind kind, const std::string& path, const LoadOptions& options);

/// The reader's census of the input, counted once while its metadata are unchanged: a plan, a
/// survey and the viewer's budget each ask for it.
Census censusOfInput(const std::string& path, const FormatReader& reader);

} // namespace exa::io
