#include "checked.h"

namespace exa::io {

void requireBytes(uint64_t count, uint64_t itemBytes, uint64_t present, const std::string& where) {
  uint64_t total = 0;
  if (productWithin(count, itemBytes, present, total)) return;
  if (count != 0 && itemBytes > UINT64_MAX / count)
    fail(where, ": declares ", count, " values of ", itemBytes, " bytes (more than 2^64 bytes), but only ", present,
         " bytes are present");
  fail(where, ": declares ", count, " values of ", itemBytes, " bytes (", count * itemBytes, " bytes), but only ",
       present, " bytes are present (truncated file or corrupt size?)");
}

void failAllocation(uint64_t bytes, const std::string& where) {
  if (bytes == UINT64_MAX) fail(where, ": cannot allocate more than 2^64 bytes (out of memory)");
  fail(where, ": cannot allocate ", bytes, " bytes (out of memory)");
}

} // namespace exa::io
