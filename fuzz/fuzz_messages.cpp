// libFuzzer entry for the messages processes exchange when they redistribute cells
// (amr/distribute.h): the input is decoded as a census and as a message of cells of two fields;
// only exa::Error may escape, and what decodes must encode back to the same bytes.
#include "exabricks/amr/distribute.h"
#include "exabricks/core/error.h"

#include <cstddef>
#include <cstdint>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<uint8_t> bytes(data, data + size);
  try {
    const exa::Census census = exa::decodeCensus(bytes);
    if (exa::encodeCensus(census) != bytes) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    exa::CellSet set;
    set.fields = {{"a", {}, ""}, {"b", {}, ""}};
    exa::appendDecodedCells(set, bytes);
    if (exa::encodeCells(set) != bytes) __builtin_trap();
  } catch (const exa::Error&) {
  }
  return 0;
}
