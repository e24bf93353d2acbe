// libFuzzer entry for HDF5 files damaged at the byte level: the input is a whole file (seeds:
// the Chombo and FLASH test fixtures in both HDF5 file formats, fuzz_seeds hdf5 DIR), probed and
// read by the Chombo and FLASH readers. libhdf5 parses the damaged metadata: every input must
// end in a clean error or a load, whatever libhdf5 would do with it (src/io/hdf5_file.cpp checks
// datatypes and dataspaces before reading and walks the file in a child process first).
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/chombo.h"
#include "exabricks/io/flash.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::write("d.hdf5", std::string(reinterpret_cast<const char*>(data), size));
  try {
    if (exa::isChomboFile(path)) {
      exa::listChomboFields(path);
      exa::readChombo(path, {});
    } else if (exa::isFlashFile(path)) {
      exa::listFlashFields(path);
      exa::readFlash(path, {});
    }
  } catch (const exa::Error&) {
  }
  return 0;
}
