// EXABRICKS_ASAN is defined where the code is built with AddressSanitizer, by GCC
// (__SANITIZE_ADDRESS__) or Clang (__has_feature(address_sanitizer)).
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define EXABRICKS_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define EXABRICKS_ASAN 1
#endif
#endif
