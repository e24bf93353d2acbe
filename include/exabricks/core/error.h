// One exception type for every user-facing failure. Messages name the file, the record and the
// problem; only the command-line front end catches and prints them.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace exa {

/// Concatenates any streamable arguments into one string.
template <typename... Args> std::string strCat(Args&&... args) {
  std::ostringstream out;
  (out << ... << std::forward<Args>(args));
  return out.str();
}

class Error : public std::runtime_error {
public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// A request that cannot be valid (a bad option or option value), as opposed to input or work
/// that failed; the command line exits with 2 for it.
class UsageError : public Error {
public:
  explicit UsageError(const std::string& message) : Error(message) {}
};

/// Throws exa::UsageError with the concatenated arguments as message.
template <typename... Args> [[noreturn]] void failUsage(Args&&... args) {
  throw UsageError(strCat(std::forward<Args>(args)...));
}

/// Throws exa::Error with the concatenated arguments as message.
template <typename... Args> [[noreturn]] void fail(Args&&... args) { throw Error(strCat(std::forward<Args>(args)...)); }

} // namespace exa

/// Internal invariant check; failing it is a bug, not bad input. Extra arguments describe the
/// values involved.
#define EXA_CHECK(...)                                                                                                 \
  do {                                                                                                                 \
    if (!(EXA_CHECK_CONDITION(__VA_ARGS__, 0)))                                                                        \
      ::exa::fail("internal check failed at " __FILE__ ":", __LINE__, ": " #__VA_ARGS__);                              \
  } while (0)
#define EXA_CHECK_CONDITION(cond, ...) (cond)
