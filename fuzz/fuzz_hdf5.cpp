// libFuzzer entry for HDF5 files damaged at the byte level: the input is a whole file (seeds:
// the Chombo and FLASH test fixtures in both HDF5 file formats, fuzz_seeds hdf5 DIR), probed and
// read by the Chombo and FLASH readers. libhdf5 parses the damaged metadata: every input must
// end in a clean error or a load, whatever libhdf5 would do with it (src/io/hdf5_checks.cpp checks
// datatypes and dataspaces before reading; src/io/hdf5_child.cpp walks the file in a child process
// first).
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/chombo.h"
#include "exabricks/io/flash.h"

// The memory limit of the metadata walk's child. Outside the sanitizers it runs under an address
// space limit, so that a huge allocation by libhdf5 fails there and the file is refused; under
// AddressSanitizer that limit cannot apply, and libFuzzer's -malloc_limit_mb would report the
// child's allocation as a finding of its own although the parent goes on with a clean error.
// AddressSanitizer refuses such allocations instead (null from malloc, which libhdf5 reports as
// an error); an oversized `new` in exabricks' own code still ends the run as a finding.
extern "C" const char* __asan_default_options() { return "allocator_may_return_null=1:max_allocation_size_mb=1000"; }

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
