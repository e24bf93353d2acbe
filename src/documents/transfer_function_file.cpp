#include "exabricks/documents/transfer_function_file.h"

#include "exabricks/core/error.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace exa {

TransferFunction readTransferFunction(const std::string& path, bool* isPreset) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(path, ": cannot open: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(path, ": cannot read: ", std::strerror(errno));
  return parseTransferFunction(text, path, isPreset);
}

} // namespace exa
