// libFuzzer entry for the model-file reader: the input is a model file, read as it is and once
// more with its header's payload size and checksum made to match (fuzz/model_bytes.h), so that
// mutations reach every array and the consistency checks. What reads must pass those checks.
// The brick table of a model read in parts (readModelTable) is read from the same bytes, and
// every brick's values with it, and every cell merged into cubes from them.
// Seeds: valid version 1 and version 2 files of several sizes (fuzz_seeds model DIR).
#include "fuzz_files.h"
#include "model_bytes.h"

#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/model_file.h"

#include <vector>

namespace {
void readOne(const std::string& bytes) {
  const std::string path = fuzz::write("m.exabricks", bytes);
  try {
    const exa::Model m = exa::readModel(path);
    if (m.fieldNames.size() != m.fieldValues.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  // The table a step read in parts takes, and every brick's values read from the file.
  try {
    const exa::ModelTable t = exa::readModelTable(path);
    if (t.fieldNames.size() != t.valuesAt.size()) __builtin_trap();
    std::vector<float> values;
    for (size_t f = 0; f < t.fieldNames.size(); ++f)
      for (const exa::Brick& b : t.bricks) {
        values.resize(b.cellCount());
        t.readValues(path, f, b, values.data());
      }
  } catch (const exa::Error&) {
  }
  // Every cell merged into cubes for a first picture, brick by brick.
  try {
    const std::optional<exa::MergedLeaves> m = exa::loadMergedLeaves(path, {}, 2);
    if (m && m->model.cellCount() > m->cells) __builtin_trap();
  } catch (const exa::Error&) {
  }
}
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  readOne(bytes);
  const std::string sealed = fuzz::sealModel(bytes);
  if (sealed != bytes) readOne(sealed);
  return 0;
}
