// Helpers for the tests of error messages: what a call or a load fails with, and whether the
// message names every expected part (file, record, problem).
#pragma once

#include "exabricks/core/error.h"
#include "exabricks/io/load.h"

#include <gtest/gtest.h>

#include <functional>
#include <initializer_list>
#include <string>

namespace exa::test {

/// The message of the exa::Error that f throws, or "no error".
inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

/// The message loading the cells of `path` fails with, or "no error".
inline std::string loadError(const std::string& path, const LoadOptions& options = {}) {
  return errorOf([&] { loadCells(path, options); });
}

/// Expects every part in the message.
inline void expectIn(const std::string& message, std::initializer_list<const char*> parts) {
  for (const char* p : parts)
    EXPECT_NE(message.find(p), std::string::npos) << "'" << p << "' not in: " << message;
}

} // namespace exa::test
