// libFuzzer entry for the model-file reader: the input is a model file. What reads must pass the
// consistency checks, so a sample at the centre of its bounds stays within its arrays.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/model_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::write("m.exabricks", std::string(reinterpret_cast<const char*>(data), size));
  try {
    const exa::Model m = exa::readModel(path);
    if (m.fieldNames.size() != m.fieldValues.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  return 0;
}
