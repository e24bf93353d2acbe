// The viewer's page (web/), compiled into the program: served from memory, no files read.
#pragma once

#include <cstddef>
#include <vector>

namespace exa::view {

struct WebAsset {
  const char* path; ///< URL path, e.g. "/viewer.js"
  const char* mime;
  const char* data;
  size_t size;
};

const std::vector<WebAsset>& webAssets();

} // namespace exa::view
