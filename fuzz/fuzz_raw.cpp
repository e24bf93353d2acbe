// libFuzzer entry for the raw-volume reader: the first input line names the file
// (NAME_NXxNYxNZ_TYPE.raw, parsed as a file name is) and the rest is its voxels; the volume is
// read and merged with a threshold taken from the name's length.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/raw.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const size_t eol = text.find('\n');
  if (eol == std::string::npos || eol == 0 || eol > 200) return 0;
  std::string name = text.substr(0, eol);
  for (char& c : name)
    if (c == '/' || c == '\0') c = '_';
  const std::string path = fuzz::write(name + ".raw", text.substr(eol + 1));
  try {
    exa::RawOptions options;
    exa::parseRawName(path, options);
    options.threshold = double(name.size() % 4) * 0.25;
    options.maxLevel = int(name.size() % 5);
    const exa::CellSet s = exa::readRaw(path, options);
    if (s.fields.size() != 1 || s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  std::error_code ec;
  std::filesystem::remove(path, ec);
  return 0;
}
