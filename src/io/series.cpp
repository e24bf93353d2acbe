#include "exabricks/io/series.h"

#include "exabricks/core/error.h"
#include "exabricks/io/load.h"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace exa {

namespace {

bool isDigit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

/// Whether a path is something a reader (or the model file loader) recognises.
bool isDataset(const std::string& path) {
  try {
    detectInput(path);
    return true;
  } catch (const Error&) {
    return false;
  }
}

} // namespace

bool naturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (isDigit(a[i]) && isDigit(b[j])) {
      size_t ei = i, ej = j;
      while (ei < a.size() && isDigit(a[ei]))
        ++ei;
      while (ej < b.size() && isDigit(b[ej]))
        ++ej;
      // Compare the runs as numbers: skip leading zeros, then length, then digits.
      size_t zi = i, zj = j;
      while (zi + 1 < ei && a[zi] == '0')
        ++zi;
      while (zj + 1 < ej && b[zj] == '0')
        ++zj;
      if (ei - zi != ej - zj) return ei - zi < ej - zj;
      const int c = a.compare(zi, ei - zi, b, zj, ej - zj);
      if (c != 0) return c < 0;
      i = ei;
      j = ej;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;
}

std::vector<std::string> expandSeries(const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  for (const std::string& input : inputs) {
    std::vector<std::string> found;
    std::error_code ec;
    if (input.find_first_of("*?[") != std::string::npos && !std::filesystem::exists(input, ec)) {
      glob_t g{};
      const int rc = ::glob(input.c_str(), 0, nullptr, &g);
      if (rc == 0)
        for (size_t i = 0; i < g.gl_pathc; ++i)
          if (isDataset(g.gl_pathv[i])) found.push_back(g.gl_pathv[i]);
      globfree(&g);
    } else if (std::filesystem::is_directory(input, ec) && !isDataset(input)) {
      for (const auto& entry : std::filesystem::directory_iterator(input, ec))
        if (isDataset(entry.path().string())) found.push_back(entry.path().string());
      if (ec) fail(input, ": cannot list the folder: ", ec.message());
    } else {
      if (!std::filesystem::exists(input, ec)) fail(input, ": no such file or folder");
      found.push_back(input);
    }
    if (found.empty()) fail(input, ": holds or matches no dataset");
    out.insert(out.end(), found.begin(), found.end());
  }
  std::sort(out.begin(), out.end(), naturalLess);
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

} // namespace exa
